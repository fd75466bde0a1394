"""A run's record: every control period's command and sensor frame as NumPy arrays.

:meth:`RunLog.save` writes one ``.npz`` file that :meth:`RunLog.load` reads back, so a
class can share one recorded drive and replay it through the estimators.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from abcwc.types import LaserScan, PotCommand, SensorFrame, Twist

FORMAT_VERSION = 1


@dataclass
class ScanLog:
    """Scans from one sensor: stamps (K,) and ranges (K, B) plus the beam layout."""

    stamps: np.ndarray
    ranges: np.ndarray
    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float

    def scan(self, k: int) -> LaserScan:
        """Scan ``k`` as a LaserScan."""
        return LaserScan(self.angle_min, self.angle_increment, self.range_min,
                         self.range_max, self.ranges[k], float(self.stamps[k]))


@dataclass
class RunLog:
    """Arrays of length N, one row per control period (SI units).

    ``cmd_pots`` is the command the host sent (-1 where it sent nothing), ``cmd_twist``
    the Twist it asked for (NaN where it sent pots or nothing), ``pots`` what the
    board actually put on the motor controller. ``pose`` is the ground truth (NaN on a
    real chair).
    """

    t: np.ndarray
    ticks: np.ndarray  # (N, 2) left, right
    gyro_z: np.ndarray
    sonar: np.ndarray
    ir: np.ndarray  # (N, 6)
    joystick: np.ndarray  # (N, 2) fb, lr
    pots: np.ndarray  # (N, 2) fb, lr
    cmd_pots: np.ndarray  # (N, 2)
    cmd_twist: np.ndarray  # (N, 2) v, w
    flags: np.ndarray
    bad_frames: np.ndarray
    pose: np.ndarray  # (N, 3)
    collisions: np.ndarray
    meta: dict = field(default_factory=dict)
    lidar: ScanLog | None = None
    depth_scan: ScanLog | None = None

    def __len__(self) -> int:
        return len(self.t)

    @property
    def period(self) -> float:
        """Control period (s)."""
        return float(self.meta.get("period", np.median(np.diff(self.t)) if len(self) > 1 else 0))

    def distance_travelled(self) -> float:
        """Length of the true path (m)."""
        steps = np.diff(self.pose[:, :2], axis=0)
        return float(np.hypot(steps[:, 0], steps[:, 1]).sum())

    def summary(self) -> str:
        """One line: duration, distance, collisions."""
        return (f"{self.t[-1] - self.t[0] + self.period:.1f} s, "
                f"{self.distance_travelled():.2f} m driven, "
                f"{int(self.collisions[-1]) if len(self) else 0} collisions")

    def save(self, path: str | Path) -> Path:
        """Write the log to ``path`` (``.npz``); returns the path written."""
        path = Path(path)
        arrays = {f.name: getattr(self, f.name) for f in fields(self)
                  if isinstance(getattr(self, f.name), np.ndarray)}
        for name in ("lidar", "depth_scan"):
            scans = getattr(self, name)
            if scans is not None:
                arrays[f"{name}__stamps"] = scans.stamps
                arrays[f"{name}__ranges"] = scans.ranges
                arrays[f"{name}__layout"] = np.array(
                    [scans.angle_min, scans.angle_increment, scans.range_min, scans.range_max])
        meta = dict(self.meta, format_version=FORMAT_VERSION)
        arrays["meta"] = np.array(json.dumps(meta, sort_keys=True))
        np.savez_compressed(path, **arrays)
        return path if path.suffix == ".npz" else path.with_suffix(path.suffix + ".npz")

    @classmethod
    def load(cls, path: str | Path) -> RunLog:
        """Read a log written by :meth:`save`."""
        with np.load(Path(path), allow_pickle=False) as data:
            meta = json.loads(str(data["meta"]))
            if meta.get("format_version") != FORMAT_VERSION:
                raise ValueError(f"{path}: log format {meta.get('format_version')!r}, "
                                 f"this abcwc reads version {FORMAT_VERSION}")
            kwargs = {f.name: data[f.name] for f in fields(cls)
                      if f.name in data.files and f.name != "meta"}
            for name in ("lidar", "depth_scan"):
                if f"{name}__stamps" in data.files:
                    layout = data[f"{name}__layout"]
                    kwargs[name] = ScanLog(data[f"{name}__stamps"], data[f"{name}__ranges"],
                                           *map(float, layout))
        return cls(meta=meta, **kwargs)


class LogRecorder:
    """Collects frames and commands row by row, then builds a RunLog."""

    def __init__(self, meta: dict | None = None):
        self.meta = dict(meta or {})
        self._rows: list[tuple] = []
        self._scans: dict[str, list[LaserScan]] = {"lidar": [], "depth_scan": []}

    def add(self, frame: SensorFrame, command: PotCommand | Twist | None,
            sent_pots: PotCommand | None) -> None:
        """Record one period: the frame after it, the command sent, its pot bytes."""
        pose = frame.pose
        twist = command if isinstance(command, Twist) else None
        self._rows.append((
            frame.t, frame.ticks_left, frame.ticks_right, frame.gyro_z, frame.sonar,
            *frame.ir, frame.joystick_fb, frame.joystick_lr, frame.pot_fb, frame.pot_lr,
            sent_pots.fb if sent_pots else -1, sent_pots.lr if sent_pots else -1,
            twist.v if twist else np.nan, twist.w if twist else np.nan,
            int(frame.flags), frame.bad_frames,
            pose.x if pose else np.nan, pose.y if pose else np.nan,
            pose.theta if pose else np.nan, frame.collisions,
        ))
        for name in ("lidar", "depth_scan"):
            scan = getattr(frame, name)
            seen = self._scans[name]
            if scan is not None and (not seen or seen[-1] is not scan):
                seen.append(scan)

    def build(self) -> RunLog:
        """The RunLog of everything added so far."""
        a = np.array(self._rows, dtype=float).reshape(-1, 25)
        as_int = lambda cols: a[:, cols].astype(np.int64)  # noqa: E731
        scan_logs = {}
        for name, scans in self._scans.items():
            if scans:
                first = scans[0]
                scan_logs[name] = ScanLog(
                    np.array([s.stamp for s in scans]), np.stack([s.ranges for s in scans]),
                    first.angle_min, first.angle_increment, first.range_min, first.range_max)
        return RunLog(
            t=a[:, 0], ticks=as_int([1, 2]), gyro_z=a[:, 3], sonar=a[:, 4], ir=a[:, 5:11],
            joystick=as_int([11, 12]), pots=as_int([13, 14]), cmd_pots=as_int([15, 16]),
            cmd_twist=a[:, 17:19], flags=as_int(19), bad_frames=as_int(20), pose=a[:, 21:24],
            collisions=as_int(24), meta=self.meta, **scan_logs,
        )
