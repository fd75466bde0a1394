"""Physics a test can trust: straight lines, spins, encoder truth, a curving chair.

The chairs here are bare (``safety = None``): these tests measure the simulator's
physics under the commands as given, not the safety filter's ramps and stops."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.sim import ChairErrors, SimBase
from abcwc.sim.world import box_world
from abcwc.types import Pose2D, PotCommand, Twist
from tests.conftest import noise_free


def bare(chair: SimBase) -> SimBase:
    """``chair`` with its safety filter taken away."""
    chair.safety = None
    return chair


def ideal_chair(**options) -> SimBase:
    return bare(SimBase(world=box_world(), errors="ideal", params=noise_free(), **options))


def test_equal_pots_drive_straight_over_5_m():
    chair = ideal_chair()
    log = chair.run(lambda f: PotCommand(200, 128), 20.0)
    travelled = np.hypot(*(log.pose[:, :2] - log.pose[0, :2]).T)
    end = int(np.argmax(travelled >= 5.0))
    assert end > 0, "the chair did not cover 5 m"
    heading_change = abs(math.degrees(log.pose[end, 2] - log.pose[0, 2]))
    assert heading_change < 1.0
    assert abs(log.pose[end, 1] - log.pose[0, 1]) < 0.01


def test_pure_turn_spins_in_place(params):
    chair = ideal_chair()
    log = chair.run(lambda f: PotCommand(128, 8), 6.0)
    drift = np.hypot(*(log.pose[:, :2] - log.pose[0, :2]).T).max()
    assert drift < 0.01
    turned = np.unwrap(log.pose[:, 2])
    rate = np.diff(turned[-100:]).mean() / chair.period  # steady state
    assert rate == pytest.approx(params.max_turn_rate * 118 / 123, rel=0.01)  # LR 8 = -0.959


def wheel_paths(log, half_base: float) -> tuple[float, float]:
    """Path lengths of the true left and right wheel contact points (m, signed)."""
    x, y, th = log.pose.T
    lengths = []
    for side in (+1, -1):
        wx, wy = x - side * half_base * np.sin(th), y + side * half_base * np.cos(th)
        dx, dy = np.diff(wx), np.diff(wy)
        forward = np.sign(dx * np.cos(th[:-1]) + dy * np.sin(th[:-1]))
        lengths.append(float((forward * np.hypot(dx, dy)).sum()))
    left, right = lengths
    return left, right


def test_encoder_counts_match_true_wheel_travel(params):
    chair = ideal_chair()
    commands = [Twist(0.8, 0.0), Twist(0.5, 0.4), Twist(0.3, -0.8), Twist(-0.4, 0.2)]
    log = chair.run(lambda f: commands[int(f.t // 5) % 4], 20.0)
    true_left, true_right = wheel_paths(log, params.wheel_base / 2)
    counted = (log.ticks[-1] - log.ticks[0]) * params.distance_per_count
    assert counted[0] == pytest.approx(true_left, abs=0.002 + 0.002 * abs(true_left))
    assert counted[1] == pytest.approx(true_right, abs=0.002 + 0.002 * abs(true_right))


def test_two_percent_wheel_diameter_error_curves_as_predicted(params):
    # right tyre 2 % larger: v_r = 1.02 v_l, so the path bends left with radius
    # R = (b / 2) (v_r + v_l) / (v_r - v_l) = (0.44 / 2) * 2.02 / 0.02 = 22.22 m.
    errors = ChairErrors(drive_wheel_right=1.02)
    chair = bare(SimBase(world=box_world(80, 80), errors=errors, params=noise_free()))
    log = chair.run(lambda f: PotCommand(200, 128), 30.0)
    steady = log.t > 2.0
    pose = log.pose[steady]
    heading = np.unwrap(pose[:, 2])
    arc = np.hypot(*np.diff(pose[:, :2], axis=0).T).sum()
    radius = arc / (heading[-1] - heading[0])
    expected = params.wheel_base / 2 * 2.02 / 0.02
    assert radius > 0, "a larger right tyre must curve left"
    assert radius == pytest.approx(expected, rel=0.02)


def test_velocity_controller_reaches_asked_speed(params):
    chair = ideal_chair()
    log = chair.run(lambda f: Twist(0.6, 0.3), 10.0)
    late = log.t > 5.0
    step = np.diff(log.pose[late], axis=0)
    speed = np.hypot(step[:, 0], step[:, 1]).mean() / chair.period
    rate = np.diff(np.unwrap(log.pose[late, 2])).mean() / chair.period
    assert speed == pytest.approx(0.6, abs=0.015)
    assert rate == pytest.approx(0.3, abs=0.01)


def test_motor_lag_and_delay_shape_the_step_response(params):
    chair = ideal_chair()
    log = chair.run(lambda f: PotCommand(253, 128), 2.0)
    speed = np.hypot(*np.diff(log.pose[:, :2], axis=0).T) / chair.period
    # nothing moves for the command delay, then a first-order rise with tau = 0.25 s
    delay_steps = round(params.command_delay / chair.period)
    assert np.all(speed[:delay_steps] == 0)
    t63 = (np.argmax(speed > 0.632 * params.max_speed) - delay_steps) * chair.period
    assert t63 == pytest.approx(params.motor_time_constant, abs=0.03)


def test_collision_with_a_wall_is_counted():
    chair = bare(SimBase(world=box_world(6, 6), errors="ideal", start=Pose2D(3, 3, 0)))
    log = chair.run(lambda f: PotCommand(253, 128), 6.0)
    assert log.collisions[-1] >= 1
    assert chair.collision_impulse > 0
    assert log.pose[:, 0].max() < 6.0 - 0.45 + 0.02  # the wall stopped the chair's front


def test_walkers_move_and_sensors_see_them():
    world = box_world(20, 20)
    from abcwc.sim.world import world_from_dict

    world = world_from_dict({
        "name": "box+person", "walls": [[[0, 0], [20, 0], [20, 20], [0, 20], [0, 0]]],
        "places": {"start": [5, 10, 0]},
        "people": [{"path": [[8, 10], [8.01, 10]], "speed": 0.01, "radius": 0.25}],
    })
    chair = bare(SimBase(world=world, errors="ideal", params=noise_free()))
    sonar_x = 5 + chair.params.sonar.mount[0]
    assert chair.frame.sonar == pytest.approx(8 - 0.25 - sonar_x, abs=0.002)


def test_same_seed_same_run_and_other_seed_differs():
    def drive(seed):
        chair = bare(SimBase(seed=seed))
        return chair.run(lambda f: Twist(0.5, 0.2 * math.sin(f.t)), 5.0)

    a, b, c = drive(3), drive(3), drive(4)
    for name in ("pose", "ticks", "gyro_z", "sonar", "ir"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert not np.array_equal(a.gyro_z, c.gyro_z)


def _box_with_walker(start: list, path: list, speed: float):
    from abcwc.sim.world import world_from_dict

    return world_from_dict({
        "name": "box+walker", "walls": [[[0, 0], [20, 0], [20, 20], [0, 20], [0, 0]]],
        "places": {"start": start},
        "people": [{"path": path, "speed": speed, "radius": 0.25, "loop": False}],
    })


def test_a_walker_stops_for_a_chair_in_its_way_and_then_turns_back():
    """A person walking towards a standing chair stops a step short of it, waits, turns
    round and goes back the way they came; they never touch it."""
    from abcwc.sim.people import LOOK_AHEAD, TURN_TIME, WAIT_PATIENCE

    world = _box_with_walker([10, 10, math.pi / 2], [[6, 10], [18, 10]], 1.0)
    chair = bare(SimBase(world=world, errors="ideal", params=noise_free()))
    walker = chair.walkers[0]
    gaps, xs = [], []
    for _ in range(round(8.0 / chair.period)):
        frame = chair.step()
        gaps.append(chair._chair_shape.point_query(walker.body.position).distance - 0.25)
        xs.append(walker.circle[0])
    assert frame.truth.collisions == 0
    assert LOOK_AHEAD - 0.05 < min(gaps) <= LOOK_AHEAD  # within a step of the look-ahead
    stood = np.sum(np.diff(xs) == 0.0) * chair.period
    assert stood == pytest.approx(WAIT_PATIENCE + TURN_TIME, abs=2 * chair.period)
    assert xs[-1] < max(xs) - 2.0  # walking back


def test_a_walker_bumped_from_the_side_stops_instead_of_shoving_the_chair():
    """A chair that drives into a person's side stops on the contact; the person stands
    for the bump pause and walks back the way they came, and the chair is not shoved (a
    kinematic body has infinite mass)."""
    from abcwc.sim.people import BUMP_PAUSE

    world = _box_with_walker([10, 8.0, math.pi / 2], [[6, 10], [18, 10]], 0.5)
    chair = bare(SimBase(world=world, errors="ideal", params=noise_free()))
    walker = chair.walkers[0]
    poses, walker_x, collisions = [], [], []
    for _ in range(round(12.0 / chair.period)):
        frame = chair.frame
        chair.send(Twist(0.0 if frame.truth.collisions or frame.t < 5.0 else 0.6, 0.0))
        frame = chair.step()
        poses.append(chair.pose)
        walker_x.append(walker.circle[0])
        collisions.append(frame.truth.collisions)
    touched = int(np.argmax(np.array(collisions) > 0))
    assert touched > 0 and collisions[-1] == 1
    assert math.hypot(poses[-1].x - poses[touched].x, poses[-1].y - poses[touched].y) < 0.05
    # it stood for the pause, then walked back at its speed
    walked_back = walker_x[touched] - walker_x[-1]
    seconds_left = (len(poses) - 1 - touched) * chair.period
    assert walked_back == pytest.approx(0.5 * (seconds_left - BUMP_PAUSE), abs=0.1)


@pytest.mark.parametrize(("offset", "passes"), [(0.05, False), (0.2, True)])
def test_a_walker_keeps_a_passing_clearance_from_the_chair(offset, passes):
    """A person whose way would brush the chair's side (5 cm) stops before it; one whose
    way keeps 20 cm off walks by. The chair stands at (10, 10) facing +y, its left side
    at x = 10 - 0.241."""
    from abcwc.sim.people import PASSING_CLEARANCE

    assert 0.05 < PASSING_CLEARANCE < 0.2
    side = 10.0 - 0.241 - 0.25 - offset  # the walker's centre line
    world = _box_with_walker([10, 10, math.pi / 2], [[side, 6], [side, 18]], 1.0)
    chair = bare(SimBase(world=world, errors="ideal", params=noise_free()))
    walker = chair.walkers[0]
    for _ in range(round(8.0 / chair.period)):
        frame = chair.step()
        assert frame.truth.collisions == 0
        if walker.circle[1] > 11.0:
            break
    assert (walker.circle[1] > 11.0) == passes
