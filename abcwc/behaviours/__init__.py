"""Behaviours: controllers that turn a goal into Twist commands every period."""

from abcwc.behaviours.landmark import (
    GoToLandmark,
    PoseEstimator,
    ThesisGoToLandmark,
    distance_and_bearing,
)
from abcwc.behaviours.waypoints import FollowWaypoints, GroundTruth, floor_mixed_drive

__all__ = ["FollowWaypoints", "GoToLandmark", "GroundTruth", "PoseEstimator",
           "ThesisGoToLandmark", "distance_and_bearing", "floor_mixed_drive"]
