"""Navigation: the sonar avoider, and costmaps (:mod:`abcwc.navigation.costmap`) for the
planners to come."""

from abcwc.navigation.sonar_avoid import SonarAvoider

__all__ = ["SonarAvoider"]
