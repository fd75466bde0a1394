"""The exercise checks of chapter 09 (gyro + encoders).

Each check must pass a correct answer (the library's and one written independently
here), and report "not yet" (never raise) for a wrong one and for an exercise that is
not written yet.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.checks import ch09
from abcwc.types import Pose2D
from tests.check_helpers import assert_not_yet, assert_pass, not_written

# --- exercise 1: the bias ----------------------------------------------------------------


def student_bias(samples):
    values = [float(s) for s in samples]
    if not values:
        raise ValueError("no samples")
    if not all(math.isfinite(v) for v in values):
        raise ValueError("a sample is NaN or inf")
    return sum(values) / len(values)


def test_bias_passes_the_mean(capsys):
    assert_pass(ch09.bias_check(student_bias), capsys)
    assert_not_yet(ch09.bias_check(ch09.reference_estimate_bias), capsys, "abcwc's own")


def test_bias_message_compares_the_estimate_with_the_simulators_truth(capsys):
    log, truth = ch09.still_log()
    ch09.bias_check(student_bias)
    out = capsys.readouterr().out
    assert f"{np.mean(log.gyro_z):.5f} rad/s" in out and f"{truth:.5f} rad/s" in out
    assert abs(np.mean(log.gyro_z) - truth) < 0.001  # 3 s: a standard error near 0.0003


def test_bias_median_is_not_yet(capsys):
    assert_not_yet(ch09.bias_check(lambda s: float(np.median(s))), capsys, "median")


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
def test_bias_that_accepts_nan_or_empty_is_not_yet(capsys):
    assert_not_yet(ch09.bias_check(lambda s: float(np.mean(s))), capsys,
                   "no samples at all gave nan", "ValueError")
    def skip_nan(samples):
        values = np.asarray(samples, dtype=float)
        if values.size == 0:
            raise ValueError("empty")
        return float(np.nanmean(values[np.isfinite(values)]))

    assert_not_yet(ch09.bias_check(skip_nan), capsys, "a NaN sample", "ValueError")


def test_bias_raising_the_wrong_error_is_not_yet(capsys):
    def zero_division(samples):
        values = [float(s) for s in samples]
        if any(v != v for v in values):
            raise ValueError("nan")
        return sum(values) / len(values) if values else 1 / 0

    assert_not_yet(ch09.bias_check(zero_division), capsys, "raised ZeroDivisionError")


def test_bias_not_written(capsys):
    assert_not_yet(ch09.bias_check(not_written), capsys, "not written yet")


# --- exercise 2: the heading -------------------------------------------------------------


def student_heading(t, gyro_z, theta0=0.0, bias=0.0):
    """A loop, unwrapped (the check compares modulo 2 pi)."""
    out = [float(theta0)]
    for k in range(len(t) - 1):
        out.append(out[-1] + (gyro_z[k] - bias) * (t[k + 1] - t[k]))
    return np.array(out)


def integrate_with(increments_of):
    def integrate(t, gyro_z, theta0=0.0, bias=0.0):
        rate = np.asarray(gyro_z) - bias
        return theta0 + np.concatenate([[0.0], np.cumsum(increments_of(rate, np.diff(t)))])
    return integrate


def test_heading_passes_the_rectangle_rule(capsys):
    assert_pass(ch09.heading_check(student_heading), capsys)
    assert_not_yet(ch09.heading_check(ch09.reference_integrate_heading), capsys, "abcwc's own")


def test_heading_with_the_end_sample_is_not_yet(capsys):
    fn = integrate_with(lambda rate, dt: rate[1:] * dt)
    assert_not_yet(ch09.heading_check(fn), capsys, "the sample at the end of each period")


def test_heading_trapezoid_is_not_yet(capsys):
    fn = integrate_with(lambda rate, dt: (rate[1:] + rate[:-1]) / 2 * dt)
    assert_not_yet(ch09.heading_check(fn), capsys, "the trapezoid")


def test_heading_with_one_common_dt_is_not_yet(capsys):
    fn = integrate_with(lambda rate, dt: rate[:-1] * 0.02)
    assert_not_yet(ch09.heading_check(fn), capsys, "uneven timestamps", "one common dt")


def test_heading_ignoring_the_bias_is_not_yet(capsys):
    result = ch09.heading_check(lambda t, g, theta0=0.0, bias=0.0: student_heading(t, g, theta0))
    assert_not_yet(result, capsys, "the bias removed")


def test_heading_without_the_start_value_is_not_yet(capsys):
    result = ch09.heading_check(lambda t, g, theta0=0.0, bias=0.0:
                                student_heading(t, g, theta0, bias)[1:])
    assert_not_yet(result, capsys, "expected 101 headings")


def test_heading_not_written(capsys):
    assert_not_yet(ch09.heading_check(not_written), capsys, "not written yet")


# --- exercise 3: one fused step ----------------------------------------------------------


def student_step(pose, d_left, d_right, gyro_z, dt, bias=0.0):
    """Returns a plain (x, y, theta) tuple, theta unwrapped: both accepted."""
    turn = (gyro_z - bias) * dt
    centre = 0.5 * (d_left + d_right)
    mid = pose.theta + 0.5 * turn
    return pose.x + centre * math.cos(mid), pose.y + centre * math.sin(mid), pose.theta + turn


def step_heading_at(fraction):
    def step(pose, d_left, d_right, gyro_z, dt, bias=0.0):
        turn = (gyro_z - bias) * dt
        heading = pose.theta + fraction * turn
        d_c = (d_left + d_right) / 2
        return Pose2D(pose.x + d_c * math.cos(heading), pose.y + d_c * math.sin(heading),
                      pose.theta + turn)
    return step


def test_fused_step_passes_eqn_16_with_the_midpoint_heading(capsys):
    assert_pass(ch09.fused_step_check(student_step), capsys)
    assert_not_yet(ch09.fused_step_check(ch09.reference_fused_step), capsys, "abcwc's own")


def test_fused_step_euler_and_a11_headings_are_not_yet(capsys):
    assert_not_yet(ch09.fused_step_check(step_heading_at(0.0)), capsys,
                   "heading at the start of the step")
    assert_not_yet(ch09.fused_step_check(step_heading_at(1.0)), capsys,
                   "heading at the end of the step", "A.11")


def test_fused_step_turning_by_the_wheels_is_not_yet(capsys):
    def wheels(pose, d_left, d_right, gyro_z, dt, bias=0.0):
        turn = (d_right - d_left) / 0.44
        heading = pose.theta + turn / 2
        d_c = (d_left + d_right) / 2
        return Pose2D(pose.x + d_c * math.cos(heading), pose.y + d_c * math.sin(heading),
                      pose.theta + turn)

    assert_not_yet(ch09.fused_step_check(wheels), capsys, "turned by the wheels")


def test_fused_step_without_the_bias_is_not_yet(capsys):
    def no_bias(pose, d_left, d_right, gyro_z, dt, bias=0.0):
        return student_step(pose, d_left, d_right, gyro_z, dt, 0.0)

    assert_not_yet(ch09.fused_step_check(no_bias), capsys, "bias was not subtracted")


def test_fused_step_returning_something_else_is_not_yet(capsys):
    assert_not_yet(ch09.fused_step_check(lambda *args: 1.0), capsys, "expected a Pose2D")


def test_fused_step_returning_nan_is_not_yet(capsys):
    assert_not_yet(ch09.fused_step_check(lambda *args: (0.0, math.inf, 0.0)), capsys,
                   "gave (0, inf, 0); a pose is three finite numbers")


def test_fused_step_not_written(capsys):
    assert_not_yet(ch09.fused_step_check(not_written), capsys, "not written yet")


# --- exercise 4: measuring the pessimistic part's best standing time ---------------------------


def test_best_standing_time_worked_by_hand():
    """The pessimistic part: sigma_w 2.4 x the datasheet's, K = 1e-4 rad/s/sqrt(s), dt 0.02 s:
    T* = sqrt(3) sigma_w sqrt(dt) / K."""
    from abcwc.params import load_params

    g = load_params(gyro="pessimistic").gyro
    assert ch09.best_standing_time() == pytest.approx(
        math.sqrt(3) * g.noise_std * math.sqrt(0.02) / 1e-4, rel=1e-9)
    assert 6.0 < ch09.best_standing_time() < 9.0
    assert 250 < ch09.best_standing_time("datasheet") < 350


def test_best_window_check_passes_an_independent_measurement(capsys):
    """Written without the notebook's helpers: the pessimistic part's model, 300 power-ups."""
    from abcwc.params import load_params

    g = load_params(gyro="pessimistic").gyro
    rng = np.random.default_rng(3)
    n, dt = 3000, 0.02
    bias = rng.normal(0, g.bias_std, (300, 1)) + np.cumsum(
        rng.normal(0, g.bias_walk_std * math.sqrt(dt), (300, n)), axis=1)
    samples = bias + rng.normal(0, g.noise_std, (300, n))
    windows = np.array([0.5, 1, 2, 4, 6, 8, 12, 16, 24, 40, 60])
    rms = [np.sqrt(np.mean((samples[:, -int(w / dt):].mean(axis=1) - bias[:, -1]) ** 2))
           for w in windows]
    measured = float(windows[int(np.argmin(rms))])
    assert_pass(ch09.best_window_check(lambda: measured), capsys)


@pytest.mark.parametrize(("measured", "fragment"), [
    (lambda: 300.0, "datasheet part"),
    (lambda: 60.0, "kept falling"),
    (lambda: 1.0, "too few samples"),
    (lambda: -5.0, "one window length"),
    (not_written, "NotImplementedError"),
    (ch09.reference_estimate_bias, "abcwc's own"),
])
def test_best_window_check_refuses(measured, fragment, capsys):
    assert_not_yet(ch09.best_window_check(measured), capsys, fragment)


# --- exercise (predict, then run): the five laps' end heading errors ----------------------------

LAPS = dict(wheels=28.5, raw_gyro=46.1, bias=0.00407, driving=195.0)   # as the notebook measures


def lap_check(predicted):
    return ch09.end_heading_prediction_check(predicted, **LAPS)


def test_lap_prediction_passes_an_independent_reading(capsys):
    wheels = math.degrees((1.03 / 1.0123 - 1) * 10 * math.pi)   # 1.7 % of five turns
    raw = math.degrees(0.00407 * 195.0)
    assert_pass(lap_check(lambda: (wheels, raw)), capsys)


@pytest.mark.parametrize(("predicted", "fragment"), [
    (lambda: (54.0, 45.5), "3 % too large"),              # the wheel base alone
    (lambda: (-30.0, 45.5), "wheels' sign"),
    (lambda: (0.52, 0.79), "radians"),
    (lambda: (30.0, -45.5), "raw gyro's sign"),
    (lambda: (30.0, 0.0), "adds its bias"),
    (lambda: 30.0, "two angles"),
    (not_written, "NotImplementedError"),
    (ch09.reference_estimate_bias, "abcwc's own"),
])
def test_lap_prediction_refuses(predicted, fragment, capsys):
    assert_not_yet(lap_check(predicted), capsys, fragment)
