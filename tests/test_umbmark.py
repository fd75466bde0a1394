"""UMBmark (Borenstein and Feng 1996): formulas, the thesis's trials, the simulator."""

import dataclasses
import math

import numpy as np
import pytest

from abcwc.behaviours import SquareDriver
from abcwc.estimation.odometry import Odometry
from abcwc.estimation.umbmark import (
    alpha_beta,
    centres_of_gravity,
    curve_radius,
    e_max_syst,
    load_thesis_trials,
    model_return_error,
    thesis_a16_outputs,
    trial_covariance,
    umbmark_corrections,
    wheel_base_ratio,
    wheel_correction_factors,
    wheel_diameter_ratio,
)
from abcwc.experiments.umbmark_trials import drive_square, run_square, run_umbmark
from abcwc.sim.base import SimBase
from abcwc.sim.motor import ChairErrors
from abcwc.sim.world import box_world
from abcwc.types import Pose2D

OPEN = box_world(20, 20, centred=True)


def test_formulas_recover_a_hand_worked_case():
    """Errors built by the small-angle model from E_d = 1.01, E_b = 1.03 come back."""
    side, b = 3.5, 0.44
    e_d, e_b = 1.01, 1.03
    alpha = math.pi / 2 * (1 - 1 / e_b)  # 0.04575 rad per turn
    radius = e_b * b / 2 * (e_d + 1) / (e_d - 1)  # 45.55 m
    beta = 2 * math.asin(side / 2 / radius)  # 0.07686 rad per leg
    cw = model_return_error(side, b, e_d, e_b, "cw")
    ccw = model_return_error(side, b, e_d, e_b, "ccw")
    assert cw[0] == pytest.approx(-2 * side * (alpha + beta))
    assert ccw[1] == pytest.approx(2 * side * (alpha - beta))
    for use in ("x", "y", "xy"):
        result = umbmark_corrections([cw], [ccw], side, b, use=use)
        assert result.alpha == pytest.approx(alpha)
        assert result.beta == pytest.approx(beta)
        assert result.e_d == pytest.approx(e_d)
        assert result.e_b == pytest.approx(e_b)
        assert result.wheel_base == pytest.approx(e_b * b)
        assert result.c_left == pytest.approx(2 / 2.01)
        assert result.c_right / result.c_left == pytest.approx(e_d)
    assert e_max_syst([cw], [ccw]) == pytest.approx(math.hypot(*cw))


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="cw_errors"):
        umbmark_corrections(np.zeros((0, 2)), [[0, 0]], 3.5, 0.44)
    with pytest.raises(ValueError, match="use"):
        umbmark_corrections([[0.1, 0]], [[0, 0]], 3.5, 0.44, use="z")
    with pytest.raises(ValueError, match=r"cg_ccw must be a finite \(x, y\)"):
        alpha_beta([0.1, 0.0], [math.nan, 0.0], 3.5)
    with pytest.raises(ValueError, match=r"cg_cw must be a finite \(x, y\)"):
        alpha_beta([0.1], [0.0, 0.0], 3.5)
    with pytest.raises(ValueError, match="beta"):
        curve_radius(math.nan, 3.5)
    with pytest.raises(ValueError, match="e_b"):
        model_return_error(3.5, 0.44, 1.01, -1.03, "cw")


def test_thesis_covariance_reproduced():
    trials = load_thesis_trials()
    ends = np.vstack([trials["cw"], trials["ccw"]])
    assert ends.shape == (10, 3)
    cov1 = trial_covariance(ends, ddof=1)
    cov0 = trial_covariance(ends, ddof=0)
    # x and y of figure 51 follow from MATLAB's cov (n - 1), not from the 1/n formula
    assert round(cov1[0, 0], 4) == 0.0212 and round(cov0[0, 0], 4) == 0.0190
    assert round(cov1[1, 1], 4) == 0.0041 and round(cov0[1, 1], 4) == 0.0037
    # theta's 0.0042 does not follow from the table's ten values (0.0038 / 0.0034) ...
    assert round(cov1[2, 2], 4) == 0.0038 and round(cov0[2, 2], 4) == 0.0034
    # ... but from A.16's nine-value theta vector
    a16 = thesis_a16_outputs(trials)
    assert round(a16["cov_theta"], 4) == 0.0042
    # and the off-diagonal terms it prints as 0 are not zero
    assert abs(cov1[0, 1]) > 0.002


def test_umbmark_in_the_simulator_cuts_systematic_error():
    errors = ChairErrors(drive_wheel_left=1.0, drive_wheel_right=1.01,
                         encoder_wheel_left=0.995, encoder_wheel_right=1.005, wheel_base=1.03)

    def make(seed):
        return SimBase(OPEN, seed=seed, errors=errors, people=False)

    cw, ccw = run_umbmark(make, runs=1, side=3.5)
    result = umbmark_corrections(cw, ccw, 3.5, 0.44)
    cw2, ccw2 = run_umbmark(make, runs=1, side=3.5, correction=result.correction,
                            wheel_base=result.wheel_base)
    before, after = result.e_max_syst, e_max_syst(cw2, ccw2)
    assert before > 0.5
    assert after < before / 5, (before, after)
    # injected: E_d = 1.005 / 0.995, E_b = 1.03, so c = (0.995, 1.005)
    assert result.e_d == pytest.approx(1.005 / 0.995, abs=0.002)
    assert result.e_b == pytest.approx(1.03, abs=0.005)
    assert result.c_left == pytest.approx(0.995, abs=0.001)
    assert result.c_right == pytest.approx(1.005, abs=0.001)


def test_the_steps_of_the_method_agree_with_the_model():
    """alpha_beta, curve_radius, wheel_diameter_ratio, wheel_base_ratio invert the model."""
    side, b, e_d, e_b = 4.0, 0.35, 0.992, 0.97  # a chair curving right, short turns
    cw = model_return_error(side, b, e_d, e_b, "cw")
    ccw = model_return_error(side, b, e_d, e_b, "ccw")
    cg_cw, cg_ccw = centres_of_gravity([cw, cw], [ccw])
    assert np.allclose(cg_cw, cw) and np.allclose(cg_ccw, ccw)
    angles = {use: alpha_beta(cg_cw, cg_ccw, side, use) for use in ("x", "y", "xy")}
    alpha = math.pi / 2 * (1 - 1 / e_b)
    for got_alpha, got_beta in angles.values():
        assert got_alpha == pytest.approx(alpha) and got_beta < 0
    radius = curve_radius(angles["x"][1], side)
    assert radius < 0  # curving right
    assert wheel_diameter_ratio(radius, e_b * b) == pytest.approx(e_d)
    assert wheel_base_ratio(alpha) == pytest.approx(e_b)
    c_left, c_right = wheel_correction_factors(e_d)
    assert c_right / c_left == pytest.approx(e_d) and (c_left + c_right) / 2 == pytest.approx(
        1.0, abs=1e-4)


def test_the_steps_handle_a_perfect_chair_and_refuse_nonsense():
    assert curve_radius(0.0, 3.5) == math.inf
    assert wheel_diameter_ratio(math.inf, 0.44) == 1.0
    assert wheel_correction_factors(1.0) == (1.0, 1.0)
    with pytest.raises(ValueError, match="side"):
        alpha_beta([0, 0], [0, 0], 0.0)
    with pytest.raises(ValueError, match="inside the wheel base"):
        wheel_diameter_ratio(0.1, 0.44)
    with pytest.raises(ValueError, match="alpha"):
        wheel_base_ratio(math.pi / 2)
    with pytest.raises(ValueError, match="E_d"):
        wheel_correction_factors(0.0)
    with pytest.raises(ValueError, match="brake_gain"):
        SquareDriver(Odometry(), brake_gain=0.0)


def test_run_square_reports_in_the_start_frame():
    """A perfect chair started anywhere closes the square; its path starts at the origin."""
    start = Pose2D(-3.0, 2.0, 2.5)
    sim = SimBase(OPEN, seed=1, errors="ideal", people=False, start=start)
    run = run_square(sim, "cw", side=2.0)
    assert np.allclose(run.true_path[0], 0.0, atol=1e-9)
    assert np.abs(run.error[:2]).max() < 0.01 and abs(run.error[2]) < 0.005
    # the corners in the start frame: x ahead, then to the right (cw)
    assert run.true_path[:, 0].max() == pytest.approx(2.0, abs=0.05)
    assert run.true_path[:, 1].min() == pytest.approx(-2.0, abs=0.05)
    # the true end, turned back into the world, is where the simulator left the chair
    end = run.true_end
    c, s = math.cos(start.theta), math.sin(start.theta)
    assert sim.pose.x == pytest.approx(start.x + c * end.x - s * end.y, abs=1e-9)
    assert sim.pose.y == pytest.approx(start.y + s * end.x + c * end.y, abs=1e-9)
    assert 20.0 < run.seconds < 80.0


def test_run_square_without_ground_truth_gives_nan():
    """The real chair has no ground truth: the odometric end only, and no error."""

    class NoTruth:
        def __init__(self, sim):
            self.sim, self.period, self.params = sim, sim.period, sim.params

        def read(self):
            return dataclasses.replace(self.sim.read(), truth=None)

        def run(self, controller, seconds):
            log = self.sim.run(lambda f: controller(dataclasses.replace(f, truth=None)), seconds)
            log.pose[:] = np.nan
            return log

    body = NoTruth(SimBase(OPEN, seed=0, errors=ChairErrors(wheel_base=1.03), people=False))
    run = run_square(body, "ccw", side=1.0)
    assert run.true_end is None and np.isnan(run.error).all()
    assert math.hypot(run.odometric_end.x, run.odometric_end.y) < 0.02
    with pytest.raises(ValueError, match="ground truth"):
        drive_square(body, "ccw", side=1.0)


def test_a_wheel_mismatch_can_hide_a_wheel_base_error_one_way_round():
    """The E_d whose legs curve by each turn's shortfall: by hand, alpha = pi/2 (1 - 1/1.03)
    = 0.04575 rad, R = 1.75 / sin(alpha / 2) = 76.51 m, E_d = (R + 0.2266) / (R - 0.2266)
    = 1.00594 for L = 3.5 m and b = 0.44 m; the model's CCW square then closes, the CW one
    does not."""
    from abcwc.estimation import cancelling_wheel_ratio, model_return_error

    e_d = cancelling_wheel_ratio(1.03, 3.5, 0.44)
    alpha = math.pi / 2 * (1 - 1 / 1.03)
    radius = 1.75 / math.sin(alpha / 2)
    assert e_d == pytest.approx((radius + 1.03 * 0.22) / (radius - 1.03 * 0.22))
    assert e_d == pytest.approx(1.00594, abs=1e-5)
    ccw = model_return_error(3.5, 0.44, e_d, 1.03, "ccw")
    cw = model_return_error(3.5, 0.44, e_d, 1.03, "cw")
    assert math.hypot(*ccw) < 0.01 < math.hypot(*cw)
    with pytest.raises(ValueError, match="e_b"):
        cancelling_wheel_ratio(-1.0, 3.5, 0.44)
