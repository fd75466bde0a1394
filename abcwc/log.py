"""A run's record: named channels of NumPy arrays, one row per control period.

Every channel shares the time stamps of channel ``t``; ``log.ticks`` reads channel
``"ticks"``. :meth:`RunLog.save` writes one ``.npz`` file that :meth:`RunLog.load`
reads back (this format, version 2, and the fixed-field version 1 before it), so a
class can share one recorded drive and replay it through the estimators. Besides the
:data:`CHANNELS` and the frames' other readings, a run may carry text channels of its
controller's own (:meth:`LogRecorder.add`'s ``text``: the mission layer's
``mission_state`` and ``mission``), saved and loaded with the rest. Camera images
are not kept (a 640 x 480 image ten times a second is 300 MB in two minutes): a run
that needs its images keeps the ones it needs itself.
"""

from __future__ import annotations

import json
import zipfile
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from abcwc.types import (
    DEPTH_SCAN_FRAME,
    IR_FRAMES,
    LIDAR_FRAME,
    SONAR_FRAME,
    CameraImage,
    LaserScan,
    PotCommand,
    SensorFrame,
    Twist,
)

FORMAT_VERSION = 2
"""The format :meth:`RunLog.save` writes; :meth:`RunLog.load` also reads version 1."""
READABLE_VERSIONS = (1, 2)

TIME = "t"
"""The channel every other channel's rows are stamped by (s)."""
CHANNELS = {
    "t": "s since start",
    "ticks": "(N, 2) cumulative encoder counts, left and right",
    "gyro_z": "rad/s, counter-clockwise positive",
    "sonar": f"m, the {SONAR_FRAME} reading",
    "ir": "(N, 6) m, the ir_0_link..ir_5_link readings",
    "joystick": "(N, 2) joystick ADC, fb and lr (pot scale)",
    "pots": "(N, 2) pot bytes the board put on the motor controller, fb and lr",
    "cmd_pots": "(N, 2) pot bytes the host sent (after the safety filter), -1 where it "
                "sent nothing",
    "cmd_twist": "(N, 2) the Twist the host sent (v, w; after the safety filter), NaN "
                 "where it sent none or sent pot bytes",
    "wanted_twist": "(N, 2) the Twist the controller wanted (v, w; before the safety "
                    "filter), NaN where it wanted none or wanted pot bytes",
    "safety": "what the safety filter's rules changed in the command, and why: the speed "
              "limit, an obstacle, the joystick or a stale command ('' where none did; "
              "its comfort ramp shows as the gap between wanted_twist and cmd_twist)",
    "flags": "StatusFlags bits",
    "bad_frames": "bad serial frames so far",
    "pose": "(N, 3) ground truth x, y, theta (NaN on a real chair)",
    "collisions": "collisions so far",
}
"""The channels every recorded run has, with their units. A frame's other scalar
readings become channels named by their frame id; its scans become :class:`ScanLog`."""


class LogFileError(ValueError):
    """A file that :meth:`RunLog.load` cannot read as a RunLog: the message names the
    file and what is wrong with it."""


_V1_SCANS = {"lidar": LIDAR_FRAME, "depth_scan": DEPTH_SCAN_FRAME}  # v1 names -> frame ids
_UNSET = object()


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


@dataclass(init=False)
class RunLog:
    """Named channels of length N, one row per control period (SI units; see
    :data:`CHANNELS`), the scans by frame id, and where the run came from (``meta``).

    Channels read as attributes: ``log.t``, ``log.ticks``, ``log.pose`` (the ground
    truth, NaN on a real chair), ``log.cmd_pots``, ...; ``log.lidar`` and
    ``log.depth_scan`` are the scans of ``lidar_link`` and ``depth_scan_link`` (None
    when the sensor was off). ``RunLog(t=..., ticks=..., ...)`` builds a log from
    arrays, and ``dataclasses.replace(log, pose=...)`` a copy with channels replaced.
    """

    channels: dict[str, np.ndarray]
    meta: dict = field(default_factory=dict)
    scans: dict[str, ScanLog] = field(default_factory=dict)

    def __init__(self, channels: dict[str, np.ndarray] | None = None, meta: dict | None = None,
                 scans: dict[str, ScanLog] | None = None, *, lidar: object = _UNSET,
                 depth_scan: object = _UNSET, **named: np.ndarray):
        merged = {**(channels or {}), **named}
        if TIME not in merged:
            raise ValueError(f"a RunLog needs the time channel {TIME!r}; got {sorted(merged)}")
        rows = len(merged[TIME])
        for name, values in merged.items():
            if np.ndim(values) == 0 or len(values) != rows:
                raise ValueError(f"channel {name!r} has {np.shape(values)} values; every "
                                 f"channel needs one row per time stamp ({rows})")
        object.__setattr__(self, "channels", merged)
        self.meta = {} if meta is None else meta
        self.scans = dict(scans or {})
        for v1_name, value in (("lidar", lidar), ("depth_scan", depth_scan)):
            if value is None:
                self.scans.pop(_V1_SCANS[v1_name], None)
            elif value is not _UNSET:
                self.scans[_V1_SCANS[v1_name]] = value  # type: ignore[assignment]

    # ---------------------------------------------------------------- channels
    def __getattr__(self, name: str) -> np.ndarray:
        channels = self.__dict__.get("channels")
        if channels is not None and name in channels:
            return channels[name]
        known = sorted(channels) if channels is not None else []
        raise AttributeError(f"RunLog has no channel or attribute {name!r}; channels: {known}")

    def __setattr__(self, name: str, value: object) -> None:
        channels = self.__dict__.get("channels")
        if channels is not None and name in channels:
            if len(value) != len(self):  # type: ignore[arg-type]
                raise ValueError(f"channel {name!r} needs {len(self)} rows, got {len(value)}")  # type: ignore[arg-type]
            channels[name] = value  # type: ignore[assignment]
        else:
            object.__setattr__(self, name, value)

    def __dir__(self) -> list[str]:
        return sorted(set(super().__dir__()) | set(self.channels))

    def __len__(self) -> int:
        return len(self.channels[TIME])

    @property
    def lidar(self) -> ScanLog | None:
        """The lidar's scans (``lidar_link``), or None."""
        return self.scans.get(LIDAR_FRAME)

    @property
    def depth_scan(self) -> ScanLog | None:
        """The depth camera's scans (``depth_scan_link``), or None."""
        return self.scans.get(DEPTH_SCAN_FRAME)

    def select(self, rows: np.ndarray | slice) -> RunLog:
        """A log of the rows ``rows`` (a boolean mask, indices or a slice) of every
        channel; the scans (stamped on their own) and ``meta`` are kept whole."""
        return RunLog({name: values[rows] for name, values in self.channels.items()},
                      meta=self.meta, scans=self.scans)

    # ---------------------------------------------------------------- summaries
    @property
    def period(self) -> float:
        """Control period (s)."""
        return float(self.meta.get("period", np.median(np.diff(self.t)) if len(self) > 1 else 0))

    @property
    def has_ground_truth(self) -> bool:
        """Whether every row has a finite true pose (the simulator's logs do)."""
        pose = self.channels.get("pose")
        return pose is not None and len(pose) > 0 and bool(np.isfinite(pose).all())

    def distance_travelled(self) -> float:
        """Length of the true path (m); NaN without ground truth."""
        steps = np.diff(self.pose[:, :2], axis=0)
        return float(np.hypot(steps[:, 0], steps[:, 1]).sum())

    def safety_interventions(self) -> int:
        """How many commands the safety filter changed (0 without a ``safety`` channel)."""
        reasons = self.channels.get("safety")
        return 0 if reasons is None else int(np.count_nonzero(reasons != ""))

    def summary(self) -> str:
        """One line: duration, distance (when the truth is known), collisions, and the
        commands the safety filter changed, if any."""
        if len(self) == 0:
            return "empty log: 0 rows"
        driven = (f"{self.distance_travelled():.2f} m driven" if self.has_ground_truth
                  else "distance driven: unknown (no ground truth)")
        collisions = self.channels.get("collisions")
        hits = int(collisions[-1]) if collisions is not None else 0
        line = f"{self.t[-1] - self.t[0] + self.period:.1f} s, {driven}, {hits} collisions"
        changed = self.safety_interventions()
        if not changed:
            return line
        commands = "command" if changed == 1 else "commands"
        return line + f", {changed} {commands} changed by the safety filter"

    # ---------------------------------------------------------------- files
    def save(self, path: str | Path) -> Path:
        """Write the log to ``path`` (``.npz``, format version 2); returns the path written."""
        path = Path(path)
        arrays = {f"channels/{name}": values for name, values in self.channels.items()}
        for frame_id, scans in self.scans.items():
            arrays[f"scans/{frame_id}/stamps"] = scans.stamps
            arrays[f"scans/{frame_id}/ranges"] = scans.ranges
            arrays[f"scans/{frame_id}/layout"] = np.array(
                [scans.angle_min, scans.angle_increment, scans.range_min, scans.range_max])
        meta = dict(self.meta, format_version=FORMAT_VERSION)
        arrays["meta"] = np.array(json.dumps(meta, sort_keys=True))
        arrays["format_version"] = np.array(FORMAT_VERSION)
        np.savez_compressed(path, **arrays)
        return path if path.suffix == ".npz" else path.with_suffix(path.suffix + ".npz")

    @classmethod
    def load(cls, path: str | Path) -> RunLog:
        """Read a log written by :meth:`save` (format version 2) or by abcwc's first
        format (version 1, one array per fixed field).

        A missing file is a ``FileNotFoundError``, a folder an ``IsADirectoryError``; a
        file that is not an ``.npz``, or an ``.npz`` that is not a RunLog, a
        :class:`LogFileError`. Each names the file and the problem."""
        path = Path(path)
        if path.is_dir():
            raise IsADirectoryError(f"{path}: a folder, not a RunLog file (.npz)")
        if not path.exists():
            raise FileNotFoundError(f"{path}: no such file (a RunLog is an .npz from "
                                    "RunLog.save)")
        try:
            data = np.load(path, allow_pickle=False)
        except (ValueError, EOFError, zipfile.BadZipFile):  # numpy's own words mislead here
            raise LogFileError(f"{path}: not an .npz file (a RunLog is an .npz from "
                               "RunLog.save)") from None
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise LogFileError(f"{path}: a single NumPy array (.npy), not a RunLog's .npz")
        with data:
            if "meta" not in data.files:
                held = ", ".join(data.files[:5]) + (", ..." if len(data.files) > 5 else "")
                raise LogFileError(f"{path}: an .npz without a RunLog's 'meta' (it holds "
                                   f"{held or 'nothing'}): not a RunLog")
            try:
                meta = json.loads(str(data["meta"]))
                version = (int(data["format_version"]) if "format_version" in data.files
                           else meta.get("format_version"))
            except (ValueError, TypeError, AttributeError) as exc:
                raise LogFileError(f"{path}: its 'meta' is not a RunLog's ({exc})") from None
            if version not in READABLE_VERSIONS:
                raise LogFileError(f"{path}: log format {version!r}, this abcwc reads "
                                   f"versions {', '.join(map(str, READABLE_VERSIONS))}")
            reader = _read_v1 if version == 1 else _read_v2
            try:
                channels, scans = reader(data)
                return cls(channels, meta=meta, scans=scans)
            except (KeyError, ValueError) as exc:
                raise LogFileError(f"{path}: not a RunLog of format {version} "
                                   f"({exc})") from None


def _scan_log(data: np.lib.npyio.NpzFile, prefix: str) -> ScanLog:
    layout = data[f"{prefix}layout"]
    return ScanLog(data[f"{prefix}stamps"], data[f"{prefix}ranges"], *map(float, layout))


def _read_v1(data: np.lib.npyio.NpzFile) -> tuple[dict[str, np.ndarray], dict[str, ScanLog]]:
    """Version 1: one array per RunLog field, scans as ``lidar__stamps`` etc."""
    channels = {name: data[name] for name in CHANNELS if name in data.files}
    scans = {frame_id: _scan_log(data, f"{name}__") for name, frame_id in _V1_SCANS.items()
             if f"{name}__stamps" in data.files}
    return channels, scans


def _read_v2(data: np.lib.npyio.NpzFile) -> tuple[dict[str, np.ndarray], dict[str, ScanLog]]:
    """Version 2: ``channels/<name>`` and ``scans/<frame id>/{stamps,ranges,layout}``."""
    channels = {key.removeprefix("channels/"): data[key] for key in data.files
                if key.startswith("channels/")}
    scans = {key.split("/")[1]: _scan_log(data, key.removesuffix("stamps"))
             for key in data.files if key.startswith("scans/") and key.endswith("/stamps")}
    return channels, scans


class LogRecorder:
    """Collects frames and commands row by row, then builds a RunLog.

    Every frame gives the :data:`CHANNELS`; its readings other than the sonar and the
    IR ring (which are the ``sonar`` and ``ir`` channels) are recorded too: a
    LaserScan into the :class:`ScanLog` of its frame id (each new scan once), any other
    reading into a channel named by its frame id (NaN in rows without one).
    """

    def __init__(self, meta: dict | None = None):
        self.meta = dict(meta or {})
        self._rows: list[tuple] = []
        self._ir_width = 6
        self._scans: dict[str, list[LaserScan]] = {}
        self._extra: dict[str, dict[int, float]] = {}
        self._safety: list[str] = []
        self._wanted: list[tuple[float, float]] = []
        self._text: dict[str, dict[int, str]] = {}

    def add(self, frame: SensorFrame, command: PotCommand | Twist | None,
            sent_pots: PotCommand | None, wanted: PotCommand | Twist | None = None,
            safety: str | None = None, text: Mapping[str, str] | None = None) -> None:
        """Record one period: the frame after it, the command sent, its pot bytes, the
        command the controller wanted (default: the one sent), what the safety
        filter changed (None: nothing) and the controller's own ``text`` fields (name ->
        short text; each a text channel, ``""`` in rows without it)."""
        for name, value in (text or {}).items():
            if name in CHANNELS or not isinstance(name, str) or not isinstance(value, str):
                raise ValueError(f"a text field is a name (not one of the channels "
                                 f"{', '.join(CHANNELS)}) and a str, got {name!r}: {value!r}")
        truth = frame.truth
        pose = truth.pose if truth is not None else None
        twist = command if isinstance(command, Twist) else None
        wanted = command if wanted is None else wanted
        wanted_twist = wanted if isinstance(wanted, Twist) else None
        ir = frame.ir
        self._ir_width = len(ir)
        self._safety.append(safety or "")
        self._wanted.append((wanted_twist.v, wanted_twist.w) if wanted_twist
                            else (np.nan, np.nan))
        self._rows.append((
            frame.t, frame.ticks_left, frame.ticks_right, frame.gyro_z, frame.sonar,
            frame.joystick_fb, frame.joystick_lr, frame.pot_fb, frame.pot_lr,
            sent_pots.fb if sent_pots else -1, sent_pots.lr if sent_pots else -1,
            twist.v if twist else np.nan, twist.w if twist else np.nan,
            int(frame.flags), frame.bad_frames,
            pose.x if pose else np.nan, pose.y if pose else np.nan,
            pose.theta if pose else np.nan, truth.collisions if truth is not None else 0, *ir,
        ))
        row = len(self._rows) - 1
        for name, value in (text or {}).items():
            self._text.setdefault(name, {})[row] = value
        for frame_id, reading in frame.readings.items():
            if frame_id == SONAR_FRAME or frame_id in IR_FRAMES or isinstance(
                    reading, CameraImage):
                continue
            if isinstance(reading, LaserScan):
                seen = self._scans.setdefault(frame_id, [])
                if not seen or seen[-1] is not reading:
                    seen.append(reading)
            else:
                self._extra.setdefault(frame_id, {})[row] = float(reading)  # type: ignore[arg-type]

    def build(self) -> RunLog:
        """The RunLog of everything added so far."""
        a = np.array(self._rows, dtype=float).reshape(-1, 19 + self._ir_width)
        as_int = lambda cols: a[:, cols].astype(np.int64)  # noqa: E731
        channels = {
            "t": a[:, 0], "ticks": as_int([1, 2]), "gyro_z": a[:, 3], "sonar": a[:, 4],
            "ir": a[:, 19:], "joystick": as_int([5, 6]), "pots": as_int([7, 8]),
            "cmd_pots": as_int([9, 10]), "cmd_twist": a[:, 11:13], "flags": as_int(13),
            "bad_frames": as_int(14), "pose": a[:, 15:18], "collisions": as_int(18),
            "wanted_twist": np.array(self._wanted, dtype=float).reshape(-1, 2),
            "safety": np.array(self._safety, dtype=str),
        }
        for frame_id, values in self._extra.items():
            column = np.full(len(a), np.nan)
            column[list(values)] = list(values.values())
            channels[frame_id] = column
        for name, values in self._text.items():
            rows = [""] * len(a)
            for row, value in values.items():
                rows[row] = value
            channels[name] = np.array(rows, dtype=str)
        scans = {}
        for frame_id, seen in self._scans.items():
            first = seen[0]
            scans[frame_id] = ScanLog(
                np.array([s.stamp for s in seen]), np.stack([s.ranges for s in seen]),
                first.angle_min, first.angle_increment, first.range_min, first.range_max)
        return RunLog(channels, meta=self.meta, scans=scans)
