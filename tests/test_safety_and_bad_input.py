"""The board's safety rules in the simulator, and clear errors on bad input."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from abcwc.control import InterfaceBoard
from abcwc.sim import SimBase, WorldError, load_world
from abcwc.sim.world import box_world
from abcwc.types import Pose2D, PotCommand, StatusFlags, Twist


def test_joystick_overrides_host_within_one_period():
    chair = SimBase(world=box_world(), errors="ideal")
    chair.safety = None  # the board's own rule, whatever the host sends
    chair.send(PotCommand(8, 128))  # host: full reverse
    chair.step()
    chair.set_joystick(fb=398)  # person pushes forward
    chair.send(PotCommand(8, 128))
    frame = chair.step()
    assert (frame.pot_fb, frame.pot_lr) == (253, 130)
    assert frame.flags & StatusFlags.JOYSTICK_OVERRIDE
    chair.release_joystick()
    frame = chair.step()  # the old command does not come back by itself
    assert frame.pot_fb == 128 and not frame.flags & StatusFlags.JOYSTICK_OVERRIDE
    chair.send(PotCommand(8, 128))
    frame = chair.step()
    assert frame.pot_fb == 8


def test_stale_command_stops_the_chair_within_250_ms():
    chair = SimBase(world=box_world(), errors="ideal")
    chair.send(PotCommand(200, 128))
    pots = []
    for _ in range(20):
        frame = chair.step()
        pots.append((frame.t, frame.pot_fb, bool(frame.flags & StatusFlags.WATCHDOG_TRIPPED)))
    # a frame stamped t reports the pots the board set at the start of its period
    tripped = [t - chair.period for t, fb, flag in pots if flag]
    assert tripped and tripped[0] <= 0.25 + chair.period + 1e-9
    assert all(fb == 128 for t, fb, flag in pots if flag)
    assert all(fb == 200 for t, fb, flag in pots if t < 0.25)


def test_pot_outputs_are_clamped_to_the_safe_range():
    board = InterfaceBoard()
    board.command(PotCommand(255, 0), now=0.0)
    out = board.update(0.0, 254, 254)
    assert out.pots == PotCommand(253, 8)
    assert out.flags & StatusFlags.SPEED_CAPPED and out.flags & StatusFlags.HOST_ACTIVE


def test_speed_cap_limits_host_but_not_joystick():
    board = InterfaceBoard()
    board.set_speed_cap(40)
    board.command(PotCommand(253, 20), now=0.0)
    out = board.update(0.0, 254, 254)
    assert out.pots == PotCommand(168, 88) and out.flags & StatusFlags.SPEED_CAPPED
    assert board.update(0.0, 398, 254).pots.fb == 253
    with pytest.raises(ValueError, match="0..125"):
        board.set_speed_cap(200)


def test_implausible_joystick_reading_is_a_fault_and_stops():
    board = InterfaceBoard()
    board.command(PotCommand(200, 128), now=0.0)
    out = board.update(0.0, 1023, 254)  # a shorted joystick wire
    assert out.pots == PotCommand(128, 128) and out.flags & StatusFlags.JOYSTICK_FAULT


@pytest.mark.parametrize("fb, lr, message", [
    (256, 128, "fb pot 256 outside 0..255"),
    (128, -1, "lr pot -1 outside 0..255"),
    (12.5, 128, "integer byte 0..255"),
])
def test_bad_pot_bytes_are_refused(fb, lr, message):
    with pytest.raises(ValueError, match=message):
        PotCommand(fb, lr)


@pytest.mark.parametrize("v, w", [(float("nan"), 0.0), (0.0, float("inf")), ("fast", 0.0)])
def test_bad_twists_are_refused(v, w):
    with pytest.raises(ValueError, match="finite number"):
        Twist(v, w)


@pytest.mark.parametrize("x, y, theta", [(math.nan, 0.0, 0.0), (0.0, -math.inf, 0.0),
                                         (0.0, 0.0, math.inf), (0.0, 0.0, "north"),
                                         (None, 0.0, 0.0)])
def test_poses_that_are_not_finite_numbers_are_refused(x, y, theta):
    with pytest.raises(ValueError, match=r"Pose2D\.\w+ \((m|rad)\) must be a finite number"):
        Pose2D(x, y, theta)


def test_a_pose_holds_floats():
    pose = Pose2D(1, np.float64(2.5), np.int64(0))
    assert pose == Pose2D(1.0, 2.5, 0.0)
    assert all(type(v) is float for v in (pose.x, pose.y, pose.theta))


def test_bad_commands_leave_the_simulator_unharmed():
    chair = SimBase(world=box_world(), errors="ideal")
    chair.send(Twist(0.5, 0.0))
    chair.step()
    before = chair.pose
    with pytest.raises(TypeError, match="PotCommand or Twist"):
        chair.send((200, 128))
    with pytest.raises(ValueError, match="0..1023"):
        chair.set_joystick(fb=2000)
    with pytest.raises(ValueError, match="finite number"):
        chair.run(lambda f: None, float("nan"))
    assert chair.pose == before
    for _ in range(25):  # the safety filter's ramp and the motors' delay take a few periods
        chair.send(Twist(0.5, 0.0))
        chair.step()
    assert chair.pose.x > before.x


def test_unknown_world_lists_the_available_ones():
    with pytest.raises(WorldError, match="unknown world 'moon'.*floor.*lab"):
        load_world("moon")


@pytest.mark.parametrize("content, message", [
    ("{not json", "not valid JSON"),
    (json.dumps({"name": "x", "walls": [[[0, 0], [1, 0]]]}), "missing places"),
    (json.dumps({"name": "x", "walls": [[[0, 0]]], "places": {"start": [0, 0, 0]}}),
     r"walls\[0\] must be a list of at least 2 points"),
    (json.dumps({"name": "x", "walls": [[[0, 0], [1, "a"]]], "places": {"start": [0, 0, 0]}}),
     "expected a point"),
    (json.dumps({"name": "x", "walls": [[[0, 0], [1, 0]]], "places": {"door": [0, 0, 0]}}),
     "must include 'start'"),
    (json.dumps({"name": "x", "walls": [[[0, 0], [1, 0]]], "places": {"start": [0, 0, 0]},
                 "people": [{"path": [[0, 0], [1, 1]], "speed": 9}]}), r"speed 9 outside 0..3"),
    (json.dumps({"name": "x", "walls": [[[0, 0], [1, 0]]], "places": {"start": [0, 0, 0]},
                 "doors": []}), "unknown key"),
])
def test_malformed_world_files_say_what_is_wrong(tmp_path, content, message):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(WorldError, match=message):
        load_world(path)


def test_bad_simulator_options():
    with pytest.raises(ValueError, match="non-negative integer"):
        SimBase(seed=-1)
    with pytest.raises(ValueError, match="unknown place 'roof'"):
        SimBase(start="roof")
    with pytest.raises(ValueError, match="'ideal', 'worn'"):
        SimBase(errors="broken")


def test_shipped_worlds_load_and_are_closed_enough():
    for name in ("lab", "floor"):
        world = load_world(name)
        assert len(world.walls) > 10
        xmin, ymin, xmax, ymax = world.bounds
        for place in world.places.values():
            assert xmin < place.x < xmax and ymin < place.y < ymax
        chair = SimBase(world=name, errors="ideal")
        assert np.isfinite(chair.frame.sonar)


def test_sonar_avoider_on_a_real_chairs_frames():
    """The real chair's frames: IR NaN (not wired), sonar NaN with no echo. NaN sonar is
    nothing in range (drive on); a near sonar echo still turns, to the right."""
    from dataclasses import replace

    from abcwc.behaviours import SonarAvoider
    from abcwc.control import twist_to_pot_command

    sim = SimBase("lab", seed=0)
    frame = replace(sim.frame, ir=np.full(6, np.nan), sonar=math.nan, truth=None)
    avoider = SonarAvoider(cruise=0.3)
    assert avoider(frame) == twist_to_pot_command(Twist(0.3, 0.0))
    turn = avoider(replace(frame, sonar=0.6))
    assert turn.lr > 128  # LR above 128 turns right
