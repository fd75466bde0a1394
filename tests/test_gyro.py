"""One step of gyro + encoder odometry and the Allan deviation (abcwc.estimation.gyro).

Truths: closed forms (a straight line, a spin on the spot, a circular arc; the Allan
deviation of white noise, of a random walk, of a constant and of a ramp) and the
step-by-step GyroOdometry on a simulated drive.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.estimation import (
    GyroOdometry,
    allan_deviation,
    gyro_odometry_from_log,
    gyro_odometry_step,
    integrate_gyro_heading,
)
from abcwc.params import default_params
from abcwc.sim import SimBase
from abcwc.types import Pose2D, Twist

# ------------------------------------------------------------------ gyro_odometry_step


def test_step_straight_ahead_moves_along_the_heading():
    pose = gyro_odometry_step(Pose2D(1.0, 2.0, 0.3), 0.02, 0.03, 0.0, 0.02)
    assert pose.x == pytest.approx(1.0 + 0.025 * math.cos(0.3), abs=1e-15)
    assert pose.y == pytest.approx(2.0 + 0.025 * math.sin(0.3), abs=1e-15)
    assert pose.theta == pytest.approx(0.3, abs=1e-15)  # unequal wheels do not turn it


def test_step_spin_on_the_spot_turns_by_rate_minus_bias_times_dt():
    pose = gyro_odometry_step(Pose2D(1.0, 2.0, 0.3), -0.01, 0.01, 0.53, 0.02, bias=0.03)
    assert (pose.x, pose.y) == (1.0, 2.0)
    assert pose.theta == pytest.approx(0.3 + 0.5 * 0.02, abs=1e-15)


def test_step_wraps_the_heading_across_pi():
    pose = gyro_odometry_step(Pose2D(0.0, 0.0, math.pi - 0.001), 0.0, 0.0, 0.1, 0.02)
    assert pose.theta == pytest.approx(-math.pi + 0.001, abs=1e-12)


def test_steps_on_a_circle_are_the_true_arc_scaled_by_arc_over_chord():
    # Constant v and w: each step's direction (the midpoint heading) is the chord's,
    # its length the arc's, so every point is the true one scaled about the start
    # by (phi/2) / sin(phi/2).
    v, w, dt, steps = 0.8, 0.6, 0.02, 400
    start = Pose2D(3.0, -1.0, 0.7)
    pose = start
    radius = v / w
    phi = w * dt
    for k in range(1, steps + 1):
        d = v * dt
        pose = gyro_odometry_step(pose, d - 0.1 * d, d + 0.1 * d, w, dt)
        angle = start.theta + k * phi
        true_x = start.x + radius * (math.sin(angle) - math.sin(start.theta))
        true_y = start.y - radius * (math.cos(angle) - math.cos(start.theta))
        scale = (phi / 2) / math.sin(phi / 2)
        assert pose.x - start.x == pytest.approx(scale * (true_x - start.x), abs=1e-12)
        assert pose.y - start.y == pytest.approx(scale * (true_y - start.y), abs=1e-12)
    assert pose.theta == pytest.approx(math.remainder(start.theta + steps * phi, 2 * math.pi))


@pytest.mark.parametrize("bad", [dict(dt=0.0), dict(dt=-0.02), dict(gyro_z=math.nan),
                                 dict(d_left=math.inf), dict(bias=math.nan)])
def test_step_refuses_bad_input(bad):
    args = dict(d_left=0.01, d_right=0.01, gyro_z=0.1, dt=0.02, bias=0.0) | bad
    with pytest.raises(ValueError, match=next(iter(bad))):
        gyro_odometry_step(Pose2D(), **args)


def test_gyro_odometry_class_equals_the_whole_log_version_on_a_drive():
    sim = SimBase(world="lab", seed=4, start="centre", people=False)
    log = sim.run(lambda f: Twist(0.6, 0.9 * math.sin(0.7 * f.t)), 12.0)
    bias = 0.004
    batch = gyro_odometry_from_log(log, bias, method="midpoint")
    odo = GyroOdometry(bias=bias, start=Pose2D(*log.pose[0]))
    for k in range(len(log)):
        pose = odo.update(log.t[k], *log.ticks[k], log.gyro_z[k])
    assert (pose.x, pose.y) == pytest.approx(tuple(batch[-1, :2]), abs=1e-9)
    assert pose.theta == pytest.approx(batch[-1, 2], abs=1e-9)


def test_gyro_odometry_survives_the_encoder_counter_wrapping():
    """Counts that wrap past the int32 top give the same path as counts that do not."""
    sim = SimBase(world="lab", seed=4, start="centre", people=False)
    log = sim.run(lambda f: Twist(0.6, 0.9 * math.sin(0.7 * f.t)), 6.0)
    near_top = 2**31 - 1 - int(log.ticks[len(log) // 2, 0])  # the left counter wraps midway
    wrapped = (log.ticks.astype(np.int64) + near_top + 2**31) % 2**32 - 2**31
    assert (np.diff(wrapped[:, 0]) < -(2**31)).any()
    plain, rolled = GyroOdometry(bias=0.004), GyroOdometry(bias=0.004)
    for k in range(len(log)):
        want = plain.update(log.t[k], *log.ticks[k], log.gyro_z[k])
        got = rolled.update(log.t[k], *wrapped[k], log.gyro_z[k])
    assert math.hypot(want.x, want.y) > 2.0
    assert (got.x, got.y, got.theta) == pytest.approx((want.x, want.y, want.theta), abs=1e-9)


def test_gyro_odometry_refuses_bad_settings_and_counts():
    with pytest.raises(ValueError, match=r"correction must be \(c_left, c_right\)"):
        GyroOdometry(correction=(1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="bias"):
        GyroOdometry(bias=math.nan)
    with pytest.raises(ValueError, match="start must be a Pose2D"):
        GyroOdometry(start=(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="ticks_right"):
        GyroOdometry().update(0.0, 0, math.nan, 0.0)
    with pytest.raises(ValueError, match="pose must be a Pose2D"):
        gyro_odometry_step((0.0, 0.0, 0.0), 0.01, 0.01, 0.1, 0.02)
    with pytest.raises(ValueError, match="theta0"):
        integrate_gyro_heading(np.arange(3.0), np.zeros(3), theta0=math.nan)


# ------------------------------------------------------------------ allan_deviation


def test_allan_deviation_of_white_noise_falls_as_one_over_root_tau():
    rng = np.random.default_rng(1)
    sigma, period = 0.003, 0.02
    taus, adev = allan_deviation(rng.normal(0.0, sigma, 200_000), period, [1, 10, 100])
    np.testing.assert_allclose(taus, [0.02, 0.2, 2.0])
    np.testing.assert_allclose(adev, sigma * np.sqrt(period / taus), rtol=0.05)


def test_allan_deviation_of_a_bias_random_walk_rises_as_root_tau_over_three():
    k_walk, period = 1e-3, 0.02
    sizes = np.array([50, 100, 200])
    ratios = []
    for seed in range(8):
        rng = np.random.default_rng(seed)
        bias = np.cumsum(rng.normal(0.0, k_walk * math.sqrt(period), 100_000))
        taus, adev = allan_deviation(bias, period, sizes)
        ratios.append(adev / (k_walk * np.sqrt(taus / 3)))
    np.testing.assert_allclose(np.sqrt(np.mean(np.square(ratios), axis=0)), 1.0, rtol=0.1)


def test_allan_deviation_of_a_constant_is_zero_and_of_a_ramp_is_r_tau_over_root_two():
    period = 0.02
    _, adev = allan_deviation(np.full(1000, 0.004), period, [1, 7, 40])
    np.testing.assert_allclose(adev, 0.0, atol=1e-15)
    slope = 2e-4  # rad/s per s
    rates = slope * period * np.arange(1000)
    taus, adev = allan_deviation(rates, period, [1, 7, 40])
    np.testing.assert_allclose(adev, slope * taus / math.sqrt(2), rtol=1e-9)


def test_allan_deviation_default_clusters_span_one_sample_to_a_tenth_of_the_record():
    rates = np.random.default_rng(0).normal(0.0, 0.003, 5000)
    taus, adev = allan_deviation(rates, 0.02)
    assert taus[0] == pytest.approx(0.02) and taus[-1] == pytest.approx(500 * 0.02)
    assert np.all(np.diff(taus) > 0) and np.all(adev > 0) and len(taus) >= 20


def test_allan_deviation_refuses_bad_input():
    good = np.zeros(100)
    with pytest.raises(ValueError, match="index 3"):
        allan_deviation(np.array([0.0, 0.1, 0.2, np.nan, 0.0]), 0.02)
    with pytest.raises(ValueError, match="at least 3"):
        allan_deviation([0.1, 0.2], 0.02)
    with pytest.raises(ValueError, match="period"):
        allan_deviation(good, 0.0)
    for sizes in ([0, 1], [50], [2.5], []):
        with pytest.raises(ValueError, match="cluster sizes"):
            allan_deviation(good, 0.02, sizes)


def test_simulated_gyro_standing_still_matches_its_noise_model():
    p = default_params()
    sim = SimBase(world="lab", seed=2, start="centre", people=False)
    log = sim.drive(Twist(0.0, 0.0), 120.0)
    taus, adev = allan_deviation(log.gyro_z, sim.period, [1, 5, 25])
    white = p.gyro.noise_std * np.sqrt(sim.period / taus)
    walk = p.gyro.bias_walk_std * np.sqrt(taus / 3)
    np.testing.assert_allclose(adev, np.hypot(white, walk), rtol=0.1)
