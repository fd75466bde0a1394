"""What the chair's cameras see: a depth image turned into a laser scan."""

from abcwc.perception.camera import PinholeCamera, kinect_camera
from abcwc.perception.depth import depth_image_to_scan

__all__ = ["PinholeCamera", "depth_image_to_scan", "kinect_camera"]
