"""The exercise checks of chapter 08 (UMBmark calibration).

Each check must pass a correct answer, and report "not yet" (never raise) for a wrong
one and for an exercise that is not written yet.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.checks import ch08
from abcwc.estimation.umbmark import load_thesis_trials
from tests.check_helpers import assert_not_yet, assert_pass, not_written

# --- independent student answers --------------------------------------------------------


def student_centres(cw, ccw):
    """Written from the paper, with plain loops."""
    def centre(rows):
        xs = [row[0] for row in rows]
        ys = [row[1] for row in rows]
        return (sum(xs) / len(xs), sum(ys) / len(ys))

    cg_cw, cg_ccw = centre(cw), centre(ccw)
    return cg_cw, cg_ccw, max(math.dist((0, 0), cg_cw), math.dist((0, 0), cg_ccw))


def student_alpha_beta(cg_cw, cg_ccw, side):
    alpha = -(cg_cw[0] + cg_ccw[0]) / (4 * side)
    beta = -(cg_cw[0] - cg_ccw[0]) / (4 * side)
    return alpha, beta, side / (2 * math.sin(beta / 2))


def student_factors(alpha, radius, wheel_base):
    e_b = 90 / (90 - math.degrees(alpha))
    b = e_b * wheel_base
    e_d = (2 * radius + b) / (2 * radius - b)
    return e_b, b, e_d, 2 / (e_d + 1), 2 * e_d / (1 + e_d)


# --- exercise 1: centres of gravity and E_max,syst ----------------------------------------


def test_centres_passes(capsys):
    result = ch08.centres_check(student_centres)
    assert_pass(result, capsys)
    assert "0.2184 m" in result.line  # figure 51's numbers, A.16's emax
    assert_not_yet(ch08.centres_check(ch08.reference_centres_of_gravity_and_emax), capsys,
                   "abcwc's own")


def test_the_thesis_centres_by_hand():
    trials = load_thesis_trials()
    cg_cw, cg_ccw, e_max = ch08.reference_centres_of_gravity_and_emax(trials["cw"],
                                                                      trials["ccw"])
    assert np.allclose(cg_cw, [(0.27 + 0.18 + 0.01 + 0.48 + 0.08) / 5,
                               (0.04 + 0.00 + 0.01 + 0.16 + 0.18) / 5])
    assert np.allclose(cg_ccw, [0.67 / 5, 0.31 / 5])
    assert e_max == pytest.approx(math.hypot(0.204, 0.078))


def test_centres_with_the_mean_distance_is_not_yet(capsys):
    def mean_distance(cw, ccw):
        cg_cw, cg_ccw, _ = student_centres(cw, ccw)
        distance = max(np.hypot(*np.asarray(cw)[:, :2].T).mean(),
                       np.hypot(*np.asarray(ccw)[:, :2].T).mean())
        return cg_cw, cg_ccw, distance

    assert_not_yet(ch08.centres_check(mean_distance), capsys, "mean distance", "eqn 5.5")


def test_centres_with_min_instead_of_max_is_not_yet(capsys):
    def smaller(cw, ccw):
        cg_cw, cg_ccw, _ = student_centres(cw, ccw)
        return cg_cw, cg_ccw, min(math.hypot(*cg_cw), math.hypot(*cg_ccw))

    assert_not_yet(ch08.centres_check(smaller), capsys, "e_max", "eqns 5.5, 5.6")


def test_centres_keeping_theta_is_not_yet(capsys):
    def with_theta(cw, ccw):
        cg_cw, cg_ccw = np.mean(cw, axis=0), np.mean(ccw, axis=0)
        return cg_cw, cg_ccw, max(np.hypot(*cg_cw[:2]), np.hypot(*cg_ccw[:2]))

    assert_not_yet(ch08.centres_check(with_theta), capsys, "shape (3,)", "shape (2,)")


def test_centres_returning_too_little_is_not_yet(capsys):
    result = ch08.centres_check(lambda cw, ccw: student_centres(cw, ccw)[2])
    assert_not_yet(result, capsys, "expected 3 values")


def test_centres_not_written(capsys):
    assert_not_yet(ch08.centres_check(not_written), capsys, "not written yet")


# --- exercise 2: alpha, beta, R -----------------------------------------------------------


def test_alpha_beta_passes(capsys):
    assert_pass(ch08.alpha_beta_radius_check(student_alpha_beta), capsys)
    assert_not_yet(ch08.alpha_beta_radius_check(ch08.reference_alpha_beta_radius), capsys,
                   "abcwc's own")


def test_worked_example_by_hand():
    """E_d 1.01, E_b 1.03, L 3.5 m, b 0.44 m: alpha, beta and R as worked in the notebook."""
    model = ch08.worked_example()
    alpha, beta, radius = ch08.reference_alpha_beta_radius(model["cw"][0], model["ccw"][0],
                                                           3.5)
    assert alpha == pytest.approx(math.pi / 2 * (1 - 1 / 1.03))
    assert radius == pytest.approx(1.03 * 0.44 / 2 * 2.01 / 0.01)
    assert beta == pytest.approx(0.07686, abs=1e-5)


def test_alpha_beta_in_degrees_is_not_yet(capsys):
    def degrees(cg_cw, cg_ccw, side):
        alpha, beta, radius = student_alpha_beta(cg_cw, cg_ccw, side)
        return math.degrees(alpha), math.degrees(beta), radius

    assert_not_yet(ch08.alpha_beta_radius_check(degrees), capsys, "degrees", "180/pi")


def test_alpha_beta_with_the_sign_flipped_is_not_yet(capsys):
    def flipped(cg_cw, cg_ccw, side):
        alpha, beta, _ = student_alpha_beta(cg_cw, cg_ccw, side)
        return -alpha, -beta, side / (2 * math.sin(-beta / 2))

    assert_not_yet(ch08.alpha_beta_radius_check(flipped), capsys, "wrong sign", "-4L")


def test_alpha_beta_with_the_chord_as_radius_is_not_yet(capsys):
    def small_angle(cg_cw, cg_ccw, side):
        alpha, beta, _ = student_alpha_beta(cg_cw, cg_ccw, side)
        return alpha, beta, side / beta

    assert_not_yet(ch08.alpha_beta_radius_check(small_angle), capsys, "R gave", "eqn 5.11")


def test_alpha_beta_not_written(capsys):
    assert_not_yet(ch08.alpha_beta_radius_check(not_written), capsys, "not written yet")


# --- exercise 3: E_b, E_d and the correction factors --------------------------------------


def test_correction_factors_pass(capsys):
    result = ch08.correction_factors_check(student_factors)
    assert_pass(result, capsys)
    assert "E_b 1.0300, E_d 1.0100" in result.line  # the worked example comes back
    assert_not_yet(ch08.correction_factors_check(ch08.reference_correction_factors), capsys,
                   "abcwc's own")


def test_correction_factors_with_the_nominal_wheel_base_is_not_yet(capsys):
    def nominal(alpha, radius, wheel_base):
        e_b, b, _, _, _ = student_factors(alpha, radius, wheel_base)
        e_d = (radius + wheel_base / 2) / (radius - wheel_base / 2)
        return e_b, b, e_d, 2 / (e_d + 1), 2 / (1 / e_d + 1)

    assert_not_yet(ch08.correction_factors_check(nominal), capsys, "nominal wheel base")


def test_correction_factors_swapped_is_not_yet(capsys):
    def swapped(alpha, radius, wheel_base):
        e_b, b, e_d, c_left, c_right = student_factors(alpha, radius, wheel_base)
        return e_b, b, e_d, c_right, c_left

    assert_not_yet(ch08.correction_factors_check(swapped), capsys, "which is c_right")


def test_correction_factors_with_alpha_taken_as_degrees_is_not_yet(capsys):
    def radians_as_degrees(alpha, radius, wheel_base):
        e_b = 90 / (90 - alpha)
        b = e_b * wheel_base
        e_d = (radius + b / 2) / (radius - b / 2)
        return e_b, b, e_d, 2 / (e_d + 1), 2 / (1 / e_d + 1)

    assert_not_yet(ch08.correction_factors_check(radians_as_degrees), capsys, "E_b gave",
                   "alpha in rad")


def test_correction_factors_not_written(capsys):
    assert_not_yet(ch08.correction_factors_check(not_written), capsys, "not written yet")


# --- exercise 4: diagnosing a second chair ---------------------------------------------------


def test_the_second_chairs_clusters_give_its_faults_back():
    """Independent of the check's stored answer: UMBmark on the second chair's return
    errors recovers a right encoder wheel smaller than the left and a narrower wheel base."""
    from abcwc.estimation.umbmark import umbmark_corrections

    cw, ccw = ch08.second_chair_return_errors()
    found = umbmark_corrections(cw, ccw, 3.5, 0.44)
    assert found.e_d == pytest.approx(0.992, abs=0.002)
    assert found.e_b == pytest.approx(0.98, abs=0.01)


def test_diagnosis_check_passes_the_right_reading(capsys):
    assert_pass(ch08.diagnosis_check(lambda: {"wheels": "left larger",
                                              "wheel base": "narrower"}), capsys)


@pytest.mark.parametrize(("said", "fragment"), [
    ({"wheels": "right larger", "wheel base": "narrower"}, "below 1"),      # E_d read upside down
    ({"wheels": "left larger", "wheel base": "wider"}, "came out long"),    # alpha's sign
    ({"wheels": "equal", "wheel base": "narrower"}, "type B"),
    ({"wheels": "left larger", "wheel base": "nominal"}, "type A"),
    ({"wheels": "left", "wheel base": "narrower"}, "say one of"),
    ({"wheels": "left larger"}, "return"),
])
def test_diagnosis_check_refuses(said, fragment, capsys):
    assert_not_yet(ch08.diagnosis_check(lambda: said), capsys, fragment)


def test_diagnosis_check_refuses_the_stub_and_abcwcs_own(capsys):
    assert_not_yet(ch08.diagnosis_check(not_written), capsys, "NotImplementedError")
    assert_not_yet(ch08.diagnosis_check(ch08.reference_correction_factors), capsys,
                   "abcwc's own")


# --- exercise 5: figure 51's covariance ------------------------------------------------------


def test_covariance_check_passes_an_independent_covariance(capsys):
    def by_hand(ends):
        n = len(ends)
        out = np.zeros((3, 3))
        for i in range(3):
            for j in range(3):
                a, b = ends[:, i] - ends[:, i].mean(), ends[:, j] - ends[:, j].mean()
                out[i, j] = (a * b).sum() / (n - 1)
        return out
    assert_pass(ch08.covariance_check(by_hand), capsys)


@pytest.mark.parametrize(("fn", "fragment"), [
    (lambda ends: np.cov(ends.T, ddof=0), "n = 10"),
    (lambda ends: np.diag(np.var(ends, axis=0, ddof=1)), "only the variances"),
    (lambda ends: np.cov(ends)[:3, :3], "ends.T"),
    (lambda ends: np.cov(ends.T)[:2, :2], "3 x 3"),
    (lambda ends: np.cov(ends.T) * 2, "expected"),
    (not_written, "NotImplementedError"),
    (ch08.reference_correction_factors, "abcwc's own"),
])
def test_covariance_check_refuses(fn, fragment, capsys):
    assert_not_yet(ch08.covariance_check(fn), capsys, fragment)
