"""Every range sensor against the analytic distance to a wall; encoders and gyro."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.sim import SimBase
from abcwc.sim.raycast import cone_nearest_distance, ray_segment_distances
from abcwc.sim.sensors import sensor_pose
from abcwc.sim.world import box_world
from abcwc.types import Pose2D
from tests.conftest import noise_free

W, H = 8.0, 6.0


def distance_to_box(origin: np.ndarray, angle: float) -> float:
    """Closed form: the ray from ``origin`` at ``angle`` leaves the box [0,W]x[0,H]."""
    c, s = math.cos(angle), math.sin(angle)
    candidates = []
    if c > 1e-12:
        candidates.append((W - origin[0]) / c)
    if c < -1e-12:
        candidates.append(-origin[0] / c)
    if s > 1e-12:
        candidates.append((H - origin[1]) / s)
    if s < -1e-12:
        candidates.append(-origin[1] / s)
    return min(candidates)


@pytest.fixture
def chair():
    pose = Pose2D(3.1, 2.4, 0.7)
    return SimBase(world=box_world(W, H), errors="ideal", params=noise_free(), start=pose,
                   lidar=True, depth_scan=True)


def test_lidar_matches_closed_form(chair):
    scan = chair.frame.lidar
    origin, heading = sensor_pose(chair.pose, chair.params.lidar.mount)
    expected = np.array([distance_to_box(origin, heading + a) for a in scan.angles])
    np.testing.assert_allclose(scan.ranges, expected, atol=1e-9)
    assert len(scan.ranges) == 360


def test_depth_scan_matches_closed_form_and_range_limits(chair):
    scan = chair.frame.depth_scan
    p = chair.params.depth_scan
    origin, heading = sensor_pose(chair.pose, p.mount)
    expected = np.array([distance_to_box(origin, heading + a) for a in scan.angles])
    expected[expected > p.max_range] = np.inf
    expected[expected < p.min_range] = -np.inf
    np.testing.assert_allclose(scan.ranges, expected, atol=1e-9)
    assert scan.angles[-1] - scan.angles[0] == pytest.approx(math.radians(57))


def test_ir_ring_matches_closed_form(chair):
    p = chair.params.ir
    readings = chair.frame.ir
    for k in range(6):
        mount = tuple(chair.ir.mounts[k])
        origin, heading = sensor_pose(chair.pose, mount)
        d = distance_to_box(origin, heading)
        expected = np.inf if d > p.max_range else (-np.inf if d < p.min_range else d)
        assert readings[k] == pytest.approx(expected, abs=1e-9)


def test_ir_sees_a_near_wall_in_range():
    chair = SimBase(world=box_world(W, H), errors="ideal", params=noise_free(),
                    start=Pose2D(7.0, 3.0, 0.0))
    p = chair.params.ir
    x_sensor = 7.0 + p.ring_centre[0] + p.ring_radius
    assert chair.frame.ir[0] == pytest.approx(W - x_sensor, abs=1e-9)


def test_sonar_facing_a_wall_reads_the_perpendicular_distance():
    chair = SimBase(world=box_world(W, H), errors="ideal", params=noise_free(),
                    start=Pose2D(5.0, 3.0, 0.0))
    assert chair.frame.sonar == pytest.approx(W - 5.0 - chair.params.sonar.mount[0], abs=0.0006)


def test_sonar_cone_sees_the_nearest_point_not_the_axis():
    # facing 30 degrees off a wall's normal: the 17-degree cone's edge is 13 degrees off,
    # so the nearest return is d / cos(13 deg), not the axis distance d / cos(30 deg).
    origin = np.zeros(2)
    wall = np.array([[2.0, -10.0, 2.0, 10.0]])
    got = cone_nearest_distance(origin, math.radians(30), math.radians(17), wall, np.zeros((0, 3)))
    assert got == pytest.approx(2.0 / math.cos(math.radians(13)), rel=1e-12)
    # inside the cone the perpendicular foot is the answer
    got = cone_nearest_distance(origin, math.radians(10), math.radians(17), wall, np.zeros((0, 3)))
    assert got == pytest.approx(2.0)
    # a wall end inside the cone, the rest outside
    stub = np.array([[1.5, 0.2, 1.5, 5.0]])
    got = cone_nearest_distance(origin, 0.0, math.radians(17), stub, np.zeros((0, 3)))
    assert got == pytest.approx(math.hypot(1.5, 0.2))


def test_sonar_clips_to_its_datasheet_range():
    near = SimBase(world=box_world(W, H), errors="ideal", params=noise_free(),
                   start=Pose2D(W - 0.6, 3.0, 0.0))
    assert near.frame.sonar == pytest.approx(0.30)  # 0.2 m away reads as 0.30 m
    far = SimBase(world=box_world(40, 40), errors="ideal", params=noise_free())
    assert far.frame.sonar == pytest.approx(5.0)


def test_ray_segment_parallel_and_behind():
    segs = np.array([[-1.0, 1.0, 5.0, 1.0], [-3.0, -1.0, -3.0, 1.0]])
    d = ray_segment_distances(np.zeros(2), np.array([0.0, math.pi / 2, math.pi]), segs)
    assert d[0] == np.inf  # parallel to the first, the second is behind
    assert d[1] == pytest.approx(1.0)
    assert d[2] == pytest.approx(3.0)


def test_gyro_reads_true_rate_plus_bias_and_noise():
    chair = SimBase(world=box_world(), errors="ideal", seed=7)
    from abcwc.types import PotCommand

    log = chair.run(lambda f: PotCommand(128, 60), 8.0)
    true_rate = np.diff(np.unwrap(log.pose[:, 2])) / chair.period
    residual = log.gyro_z[:-1] - true_rate
    p = chair.params.gyro
    tolerance = 4 * p.noise_std / math.sqrt(len(residual)) + 0.001
    assert abs(residual.mean() - chair.gyro.bias) < tolerance
    assert residual.std() == pytest.approx(p.noise_std, rel=0.15)
