"""CARMEN laser logs (``.clf``, plain or gzipped): scans with the odometry pose at each.

CARMEN (Montemerlo, Roy and Thrun, IROS 2003) logs one message per line; the SLAM
benchmark of Kümmerle et al. (Autonomous Robots 27(4), 2009) ships its data this way.
Three messages are read, everything else (``#`` comments, ``PARAM`` lines other than
the front laser's offset, maximum range and resolution, other message types) is skipped:

* ``ODOM x y theta tv rv accel timestamp host logger_timestamp``: the odometry stream.
* ``FLASER n r_1 .. r_n x y theta odom_x odom_y odom_theta timestamp host logger_ts``:
  an old-style front-laser scan; ``odom_*`` is the robot's odometry pose at the scan
  (the first pose, the laser's as the logging program saw it, is not used). The line
  carries no geometry, so it is CARMEN's own reader's (``readlog.c``): the first beam
  at -90 degrees, the beams ``laser_front_laser_resolution`` degrees apart where the
  log's PARAM lines say so, else as a SICK LMS logs them (:func:`guess_flaser_increment`:
  180 or 181 readings 1 degree apart, 360 or 361 half a degree, 400 or 401 a quarter;
  any other count spread over 180 degrees). The maximum range is the
  ``robot_front_laser_max`` PARAM, the offset on the robot the
  ``robot_frontlaser_*offset`` PARAMs; a log without them needs ``max_range`` and
  ``laser_offset``.
* ``ROBOTLASER1 laser_type start_angle fov angular_res max_range accuracy remission_mode
  n r_1 .. r_n m e_1 .. e_m laser_x laser_y laser_theta robot_x robot_y robot_theta tv
  rv forward_safety side_safety turn_axis timestamp host logger_timestamp``: a scan with
  its own geometry; the laser's offset on the robot is ``relative(robot, laser)``.

A log whose scans come as ROBOTLASER1 is read from those and its FLASER lines (often
the same scans again) are ignored, unless ``laser_message`` says otherwise.

Scans are kept, not dropped: ``ranges`` is a masked ``(N, B)`` array (``B`` the
largest beam count) whose mask marks readings that are not obstacles: "no return"
(81.83 m and above, :data:`NO_RETURN_RANGE`), at or beyond the laser's maximum range,
zero, negative or not finite, and the padding of scans with fewer beams. A fixed beam
count keeps the hot paths vectorised; :meth:`CarmenLog.points` gives one scan's valid
endpoints and :meth:`CarmenLog.scan` one scan as an :class:`abcwc.types.LaserScan`.
Why not keep a list of LaserScans: a log of thousands of scans is one array operation
on (N, B) arrays and a Python loop over as many objects.
"""

from __future__ import annotations

import math
import zlib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from abcwc.geometry import compose, relative, transform_points, wrap_angle
from abcwc.types import LaserScan

NO_RETURN_RANGE = 81.83
"""Readings at or above this (m) are the SICK's "no return" codes (81.83, 81.91, ...)."""

LASER_MESSAGES = ("FLASER", "ROBOTLASER1")
_OFFSET_PARAMS = {"robot_frontlaser_offset": 0, "robot_frontlaser_side_offset": 1,
                  "robot_frontlaser_angular_offset": 2}
_FLASER_PARAMS = ("robot_front_laser_max", "laser_front_laser_resolution")
"""PARAMs that give the FLASER lines' maximum range (m) and beam spacing (degrees)."""


def guess_flaser_increment(beams: np.ndarray) -> np.ndarray:
    """(rad) the beam spacing of FLASER scans of ``beams`` readings, as CARMEN's own
    reader guesses it (``carmen_laser_guess_angle_increment``, CARMEN's ``readlog.c``): a
    SICK LMS scanning at 1, 0.5 or 0.25 degrees logs 181, 361 or 401 readings, or one
    fewer when its last is dropped (180, 360, 400); any other count spans 180 degrees."""
    beams = np.asarray(beams)
    return np.select([np.isin(beams, (180, 181)), np.isin(beams, (360, 361)),
                      np.isin(beams, (400, 401))],
                     [np.pi / 180, np.pi / 360, np.pi / 720],
                     np.pi / np.maximum(beams - 1, 1))


@dataclass(frozen=True, eq=False)
class CarmenLog:
    """The scans of a CARMEN log, as arrays with one row per scan (N scans, B beams).

    ``stamps`` (s) are the messages' ``timestamp`` fields (the ones benchmark relations
    refer to); ``odometry`` the robot's ``(x, y, theta)`` at each scan (m, rad);
    ``laser_offset`` the laser's pose on the robot ``(x, y, theta)``; ``angle_min`` and
    ``angle_increment`` (rad) each scan's first beam and beam spacing; ``range_max`` (m)
    each scan's maximum range; ``beams`` each scan's number of readings; ``ranges`` the
    masked ``(N, B)`` readings (m), ``B = max(beams)``. ``odom_stamps`` and
    ``odom_poses`` are the log's ODOM lines (empty if it has none).
    """

    path: Path
    laser_message: str
    stamps: np.ndarray
    odometry: np.ndarray
    laser_offset: np.ndarray
    angle_min: np.ndarray
    angle_increment: np.ndarray
    range_max: np.ndarray
    beams: np.ndarray
    ranges: np.ma.MaskedArray
    odom_stamps: np.ndarray
    odom_poses: np.ndarray

    def __len__(self) -> int:
        return len(self.stamps)

    @property
    def angles(self) -> np.ndarray:
        """``(N, B)`` beam angles (rad) in the laser frame."""
        beams = np.arange(self.ranges.shape[1])
        return self.angle_min[:, None] + self.angle_increment[:, None] * beams

    @property
    def laser_poses(self) -> np.ndarray:
        """``(N, 3)`` the laser's pose at each scan in the odometry frame (m, rad)."""
        return np.asarray(compose(self.odometry, self.laser_offset))

    def points(self, index: int, frame: str = "laser") -> np.ndarray:
        """Scan ``index``'s valid endpoints ``(M, 2)`` (m) in the ``"laser"`` frame, the
        robot's (``"base"``) or the odometry frame (``"odom"``)."""
        xy = self.scan(index).points()
        if frame == "laser":
            return xy
        if frame == "base":
            return transform_points(self.laser_offset, xy)
        if frame == "odom":
            return transform_points(compose(self.odometry[index], self.laser_offset), xy)
        raise ValueError(f"frame {frame!r} is not one of 'laser', 'base', 'odom'")

    def scan(self, index: int) -> LaserScan:
        """Scan ``index`` as a LaserScan: masked readings become ``inf``, padding is cut."""
        count = int(self.beams[index])
        ranges = self.ranges[index, :count].filled(np.inf).astype(float)
        return LaserScan(angle_min=float(self.angle_min[index]),
                         angle_increment=float(self.angle_increment[index]),
                         range_min=0.0, range_max=float(self.range_max[index]),
                         ranges=ranges, stamp=float(self.stamps[index]))


def read_carmen_log(path: str | Path, *, max_range: float | None = None,
                    laser_offset: tuple[float, float, float] | None = None,
                    laser_message: str | None = None) -> CarmenLog:
    """Read a CARMEN log's laser scans and odometry (a ``.clf`` file, gzipped or not).

    ``max_range`` (m): readings at or beyond it are masked; FLASER lines do not carry it
    (a log may state it in a ``robot_front_laser_max`` PARAM; ACES's SICK has a 50 m
    range and the file does not say), ROBOTLASER1 lines do (a smaller ``max_range`` here
    wins). ``laser_offset`` ``(x, y, theta)`` (m, rad): the laser's pose on the robot
    (FR079's is 0.04 m ahead); by default it is the ROBOTLASER1 lines' laser pose seen
    from their robot pose, else the ``robot_frontlaser_*offset`` PARAMs, else zero.
    ``laser_message``: ``"FLASER"`` or ``"ROBOTLASER1"``; by default ROBOTLASER1 when
    the log has any. Bad input (missing file, truncated gzip, a line with too few
    fields, a wrong count, a value that is not a number) raises ValueError naming the
    file and line.
    """
    path = Path(path)
    if laser_message is not None and laser_message not in LASER_MESSAGES:
        raise ValueError(f"laser_message {laser_message!r} is not one of {LASER_MESSAGES}")
    if max_range is not None and not max_range > 0:
        raise ValueError(f"max_range must be > 0 m, got {max_range!r}")
    lines = _read_lines(path)
    if laser_message is None:
        has_robotlaser = any(line.startswith("ROBOTLASER1") for line in lines)
        laser_message = "ROBOTLASER1" if has_robotlaser else "FLASER"
    scans = _ScanLines(path, laser_message)
    odom = _OdomLines(path)
    param_offset = np.zeros(3)
    laser_params: dict[str, float] = {}
    for number, line in enumerate(lines, 1):
        fields = line.split()
        if not fields or fields[0].startswith("#"):
            continue
        kind = fields[0]
        if kind == laser_message:
            scans.add(number, fields)
        elif kind == "ODOM":
            odom.add(number, fields)
        elif kind == "PARAM" and len(fields) >= 3 and fields[1] in _OFFSET_PARAMS:
            param_offset[_OFFSET_PARAMS[fields[1]]] = _number(path, number, fields[2])
        elif kind == "PARAM" and len(fields) >= 3 and fields[1] in _FLASER_PARAMS:
            value = _number(path, number, fields[2])
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{path}, line {number}: {fields[1]} must be a number > 0, "
                                 f"got {fields[2]!r}")
            laser_params[fields[1]] = value
    if not scans.numbers:
        raise ValueError(f"{path}: no {laser_message} lines (no laser scans)")
    (stamps, odometry, logged_offset, angle_min, increment, range_max, beams,
     ranges) = scans.arrays(laser_params)
    if max_range is not None:
        range_max = np.minimum(range_max, max_range)
    if laser_offset is not None:
        offset = np.asarray(laser_offset, dtype=float)
        if offset.shape != (3,) or not np.all(np.isfinite(offset)):
            raise ValueError(f"laser_offset must be finite (x, y, theta), got {laser_offset!r}")
    elif logged_offset is not None:
        offset = logged_offset
    else:
        offset = param_offset
    invalid = (~np.isfinite(ranges) | (ranges <= 0.0)
               | (ranges >= NO_RETURN_RANGE) | (ranges >= range_max[:, None]))
    odom_stamps, odom_poses = odom.arrays()
    return CarmenLog(path=path, laser_message=laser_message, stamps=stamps,
                     odometry=odometry, laser_offset=offset, angle_min=angle_min,
                     angle_increment=increment, range_max=range_max, beams=beams,
                     ranges=np.ma.MaskedArray(ranges, mask=invalid),
                     odom_stamps=odom_stamps, odom_poses=odom_poses)


def _read_lines(path: Path) -> list[str]:
    """The file's lines, gunzipped if it starts with the gzip magic number."""
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise ValueError(f"{path}: cannot read the CARMEN log ({exc.strerror})") from exc
    if raw[:2] == b"\x1f\x8b":
        raw = _gunzip(path, raw)
    return raw.decode("latin-1").splitlines()


def _gunzip(path: Path, raw: bytes) -> bytes:
    """Every gzip member of ``raw``; a truncated or corrupt stream is a ValueError."""
    parts: list[bytes] = []
    while raw:
        inflater = zlib.decompressobj(wbits=31)
        try:
            parts.append(inflater.decompress(raw))
        except zlib.error as exc:
            done = b"".join(parts).count(b"\n")
            raise ValueError(f"{path}: corrupt gzip data after line {done} ({exc})") from exc
        if not inflater.eof:
            done = b"".join(parts).count(b"\n")
            raise ValueError(f"{path}: gzip stream truncated after line {done} "
                             f"(the file ends before the end of the compressed data)")
        raw = inflater.unused_data.lstrip(b"\0")
    return b"".join(parts)


def _number(path: Path, number: int, text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"{path}, line {number}: {text!r} is not a number") from None


def _count(path: Path, number: int, fields: list[str], at: int, what: str) -> int:
    """The count in ``fields[at]``: a whole number >= 0, or a ValueError."""
    if len(fields) <= at:
        raise ValueError(f"{path}, line {number}: {fields[0]} has {len(fields)} fields, "
                         f"too few to hold its {what}")
    try:
        count = int(fields[at])
    except ValueError:
        raise ValueError(f"{path}, line {number}: {fields[0]}'s {what} {fields[at]!r} "
                         f"is not a whole number") from None
    if count < 0:
        raise ValueError(f"{path}, line {number}: {fields[0]}'s {what} {count} is negative")
    return count


def _to_floats(path: Path, numbers: list[int], tokens: list[list[str]]) -> list[np.ndarray]:
    """Each line's numeric tokens as floats, converted in one call (the slow path, line
    by line, only runs to name the line of a bad value)."""
    flat = [token for line in tokens for token in line]
    try:
        values = np.array(flat, dtype=float)
    except ValueError:
        for number, line in zip(numbers, tokens):
            for token in line:
                _number(path, number, token)
        raise
    return np.split(values, np.cumsum([len(line) for line in tokens])[:-1])


class _ScanLines:
    """Collects one laser message type's lines, then converts them all at once.

    Each line's kept tokens are its ranges, then six pose values (laser or FLASER pose,
    then robot odometry pose), then its timestamp.
    """

    def __init__(self, path: Path, kind: str) -> None:
        self.path, self.kind = path, kind
        self.numbers: list[int] = []
        self.tokens: list[list[str]] = []
        self.geometry: list[tuple[str, str, str]] = []  # start angle, resolution, max range

    def add(self, number: int, fields: list[str]) -> None:
        if self.kind == "FLASER":
            n = _count(self.path, number, fields, 1, "number of readings")
            self._expect(number, fields, n + 11, f"with {n} readings")
            self.tokens.append(fields[2:n + 9])
        else:
            n = _count(self.path, number, fields, 8, "number of readings")
            m = _count(self.path, number, fields, 9 + n, "number of remissions")
            self._expect(number, fields, n + m + 24,
                         f"with {n} readings and {m} remissions")
            poses = fields[10 + n + m:16 + n + m]
            self.tokens.append(fields[9:9 + n] + poses + [fields[21 + n + m]])
            self.geometry.append((fields[2], fields[4], fields[5]))
        self.numbers.append(number)

    def _expect(self, number: int, fields: list[str], expected: int, what: str) -> None:
        if len(fields) != expected:
            raise ValueError(f"{self.path}, line {number}: {self.kind} {what} needs "
                             f"{expected} fields, got {len(fields)}")

    def arrays(self, laser_params: dict[str, float]) -> tuple[np.ndarray, ...]:
        """stamps, odometry, logged laser offset (or None), angle_min, angle_increment,
        range_max, beam counts and NaN-padded ranges; FLASER's geometry from the log's
        ``laser_params`` (:data:`_FLASER_PARAMS`) where it has them."""
        rows = _to_floats(self.path, self.numbers, self.tokens)
        counts = np.array([len(row) - 7 for row in rows])
        if np.all(counts == counts[0]):
            table = np.stack(rows)
            ranges = table[:, :-7]
        else:
            ranges = np.full((len(rows), counts.max()), np.nan)
            for k, row in enumerate(rows):
                ranges[k, :counts[k]] = row[:-7]
            table = np.stack([row[-7:] for row in rows])
        laser_poses, odometry, stamps = table[:, -7:-4], table[:, -4:-1], table[:, -1]
        odometry = odometry.copy()
        odometry[:, 2] = wrap_angle(odometry[:, 2])
        if self.kind == "FLASER":
            angle_min = np.full(len(rows), -np.pi / 2)
            resolution = laser_params.get("laser_front_laser_resolution")
            increment = (guess_flaser_increment(counts) if resolution is None
                         else np.full(len(rows), math.radians(resolution)))
            range_max = np.full(len(rows), min(NO_RETURN_RANGE, laser_params.get(
                "robot_front_laser_max", NO_RETURN_RANGE)))
            return stamps, odometry, None, angle_min, increment, range_max, counts, ranges
        geometry = _to_floats(self.path, self.numbers, [list(g) for g in self.geometry])
        angle_min, increment, range_max = np.stack(geometry).T
        offsets = np.asarray(relative(odometry, laser_poses))
        offset = np.median(offsets, axis=0)
        offset[2] = wrap_angle(float(offset[2]))
        return stamps, odometry, offset, angle_min, increment, range_max, counts, ranges


class _OdomLines:
    """Collects ODOM lines: ``x y theta tv rv accel timestamp`` are kept."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.numbers: list[int] = []
        self.tokens: list[list[str]] = []

    def add(self, number: int, fields: list[str]) -> None:
        if len(fields) < 8:
            raise ValueError(f"{self.path}, line {number}: ODOM needs at least 8 fields "
                             f"(x y theta tv rv accel timestamp ...), got {len(fields)}")
        self.numbers.append(number)
        self.tokens.append(fields[1:8])

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """``(K,)`` stamps (s) and ``(K, 3)`` poses."""
        if not self.tokens:
            return np.zeros(0), np.zeros((0, 3))
        table = np.stack(_to_floats(self.path, self.numbers, self.tokens))
        poses = table[:, :3].copy()
        poses[:, 2] = wrap_angle(poses[:, 2])
        return table[:, 6], poses
