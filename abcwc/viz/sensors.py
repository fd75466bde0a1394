"""What the chair's range sensors see, drawn in the world frame.

A reading is measured from its sensor's mount: the mount (x, y, yaw in base_link,
from :mod:`abcwc.params`) placed at the chair's pose gives the sensor's position and
heading in the world, and a beam at angle ``a`` with range ``r`` ends at
``sensor + r * (cos(heading + a), sin(heading + a))``.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.colors import to_rgba
from matplotlib.patches import Wedge

from abcwc.geometry import compose, transform_points
from abcwc.log import RunLog
from abcwc.params import ChairParams, default_params
from abcwc.sim.sensors import IrRing
from abcwc.types import LaserScan, SensorFrame
from abcwc.viz._common import (
    DEPTH_COLOR,
    IR_COLOR,
    LIDAR_COLOR,
    SONAR_COLOR,
    PoseLike,
    as_pose,
    new_axes,
)

Mount = tuple[float, float, float]


def mount_pose(pose: PoseLike, mount: Mount) -> tuple[float, float, float]:
    """World ``(x, y, heading)`` of a sensor mounted at ``mount`` on a chair at ``pose``:
    ``pose (+) mount`` (heading wrapped to (-pi, pi])."""
    x, y, heading = compose(as_pose(pose), mount)
    return float(x), float(y), float(heading)


def scan_to_points(scan: LaserScan, pose: PoseLike, mount: Mount = (0.0, 0.0, 0.0),
                   ) -> np.ndarray:
    """World points (K, 2) of a scan's returns (:meth:`LaserScan.points`: beams without
    a finite range within the scan's bounds are dropped).

    ``pose`` is the chair's (base_link) pose when the scan was taken and ``mount`` the
    scanner's x, y, yaw in base_link (e.g. ``params.lidar.mount``).
    """
    return transform_points(mount_pose(pose, mount), scan.points())


def plot_scan(scan: LaserScan, pose: PoseLike, mount: Mount, ax: Axes | None = None,
              color: str = LIDAR_COLOR, label: str | None = None, size: float = 4) -> Axes:
    """Draw a scan's returns as dots at their world positions (nothing if none)."""
    ax = new_axes(ax)
    points = scan_to_points(scan, pose, mount)
    if len(points) == 0:
        return ax
    ax.scatter(points[:, 0], points[:, 1], s=size, color=color, linewidths=0, zorder=5,
               label=label)
    return ax


def _frame_of(frame_or_chair: object) -> SensorFrame:
    """The frame itself, or a chair's latest ``.frame``."""
    if isinstance(frame_or_chair, SensorFrame):
        return frame_or_chair
    frame = getattr(frame_or_chair, "frame", None)
    if not isinstance(frame, SensorFrame):
        raise ValueError("plot_sensors needs a SensorFrame or a chair with a .frame, "
                         f"got {type(frame_or_chair).__name__}")
    return frame


def plot_sensors(frame_or_chair: object, ax: Axes | None = None,
                 params: ChairParams | None = None, pose: PoseLike | None = None,
                 sonar: bool = True, ir: bool = True, scans: bool = True) -> Axes:
    """Draw one frame's range readings: sonar cone, IR rays, lidar and depth-scan points.

    The sonar is a wedge of +-half angle out to its reading; each IR ray runs to its
    reading (none for ``inf``, nothing in range; a red dot at the sensor for ``-inf``,
    closer than its minimum). ``pose`` defaults to the frame's ground truth. A live
    frame's scans can be up to one scan period (100 ms) older than its pose, so on a
    moving chair they may sit a few centimetres off the walls; :func:`plot_run` and
    the animations draw logged scans from the pose they were taken at.
    """
    frame = _frame_of(frame_or_chair)
    p = params or getattr(frame_or_chair, "params", None) or default_params()
    pose = pose if pose is not None else (frame.truth.pose if frame.truth else None)
    if pose is None:
        raise ValueError("the frame has no ground-truth pose (a real chair); pass pose=")
    ax = new_axes(ax)
    if sonar:
        _draw_sonar(ax, frame.sonar, pose, p)
    if ir:
        _draw_ir(ax, np.asarray(frame.ir, dtype=float), pose, p)
    if scans and frame.lidar is not None:
        plot_scan(frame.lidar, pose, p.lidar.mount, ax, LIDAR_COLOR, "lidar")
    if scans and frame.depth_scan is not None:
        plot_scan(frame.depth_scan, pose, p.depth_scan.mount, ax, DEPTH_COLOR, "depth scan")
    ax.set_aspect("equal", adjustable="box")
    return ax


def _draw_sonar(ax: Axes, reading: float, pose: PoseLike, p: ChairParams) -> None:
    x, y, heading = mount_pose(pose, p.sonar.mount)
    half = p.sonar.half_angle_deg
    centre = math.degrees(heading)
    ax.add_patch(Wedge((x, y), reading, centre - half, centre + half, zorder=3,
                       facecolor=to_rgba(SONAR_COLOR, 0.25), edgecolor=SONAR_COLOR,
                       linewidth=1.0, label=f"sonar {reading:.2f} m"))


def _draw_ir(ax: Axes, readings: np.ndarray, pose: PoseLike, p: ChairParams) -> None:
    mounts = IrRing(p.ir, np.random.default_rng(0)).mounts
    ends, too_close = [], []
    for (mx, my, yaw), reading in zip(mounts, readings):
        sensor = mount_pose(pose, (mx, my, yaw))
        x, y = sensor[:2]
        if math.isfinite(reading):
            ends.append([(x, y), tuple(transform_points(sensor, (reading, 0.0)))])
        elif reading < 0:
            too_close.append((x, y))
    if ends:
        ax.add_collection(LineCollection(ends, colors=IR_COLOR, linewidths=1.5, zorder=4,
                                         label="IR"))
    if too_close:
        xy = np.array(too_close)
        ax.scatter(xy[:, 0], xy[:, 1], s=18, color="tab:red", zorder=8, label="IR too close")


def scan_row(log: RunLog, name: str, row: int) -> tuple[LaserScan, np.ndarray] | None:
    """The newest ``name`` scan at or before log row ``row`` and the pose it was taken
    from, or None when the log has no such scan yet."""
    scans = getattr(log, name, None)
    if scans is None or len(scans.stamps) == 0:
        return None
    k = int(np.searchsorted(scans.stamps, log.t[row] + 1e-9, side="right")) - 1
    if k < 0:
        return None
    taken = min(int(np.searchsorted(log.t, scans.stamps[k] - 1e-9)), len(log) - 1)
    return scans.scan(k), log.pose[taken]


def plot_log_scan(log: RunLog, row: int, ax: Axes, params: ChairParams | None = None) -> Axes:
    """Draw the newest lidar and depth-camera scans at log row ``row``, when present."""
    p = params or default_params()
    for name, mount, color, label in (("lidar", p.lidar.mount, LIDAR_COLOR, "lidar scan"),
                                      ("depth_scan", p.depth_scan.mount, DEPTH_COLOR,
                                       "depth scan")):
        found = scan_row(log, name, row)
        if found is not None and np.isfinite(found[1]).all():
            plot_scan(found[0], found[1], mount, ax, color, label)
    return ax
