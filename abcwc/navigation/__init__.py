"""Navigation behaviours: sonar avoidance now; costmaps and planners later."""

from abcwc.navigation.sonar_avoid import SonarAvoider

__all__ = ["SonarAvoider"]
