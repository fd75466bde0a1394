"""Behaviours: frame in, command out, with a status, a rate, reset and cancel.

:mod:`abcwc.behaviours.base` holds the interface (:class:`Behaviour`,
:class:`BehaviourBase`, :class:`Status`), below every behaviour: the landmark goers, the
waypoint follower, the UMBmark square driver and the sonar avoider (here), a
recorded drive replayed (:mod:`abcwc.behaviours.recorded`), the navigator
(:mod:`abcwc.behaviours.navigator`), the tag followers (:mod:`abcwc.behaviours.follow`),
the sign seeker (:mod:`abcwc.behaviours.find_sign`), voice control
(:mod:`abcwc.behaviours.voice`) and, over them, the mission layer's errands
(:mod:`abcwc.behaviours.mission`, exported here). None applies the safety filter: the
body's control loop passes every command through it.
"""

from abcwc.behaviours.base import LOOP_RATE_HZ, Behaviour, BehaviourBase, Status
from abcwc.behaviours.landmark import (
    GoalBehaviour,
    GoToLandmark,
    PoseEstimator,
    ThesisGoToLandmark,
    distance_and_bearing,
)
from abcwc.behaviours.mission import (
    LIFT_REQUESTED,
    Mission,
    MissionEvent,
    MissionState,
    PlaceEvent,
    Situation,
    Transition,
    mission_timeline,
    next_state,
)
from abcwc.behaviours.sonar_avoid import SonarAvoider
from abcwc.behaviours.square import SquareDriver
from abcwc.behaviours.waypoints import FollowWaypoints, GroundTruth, floor_mixed_drive

__all__ = ["LIFT_REQUESTED", "LOOP_RATE_HZ", "Behaviour", "BehaviourBase", "FollowWaypoints",
           "GoToLandmark", "GoalBehaviour", "GroundTruth", "Mission", "MissionEvent",
           "MissionState", "PlaceEvent", "PoseEstimator", "Situation", "SonarAvoider",
           "SquareDriver", "Status", "ThesisGoToLandmark", "Transition",
           "distance_and_bearing", "floor_mixed_drive", "mission_timeline", "next_state"]
