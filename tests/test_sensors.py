"""Every range sensor against the analytic distance to a wall; encoders and gyro."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.geometry import compose
from abcwc.sim import SimBase
from abcwc.sim.raycast import cone_nearest_distance, ray_segment_distances
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
    sensor = compose(chair.pose, chair.params.lidar.mount)  # x, y, heading in the world
    origin, heading = sensor[:2], sensor[2]
    expected = np.array([distance_to_box(origin, heading + a) for a in scan.angles])
    np.testing.assert_allclose(scan.ranges, expected, atol=1e-9)
    assert len(scan.ranges) == 360


def test_depth_scan_matches_closed_form_and_range_limits(chair):
    scan = chair.frame.depth_scan
    p = chair.params.depth_scan
    sensor = compose(chair.pose, p.mount)  # x, y, heading in the world
    origin, heading = sensor[:2], sensor[2]
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
        sensor = compose(chair.pose, mount)  # x, y, heading in the world
        origin, heading = sensor[:2], sensor[2]
        d = distance_to_box(origin, heading)
        expected = np.inf if d > p.max_range else (-np.inf if d < p.min_range else d)
        assert readings[k] == pytest.approx(expected, abs=1e-9)


def test_ir_sees_a_near_wall_in_range():
    chair = SimBase(world=box_world(W, H), errors="ideal", params=noise_free(),
                    start=Pose2D(7.0, 3.0, 0.0))
    p = chair.params.ir
    x_sensor = 7.0 + p.mounts[0, 0]
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

    log = chair.run(lambda f: PotCommand(128, 60), 8.0, safety=None)  # the full turn rate
    true_rate = np.diff(np.unwrap(log.pose[:, 2])) / chair.period
    residual = log.gyro_z[:-1] - true_rate
    p = chair.params.gyro
    tolerance = 4 * p.noise_std / math.sqrt(len(residual)) + 0.001
    assert abs(residual.mean() - chair.gyro.bias) < tolerance
    assert residual.std() == pytest.approx(p.noise_std, rel=0.15)


# ------------------------------------------------------------------ heights
def _room_with_table(start: Pose2D) -> SimBase:
    """A 10 x 10 m room with a 1.2 x 0.8 m table (top 0.70-0.75 m) centred at (5, 5)."""
    from abcwc.sim.world import table, world_from_dict

    world = world_from_dict({
        "name": "room+table", "walls": [[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]],
        "places": {"start": [start.x, start.y, start.theta]}, "objects": table((5.0, 5.0)),
    })
    return SimBase(world=world, errors="ideal", params=noise_free(), lidar=True,
                   depth_scan=True, people=False)


def test_the_lidar_sees_a_tables_legs_and_the_depth_scan_its_top():
    """The lidar's plane (0.35 m) passes under the top (0.70-0.75 m): its middle beam
    runs between the legs to the far wall; the depth scan's band of rows (8.5 degrees
    each side of 0.76 m) reaches the top's edge at x = 4.4 m."""
    chair = _room_with_table(Pose2D(3.0, 5.0, 0.0))
    frame = chair.read()
    p = chair.params
    lidar = frame.lidar
    middle = int(round(-lidar.angle_min / lidar.angle_increment))
    assert lidar.angle_min + middle * lidar.angle_increment == pytest.approx(0.0)
    assert lidar.ranges[middle] == pytest.approx(10.0 - 3.0 - p.lidar.mount[0])
    # the lidar does see a leg: the beam towards the near left leg's centre
    leg = np.array([4.425, 5.375]) - (3.0 + p.lidar.mount[0], 5.0)
    beam = int(round((math.atan2(leg[1], leg[0]) - lidar.angle_min) / lidar.angle_increment))
    assert lidar.ranges[beam] < np.hypot(*leg)
    depth = frame.depth_scan
    angles = depth.angle_min + depth.angle_increment * np.arange(len(depth.ranges))
    ahead = np.abs(angles) < 0.15  # beams that meet the top's near edge, x = 4.4
    expected = (4.4 - 3.0 - p.depth_scan.mount[0]) / np.cos(angles[ahead])
    np.testing.assert_allclose(depth.ranges[ahead], expected, atol=1e-9)


def test_a_depth_scan_sees_a_top_only_from_where_its_rows_reach_it():
    """A top from 1.00 to 1.05 m, above the camera (0.76 m): the band's upper edge (95
    rows above the centre of 480, through a 43-degree pinhole) rises tan(21.5 deg) 95 /
    240 = 0.156 per metre, so it reaches 1.00 m at 0.24 / 0.156 = 1.54 m (and the
    sonar's 17-degree cone at (1.00 - 0.69) / tan(17 deg) = 1.01 m)."""
    from abcwc.sim.raycast import visible_segments

    p = noise_free()
    segments = np.array([[2.0, -1.0, 2.0, 1.0], [1.0, -1.0, 1.0, 1.0]])
    bands = np.array([[1.00, 1.05], [1.00, 1.05]])
    seen = visible_segments(segments, bands, p.depth_scan.height,
                            p.depth_scan.vertical_half_angle)
    reach = (1.00 - p.depth_scan.height) / math.tan(p.depth_scan.vertical_half_angle)
    assert reach == pytest.approx((1.00 - 0.76) / (math.tan(math.radians(21.5)) * 95 / 240))
    np.testing.assert_allclose(seen[:, 4], reach)
    # the near top (1 m) is closer than the reach and is not seen; the far one (2 m) is
    assert ray_segment_distances(np.zeros(2), np.array([0.0]), seen)[0] == pytest.approx(2.0)
    # the sonar's cone: the near top's in-cone part runs out to 1 / cos(17 deg) = 1.046
    # m, past the cone's reach of 1.01 m, so the sonar reads the reach
    sonar = visible_segments(segments, bands, p.sonar.height, p.sonar.vertical_half_angle)
    cone_reach = (1.00 - p.sonar.height) / math.tan(math.radians(p.sonar.half_angle_deg))
    got = cone_nearest_distance(np.zeros(2), 0.0, math.radians(p.sonar.half_angle_deg),
                                sonar, np.zeros((0, 3)))
    assert got == pytest.approx(cone_reach)


def test_the_chair_runs_into_a_table_top_it_cannot_pass_under():
    """Every object stops the chair, whatever its height: driving at the table (bare:
    without the safety filter, which would stop it short), the chair's front (0.45 m
    ahead of the axle) stops at the top's edge."""
    from abcwc.types import Twist

    chair = _room_with_table(Pose2D(3.0, 5.0, 0.0))
    log = chair.run(lambda f: Twist(0.4, 0.0), 5.0, safety=None)
    assert log.collisions[-1] >= 1
    front = chair.params.length - chair.params.axle_to_rear
    assert chair.pose.x + front == pytest.approx(4.4, abs=0.02)


def test_a_rendered_depth_image_made_into_a_scan_is_the_simulators_depth_scan():
    """Two ways to the Kinect's fake scan agree: the simulator's own (each segment seen
    from where the band of rows reaches its heights) and a depth image rendered pixel
    by pixel and turned into a scan as depthimage_to_laserscan does. Looking at the
    table from 1.5 m, the top's edge; a low box beside it that the band reaches only
    from further away is missing from both."""
    from abcwc.perception import depth_image_to_scan, kinect_camera
    from abcwc.sim.depth_camera import render_depth
    from abcwc.sim.world import table, world_from_dict

    box = {"name": "box", "outline": [[4.3, 2.0], [4.6, 2.0], [4.6, 2.3], [4.3, 2.3],
                                      [4.3, 2.0]], "z": [0.0, 0.3]}
    world = world_from_dict({
        "name": "room", "walls": [[[0, 0], [8, 0], [8, 6], [0, 6], [0, 0]]],
        "places": {"start": [2.6, 3.0, 0.0]}, "objects": table((5.0, 3.0)) + [box]})
    chair = SimBase(world=world, errors="ideal", params=noise_free(), depth_scan=True,
                    people=False)
    p = chair.params.depth_scan
    simulated = chair.read().depth_scan
    camera = kinect_camera(p)
    image = render_depth(camera, chair.pose, p.mount, p.height, world.walls, world.bands,
                         np.zeros((0, 3)), p.min_range, p.max_range)
    rendered = depth_image_to_scan(image, camera, p.scan_height_px, p.min_range, p.max_range)
    # compare at the rendered scan's beams, by the simulated scan's nearest beam
    index = np.rint((rendered.angles - simulated.angle_min) / simulated.angle_increment)
    pairs = np.isfinite(rendered.ranges)
    assert pairs.sum() > 100
    np.testing.assert_allclose(rendered.ranges[pairs],
                               simulated.ranges[index[pairs].astype(int)], atol=0.01)
    # the box (0.3 m tall, 1.7 m ahead and to the right) is in neither: the band's lower
    # edge reaches 0.3 m only (0.76 - 0.3) / 0.156 = 2.9 m out
    bearing = math.atan2(2.15 - 3.0, 4.3 - 2.9)
    beam = int(np.argmin(np.abs(rendered.angles - bearing)))
    assert rendered.ranges[beam] > 2.0
    sim_beam = int(np.argmin(np.abs(simulated.angles - bearing)))
    assert simulated.ranges[sim_beam] > 2.0
