"""People who walk fixed paths: kinematic discs the sensors see and the chair can hit.

A walker heads for its next waypoint at constant speed and, at the end of its path,
loops back to the start or turns round, standing ``TURN_TIME`` s to do so. It does not
steer round the chair, and it steps
across the chair's way without slowing: keeping clear of people is the chair's job. But
it looks where it walks, as people do: when the chair stands in its way within
``LOOK_AHEAD`` m ahead, or would pass closer than ``PASSING_CLEARANCE`` to its side, it
stops there, and if the way is still blocked after ``WAIT_PATIENCE``
s it turns back the way it came. A person who is bumped (from the side or behind, where
they do not look) stops too: a walker touching the chair stands still for
``BUMP_PAUSE`` s, then turns back. (A kinematic body has infinite mass; without this a
walker would shove a chair and its passenger down a corridor for as long as it walked,
or lean on a standing chair for ever.)
"""

from __future__ import annotations

import math

import numpy as np
import pymunk

from abcwc.geometry import wrap_angle
from abcwc.sim.colour_camera import PlanarTarget
from abcwc.sim.world import PersonSpec

PERSON_COLLISION_TYPE = 3
TAG_HEIGHT = 0.9
"""m: the centre of the card a person wears on their back; the marker at the card's foot
is then at about the height of the chair's camera (0.76 m), and the card stays in view
from 0.6 m."""
BUMP_PAUSE = 1.0
"""s a walker stands still after touching the chair."""
LOOK_AHEAD = 0.4
"""m ahead (gap between body and chair) at which a walker stops for the chair in its way."""
PASSING_CLEARANCE = 0.1
"""m a walker keeps from the chair to either side as it passes (it does not brush by)."""
WAIT_PATIENCE = 2.0
"""s a walker waits for the chair to clear its way before it turns back."""
TURN_TIME = 0.8
"""s a walker stands to turn round (at the end of its path, or to go back the way it
came): a person walking at 1 m/s needs about this long to stop, turn and set off again
(people brake and accelerate at 1-2 m/s^2), and does not reverse in an instant."""


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
        self._waited = 0.0  # s stood so far for a blocked way
        self._touching = False  # in contact with the chair at the last step
        self._facing = self.heading()  # the way the walker last faced
        self._card = spec.tag.image() if spec.tag is not None else None

    def heading(self) -> tuple[float, float]:
        """Unit vector towards the waypoint the walker is making for ((0, 0) on it)."""
        x, y = self.body.position
        tx, ty = self._waypoints[self._target]
        distance = math.hypot(tx - x, ty - y)
        if distance < 1e-9:
            return 0.0, 0.0
        return (tx - x) / distance, (ty - y) / distance

    def steer(self, dt: float, touching: bool = False, way_blocked: bool = False) -> None:
        """Set the velocity for the next ``dt`` seconds towards the current waypoint, or
        zero while pausing after touching the chair (``touching``: in contact now) or
        while the chair blocks the way ahead (``way_blocked``: seen along
        :meth:`heading` within ``LOOK_AHEAD``)."""
        if touching and not self._touching:  # a new bump: not one it stood through
            self._turn_back()
            self._paused = max(BUMP_PAUSE, self._paused)
        self._touching = touching
        if self._paused > 0.0:
            self._paused -= dt
            self.body.velocity = (0.0, 0.0)
            return
        if way_blocked:
            self._waited += dt
            if self._waited >= WAIT_PATIENCE:
                self._waited = 0.0
                self._turn_back()
            self.body.velocity = (0.0, 0.0)
            return
        self._waited = 0.0
        x, y = self.body.position
        tx, ty = self._waypoints[self._target]
        distance = math.hypot(tx - x, ty - y)
        if distance < self.spec.speed * dt:
            self._advance_target()
            tx, ty = self._waypoints[self._target]
            distance = math.hypot(tx - x, ty - y)
        if distance < 1e-9 or self._paused > 0.0:  # on the spot, or turning round
            self.body.velocity = (0.0, 0.0)
            return
        scale = self.spec.speed / distance
        self.body.velocity = ((tx - x) * scale, (ty - y) * scale)

    def _turn_back(self) -> None:
        """Head for the waypoint behind instead of the one ahead, standing ``TURN_TIME``
        s to turn round."""
        self._direction = -self._direction
        self._target = (self._target + self._direction) % len(self._waypoints)
        self._paused = max(self._paused, TURN_TIME)

    def _advance_target(self) -> None:
        """On to the next waypoint, standing to turn: ``TURN_TIME`` for a full turn round,
        in proportion for a sharp corner (none for one under 90 degrees)."""
        last = len(self._waypoints) - 1
        reached = self._waypoints[self._target]
        came_from = self._waypoints[(self._target - self._direction) % (last + 1)]
        if self.spec.loop:
            self._target = (self._target + self._direction) % (last + 1)
        else:
            if not 0 <= self._target + self._direction <= last:
                self._direction = -self._direction
            self._target += self._direction
        going_to = self._waypoints[self._target]
        turn = abs(wrap_angle(
            math.atan2(going_to[1] - reached[1], going_to[0] - reached[0])
            - math.atan2(reached[1] - came_from[1], reached[0] - came_from[0])))
        if turn > math.pi / 2:
            self._paused = max(self._paused, TURN_TIME * turn / math.pi)

    def tag_target(self) -> PlanarTarget | None:
        """The card on the walker's back (None without one): facing backwards, just
        clear of the body's disc, centred at ``TAG_HEIGHT``."""
        if self._card is None or self.spec.tag is None:
            return None
        hx, hy = self.heading()
        if hx or hy:
            self._facing = (hx, hy)
        fx, fy = self._facing
        x, y = self.body.position
        back = self.spec.radius + 0.01
        return PlanarTarget(f"{self.spec.name}'s tag", self._card, self.spec.tag.width,
                            (x - back * fx, y - back * fy, TAG_HEIGHT),
                            math.atan2(-fy, -fx))

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
