"""A chair's run as a laser log: the scans of one sensor in a RunLog, with the poses they
were taken at, in the shape SLAM reads (:class:`abcwc.mapping.carmen.CarmenLog`).

The same front and back end then map a real robot's CARMEN log and a drive of the
simulated chair. The poses are the chair's own estimate (wheel odometry, the EKF), never
the simulator's truth unless asked: SLAM is there to correct them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from abcwc.log import RunLog
from abcwc.mapping.carmen import CarmenLog
from abcwc.mapping.grid import scan_rows
from abcwc.params import ChairParams, default_params
from abcwc.types import LIDAR_FRAME


def laser_log_from_run(log: RunLog, poses: np.ndarray, frame_id: str = LIDAR_FRAME,
                       params: ChairParams | None = None) -> CarmenLog:
    """The scans of ``frame_id`` in ``log`` with the chair's pose at each (``poses``: (N,
    3) map poses, one per log row, e.g. ``odometry_from_log(log)``), the scanner's mount
    from ``params``. Readings outside the scanner's range (``inf``, ``-inf``) are masked,
    as a CARMEN log's no-return readings are dropped."""
    p = params or default_params()
    poses = np.asarray(poses, dtype=float)
    if poses.shape != (len(log), 3) or not np.isfinite(poses).all():
        raise ValueError(f"poses must be finite (N, 3), one per log row ({len(log)}), "
                         f"got {poses.shape}")
    scans = log.scans.get(frame_id)
    if scans is None:
        raise ValueError(f"the log has no scans of {frame_id!r}; it has {sorted(log.scans)}")
    rows = scan_rows(log, frame_id)
    count, beams = scans.ranges.shape
    ranges = np.ma.masked_invalid(np.where(np.isfinite(scans.ranges), scans.ranges, np.nan))
    return CarmenLog(
        path=Path(f"<run: {frame_id}>"), laser_message=frame_id,
        stamps=np.asarray(scans.stamps, dtype=float), odometry=poses[rows],
        laser_offset=np.asarray(p.sensors[frame_id].mount, dtype=float),  # type: ignore[union-attr]
        angle_min=np.full(count, scans.angle_min), angle_increment=np.full(count,
                                                                           scans.angle_increment),
        range_max=np.full(count, scans.range_max), beams=np.full(count, beams),
        ranges=ranges, odom_stamps=np.zeros(0), odom_poses=np.zeros((0, 3)))
