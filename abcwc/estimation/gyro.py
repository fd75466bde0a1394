"""Gyro + encoders: heading from the gyro, distance from the wheels (thesis 4.2.4).

The thesis replaces the encoders' heading change (eqn 7) by the integrated gyro rate::

    theta_imu = integral of g_z dt             (eqns 14-15)
    d_c = (d_r + d_l) / 2                      (eqn 6)
    x' = x + d_c cos(theta_imu)                (eqn 16)
    y' = y + d_c sin(theta_imu)

A wrong wheel base or unequal wheels then no longer bend the path; what is left in
heading is the gyro's bias. It is estimated as the mean rate while the chair stands
still (:func:`estimate_gyro_bias`) and subtracted; the remainder (the bias's slow
random walk and the white noise) makes heading drift as ``sqrt(t)`` rather than ``t``.

Timing convention of a :class:`abcwc.log.RunLog` (and of the simulator): the sample
at row ``k`` is the rate over the period that starts at ``t[k]``, while the counts at
row ``k`` are the travel over the period that ends there. So
``theta[k + 1] = theta[k] + (g_z[k] - bias) (t[k + 1] - t[k])``.
"""

from __future__ import annotations

import math

import numpy as np

from abcwc.estimation.odometry import (
    Method,
    _check_method,
    _log_start,
    log_wheel_travel,
    validate_log,
)
from abcwc.log import RunLog
from abcwc.params import ChairParams, default_params
from abcwc.types import Pose2D, SensorFrame, wrap_angle


def estimate_gyro_bias(gyro_samples_while_still: np.ndarray) -> float:
    """Gyro bias (rad/s): the mean of the rates read while the chair stands still.

    Its standard error is ``noise_std / sqrt(n)``: one second at 50 Hz with the
    simulated MPU9250's 0.003 rad/s noise gives 0.0004 rad/s, a tenth of the
    turn-on bias it removes.
    """
    samples = np.asarray(gyro_samples_while_still, dtype=float).ravel()
    if samples.size == 0:
        raise ValueError("estimate_gyro_bias needs at least one sample taken while still")
    bad = np.flatnonzero(~np.isfinite(samples))
    if bad.size:
        raise ValueError(f"gyro sample at index {bad[0]} is not finite ({samples[bad[0]]})")
    return float(samples.mean())


def integrate_gyro_heading(
    t: np.ndarray, gyro_z: np.ndarray, theta0: float = 0.0, bias: float = 0.0
) -> np.ndarray:
    """Heading (rad, wrapped) at every timestamp from gyro rates (eqn 14).

    ``theta[0] = theta0`` and ``theta[k + 1] = theta[k] + (g[k] - bias) dt[k]``.
    Refuses NaN samples and non-increasing timestamps.
    """
    t = np.asarray(t, dtype=float)
    gyro = np.asarray(gyro_z, dtype=float)
    if t.shape != gyro.shape or t.ndim != 1:
        raise ValueError(f"t and gyro_z must be 1-D and the same length, "
                         f"got {t.shape} and {gyro.shape}")
    bad = np.flatnonzero(~np.isfinite(gyro))
    if bad.size:
        raise ValueError(f"gyro_z has a missing (NaN) sample at index {bad[0]}")
    if not np.isfinite(t).all() or (np.diff(t) <= 0).any():
        raise ValueError("timestamps must be finite and strictly increasing")
    increments = (gyro[:-1] - bias) * np.diff(t)
    theta = theta0 + np.concatenate([[0.0], np.cumsum(increments)])
    return np.angle(np.exp(1j * theta))


def gyro_odometry_from_log(
    log: RunLog,
    bias: float = 0.0,
    params: ChairParams | None = None,
    method: Method = "midpoint",
    correction: tuple[float, float] = (1.0, 1.0),
    start: Pose2D | None = None,
    bits: int = 32,
) -> np.ndarray:
    """Poses ``(N, 3)`` with heading from the gyro and distance from the encoders.

    ``method`` chooses the heading the step's travel is pointed along: ``"euler"``
    the heading at the step's start, ``"midpoint"`` the mean of start and end
    (the thesis's A.11 listing uses the end), ``"exact"`` the mean heading and the
    arc's chord length.
    """
    _check_method(method)
    validate_log(log, need_gyro=True)
    start = _log_start(log, start)
    theta = np.unwrap(integrate_gyro_heading(log.t, log.gyro_z, start.theta, bias))
    travel = log_wheel_travel(log, params, correction, bits)
    d_c = travel.sum(axis=1) / 2.0
    phi = np.diff(theta)
    if method == "euler":
        heading, length = theta[:-1], d_c
    else:
        heading = theta[:-1] + phi / 2.0
        length = d_c * np.sinc(phi / (2.0 * np.pi)) if method == "exact" else d_c
    out = np.empty((len(theta), 3))
    out[:, 0] = start.x + np.concatenate([[0.0], np.cumsum(length * np.cos(heading))])
    out[:, 1] = start.y + np.concatenate([[0.0], np.cumsum(length * np.sin(heading))])
    out[:, 2] = np.angle(np.exp(1j * theta))
    return out


class GyroOdometry:
    """Step by step: gyro heading, encoder distance (midpoint heading per step).

    Feed it every frame (:meth:`update_frame`); the gyro sample of one frame turns
    the heading over the period up to the next.
    """

    def __init__(self, bias: float = 0.0, params: ChairParams | None = None,
                 correction: tuple[float, float] = (1.0, 1.0), start: Pose2D | None = None):
        self.params = params or default_params()
        self.bias = float(bias)
        self.correction = correction
        self.pose = start or Pose2D()
        self._last: tuple[int, int, float, float] | None = None  # counts, t, rate

    def update(self, t: float, ticks_left: int, ticks_right: int, gyro_z: float) -> Pose2D:
        """Feed one frame's time (s), cumulative counts and gyro rate (rad/s)."""
        if not math.isfinite(gyro_z):
            raise ValueError(f"gyro_z sample at t={t} s is not finite ({gyro_z})")
        if self._last is None:
            self._last = (int(ticks_left), int(ticks_right), float(t), float(gyro_z))
            return self.pose
        left0, right0, t0, rate = self._last
        if not t > t0:
            raise ValueError(f"timestamps must increase: {t0} s then {t} s")
        per_count = self.params.distance_per_count
        d_c = ((int(ticks_left) - left0) * per_count * self.correction[0]
               + (int(ticks_right) - right0) * per_count * self.correction[1]) / 2.0
        phi = (rate - self.bias) * (t - t0)
        heading = self.pose.theta + phi / 2.0
        self.pose = Pose2D(self.pose.x + d_c * math.cos(heading),
                           self.pose.y + d_c * math.sin(heading),
                           wrap_angle(self.pose.theta + phi))
        self._last = (int(ticks_left), int(ticks_right), float(t), float(gyro_z))
        return self.pose

    def update_frame(self, frame: SensorFrame) -> Pose2D:
        """:meth:`update` from a SensorFrame."""
        return self.update(frame.t, frame.ticks_left, frame.ticks_right, frame.gyro_z)
