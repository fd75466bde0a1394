"""A depth image as a laser scan, the way ROS's depthimage_to_laserscan makes one.

The thesis fed RTAB-Map and move_base a "fake laser scan" from the Kinect
(3.2.2, its launch file's ``scan_height: 190``). For each column ``u`` of the image,
a pixel at depth ``z`` (m, along the optical axis) lies ``x = (u - cx) z / fx`` to the
right, so at range ``r = sqrt(x^2 + z^2)`` and bearing ``-atan2(x, z)`` (REP 103: the
scan's angles grow to the left). Over a band of ``scan_height`` rows centred on the
principal point, the scan keeps the nearest valid range in each column (one inside
``[range_min, range_max]``); a column with none reads ``inf``. The scan's beams run
evenly from the rightmost column's bearing to the leftmost's, one per column, and each
column lands on the beam nearest its bearing.
"""

from __future__ import annotations

import math

import numpy as np

from abcwc.perception.camera import PinholeCamera
from abcwc.types import LaserScan


def depth_image_to_scan(depth: np.ndarray, camera: PinholeCamera, scan_height: int,
                        range_min: float, range_max: float, stamp: float = 0.0
                        ) -> LaserScan:
    """The fake laser scan of a depth image (H x W, m; ``nan`` or 0 for no return)."""
    depth = np.asarray(depth, dtype=float)
    if depth.shape != (camera.height, camera.width):
        raise ValueError(f"the depth image is {depth.shape}, the camera "
                         f"{camera.height} x {camera.width} (rows x columns)")
    if not (isinstance(scan_height, (int, np.integer)) and 1 <= scan_height <= camera.height):
        raise ValueError(f"scan_height must be a whole number of rows in 1..{camera.height}, "
                         f"got {scan_height!r}")
    if not (0 <= range_min < range_max):
        raise ValueError(f"need 0 <= range_min < range_max (m), got {range_min}, {range_max}")
    top = int(round(camera.cy - scan_height / 2))
    top = min(max(top, 0), camera.height - scan_height)
    band = depth[top:top + scan_height]
    lateral = (np.arange(camera.width) - camera.cx) / camera.fx
    with np.errstate(invalid="ignore"):
        ranges = band * np.sqrt(1.0 + lateral**2)
        valid = np.isfinite(ranges) & (ranges >= range_min) & (ranges <= range_max)
    nearest = np.where(valid, ranges, np.inf).min(axis=0)  # (W,) per column
    bearings = -np.arctan(lateral)
    angle_min, angle_max = float(bearings[-1]), float(bearings[0])
    widest = float(np.max(-np.diff(bearings)))
    beams = int(math.floor((angle_max - angle_min) / widest)) + 1
    increment = (angle_max - angle_min) / (beams - 1)
    index = np.rint((bearings - angle_min) / increment).astype(int)
    out = np.full(beams, math.inf)
    np.minimum.at(out, index, nearest)
    return LaserScan(angle_min, increment, range_min, range_max, out, stamp)
