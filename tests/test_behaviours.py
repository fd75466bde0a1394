"""The behaviour interface: status, rate, reset and cancel, and bad input refused."""

import math

import pytest

from abcwc.behaviours import (
    LOOP_RATE_HZ,
    Behaviour,
    BehaviourBase,
    FollowWaypoints,
    GoToLandmark,
    GroundTruth,
    SonarAvoider,
    SquareDriver,
    Status,
    ThesisGoToLandmark,
)
from abcwc.estimation import Odometry
from abcwc.sim.base import SimBase
from abcwc.types import NEUTRAL, Pose2D, SimTruth, Twist, make_frame

PERIOD = 1.0 / LOOP_RATE_HZ


def frames(seconds):
    """Frames of a chair standing still every 20 ms for ``seconds`` s."""
    return [make_frame(k * PERIOD) for k in range(round(seconds / PERIOD))]


class Counting(BehaviourBase):
    """Counts its observations and decisions; its command says which decision it is."""

    def __init__(self, rate_hz):
        super().__init__(rate_hz)
        self.observed = self.decided = 0

    def observe(self, frame):
        self.observed += 1

    def update(self, frame):
        self.decided += 1
        return Twist(0.1 * self.decided, 0.0)


@pytest.mark.parametrize("rate_hz, decisions", [(5.0, 5), (10.0, 10), (50.0, 50), (200.0, 50)])
def test_a_behaviour_decides_at_its_rate_and_observes_every_frame(rate_hz, decisions):
    behaviour = Counting(rate_hz)
    commands = [behaviour(frame) for frame in frames(1.0)]
    assert behaviour.observed == 50
    assert behaviour.decided == decisions
    # between decisions the last command is repeated, never None
    assert len(set(commands)) == decisions and all(c is not None for c in commands)
    assert commands[0] == Twist(0.1, 0.0)


def test_a_late_loop_does_not_make_a_behaviour_catch_up():
    behaviour = Counting(10.0)
    for t in (0.0, 0.02, 0.5, 0.52, 0.6):  # the loop stalled from 0.02 to 0.5 s
        behaviour(make_frame(t))
    assert behaviour.decided == 3  # at 0, at 0.5 (late), at 0.6; not a burst at 0.5


def test_status_cancel_and_reset():
    goal = GoToLandmark((3.0, 0.0), GroundTruth(), tolerance=0.1)
    assert isinstance(goal, Behaviour) and goal.status is Status.RUNNING
    assert goal.failure is None
    driving = goal(make_frame(0.0, truth=SimTruth(Pose2D())))
    assert driving.v > 0
    goal.cancel()
    assert goal.status is Status.FAILED and goal.failure == "cancelled"
    assert goal(make_frame(0.02, truth=SimTruth(Pose2D()))) == Twist(0.0, 0.0)
    goal.reset()
    assert goal.status is Status.RUNNING and goal.failure is None
    assert goal(make_frame(0.04, truth=SimTruth(Pose2D()))) == driving
    # within the tolerance: succeeded, and stays so when the chair drifts away again
    assert goal(make_frame(0.06, truth=SimTruth(Pose2D(2.95, 0.0, 0.0)))) == Twist(0.0, 0.0)
    assert goal.status is Status.SUCCEEDED
    assert goal(make_frame(0.08, truth=SimTruth(Pose2D(1.0, 0.0, 0.0)))) == Twist(0.0, 0.0)
    assert goal.status is Status.SUCCEEDED
    goal.cancel()  # cancelling a finished behaviour changes nothing
    assert goal.status is Status.SUCCEEDED


def test_fail_needs_a_reason_and_stops_the_chair():
    behaviour = Counting(50.0)
    with pytest.raises(ValueError, match="reason"):
        behaviour.fail("")
    behaviour.fail("path blocked")
    assert behaviour.status is Status.FAILED and behaviour.failure == "path blocked"
    assert behaviour(make_frame(0.0)) == Twist(0.0, 0.0)
    assert behaviour.observed == 1 and behaviour.decided == 0


def test_every_behaviour_follows_the_interface():
    odometry = Odometry()
    for behaviour in (GoToLandmark((1.0, 0.0), odometry), ThesisGoToLandmark((1, 0), odometry),
                      FollowWaypoints([(1.0, 0.0)], GroundTruth()), SquareDriver(odometry),
                      SonarAvoider()):
        assert isinstance(behaviour, Behaviour), type(behaviour).__name__
        assert behaviour.status is Status.RUNNING and behaviour.rate_hz == LOOP_RATE_HZ


def test_a_cancelled_sonar_avoider_sends_neutral_pots():
    avoider = SonarAvoider()
    assert avoider(make_frame(0.0)) != NEUTRAL  # cruising
    avoider.cancel()
    assert avoider(make_frame(0.02)) == NEUTRAL


def test_waypoints_succeed_after_the_last_and_reset_restarts_the_route():
    route = FollowWaypoints([(1.0, 0.0), (1.0, 1.0)], GroundTruth(), tolerance=0.2)
    route(make_frame(0.0, truth=SimTruth(Pose2D())))
    assert route.index == 0
    route(make_frame(0.02, truth=SimTruth(Pose2D(0.9, 0.0, 0.0))))
    assert route.index == 1 and route.status is Status.RUNNING
    assert route(make_frame(0.04, truth=SimTruth(Pose2D(1.0, 0.9, 0.0)))) == Twist(0.0, 0.0)
    assert route.status is Status.SUCCEEDED
    route.reset()
    assert route.index == 0 and route.status is Status.RUNNING
    assert route(make_frame(0.06, truth=SimTruth(Pose2D(-1.0, 0.0, 0.0)))).v > 0


def test_a_goal_behaviour_at_5_hz_still_reaches_its_goal():
    """In the simulator, deciding at 5 Hz inside the 50 Hz loop is slower, not wrong."""
    results = {}
    for rate in (50.0, 5.0):
        sim = SimBase("lab", seed=0, people=False)
        goal = (sim.pose.x + 2.0, sim.pose.y)
        behaviour = GoToLandmark(goal, GroundTruth(), tolerance=0.1, max_speed=0.5,
                                 rate_hz=rate)
        sim.run(behaviour, 15.0)
        results[rate] = math.hypot(sim.pose.x - goal[0], sim.pose.y - goal[1])
        assert behaviour.status is Status.SUCCEEDED
    assert results[5.0] < 0.2 and results[50.0] < 0.2


def test_the_square_driver_succeeds_after_four_legs():
    sim = SimBase("lab", seed=0, people=False)
    driver = SquareDriver(Odometry(sim.params, start=sim.pose), side=1.0)
    sim.run(driver, 45.0)
    assert driver.status is Status.SUCCEEDED and driver.leg == 4
    assert math.hypot(driver.pose.x - driver.start.x, driver.pose.y - driver.start.y) < 0.02


@pytest.mark.parametrize("make, message", [
    (lambda: GoToLandmark("ab", Odometry()), "goal must be a finite"),
    (lambda: GoToLandmark((1.0, True), Odometry()), "goal must be a finite"),
    (lambda: GoToLandmark((1.0, 2.0, 3.0), Odometry()), "goal must be a finite"),
    (lambda: GoToLandmark((1.0, 2.0), Odometry(), rate_hz=0), "rate_hz"),
    (lambda: FollowWaypoints("ab", GroundTruth()), "waypoints"),
    (lambda: FollowWaypoints([(0, 0)], GroundTruth(), tolerance=-1), "tolerance"),
    (lambda: FollowWaypoints([(0, 0)], None), "observe\\(frame\\) and pose"),
    (lambda: SonarAvoider(near=-1), "near"),
    (lambda: SonarAvoider(near=9.0), "near"),
    (lambda: SonarAvoider(reverse_time=math.nan), "reverse_time"),
    (lambda: SonarAvoider(cruise=5.0), "cruise"),
    (lambda: SquareDriver(Odometry(), side=0), "side"),
    (lambda: SquareDriver(Odometry(), direction="left"), "direction"),
    (lambda: SquareDriver(Odometry(), settle=-1), "settle"),
])
def test_bad_settings_are_refused_with_what_is_allowed(make, message):
    with pytest.raises(ValueError, match=message):
        make()



def test_the_freer_side_counts_too_close_as_no_room_and_clear_as_the_ir_range():
    from abcwc.behaviours.sonar_avoid import freer_side

    inf = math.inf
    # ring: 0 ahead, 1 front-left, 2 back-left, 3 behind, 4 back-right, 5 front-right
    assert freer_side([1.0, 1.2, 0.5, 1.0, 0.4, 1.2], 1.5) == 1.0  # 1.7 m left, 1.6 right
    assert freer_side([1.0, -inf, 1.5, 1.0, 0.4, 1.0], 1.5) == 1.0  # too close: 0, not -inf
    assert freer_side([1.0, inf, 0.1, 1.0, 0.2, 1.5], 1.5) == -1.0  # clear: 1.5, not inf
    assert freer_side([1.0, 0.5, 0.5, 1.0, 0.5, 0.5], 1.5) == 1.0  # a tie goes left
