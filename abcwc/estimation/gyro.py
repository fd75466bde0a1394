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

:func:`allan_deviation` tells the gyro's noise terms apart in a still recording:
white rate noise falls as ``N / sqrt(tau)`` (angle random walk ``N``), the bias's
random walk rises as ``K sqrt(tau / 3)`` (IEEE Std 952-1997, annex C).
"""

from __future__ import annotations

import math

import numpy as np

from abcwc import geometry
from abcwc.estimation.odometry import (
    Method,
    _check_correction,
    _check_method,
    _check_pose,
    _chord,
    _log_start,
    _whole_count,
    log_wheel_travel,
    validate_log,
)
from abcwc.log import RunLog
from abcwc.params import ChairParams, default_params
from abcwc.types import Pose2D, SensorFrame, require_finite


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
    Refuses NaN samples, a NaN ``theta0`` or ``bias`` and non-increasing timestamps.
    """
    theta0 = require_finite("theta0 (rad)", theta0)
    bias = require_finite("bias (rad/s)", bias)
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
    return geometry.wrap_angle(theta)


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
    start = _check_pose("start", _log_start(log, start))
    theta = np.unwrap(integrate_gyro_heading(log.t, log.gyro_z, start.theta, bias))
    travel = log_wheel_travel(log, params, correction, bits)  # None: the nominal chair
    dx, dy = _chord(travel.sum(axis=1) / 2.0, np.diff(theta), theta[:-1], method)
    out = np.empty((len(theta), 3))
    out[:, 0] = start.x + np.concatenate([[0.0], np.cumsum(dx)])
    out[:, 1] = start.y + np.concatenate([[0.0], np.cumsum(dy)])
    out[:, 2] = geometry.wrap_angle(theta)
    return out


def gyro_odometry_step(pose: Pose2D, d_left: float, d_right: float, gyro_z: float,
                       dt: float, bias: float = 0.0) -> Pose2D:
    """One step of eqns 14-16: turn by the gyro, move by the wheels' mean travel.

    ``d_left``, ``d_right`` (m) are the wheels' travel over the step, ``gyro_z``
    (rad/s) the rate sample of the step, ``dt`` (s) its length, ``bias`` (rad/s) the
    gyro's estimated bias::

        phi = (gyro_z - bias) dt              (eqn 14, one rectangle)
        d_c = (d_r + d_l) / 2                 (eqn 6)
        x' = x + d_c cos(theta + phi / 2)     (eqn 16, midpoint heading)
        y' = y + d_c sin(theta + phi / 2)
        theta' = theta + phi                  (wrapped to (-pi, pi])

    The wheels' own heading change ``(d_r - d_l) / b`` is not used at all. A pose or
    value that is not a finite number is refused (ValueError).
    """
    _check_pose("pose", pose)
    values = {"d_left": d_left, "d_right": d_right, "gyro_z": gyro_z, "dt": dt, "bias": bias}
    for name, value in values.items():
        if not math.isfinite(value):
            raise ValueError(f"{name} must be a finite number, got {value!r}")
    if not dt > 0:
        raise ValueError(f"dt must be > 0 s, got {dt!r}")
    phi = (gyro_z - bias) * dt
    d_c = (d_right + d_left) / 2.0
    heading = pose.theta + phi / 2.0
    return Pose2D(pose.x + d_c * math.cos(heading), pose.y + d_c * math.sin(heading),
                  geometry.wrap_angle(pose.theta + phi))


def allan_deviation(rates: np.ndarray, period: float,
                    cluster_sizes: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Overlapping Allan deviation of a still recording: ``(taus, adev)`` (s, rad/s).

    With ``theta`` the running integral of the rates (``theta[0] = 0``, ``n + 1``
    values) and ``tau = m period``, averaging over every ``k`` that fits::

        adev(tau)^2 = mean_k (theta[k + 2m] - 2 theta[k + m] + theta[k])^2 / (2 tau^2)

    (IEEE Std 952-1997, annex C). ``cluster_sizes`` are the ``m`` to use (default:
    about 10 per decade from 1 to ``n / 10``). White noise of ``s`` rad/s per sample
    gives ``s sqrt(period / tau)``; a bias random walk of ``K`` rad/s/sqrt(s) gives
    ``K sqrt(tau / 3)``; a constant bias gives 0.
    """
    values = np.asarray(rates, dtype=float).ravel()
    if not (math.isfinite(period) and period > 0):
        raise ValueError(f"period must be > 0 s, got {period!r}")
    if values.size < 3:
        raise ValueError(f"allan_deviation needs at least 3 samples, got {values.size}")
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise ValueError(f"rate sample at index {bad[0]} is not finite ({values[bad[0]]})")
    n = values.size
    if cluster_sizes is None:
        top = max(n // 10, 1)
        per_decade = int(10 * np.log10(top)) + 1
        cluster_sizes = np.unique(np.round(np.logspace(0, np.log10(top), per_decade)))
    sizes = np.asarray(cluster_sizes, dtype=float).ravel()
    m = np.round(sizes).astype(np.int64) if np.isfinite(sizes).all() else np.zeros(0, int)
    if m.size == 0 or (m != sizes).any() or (m < 1).any() or (2 * m >= n).any():
        raise ValueError(f"cluster sizes must be whole numbers from 1 to {(n - 1) // 2} "
                         f"for {n} samples, got {np.asarray(cluster_sizes)!r}")
    theta = np.concatenate([[0.0], np.cumsum(values)]) * period
    adev = np.empty(m.size)
    for i, size in enumerate(m):
        second = theta[2 * size:] - 2.0 * theta[size:-size] + theta[:-2 * size]
        adev[i] = math.sqrt(np.mean(second**2) / 2.0) / (size * period)
    return m * period, adev


class GyroOdometry:
    """Step by step: gyro heading, encoder distance (midpoint heading per step).

    Feed it every frame (:meth:`observe`); the gyro sample of one frame turns
    the heading over the period up to the next. Counts may wrap at ``bits`` width.
    ``bias`` (rad/s), ``correction`` (UMBmark's ``(c_left, c_right)``) and ``start``
    are checked here (ValueError).
    """

    def __init__(self, bias: float = 0.0, params: ChairParams | None = None,
                 correction: tuple[float, float] = (1.0, 1.0), start: Pose2D | None = None,
                 bits: int = 32):
        self.params = params or default_params()
        self.bias = require_finite("bias (rad/s)", bias)
        self.correction = _check_correction(correction)
        geometry.wrap_tick_delta(0, bits)  # refuses a counter width outside 2..64 bits now
        self.bits = bits
        self.pose = _check_pose("start", start or Pose2D())
        self._last: tuple[int, int, float, float] | None = None  # counts, t, rate

    def update(self, t: float, ticks_left: int, ticks_right: int, gyro_z: float) -> Pose2D:
        """Feed one frame's time (s), cumulative counts and gyro rate (rad/s)."""
        if not math.isfinite(gyro_z):
            raise ValueError(f"gyro_z sample at t={t} s is not finite ({gyro_z})")
        counts = (_whole_count("ticks_left", ticks_left), _whole_count("ticks_right", ticks_right))
        if self._last is None:
            self._last = (*counts, float(t), float(gyro_z))
            return self.pose
        left0, right0, t0, rate = self._last
        if not t > t0:
            raise ValueError(f"timestamps must increase: {t0} s then {t} s")
        travel = geometry.encoder_ticks_to_wheel_distance(
            np.array([(left0, right0), counts]), self.params.distance_per_count, self.bits)[0]
        d_left = float(travel[0]) * self.correction[0]
        d_right = float(travel[1]) * self.correction[1]
        self.pose = gyro_odometry_step(self.pose, d_left, d_right, rate, t - t0, self.bias)
        self._last = (*counts, float(t), float(gyro_z))
        return self.pose

    def observe(self, frame: SensorFrame) -> None:
        """:meth:`update` from a SensorFrame (the one estimator shape,
        :class:`~abcwc.estimation.estimator.PoseEstimator`: then read :attr:`pose`)."""
        self.update(frame.t, frame.ticks_left, frame.ticks_right, frame.gyro_z)
