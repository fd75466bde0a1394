"""Navigation's parts: costmaps (:mod:`abcwc.navigation.costmap`, with the range-sensor
layer), the global planner (:mod:`abcwc.navigation.planner`), DWA
(:mod:`abcwc.navigation.dwa`), people tracking (:mod:`abcwc.navigation.people`) and map
localisation (:mod:`abcwc.navigation.localization`). The behaviours that use them, the
navigator and the sonar avoider among them, live in :mod:`abcwc.behaviours`."""
