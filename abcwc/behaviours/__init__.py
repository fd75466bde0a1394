"""Behaviours: frame in, command out, with a status, a rate, reset and cancel.

:mod:`abcwc.behaviours.base` holds the interface (:class:`Behaviour`,
:class:`BehaviourBase`, :class:`Status`); the behaviours are the landmark goers, the
waypoint follower and the UMBmark square driver (and, in :mod:`abcwc.navigation`, the
sonar avoider).
"""

from abcwc.behaviours.base import LOOP_RATE_HZ, Behaviour, BehaviourBase, Status
from abcwc.behaviours.landmark import (
    GoalBehaviour,
    GoToLandmark,
    PoseEstimator,
    ThesisGoToLandmark,
    distance_and_bearing,
)
from abcwc.behaviours.square import SquareDriver
from abcwc.behaviours.waypoints import FollowWaypoints, GroundTruth, floor_mixed_drive

__all__ = ["LOOP_RATE_HZ", "Behaviour", "BehaviourBase", "FollowWaypoints", "GoToLandmark",
           "GoalBehaviour", "GroundTruth", "PoseEstimator", "SquareDriver", "Status",
           "ThesisGoToLandmark", "distance_and_bearing", "floor_mixed_drive"]
