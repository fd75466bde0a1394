"""A pinhole camera's intrinsics, as a calibration file gives them (ROS CameraInfo's K)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from abcwc.params import RangeSensorParams
from abcwc.types import CameraImage


@dataclass(frozen=True)
class PinholeCamera:
    """Intrinsics of an image ``width`` x ``height`` px with focal lengths ``fx``, ``fy``
    and principal point ``cx``, ``cy`` (px)."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float

    @classmethod
    def from_fov(cls, width: int, height: int, horizontal_fov_deg: float,
                 vertical_fov_deg: float) -> PinholeCamera:
        """The camera whose image spans the given fields of view (degrees) edge to edge."""
        fx = width / 2 / math.tan(math.radians(horizontal_fov_deg) / 2)
        fy = height / 2 / math.tan(math.radians(vertical_fov_deg) / 2)
        return cls(width, height, fx, fy, (width - 1) / 2, (height - 1) / 2)


    @classmethod
    def of_image(cls, image: CameraImage) -> PinholeCamera:
        """The camera that took ``image`` (its size and the intrinsics it carries)."""
        height, width = image.pixels.shape[:2]
        return cls(width, height, image.fx, image.fy, image.cx, image.cy)


def kinect_camera(params: RangeSensorParams, width: int = 640) -> PinholeCamera:
    """The chair's depth camera (``params.depth_scan``: its 57 x 43 degree view) at
    ``width`` px across (640 as the Kinect; less for speed), 4:3."""
    return PinholeCamera.from_fov(width, width * 3 // 4, params.fov_deg,
                                  params.vertical_fov_deg)


def to_gray(image: np.ndarray | CameraImage) -> np.ndarray:
    """A uint8 grey image from a grey or RGB uint8 array or a :class:`CameraImage`
    (RGB to grey with OpenCV's ITU-R BT.601 weights)."""
    pixels = image.pixels if isinstance(image, CameraImage) else np.asarray(image)
    if pixels.dtype != np.uint8:
        raise ValueError(f"image must be uint8, got {pixels.dtype}")
    if pixels.ndim == 3:
        return cv2.cvtColor(np.ascontiguousarray(pixels), cv2.COLOR_RGB2GRAY)
    return pixels
