"""LaserScan.points, hits and misses against beams worked out by hand: which readings
are returns (REP 117 and sensor_msgs/LaserScan's bounds), where they lie, in which order."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.types import LaserScan

INF, NAN = math.inf, math.nan


def quarter_scan(ranges: list[float]) -> LaserScan:
    """Beams every quarter turn from straight ahead (0, 90, 180, 270 deg, ...), 0.2..5 m."""
    return LaserScan(0.0, math.pi / 2, 0.2, 5.0, np.array(ranges, dtype=float))


def test_returns_lie_along_their_beams_in_beam_order():
    scan = quarter_scan([1.0, 2.0, 3.0, 4.0])
    expected = [[1.0, 0.0], [0.0, 2.0], [-3.0, 0.0], [0.0, -4.0]]  # ahead, left, behind, right
    np.testing.assert_allclose(scan.points(), expected, atol=1e-12)


def test_only_finite_readings_within_the_bounds_are_returns():
    # inf: nothing in range; -inf: too close; NaN: no reading; 0.1 below range_min;
    # 6.0 beyond range_max; the bounds themselves count (sensor_msgs/LaserScan)
    scan = quarter_scan([INF, -INF, NAN, 0.1, 6.0, 0.2, 5.0, 1.5])
    assert scan.hits().tolist() == [False] * 5 + [True] * 3
    assert scan.misses().tolist() == [True, False, False, False, True, False, False, False]
    angles = np.array([5, 6, 7]) * math.pi / 2
    radii = np.array([0.2, 5.0, 1.5])
    np.testing.assert_allclose(scan.points(), np.column_stack(
        [radii * np.cos(angles), radii * np.sin(angles)]), atol=1e-12)


def test_max_range_drops_the_far_returns_and_moves_the_limit_of_a_miss():
    scan = quarter_scan([1.0, 3.0, INF, 4.5, -INF])
    np.testing.assert_allclose(scan.points(max_range=2.0), [[1.0, 0.0]], atol=1e-12)
    assert scan.misses(2.0).tolist() == [False, True, True, True, False]
    # a max_range beyond range_max changes nothing: the sensor saw no farther
    np.testing.assert_array_equal(scan.points(max_range=50.0), scan.points())


def test_with_misses_adds_the_end_of_each_free_ray_at_the_limit():
    scan = quarter_scan([1.0, INF, 3.0, NAN, 6.0])
    ends = scan.points(with_misses=True)
    # beam 1 (inf) and beam 4 (beyond 5 m) end at range_max; NaN is neither
    np.testing.assert_allclose(ends, [[1.0, 0.0], [0.0, 5.0], [-3.0, 0.0], [5.0, 0.0]],
                               atol=1e-12)
    near = scan.points(2.0, with_misses=True)  # a 2 m limit: 3 m becomes a free ray too
    np.testing.assert_allclose(near, [[1.0, 0.0], [0.0, 2.0], [-2.0, 0.0], [2.0, 0.0]],
                               atol=1e-12)
    hit = scan.hits(2.0)
    assert hit[hit | scan.misses(2.0)].tolist() == [True, False, False, False]


def test_a_scan_without_returns_gives_no_points():
    scan = quarter_scan([INF, NAN, -INF])
    assert scan.points().shape == (0, 2)


@pytest.mark.parametrize("max_range", [0.0, -1.0, NAN, "far"])
def test_a_bad_max_range_is_refused(max_range):
    with pytest.raises(ValueError, match="max_range must be a number > 0 m"):
        quarter_scan([1.0]).points(max_range)
