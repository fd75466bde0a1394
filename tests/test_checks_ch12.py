"""The exercise checks of chapter 12 (range sensors): each passes an answer written
independently of the library, and says "not yet" (never raises) for the plausible
wrong answers, the unwritten stub and abcwc's own function handed in."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.checks import ch12
from abcwc.params import default_params
from abcwc.perception.depth import depth_image_to_scan
from tests.check_helpers import assert_not_yet, assert_pass, not_written


def student_ranges(depth, fx, cx, scan_height, range_min, range_max, *, use_z=False,
                   all_rows=False, no_limits=False, flip=False):
    """A column at a time, as a student writes it from the text."""
    rows, width = depth.shape
    first = int(round((rows - 1) / 2 - scan_height / 2))
    band = range(rows) if all_rows else range(first, first + scan_height)
    bearings, ranges = [], []
    for u in range(width):
        x_over_z = (u - cx) / fx
        bearings.append(math.atan(x_over_z) if flip else -math.atan(x_over_z))
        best = math.inf
        for v in band:
            z = depth[v, u]
            if not math.isfinite(z):
                continue
            r = z if use_z else z * math.sqrt(1 + x_over_z**2)
            if (no_limits or range_min <= r <= range_max) and r < best:
                best = r
        ranges.append(best)
    return np.array(bearings), np.array(ranges)


def test_ranges_passes_an_independent_answer(capsys):
    assert_pass(ch12.ranges_check(student_ranges), capsys)


@pytest.mark.parametrize(("wrong", "fragment"), [
    (lambda *a: student_ranges(*a, use_z=True), "not ranges"),
    (lambda *a: student_ranges(*a, all_rows=True), "every row was used"),
    (lambda *a: student_ranges(*a, no_limits=True), "range limits"),
    (lambda *a: student_ranges(*a, flip=True), "wrong sign"),
    (lambda *a: student_ranges(*a)[1], "two arrays"),
    (lambda *a: (student_ranges(*a)[0], student_ranges(*a)[1] * 1.01), "column"),
    (not_written, "NotImplementedError"),
    (ch12.reference_depth_to_ranges, "abcwc's own"),
    (depth_image_to_scan, "abcwc's own"),
])
def test_ranges_refuses_plausible_slips(wrong, fragment, capsys):
    assert_not_yet(ch12.ranges_check(wrong), capsys, fragment)


def test_the_reach_is_the_band_edge_worked_by_hand():
    """0.76 m camera, 0.30 m box, 95 rows of 240 from the centre through a 43-degree
    pinhole: (0.76 - 0.30) / (tan(21.5 deg) 95 / 240) = 2.95 m."""
    assert ch12.true_reach() == pytest.approx(0.46 / (math.tan(math.radians(21.5)) * 95 / 240))
    assert ch12.true_reach() == pytest.approx(2.95, abs=0.01)


def test_reach_check(capsys):
    assert_pass(ch12.reach_check(lambda: 3.0, 2.9), capsys)
    whole = 0.46 / math.tan(math.radians(21.5))
    assert_not_yet(ch12.reach_check(lambda: whole, 2.9), capsys, "whole image")
    assert_not_yet(ch12.reach_check(lambda: 0.5, 2.9), capsys, "2.95 m")
    assert_not_yet(ch12.reach_check(lambda: "far", 2.9), capsys, "one distance")


@pytest.mark.parametrize(("answer", "fragment"), [
    ({"lidar_link", "depth_scan_link"}, "passes under"),
    ({"depth_scan_link"}, "missing sonar_link"),
    ({"sonar_link", "depth_scan_link", "ir_0_link"}, "thin beams"),
    ({"kinect"}, "not the chair's frames"),
    (None, "set of frame ids"),
])
def test_seen_check_explains(answer, fragment, capsys):
    assert_not_yet(ch12.seen_check(lambda: answer), capsys, fragment)


def test_seen_check_explains_every_frame_of_the_chair(capsys):
    """A frame of the chair that is no range sensor (the IMU) is the student's slip, told
    as such, not a KeyError in the check."""
    for frame in set(default_params().sensors) - ch12.SEEN_BY:
        result = ch12.seen_check(lambda frame=frame: {frame, *ch12.SEEN_BY})
        assert "raised" not in result.message, result.message
        assert_not_yet(result, capsys, f"not {frame}; {frame}: ")
    assert_not_yet(ch12.seen_check(lambda: {"imu_link"}), capsys, "imu_link: not a range sensor")


def test_seen_check_passes_the_two(capsys):
    assert_pass(ch12.seen_check(lambda: {"sonar_link", "depth_scan_link"}), capsys)
    assert ch12.SEEN_BY == {"sonar_link", "depth_scan_link"}
