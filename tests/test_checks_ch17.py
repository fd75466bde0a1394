"""The exercise checks of chapter 17 (following a person with a tag): each passes an
answer written independently of the library, and says "not yet" (never raises) for the
plausible wrong answers, the unwritten stub and abcwc's own function handed in."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.checks import ch17
from tests.check_helpers import assert_not_yet, assert_pass, not_written


def student_optical_to_base(point, mount, *, plus_x=False, no_offset=False, no_yaw=False,
                            use_y=False):
    """With a rotation matrix, as a student who has done chapter 11 writes it."""
    x, y, z = point
    ahead, left = (y if use_y else z), (x if plus_x else -x)
    yaw = 0.0 if no_yaw else mount[2]
    rotation = np.array([[math.cos(yaw), -math.sin(yaw)], [math.sin(yaw), math.cos(yaw)]])
    offset = np.zeros(2) if no_offset else np.array(mount[:2], float)
    return offset + rotation @ np.array([ahead, left])


def test_optical_check_passes_an_independent_answer(capsys):
    assert_pass(ch17.optical_check(student_optical_to_base), capsys)


@pytest.mark.parametrize(("wrong", "fragment"), [
    (lambda p, m: student_optical_to_base(p, m, plus_x=True), "x points to the right"),
    (lambda p, m: student_optical_to_base(p, m, no_offset=True), "position is missing"),
    (lambda p, m: student_optical_to_base(p, m, no_yaw=True), "yaw is missing"),
    (lambda p, m: student_optical_to_base(p, m, use_y=True), "ahead is z"),
    (lambda p, m: student_optical_to_base(p, (*m[:2], -m[2])), "wrong way"),
    (lambda p, m: student_optical_to_base(p, m) + 0.01, "expected"),
    (lambda p, m: 3.0, "return (x, y)"),
    (not_written, "NotImplementedError"),
    (ch17.reference_optical_to_base, "abcwc's own"),
])
def test_optical_check_refuses_plausible_slips(wrong, fragment, capsys):
    assert_not_yet(ch17.optical_check(wrong), capsys, fragment)


def test_the_qr_range_is_the_pinhole_worked_by_hand():
    """fx = 320 / tan(28.5 deg) = 589.4 px; 0.2 m over 21 modules at 4 px a module:
    589.4 * 0.2 / 84 = 1.403 m."""
    fx = 320 / math.tan(math.radians(28.5))
    assert ch17.true_qr_range(4.0) == pytest.approx(fx * 0.2 / 84)
    assert ch17.true_qr_range(4.0) == pytest.approx(1.403, abs=0.001)


def test_qr_range_check(capsys):
    assert_pass(ch17.qr_range_check(lambda: 1.3, 1.15), capsys)
    quiet = ch17.true_qr_range(4.0) * 21 / 29  # 0.2 m taken as 29 modules
    assert_not_yet(ch17.qr_range_check(lambda: quiet, 1.15), capsys, "quiet zone")
    marker = ch17.true_qr_range(4.0) * 21 / 6
    assert_not_yet(ch17.qr_range_check(lambda: marker, 1.15), capsys, "ArUco")
    assert_not_yet(ch17.qr_range_check(lambda: 3.0, 1.15), capsys, "4-5 px")
    assert_not_yet(ch17.qr_range_check(lambda: "far", 1.15), capsys, "one distance")
    assert_not_yet(ch17.qr_range_check(not_written, 1.15), capsys, "NotImplementedError")


def student_law(gap, bearing, receding):
    """Proportional on both, the person's speed added, written from the text."""
    v = receding + 1.0 * gap
    if abs(bearing) > math.pi / 2:
        v = 0.0
    return v, 1.2 * bearing


def test_law_check_passes_an_independent_law(capsys):
    assert_pass(ch17.law_check(student_law), capsys)


@pytest.mark.parametrize(("wrong", "fragment"), [
    (lambda gap, bearing, receding: (0.5, 0.0), "lags"),  # blind: a fixed command
    (lambda gap, bearing, receding: (1.2 * gap, 1.5 * bearing), "lags"),  # no feed-forward
    # figure 50: a fixed turn rate either way, however small the bearing
    (lambda gap, bearing, receding: (min(1.0, 1.2 * gap + receding),
                                     0.5 * math.copysign(1.0, bearing)), "figure 50"),
    (lambda gap, bearing, receding: 0.5, "two numbers"),
    (not_written, "NotImplementedError"),
])
def test_law_check_refuses_laws_that_do_not_follow(wrong, fragment, capsys):
    assert_not_yet(ch17.law_check(wrong), capsys, fragment)


def test_law_check_refuses_abcwc_s_own_law(capsys):
    from abcwc.behaviours.follow import TagFollower
    from abcwc.estimation.gyro import GyroOdometry
    from abcwc.perception.tags import FollowCard

    own = TagFollower(FollowCard("ana", 7), GyroOdometry()).range_and_bearing
    assert_not_yet(ch17.law_check(own), capsys, "abcwc's own")


def student_aim_clearance(chair, person, frame_end, *, whole_line=False, ends=False,
                          squared=False):
    """Parametrised by the fraction along the way, as a student derives it."""
    (x0, y0), (x1, y1), (px, py) = chair, person, frame_end
    dx, dy = x1 - x0, y1 - y0
    t = ((px - x0) * dx + (py - y0) * dy) / (dx * dx + dy * dy)
    if not whole_line:
        t = min(1.0, max(0.0, t))
    if ends:
        return min(math.dist(chair, frame_end), math.dist(person, frame_end))
    gap2 = (px - x0 - t * dx) ** 2 + (py - y0 - t * dy) ** 2
    return gap2 if squared else math.sqrt(gap2)


def test_aim_check_passes_an_independent_answer(capsys):
    assert_pass(ch17.aim_check(student_aim_clearance), capsys)


def test_the_aim_clearance_worked_by_hand():
    """The way from (0, 0) to (2, 0): a point 1 m above its middle is 1 m off; one 1 m
    behind the chair's end is sqrt(1 + 1) off, though the line passes 1 m from it."""
    assert ch17.reference_aim_clearance((0, 0), (2, 0), (1, 1)) == pytest.approx(1.0)
    assert ch17.reference_aim_clearance((0, 0), (2, 0), (-1, 1)) == pytest.approx(
        math.sqrt(2))


@pytest.mark.parametrize(("wrong", "fragment"), [
    (lambda c, p, f: student_aim_clearance(c, p, f, whole_line=True), "whole line"),
    (lambda c, p, f: student_aim_clearance(c, p, f, ends=True), "nearer end"),
    (lambda c, p, f: student_aim_clearance(c, p, f, squared=True), "square root"),
    (lambda c, p, f: student_aim_clearance(c, p, f) + 0.01, "keep the projection"),
    (lambda c, p, f: (1.0, 2.0), "one distance"),
    (not_written, "NotImplementedError"),
    (ch17.reference_aim_clearance, "abcwc's own"),
])
def test_aim_check_refuses_plausible_slips(wrong, fragment, capsys):
    assert_not_yet(ch17.aim_check(wrong), capsys, fragment)

