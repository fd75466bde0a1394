"""The exercise checks of chapter 11 (the chair's description and frames): each passes an
answer written independently of the library, and says "not yet" (never raises) for the
plausible wrong answers, the unwritten stub and abcwc's own function handed in."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.checks import ch11
from abcwc.description import homogeneous
from tests.check_helpers import assert_not_yet, assert_pass, not_written

# --- exercise 1: a joint's origin -------------------------------------------------------


def student_origin(xyz, rpy, order="zyx", degrees=False, transpose=False,
                   rotate_translation=False):
    """Three elementary rotations multiplied as a student writes them from the text."""
    roll, pitch, yaw = np.radians(rpy) if degrees else rpy

    def about(axis, a):
        c, s = math.cos(a), math.sin(a)
        if axis == "x":
            return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
        if axis == "y":
            return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
        return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])

    angles = {"x": roll, "y": pitch, "z": yaw}
    rotation = np.eye(3)
    for axis in order:
        rotation = rotation @ about(axis, angles[axis])
    if transpose:
        rotation = rotation.T
    out = np.eye(4)
    out[:3, :3] = rotation
    out[:3, 3] = rotation @ xyz if rotate_translation else xyz
    return out


def test_origin_passes_an_independent_answer(capsys):
    assert_pass(ch11.origin_check(student_origin), capsys)


@pytest.mark.parametrize(("wrong", "fragment"), [
    (lambda xyz, rpy: student_origin(xyz, rpy, order="xyz"), "other way round"),
    (lambda xyz, rpy: student_origin(xyz, rpy, transpose=True), "transposed"),
    (lambda xyz, rpy: student_origin(xyz, rpy, rotate_translation=True),
     "translation is rotated"),
    (lambda xyz, rpy: student_origin(xyz, rpy, degrees=True), "degrees"),
    (lambda xyz, rpy: student_origin(xyz, rpy)[:3], "shape (3, 4)"),
    (lambda xyz, rpy: student_origin(xyz, np.array([0.0, 0.0, rpy[2]])), "expected"),
    (not_written, "NotImplementedError"),
    (ch11.reference_origin_transform, "abcwc's own"),
    (homogeneous, "abcwc's own"),
])
def test_origin_refuses_plausible_slips(wrong, fragment, capsys):
    assert_not_yet(ch11.origin_check(wrong), capsys, fragment)


# --- exercise 2: predict where a ranger's reading lies ----------------------------------


def _by_hand(mount_yaw_deg=120.0, chair_heading=math.pi / 2, place=(0.04, 0.1732)):
    """The chain by hand: the ranger at `place` on the rod facing `mount_yaw_deg`,
    0.5 m out, then the chair's turn and position."""
    yaw = math.radians(mount_yaw_deg)
    bx, by = place[0] + 0.5 * math.cos(yaw), place[1] + 0.5 * math.sin(yaw)
    c, s = math.cos(chair_heading), math.sin(chair_heading)
    return 2.0 + c * bx - s * by, 1.0 + s * bx + c * by


def test_prediction_passes_the_chain_worked_by_hand(capsys):
    # (0.04 - 0.25, 0.173 + 0.433) = (-0.21, 0.606) in base_link; turned a quarter
    # counter-clockwise: (-0.606, -0.21); plus (2, 1)
    assert _by_hand() == pytest.approx((1.394, 0.79), abs=0.001)
    assert_pass(ch11.hit_check(lambda: (1.39, 0.79)), capsys)


@pytest.mark.parametrize(("answer", "fragment"), [
    (_by_hand(chair_heading=0.0), "heading is missing"),
    (_by_hand(mount_yaw_deg=0.0), "own facing is missing"),
    (_by_hand(place=(0.0, 0.0)), "place on the rod"),
    ((3.0, 3.0), "go down the chain"),
    ((math.nan, 1.0), "finite"),
    ("left", "write (x, y)"),
])
def test_prediction_explains_the_slip(answer, fragment, capsys):
    assert_not_yet(ch11.hit_check(lambda: answer), capsys, fragment)


# --- exercise 3: the localiser's correction ---------------------------------------------


def _pose_matrix(x, y, theta):
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s, x], [s, c, y], [0, 0, 1]])


def student_correction(log, measure="chair", radians=False):
    """With 3 x 3 matrices: map -> odom = map_base @ inv(odom_base) at each sample; its
    biggest change, as where it puts the chair against where the old one would."""
    mats = [_pose_matrix(*m) @ np.linalg.inv(_pose_matrix(*o)) for m, o in zip(log.map, log.odom)]
    best = (0.0, 0, 0.0)
    for k in range(1, len(mats)):
        odom = _pose_matrix(*log.odom[k])
        new, old = mats[k] @ odom, mats[k - 1] @ odom
        if measure == "chair":
            moved = math.hypot(*(new[:2, 2] - old[:2, 2]))
        elif measure == "origin":
            moved = math.hypot(*(mats[k][:2, 2] - mats[k - 1][:2, 2]))
        else:  # the raw step of the estimate, motion included
            moved = math.hypot(*(log.map[k, :2] - log.map[k - 1, :2]))
        turned = math.atan2(new[1, 0], new[0, 0]) - math.atan2(old[1, 0], old[0, 0])
        turned = (turned + math.pi) % (2 * math.pi) - math.pi
        if moved > best[0]:
            best = (moved, k, turned)
    moved, k, turned = best
    return log.t[k], moved, turned if radians else math.degrees(turned)


def test_correction_passes_an_independent_answer(capsys):
    assert_pass(ch11.correction_check(student_correction), capsys)


@pytest.mark.parametrize(("wrong", "fragment"), [
    (lambda log: student_correction(log, radians=True), "radians"),
    (lambda log: student_correction(log, measure="origin"), "map -> odom's origin"),
    (lambda log: student_correction(log, measure="step"), "own motion"),
    (lambda log: (40.0, 0.6, -4.6), "came at t ="),  # one log's answer, written down
    (lambda log: student_correction(log)[:2], "(time s, distance m, turn deg)"),
    (lambda log: (*student_correction(log)[:2], -student_correction(log)[2]), "sign"),
    (not_written, "NotImplementedError"),
    (ch11.reference_biggest_correction, "abcwc's own"),
    (lambda log: ch11.reference_biggest_correction(log), "abcwc's own"),
    # the log handed to the student carries no answer to read off
    (lambda log: (log.corrected_at, *log.correction), "AttributeError"),
])
def test_correction_refuses_plausible_slips(wrong, fragment, capsys):
    assert_not_yet(ch11.correction_check(wrong), capsys, fragment)


def test_the_log_handed_out_holds_the_poses_alone():
    log = ch11.localisation_log(11)
    assert [name for name in vars(log)] == ["t", "odom", "map"]
    assert np.array_equal(log.map, ch11._drive(11)[0].map)


def test_the_log_corrects_once_in_a_big_way():
    """Away from the corridor the fixes are small (a second of drift); the one after it
    is the drift of the whole corridor."""
    log, truth = ch11._drive(11)
    t, metres, degrees = ch11.reference_biggest_correction(log)
    assert t == pytest.approx(truth.at) and 22.0 < t < 45.0
    assert metres == pytest.approx(truth.metres) and metres > 0.3
    assert degrees == pytest.approx(truth.degrees)
    others = ch11.localisation_log(11)
    clipped = ch11.LocalisationLog(others.t[:200], others.odom[:200], others.map[:200])
    assert ch11.reference_biggest_correction(clipped)[1] < 0.05
