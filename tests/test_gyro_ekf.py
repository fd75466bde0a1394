"""Gyro fusion (thesis 4.2.4) and the EKF (4.3.5): bias, back ends agree, consistency."""

import math

import numpy as np
import pytest

from abcwc.behaviours import GoToLandmark
from abcwc.estimation import (
    ChairEkf,
    absolute_fixes,
    calibrate_distance_scale,
    estimate_gyro_bias,
    gyro_odometry_from_log,
    nees,
    nees_band,
    noise_from_models,
    odometry_from_log,
    run_ekf,
    run_umbmark,
    umbmark_corrections,
)
from abcwc.estimation.bench import bench_ekf
from abcwc.sim.base import SimBase
from abcwc.types import Pose2D, Twist
from tests.conftest import box_world

OPEN = box_world(20, 20, centred=True)
FIX_STD = (0.05, 0.05, 0.02)  # m, m, rad: an occasional landmark sighting
# Up and down the floor world's corridor (y 8..10 m), weaving a little
CORRIDOR = [(8, 8.8), (14, 9.3), (20, 8.7), (26, 9.3), (32, 8.8), (37, 9.0),
            (30, 9.2), (24, 8.7), (18, 9.3), (12, 8.8), (3, 9.0)] * 6


class _Truth:
    def update_frame(self, frame):
        return frame.pose


class CorridorRoute:
    """Waypoint following on ground truth (the estimators under test never see it)."""

    def __init__(self):
        self.index = 0
        self.leg = GoToLandmark(CORRIDOR[0], _Truth(), tolerance=0.5, max_speed=0.9)

    def __call__(self, frame):
        command = self.leg(frame)
        if self.leg.reached:
            self.index += 1
            self.leg = GoToLandmark(CORRIDOR[self.index], _Truth(), tolerance=0.5,
                                    max_speed=0.9)
            command = self.leg(frame)
        return command


@pytest.fixture(scope="module")
def calibration():
    """UMBmark (one square each way) plus a straight-line scale, on the worn chair."""

    def make(seed):
        return SimBase(OPEN, seed=seed, errors="worn", people=False)

    cw, ccw = run_umbmark(make, runs=1)
    result = umbmark_corrections(cw, ccw, 3.5, 0.44)
    scale = calibrate_distance_scale(make(99), correction=result.correction)
    return (result.c_left * scale, result.c_right * scale), result.wheel_base * scale


def _drive(seed, seconds):
    sim = SimBase("floor", seed=seed, errors="worn", people=False)
    bias = estimate_gyro_bias(sim.drive(Twist(0.0, 0.0), 2.0).gyro_z)
    log = sim.run(CorridorRoute(), seconds)
    assert log.collisions[-1] == 0
    return log, bias


def _filter(log, bias, calibration, seconds, seed):
    correction, wheel_base = calibration
    ekf = ChairEkf(Pose2D(*log.pose[0]), correction=correction, wheel_base=wheel_base,
                   gyro_bias=bias, noise=noise_from_models(bias_hold=seconds))
    fixes = absolute_fixes(log, 10.0, FIX_STD, seed=seed)
    return run_ekf(log, ekf, fixes, np.diag(np.square(FIX_STD)))


def test_gyro_bias_from_standing_still():
    sim = SimBase(OPEN, seed=3, errors="worn", people=False)
    still = sim.drive(Twist(0.0, 0.0), 2.0)
    assert estimate_gyro_bias(still.gyro_z) == pytest.approx(sim.gyro.bias, abs=0.001)
    with pytest.raises(ValueError, match="index 2"):
        estimate_gyro_bias(np.array([0.0, 0.1, np.nan]))
    with pytest.raises(ValueError, match="at least one"):
        estimate_gyro_bias(np.array([]))


def test_gyro_heading_beats_a_wrong_wheel_base():
    sim = SimBase(OPEN, seed=1, errors="worn", people=False)
    bias = estimate_gyro_bias(sim.drive(Twist(0.0, 0.0), 2.0).gyro_z)
    log = sim.run(lambda f: Twist(0.5, 0.4 * math.sin(f.t / 2)), 30.0)
    truth = np.unwrap(log.pose[:, 2])
    wheel = np.unwrap(odometry_from_log(log)[:, 2])
    gyro = np.unwrap(gyro_odometry_from_log(log, bias)[:, 2])
    assert np.abs(gyro - truth).max() < 0.5 * np.abs(wheel - truth).max()


def test_fast_ekf_equals_filterpy():
    rng = np.random.default_rng(1)
    fast = ChairEkf(Pose2D(1, 2, 3.0), backend="fast")
    slow = ChairEkf(Pose2D(1, 2, 3.0), backend="filterpy")
    for k in range(400):
        d_left, d_right = rng.normal(0.01, 0.005, 2)
        rate = rng.normal(0.1, 0.05)
        for ekf in (fast, slow):
            ekf.update_wheels(d_left, d_right, 0.02)
            ekf.predict(0.02)
            ekf.update_gyro(rate)
            if k % 100 == 50:  # across the +-pi seam: the residual must wrap
                ekf.update_pose(Pose2D(1 + k * 0.01, 2, -3.1), np.diag([0.01, 0.01, 0.001]))
    assert np.allclose(fast.filter.x, slow.filter.x, atol=1e-12)
    assert np.allclose(fast.filter.P, slow.filter.P, atol=1e-15)


def test_ekf_beats_odometry_and_is_consistent(calibration):
    # a five-minute drive: the EKF's final error at most half the raw odometry's
    log, bias = _drive(0, 300.0)
    states, _ = _filter(log, bias, calibration, 300.0, seed=0)
    raw = odometry_from_log(log)
    ekf_error = math.hypot(*(states[-1, :2] - log.pose[-1, :2]))
    odo_error = math.hypot(*(raw[-1, :2] - log.pose[-1, :2]))
    assert ekf_error <= 0.5 * odo_error, (ekf_error, odo_error)
    # NEES over seeded runs (10 x 60 s here; 50 x 300 s by hand, see the docs)
    runs, seconds = 10, 60.0
    values = []
    for seed in range(runs):
        log, bias = _drive(seed, seconds)
        states, covs = _filter(log, bias, calibration, seconds, seed)
        values.append(nees(log.pose, states, covs))
    average = np.mean(values, axis=0)  # over runs, at every time step
    low, high = nees_band(runs, dof=3)
    assert low < average.mean() < high, (average.mean(), low, high)


def test_bench_ekf_reports_cycles_per_second():
    result = bench_ekf(cycles=200, repeats=1)
    assert set(result) == {"ekf_fast_cycles_per_s", "ekf_filterpy_cycles_per_s"}
    assert all(value > 0 for value in result.values())
