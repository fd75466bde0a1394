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

import numpy as np

from abcwc.perception.camera import PinholeCamera
from abcwc.sim.raycast import cull_segments, ray_circle_hits, ray_segment_hits
from abcwc.sim.sensors import sensor_pose
from abcwc.types import Pose2D

PERSON_HEIGHT = 1.75
"""m: walking people stand from the floor to this height."""


def render_depth(camera: PinholeCamera, pose: Pose2D, mount: tuple[float, float, float],
                 height: float, segments: np.ndarray, bands: np.ndarray,
                 circles: np.ndarray, min_range: float, max_range: float) -> np.ndarray:
    """The depth image (height x width, m; ``nan`` for no return) of a camera at
    ``height`` m on the chair at ``pose``, mounted at ``mount`` (x, y, yaw in base_link),
    seeing wall ``segments`` (N, 4) standing between ``bands`` (N, 2), people
    ``circles`` (M, 3: x, y, radius) from the floor to ``PERSON_HEIGHT``, and the floor."""
    origin, heading = sensor_pose(pose, mount)
    u = np.arange(camera.width)
    v = np.arange(camera.height)
    lateral = (u - camera.cx) / camera.fx  # x / z of each column
    bearing = heading - np.arctan(lateral)  # (W,): image x is to the right
    slope = (v - camera.cy) / camera.fy  # (H,): downward per metre of z
    # horizontal distance t along each column's ray to every segment and circle
    near = cull_segments(np.column_stack([segments, bands]), origin,
                         max_range * math.hypot(1.0, float(np.abs(lateral).max())))
    walls, wall_bands = near[:, :4], near[:, 4:]
    hits = np.concatenate([ray_segment_hits(origin, bearing, walls),  # (W, N)
                           ray_circle_hits(origin, bearing, circles)], axis=1)  # (W, M)
    low = np.concatenate([wall_bands[:, 0], np.zeros(len(circles))])
    high = np.concatenate([wall_bands[:, 1], np.full(len(circles), PERSON_HEIGHT)])
    # z (along the axis) of a hit t m away horizontally: t cos(bearing - heading)
    along = 1.0 / np.sqrt(1.0 + lateral**2)  # (W,) cos of each column's bearing offset
    z_hits = hits * along[:, None]  # (W, K)
    # the ray of row v is at height `height - slope z` when z m ahead
    ray_height = height - slope[:, None, None] * z_hits[None, :, :]  # (H, W, K)
    inside = (ray_height >= low) & (ray_height <= high) & np.isfinite(z_hits)[None]
    depth = np.where(inside, z_hits[None], np.inf).min(axis=2)  # (H, W)
    floor = np.where(slope > 0, height / np.where(slope > 0, slope, 1.0), np.inf)
    depth = np.minimum(depth, floor[:, None])
    depth[(depth > max_range) | (depth < min_range)] = np.nan
    return depth

