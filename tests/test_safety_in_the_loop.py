"""The safety filter sits in every body's control loop: no controller goes round it.

Each behaviour, and a bare function, is sent at an obstacle. Through the body's own
filter the chair stops short of it, without contact; with ``safety=None`` (the bare
chair, for teaching) the same controller touches it. Behaviours whose own rules keep
them off walls (the navigator, the followers, the sign seeker) are sent "gone wrong":
their decision replaced by full ahead, the rest of the behaviour (its ``__call__``,
estimators, status) left as it is.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.base import BODY_FILTER
from abcwc.behaviours import (
    FollowWaypoints,
    GoToLandmark,
    GroundTruth,
    SquareDriver,
    ThesisGoToLandmark,
)
from abcwc.behaviours.find_sign import SignSeeker
from abcwc.behaviours.follow import TagFollower, ThesisFollower
from abcwc.behaviours.navigator import Navigator
from abcwc.behaviours.sonar_avoid import SonarAvoider
from abcwc.behaviours.voice import VoiceControl
from abcwc.control.safety import ComfortLimits, SafetyFilter
from abcwc.control.velocity import twist_to_pot_command
from abcwc.estimation import GyroOdometry, Odometry
from abcwc.perception.known_objects import KnownObject, ObjectDetector
from abcwc.perception.signs import WORD_BOX, house_sign
from abcwc.perception.speech.commands import CommandSet
from abcwc.perception.tags import FollowCard
from abcwc.sim import SimBase
from abcwc.sim.world import box_world, world_from_dict
from abcwc.types import Pose2D, PotCommand, StatusFlags, Twist, make_frame

WALL_X = 6.0  # m: the dead end's wall, 4.5 m ahead of the start
START = Pose2D(1.5, 1.5, 0.0)


def dead_end(**options) -> SimBase:
    """A 3 m wide dead end, its wall at x = 6 m; the chair at (1.5, 1.5) facing it."""
    world = world_from_dict({"name": "dead end",
                             "walls": [[[0, 0], [WALL_X, 0], [WALL_X, 3], [0, 3], [0, 0]]],
                             "places": {"start": [START.x, START.y, START.theta],
                                        "beyond": [WALL_X + 3.0, 1.5, 0.0]}})
    return SimBase(world, seed=1, errors="ideal", people=False, **options)


def reckless(behaviour, command=None):
    """``behaviour`` with its decision replaced by full ahead (gone wrong)."""
    behaviour.update = lambda frame: command or Twist(0.8, 0.0)
    return behaviour


def _navigator(chair):
    navigator = Navigator.for_world(chair.world)
    navigator.go_to("beyond")  # off the map: it fails, and a failed one stands still ...
    navigator.reset()  # ... so it is set running again, to be sent ahead
    return reckless(navigator)


def _exit_detector() -> ObjectDetector:
    return ObjectDetector([KnownObject("exit", house_sign("EXIT"), 0.6, WORD_BOX)])


CARD = FollowCard("ana", 7)
SENT_AT_THE_WALL = {
    "a bare function": lambda chair: (lambda frame: Twist(0.8, 0.0)),
    "GoToLandmark": lambda chair: GoToLandmark((WALL_X + 3, 1.5), GroundTruth()),
    "ThesisGoToLandmark": lambda chair: ThesisGoToLandmark((WALL_X + 3, 1.5), GroundTruth()),
    "FollowWaypoints": lambda chair: FollowWaypoints([(WALL_X + 3, 1.5)], GroundTruth()),
    "SquareDriver": lambda chair: SquareDriver(Odometry(chair.params, start=chair.pose),
                                               side=6.0),
    "VoiceControl": lambda chair: _heard(VoiceControl(CommandSet([])), "drive forward"),
    "Navigator (gone wrong)": _navigator,
    "TagFollower (gone wrong)": lambda chair: reckless(
        TagFollower(CARD, GyroOdometry(params=chair.params), chair.params)),
    "ThesisFollower (gone wrong)": lambda chair: reckless(ThesisFollower(CARD, chair.params)),
    "SignSeeker (gone wrong)": lambda chair: reckless(SignSeeker(_exit_detector(), "exit")),
}


def _heard(control: VoiceControl, phrase: str) -> VoiceControl:
    control.hear(phrase)
    return control


@pytest.mark.parametrize("name", list(SENT_AT_THE_WALL))
def test_every_controller_sent_at_a_wall_stops_short_of_it_and_bare_it_touches(name):
    seconds = 14.0
    filtered = dead_end(lidar=name.startswith("Navigator"))
    log = filtered.run(SENT_AT_THE_WALL[name](filtered), seconds)
    front = filtered.pose.x + filtered.params.length - filtered.params.axle_to_rear
    assert log.collisions[-1] == 0, name
    assert 0.0 < WALL_X - front < 0.6, name  # it did drive up, and stopped short
    assert abs(log.cmd_twist[-25:, 0]).max() < 1e-9 or (log.cmd_pots[-25:, 0] == 128).all()
    assert any(reason.startswith("obstacle") for reason in log.safety), name

    bare = dead_end(lidar=name.startswith("Navigator"))
    log = bare.run(SENT_AT_THE_WALL[name](bare), seconds, safety=None)
    assert log.collisions[-1] >= 1, f"{name}: the bare chair should have touched the wall"
    assert (log.safety == "").all()


def test_a_bare_function_at_the_lab_wall_stops_within_its_braking_distance():
    """The issue's case: ``chair.run(lambda f: Twist(0.8, 0.0), 10)`` in the lab (the
    east wall 8.5 m ahead of the start) ends without contact, and from the moment the
    filter first stopped it the chair rolled no farther than the braking distance the
    filter allowed for (the chair model's: reaction time times speed)."""
    chair = SimBase("lab", seed=0)
    log = chair.run(lambda frame: Twist(0.8, 0.0), 10.0)
    assert log.collisions[-1] == 0
    first = int(np.argmax(np.char.startswith(log.safety, "obstacle")))
    assert first > 0
    speed = float(np.hypot(*np.diff(log.pose[first - 1:first + 1, :2], axis=0)[0])) / chair.period
    rolled = float(np.hypot(*(log.pose[-1, :2] - log.pose[first, :2])))
    check = chair.safety.check
    assert rolled <= check.braking_distance(speed) - check.limits.stop_margin + 0.02
    assert np.hypot(*np.diff(log.pose[-2:, :2], axis=0)[0]) < 1e-4  # standing

    bare = SimBase("lab", seed=0)
    assert bare.run(lambda frame: Twist(0.8, 0.0), 10.0, safety=None).collisions[-1] >= 1


def test_the_sonar_avoider_reversing_blind_is_stopped_by_the_rear_ranger():
    """Table 7's rule backs off when something is near in front; the thesis's chair did
    so blind. In a box 0.95 m long the bare chair backs into the wall behind it; through
    the filter the rear IR rangers stop the reverse."""
    def boxed():
        world = box_world(0.95, 3.0)
        start = Pose2D(0.31, 1.5, 0.0)  # rear edge 0.15 m from the west wall
        return SimBase(world, seed=2, errors="ideal", people=False, start=start)

    chair = boxed()
    log = chair.run(SonarAvoider(), 6.0)
    assert log.collisions[-1] == 0
    assert any("behind" in reason for reason in log.safety)
    assert boxed().run(SonarAvoider(), 6.0, safety=None).collisions[-1] >= 1


def test_raw_pot_bytes_get_the_speed_cap_and_the_obstacle_stop_but_no_ramp():
    chair = dead_end()
    log = chair.run(lambda frame: PotCommand(253, 128), 12.0)  # full ahead, 6 km/h
    limits = chair.safety.limits
    assert log.collisions[-1] == 0
    driving = log.cmd_pots[:, 0] > 128
    assert driving[0]  # no ramp: the first period's bytes already drive
    # the velocity controller's bytes for the limits (1.0 m/s: 204; 0.8 rad/s: 64)
    assert log.cmd_pots[driving, 0].max() == twist_to_pot_command(Twist(limits.max_speed)).fb
    assert "speed limit" in log.safety[0]
    full_left = SafetyFilter(chair.params).apply(make_frame(0.0), PotCommand(128, 8))
    assert full_left.lr == twist_to_pot_command(Twist(0, limits.max_turn_rate)).lr
    assert (log.cmd_pots[-25:, 0] == 128).all()  # standing at the wall, FB at neutral


def test_the_joystick_stops_a_software_command_within_one_period_and_it_waits():
    chair = dead_end()
    chair.run(lambda frame: Twist(0.5, 0.0), 2.0)
    chair.set_joystick(fb=chair.params.joystick_centre - 40)  # pulled back
    log = chair.run(lambda frame: Twist(0.5, 0.0), 1.0)
    # in the first period the board hands the pots to the joystick; from the next the
    # filter, seeing the override flag, stops the software's command too
    assert (log.flags & StatusFlags.JOYSTICK_OVERRIDE).all()
    assert (log.pots[:, 0] < 128).all()  # the joystick drives, pulled back
    assert (log.cmd_twist[1:, 0] == 0.0).all()
    assert (log.safety[1:] == "joystick override").all()
    chair.release_joystick()
    log = chair.run(lambda frame: Twist(0.5, 0.0), 2.0)
    resumed = np.flatnonzero(log.cmd_twist[:, 0] > 0)[0] * chair.period
    assert resumed == pytest.approx(chair.safety.limits.resume_delay, abs=2 * chair.period)


def test_a_behaviour_whose_decision_goes_stale_is_stopped():
    """A planner that stops deciding (a 1 Hz behaviour, its command repeated) is
    stopped by the filter once its decision is older than ``stale_after``."""
    chair = dead_end()
    behaviour = GoToLandmark((4.0, 1.5), GroundTruth(), rate_hz=1.0)
    log = chair.run(behaviour, 2.0)
    stale = np.char.startswith(log.safety, "stale command")
    assert stale.any() and (log.cmd_twist[stale, 0] == 0.0).all()


def test_run_takes_a_filter_of_ones_own_or_none_and_refuses_anything_else():
    chair = dead_end()
    gentle = SafetyFilter(chair.params, ComfortLimits(max_speed=0.3))
    log = chair.run(lambda frame: Twist(0.8, 0.0), 3.0, safety=gentle)
    assert log.cmd_twist[:, 0].max() == pytest.approx(0.3)
    assert chair.safety is not gentle  # the body's own filter is back
    with pytest.raises(ValueError, match="SafetyFilter, or None"):
        chair.run(lambda frame: Twist(0.1, 0.0), 1.0, safety="off")
    assert repr(BODY_FILTER) == "BODY_FILTER"


def test_a_stop_is_never_filtered_and_restarts_the_ramp():
    chair = dead_end()
    chair.run(lambda frame: Twist(0.6, 0.0), 3.0)
    assert chair.safety.v == pytest.approx(0.6)
    chair.stop()
    assert chair.safety.v == 0.0
    sent = chair.send(Twist(0.6, 0.0))
    assert 0.0 < sent.v < 0.01  # ramping up from standing again
    assert math.isclose(chair.last_command.fb, 128, abs_tol=3)


def test_a_stop_asked_for_near_a_wall_is_not_left_to_the_comfort_ramp():
    """A controller that sees the wall late and asks to stop: the comfort ramp alone
    would roll the chair over a metre from 0.8 m/s, into the wall; the obstacle stop
    also guards the way the chair still rolls, so it brakes at once."""
    def late_stopper(frame):
        return Twist(0.8, 0.0) if frame.sonar > 0.6 else Twist(0.0, 0.0)

    chair = SimBase("lab", seed=0, start=Pose2D(5.0, 6.0, 0.0), people=False)
    log = chair.run(late_stopper, 10.0)
    assert log.collisions[-1] == 0
    asked = int(np.argmax(log.wanted_twist[:, 0] == 0.0))
    stopped = np.flatnonzero(np.char.startswith(log.safety, "obstacle"))
    assert len(stopped) and stopped[0] >= asked  # the stop came while it braked
    assert (log.cmd_twist[stopped[0]:, 0] == 0.0).all()
