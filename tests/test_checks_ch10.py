"""The exercise checks of chapter 10 (the EKF).

Each check must pass a correct answer, and report "not yet" (never raise) for a wrong
one and for an exercise that is not written yet.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.checks import ch10
from tests.check_helpers import assert_not_yet, assert_pass, not_written

# --- exercise 1: f and F --------------------------------------------------------------


def student_motion(s, dt):
    """Written from the equations, independently of the library."""
    x, y, theta, v, w, b = s
    return np.array([x + v * dt * math.cos(theta), y + v * dt * math.sin(theta),
                     theta + w * dt, v, w, b])


def student_jacobian(s, dt):
    theta, v = s[2], s[3]
    f = np.eye(6)
    f[0, 2], f[0, 3] = -v * dt * math.sin(theta), dt * math.cos(theta)
    f[1, 2], f[1, 3] = v * dt * math.cos(theta), dt * math.sin(theta)
    f[2, 4] = dt
    return f


def test_motion_check_passes_the_unicycle(capsys):
    assert_pass(ch10.motion_check(student_motion, student_jacobian), capsys)
    assert_not_yet(ch10.motion_check(ch10.reference_motion, ch10.reference_motion_jacobian),
                   capsys, "abcwc's own")


def test_motion_with_sin_and_cos_swapped_is_not_yet(capsys):
    def swapped(s, dt):
        out = student_motion(s, dt)
        out[0] = s[0] + s[3] * dt * math.sin(s[2])
        return out

    assert_not_yet(ch10.motion_check(swapped, student_jacobian), capsys, "x' for s =")


def test_motion_that_forgets_the_bias_state_is_not_yet(capsys):
    result = ch10.motion_check(lambda s, dt: student_motion(s, dt)[:5], student_jacobian)
    assert_not_yet(result, capsys, "shape (5,), expected (6,)")


def test_jacobian_with_a_sign_slip_is_not_yet(capsys):
    def slip(s, dt):
        f = student_jacobian(s, dt)
        f[0, 2] = -f[0, 2]
        return f

    assert_not_yet(ch10.motion_check(student_motion, slip), capsys, "F[0, 2]",
                   "dx'/dtheta")


def test_jacobian_without_the_heading_rate_term_is_not_yet(capsys):
    def no_dt(s, dt):
        f = student_jacobian(s, dt)
        f[2, 4] = 0.0
        return f

    assert_not_yet(ch10.motion_check(student_motion, no_dt), capsys, "F[2, 4]")


def test_motion_not_written(capsys):
    assert_not_yet(ch10.motion_check(not_written, not_written), capsys, "not written yet")
    assert_not_yet(ch10.motion_check(student_motion, not_written), capsys, "not written yet")


# --- exercise 2: one Kalman update ----------------------------------------------------


def textbook_update(x, P, z, H, R):
    """The short form (I - K H) P: what most books print."""
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    return x + K @ (z - H @ x), (np.eye(len(x)) - K @ H) @ P


def test_kalman_update_passes_the_textbook_and_refuses_the_library(capsys):
    assert_pass(ch10.kalman_update_check(textbook_update), capsys)
    assert_not_yet(ch10.kalman_update_check(ch10.reference_kalman_update), capsys, "abcwc's own")


def test_kalman_update_without_the_inverse_is_not_yet(capsys):
    def no_inverse(x, P, z, H, R):
        S = H @ P @ H.T + R
        K = P @ H.T @ S  # S where S^-1 belongs
        return x + K @ (z - H @ x), P - K @ S @ K.T

    assert_not_yet(ch10.kalman_update_check(no_inverse), capsys, "wheel update", "filterpy")


def test_kalman_update_that_forgets_p_is_not_yet(capsys):
    def keep_p(x, P, z, H, R):
        return textbook_update(x, P, z, H, R)[0], P

    assert_not_yet(ch10.kalman_update_check(keep_p), capsys, "P came back unchanged")


def test_kalman_update_in_place_is_not_yet(capsys):
    def in_place(x, P, z, H, R):
        new_x, new_p = textbook_update(x, P, z, H, R)
        x += new_x - x
        return x, new_p

    assert_not_yet(ch10.kalman_update_check(in_place), capsys, "changed the arrays")


def test_kalman_update_returning_one_thing_is_not_yet(capsys):
    result = ch10.kalman_update_check(lambda x, P, z, H, R: textbook_update(x, P, z, H, R)[0])
    assert_not_yet(result, capsys, "tuple (x, P)")


def test_kalman_update_not_written(capsys):
    assert_not_yet(ch10.kalman_update_check(not_written), capsys, "not written yet")


# --- exercise 3: NEES of a sample -----------------------------------------------------


def student_nees(truth, estimate, P):
    e = np.asarray(truth, dtype=float) - np.asarray(estimate, dtype=float)
    e[2] = (e[2] + math.pi) % (2 * math.pi) - math.pi
    return float(e @ np.linalg.solve(P, e))


def test_nees_passes_a_wrapped_solve(capsys):
    assert_pass(ch10.nees_check(student_nees), capsys)
    assert_not_yet(ch10.nees_check(ch10.reference_nees_sample), capsys, "abcwc's own")


def test_nees_without_wrapping_is_not_yet(capsys):
    def unwrapped(truth, estimate, P):
        e = np.asarray(truth) - np.asarray(estimate)
        return float(e @ np.linalg.solve(P, e))

    assert_not_yet(ch10.nees_check(unwrapped), capsys, "wrap the error", "6.20 rad")


def test_nees_without_the_inverse_is_not_yet(capsys):
    def times_p(truth, estimate, P):
        e = np.asarray(truth) - np.asarray(estimate)
        return float(e @ P @ e)

    assert_not_yet(ch10.nees_check(times_p), capsys, "e^T P^-1 e")


def test_nees_as_an_array_is_not_yet(capsys):
    def per_component(truth, estimate, P):
        e = np.asarray(truth) - np.asarray(estimate)
        return e ** 2 / np.diag(P)

    assert_not_yet(ch10.nees_check(per_component), capsys, "expected one number")


def test_nees_not_written(capsys):
    assert_not_yet(ch10.nees_check(not_written), capsys, "not written yet")


@pytest.mark.parametrize("check", [ch10.kalman_update_check, ch10.nees_check])
def test_checks_survive_student_exceptions(check, capsys):
    def broken(*args):
        raise ZeroDivisionError("division by zero")

    assert_not_yet(check(broken), capsys, "ZeroDivisionError")


# --- predict, then run: which set-up's NEES is inside the band ---------------------------------

RUN_VERDICTS = {"bias held, gyro R = white noise": "above",
                "bias held, its error spread into R": "inside",
                "bias as a state (this chapter)": "inside"}


def test_nees_prediction_passes_the_runs_verdicts(capsys):
    assert_pass(ch10.nees_prediction_check(lambda: ["above", "inside", "inside"], RUN_VERDICTS),
                capsys)


@pytest.mark.parametrize(("predicted", "fragment"), [
    (lambda: ("inside", "inside", "inside"), "overconfident"),   # a held bias taken as honest
    (lambda: ("below", "inside", "inside"), "overconfident"),    # over- and under- confused
    (lambda: ("above", "above", "inside"), "about the right size"),
    (lambda: ("above", "inside", "above"), "carries its uncertainty"),
    (lambda: ("above", "inside"), "one per set-up"),
    (lambda: ("high", "ok", "ok"), "one per set-up"),
    (not_written, "NotImplementedError"),
    (ch10.reference_nees_sample, "abcwc's own"),
])
def test_nees_prediction_refuses(predicted, fragment, capsys):
    assert_not_yet(ch10.nees_prediction_check(predicted, RUN_VERDICTS), capsys, fragment)


# --- exercise 3: how often the errors lie inside the filter's band -------------------------------


def band_data():
    rng = np.random.default_rng(8)
    sigmas = np.abs(rng.normal(0.05, 0.01, (400, 3))) + 0.01
    errors = rng.normal(0.0, 1.0, (400, 3)) * sigmas * 0.9
    return errors, sigmas


def test_band_share_check_passes_an_independent_count(capsys):
    errors, sigmas = band_data()

    def count(e, s):
        return [sum(abs(e[k, j]) <= 2 * s[k, j] for k in range(len(e))) / len(e)
                for j in range(3)]
    assert_pass(ch10.band_share_check(count, errors, sigmas), capsys)


@pytest.mark.parametrize(("fn", "fragment"), [
    (lambda e, s: 100 * (np.abs(e) <= 2 * s).mean(axis=0), "percentages"),
    (lambda e, s: (np.abs(e) <= s).mean(axis=0), "1-sigma"),
    (lambda e, s: (np.abs(e) <= 2 * s**2).mean(axis=0), "variances"),
    (lambda e, s: (np.abs(e) <= 2 * s).mean(), "three"),
    (lambda e, s: (e <= 2 * s).mean(axis=0), "expected"),
    (not_written, "NotImplementedError"),
    (ch10.reference_nees_sample, "abcwc's own"),
])
def test_band_share_check_refuses(fn, fragment, capsys):
    errors, sigmas = band_data()
    assert_not_yet(ch10.band_share_check(fn, errors, sigmas), capsys, fragment)
