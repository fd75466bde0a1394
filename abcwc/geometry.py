"""Planar geometry every layer shares: angle wrapping, SE(2) poses, encoder counts.

Conventions (ROS REP 103): x forward, y left, yaw counter-clockwise, angles in rad
wrapped to (-pi, pi]. A pose is ``(x, y, theta)``: a :class:`~abcwc.types.Pose2D`, a
length-3 sequence, or an ``(N, 3)`` array of N poses. Every function takes single poses
and arrays alike and answers in kind (a Pose2D for Pose2D inputs, arrays otherwise).

SE(2) composition, inverse and relative pose follow Smith, Self and Cheeseman, "Estimating
uncertain spatial relationships in robotics" (1990), eqns 1-3 (their head-to-tail
``\\oplus`` and inverse ``\\ominus``); the same operations as ROS tf2 on 2D transforms.
"""

from __future__ import annotations

import math
from typing import Union

import numpy as np

from abcwc.types import Pose2D

PoseLike = Union[Pose2D, "np.ndarray", "tuple[float, float, float]", "list[float]"]


def wrap_angle(angle: float | np.ndarray) -> float | np.ndarray:
    """Wrap angles (rad) into (-pi, pi]; a float for a scalar, an array for an array.

    ``math.remainder`` gives [-pi, pi]; -pi is mapped to +pi so that the interval is
    half-open and every heading has exactly one representation. Both paths are exact
    (the answer is ``angle - 2 pi n`` to the last bit, so an angle already in range comes
    back unchanged) and agree bit for bit: ``np.fmod`` is exact, and moving its result
    from (pi, 2 pi) or (-2 pi, -pi] by one ``2 pi`` is exact too (Sterbenz's lemma).
    """
    if not isinstance(angle, np.ndarray):
        wrapped = math.remainder(float(angle), 2.0 * math.pi)
        return math.pi if wrapped == -math.pi else wrapped
    wrapped = np.fmod(angle.astype(float), 2.0 * math.pi)  # (-2 pi, 2 pi), exact
    wrapped = np.where(wrapped > math.pi, wrapped - 2.0 * math.pi, wrapped)
    return np.where(wrapped <= -math.pi, wrapped + 2.0 * math.pi, wrapped)


def _as_poses(pose: PoseLike) -> np.ndarray:
    """A pose or poses as a float array of shape (3,) or (N, 3)."""
    if isinstance(pose, Pose2D):
        return np.array([pose.x, pose.y, pose.theta])
    array = np.asarray(pose, dtype=float)
    if array.shape[-1:] != (3,) or array.ndim > 2:
        raise ValueError(f"a pose is (x, y, theta) or an (N, 3) array, got shape {array.shape}")
    return array


def position_of(point: PoseLike | tuple[float, float], name: str = "point") -> np.ndarray:
    """The map position ``(x, y)`` (m) of a Pose2D, an ``(x, y)`` or an ``(x, y, theta)``;
    ValueError naming ``name`` unless it is one of those and finite."""
    values = np.asarray([point.x, point.y] if isinstance(point, Pose2D) else point,
                        dtype=float)
    if values.shape not in ((2,), (3,)) or not np.isfinite(values[:2]).all():
        raise ValueError(f"{name} must be a finite (x, y) in metres, got {point!r}")
    return values[:2]


def _answer(result: np.ndarray, *inputs: PoseLike) -> Pose2D | np.ndarray:
    """A Pose2D when every input was one, the array otherwise."""
    if all(isinstance(p, Pose2D) for p in inputs):
        return Pose2D(float(result[0]), float(result[1]), float(result[2]))
    return result


def compose(a: PoseLike, b: PoseLike) -> Pose2D | np.ndarray:
    """Head-to-tail ``a (+) b``: pose ``b``, given in ``a``'s frame, in ``a``'s parent.

    x = x_a + x_b cos(t_a) - y_b sin(t_a); y = y_a + x_b sin(t_a) + y_b cos(t_a);
    theta = wrap(t_a + t_b) (Smith, Self and Cheeseman 1990, eqn 1). Broadcasts over
    arrays of poses.
    """
    pa, pb = _as_poses(a), _as_poses(b)
    if pa.ndim == 1 and pb.ndim == 1:  # one pose each: in floats, five times faster
        (xa, ya, ta), (xb, yb, tb) = pa.tolist(), pb.tolist()
        c, s = math.cos(ta), math.sin(ta)
        return _answer(np.array([xa + c * xb - s * yb, ya + s * xb + c * yb,
                                 wrap_angle(ta + tb)]), a, b)
    c, s = np.cos(pa[..., 2]), np.sin(pa[..., 2])
    out = np.stack([pa[..., 0] + c * pb[..., 0] - s * pb[..., 1],
                    pa[..., 1] + s * pb[..., 0] + c * pb[..., 1],
                    wrap_angle(pa[..., 2] + pb[..., 2])], axis=-1)
    return _answer(out, a, b)


def inverse(a: PoseLike) -> Pose2D | np.ndarray:
    """``(-) a``: the parent's origin seen from ``a`` (Smith, Self and Cheeseman, eqn 2)."""
    pa = _as_poses(a)
    c, s = np.cos(pa[..., 2]), np.sin(pa[..., 2])
    out = np.stack([-c * pa[..., 0] - s * pa[..., 1],
                    s * pa[..., 0] - c * pa[..., 1],
                    wrap_angle(-pa[..., 2])], axis=-1)
    return _answer(out, a)


def relative(a: PoseLike, b: PoseLike) -> Pose2D | np.ndarray:
    """``(-) a (+) b``: pose ``b`` seen from pose ``a`` (both in the same frame).

    The odometry edge from ``a`` to ``b`` of a pose graph; ``compose(a, relative(a, b))``
    gives ``b`` back.
    """
    pa, pb = _as_poses(a), _as_poses(b)
    c, s = np.cos(pa[..., 2]), np.sin(pa[..., 2])
    dx, dy = pb[..., 0] - pa[..., 0], pb[..., 1] - pa[..., 1]
    out = np.stack([c * dx + s * dy, -s * dx + c * dy,
                    wrap_angle(pb[..., 2] - pa[..., 2])], axis=-1)
    return _answer(out, a, b)


def chain_poses(start: PoseLike, steps: np.ndarray) -> np.ndarray:
    """Poses ``(K + 1, 3)`` from ``start`` by composing relative poses ``steps`` ``(K, 3)``
    in turn, ``x_{k+1} = x_k (+) step_k`` (eqn 1 of Smith, Self and Cheeseman 1990), all
    at once: the headings by a cumulative sum, then each step rotated into the parent by
    the heading before it, and the moves summed. Odometry chained into a path, a pose
    graph's first guess from its ``i -> i + 1`` edges, scan matches into a trajectory.
    """
    first = _as_poses(start)
    if first.shape != (3,):
        raise ValueError(f"start must be one pose (x, y, theta), got shape {first.shape}")
    moves = np.asarray(steps, dtype=float).reshape(-1, 3)
    headings = first[2] + np.concatenate([[0.0], np.cumsum(moves[:, 2])])  # unwrapped
    c, s = np.cos(headings[:-1]), np.sin(headings[:-1])
    in_parent = np.column_stack([c * moves[:, 0] - s * moves[:, 1],
                                 s * moves[:, 0] + c * moves[:, 1]])
    xy = first[:2] + np.concatenate([[[0.0, 0.0]], np.cumsum(in_parent, axis=0)])
    return np.column_stack([xy, wrap_angle(headings)])


def transform_points(pose: PoseLike, points: np.ndarray) -> np.ndarray:
    """Points ``(..., 2)`` given in ``pose``'s frame, expressed in its parent frame (m).

    ``p' = R(theta) p + t``. With one pose, ``points`` may be any ``(..., 2)`` array; with
    N poses, ``points`` is ``(N, 2)`` (one point per pose) or ``(N, M, 2)``.
    """
    p = _as_poses(pose)
    pts = np.asarray(points, dtype=float)
    if pts.shape[-1] != 2:
        raise ValueError(f"points must have shape (..., 2), got {pts.shape}")
    c, s = np.cos(p[..., 2]), np.sin(p[..., 2])
    if p.ndim == 2 and pts.ndim == 3:
        c, s, tx, ty = (v[:, None] for v in (c, s, p[:, 0], p[:, 1]))
    else:
        tx, ty = p[..., 0], p[..., 1]
    x, y = pts[..., 0], pts[..., 1]
    return np.stack([tx + c * x - s * y, ty + s * x + c * y], axis=-1)


def inverse_transform_points(pose: PoseLike, points: np.ndarray) -> np.ndarray:
    """Points ``(..., 2)`` in ``pose``'s parent frame, expressed in ``pose``'s frame (m).

    ``p = R(theta)^T (p' - t)``: the inverse of :func:`transform_points`.
    """
    return transform_points(_as_poses(inverse(_as_poses(pose))), points)


def densify_polyline(points: np.ndarray, spacing: float) -> np.ndarray:
    """Points along the polyline ``points`` (K, 2, m) no more than ``spacing`` m apart:
    each segment cut into equal pieces, its corners kept."""
    points = np.asarray(points, dtype=float)
    if len(points) < 2:
        return points
    steps = points[1:] - points[:-1]
    counts = np.maximum(1, np.ceil(np.hypot(*steps.T) / spacing).astype(int))
    segment = np.repeat(np.arange(len(steps)), counts)
    piece = np.arange(len(segment)) - np.repeat(np.cumsum(counts) - counts, counts) + 1
    fraction = piece / counts[segment]  # 1/n, 2/n, .. 1 along each segment
    return np.concatenate([points[:1], points[:-1][segment] + fraction[:, None] * steps[segment]])


def rotation_matrix(theta: float) -> np.ndarray:
    """The 2x2 rotation ``R(theta)`` (counter-clockwise, rad)."""
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


def wrap_tick_delta(delta: int | np.ndarray, bits: int = 32) -> int | np.ndarray:
    """Difference of two cumulative counts, corrected for wrap-around at ``bits`` width.

    The firmware keeps counts in a signed ``bits``-bit integer, which wraps from
    ``2**(bits-1) - 1`` to ``-2**(bits-1)``. Any true increment smaller than half the
    range in magnitude comes back right: the difference is taken modulo ``2**bits``
    into ``[-2**(bits-1), 2**(bits-1))``.
    """
    if not isinstance(bits, int) or not 2 <= bits <= 64:
        raise ValueError(f"bits must be an integer 2..64, got {bits!r}")
    span = 1 << bits
    half = 1 << (bits - 1)
    if isinstance(delta, np.ndarray):
        d = delta.astype(object) if bits == 64 else delta.astype(np.int64)
        return ((d + half) % span - half).astype(np.int64)
    return (int(delta) + half) % span - half


def encoder_ticks_to_wheel_distance(ticks: np.ndarray, distance_per_count: float,
                                    bits: int = 32) -> np.ndarray:
    """Each wheel's travel (m) between consecutive rows of cumulative counts.

    ``ticks`` is ``(N, ...)`` cumulative counts (one column per wheel); the answer is
    ``(N-1, ...)``: the count differences, corrected for the counter wrapping at ``bits``
    width (:func:`wrap_tick_delta`), times ``distance_per_count`` (m per count,
    ``pi d_e / N_e``, thesis 4.2.1). The one place in the library where counts become
    metres.
    """
    if not (isinstance(distance_per_count, (int, float, np.floating))
            and math.isfinite(distance_per_count) and distance_per_count > 0):
        raise ValueError(f"distance_per_count must be a finite number > 0 m, "
                         f"got {distance_per_count!r}")
    counts = np.asarray(ticks)
    if not np.issubdtype(counts.dtype, np.integer):
        if not np.all(np.isfinite(counts)) or np.any(counts != np.round(counts)):
            raise ValueError("encoder counts must be whole numbers")
        counts = counts.astype(np.int64)
    deltas = wrap_tick_delta(np.diff(counts.astype(np.int64), axis=0), bits)
    return deltas * float(distance_per_count)
