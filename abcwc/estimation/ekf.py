"""An extended Kalman filter for the chair (thesis 4.3.5) with a gyro-bias state.

The thesis fuses wheel odometry and the IMU with robot_localization's EKF on the state
``[x, y, theta, v, omega]``. We add the gyro's bias, so the state is six numbers::

    s = [x, y, theta, v, omega, b]        (m, m, rad, m/s, rad/s, rad/s)

**Motion model** over a period ``dt`` (a unicycle, eqns 9-10 with the velocities held
over the period; the bias is a random walk)::

    x' = x + v dt cos(theta)        v'     = v + a dt
    y' = y + v dt sin(theta)        omega' = omega + alpha dt
    theta' = theta + omega dt       b'     = b + n_b

with white accelerations ``a``, ``alpha`` and a bias step ``n_b ~ N(0, q_b^2 dt)``.
Its Jacobian ``F = df/ds`` (:func:`motion_jacobian`) is the identity plus
``dx/dtheta = -v dt sin(theta)``, ``dx/dv = dt cos(theta)``, ``dy/dtheta = v dt cos(theta)``,
``dy/dv = dt sin(theta)`` and ``dtheta/domega = dt``. ``Q = diag(0, 0, 0, (a dt)^2,
(alpha dt)^2, q_b^2 dt)``, so the thesis's ``G Q G^T`` is our ``Q`` with ``G = I``.

**Predict and update** (Thrun, Burgard and Fox, *Probabilistic Robotics*, 2005, table
3.3; thesis 4.3.5)::

    s = f(s)                    P = F P F^T + Q
    y = z - H s                 S = H P H^T + R          K = P H^T S^-1
    s = s + K y                 P = P - K S K^T

(the thesis's ``K = P H^T S - 1`` means ``S^-1``). filterpy writes the covariance step
in Joseph form, ``(I - K H) P (I - K H)^T + K R K^T``: the same for this K, and safer
when K is not the optimal gain. Three measurements, all linear in the state:

* the wheels, ``z = [d_c / dt, phi / dt]`` (eqns 6-7 over the period): ``H`` picks v, omega;
* the gyro, ``z = g_z = omega + b``: ``H = [0, 0, 0, 0, 1, 1]``;
* an absolute fix, ``z = [x, y, theta]`` (a landmark or tag sighting), with the heading
  residual wrapped to (-pi, pi].

The wheels and the gyro both see omega; their difference is what makes the bias
observable, and absolute fixes pin the heading the bias would otherwise bend.

Order of one cycle on a log row ``k`` (see :mod:`abcwc.estimation.gyro` for the
timing): update with row k's wheel measurement (the period that ends at ``t_k``),
predict over that period, then update with row k's gyro sample (the period that
starts at ``t_k``) and any fix taken at ``t_k``.

**Noise from the models, not guessed** (:func:`noise_from_models`):

* wheels: three errors of different kinds, each made white over the filter's horizon
  ``T`` (the time between absolute fixes, ``N = T / dt`` periods), so that its sum over
  ``N`` periods, which is what moves the pose, has the right size:

  - count quantisation: ``d / sqrt(6)`` per wheel and period for a distance per count
    ``d`` (each increment is the difference of two floors of a uniformly spread
    remainder: variance ``2 / 12`` counts squared). The increments' errors telescope:
    over ``N`` periods they add up to one such difference, not ``sqrt(N)`` of them, so
    the per-period figure is divided by ``sqrt(N)``;
  - the systematic error UMBmark leaves, ``r = E_max,syst / (4 L)`` of a corrected
    square: the same sign in every period, so over ``N`` periods it grows as ``N r``,
    not ``sqrt(N) r``: the per-period figure is ``r sqrt(N)``;
  - the tyres' random slip, independent from period to period: white as it is;
* gyro: the sensor model's white noise per sample (``noise_std``) and its bias walk
  ``q_b = bias_walk_std`` (rad/s per sqrt(s)); the simulator's gyro
  (:class:`abcwc.sim.sensors.Gyro`, ``data/chair.toml``) is exactly this model
  (IEEE Std 952-1997's rate white noise plus rate random walk);
* the bias starts at the standing-still estimate with that estimate's variance
  (:func:`gyro_bias_prior`); without one, at 0 with the turn-on spread ``bias_std``.

Two back ends with the same equations: :class:`FilterpyEkf` wraps
``filterpy.kalman.ExtendedKalmanFilter`` (filterpy >= 2.0; Joseph form) and
:class:`FastEkf` runs :func:`kalman_update` in NumPy without filterpy's bookkeeping
(copies of every prior and posterior, column vectors, a general inverse): about twice
as fast, and equal to 1e-14 over a five-minute drive. Consistency is checked with the NEES
(:func:`nees`, :func:`nees_band`; Bar-Shalom, Li and Kirubarajan, *Estimation with
Applications to Tracking and Navigation*, 2001, ch. 5.4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Protocol

import numpy as np
from scipy.stats import chi2

from abcwc import geometry
from abcwc.estimation.gyro import estimate_gyro_bias
from abcwc.estimation.odometry import (
    _check_correction,
    _check_pose,
    log_wheel_travel,
    validate_log,
)
from abcwc.estimation.range_bearing import range_bearing
from abcwc.log import RunLog
from abcwc.params import ChairParams, default_params
from abcwc.types import Pose2D, SensorFrame

DIM = 6
X, Y, THETA, V, OMEGA, BIAS = range(DIM)
POSE = (X, Y, THETA)  # the components an absolute fix measures, and the NEES looks at
STATE_NAMES = ("x", "y", "theta", "v", "omega", "b")


def _rows(*rows: tuple[int, ...]) -> np.ndarray:
    """A read-only measurement matrix whose row i has ones at the indices ``rows[i]``."""
    h = np.zeros((len(rows), DIM))
    for i, idx in enumerate(rows):
        h[i, list(idx)] = 1.0
    h.flags.writeable = False
    return h


H_WHEEL = _rows((V,), (OMEGA,))  # z = [v, omega]
H_GYRO = _rows((OMEGA, BIAS))  # z = omega + b
H_POSE = _rows((X,), (Y,), (THETA,))  # z = [x, y, theta]
_EYE = np.eye(DIM)


def motion(s: np.ndarray, dt: float) -> np.ndarray:
    """The unicycle motion model ``f(s)`` over ``dt`` seconds (the bias is held)."""
    x, y, theta, v, w, b = s
    return np.array([x + v * dt * math.cos(theta), y + v * dt * math.sin(theta),
                     theta + w * dt, v, w, b])


def motion_jacobian(s: np.ndarray, dt: float) -> np.ndarray:
    """``F = df/ds`` at ``s`` (6 x 6)."""
    theta, v = s[THETA], s[V]
    c, sn = math.cos(theta), math.sin(theta)
    f = np.eye(DIM)
    f[X, THETA], f[X, V] = -v * dt * sn, dt * c
    f[Y, THETA], f[Y, V] = v * dt * c, dt * sn
    f[THETA, OMEGA] = dt
    return f


def kalman_update(x: np.ndarray, p: np.ndarray, z: np.ndarray, h: np.ndarray,
                  r: np.ndarray, angle: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """One Kalman update of state ``x`` (n,) and covariance ``p`` (n, n); returns both.

    ``z`` (m,) is the measurement, ``h`` (m, n) its matrix (the Jacobian of a nonlinear
    ``h(s)``; ours are linear), ``r`` (m, m) its noise covariance; ``angle`` is the
    position in ``z`` of a heading, whose residual is wrapped to (-pi, pi]. The
    covariance update is the thesis's ``P - K S K^T``, computed as ``P - K (P H^T)^T``
    and symmetrised.
    """
    y = z - h @ x
    if angle is not None:
        y[angle] = geometry.wrap_angle(float(y[angle]))
    pht = p @ h.T
    s = h @ pht + r
    k = pht @ _inverse(s)
    p = p - k @ pht.T
    return x + k @ y, (p + p.T) / 2


def _inverse(s: np.ndarray) -> np.ndarray:
    """Inverse of a small symmetric positive-definite matrix (closed form to 2 x 2)."""
    if s.shape[0] == 1:
        return 1.0 / s
    if s.shape[0] == 2:
        a, b, c, d = s[0, 0], s[0, 1], s[1, 0], s[1, 1]
        return np.array([[d, -b], [-c, a]]) / (a * d - b * c)
    return np.linalg.inv(s)


@dataclass(frozen=True)
class EkfNoise:
    """Standard deviations (SI units) of the process and the measurements."""

    accel: float = 0.5  # m/s^2, white linear acceleration
    ang_accel: float = 1.0  # rad/s^2, white angular acceleration
    wheel_v: float = 0.0003  # m/s, count quantisation, white over a 10 s horizon
    wheel_w: float = 0.0014  # rad/s
    wheel_rel: float = 0.045  # relative: slip + residual systematic error (10 s horizon)
    gyro: float = 0.003  # rad/s, white noise per sample
    bias_walk: float = 0.0001  # rad/s per sqrt(s), the bias's random walk

    def __post_init__(self) -> None:
        for name in self.__dataclass_fields__:
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ValueError(f"EkfNoise.{name} must be a finite number >= 0, got {value!r}")

    def process(self, dt: float, bias_walk: bool = True) -> np.ndarray:
        """Q for one period (cached, read-only); ``bias_walk=False`` holds the bias still."""
        return _process(self.accel, self.ang_accel, self.bias_walk if bias_walk else 0.0, dt)

    def wheel(self, v: float, w: float, wheel_base: float) -> np.ndarray:
        """R for a wheel measurement of speed v (m/s) and turn rate w (rad/s)."""
        rel = self.wheel_rel
        wheel_speed = abs(v) + abs(w) * wheel_base / 2
        return np.array([[self.wheel_v ** 2 + (rel * v) ** 2, 0.0],
                         [0.0, self.wheel_w ** 2 + (2 * rel * wheel_speed / wheel_base) ** 2]])


@lru_cache(maxsize=64)
def _process(accel: float, ang_accel: float, bias_walk: float, dt: float) -> np.ndarray:
    q = np.zeros((DIM, DIM))
    q[V, V] = (accel * dt) ** 2
    q[OMEGA, OMEGA] = (ang_accel * dt) ** 2
    q[BIAS, BIAS] = bias_walk ** 2 * dt
    q.flags.writeable = False
    return q


def noise_from_models(params: ChairParams | None = None, slip_std: float = 0.003,
                      residual_rel: float = 0.002, horizon: float = 10.0) -> EkfNoise:
    """Noise from the sensor models (see the module docstring for the derivation).

    ``slip_std`` is the per-wheel per-period relative slip (the simulated worn chair's,
    :meth:`abcwc.sim.motor.ChairErrors.worn`), ``residual_rel`` the relative odometry
    error UMBmark leaves (``E_max,syst / (4 L)`` of a corrected square) and ``horizon``
    (s) the time over which the filter leans on the wheels alone: the interval between
    absolute fixes. Quantisation (which telescopes) and the residual (which keeps its
    sign) are made white over that horizon. The gyro's white noise and bias walk come
    from ``params.gyro``.
    """
    if not (slip_std >= 0 and residual_rel >= 0 and horizon > 0):
        raise ValueError(f"slip_std and residual_rel must be >= 0 and horizon > 0 s, "
                         f"got {slip_std!r}, {residual_rel!r}, {horizon!r}")
    p = params or default_params()
    dt = p.control_period
    periods = max(horizon / dt, 1.0)
    per_wheel = p.distance_per_count / math.sqrt(6) / math.sqrt(periods)
    return EkfNoise(
        wheel_v=per_wheel / math.sqrt(2) / dt,
        wheel_w=per_wheel * math.sqrt(2) / p.wheel_base / dt,
        wheel_rel=math.hypot(slip_std, residual_rel * math.sqrt(periods)),
        gyro=p.gyro.noise_std,
        bias_walk=p.gyro.bias_walk_std,
    )


def gyro_bias_prior(gyro_samples_while_still: np.ndarray,
                    params: ChairParams | None = None) -> tuple[float, float]:
    """The gyro bias (rad/s) from standing still, and its standard deviation (rad/s).

    The bias is the samples' mean (:func:`estimate_gyro_bias`). Its error has the white
    noise's ``noise_std^2 / n`` and, because the bias walks while the samples are taken,
    ``bias_walk_std^2 T / 3`` over a window of ``T = n dt`` seconds (the variance of a
    random walk's end about its mean over the window).
    """
    p = params or default_params()
    bias = estimate_gyro_bias(gyro_samples_while_still)
    n = np.asarray(gyro_samples_while_still).size
    window = n * p.control_period
    std = math.hypot(p.gyro.noise_std / math.sqrt(n), p.gyro.bias_walk_std * math.sqrt(window / 3))
    return bias, std


def _standard_deviations(name: str, values: tuple[float, ...], size: int) -> np.ndarray:
    """``values`` as a float array of ``size`` standard deviations; ValueError unless each
    is a finite number >= 0 (a negative one would pass unnoticed once squared)."""
    try:
        stds = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        stds = np.zeros(0)
    if stds.shape != (size,) or not (np.isfinite(stds).all() and (stds >= 0).all()):
        raise ValueError(f"{name} must be {size} finite standard deviations >= 0, "
                         f"got {values!r}")
    return stds


# --------------------------------------------------------------------- back ends
class FastEkf:
    """The EKF in plain NumPy: :func:`motion`, :func:`motion_jacobian` (inlined, on a
    reused F) and :func:`kalman_update`, nothing more."""

    def __init__(self, x0: np.ndarray, p0: np.ndarray):
        self.x = np.array(x0, dtype=float).reshape(DIM)
        self.P = np.array(p0, dtype=float).reshape(DIM, DIM)
        self._f = np.eye(DIM)

    def predict(self, dt: float, q: np.ndarray) -> None:
        """``x = f(x)``, ``P = F P F^T + Q``."""
        x, y, theta, v, w, b = self.x  # motion() and motion_jacobian(), inlined
        c, s = math.cos(theta), math.sin(theta)
        f = self._f
        f[X, THETA], f[X, V] = -v * dt * s, dt * c
        f[Y, THETA], f[Y, V] = v * dt * c, dt * s
        f[THETA, OMEGA] = dt
        self.x = np.array([x + v * dt * c, y + v * dt * s, theta + w * dt, v, w, b])
        self.P = f @ self.P @ f.T + q

    def update(self, z: np.ndarray, h: np.ndarray, r: np.ndarray,
               angle: int | None = None) -> None:
        """Update with measurement ``z`` of matrix ``h`` and noise ``r`` (see
        :func:`kalman_update`)."""
        self.x, self.P = kalman_update(self.x, self.P, z, h, r, angle)


class FilterpyEkf:
    """The same filter on ``filterpy.kalman.ExtendedKalmanFilter``."""

    def __init__(self, x0: np.ndarray, p0: np.ndarray):
        from filterpy.kalman import ExtendedKalmanFilter

        self._kf = ExtendedKalmanFilter(dim_x=DIM, dim_z=3)
        self._kf.x = np.array(x0, dtype=float).reshape(DIM, 1)
        self._kf.P = np.array(p0, dtype=float)
        self._dt = 0.0
        self._kf.predict_x = lambda u=0: self._predict_x()

    def _predict_x(self) -> None:
        self._kf.x = motion(self._kf.x[:, 0], self._dt).reshape(DIM, 1)

    @property
    def x(self) -> np.ndarray:
        return self._kf.x[:, 0]

    @property
    def P(self) -> np.ndarray:  # noqa: N802 (the usual name)
        return self._kf.P

    def predict(self, dt: float, q: np.ndarray) -> None:
        self._dt = dt
        self._kf.F = motion_jacobian(self._kf.x[:, 0], dt)
        self._kf.Q = q
        self._kf.predict()

    def update(self, z: np.ndarray, h: np.ndarray, r: np.ndarray,
               angle: int | None = None) -> None:
        def residual(a: np.ndarray, b: np.ndarray) -> np.ndarray:
            y = a - b
            if angle is not None:
                y[angle] = geometry.wrap_angle(float(y[angle, 0]))
            return y

        self._kf.update(np.asarray(z, dtype=float).reshape(-1, 1), lambda s: h,
                        lambda s: h @ s, R=r, residual=residual)


# --------------------------------------------------------------------- the chair's filter
class ChairEkf:
    """Wheel odometry + gyro (with its bias) + occasional absolute fixes.

    ``start_std`` (m, m, rad) is the start pose's uncertainty, three finite numbers
    ``>= 0``. ``correction`` and ``wheel_base`` are UMBmark's; ``gyro_bias`` and
    ``gyro_bias_std`` (rad/s) the bias's starting estimate and its uncertainty
    (:func:`gyro_bias_prior`; ``None``: the gyro model's turn-on spread).
    ``estimate_bias=False`` holds the bias at ``gyro_bias`` for good (no walk, no
    uncertainty): the filter without a bias state, for comparison.
    """

    def __init__(self, start: Pose2D, params: ChairParams | None = None,
                 noise: EkfNoise | None = None, start_std: tuple[float, float, float] = (
                     0.01, 0.01, 0.005), backend: str = "fast",
                 correction: tuple[float, float] = (1.0, 1.0),
                 wheel_base: float | None = None, gyro_bias: float = 0.0,
                 gyro_bias_std: float | None = None, estimate_bias: bool = True):
        self.params = p = params or default_params()
        self.noise = noise or noise_from_models(p)
        self.correction = _check_correction(correction)
        self.wheel_base = p.wheel_base if wheel_base is None else float(wheel_base)
        if not (math.isfinite(self.wheel_base) and self.wheel_base > 0):
            raise ValueError(f"wheel_base must be a finite distance > 0 m, got {wheel_base!r}")
        start_std = _standard_deviations("start_std (m, m, rad)", start_std, 3)
        _check_pose("start", start)
        self.estimate_bias = bool(estimate_bias)
        bias_std = p.gyro.bias_std if gyro_bias_std is None else float(gyro_bias_std)
        if not (math.isfinite(gyro_bias) and math.isfinite(bias_std) and bias_std >= 0):
            raise ValueError(f"gyro_bias must be finite and gyro_bias_std >= 0, "
                             f"got {gyro_bias!r}, {gyro_bias_std!r}")
        x0 = np.array([start.x, start.y, start.theta, 0.0, 0.0, gyro_bias])
        p0 = np.diag([start_std[0] ** 2, start_std[1] ** 2, start_std[2] ** 2, 1e-4, 1e-4,
                      bias_std ** 2 if self.estimate_bias else 0.0])
        if backend == "fast":
            self.filter: FastEkf | FilterpyEkf = FastEkf(x0, p0)
        elif backend == "filterpy":
            self.filter = FilterpyEkf(x0, p0)
        else:
            raise ValueError(f"backend must be 'fast' or 'filterpy', got {backend!r}")
        self._r_gyro = np.array([[self.noise.gyro ** 2]])

    @property
    def pose(self) -> Pose2D:
        """The current pose estimate (heading wrapped)."""
        x = self.filter.x
        return Pose2D(float(x[X]), float(x[Y]), geometry.wrap_angle(float(x[THETA])))

    @property
    def bias(self) -> float:
        """The current gyro-bias estimate (rad/s)."""
        return float(self.filter.x[BIAS])

    def predict(self, dt: float) -> None:
        """Propagate over ``dt`` seconds."""
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"dt must be a finite period > 0 s, got {dt!r}")
        self.filter.predict(dt, self.noise.process(dt, self.estimate_bias))

    def update_wheels(self, d_left: float, d_right: float, dt: float) -> None:
        """Update with one period's wheel travel (m, already corrected) over ``dt`` (s)."""
        if not (math.isfinite(d_left) and math.isfinite(d_right) and math.isfinite(dt)
                and dt > 0):
            raise ValueError(f"wheel travel must be finite and dt > 0 s, got d_left={d_left!r}, "
                             f"d_right={d_right!r}, dt={dt!r}")
        v = (d_right + d_left) / 2 / dt
        w = (d_right - d_left) / self.wheel_base / dt
        self.filter.update(np.array([v, w]), H_WHEEL, self.noise.wheel(v, w, self.wheel_base))

    def update_gyro(self, gyro_z: float) -> None:
        """Update with one gyro sample (rad/s, bias included: ``z = omega + b``)."""
        if not math.isfinite(gyro_z):
            raise ValueError(f"gyro_z must be a finite rate (rad/s), got {gyro_z!r}")
        self.filter.update(np.array([gyro_z]), H_GYRO, self._r_gyro)

    def step(self, d_left: float, d_right: float, dt: float, gyro_z: float) -> None:
        """One control period: the wheels' travel (m, corrected) over ``dt`` (s), the
        prediction over it, then the gyro sample (rad/s) at its end. The one feed of
        the wheels and the gyro, over a log (:func:`run_ekf`) or frame by frame
        (:class:`EkfEstimator`)."""
        self.update_wheels(d_left, d_right, dt)
        self.predict(dt)
        self.update_gyro(gyro_z)

    def update_pose(self, pose: Pose2D, cov: np.ndarray) -> None:
        """Update with an absolute fix ``pose`` of covariance ``cov`` (3 x 3)."""
        _check_pose("pose", pose)
        self.filter.update(np.array([pose.x, pose.y, pose.theta]), H_POSE, np.asarray(cov),
                           angle=2)

    def reset_pose(self, pose: Pose2D, cov: np.ndarray) -> None:
        """Put the pose at ``pose`` with covariance ``cov`` (3 x 3), its correlations
        with the other states dropped; velocity and gyro bias keep their estimates. Not a
        fusion: the pose is known afresh (a relocalisation, or a map whose frame the
        filter's own map had drifted from)."""
        _check_pose("pose", pose)
        cov = np.asarray(cov, dtype=float)
        if cov.shape != (3, 3) or not np.isfinite(cov).all():
            raise ValueError(f"cov must be a finite 3 x 3 covariance, got shape {cov.shape}")
        x, full = self.filter.x, self.filter.P
        x[:3] = (pose.x, pose.y, pose.theta)
        full[:3, 3:] = 0.0
        full[3:, :3] = 0.0
        full[:3, :3] = cov

    def update_landmark(self, measured: tuple[float, float], landmark: tuple[float, float],
                        mount: tuple[float, float, float], cov: np.ndarray) -> None:
        """Update with a sighting of a landmark whose place is known: ``measured`` =
        (range m, bearing rad) from a sensor at ``mount`` (base_link) to ``landmark``
        (x, y, map), of covariance ``cov`` (2 x 2). The model and its Jacobian are
        :func:`~abcwc.estimation.range_bearing.range_bearing`'s; the update is the EKF's
        with the measurement linearised about the estimate (the linear update given
        ``H x + (z - h(x))``, the bearing's difference wrapped)."""
        z = np.asarray(measured, dtype=float)
        if z.shape != (2,) or not np.isfinite(z).all() or z[0] <= 0:
            raise ValueError(f"measured must be (range > 0 m, bearing rad), got {measured!r}")
        expected, h = range_bearing(self.filter.x, landmark, mount)
        innovation = np.array([z[0] - expected[0],
                               geometry.wrap_angle(float(z[1] - expected[1]))])
        self.filter.update(h @ self.filter.x + innovation, h, np.asarray(cov, dtype=float),
                           angle=1)


class EkfEstimator:
    """A :class:`ChairEkf` fed frame by frame: the one estimator shape
    (:class:`~abcwc.estimation.estimator.PoseEstimator`, ``observe(frame)`` then
    :attr:`pose`). The first frame gives the gyro sample only; each later one the
    wheels' travel since the one before (counts wrapped, times the filter's UMBmark
    correction), the prediction and its gyro sample (:meth:`ChairEkf.step`)."""

    def __init__(self, ekf: ChairEkf):
        self.ekf = ekf
        self._per_count = ekf.params.distance_per_count * np.asarray(ekf.correction, dtype=float)
        self._ticks: tuple[int, int] | None = None
        self._t: float | None = None

    @property
    def pose(self) -> Pose2D:
        """The filter's pose estimate."""
        return self.ekf.pose

    def observe(self, frame: SensorFrame) -> None:
        """Dead-reckon over the period that ended at ``frame``."""
        ticks = (frame.ticks_left, frame.ticks_right)
        if self._t is None:
            self.ekf.update_gyro(frame.gyro_z)
        else:
            dt = frame.t - self._t
            if dt <= 0:
                raise ValueError(f"frames must come in time order: {frame.t} s after "
                                 f"{self._t} s")
            counts = np.array([geometry.wrap_tick_delta(ticks[0] - self._ticks[0]),  # type: ignore[index]
                               geometry.wrap_tick_delta(ticks[1] - self._ticks[1])])  # type: ignore[index]
            travel = counts * self._per_count
            self.ekf.step(float(travel[0]), float(travel[1]), dt, frame.gyro_z)
        self._ticks, self._t = ticks, frame.t


class Sighting(Protocol):
    """A landmark read by a sensor: which one, its range (m) and bearing (rad), and the
    2 x 2 covariance of the two (:class:`abcwc.perception.markers.MarkerSighting`)."""

    marker_id: int
    range: float
    bearing: float

    @property
    def covariance(self) -> np.ndarray: ...


def run_ekf(log: RunLog, ekf: ChairEkf, fixes: dict[int, Pose2D] | None = None,
            fix_cov: np.ndarray | None = None,
            sightings: dict[int, list[Sighting]] | None = None,
            landmarks: dict[int, tuple[float, float]] | None = None,
            mount: tuple[float, float, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Run the filter over a log: states ``(N, 6)`` and covariances ``(N, 6, 6)``.

    Row 0 is the initial state; ``fixes`` maps rows to absolute poses of covariance
    ``fix_cov``; ``sightings`` maps rows to what a sensor at ``mount`` read of known
    ``landmarks`` (id: (x, y) m): objects with ``marker_id``, ``range``, ``bearing`` and
    ``covariance``, as :func:`abcwc.perception.markers.sight_markers` gives them. Needs
    only the counts and gyro samples (and those readings), so it runs on a recording
    from the real chair as well as on a simulated one.
    """
    sightings = sightings or {}
    if sightings and (landmarks is None or mount is None):
        raise ValueError("sightings given without the landmarks' places and the sensor's mount")
    validate_log(log, need_gyro=True)
    fixes = fixes or {}
    if fixes and fix_cov is None:
        raise ValueError("fixes given without fix_cov (3 x 3 covariance of a fix)")
    if fixes:
        cov = np.asarray(fix_cov, dtype=float)
        if cov.shape != (3, 3) or not np.isfinite(cov).all() or (np.diag(cov) <= 0).any():
            raise ValueError(f"fix_cov must be a finite 3 x 3 covariance with a positive "
                             f"diagonal, got {fix_cov!r}")
    travel = log_wheel_travel(log, ekf.params, ekf.correction)
    dts = np.diff(log.t)
    n = len(log)
    states, covs = np.empty((n, DIM)), np.empty((n, DIM, DIM))
    ekf.update_gyro(float(log.gyro_z[0]))
    states[0], covs[0] = ekf.filter.x, ekf.filter.P
    for k in range(1, n):
        ekf.step(float(travel[k - 1, 0]), float(travel[k - 1, 1]), float(dts[k - 1]),
                 float(log.gyro_z[k]))
        if k in fixes:
            ekf.update_pose(fixes[k], fix_cov)
        for seen in sightings.get(k, ()):
            if seen.marker_id in landmarks:  # type: ignore[operator]
                ekf.update_landmark((seen.range, seen.bearing),
                                    landmarks[seen.marker_id],  # type: ignore[index]
                                    mount, seen.covariance)  # type: ignore[arg-type]
        states[k], covs[k] = ekf.filter.x, ekf.filter.P
    return states, covs


# --------------------------------------------------------------------- consistency
def nees(truth: np.ndarray, states: np.ndarray, covs: np.ndarray,
         idx: tuple[int, ...] = POSE) -> np.ndarray:
    """Normalised estimation error squared ``e^T P^-1 e`` per row, on components ``idx``.

    ``truth`` holds those components (e.g. the ``(N, 3)`` true poses); the heading
    error is wrapped when component 2 is among them.
    """
    ix = list(idx)
    err = np.asarray(truth, dtype=float).reshape(len(states), len(ix)) - states[:, ix]
    if THETA in ix:
        j = ix.index(THETA)
        err[:, j] = geometry.wrap_angle(err[:, j])
    sub = covs[:, ix][:, :, ix]
    return np.einsum("ni,ni->n", err, np.linalg.solve(sub, err[:, :, None])[:, :, 0])


def nees_band(runs: int, dof: int = 3, confidence: float = 0.95) -> tuple[float, float]:
    """Two-sided band for the NEES averaged over ``runs`` runs: chi2(runs dof) / runs."""
    if runs < 1 or dof < 1 or not 0 < confidence < 1:
        raise ValueError(f"need runs >= 1, dof >= 1 and 0 < confidence < 1, "
                         f"got {runs!r}, {dof!r}, {confidence!r}")
    tail = (1 - confidence) / 2
    return (float(chi2.ppf(tail, runs * dof) / runs),
            float(chi2.ppf(1 - tail, runs * dof) / runs))
