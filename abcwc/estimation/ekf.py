"""An extended Kalman filter for the chair (thesis 4.3.5; Thrun, Burgard and Fox,
*Probabilistic Robotics*, 2005, ch. 3.3).

State ``s = [x, y, theta, v, omega]`` (m, m, rad, m/s, rad/s). Motion model over a
period ``dt`` (a unicycle, eqns 9-10 with the velocities held over the period)::

    x' = x + v dt cos(theta)      y' = y + v dt sin(theta)
    theta' = theta + omega dt     v' = v + a dt     omega' = omega + alpha dt

with white accelerations ``a``, ``alpha`` as process noise. Its Jacobian is
:func:`motion_jacobian`. Three measurements:

* wheel odometry ``z = [d_c / dt, phi / dt]`` (eqns 6-7 over the period), H picks v, omega;
* the gyro ``z = g_z - bias``, H picks omega;
* an absolute fix ``z = [x, y, theta]`` (a landmark or tag sighting), with the
  heading residual wrapped to (-pi, pi].

Order of one cycle on a log row ``k`` (see :mod:`abcwc.estimation.gyro` for the
timing): update with row k's wheel measurement (the period that ends at ``t_k``),
predict over that period, then update with row k's gyro sample (the period that
starts at ``t_k``) and any fix taken at ``t_k``.

Noise (:func:`noise_from_models`): the wheel measurement's standard deviation is the
count quantisation, ``d/sqrt(6)`` per wheel for a distance per count ``d`` (each
increment is the difference of two floors), plus a relative part for slip and the
residual systematic error UMBmark leaves (``E_max,syst / (4 L)`` per metre after
correction, about 0.2 %); the gyro's is the sensor model's white noise plus the
uncertainty of the still-standing bias estimate and the bias walk since then. The
state has no bias, so a bias error ``b`` is spread as white noise that integrates to
the same heading error over a fix interval ``T``: ``b sqrt(T / dt)`` per sample.

Two back ends with the same equations: :class:`FilterpyEkf` wraps
``filterpy.kalman.ExtendedKalmanFilter`` (Joseph-form covariance update) and
:class:`FastEkf` does the same algebra in NumPy, exploiting that every H here just
picks state components. Consistency is checked with the NEES (:func:`nees`,
:func:`nees_band`; Bar-Shalom, Li and Kirubarajan 2001, ch. 5.4).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.stats import chi2

from abcwc.estimation.odometry import log_wheel_travel, validate_log
from abcwc.log import RunLog
from abcwc.params import ChairParams, default_params
from abcwc.types import Pose2D

DIM = 5
WHEEL = (3, 4)  # state indices each measurement reads
GYRO = (4,)
POSE = (0, 1, 2)


def motion(s: np.ndarray, dt: float) -> np.ndarray:
    """The unicycle motion model f(s) over ``dt`` seconds."""
    x, y, theta, v, w = s
    return np.array([x + v * dt * math.cos(theta), y + v * dt * math.sin(theta),
                     theta + w * dt, v, w])


def motion_jacobian(s: np.ndarray, dt: float) -> np.ndarray:
    """``F = df/ds`` at ``s``."""
    theta, v = s[2], s[3]
    c, sn = math.cos(theta), math.sin(theta)
    return np.array([[1.0, 0.0, -v * dt * sn, dt * c, 0.0],
                     [0.0, 1.0, v * dt * c, dt * sn, 0.0],
                     [0.0, 0.0, 1.0, 0.0, dt],
                     [0.0, 0.0, 0.0, 1.0, 0.0],
                     [0.0, 0.0, 0.0, 0.0, 1.0]])


@dataclass(frozen=True)
class EkfNoise:
    """Standard deviations (SI units) of the process and the measurements."""

    accel: float = 0.5  # m/s^2, white linear acceleration
    ang_accel: float = 1.0  # rad/s^2, white angular acceleration
    wheel_v: float = 0.007  # m/s, count quantisation over one period
    wheel_w: float = 0.032  # rad/s
    wheel_rel: float = 0.004  # relative: slip + residual systematic error
    gyro: float = 0.003  # rad/s, per sample

    def process(self, dt: float) -> np.ndarray:
        """Q for one period: accelerations enter v and omega (cached, read-only)."""
        return _process(self.accel, self.ang_accel, dt)

    def wheel(self, v: float, w: float, wheel_base: float) -> np.ndarray:
        """R for a wheel measurement of speed v and turn rate w."""
        rel = self.wheel_rel
        wheel_speed = abs(v) + abs(w) * wheel_base / 2
        return np.array([[self.wheel_v ** 2 + (rel * v) ** 2, 0.0],
                         [0.0, self.wheel_w ** 2 + (2 * rel * wheel_speed / wheel_base) ** 2]])


@lru_cache(maxsize=64)
def _process(accel: float, ang_accel: float, dt: float) -> np.ndarray:
    q = np.zeros((DIM, DIM))
    q[3, 3] = (accel * dt) ** 2
    q[4, 4] = (ang_accel * dt) ** 2
    q.flags.writeable = False
    return q


def noise_from_models(params: ChairParams | None = None, slip_std: float = 0.003,
                      residual_rel: float = 0.002, bias_samples: int = 100,
                      bias_hold: float = 60.0, fix_interval: float = 10.0) -> EkfNoise:
    """Noise from the sensor models (see the module docstring for the derivation).

    ``slip_std`` is the per-wheel per-period relative slip, ``residual_rel`` the
    relative odometry error UMBmark leaves, ``bias_samples`` how many still samples
    estimated the gyro bias, ``bias_hold`` (s) how long that estimate is used (the
    bias walks meanwhile) and ``fix_interval`` (s) the time between absolute fixes,
    over which a bias error acts unchecked.
    """
    p = params or default_params()
    dt = p.control_period
    per_wheel = p.distance_per_count / math.sqrt(6)
    g = p.gyro
    bias_error = math.hypot(g.noise_std / math.sqrt(bias_samples),
                            g.bias_walk_std * math.sqrt(bias_hold))
    # a constant bias error b over T seconds of n samples looks like white noise of
    # std b sqrt(n) per sample in its effect on the integrated heading
    per_sample_bias = bias_error * math.sqrt(fix_interval / dt)
    return EkfNoise(
        wheel_v=per_wheel / math.sqrt(2) / dt,
        wheel_w=per_wheel * math.sqrt(2) / p.wheel_base / dt,
        wheel_rel=math.hypot(slip_std, residual_rel),
        gyro=math.hypot(g.noise_std, per_sample_bias),
    )


# --------------------------------------------------------------------- back ends
class FastEkf:
    """The EKF in plain NumPy: predict, and updates on a contiguous block of the state.

    Every H here picks consecutive components (``WHEEL``, ``GYRO``, ``POSE``), so
    ``P H^T`` is a column slice of P and ``S`` a block; 1 x 1 and 2 x 2 blocks are
    inverted in closed form. About 3x faster than the generic filterpy code.
    """

    def __init__(self, x0: np.ndarray, p0: np.ndarray):
        self.x = np.array(x0, dtype=float).reshape(DIM)
        self.P = np.array(p0, dtype=float).reshape(DIM, DIM)
        self._f = np.eye(DIM)
        self._eye = np.eye(DIM)

    def predict(self, dt: float, q: np.ndarray) -> None:
        """``x = f(x)``, ``P = F P F^T + Q``."""
        x, y, theta, v, w = self.x
        c, s = math.cos(theta), math.sin(theta)
        f = self._f
        f[0, 2], f[0, 3] = -v * dt * s, dt * c
        f[1, 2], f[1, 3] = v * dt * c, dt * s
        f[2, 4] = dt
        self.x = np.array([x + v * dt * c, y + v * dt * s, theta + w * dt, v, w])
        self.P = f @ self.P @ f.T + q

    def update(self, z: np.ndarray, idx: tuple[int, ...], r: np.ndarray,
               angle: int | None = None) -> None:
        """Update with ``z`` of the components ``idx`` (consecutive; H picks them).

        ``r`` is the measurement noise; ``angle`` the position in ``z`` of a heading,
        whose residual is wrapped. Joseph form, as filterpy.
        """
        block = slice(idx[0], idx[-1] + 1)
        y = z - self.x[block]
        if angle is not None:
            y[angle] = math.remainder(y[angle], 2 * math.pi)
        pht = self.P[:, block]
        s = pht[block] + r
        k = pht @ _inverse(s)
        self.x = self.x + k @ y
        i_kh = self._eye.copy()
        i_kh[:, block] -= k
        self.P = i_kh @ self.P @ i_kh.T + k @ r @ k.T


def _inverse(s: np.ndarray) -> np.ndarray:
    """Inverse of a small symmetric positive-definite matrix (closed form to 2 x 2)."""
    if s.shape[0] == 1:
        return 1.0 / s
    if s.shape[0] == 2:
        a, b, c, d = s[0, 0], s[0, 1], s[1, 0], s[1, 1]
        return np.array([[d, -b], [-c, a]]) / (a * d - b * c)
    return np.linalg.inv(s)


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

    def update(self, z: np.ndarray, idx: tuple[int, ...], r: np.ndarray,
               angle: int | None = None) -> None:
        h = np.zeros((len(idx), DIM))
        h[range(len(idx)), list(idx)] = 1.0

        def residual(a: np.ndarray, b: np.ndarray) -> np.ndarray:
            y = a - b
            if angle is not None:
                y[angle] = math.remainder(float(y[angle, 0]), 2 * math.pi)
            return y

        self._kf.update(np.asarray(z, dtype=float).reshape(-1, 1), lambda s: h,
                        lambda s: h @ s, R=r, residual=residual)


# --------------------------------------------------------------------- the chair's filter
class ChairEkf:
    """Wheel odometry + gyro + occasional absolute fixes, on either back end."""

    def __init__(self, start: Pose2D, params: ChairParams | None = None,
                 noise: EkfNoise | None = None, start_std: tuple[float, float, float] = (
                     0.01, 0.01, 0.005), backend: str = "fast",
                 correction: tuple[float, float] = (1.0, 1.0),
                 wheel_base: float | None = None, gyro_bias: float = 0.0):
        self.params = p = params or default_params()
        self.noise = noise or noise_from_models(p)
        self.correction = correction
        self.wheel_base = p.wheel_base if wheel_base is None else wheel_base
        self.gyro_bias = gyro_bias
        x0 = np.array([start.x, start.y, start.theta, 0.0, 0.0])
        p0 = np.diag([start_std[0] ** 2, start_std[1] ** 2, start_std[2] ** 2, 1e-4, 1e-4])
        if backend == "fast":
            self.filter: FastEkf | FilterpyEkf = FastEkf(x0, p0)
        elif backend == "filterpy":
            self.filter = FilterpyEkf(x0, p0)
        else:
            raise ValueError(f"backend must be 'fast' or 'filterpy', got {backend!r}")

    @property
    def pose(self) -> Pose2D:
        """The current pose estimate (heading wrapped)."""
        x = self.filter.x
        return Pose2D(float(x[0]), float(x[1]), math.remainder(float(x[2]), 2 * math.pi))

    def predict(self, dt: float) -> None:
        """Propagate over ``dt`` seconds."""
        self.filter.predict(dt, self.noise.process(dt))

    def update_wheels(self, d_left: float, d_right: float, dt: float) -> None:
        """Update with one period's wheel travel (m, already corrected)."""
        v = (d_right + d_left) / 2 / dt
        w = (d_right - d_left) / self.wheel_base / dt
        self.filter.update(np.array([v, w]), WHEEL, self.noise.wheel(v, w, self.wheel_base))

    def update_gyro(self, gyro_z: float) -> None:
        """Update with one gyro sample (rad/s); the bias is subtracted here."""
        self.filter.update(np.array([gyro_z - self.gyro_bias]), GYRO,
                           np.array([[self.noise.gyro ** 2]]))

    def update_pose(self, pose: Pose2D, cov: np.ndarray) -> None:
        """Update with an absolute fix ``pose`` of covariance ``cov`` (3 x 3)."""
        self.filter.update(np.array([pose.x, pose.y, pose.theta]), POSE, np.asarray(cov),
                           angle=2)


def absolute_fixes(log: RunLog, every: float, std: tuple[float, float, float],
                   seed: int = 0) -> dict[int, Pose2D]:
    """Noisy fixes from the log's ground truth every ``every`` seconds: {row: pose}."""
    rng = np.random.default_rng(seed)
    rows = np.flatnonzero(np.diff(np.floor((log.t - log.t[0]) / every), prepend=0) > 0)
    noise = rng.standard_normal((len(rows), 3)) * np.asarray(std)
    return {int(k): Pose2D(*(log.pose[k] + e)) for k, e in zip(rows, noise)}


def run_ekf(log: RunLog, ekf: ChairEkf, fixes: dict[int, Pose2D] | None = None,
            fix_cov: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Run the filter over a log: states ``(N, 5)`` and covariances ``(N, 5, 5)``.

    Row 0 is the initial state; ``fixes`` maps rows to absolute poses of covariance
    ``fix_cov``.
    """
    validate_log(log, need_gyro=True)
    fixes = fixes or {}
    if fixes and fix_cov is None:
        raise ValueError("fixes given without fix_cov (3 x 3 covariance of a fix)")
    travel = log_wheel_travel(log, ekf.params, ekf.correction)
    dts = np.diff(log.t)
    n = len(log)
    states, covs = np.empty((n, DIM)), np.empty((n, DIM, DIM))
    ekf.update_gyro(float(log.gyro_z[0]))
    states[0], covs[0] = ekf.filter.x, ekf.filter.P
    for k in range(1, n):
        dt = float(dts[k - 1])
        ekf.update_wheels(float(travel[k - 1, 0]), float(travel[k - 1, 1]), dt)
        ekf.predict(dt)
        ekf.update_gyro(float(log.gyro_z[k]))
        if k in fixes:
            ekf.update_pose(fixes[k], fix_cov)
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
    err = np.asarray(truth, dtype=float) - states[:, ix]
    if 2 in ix:
        j = ix.index(2)
        err[:, j] = np.angle(np.exp(1j * err[:, j]))
    sub = covs[:, ix][:, :, ix]
    return np.einsum("ni,ni->n", err, np.linalg.solve(sub, err[:, :, None])[:, :, 0])


def nees_band(runs: int, dof: int = 3, confidence: float = 0.95) -> tuple[float, float]:
    """Two-sided band for the NEES averaged over ``runs`` runs: chi2(runs dof) / runs."""
    tail = (1 - confidence) / 2
    return (float(chi2.ppf(tail, runs * dof) / runs),
            float(chi2.ppf(1 - tail, runs * dof) / runs))
