"""Plots and animations of the chair, its world, its sensors and its runs.

Top-down plots use the world (map) frame in metres; every ``plot_*`` function takes an
optional ``ax`` and returns the Axes (``plot_run`` and ``plot_signals`` return the
Figure). Nothing here calls ``plt.show``. A typical cell::

    from abcwc import viz
    chair = abcwc.connect(world="lab", lidar=True)
    log = chair.drive(abcwc.Twist(0.5, 0.2), 10)
    viz.plot_run(log, chair.world)

and for a moving picture, ``HTML(viz.to_html(viz.animate_run(log, chair.world)))``.
"""

from abcwc.viz.animation import animate_run, frame_rows, save_animation, to_html
from abcwc.viz.costmap import (
    costmap_colours,
    plot_costmap,
    plot_dwa,
    plot_footprint,
    plot_occupancy,
)
from abcwc.viz.landmark import plot_distance_and_bearing
from abcwc.viz.mission import plot_state_machine, plot_timeline, probe_rule
from abcwc.viz.scene import (
    ChairArtist,
    chair_outlines,
    collision_rows,
    plot_chair,
    plot_people,
    plot_run,
    plot_trajectory,
    plot_world,
)
from abcwc.viz.sensors import (
    mount_pose,
    plot_log_scan,
    plot_scan,
    plot_sensors,
    scan_row,
    scan_to_points,
)
from abcwc.viz.signals import (
    SIGNALS,
    encoder_velocity,
    plot_safety_filter,
    plot_signals,
    true_velocity,
)

__all__ = [
    "SIGNALS",
    "ChairArtist",
    "animate_run",
    "costmap_colours",
    "chair_outlines",
    "collision_rows",
    "encoder_velocity",
    "plot_distance_and_bearing",
    "plot_state_machine",
    "plot_timeline",
    "probe_rule",
    "frame_rows",
    "mount_pose",
    "plot_chair",
    "plot_costmap",
    "plot_dwa",
    "plot_footprint",
    "plot_occupancy",
    "plot_log_scan",
    "plot_people",
    "plot_run",
    "plot_scan",
    "plot_sensors",
    "plot_safety_filter",
    "plot_signals",
    "plot_trajectory",
    "plot_world",
    "save_animation",
    "scan_row",
    "scan_to_points",
    "to_html",
    "true_velocity",
]
