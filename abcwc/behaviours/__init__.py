"""Behaviours: controllers that turn a goal into Twist commands every period."""

from abcwc.behaviours.landmark import (
    GoToLandmark,
    PoseEstimator,
    ThesisGoToLandmark,
    distance_and_bearing,
)

__all__ = ["GoToLandmark", "PoseEstimator", "ThesisGoToLandmark", "distance_and_bearing"]
