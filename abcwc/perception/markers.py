"""Fixed markers: ArUco markers on the building's walls at surveyed places, and what the
chair's camera makes of them, a range and a bearing to each one it reads.

A sighting of a marker whose place is known is an absolute fix: the filter
(:meth:`abcwc.estimation.ekf.ChairEkf.update_landmark`) compares it with the range and
bearing it expects from where it thinks the chair is. The range and bearing come from
the marker's pose (:func:`~abcwc.perception.tags.square_pose`), measured only while the
marker spans :data:`~abcwc.perception.tags.MIN_POSE_SIDE_PX` or more, where the tag
sweep (chapter 17) measured the range within 1.7 % and the bearing within 0.03 deg.
Their noise is modelled as 1.5 % of the range and 0.3 deg of bearing: the sweep's range
error, and a bearing error ten times the sweep's for the camera's mounting and
calibration, which the simulator does not perturb but a real chair does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from abcwc.perception.camera import PinholeCamera
from abcwc.perception.tags import (
    MIN_POSE_SIDE_PX,
    aruco_marker_image,
    detect_aruco_markers,
    printed_marker_width,
    square_pose,
)
from abcwc.types import CameraImage

RANGE_STD = 0.015
"""Relative: the range's standard deviation is this times the range."""
BEARING_STD = math.radians(0.3)
"""rad: the bearing's standard deviation."""


@dataclass(frozen=True)
class FixedMarker:
    """ArUco marker ``marker_id`` on a wall, its black square ``side`` m across, its
    centre at ``centre`` (x, y, z m, map frame), its face turned to ``facing`` (rad)."""

    marker_id: int
    centre: tuple[float, float, float]
    facing: float
    side: float = 0.3

    def __post_init__(self) -> None:
        aruco_marker_image(self.marker_id, cell_px=1)  # refuses an id not in the dictionary
        if not (math.isfinite(self.side) and self.side > 0):
            raise ValueError(f"side must be a finite number > 0 m, got {self.side!r}")

    @property
    def width(self) -> float:
        """m across the printed marker with its white quiet zone."""
        return printed_marker_width(self.side)

    def image(self) -> np.ndarray:
        """The printed marker, quiet zone included (grey, uint8)."""
        return aruco_marker_image(self.marker_id)


@dataclass(frozen=True)
class MarkerSighting:
    """Marker ``marker_id`` seen at ``range`` m and ``bearing`` rad (left positive) from
    the camera, ``side_px`` px across, in the image taken at ``stamp`` s."""

    marker_id: int
    range: float
    bearing: float
    side_px: float
    stamp: float

    @property
    def covariance(self) -> np.ndarray:
        """2 x 2 covariance of (range, bearing): the module's noise model."""
        return np.diag([(RANGE_STD * self.range) ** 2, BEARING_STD ** 2])


def sight_markers(image: CameraImage, markers: dict[int, FixedMarker],
                  min_side_px: float = MIN_POSE_SIDE_PX) -> list[MarkerSighting]:
    """The known ``markers`` (by id) read in ``image`` wide enough to range
    (``min_side_px``), each with its range and bearing from the camera."""
    camera = PinholeCamera.of_image(image)
    found = []
    for tag in detect_aruco_markers(image.pixels):
        marker = markers.get(tag.marker_id)
        if marker is None or tag.side_px < min_side_px:
            continue
        pose = square_pose(tag.corners, marker.side, camera)
        found.append(MarkerSighting(tag.marker_id, pose.range, pose.bearing, tag.side_px,
                                    image.stamp))
    return found


__all__ = ["BEARING_STD", "RANGE_STD", "FixedMarker", "MarkerSighting", "sight_markers"]
