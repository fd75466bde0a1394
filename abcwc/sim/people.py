"""People who walk fixed paths: kinematic discs the sensors see and the chair can hit.

A walker heads for its next waypoint at constant speed and, at the end of its path,
loops back to the start or turns round. It does not avoid the chair: that is the
chair's job. But a person who bumps into something stops: a walker touching the chair
stands still for ``BUMP_PAUSE`` s, then turns back the way it came. (A kinematic body
has infinite mass; without this a walker would shove a chair and its passenger down a
corridor for as long as it walked, or lean on a standing chair for ever.)
"""

from __future__ import annotations

import math

import numpy as np
import pymunk

from abcwc.sim.world import PersonSpec

PERSON_COLLISION_TYPE = 3
BUMP_PAUSE = 1.0
"""s a walker stands still after touching the chair."""


class Walker:
    """One person on a path, as a pymunk kinematic body with a circle shape."""

    def __init__(self, spec: PersonSpec, space: pymunk.Space):
        self.spec = spec
        self.body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
        self.body.position = tuple(spec.path[0])
        self.shape = pymunk.Circle(self.body, spec.radius)
        self.shape.collision_type = PERSON_COLLISION_TYPE
        self.shape.friction = 0.5
        space.add(self.body, self.shape)
        self._waypoints = [tuple(map(float, p)) for p in spec.path]
        self._target = 1
        self._direction = 1
        self._paused = 0.0  # s of standing still left after a bump

    def steer(self, dt: float, touching: bool = False) -> None:
        """Set the velocity for the next ``dt`` seconds towards the current waypoint, or
        zero while pausing after touching the chair (``touching``: in contact now)."""
        if touching and self._paused <= 0.0:
            self._paused = BUMP_PAUSE
            self._turn_back()
        if self._paused > 0.0:
            self._paused -= dt
            self.body.velocity = (0.0, 0.0)
            return
        x, y = self.body.position
        tx, ty = self._waypoints[self._target]
        distance = math.hypot(tx - x, ty - y)
        if distance < self.spec.speed * dt:
            self._advance_target()
            tx, ty = self._waypoints[self._target]
            distance = math.hypot(tx - x, ty - y)
        if distance < 1e-9:
            self.body.velocity = (0.0, 0.0)
            return
        scale = self.spec.speed / distance
        self.body.velocity = ((tx - x) * scale, (ty - y) * scale)

    def _turn_back(self) -> None:
        """Head for the waypoint behind instead of the one ahead."""
        self._direction = -self._direction
        self._target = (self._target + self._direction) % len(self._waypoints)

    def _advance_target(self) -> None:
        last = len(self._waypoints) - 1
        if self.spec.loop:
            self._target = (self._target + self._direction) % (last + 1)
        else:
            if not 0 <= self._target + self._direction <= last:
                self._direction = -self._direction
            self._target += self._direction

    @property
    def circle(self) -> tuple[float, float, float]:
        """(x, y, radius) now."""
        x, y = self.body.position
        return x, y, self.spec.radius


def circles_of(walkers: list[Walker]) -> np.ndarray:
    """(M, 3) array of the walkers' discs."""
    if not walkers:
        return np.zeros((0, 3))
    return np.array([w.circle for w in walkers])
