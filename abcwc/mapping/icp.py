"""2D point-to-line ICP: the pose that lays one point set (or scan) onto another.

The point-to-line metric of Censi, "An ICP variant using a point-to-line metric"
(ICRA 2008): each source point ``p_i``, moved by the current pose, is paired with its
nearest target point ``q_i`` (a :class:`scipy.spatial.cKDTree` query) and pays the
squared distance to the line through ``q_i`` with normal ``n_i``::

    E(x) = sum_i (n_i . (R(theta) p_i + t - q_i))^2

The normals come from each target point and its nearest neighbours (3 in all by
default): the direction of least spread of their 2x2 scatter matrix (total least
squares). Target points whose neighbourhood is not line-like (corners, clutter) or
spreads over more than ``normal_max_spread`` (m: a gap, not a surface) have no normal
and take no part.

Each iteration minimises E linearised for a small correction ``(dx, dy, dtheta)``
composed on the left of the current pose (the small-angle linearisation of Low,
"Linear least-squares optimization for point-to-plane ICP surface registration", UNC
TR04-004, 2004, in 2D): ``R(dtheta) p' ~ p' + dtheta (-p'_y, p'_x)``, so each residual
is linear in the correction with Jacobian row ``J_i = [n_x, n_y, n_i . (-p'_y, p'_x)]``
and the correction is the least-squares solution of ``J dx = -r`` (the minimum-norm
one where ``J^T J`` is singular: a perfect corridor leaves the guess alone along it).
Optionally the initial guess is also a Gaussian prior (``initial_sigma``): three more
rows ``(residual_sigma / sigma_k) (pose_k - guess_k)`` join the system, so the points
decide what they can fix and odometry the rest.

Outliers are rejected twice per iteration: pairs further apart than
``max_correspondence_distance`` (m), then all but the ``trim_fraction`` of pairs with the
smallest point-to-line residuals (trimmed ICP, Chetverikov et al., ICPR 2002). Iteration
stops when the correction is below ``tolerance`` (m and rad), when the pose is back
where it was two iterations before (the pairing flips between two sets), or after
``max_iterations``.

Covariance: the Hessian approximation (Bengtsson and Baerveldt, "Robot localization
based on scan-matching - estimating the covariance matrix for the IDC algorithm", RAS
2003): ``cov = s^2 (J^T J)^-1`` at the solution, ``s^2 = sum r_i^2 / (n - 3)`` the
inliers' residual variance (m^2), ``J`` with the prior's rows if there is one. It is
cheap and shows the shape of the uncertainty (a corridor gives a long axis along the
corridor), but it is optimistic: Censi's closed form ("An accurate closed-form estimate
of ICP's covariance", ICRA 2007) also propagates the measurement noise through the
correspondences, and noisy normals make a real corridor look better fixed along its
length than it is (on ACES, matches that err by decimetres along a corridor report
standard deviations of millimetres). Directions
the points cannot fix at all (an endless corridor) have eigenvalues of ``J^T J`` near
zero; they are floored at ``1e-9`` of the largest, which leaves a huge, finite variance.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.spatial import cKDTree

from abcwc.geometry import compose, inverse, relative, transform_points, wrap_angle
from abcwc.types import LaserScan

if TYPE_CHECKING:
    from abcwc.mapping.carmen import CarmenLog

LINE_LIKE = 0.1
"""A neighbourhood is line-like when its scatter's small eigenvalue is at most this
fraction of the large one (an even spread along a segment gives 0, a disc 1)."""
_EIGENVALUE_FLOOR = 1e-9


class TooFewPairsError(ValueError):
    """ICP found fewer than 3 usable point pairs (points too sparse, or too far apart)."""


@dataclass(frozen=True)
class IcpResult:
    """What ICP found.

    ``pose``: ``(x, y, theta)`` (m, rad) of the source's frame in the target's frame
    (``transform_points(pose, source)`` lies on ``target``); ``covariance``: its 3x3
    covariance (m^2, m rad, rad^2); ``fitness``: the fraction of source points paired
    as inliers at the end; ``rms``: the inliers' root-mean-square point-to-line
    distance (m); ``iterations`` run and whether the correction fell below tolerance.
    """

    pose: np.ndarray
    covariance: np.ndarray
    fitness: float
    rms: float
    iterations: int
    converged: bool


def line_normals(points: np.ndarray, neighbours: int = 3,
                 max_spread: float = np.inf) -> np.ndarray:
    """Unit normals ``(N, 2)`` of each point's neighbourhood; NaN where not line-like.

    The neighbourhood is the point and its ``neighbours - 1`` nearest others, all
    within ``max_spread`` (m) of it, or the point has no normal; its normal
    is the scatter matrix's eigenvector of least spread, from the closed form of a
    symmetric 2x2 eigenproblem (vectorised over all points).
    """
    points = _as_points(points, "points")
    if len(points) < neighbours:
        return np.full(points.shape, np.nan)
    distance, near = cKDTree(points).query(points, k=neighbours)
    group = points[near]  # (N, k, 2)
    centred = group - group.mean(axis=1, keepdims=True)
    sxx = np.mean(centred[..., 0] ** 2, axis=1)
    syy = np.mean(centred[..., 1] ** 2, axis=1)
    sxy = np.mean(centred[..., 0] * centred[..., 1], axis=1)
    half_gap = np.hypot((sxx - syy) / 2, sxy)
    large, small = (sxx + syy) / 2 + half_gap, (sxx + syy) / 2 - half_gap
    along = 0.5 * np.arctan2(2 * sxy, sxx - syy)  # direction of most spread
    normals = np.stack([-np.sin(along), np.cos(along)], axis=-1)
    line_like = (small <= LINE_LIKE * large) & (large > 0) & (distance[:, -1] <= max_spread)
    normals[~line_like] = np.nan
    return normals


@dataclass(frozen=True)
class IcpTarget:
    """A target made ready once: its line-like ``points`` (M, 2), their unit ``normals``
    (M, 2) and a KD-tree over them. Matching many scans against one map (localisation)
    builds it once instead of once per scan; :func:`icp` takes it in place of points."""

    points: np.ndarray
    normals: np.ndarray
    tree: cKDTree

    @classmethod
    def build(cls, points: np.ndarray, neighbours: int = 3,
              max_spread: float = 0.5) -> IcpTarget:
        """The target for ``points`` (N, 2), m: normals by :func:`line_normals`; points
        without one are dropped. TooFewPairsError when fewer than 3 are left."""
        points = _as_points(points, "target")
        normals = line_normals(points, neighbours, max_spread)
        has_normal = np.all(np.isfinite(normals), axis=1)
        if has_normal.sum() < 3:
            raise TooFewPairsError(f"the target has {int(has_normal.sum())} points with a "
                                   f"line-like neighbourhood; ICP needs at least 3")
        kept = points[has_normal]
        return cls(kept, normals[has_normal], cKDTree(kept))


def icp(source: np.ndarray, target: np.ndarray | IcpTarget,
        initial: tuple[float, float, float] | np.ndarray = (0.0, 0.0, 0.0), *,
        max_correspondence_distance: float = 0.5, trim_fraction: float = 0.9,
        max_iterations: int = 50, tolerance: float = 1e-6,
        normal_neighbours: int = 3, normal_max_spread: float = 0.5,
        initial_sigma: tuple[float, float, float] | None = None,
        residual_sigma: float = 0.02) -> IcpResult:
    """Point-to-line ICP of ``source`` ``(N, 2)`` onto ``target`` ``(M, 2)`` (m), or onto
    an :class:`IcpTarget` built once (then ``normal_*`` are its own).

    ``initial``: the first guess of the source frame's pose in the target frame. With
    ``initial_sigma`` (standard deviations of the guess: m, m, rad) the guess is also a
    Gaussian prior on the pose, weighed against point-to-line residuals of standard
    deviation ``residual_sigma`` (m): what the points fix they decide, and along what
    they cannot fix (a corridor) the guess stays. See the module docstring for the
    method. Raises ValueError for bad shapes or settings, and
    TooFewPairsError (a ValueError) when fewer than 3 pairs survive the outlier rejection.
    """
    source = _as_points(source, "source")
    if not max_correspondence_distance > 0:
        raise ValueError(f"max_correspondence_distance must be > 0 m, "
                         f"got {max_correspondence_distance!r}")
    if not 0 < trim_fraction <= 1:
        raise ValueError(f"trim_fraction {trim_fraction!r} outside (0, 1]")
    if not (isinstance(max_iterations, int) and max_iterations >= 1):
        raise ValueError(f"max_iterations must be an integer >= 1, got {max_iterations!r}")
    if not isinstance(target, IcpTarget):
        target = IcpTarget.build(target, normal_neighbours, normal_max_spread)
    tree, normals, target = target.tree, target.normals, target.points
    guess = np.asarray(initial, dtype=float).reshape(3)
    prior = None if initial_sigma is None else residual_sigma / _positive(initial_sigma)
    poses = [guess.copy()]  # one per iteration
    converged = False
    while not converged and len(poses) <= max_iterations:
        jacobian, residuals = _pairs(tree, target, normals, source, poses[-1],
                                     max_correspondence_distance, trim_fraction)
        rows, values = _with_prior(jacobian, residuals, poses[-1], guess, prior)
        step = np.linalg.lstsq(rows, -values, rcond=None)[0]
        poses.append(np.asarray(compose(step, poses[-1])))
        # done when there is nothing left to correct, or when back where it was two
        # steps ago (the pairs flip between two sets, the pose between two answers)
        converged = _small(step, tolerance) or (
            len(poses) > 2 and _small(np.asarray(relative(poses[-3], poses[-1])), tolerance))
    pose, iterations = poses[-1], len(poses) - 1
    jacobian, residuals = _pairs(tree, target, normals, source, pose,
                                 max_correspondence_distance, trim_fraction)
    rows, _ = _with_prior(jacobian, residuals, pose, guess, prior)
    return IcpResult(pose=pose, covariance=_covariance(rows, residuals),
                     fitness=len(residuals) / len(source),
                     rms=float(np.sqrt(np.mean(residuals ** 2))),
                     iterations=iterations, converged=converged)


def _small(change: np.ndarray, tolerance: float) -> bool:
    """Whether a pose change is below ``tolerance`` in every component (m, m, rad)."""
    return bool(np.all(np.abs(change) < tolerance))


def _positive(sigma: tuple[float, float, float]) -> np.ndarray:
    values = np.asarray(sigma, dtype=float)
    if values.shape != (3,) or not np.all(values > 0) or not np.all(np.isfinite(values)):
        raise ValueError(f"initial_sigma must be three finite numbers > 0 (m, m, rad), "
                         f"got {sigma!r}")
    return values


def _with_prior(jacobian: np.ndarray, residuals: np.ndarray, pose: np.ndarray,
                guess: np.ndarray, weights: np.ndarray | None
                ) -> tuple[np.ndarray, np.ndarray]:
    """The point rows, and with ``weights`` three more: ``weights * (pose - guess)``,
    linearised for a correction composed on the left of ``pose``."""
    if weights is None:
        return jacobian, residuals
    deviation = pose - guess
    deviation[2] = wrap_angle(float(deviation[2]))
    # d(step (+) pose) / d(step) at step = 0
    moves = np.array([[1.0, 0.0, -pose[1]], [0.0, 1.0, pose[0]], [0.0, 0.0, 1.0]])
    return (np.vstack([jacobian, weights[:, None] * moves]),
            np.concatenate([residuals, weights * deviation]))


def _as_points(points: np.ndarray, name: str) -> np.ndarray:
    array = np.asarray(points, dtype=float)
    if array.ndim != 2 or array.shape[1] != 2:
        raise ValueError(f"{name} must be an (N, 2) array of points, got shape {array.shape}")
    return array[np.all(np.isfinite(array), axis=1)]


def _pairs(tree: cKDTree, target: np.ndarray, normals: np.ndarray, source: np.ndarray,
           pose: np.ndarray, max_distance: float, trim_fraction: float
           ) -> tuple[np.ndarray, np.ndarray]:
    """The inlier pairs at ``pose``: their Jacobian rows ``(n, 3)`` and point-to-line
    residuals ``(n,)`` (m)."""
    moved = transform_points(pose, source)
    distance, nearest = tree.query(moved, distance_upper_bound=max_distance)
    paired = np.isfinite(distance)
    moved, nearest = moved[paired], nearest[paired]
    n = normals[nearest]
    residuals = np.einsum("ij,ij->i", n, moved - target[nearest])
    keep = int(np.ceil(trim_fraction * len(residuals)))
    if keep < len(residuals):
        best = np.argpartition(np.abs(residuals), keep - 1)[:keep]
        moved, n, residuals = moved[best], n[best], residuals[best]
    if len(residuals) < 3:
        raise TooFewPairsError(f"only {len(residuals)} point pairs within "
                         f"{max_distance} m; ICP needs at least 3 (is the initial guess "
                         f"too far off?)")
    turn = n[:, 1] * moved[:, 0] - n[:, 0] * moved[:, 1]  # n . (-p'_y, p'_x)
    return np.column_stack([n, turn]), residuals


def _covariance(jacobian: np.ndarray, residuals: np.ndarray) -> np.ndarray:
    """``s^2 (J^T J)^-1`` with near-zero eigenvalues of ``J^T J`` floored; ``s^2`` from
    the point residuals (``jacobian`` may hold the prior's rows too)."""
    dof = max(len(residuals) - 3, 1)
    variance = float(residuals @ residuals) / dof
    values, vectors = np.linalg.eigh(jacobian.T @ jacobian)
    values = np.maximum(values, _EIGENVALUE_FLOOR * max(values[-1], 1e-300))
    return variance * (vectors / values) @ vectors.T


def match_scans(reference: LaserScan, current: LaserScan,
                initial: tuple[float, float, float] | np.ndarray = (0.0, 0.0, 0.0),
                **options: Any) -> IcpResult:
    """The pose of ``current``'s laser frame in ``reference``'s, by point-to-line ICP.

    ``initial`` is the first guess (e.g. from odometry); ``options`` go to :func:`icp`.
    """
    return icp(current.points(), reference.points(), initial, **options)


def match_consecutive_scans(log: CarmenLog, first: int = 0, last: int | None = None,
                            **options: Any) -> np.ndarray:
    """Scan-matching odometry: ``(K, 3)`` relative robot poses from scan ``k`` to ``k+1``
    for ``k`` in ``first .. last - 1`` (``last`` defaults to the last scan).

    Each pair is matched by :func:`icp`, starting from the odometry's relative pose, in
    the laser frame, then moved to the robot frame: ``offset (+) delta (+) offset^-1``.
    A pair ICP cannot match (fewer than 3 point pairs) keeps the odometry's pose.
    """
    last = len(log) - 1 if last is None else last
    if not 0 <= first <= last < len(log):
        raise ValueError(f"scan range {first}..{last} outside 0..{len(log) - 1}")
    laser = log.laser_poses
    guesses = np.asarray(relative(laser[first:last], laser[first + 1:last + 1]))
    previous = log.points(first)
    deltas = np.empty((last - first, 3))
    for k in range(first, last):
        current = log.points(k + 1)
        try:
            deltas[k - first] = icp(current, previous, guesses[k - first], **options).pose
        except TooFewPairsError:
            deltas[k - first] = guesses[k - first]
        previous = current
    offset = log.laser_offset
    return np.asarray(compose(compose(offset, deltas), inverse(offset)))


