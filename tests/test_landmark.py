"""Going to a landmark (thesis 4.2.2, eqns 11-12, A.10) in the simulator."""

import math

import numpy as np
import pytest

from abcwc.behaviours import GoToLandmark, Status, ThesisGoToLandmark, distance_and_bearing
from abcwc.behaviours.landmark import proportional_command, turn_then_drive
from abcwc.estimation import Odometry
from abcwc.sim.base import SimBase
from abcwc.sim.world import box_world
from abcwc.types import Pose2D, Twist

OPEN = box_world(20, 20, centred=True, name="open")
GOAL = (-2.0, 3.0)  # behind and to the left: needs a big turn first


def test_distance_and_bearing_wraps():
    rho, alpha = distance_and_bearing(Pose2D(0, 0, 3.0), (-1.0, -0.1))
    assert rho == pytest.approx(math.hypot(1, 0.1))
    assert abs(alpha) < 0.3  # not 2 pi - 0.24


def _drive(controller_class, **options):
    sim = SimBase(OPEN, errors="ideal", people=False)
    controller = controller_class(GOAL, Odometry(start=sim.pose), **options)
    log = sim.run(controller, 30.0)
    steps = np.hypot(*np.diff(log.pose[:, :2], axis=0).T)
    moving = np.flatnonzero(steps > 1e-5)
    error = math.hypot(log.pose[-1, 0] - GOAL[0], log.pose[-1, 1] - GOAL[1])
    return controller, error, log.distance_travelled(), log.t[moving[-1]]


def test_thesis_and_proportional_controllers_reach_the_goal():
    thesis, error_t, length_t, time_t = _drive(ThesisGoToLandmark)
    better, error_p, length_p, time_p = _drive(GoToLandmark)
    assert thesis.status is better.status is Status.SUCCEEDED
    assert error_t <= 0.5  # the thesis's tolerance (A.10)
    assert error_p <= 0.1  # a 0.1 m tolerance, stopping included
    assert time_p < time_t  # turns while driving instead of stopping to turn
    straight = math.hypot(*GOAL)
    assert length_p < 1.2 * straight and length_t < straight


def test_goal_is_validated():
    with pytest.raises(ValueError, match="goal"):
        GoToLandmark((float("nan"), 1.0), Odometry())
    with pytest.raises(ValueError, match="tolerance"):
        GoToLandmark((1.0, 1.0), Odometry(), tolerance=0)


def test_turn_then_drive_states():
    # turning with hysteresis: 0.2 rad is not yet aligned, 0.05 is
    assert turn_then_drive("turn", 2.0, 0.2, align_tolerance=0.1) == ("turn", Twist(0, 0.5))
    assert turn_then_drive("turn", 2.0, -0.05, align_tolerance=0.1) == ("drive", Twist(0.5, 0))
    # driving tolerates up to heading_tolerance, then turns towards the goal (right here)
    assert turn_then_drive("drive", 2.0, 0.2) == ("drive", Twist(0.5, 0))
    assert turn_then_drive("drive", 2.0, -0.4) == ("turn", Twist(0, -0.5))
    # within the tolerance it stops, and stays stopped whatever comes next
    assert turn_then_drive("drive", 0.4, 0.0) == ("reached", Twist(0, 0))
    assert turn_then_drive("reached", 3.0, 1.0) == ("reached", Twist(0, 0))
    with pytest.raises(ValueError, match="state 'stop' unknown"):
        turn_then_drive("stop", 1.0, 0.0)


def test_proportional_command_limits():
    far = proportional_command(2.0, 0.2)  # speed limit, times cos(alpha); w = 1.5 * 0.2
    assert far.v == pytest.approx(0.8 * math.cos(0.2)) and far.w == pytest.approx(0.3)
    assert proportional_command(0.3, 0.0).v == pytest.approx(0.24)  # k_rho * rho
    assert proportional_command(0.5, 0.0, k_rho=2.0).v == pytest.approx(math.sqrt(0.5))
    behind = proportional_command(2.0, -2.5)
    assert behind.v == 0.0 and behind.w == pytest.approx(-0.8)


def _open_sim(start):
    return SimBase(OPEN, errors="ideal", people=False, start=start)


def test_a_goal_just_left_of_west_is_a_small_left_turn():
    # facing west (pi); the goal's bearing is -2.82 rad: unwrapped that is 5.96 rad to
    # the right, wrapped it is 0.32 rad to the left
    sim = _open_sim(Pose2D(0, 0, math.pi))
    controller = ThesisGoToLandmark((-3.0, -1.0), Odometry(start=sim.pose))
    commands = []
    log = sim.run(lambda frame: commands.append(controller(frame)) or commands[-1], 15.0)
    first_turn = next(c.w for c in commands if c.w != 0)
    assert first_turn > 0  # left, towards the goal
    heading = np.unwrap(log.pose[:, 2])
    assert np.ptp(heading) < 0.6  # no long way round
    assert controller.status is Status.SUCCEEDED and controller.state == "reached"


def test_hysteresis_sets_off_better_aimed():
    def turn_phases(**options):
        sim = _open_sim(Pose2D(0, 0, 0))
        controller = ThesisGoToLandmark(GOAL, Odometry(start=sim.pose), tolerance=0.1,
                                        **options)
        states = []  # the bare chair: the count is of the controller's own turns
        sim.run(lambda frame: states.append(controller.state) or controller(frame), 30.0,
                safety=None)
        states.append(controller.state)
        assert controller.status is Status.SUCCEEDED
        return sum(a != "turn" and b == "turn" for a, b in zip(states, states[1:]))

    assert turn_phases(align_tolerance=0.1) < turn_phases()


def test_controller_settings_are_validated():
    with pytest.raises(ValueError, match="align_tolerance"):
        ThesisGoToLandmark((1.0, 1.0), Odometry(), align_tolerance=0.5)
    with pytest.raises(ValueError, match="speed"):
        ThesisGoToLandmark((1.0, 1.0), Odometry(), speed=-0.5)
    with pytest.raises(ValueError, match="k_alpha"):
        GoToLandmark((1.0, 1.0), Odometry(), k_alpha=0)
