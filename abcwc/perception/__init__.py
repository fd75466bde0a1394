"""What the chair's cameras see: a depth image turned into a laser scan."""

from abcwc.perception.depth import depth_image_to_scan

__all__ = ["depth_image_to_scan"]
