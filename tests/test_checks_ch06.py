"""The exercise checks of chapter 06, wheel odometry.

Each check must pass a correct answer (the library's and one written independently),
and report "not yet" (never raise) for a wrong one and for an exercise that is not
written yet.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.checks import ch06
from abcwc.types import Pose2D
from tests.check_helpers import assert_not_yet, assert_pass, not_written


@pytest.mark.parametrize("check", [ch06.wheel_travel_check, ch06.odometry_step_check,
                                   ch06.integrate_arcs_check])
def test_not_written_is_not_yet(check, capsys):
    assert_not_yet(check(not_written), capsys, "not written yet")


# --- exercise 1: wheel travel ---------------------------------------------------------


def modular_travel(ticks, distance_per_count, bits=32):
    """Written from the text: differences modulo 2**bits, centred on 0."""
    half = 2 ** (bits - 1)
    deltas = (np.diff(np.asarray(ticks, dtype=np.int64), axis=0) + half) % (2 * half) - half
    return deltas * distance_per_count


def test_wheel_travel_passes(capsys):
    assert_pass(ch06.wheel_travel_check(modular_travel), capsys)
    assert_not_yet(ch06.wheel_travel_check(ch06.reference_wheel_travel), capsys, "abcwc's own")


def test_wheel_travel_without_the_wrap_is_not_yet(capsys):
    result = ch06.wheel_travel_check(lambda t, d, bits: np.diff(t, axis=0) * d)
    assert_not_yet(result, capsys, "16-bit", "modulo 2**16")


def test_wheel_travel_one_row_too_many_is_not_yet(capsys):
    result = ch06.wheel_travel_check(
        lambda t, d, bits: modular_travel(np.vstack([t[:1], t]), d, bits))
    assert_not_yet(result, capsys, "shape (5, 2), expected (4, 2)", "N - 1")


def test_wheel_travel_with_the_wheels_swapped_is_not_yet(capsys):
    result = ch06.wheel_travel_check(lambda t, d, bits: modular_travel(t, d, bits)[:, ::-1])
    assert_not_yet(result, capsys, "hand-worked", "gave")


# --- exercise 2: one step -------------------------------------------------------------


def eqns_6_to_10(pose, d_left, d_right, wheel_base):
    """Written from eqns 6-10, returning a tuple."""
    d_c = (d_right + d_left) / 2
    phi = (d_right - d_left) / wheel_base
    theta = math.atan2(math.sin(pose.theta + phi), math.cos(pose.theta + phi))
    return (pose.x + d_c * math.cos(pose.theta), pose.y + d_c * math.sin(pose.theta), theta)


def test_odometry_step_passes(capsys):
    assert_pass(ch06.odometry_step_check(eqns_6_to_10), capsys)
    assert_not_yet(ch06.odometry_step_check(ch06.reference_odometry_step), capsys, "abcwc's own")


def test_odometry_step_like_a9_is_not_yet(capsys):
    def a9(pose, d_left, d_right, b):
        theta = pose.theta + (d_right - d_left) / b
        d_c = (d_left + d_right) / 2
        return Pose2D(pose.x + d_c * math.cos(theta), pose.y + d_c * math.sin(theta),
                      math.remainder(theta, 2 * math.pi))

    assert_not_yet(ch06.odometry_step_check(a9), capsys, "after the turn", "A.9")


def test_odometry_step_with_left_and_right_swapped_is_not_yet(capsys):
    result = ch06.odometry_step_check(lambda p, left, right, b: eqns_6_to_10(p, right, left, b))
    assert_not_yet(result, capsys, "wrong way")


def test_odometry_step_without_wrap_is_not_yet(capsys):
    def unwrapped(pose, d_left, d_right, b):
        x, y, _ = eqns_6_to_10(pose, d_left, d_right, b)
        return x, y, pose.theta + (d_right - d_left) / b

    assert_not_yet(ch06.odometry_step_check(unwrapped), capsys, "past +pi", "wrap")


def test_odometry_step_midpoint_is_not_yet(capsys):
    def midpoint(pose, d_left, d_right, wheel_base):
        d_c, phi = (d_right + d_left) / 2, (d_right - d_left) / wheel_base
        heading = pose.theta + phi / 2
        theta = math.atan2(math.sin(pose.theta + phi), math.cos(pose.theta + phi))
        return (pose.x + d_c * math.cos(heading), pose.y + d_c * math.sin(heading), theta)

    result = ch06.odometry_step_check(midpoint)
    assert_not_yet(result, capsys, "theta + phi/2", "as printed")


def test_odometry_step_returning_nothing_is_not_yet(capsys):
    assert_not_yet(ch06.odometry_step_check(lambda *args: None), capsys,
                   "expected a Pose2D")


def test_odometry_step_returning_nan_is_not_yet(capsys):
    assert_not_yet(ch06.odometry_step_check(lambda *args: (math.nan, 0.0, 0.0)), capsys,
                   "gave (nan, 0, 0); a pose is three finite numbers")


# --- exercise 3: the whole log --------------------------------------------------------


def arcs_step_by_step(d_left, d_right, wheel_base, start, method="exact"):
    """A loop of exact-arc steps: slow, but the same answer (``method`` "euler" or
    "midpoint": the chords a student might take instead)."""
    poses = [start]
    for left, right in zip(d_left, d_right):
        d_c, phi = (left + right) / 2, (right - left) / wheel_base
        p = poses[-1]
        exact = method == "exact" and phi != 0
        length = d_c * math.sin(phi / 2) / (phi / 2) if exact else d_c
        heading = p.theta if method == "euler" else p.theta + phi / 2
        poses.append(Pose2D(p.x + length * math.cos(heading), p.y + length * math.sin(heading),
                            math.atan2(math.sin(p.theta + phi), math.cos(p.theta + phi))))
    return np.array([p.as_array() for p in poses])


def test_integrate_arcs_passes(capsys):
    assert_pass(ch06.integrate_arcs_check(arcs_step_by_step), capsys)
    assert_not_yet(ch06.integrate_arcs_check(ch06.reference_integrate_arcs), capsys, "abcwc's own")


@pytest.mark.parametrize("method, fragment", [("euler", "heading before its step"),
                                              ("midpoint", "sin(phi/2)/(phi/2)")])
def test_integrate_arcs_other_methods_are_not_yet(method, fragment, capsys):
    result = ch06.integrate_arcs_check(
        lambda left, right, b, s: arcs_step_by_step(left, right, b, s, method))
    assert_not_yet(result, capsys, fragment)


def test_integrate_arcs_dividing_by_zero_is_not_yet(capsys):
    def naive(d_left, d_right, b, start):
        with np.errstate(invalid="ignore", divide="ignore"):
            phi = (d_right - d_left) / b
            length = (d_left + d_right) / 2 * np.sin(phi / 2) / (phi / 2)
        theta = start.theta + np.concatenate([[0.0], np.cumsum(phi)])
        heading = theta[:-1] + phi / 2
        x = start.x + np.concatenate([[0.0], np.cumsum(length * np.cos(heading))])
        y = start.y + np.concatenate([[0.0], np.cumsum(length * np.sin(heading))])
        return np.column_stack([x, y, np.angle(np.exp(1j * theta))])

    assert_not_yet(ch06.integrate_arcs_check(naive), capsys, "straight line", "np.sinc")


def test_integrate_arcs_unwrapped_is_not_yet(capsys):
    def unwrapped(d_left, d_right, b, start):
        poses = arcs_step_by_step(d_left, d_right, b, start)
        poses[:, 2] = start.theta + np.concatenate([[0.0], np.cumsum((d_right - d_left) / b)])
        return poses

    assert_not_yet(ch06.integrate_arcs_check(unwrapped), capsys, "on the spot", "wrap")


def test_integrate_arcs_without_the_start_row_is_not_yet(capsys):
    result = ch06.integrate_arcs_check(
        lambda *args: arcs_step_by_step(*args)[1:])
    assert_not_yet(result, capsys, "shape (50, 3), expected (51, 3)", "N + 1 poses")


# --- predict, then run: euler at 0.5 s ---------------------------------------------------------

EULER = dict(measured=0.581, at_20_ms=0.0239)   # % of the distance, as the notebook measures


def test_euler_prediction_passes_first_order_scaling(capsys):
    assert_pass(ch06.euler_prediction_check(lambda: 0.0239 * 0.5 / 0.02, **EULER), capsys)


@pytest.mark.parametrize(("predicted", "fragment"), [
    (lambda: 0.0239, "error at 20 ms"),
    (lambda: 0.0239 * 625, "square of the period"),
    (lambda: 0.00598, "as a fraction"),
    (lambda: 2.0, "first order"),
    (lambda: float("inf"), "one percentage"),
    (not_written, "NotImplementedError"),
    (ch06.reference_wheel_travel, "abcwc's own"),
])
def test_euler_prediction_refuses(predicted, fragment, capsys):
    assert_not_yet(ch06.euler_prediction_check(predicted, **EULER), capsys, fragment)


# --- diagnose: the faulty log --------------------------------------------------------------------


def test_the_faulty_log_mirrors_the_true_path():
    """Independent of the check's stored answer: odometry from the log's counts turns the
    other way at every step (its headings are the truth's negated) over the true distance."""
    log = ch06.faulty_log()
    from abcwc.estimation import odometry_from_log

    poses = odometry_from_log(log, method="exact")
    assert np.allclose(poses[:, 2], -log.pose[:, 2], atol=0.01)
    assert np.allclose(poses[:, 1], -log.pose[:, 1], atol=0.02)


def test_diagnosis_check(capsys):
    assert_pass(ch06.diagnosis_check(lambda: "channels swapped"), capsys)
    assert_not_yet(ch06.diagnosis_check(lambda: "left counts backwards"), capsys, "spin")
    assert_not_yet(ch06.diagnosis_check(lambda: "right counts backwards"), capsys, "spin")
    assert_not_yet(ch06.diagnosis_check(lambda: "swapped"), capsys, "say one of")
    assert_not_yet(ch06.diagnosis_check(not_written), capsys, "NotImplementedError")
    assert_not_yet(ch06.diagnosis_check(ch06.faulty_log), capsys, "abcwc's own")
