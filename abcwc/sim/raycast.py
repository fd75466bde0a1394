"""Vectorised range queries against wall segments and round bodies.

Every beam is tested against every segment (and every circle) in one NumPy
expression: a ray ``o + t d`` meets segment ``p + s e`` where, with the 2-D cross
product ``a x b = a_x b_y - a_y b_x``,

    t = ((p - o) x e) / (d x e),    s = ((p - o) x d) / (d x e),

and it is a hit when ``t >= 0`` and ``0 <= s <= 1``. The chair's own outline is never
in the arrays, so a sensor inside the chair does not see the chair.

Heights: a segment stands between two heights, and a sensor at height ``h`` that sees
``+-a`` about the horizontal reaches heights ``h +- t tan a`` at distance ``t``. So a
segment standing from ``z0`` to ``z1`` is seen only from the distance
``max(0, (z0 - h) / tan a, (h - z1) / tan a)`` on (never, for a planar sensor, ``a = 0``,
that is not at its height). :func:`visible_segments` appends that distance as a fifth
column, and every query here honours it.
"""

from __future__ import annotations

import numpy as np

INF = np.inf


def _origin_columns(origin: np.ndarray) -> tuple[np.ndarray | float, np.ndarray | float]:
    """x and y of a shared origin (scalars) or of per-ray origins (B, 1) columns."""
    origin = np.asarray(origin, dtype=float)
    if origin.ndim == 1:
        return origin[0], origin[1]
    return origin[:, 0:1], origin[:, 1:2]


def visible_segments(segments: np.ndarray, bands: np.ndarray, height: float,
                     half_angle: float) -> np.ndarray:
    """Segments (N, 4) standing between ``bands`` (N, 2: bottom, top, m) as a sensor at
    ``height`` (m) seeing ``+-half_angle`` (rad) vertically sees them: (M, 5), the fifth
    column the distance (m) from which each is in view; segments never in view dropped."""
    bottom, top = bands[:, 0], bands[:, 1]
    if half_angle <= 0.0:
        near = np.where((bottom <= height) & (height <= top), 0.0, INF)
    else:
        slope = np.tan(half_angle)
        near = np.maximum.reduce([np.zeros(len(bands)), (bottom - height) / slope,
                                  (height - top) / slope])
    seen = np.isfinite(near)
    return np.column_stack([segments[seen, :4], near[seen]])


def cull_segments(
    segments: np.ndarray, origin: np.ndarray, max_range: float
) -> np.ndarray:
    """Segments (N, 4: x1 y1 x2 y2) that come within ``max_range`` of ``origin``."""
    if len(segments) == 0:
        return segments
    p = segments[:, :2]
    e = segments[:, 2:4] - p
    w = origin - p
    length2 = np.einsum("ij,ij->i", e, e)
    s = np.clip(np.einsum("ij,ij->i", w, e) / np.where(length2 > 0, length2, 1.0), 0.0, 1.0)
    closest = p + s[:, None] * e - origin
    return segments[np.einsum("ij,ij->i", closest, closest) <= max_range * max_range]


def ray_segment_hits(
    origin: np.ndarray, angles: np.ndarray, segments: np.ndarray
) -> np.ndarray:
    """(B, N): distance (m) along each ray from ``origin`` at world ``angles`` (rad) to
    each segment, ``inf`` where it misses. Shapes: origin (2,) shared by all rays or
    (B, 2) one per ray, angles (B,), segments (N, 4), or (N, 5) with the distance each is
    in view from (:func:`visible_segments`)."""
    dx, dy = np.cos(angles)[:, None], np.sin(angles)[:, None]
    ox, oy = _origin_columns(origin)
    px, py = segments[:, 0] - ox, segments[:, 1] - oy
    ex, ey = segments[:, 2] - segments[:, 0], segments[:, 3] - segments[:, 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        inv_denom = 1.0 / (dx * ey - dy * ex)
        t = (px * ey - py * ex) * inv_denom
        s = (px * dy - py * dx) * inv_denom
    hit = (t >= 0.0) & (s >= 0.0) & (s <= 1.0)
    if segments.shape[1] > 4:
        hit &= t >= segments[:, 4]
    return np.where(hit, t, INF)


def ray_segment_distances(
    origin: np.ndarray, angles: np.ndarray, segments: np.ndarray
) -> np.ndarray:
    """(B,): distance along each ray to the nearest segment (:func:`ray_segment_hits`);
    ``inf`` where a ray meets none."""
    if len(segments) == 0:
        return np.full(angles.shape, INF)
    return ray_segment_hits(origin, angles, segments).min(axis=1)


def ray_circle_hits(
    origin: np.ndarray, angles: np.ndarray, circles: np.ndarray
) -> np.ndarray:
    """(B, M): distance along each ray to each circle's near side (M, 3: cx cy r), ``inf``
    where it misses. A circle that contains the origin is not seen (the ray starts
    inside it)."""
    dx, dy = np.cos(angles)[:, None], np.sin(angles)[:, None]
    ox, oy = _origin_columns(origin)
    wx, wy = circles[:, 0] - ox, circles[:, 1] - oy
    r2 = circles[:, 2] ** 2
    along = dx * wx + dy * wy
    off2 = (wx * wx + wy * wy) - along * along
    with np.errstate(invalid="ignore"):
        t = along - np.sqrt(r2 - off2)
    return np.where((off2 <= r2) & (t >= 0.0), t, INF)


def ray_circle_distances(
    origin: np.ndarray, angles: np.ndarray, circles: np.ndarray
) -> np.ndarray:
    """(B,): distance along each ray to the nearest circle (:func:`ray_circle_hits`);
    ``inf`` if none."""
    if len(circles) == 0:
        return np.full(angles.shape, INF)
    return ray_circle_hits(origin, angles, circles).min(axis=1)


def ray_distances(
    origin: np.ndarray,
    angles: np.ndarray,
    segments: np.ndarray,
    circles: np.ndarray,
    max_range: float,
) -> np.ndarray:
    """Nearest hit over walls and round bodies within ``max_range`` (else ``inf``).
    ``origin`` is (2,) or (B, 2); per-ray origins are culled around their mean."""
    origin = np.asarray(origin, dtype=float)
    if origin.ndim == 1:
        near = cull_segments(segments, origin, max_range)
    else:
        centre = origin.mean(axis=0)
        spread = float(np.sqrt(((origin - centre) ** 2).sum(axis=1).max()))
        near = cull_segments(segments, centre, max_range + spread)
    distance = np.minimum(
        ray_segment_distances(origin, angles, near),
        ray_circle_distances(origin, angles, circles),
    )
    distance[distance > max_range] = INF
    return distance


def cone_nearest_distance(
    origin: np.ndarray,
    heading: float,
    half_angle: float,
    segments: np.ndarray,
    circles: np.ndarray,
) -> float:
    """Distance (m) from ``origin`` to the nearest point of any wall or body inside the
    cone ``heading +- half_angle`` (rad, < pi/2): what an ultrasonic sensor reports.

    Exact, not sampled: the part of a segment inside the cone is a sub-segment (the
    segment clipped by the cone's two edge half-planes), and its nearest point to the
    apex is the segment's closest point clamped into that part. A segment in view only
    from a distance (a fifth column, :func:`visible_segments`) is seen there if its part
    in the cone reaches that far. For a disc, it is the point towards its centre if the
    centre is inside the cone, else where a cone edge first meets the disc.
    """
    cos_half = np.cos(half_angle)
    ux, uy = np.cos(heading), np.sin(heading)
    best = INF
    if len(segments):
        best = float(_cone_segment_distances(origin, heading, half_angle, segments).min())
    if len(circles):
        w = circles[:, :2] - origin
        centre_dist = np.hypot(w[:, 0], w[:, 1])
        inside = (w[:, 0] * ux + w[:, 1] * uy) >= cos_half * centre_dist
        surface = centre_dist - circles[:, 2]
        ok = inside & (surface >= 0)
        if ok.any():
            best = min(best, float(surface[ok].min()))
        edges = np.array([heading - half_angle, heading + half_angle])
        best = min(best, float(ray_circle_distances(origin, edges, circles).min()))
    return best


def _cone_segment_distances(origin: np.ndarray, heading: float, half_angle: float,
                            segments: np.ndarray) -> np.ndarray:
    """Per segment, the distance from the apex to its nearest point inside the cone that
    is in view (``inf`` if none)."""
    p = segments[:, :2] - origin
    e = segments[:, 2:4] - segments[:, :2]
    lo, hi = np.zeros(len(segments)), np.ones(len(segments))
    for side in (1.0, -1.0):  # inward normals of the two edges of the wedge
        edge = heading + side * half_angle
        normal = side * np.array([np.sin(edge), -np.cos(edge)])
        start = p @ normal  # f(s) = start + s * rate >= 0 inside
        rate = e @ normal
        with np.errstate(divide="ignore", invalid="ignore"):
            crossing = -start / rate
        lo = np.where(rate > 0, np.maximum(lo, crossing), lo)
        hi = np.where(rate < 0, np.minimum(hi, crossing), hi)
        outside = (rate == 0) & (start < 0)
        hi = np.where(outside, -1.0, hi)
    inside = lo <= hi
    length2 = np.maximum(np.einsum("ij,ij->i", e, e), 1e-18)
    closest = np.clip(-np.einsum("ij,ij->i", p, e) / length2, lo, hi)
    near = np.hypot(*(p + closest[:, None] * e).T)
    far = np.maximum(np.hypot(*(p + lo[:, None] * e).T), np.hypot(*(p + hi[:, None] * e).T))
    if segments.shape[1] > 4:
        in_view = segments[:, 4]
        inside &= far >= in_view
        near = np.maximum(near, in_view)
    return np.where(inside, near, INF)
