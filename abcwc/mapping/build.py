"""A map from the chair's own drive: graph SLAM over its scans, saved as map_server files.

:func:`build_map` takes the RunLog of a drive (an exploration, :mod:`abcwc.behaviours.
explore`), lays its lidar scans at the chair's own odometry (:func:`abcwc.mapping.
run_scans.laser_log_from_run`; never the simulator's truth), corrects the poses with graph
SLAM (:func:`abcwc.mapping.slam.run_slam`), renders the occupancy grid from every scan
(:func:`abcwc.mapping.slam.render`) and, given a path, writes it as map_server files
(:func:`abcwc.mapping.map_io.save_map`). The map's frame is the one the odometry starts
in: the chair's known start pose.

The keyframes are drawn at their optimised poses, and the scans between them ride on
their keyframe with the chair's own motion since it (:func:`abcwc.mapping.slam.
scan_poses`), not on SLAM's own matches of them: SLAM starts each such match from a pose
interpolated in time between the keyframes either side, which is far off where the chair
turned one way and back between two keyframes (turning to a goal's heading), and ICP
then settles on a wrong fit. Measured on the floor world's tour: 30 of 1100 scans put
0.4 m and 0.5 rad off that way, their walls drawn as streaks across rooms; riding on the
EKF, every scan is within 0.025 m of the truth and every occupied cell within 0.05 m of a
true wall.

:func:`load_built_map` reads a known floor's saved map back in the same shape, so a
navigator (``Navigator.for_map(cells, grid, start)``) is built the same way from either.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from abcwc.estimation.odometry import odometry_from_log
from abcwc.geometry import compose, relative
from abcwc.log import RunLog
from abcwc.mapping.grid import OccupancyGrid
from abcwc.mapping.map_io import load_map, save_map
from abcwc.mapping.run_scans import laser_log_from_run
from abcwc.mapping.slam import SlamResult, SlamSettings, render, run_slam, scan_poses
from abcwc.params import ChairParams
from abcwc.types import LIDAR_FRAME, Pose2D


@dataclass
class BuiltMap:
    """A map built from a drive: trinary ``cells`` (map_server's values) on ``grid``, the
    ``slam`` result (None for a loaded map), the YAML ``path`` it was saved to (or None)
    and, for a built map, ``end_pose``: where the chair stood at the drive's end, in the
    map's frame (the last scan's corrected pose moved on by the chair's own poses since
    it), the pose a navigator on this map starts from."""

    cells: np.ndarray
    grid: OccupancyGrid
    slam: SlamResult | None
    path: Path | None
    end_pose: Pose2D | None = None  # the chair at the log's end, in the map's frame


MAPPING_SLAM = SlamSettings(linear_update=0.5, angular_update=0.4)
"""The SLAM settings for a chair's own drive: a keyframe every 0.5 m or 0.4 rad (the
defaults' 0.2 m and 0.2 rad suit wheel odometry that drifts by metres; the chair's EKF,
matched against its own map as it drove, is within about 0.1 m). On the floor world's
tour this keeps the map's agreement with the true walls and takes a quarter of the time."""


def build_map(log: RunLog, start: Pose2D, path: str | Path | None = None,
              poses: np.ndarray | None = None, params: ChairParams | None = None,
              settings: SlamSettings = MAPPING_SLAM, scan_every: int = 3,
              resolution: float = 0.05, frame_id: str = LIDAR_FRAME) -> BuiltMap:
    """The map of the floor ``log`` drove over (module notes). ``start`` is the chair's
    pose at the log's first row (the map frame's anchor); ``path`` a ``.yaml`` to save
    the map to (with its ``.pgm``); ``poses`` the chair's own estimate at every row
    ((N, 3), e.g. :meth:`Explorer.estimates <abcwc.behaviours.explore.Explorer.
    estimates>`), default the wheel odometry from ``start``. Every ``scan_every``-th
    scan is used (at 10 Hz and 0.8 m/s, one each 0.24 m is plenty for a 12 m lidar)."""
    if not isinstance(start, Pose2D):
        raise ValueError(f"start must be a Pose2D (m, rad), got {start!r}")
    if len(log) < 2:
        raise ValueError(f"the log has {len(log)} rows: a drive to map has many")
    if isinstance(scan_every, bool) or not isinstance(scan_every, int) or scan_every < 1:
        raise ValueError(f"scan_every must be a whole number >= 1, got {scan_every!r}")
    if frame_id not in log.scans:
        raise ValueError(f"the log has no scans of {frame_id!r}; it has {sorted(log.scans)}")
    if poses is None:
        poses = odometry_from_log(log, params, start=start)
    scans = log.scans[frame_id]
    kept = replace(scans, stamps=scans.stamps[::scan_every], ranges=scans.ranges[::scan_every])
    laser = laser_log_from_run(RunLog(log.channels, log.meta, {frame_id: kept}), poses,
                               frame_id, params)
    result = run_slam(laser, settings)
    ridden = scan_poses(result.poses, result.keyframes, laser.odometry)
    grid = render(laser, ridden, resolution=resolution)
    saved = None if path is None else save_map(grid, path)
    last = laser.odometry[-1]  # the chair's own pose at the last scan
    since = relative(last, np.asarray(poses, dtype=float)[-1])
    end = Pose2D(*map(float, compose(ridden[-1], since)))
    return BuiltMap(grid.trinary(), grid, result, saved, end)


def load_built_map(path: str | Path) -> BuiltMap:
    """A known floor's saved map (map_server files) as a :class:`BuiltMap`."""
    grid = load_map(path)
    return BuiltMap(grid.trinary(), grid, None, Path(path))
