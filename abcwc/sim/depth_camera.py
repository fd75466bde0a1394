"""A depth camera in the simulator: the Kinect's depth image of a world of walls,
objects between two heights, people and the floor.

A pinhole camera looking straight ahead (no tilt) at ``height`` m: pixel ``(u, v)``
sees along the direction ``((u - cx) / fx, (v - cy) / fy, 1)`` in the optical frame
(x right, y down, z forward; REP 103's ``*_optical_frame``). In the plane, column ``u``
is a ray at bearing ``-atan((u - cx) / fx)`` from the camera's heading; a wall segment
it meets ``t`` m away (horizontally) fills the rows whose ray is at a height inside the
segment's band there: ``height - t (v - cy) / fy`` between its bottom and top. Below
the horizon the floor is seen at ``t = height fy / (v - cy)``. The pixel's value is the
depth ``z`` (m, along the optical axis) of the nearest of these, as a Kinect reports
it; ``nan`` where nothing is within ``max_range`` or nearer than ``min_range``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from abcwc.geometry import compose
from abcwc.perception.camera import PinholeCamera
from abcwc.sim.raycast import cull_segments, ray_circle_hits, ray_segment_hits
from abcwc.types import Pose2D

PERSON_HEIGHT = 1.75
"""m: walking people stand from the floor to this height."""


@dataclass(frozen=True)
class ColumnHits:
    """What each image column's ray meets (the model in the module notes): ``z``
    (W, K), the depth along the optical axis of every wall segment kept (first) and
    every person (last) it meets (``inf``: missed), each standing from ``low`` to
    ``high`` (K,) m; the ``walls`` (N, 4) and their ``bands`` (N, 2) kept after
    culling; and each row's ``slope`` (H,), down per metre of depth."""

    z: np.ndarray
    low: np.ndarray
    high: np.ndarray
    walls: np.ndarray
    bands: np.ndarray
    slope: np.ndarray


def column_hits(camera: PinholeCamera, origin: np.ndarray, heading: float,
                segments: np.ndarray, bands: np.ndarray, circles: np.ndarray,
                reach: float) -> ColumnHits:
    """Every column's ray from a camera at ``origin`` looking along ``heading`` against
    the wall ``segments`` standing between ``bands`` within ``reach`` m (horizontally)
    and the people ``circles`` (M, 3) from the floor to ``PERSON_HEIGHT``."""
    lateral = (np.arange(camera.width) - camera.cx) / camera.fx  # x / z of each column
    bearing = heading - np.arctan(lateral)  # (W,): image x is to the right
    near = cull_segments(np.column_stack([segments, bands]), origin, reach)
    walls, wall_bands = near[:, :4], near[:, 4:]
    circles = np.asarray(circles, dtype=float).reshape(-1, 3)
    # horizontal distance t along each column's ray to every segment and circle
    hits = np.concatenate([ray_segment_hits(origin, bearing, walls),  # (W, N)
                           ray_circle_hits(origin, bearing, circles)], axis=1)  # (W, M)
    # z (along the axis) of a hit t m away horizontally: t cos(bearing - heading)
    along = 1.0 / np.sqrt(1.0 + lateral**2)  # (W,) cos of each column's bearing offset
    low = np.concatenate([wall_bands[:, 0], np.zeros(len(circles))])
    high = np.concatenate([wall_bands[:, 1], np.full(len(circles), PERSON_HEIGHT)])
    slope = (np.arange(camera.height) - camera.cy) / camera.fy  # (H,)
    return ColumnHits(hits * along[:, None], low, high, walls, wall_bands, slope)


def floor_depth(slope: np.ndarray, height: float) -> np.ndarray:
    """(H,) the depth (m) at which each row of a camera ``height`` m up meets the floor
    (``inf`` at and above the horizon)."""
    return np.where(slope > 0, height / np.where(slope > 0, slope, 1.0), np.inf)


def render_depth(camera: PinholeCamera, pose: Pose2D, mount: tuple[float, float, float],
                 height: float, segments: np.ndarray, bands: np.ndarray,
                 circles: np.ndarray, min_range: float, max_range: float) -> np.ndarray:
    """The depth image (height x width, m; ``nan`` for no return) of a camera at
    ``height`` m on the chair at ``pose``, mounted at ``mount`` (x, y, yaw in base_link),
    seeing wall ``segments`` (N, 4) standing between ``bands`` (N, 2), people
    ``circles`` (M, 3: x, y, radius) from the floor to ``PERSON_HEIGHT``, and the floor."""
    sensor = compose(pose, mount)  # x, y, heading in the world
    origin, heading = sensor[:2], sensor[2]
    widest = float(np.abs((np.array([0, camera.width - 1]) - camera.cx) / camera.fx).max())
    seen = column_hits(camera, origin, heading, segments, bands, circles,
                       max_range * math.hypot(1.0, widest))
    # the ray of row v is at height `height - slope z` when z m ahead
    ray_height = height - seen.slope[:, None, None] * seen.z[None, :, :]  # (H, W, K)
    inside = (ray_height >= seen.low) & (ray_height <= seen.high) & np.isfinite(seen.z)[None]
    depth = np.where(inside, seen.z[None], np.inf).min(axis=2, initial=np.inf)  # (H, W)
    floor = floor_depth(seen.slope, height)
    depth = np.minimum(depth, floor[:, None])
    depth[(depth > max_range) | (depth < min_range)] = np.nan
    return depth

