"""Navigation: the sonar avoider; costmaps (:mod:`abcwc.navigation.costmap`) and the global
planner (:mod:`abcwc.navigation.planner`) for the navigator to come."""

from abcwc.navigation.sonar_avoid import SonarAvoider

__all__ = ["SonarAvoider"]
