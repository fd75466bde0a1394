"""The way a followed person walked: a trail of points in the odom frame, and the point
on it a pure-pursuit follower steers for.

A follower that aims at the person cuts every corner she turns: she steps through a
side door, and the straight line from the chair to her crosses the door's frame. A
follower that drives along the trail she left goes where she went. The trail keeps a
point every ``spacing`` m of her measured centre; the chair steers for the *carrot*, the
first point of the trail at least ``lookahead`` m from it, beyond the trail point nearest
to it (pure pursuit: Coulter, "Implementation of the pure pursuit path tracking
algorithm", CMU-RI-TR-92-01, 1992), and keeps its distance measured *along* the trail:
the length from the point nearest the chair to her, which is the straight-line distance
on a straight way and the way round at a corner. Points the chair has passed are
dropped.
"""

from __future__ import annotations

import math

import numpy as np


class Trail:
    """Where the followed person has walked (odom frame, m): a point every ``spacing``
    m, at most ``max_points`` kept (the oldest dropped first)."""

    def __init__(self, spacing: float = 0.1, max_points: int = 400):
        if not (math.isfinite(spacing) and spacing > 0):
            raise ValueError(f"spacing must be a finite number of m > 0, got {spacing!r}")
        if max_points < 2:
            raise ValueError(f"max_points must be at least 2, got {max_points!r}")
        self.spacing = spacing
        self.max_points = max_points
        self.points = np.zeros((0, 2))

    def __len__(self) -> int:
        return len(self.points)

    def clear(self) -> None:
        self.points = np.zeros((0, 2))

    def add(self, point: np.ndarray | tuple[float, float]) -> None:
        """Extend the trail to ``point`` (m) if it is ``spacing`` or more from its end."""
        point = np.asarray(point, dtype=float).reshape(2)
        if not np.isfinite(point).all():
            raise ValueError(f"a trail point must be finite (x, y) m, got {point!r}")
        if len(self.points) and math.hypot(*(point - self.points[-1])) < self.spacing:
            return
        self.points = np.vstack([self.points, point])[-self.max_points:]

    def nearest(self, at: tuple[float, float]) -> int:
        """Index of the trail point nearest ``at`` (m)."""
        if not len(self.points):
            raise ValueError("the trail is empty")
        return int(np.argmin(np.hypot(*(self.points - at).T)))

    def passed(self, at: tuple[float, float]) -> None:
        """Drop the points before the one nearest ``at`` (the chair's position): the
        chair has come past them."""
        if len(self.points) > 1:
            self.points = self.points[self.nearest(at):]

    def length_from(self, at: tuple[float, float], to: np.ndarray | None = None) -> float:
        """m along the trail from its point nearest ``at`` to its end, plus the step
        from ``at`` to that point, plus the step from the end to ``to`` if given."""
        k = self.nearest(at)
        steps = np.hypot(*np.diff(self.points[k:], axis=0).T).sum()
        length = float(steps) + math.hypot(*(self.points[k] - at))
        if to is not None:
            length += math.hypot(*(np.asarray(to, dtype=float) - self.points[-1]))
        return length

    def carrot(self, at: tuple[float, float], lookahead: float) -> np.ndarray:
        """The pure-pursuit goal for a chair at ``at``: the first trail point beyond the
        one nearest ``at`` that is at least ``lookahead`` m from ``at``; the trail's end
        if none is."""
        k = self.nearest(at)
        ahead = self.points[k:]
        far = np.flatnonzero(np.hypot(*(ahead - at).T) >= lookahead)
        return ahead[far[0]].copy() if len(far) else ahead[-1].copy()

    def ahead_of(self, at: tuple[float, float]) -> np.ndarray:
        """(K, 2) the trail's points from the one nearest ``at`` to its end."""
        return self.points[self.nearest(at):]


__all__ = ["Trail"]
