"""Correlative scan matching: found where ICP's basin ends, exact against brute force,
honest about corridors."""

import math

import numpy as np
import pytest

from abcwc.geometry import inverse_transform_points
from abcwc.mapping.correlative import LikelihoodField, correlative_match
from abcwc.mapping.icp import TooFewPairsError, icp


def room(spacing=0.02):
    """Points along the walls of an L-shaped room with a pillar (m)."""
    corners = [(0, 0), (6, 0), (6, 3), (3, 3), (3, 5), (0, 5), (0, 0)]
    walls = []
    for (x0, y0), (x1, y1) in zip(corners[:-1], corners[1:]):
        n = int(math.hypot(x1 - x0, y1 - y0) / spacing)
        t = np.linspace(0, 1, n, endpoint=False)[:, None]
        walls.append(np.array([x0, y0]) + t * np.array([x1 - x0, y1 - y0]))
    angle = np.linspace(0, 2 * math.pi, 60, endpoint=False)
    walls.append(np.column_stack([4.5 + 0.3 * np.cos(angle), 1.5 + 0.3 * np.sin(angle)]))
    return np.vstack(walls)


def seen_from(points, pose, rng, noise=0.01):
    """The room's points in the frame of a scanner at ``pose``, with range noise."""
    local = inverse_transform_points(pose, points)
    return local + rng.normal(0.0, noise, local.shape)


@pytest.mark.parametrize("offset", [(0.45, 0.3, 0.3), (0.45, -0.45, -0.3),
                                    (-0.45, 0.45, 0.34)])
def test_it_finds_a_pose_far_outside_icps_basin(offset):
    rng = np.random.default_rng(1)
    reference = room()
    truth = np.array([2.0, 1.5, 0.3])
    scan = seen_from(reference, truth, rng)[::3]
    guess = truth - np.array(offset)
    field = LikelihoodField(reference, resolution=0.03)
    result = correlative_match(scan, field, guess, window_xy=0.5,
                               window_theta=math.radians(21))
    assert np.hypot(*(result.pose[:2] - truth[:2])) <= 0.03 * math.sqrt(2)
    assert abs(result.pose[2] - truth[2]) <= math.radians(0.5)
    try:
        icp_pose = icp(scan, reference, guess, max_correspondence_distance=0.2).pose
        icp_miss = np.hypot(*(icp_pose[:2] - truth[:2]))
    except TooFewPairsError:
        icp_miss = math.inf
    assert icp_miss > 3 * np.hypot(*(result.pose[:2] - truth[:2])) + 0.02


def test_branch_and_bound_gives_the_brute_force_answer():
    rng = np.random.default_rng(2)
    reference = room()
    truth = np.array([1.2, 3.8, -0.5])
    scan = seen_from(reference, truth, rng, noise=0.02)[::4]
    field = LikelihoodField(reference, resolution=0.04)
    guess = truth + np.array([0.2, -0.15, 0.1])
    options = dict(window_xy=0.3, window_theta=math.radians(10))
    fast = correlative_match(scan, field, guess, factor=6, **options)
    brute = correlative_match(scan, field, guess, factor=1, **options)
    assert fast.score == brute.score
    np.testing.assert_allclose(fast.pose, brute.pose)
    assert fast.window == brute.window and fast.evaluated < fast.window / 5


def test_a_corridor_is_uncertain_along_itself():
    """Two long parallel walls: the match is pinned across the corridor and in heading,
    but along it every position fits alike."""
    x = np.arange(-10, 10, 0.02)
    reference = np.vstack([np.column_stack([x, np.full_like(x, 1.0)]),
                           np.column_stack([x, np.full_like(x, -1.0)])])
    scan = reference[(np.abs(reference[:, 0]) < 3)][::2]
    field = LikelihoodField(reference, resolution=0.03)
    result = correlative_match(scan, field, (0.1, 0.05, 0.02), window_xy=0.3,
                               window_theta=math.radians(5))
    values, vectors = np.linalg.eigh(result.covariance[:2, :2])
    assert abs(vectors[0, 1]) > 0.99  # the long axis is x, along the corridor
    assert values[1] > 20 * values[0]
    assert abs(result.pose[1]) <= 0.03 and abs(result.pose[2]) <= math.radians(0.5)


def test_bad_input_is_refused():
    field = LikelihoodField(room())
    with pytest.raises(ValueError, match="points"):
        correlative_match(np.zeros((2, 2)), field)
    with pytest.raises(ValueError, match="window"):
        correlative_match(room()[:10], field, window_xy=0.0)
    with pytest.raises(ValueError, match="factor"):
        correlative_match(room()[:10], field, factor=0)
    with pytest.raises(ValueError, match="initial"):
        correlative_match(room()[:10], field, (math.nan, 0.0, 0.0))
    with pytest.raises(ValueError, match="resolution"):
        LikelihoodField(room(), resolution=-1.0)
    with pytest.raises(ValueError, match="reference"):
        LikelihoodField(np.zeros((0, 2)))
