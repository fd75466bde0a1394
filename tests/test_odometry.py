"""Wheel odometry (thesis 4.2.1, eqns 6-10): units, integration methods, wrap, validation."""

import dataclasses
import math

import numpy as np
import pytest

from abcwc.estimation import (
    Odometry,
    encoder_ticks_to_wheel_distance,
    integrate_odometry,
    odometry_from_log,
    odometry_step,
    validate_log,
    wheel_travel,
    wrap_tick_delta,
)
from abcwc.estimation.gyro import gyro_odometry_from_log
from abcwc.params import default_params
from abcwc.sim.base import SimBase
from abcwc.sim.world import box_world
from abcwc.types import Pose2D, Twist

OPEN = box_world(120, 120, centred=True)


@pytest.fixture(scope="module")
def curvy_log():
    sim = SimBase(OPEN, errors="ideal", people=False)
    return sim.run(lambda f: Twist(0.8, 0.35 * math.sin(f.t / 3)), 64)


def test_distance_per_count_matches_wheel_turn():
    p = default_params()
    assert p.distance_per_count == pytest.approx(math.pi * 0.062 / 400)
    # one drive-wheel turn is ~1258 counts (4.2.1) and pi * 195 mm of travel
    turn = encoder_ticks_to_wheel_distance(p.counts_per_wheel_turn)
    assert turn == pytest.approx(math.pi * 0.195)
    both = encoder_ticks_to_wheel_distance(np.array([[100, 200]]), correction=(0.99, 1.01))
    assert both[0, 1] / both[0, 0] == pytest.approx(2 * 1.01 / 0.99)


def test_wrap_tick_delta_at_int32():
    top = 2**31 - 1
    assert wrap_tick_delta((-(2**31) + 4) - top) == 5
    assert wrap_tick_delta(top - (-(2**31) + 4)) == -5
    deltas = wrap_tick_delta(np.array([2**32 - 3, -(2**32) + 7, 12]))
    assert deltas.tolist() == [-3, 7, 12]
    assert wrap_tick_delta(3 - 65533, bits=16) == 6


def test_step_odometry_survives_counter_wrap():
    odo = Odometry(start=Pose2D())
    top = 2**31 - 1
    odo.update(top - 500, top - 500)
    pose = odo.update(-(2**31) + 500, -(2**31) + 500)  # 1001 counts each, wrapped
    assert pose.x == pytest.approx(1001 * default_params().distance_per_count)


def test_wheel_travel_differences_counts_and_unwraps_16_bit():
    per_count = default_params().distance_per_count
    ticks = np.array([[0, 0], [10, -4], [32760, 5], [-32766, 5]])
    travel = wheel_travel(ticks, bits=16)
    assert travel.shape == (3, 2)
    assert np.allclose(travel / per_count, [[10, -4], [32750, 9], [10, 0]])
    assert np.allclose(wheel_travel(ticks[:2], 0.001), [[0.010, -0.004]])
    with pytest.raises(ValueError, match="shape"):
        wheel_travel(np.arange(6))
    with pytest.raises(ValueError, match="whole"):
        wheel_travel(np.array([[0.0, 0.0], [0.5, np.nan]]))


def test_odometry_step_closed_forms():
    b = 0.44
    ahead = odometry_step(Pose2D(1.0, 2.0, math.pi / 6), 0.3, 0.3, b)
    assert (ahead.x, ahead.y) == pytest.approx((1.0 + 0.3 * math.cos(math.pi / 6),
                                                2.0 + 0.3 * math.sin(math.pi / 6)))
    spin = odometry_step(Pose2D(1.0, 2.0, 3.0), -0.11, 0.11, b)
    assert (spin.x, spin.y) == pytest.approx((1.0, 2.0))
    assert spin.theta == pytest.approx(3.0 + 0.5 - 2 * math.pi)  # wrapped past +pi
    # one exact step lands on the circle of radius R = b/2 (d_r + d_l)/(d_r - d_l)
    d_l, d_r = 0.4, 0.6
    radius, phi = b / 2 * (d_r + d_l) / (d_r - d_l), (d_r - d_l) / b
    arc = odometry_step(Pose2D(), d_l, d_r, b, method="exact")
    assert (arc.x, arc.y, arc.theta) == pytest.approx(
        (radius * math.sin(phi), radius * (1 - math.cos(phi)), phi))
    euler = odometry_step(Pose2D(), d_l, d_r, b)  # eqns 9-10: along the old heading
    assert (euler.x, euler.y) == pytest.approx((0.5, 0.0))


def test_methods_on_a_circle():
    """Constant wheel speeds drive an arc: 'exact' lands on it, midpoint nearly, Euler not."""
    b, radius, steps = 0.44, 2.0, 200
    arc = math.pi  # half a circle, counter-clockwise
    d_c = radius * arc / steps
    d_l = np.full(steps, d_c * (radius - b / 2) / radius)
    d_r = np.full(steps, d_c * (radius + b / 2) / radius)
    end = np.array([0.0, 2 * radius])
    errors = {m: np.hypot(*(integrate_odometry(d_l, d_r, b, method=m)[-1, :2] - end))
              for m in ("euler", "midpoint", "exact")}
    assert errors["exact"] < 1e-12
    assert errors["midpoint"] < 1e-3 < errors["euler"]
    final = integrate_odometry(d_l, d_r, b, method="exact")[-1, 2]
    assert abs(abs(final) - math.pi) < 1e-9


@pytest.mark.parametrize("method", ["euler", "midpoint", "exact"])
def test_vectorised_equals_step_by_step(curvy_log, method):
    log = curvy_log
    whole = odometry_from_log(log, method=method, correction=(0.99, 1.01), wheel_base=0.45)
    odo = Odometry(method=method, correction=(0.99, 1.01), wheel_base=0.45,
                   start=Pose2D(*log.pose[0]))
    steps = np.array([odo.update(*ticks).as_array() for ticks in log.ticks])
    assert np.allclose(steps, whole, atol=1e-9)


def test_ideal_chair_50_m_error_small(curvy_log):
    log = curvy_log
    distance = log.distance_travelled()
    assert distance > 50
    for method in ("euler", "midpoint", "exact"):
        est = odometry_from_log(log, method=method)
        error = np.hypot(*(est[-1, :2] - log.pose[-1, :2]))
        assert error / distance < 0.003, (method, error)


def test_gyro_odometry_runs_on_log(curvy_log):
    est = gyro_odometry_from_log(curvy_log, bias=0.0)
    assert est.shape == curvy_log.pose.shape and np.isfinite(est).all()


def test_log_validation_names_the_problem(curvy_log):
    log = curvy_log
    t = log.t.copy()
    t[10] = t[9]
    with pytest.raises(ValueError, match="not strictly increasing at index 10"):
        validate_log(dataclasses.replace(log, t=t))
    t = log.t.copy()
    t[7] = np.nan
    with pytest.raises(ValueError, match="missing .* timestamp at index 7"):
        odometry_from_log(dataclasses.replace(log, t=t))
    gyro = log.gyro_z.copy()
    gyro[42] = np.nan
    with pytest.raises(ValueError, match="gyro_z has a missing .* at index 42"):
        gyro_odometry_from_log(dataclasses.replace(log, gyro_z=gyro))
    ticks = log.ticks.astype(float)
    ticks[3, 1] = np.nan
    with pytest.raises(ValueError, match="index 3"):
        validate_log(dataclasses.replace(log, ticks=ticks))
    with pytest.raises(ValueError, match="method"):
        Odometry(method="rk4")


@pytest.mark.parametrize("correction", [(1, 1, 1), (1.0,), (0.99, math.nan), (1.0, -1.0),
                                        "ab", 1.0])
def test_a_correction_that_is_not_two_positive_factors_is_refused(curvy_log, correction):
    with pytest.raises(ValueError, match=r"correction must be \(c_left, c_right\)"):
        Odometry(correction=correction)
    with pytest.raises(ValueError, match=r"correction must be \(c_left, c_right\)"):
        odometry_from_log(curvy_log, correction=correction)
    with pytest.raises(ValueError, match=r"correction must be \(c_left, c_right\)"):
        gyro_odometry_from_log(curvy_log, correction=correction)


def test_step_and_whole_log_refuse_nan_travel_and_poses():
    with pytest.raises(ValueError, match="d_left .* finite"):
        odometry_step(Pose2D(), math.nan, 0.1, 0.44)
    with pytest.raises(ValueError, match="d_right .* finite"):
        odometry_step(Pose2D(), 0.1, math.inf, 0.44)
    with pytest.raises(ValueError, match="pose must be a Pose2D of finite numbers"):
        odometry_step((0.0, 0.1, 0.0), 0.1, 0.1, 0.44)
    d_left = np.array([0.1, 0.1, np.nan, 0.1])
    with pytest.raises(ValueError, match="at step 2 is not finite"):
        integrate_odometry(d_left, np.full(4, 0.1), 0.44)
    with pytest.raises(ValueError, match="one length"):
        integrate_odometry(np.full(3, 0.1), np.full(4, 0.1), 0.44)
    with pytest.raises(ValueError, match="start must be a Pose2D"):
        integrate_odometry(np.full(4, 0.1), np.full(4, 0.1), 0.44, start=(0.0, 0.0, 0.0))


def test_step_odometry_refuses_bad_counts_and_settings():
    odo = Odometry()
    for bad in (math.nan, 3.5, "7"):
        with pytest.raises(ValueError, match="ticks_left"):
            odo.update(bad, 0)
    assert odo.update(3.0, 0) == Pose2D()  # a whole float count is a count
    with pytest.raises(ValueError, match="bits"):
        Odometry(bits=70)
    with pytest.raises(ValueError, match="wheel_base"):
        Odometry(wheel_base=math.nan)
    with pytest.raises(ValueError, match="start must be a Pose2D"):
        Odometry(start=(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match="correction"):
        encoder_ticks_to_wheel_distance(np.array([[1, 2]]), correction=(1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match="correction"):
        encoder_ticks_to_wheel_distance(10, correction=-1.0)
