"""abcwc.geometry against closed forms: homogeneous 3x3 matrices and hand cases."""

import math
from pathlib import Path

import numpy as np
import pytest

from abcwc.geometry import (
    chain_poses,
    compose,
    encoder_ticks_to_wheel_distance,
    inverse,
    inverse_transform_points,
    relative,
    transform_points,
    wrap_angle,
    wrap_tick_delta,
)
from abcwc.types import Pose2D


def matrix(pose):
    """The homogeneous transform of (x, y, theta): an independent SE(2) reference."""
    x, y, t = pose
    return np.array([[math.cos(t), -math.sin(t), x], [math.sin(t), math.cos(t), y], [0, 0, 1]])


def pose_of(m):
    return np.array([m[0, 2], m[1, 2], math.atan2(m[1, 0], m[0, 0])])


def random_poses(n, seed):
    rng = np.random.default_rng(seed)
    return np.c_[rng.uniform(-5, 5, (n, 2)), rng.uniform(-math.pi, math.pi, n)]


def same_pose(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert np.allclose(a[..., :2], b[..., :2], atol=1e-12)
    assert np.allclose(wrap_angle(a[..., 2] - b[..., 2]), 0, atol=1e-12)


def test_wrap_angle_is_half_open_for_scalars_and_arrays():
    assert wrap_angle(-math.pi) == math.pi
    assert wrap_angle(math.pi) == math.pi
    assert wrap_angle(3 * math.pi) == pytest.approx(math.pi)
    assert wrap_angle(-0.1) == -0.1
    assert isinstance(wrap_angle(0.3), float)
    angles = np.array([-math.pi, math.pi, -3 * math.pi, 7.0, -7.0, 0.0])
    wrapped = wrap_angle(angles)
    assert np.all(wrapped > -math.pi) and np.all(wrapped <= math.pi)
    assert np.allclose(np.cos(wrapped), np.cos(angles)) and np.allclose(
        np.sin(wrapped), np.sin(angles))
    assert wrapped[0] == math.pi and wrapped[2] == math.pi


def test_wrap_angle_removes_whole_turns_only_and_both_paths_agree_bit_for_bit():
    rng = np.random.default_rng(7)
    angles = np.concatenate([rng.uniform(-1000.0, 1000.0, 5000),
                             np.arange(-7, 8) * math.pi,  # the odd multiples land on the edge
                             [0.0, -0.0, 1e-300, -1e-300, math.pi, -math.pi]])
    wrapped = wrap_angle(angles)
    assert np.all((wrapped > -math.pi) & (wrapped <= math.pi))
    turns = (angles - wrapped) / (2 * math.pi)
    np.testing.assert_allclose(turns, np.round(turns), atol=1e-9)
    one_by_one = np.array([wrap_angle(float(a)) for a in angles])
    np.testing.assert_array_equal(wrapped, one_by_one)
    assert wrap_angle(np.float64(-math.pi)) == math.pi
    assert wrap_angle(-4) == pytest.approx(2 * math.pi - 4)
    assert wrap_angle(np.array([-3, 4])).dtype == float  # integer headings too
    assert math.isnan(wrap_angle(math.nan))


def test_the_package_wraps_angles_only_through_wrap_angle():
    """math.remainder gives [-pi, pi] and np.remainder [-pi, pi): the one wrap is
    geometry.wrap_angle's (-pi, pi]."""
    package = Path(__file__).resolve().parent.parent / "abcwc"
    found = [f"{path.relative_to(package)}:{number}"
             for path in sorted(package.rglob("*.py")) if path.name != "geometry.py"
             for number, line in enumerate(path.read_text().splitlines(), 1)
             if "remainder(" in line]
    assert not found, found


def test_a_landmark_straight_behind_is_at_plus_pi():
    from abcwc.estimation.range_bearing import range_bearing

    z, _ = range_bearing(np.array([0.0, 0.0, math.pi]), (1.0, 0.0), (0.0, 0.0, 0.0))
    assert z[0] == 1.0 and z[1] == math.pi


def test_compose_inverse_relative_match_homogeneous_matrices():
    a, b = random_poses(50, 1), random_poses(50, 2)
    for pa, pb, got_c, got_r, got_i in zip(a, b, compose(a, b), relative(a, b), inverse(a)):
        same_pose(got_c, pose_of(matrix(pa) @ matrix(pb)))
        same_pose(got_r, pose_of(np.linalg.inv(matrix(pa)) @ matrix(pb)))
        same_pose(got_i, pose_of(np.linalg.inv(matrix(pa))))


def test_single_poses_answer_with_pose2d_and_arrays_with_arrays():
    a, b = Pose2D(1.0, 2.0, 0.5), Pose2D(-0.3, 0.7, 2.9)
    back = compose(a, relative(a, b))
    assert isinstance(back, Pose2D)
    same_pose([back.x, back.y, back.theta], [b.x, b.y, b.theta])
    assert isinstance(compose((0, 0, 0), (1, 0, 0)), np.ndarray)
    # a quarter turn then one metre forward ends one metre to the left
    same_pose(compose(Pose2D(0, 0, math.pi / 2), Pose2D(1, 0, 0)).as_array(), [0, 1, math.pi / 2])


def test_chain_poses_composes_relative_poses_in_turn():
    rng = np.random.default_rng(2)
    steps = rng.normal(0, 1, (30, 3))
    poses = [np.array([1.0, -2.0, 3.0])]
    for step in steps:  # one matrix product per step: the independent reference
        poses.append(pose_of(matrix(poses[-1]) @ matrix(step)))
    chained = chain_poses(Pose2D(1.0, -2.0, 3.0), steps)
    assert chained.shape == (31, 3)
    for got, expected in zip(chained, poses):
        same_pose(got, expected)
    assert np.all(np.abs(chained[:, 2]) <= math.pi)
    np.testing.assert_array_equal(chain_poses((0, 0, 0), np.zeros((0, 3))), [[0, 0, 0]])


def test_a_pose_graphs_odometry_chain_is_chain_poses_over_its_forward_edges():
    from abcwc.mapping.g2o import chain_odometry

    rng = np.random.default_rng(5)
    steps = rng.normal(0, 1, (8, 3))
    # edges in file order: a loop closure 0 -> 5 first, then the odometry i -> i + 1
    edges = np.array([(0, 5), *[(k, k + 1) for k in range(8)]])
    measurements = np.vstack([[9.0, 9.0, 1.0], steps])
    np.testing.assert_array_equal(chain_odometry(np.arange(9), edges, measurements),
                                  chain_poses((0.0, 0.0, 0.0), steps))


def test_point_transforms_round_trip_and_match_matrices():
    poses = random_poses(6, 3)
    points = np.random.default_rng(4).normal(size=(6, 9, 2))
    world = transform_points(poses, points)
    for pose, local, got in zip(poses, points, world):
        expect = (matrix(pose) @ np.c_[local, np.ones(len(local))].T).T[:, :2]
        assert np.allclose(got, expect)
        assert np.allclose(inverse_transform_points(pose, got), local)
    assert transform_points(poses, points[:, 0]).shape == (6, 2)


def test_bad_shapes_are_refused_with_the_allowed_shape():
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        compose(np.zeros(2), np.zeros(3))
    with pytest.raises(ValueError, match=r"\(\.\.\., 2\)"):
        transform_points((0, 0, 0), np.zeros((4, 3)))


def test_encoder_counts_to_metres_corrects_the_counter_wrap():
    top = 2**31 - 1
    ticks = np.array([[top - 2, 0], [-(2**31) + 3, 10]])  # left wrapped after 6 counts
    travel = encoder_ticks_to_wheel_distance(ticks, 0.001)
    assert np.allclose(travel, [[0.006, 0.010]])
    assert wrap_tick_delta(-(2**15) + 1 - (2**15 - 2), bits=16) == 3
    with pytest.raises(ValueError, match="> 0 m"):
        encoder_ticks_to_wheel_distance(ticks, -1.0)
    with pytest.raises(ValueError, match="whole numbers"):
        encoder_ticks_to_wheel_distance(np.array([[0.5, 1.0], [1.0, 2.0]]), 0.001)


def test_wrap_angle_is_exact_and_arrays_agree_with_scalars_bit_for_bit():
    rng = np.random.default_rng(5)
    inside = rng.uniform(-math.pi, math.pi, 1000)
    assert np.array_equal(wrap_angle(inside), inside)  # in range: unchanged to the last bit
    assert not np.array_equal(np.angle(np.exp(1j * inside)), inside)  # the old way rounds
    angles = np.concatenate([inside * 40.0, [math.pi, -math.pi, 2 * math.pi, -0.0, 1e6]])
    one_by_one = np.array([wrap_angle(float(a)) for a in angles])
    assert np.array_equal(wrap_angle(angles), one_by_one)
    # the answer is angle - 2 pi n exactly: 2 pi (the double) plus a small angle wraps back
    assert wrap_angle(np.array([2 * math.pi + 0.25]))[0] == (2 * math.pi + 0.25) - 2 * math.pi


def test_densify_polyline_keeps_the_corners_and_the_spacing():
    from abcwc.geometry import densify_polyline

    corner = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.25]])
    points = densify_polyline(corner, 0.3)
    # 1 m in four pieces of 0.25 m, then 0.25 m in one
    assert np.allclose(points, [[0, 0], [0.25, 0], [0.5, 0], [0.75, 0], [1, 0], [1, 0.25]])
    assert np.hypot(*np.diff(points, axis=0).T).max() <= 0.3
    assert np.array_equal(densify_polyline(corner[:1], 0.3), corner[:1])
