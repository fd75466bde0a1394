"""Seeded random views of one flat target (a tag, a sign) in front of the chair's camera,
in an empty room: what the detection sweeps measure against the simulator's truth.

Each view puts the target at a distance drawn uniformly from ``distances`` (m), at a
bearing within ``max_bearing`` (rad) of the camera's axis, turned up to ``max_turn``
(rad) from facing the camera, with its centre at a height drawn from ``heights`` (m),
and renders the grey image with the frame's lighting, blur and noise, all from one
seeded generator.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from abcwc.geometry import compose, wrap_angle
from abcwc.params import ChairParams, default_params
from abcwc.perception.camera import PinholeCamera
from abcwc.sim.colour_camera import Imaging, PlanarTarget, render_colour
from abcwc.sim.world import box_world
from abcwc.types import Pose2D


@dataclass(frozen=True)
class TargetView:
    """One rendered view: the ``gray`` image from ``camera`` at ``origin`` (x, y m) looking
    along ``heading`` (rad), of the target with its centre at ``centre`` (x, y, z m)
    facing ``facing`` (rad), turned ``turn`` (rad) from facing the camera."""

    gray: np.ndarray
    camera: PinholeCamera
    origin: np.ndarray
    heading: float
    centre: tuple[float, float, float]
    facing: float
    turn: float

    def range_and_bearing(self, point: np.ndarray) -> tuple[float, float]:
        """(m, rad left positive) from the camera to ``point`` (x, y m): the truth."""
        gap = np.asarray(point, dtype=float)[:2] - self.origin
        return (float(np.hypot(*gap)),
                wrap_angle(math.atan2(gap[1], gap[0]) - self.heading))


def random_views(image: np.ndarray, width: float, count: int, seed: int,
                 distances: tuple[float, float], max_bearing: float, max_turn: float,
                 heights: tuple[float, float], params: ChairParams | None = None,
                 imaging: Imaging | None = None) -> Iterator[TargetView]:
    """``count`` views of a target showing ``image``, ``width`` m wide (module notes),
    each frame departing from the ideal as ``imaging`` says (the camera's default)."""
    p = params or default_params()
    camera = PinholeCamera.from_fov(640, 480, p.depth_scan.fov_deg, p.depth_scan.vertical_fov_deg)
    room = box_world(24.0, 24.0)
    pose = Pose2D(2.0, 12.0, 0.0)
    sensor = compose(pose, p.depth_scan.mount)  # x, y, heading in the world
    origin, heading = sensor[:2], float(sensor[2])
    rng = np.random.default_rng(seed)
    for _ in range(count):
        distance = rng.uniform(*distances)
        bearing = rng.uniform(-max_bearing, max_bearing)
        turn = rng.uniform(-max_turn, max_turn)
        centre = (origin[0] + distance * math.cos(heading + bearing),
                  origin[1] + distance * math.sin(heading + bearing), rng.uniform(*heights))
        facing = math.atan2(origin[1] - centre[1], origin[0] - centre[0]) + turn
        target = PlanarTarget("target", image, width, centre, facing)
        gray = render_colour(camera, pose, p.depth_scan.mount, p.depth_scan.height,
                             room.walls, room.bands, np.zeros((0, 3)), (target,), rng,
                             imaging=imaging, gray=True)
        yield TargetView(gray, camera, origin, heading, centre, facing, turn)


__all__ = ["TargetView", "random_views"]
