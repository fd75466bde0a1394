"""Wheel odometry: encoder counts -> wheel travel -> pose (thesis 4.2.1, eqns 6-10).

Each wheel's travel over a period is its count increment times the distance per count,
``pi d_e / N_e`` (62 mm encoder wheel, 400 counts per turn: 0.487 mm), times an
optional per-wheel correction factor from UMBmark (:mod:`abcwc.estimation.umbmark`).
Then, with wheel base ``b``::

    d_c = (d_r + d_l) / 2                      (eqn 6)
    phi = (d_r - d_l) / b                      (eqn 7)
    theta' = theta + phi                       (eqn 8)
    x' = x + d_c cos(theta_used)               (eqn 9)
    y' = y + d_c sin(theta_used)               (eqn 10)

Three choices of ``theta_used`` (the ``method`` argument):

* ``"euler"``: the old heading ``theta``, as eqns 9-10 are written. Each step's chord
  is pointed along the heading at the start of the step, so on a curve every step
  errs by ``d_c phi / 2`` sideways, always to the same side: a first-order error that
  makes the estimated path spiral off on long curves and grows with the period.
* ``"midpoint"`` (second-order Runge-Kutta): ``theta + phi / 2``. The chord of a
  circular arc points exactly along the mean heading, so the direction error is gone;
  what remains is the length: the chord is shorter than the arc by a factor
  ``sin(phi/2) / (phi/2)``, an error of order ``d_c phi^2 / 24`` per step.
* ``"exact"``: the heading ``theta + phi / 2`` and the chord length
  ``d_c sin(phi/2) / (phi/2)``. Exact when the wheels turn at constant speeds over the
  step (the chair drives a circular arc); no integration error is left, only the
  sensors' own (count quantisation, slip, wrong wheel sizes or wheel base).

The same maths runs on a whole log at once (:func:`integrate_odometry`,
:func:`odometry_from_log`: ``np.cumsum`` of per-step increments) and step by step
(:func:`odometry_step`, :class:`Odometry`: what a controller calls every period).
:func:`wheel_travel` turns a log's cumulative counts into per-step travel.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal, TypedDict, Unpack

import numpy as np

from abcwc import geometry
from abcwc.log import RunLog
from abcwc.params import ChairParams, default_params
from abcwc.types import Pose2D, SensorFrame, require_finite

Method = Literal["euler", "midpoint", "exact"]
METHODS: tuple[str, ...] = ("euler", "midpoint", "exact")


def _check_method(method: str) -> None:
    if method not in METHODS:
        raise ValueError(f"odometry method {method!r} unknown; allowed: {', '.join(METHODS)}")


def _check_correction(correction: Sequence[float]) -> tuple[float, float]:
    """UMBmark's ``(c_left, c_right)`` as two floats; ValueError unless two finite factors > 0."""
    try:
        values = np.asarray(correction, dtype=float)
    except (TypeError, ValueError):
        values = np.zeros(0)
    if values.shape != (2,) or not (np.isfinite(values).all() and (values > 0).all()):
        raise ValueError(f"correction must be (c_left, c_right), two finite factors > 0, "
                         f"got {correction!r}")
    return float(values[0]), float(values[1])


def _check_pose(name: str, pose: Pose2D) -> Pose2D:
    """``pose`` itself; ValueError unless it is a Pose2D of finite numbers."""
    if not isinstance(pose, Pose2D) or not all(map(math.isfinite, pose.as_array())):
        raise ValueError(f"{name} must be a Pose2D of finite numbers (m, m, rad), got {pose!r}")
    return pose


def _whole_count(name: str, value: int) -> int:
    """An encoder count as an int; ValueError for NaN, infinity or a fraction."""
    number = require_finite(name, value)
    if number != round(number):
        raise ValueError(f"{name} must be a whole number of counts, got {value!r}")
    return int(value)


def encoder_ticks_to_wheel_distance(
    ticks: int | float | np.ndarray,
    params: ChairParams | None = None,
    correction: float | tuple[float, float] = 1.0,
) -> float | np.ndarray:
    """Wheel travel (m) from encoder count increments: ``ticks * pi d_e / N_e * c``.

    ``ticks`` is a number of counts, not necessarily whole (or an array of them; an
    ``(..., 2)`` array is read as left, right columns): a unit conversion, with no
    counter wrap. Cumulative counts from a log become travel through
    :func:`wheel_travel` (:func:`abcwc.geometry.encoder_ticks_to_wheel_distance`).
    ``correction`` is one factor for both wheels or a ``(c_left, c_right)`` pair from
    UMBmark, applied to the last axis.
    """
    p = params or default_params()
    per_count = p.distance_per_count
    if not isinstance(correction, (int, float, np.number)):
        factors = np.asarray(_check_correction(correction))
        arr = np.asarray(ticks, dtype=float)
        if arr.ndim == 0 or arr.shape[-1] != 2:
            raise ValueError("a (c_left, c_right) correction needs ticks shaped (..., 2), "
                             f"got shape {arr.shape}")
        return arr * per_count * factors
    if not (math.isfinite(correction) and correction > 0):
        raise ValueError(f"correction must be a finite factor > 0 or (c_left, c_right), "
                         f"got {correction!r}")
    if isinstance(ticks, np.ndarray):
        return ticks.astype(float) * per_count * float(correction)
    return float(ticks) * per_count * float(correction)


def wheel_travel(
    ticks: np.ndarray, distance_per_count: float | None = None, bits: int = 32
) -> np.ndarray:
    """Per-period wheel travel (m), ``(N - 1, 2)`` left/right, from cumulative counts.

    ``ticks`` is an ``(N, 2)`` array of cumulative counts (left, right), as in a log.
    Each row's travel is the difference from the row before, corrected for the
    counter wrapping at ``bits`` width, times ``distance_per_count`` (m; default the
    nominal ``pi d_e / N_e``, 4.2.1): :func:`abcwc.geometry.encoder_ticks_to_wheel_distance`.
    """
    counts = np.asarray(ticks)
    if counts.ndim != 2 or counts.shape[1] != 2:
        raise ValueError(f"ticks must have shape (N, 2) (left, right counts), got {counts.shape}")
    if counts.dtype.kind not in "iuf":
        raise ValueError(f"ticks must be integer counts, got dtype {counts.dtype}")
    if distance_per_count is None:
        distance_per_count = default_params().distance_per_count
    return geometry.encoder_ticks_to_wheel_distance(counts, distance_per_count, bits)


def pose_increments(
    d_left: np.ndarray, d_right: np.ndarray, wheel_base: float
) -> tuple[np.ndarray, np.ndarray]:
    """Per-step centre travel ``d_c`` (m, eqn 6) and heading change ``phi`` (rad, eqn 7)."""
    if not wheel_base > 0:
        raise ValueError(f"wheel_base must be > 0 m, got {wheel_base!r}")
    d_left = np.asarray(d_left, dtype=float)
    d_right = np.asarray(d_right, dtype=float)
    return (d_right + d_left) / 2.0, (d_right - d_left) / wheel_base


def _chord(d_c: np.ndarray, phi: np.ndarray, theta_old: np.ndarray,
           method: str) -> tuple[np.ndarray, np.ndarray]:
    """The step's displacement (dx, dy) in the world frame for each method."""
    if method == "euler":
        heading, length = theta_old, d_c
    else:
        heading = theta_old + phi / 2.0
        length = d_c * np.sinc(phi / (2.0 * np.pi)) if method == "exact" else d_c
    return length * np.cos(heading), length * np.sin(heading)


def odometry_step(
    pose: Pose2D, d_left: float, d_right: float, wheel_base: float,
    method: Method = "euler",
) -> Pose2D:
    """The pose after one period's wheel travels ``d_left``, ``d_right`` (m): eqns 6-10.

    ``method`` picks the heading the step's chord points along (see the module
    docstring); ``"euler"`` is eqns 9-10 as printed. Heading wrapped to (-pi, pi].
    A pose or travel that is not a finite number is refused (ValueError).
    """
    _check_method(method)
    _check_pose("pose", pose)
    d_c, phi = pose_increments(require_finite("d_left (m)", d_left),
                               require_finite("d_right (m)", d_right), wheel_base)
    dx, dy = _chord(d_c, phi, np.float64(pose.theta), method)
    return Pose2D(pose.x + float(dx), pose.y + float(dy),
                  geometry.wrap_angle(pose.theta + float(phi)))


def integrate_odometry(
    d_left: np.ndarray,
    d_right: np.ndarray,
    wheel_base: float,
    start: Pose2D | None = None,
    method: Method = "euler",
) -> np.ndarray:
    """Poses after each step from per-step wheel travels (m), vectorised.

    Returns an ``(N + 1, 3)`` array ``[x, y, theta]``: row 0 is ``start`` and row
    ``k`` the pose after step ``k``. Heading is wrapped to (-pi, pi]. ``d_left`` and
    ``d_right`` must be 1-D, of one length and finite (ValueError names the step).
    """
    _check_method(method)
    start = _check_pose("start", start or Pose2D())
    d_left, d_right = np.asarray(d_left, dtype=float), np.asarray(d_right, dtype=float)
    if d_left.ndim != 1 or d_left.shape != d_right.shape:
        raise ValueError(f"d_left and d_right must be 1-D and of one length, "
                         f"got shapes {d_left.shape} and {d_right.shape}")
    bad = np.flatnonzero(~(np.isfinite(d_left) & np.isfinite(d_right)))
    if bad.size:
        raise ValueError(f"wheel travel at step {bad[0]} is not finite "
                         f"({d_left[bad[0]]}, {d_right[bad[0]]} m)")
    d_c, phi = pose_increments(d_left, d_right, wheel_base)
    theta = start.theta + np.concatenate([[0.0], np.cumsum(phi)])
    dx, dy = _chord(d_c, phi, theta[:-1], method)
    out = np.empty((len(d_c) + 1, 3))
    out[:, 0] = start.x + np.concatenate([[0.0], np.cumsum(dx)])
    out[:, 1] = start.y + np.concatenate([[0.0], np.cumsum(dy)])
    out[:, 2] = geometry.wrap_angle(theta)
    return out


def validate_log(log: RunLog, need_gyro: bool = False) -> None:
    """Refuse a log that odometry cannot integrate, saying what is wrong and where.

    Timestamps must be finite and strictly increasing; ticks an ``(N, 2)`` array of
    finite counts; with ``need_gyro`` every gyro sample must be finite.
    """
    t = np.asarray(log.t, dtype=float)
    if t.ndim != 1 or len(t) < 1:
        raise ValueError(f"log.t must be a non-empty 1-D array, got shape {t.shape}")
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        raise ValueError(f"log.t has a missing (NaN/inf) timestamp at index {bad[0]}; "
                         "timestamps must be finite")
    steps = np.diff(t)
    bad = np.flatnonzero(steps <= 0)
    if bad.size:
        k = int(bad[0])
        raise ValueError(f"log.t is not strictly increasing at index {k + 1} "
                         f"({t[k]:.6g} s then {t[k + 1]:.6g} s)")
    ticks = np.asarray(log.ticks)
    if ticks.shape != (len(t), 2):
        raise ValueError(f"log.ticks must have shape ({len(t)}, 2), got {ticks.shape}")
    if ticks.dtype.kind == "f":
        bad = np.flatnonzero(~np.isfinite(ticks).all(axis=1))
        if bad.size:
            raise ValueError(f"log.ticks has a missing (NaN) count at index {bad[0]}")
    if need_gyro:
        gyro = np.asarray(log.gyro_z, dtype=float)
        if gyro.shape != t.shape:
            raise ValueError(f"log.gyro_z must have shape {t.shape}, got {gyro.shape}")
        bad = np.flatnonzero(~np.isfinite(gyro))
        if bad.size:
            raise ValueError(f"log.gyro_z has a missing (NaN) sample at index {bad[0]}; "
                             "drop or interpolate it before integrating")


def log_wheel_travel(
    log: RunLog,
    params: ChairParams | None = None,
    correction: tuple[float, float] = (1.0, 1.0),
    bits: int = 32,
) -> np.ndarray:
    """Per-step wheel travel (m), ``(N - 1, 2)`` left/right, from a log's counts.

    Each wheel's travel is multiplied by its factor of ``correction`` (UMBmark's
    ``(c_left, c_right)``).
    """
    validate_log(log)
    factors = np.asarray(_check_correction(correction))
    p = params or default_params()
    travel = wheel_travel(log.ticks, p.distance_per_count, bits)
    return travel * factors


def _log_start(log: RunLog, start: Pose2D | None) -> Pose2D:
    if start is not None:
        return start
    first = np.asarray(log.pose[0], dtype=float) if len(log.pose) else np.full(3, np.nan)
    return Pose2D(*map(float, first)) if np.isfinite(first).all() else Pose2D()


class OdometrySettings(TypedDict, total=False):
    """How :class:`Odometry` and :func:`odometry_from_log` integrate (see :class:`Odometry`)."""

    method: Method
    correction: tuple[float, float]
    wheel_base: float | None
    bits: int


def odometry_from_log(
    log: RunLog,
    params: ChairParams | None = None,
    start: Pose2D | None = None,
    **settings: Unpack[OdometrySettings],
) -> np.ndarray:
    """Odometric pose at every row of a log, ``(N, 3)``, aligned with ``log.pose``.

    Row ``k``'s counts hold the travel over the period ending at ``log.t[k]``, so the
    step from row ``k - 1`` to ``k`` uses their difference. Starts at ``start``, or
    at the log's first ground-truth pose when it has one, else at the origin.
    ``settings`` (``method``, ``correction``, ``wheel_base``, ``bits``) are those of
    :class:`Odometry`, with its defaults and checks: the same poses as feeding every
    row to an :class:`Odometry`, in one array expression.
    """
    odometry = Odometry(params, start=_log_start(log, start), **settings)
    travel = log_wheel_travel(log, odometry.params, odometry.correction, odometry.bits)
    return integrate_odometry(travel[:, 0], travel[:, 1], odometry.wheel_base, odometry.pose,
                              odometry.method)


class Odometry:
    """Step-by-step wheel odometry, for controllers that run every period.

    The first :meth:`update` only records the counts (the reference); each later
    one integrates the increment since the previous call. Counts may wrap at
    ``bits`` width. ``method`` is one of :data:`METHODS`; ``correction`` UMBmark's
    ``(c_left, c_right)`` and ``wheel_base`` (m, default the nominal one) its
    ``b_actual``; ``start`` the first pose. Each is checked here (ValueError).
    """

    def __init__(
        self,
        params: ChairParams | None = None,
        method: Method = "euler",
        correction: tuple[float, float] = (1.0, 1.0),
        wheel_base: float | None = None,
        start: Pose2D | None = None,
        bits: int = 32,
    ):
        _check_method(method)
        self.params = p = params or default_params()
        self.method = method
        self.correction = _check_correction(correction)
        self.wheel_base = p.wheel_base if wheel_base is None else float(wheel_base)
        if not (math.isfinite(self.wheel_base) and self.wheel_base > 0):
            raise ValueError(f"wheel_base must be a finite distance > 0 m, got {wheel_base!r}")
        geometry.wrap_tick_delta(0, bits)  # refuses a counter width outside 2..64 bits now
        self.bits = bits
        self.pose = _check_pose("start", start or Pose2D())
        self.distance = 0.0  # m, total centre travel (signed)
        self.last_step = (0.0, 0.0)  # (d_c m, phi rad) of the latest update
        self._last: tuple[int, int] | None = None

    def reset(self, pose: Pose2D | None = None) -> None:
        """Restart from ``pose`` (default the origin) at the next counts seen."""
        self.pose = _check_pose("pose", pose or Pose2D())
        self.distance = 0.0
        self.last_step = (0.0, 0.0)
        self._last = None

    def update(self, ticks_left: int, ticks_right: int) -> Pose2D:
        """Feed the cumulative counts; return the new pose estimate."""
        counts = (_whole_count("ticks_left", ticks_left), _whole_count("ticks_right", ticks_right))
        if self._last is None:
            self._last = counts
            return self.pose
        travel = geometry.encoder_ticks_to_wheel_distance(
            np.array([self._last, counts]), self.params.distance_per_count, self.bits)[0]
        self._last = counts
        d_left = float(travel[0]) * self.correction[0]
        d_right = float(travel[1]) * self.correction[1]
        self.pose = odometry_step(self.pose, d_left, d_right, self.wheel_base, self.method)
        d_c, phi = pose_increments(d_left, d_right, self.wheel_base)
        self.distance += float(d_c)
        self.last_step = (float(d_c), float(phi))
        return self.pose

    def observe(self, frame: SensorFrame) -> None:
        """:meth:`update` from a SensorFrame's counts (the one estimator shape,
        :class:`~abcwc.estimation.estimator.PoseEstimator`: then read :attr:`pose`)."""
        self.update(frame.ticks_left, frame.ticks_right)
