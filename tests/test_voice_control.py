"""Driving by voice or typed command: VoiceControl in the simulated lab."""

import math

import pytest

from abcwc.behaviours.navigator import Navigator
from abcwc.behaviours.voice import VoiceControl
from abcwc.perception.speech.commands import CommandSet
from abcwc.sim import SimBase
from abcwc.types import Pose2D


def drive(chair, control, script, seconds):
    frame = chair.read()
    script = dict(script)
    while chair.t < seconds:
        for t in [t for t in script if chair.t >= t]:
            control.hear(script.pop(t))
        chair.send(control(frame))
        frame = chair.step()
    return frame


def test_typed_commands_drive_turn_and_stop():
    chair = SimBase("lab", seed=1, start=Pose2D(2.0, 4.0, 0.0))
    control = VoiceControl(CommandSet(chair.world.places))
    drive(chair, control, {0.1: "drive forward"}, 3.0)
    moved = chair.pose
    assert moved.x - 2.0 > 0.8 and abs(moved.y - 4.0) < 0.05   # ~0.5 m/s, straight
    drive(chair, control, {3.0: "turn left"}, 5.0)
    assert chair.pose.theta > 0.4                              # turned left on the spot
    assert math.hypot(chair.pose.x - moved.x, chair.pose.y - moved.y) < 0.5
    drive(chair, control, {5.0: "stop"}, 7.0)
    still = chair.pose
    drive(chair, control, {}, 8.0)
    assert math.hypot(chair.pose.x - still.x, chair.pose.y - still.y) < 1e-3
    assert [p for _, p in control.heard] == ["drive forward", "turn left", "stop"]


def test_a_motion_lapses_after_its_hold_time():
    chair = SimBase("lab", seed=1, start=Pose2D(2.0, 4.0, math.pi / 2))
    control = VoiceControl(CommandSet(chair.world.places), hold_seconds=1.0)
    drive(chair, control, {0.1: "turn right"}, 3.0)
    heading = chair.pose.theta
    drive(chair, control, {}, 4.0)
    assert chair.pose.theta == pytest.approx(heading, abs=1e-3)
    assert heading < math.pi / 2 - 0.2


def test_the_wall_stops_a_spoken_drive_forward():
    chair = SimBase("lab", seed=1, start=Pose2D(8.0, 2.0, 0.0))   # 2 m from the east wall
    control = VoiceControl(CommandSet(chair.world.places))
    drive(chair, control, {0.1: "drive forward"}, 9.0)
    assert chair.collisions == 0
    assert chair.safety.interventions["obstacle"]               # the loop's filter stopped it


def test_go_to_a_place_hands_over_to_the_navigator_and_stop_cancels_it():
    chair = SimBase("lab", seed=1, lidar=True)
    navigator = Navigator.for_world(chair.world)
    control = VoiceControl(CommandSet(chair.world.places), navigator=navigator)
    drive(chair, control, {0.1: "go to the door"}, 40.0)
    door = chair.world.places["door"]
    assert control.last_outcome == "succeeded"
    assert math.hypot(chair.pose.x - door.x, chair.pose.y - door.y) < 0.5
    drive(chair, control, {40.0: "go to the table", 41.0: "stop"}, 43.0)
    assert not navigator.running and control.last_outcome == "cancelled"


def test_commands_it_cannot_obey_are_refused():
    control = VoiceControl(CommandSet(["lab"]))
    with pytest.raises(ValueError, match="needs a navigator"):
        control.hear("go to the lab")
    with pytest.raises(ValueError, match="needs a follower"):
        control.hear("follow me")
    with pytest.raises(ValueError, match="is not a command"):
        control.hear("go left")
    with pytest.raises(ValueError, match="hold_seconds"):
        VoiceControl(CommandSet(), hold_seconds=0)
