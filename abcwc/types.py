"""Message types shared by every layer, mirroring ROS field meanings.

SI units throughout; ROS REP 103 frames: x forward, y left, yaw counter-clockwise,
angles wrapped to (-pi, pi].
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import IntFlag

import numpy as np

from abcwc.params import ChairParams, default_params


def require_finite(name: str, value: float) -> float:
    """Return ``value`` as float, or raise ValueError if it is not a finite number."""
    if type(value) is float and math.isfinite(value):  # the common case, first: poses are hot
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return number


@dataclass(frozen=True)
class Pose2D:
    """A planar pose: position (m) and heading (rad, counter-clockwise from x).

    Every field must be a finite number (ValueError otherwise, as for :class:`Twist`):
    an unknown pose is ``None``, not a Pose2D of NaNs.
    """

    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "x", require_finite("Pose2D.x (m)", self.x))
        object.__setattr__(self, "y", require_finite("Pose2D.y (m)", self.y))
        object.__setattr__(self, "theta", require_finite("Pose2D.theta (rad)", self.theta))

    def as_array(self) -> np.ndarray:
        """``[x, y, theta]`` as a float array."""
        return np.array([self.x, self.y, self.theta])


@dataclass(frozen=True)
class Twist:
    """A velocity command: forward speed ``v`` (m/s, ROS linear.x) and turn rate
    ``w`` (rad/s, ROS angular.z, positive = counter-clockwise = left)."""

    v: float = 0.0
    w: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "v", require_finite("Twist.v (m/s)", self.v))
        object.__setattr__(self, "w", require_finite("Twist.w (rad/s)", self.w))


@dataclass(frozen=True)
class PotCommand:
    """The two MCP42010 digital-pot bytes sent to the motor controller.

    ``fb`` drives forward (above 128) or back (below); ``lr`` turns left (below 128)
    or right (above). Bytes must be integers 0..255; the chair's interface board
    further clamps them to its safe range (8..253) before they reach the motors.
    """

    fb: int = 128
    lr: int = 128

    def __post_init__(self) -> None:
        for name in ("fb", "lr"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
                raise ValueError(f"{name} pot must be an integer byte 0..255, got {value!r}")
            if not 0 <= int(value) <= 255:
                raise ValueError(f"{name} pot {int(value)} outside 0..255")
            object.__setattr__(self, name, int(value))


NEUTRAL = PotCommand(128, 128)


class StatusFlags(IntFlag):
    """Status bits reported in every SensorFrame (same bits as the firmware's)."""

    NONE = 0
    JOYSTICK_OVERRIDE = 1  # the joystick is deflected and drives the pots
    WATCHDOG_TRIPPED = 2  # no valid command for the watchdog timeout: pots neutral
    JOYSTICK_FAULT = 4  # implausible joystick reading: pots neutral
    IMU_FAULT = 8
    SPEED_CAPPED = 16  # a host command was changed: speed cap or safe pot range
    HOST_ACTIVE = 32  # a host command drives the pots


@dataclass(frozen=True)
class LaserScan:
    """A planar range scan, ROS sensor_msgs/LaserScan fields.

    ``ranges`` holds metres, one per beam; beam ``k`` points ``angle_min + k
    angle_increment`` rad from the sensor's x axis. REP 117: ``inf`` means no return
    within ``range_max``, ``-inf`` an object closer than ``range_min``, NaN no reading.
    """

    angle_min: float
    angle_increment: float
    range_min: float
    range_max: float
    ranges: np.ndarray
    stamp: float = 0.0

    @property
    def angles(self) -> np.ndarray:
        """Beam angles (rad) in the sensor frame."""
        return self.angle_min + self.angle_increment * np.arange(len(self.ranges))

    def _limit(self, max_range: float | None) -> float:
        if max_range is None:
            return self.range_max
        if not (isinstance(max_range, (int, float, np.integer, np.floating))
                and max_range > 0):
            raise ValueError(f"max_range must be a number > 0 m (or None), got {max_range!r}")
        return min(float(max_range), self.range_max)

    def hits(self, max_range: float | None = None) -> np.ndarray:
        """Which beams returned (bool, one per beam): a finite range ``r`` with
        ``range_min <= r <= range_max`` (sensor_msgs/LaserScan: readings outside those
        bounds are to be discarded), and ``r <= max_range`` (m) when it is given. inf,
        -inf, NaN and finite readings outside the bounds are not returns."""
        ranges = np.asarray(self.ranges, dtype=float)
        return (np.isfinite(ranges) & (ranges >= self.range_min)
                & (ranges <= self._limit(max_range)))

    def misses(self, max_range: float | None = None) -> np.ndarray:
        """Which beams saw nothing up to the limit, ``range_max`` or ``max_range`` (m) if
        nearer (bool, one per beam): ``inf``, or a finite range beyond the limit. -inf
        (too close) and NaN (no reading) are neither hits nor misses."""
        ranges = np.asarray(self.ranges, dtype=float)
        return (ranges == np.inf) | (np.isfinite(ranges) & (ranges > self._limit(max_range)))

    def points(self, max_range: float | None = None, *, with_misses: bool = False
               ) -> np.ndarray:
        """The returns as ``(N, 2)`` x, y (m) in the sensor frame, in beam order: one row
        per beam of :meth:`hits` (``r cos(angle), r sin(angle)``; ``max_range`` (m) drops
        the returns beyond it too).

        ``with_misses``: also a row for each beam of :meth:`misses`, at the limit
        (``range_max``, or ``max_range`` if nearer) along the beam, still in beam order:
        the ends of the rays a mapper traces as free (costmap_2d does the same with
        ``inf_is_valid``); ``hits(max_range)[hits(max_range) | misses(max_range)]`` says
        which rows are returns.
        """
        ranges = np.asarray(self.ranges, dtype=float)
        hit = self.hits(max_range)
        used = hit | self.misses(max_range) if with_misses else hit
        length = np.where(hit, ranges, self._limit(max_range))[used]
        angles = self.angles[used]
        return np.column_stack([length * np.cos(angles), length * np.sin(angles)])


@dataclass(frozen=True)
class CameraImage:
    """An image and its camera (sensor_msgs/Image with CameraInfo's K): ``pixels``
    (h, w) grey or (h, w, 3) RGB, uint8, taken at ``stamp`` s by a pinhole camera of
    focal lengths ``fx``, ``fy`` and principal point ``cx``, ``cy`` (px), level, in the
    optical frame of REP 103 (x right, y down, z ahead)."""

    pixels: np.ndarray
    fx: float
    fy: float
    cx: float
    cy: float
    stamp: float = 0.0


SONAR_FRAME = "sonar_link"
"""Frame id of the MaxSonar MB1013 under the tray: one range (m) per reading."""
IR_FRAMES = tuple(f"ir_{k}_link" for k in range(6))
"""Frame ids of the six Sharp IR rangers, ``ir_k_link`` facing ``first_angle + 60 k`` deg."""
DEPTH_SCAN_FRAME = "depth_scan_link"
"""Frame id of the Kinect's fake laser scan (depthimage_to_laserscan): a LaserScan."""
LIDAR_FRAME = "lidar_link"
"""Frame id of the 360-degree 2D lidar: a LaserScan."""
CAMERA_FRAME = "camera_link"
"""Frame id of the Kinect's colour camera: a CameraImage."""

_UNSET = object()  # "not given" for SensorFrame's keyword arguments (None means "no scan")


@dataclass(frozen=True)
class SimTruth:
    """What only a simulator knows about a frame: the chair's true ``pose`` (base_link in
    the map frame, m and rad) and the ``collisions`` (pymunk contacts with a wall, an
    object or a person) so far.

    A real chair's frames have none (``frame.truth is None``). Only the judges read it
    (the exercise checks, the seeded studies and their plots) and the
    :class:`~abcwc.behaviours.GroundTruth` "estimator" that teaching runs steer by on
    purpose; no behaviour or estimator does (a test holds them to it).
    """

    pose: Pose2D
    collisions: int = 0


def ir_frame(k: int) -> str:
    """Frame id of IR ranger ``k`` (0-based): ``ir_<k>_link``."""
    return f"ir_{k}_link"


def _ir_frame_id(k: int) -> str:
    """:func:`ir_frame`, from :data:`IR_FRAMES` for the ring's six (read every period)."""
    return IR_FRAMES[k] if k < len(IR_FRAMES) else ir_frame(k)


@dataclass(init=False)
class SensorFrame:
    """Everything the chair reports in one control period.

    The first block is what the real chair's firmware sends. ``truth`` is the
    simulator's ground truth (:class:`SimTruth`: the true pose and the collisions), None
    on a real chair: it is marked apart so that nothing that drives the chair reads it
    by mistake. The simulator fills the heavier sensors' ``readings`` too.

    ``readings`` holds every range sensor's newest reading keyed by its ROS frame id
    (as a ``header.frame_id``): :data:`SONAR_FRAME` and the six :data:`IR_FRAMES` map to
    a range (float, m; REP 117: ``inf`` nothing in range, ``-inf`` too close, NaN no
    reading), :data:`DEPTH_SCAN_FRAME` and :data:`LIDAR_FRAME` to a :class:`LaserScan`
    and :data:`CAMERA_FRAME` to a :class:`CameraImage` (absent when the sensor is off).
    ``sonar``, ``ir``, ``lidar`` and ``depth_scan`` read
    (and set) the same entries, and the constructor takes them by those names too.
    """

    t: float  # s since start
    ticks_left: int  # cumulative encoder counts (x1 decoding, + = wheel forward)
    ticks_right: int
    gyro_z: float  # rad/s, counter-clockwise positive
    joystick_fb: int  # joystick ADC (pot scale: centre 254, 110..398)
    joystick_lr: int
    pot_fb: int  # bytes on the digital pot now
    pot_lr: int
    flags: StatusFlags = StatusFlags.NONE
    bad_frames: int = 0
    truth: SimTruth | None = None  # the simulator's ground truth; None on a real chair
    extras: dict = field(default_factory=dict)
    readings: dict[str, object] = field(default_factory=dict)  # frame id -> range / scan

    def __init__(
        self,
        t: float,
        ticks_left: int,
        ticks_right: int,
        gyro_z: float,
        *,
        joystick_fb: int,
        joystick_lr: int,
        pot_fb: int,
        pot_lr: int,
        sonar: object = _UNSET,
        ir: object = _UNSET,
        flags: StatusFlags = StatusFlags.NONE,
        bad_frames: int = 0,
        truth: SimTruth | None = None,
        lidar: object = _UNSET,
        depth_scan: object = _UNSET,
        extras: dict | None = None,
        readings: dict[str, object] | None = None,
    ):
        self.t, self.ticks_left, self.ticks_right, self.gyro_z = t, ticks_left, ticks_right, gyro_z
        self.joystick_fb, self.joystick_lr = joystick_fb, joystick_lr
        self.pot_fb, self.pot_lr = pot_fb, pot_lr
        if truth is not None and not isinstance(truth, SimTruth):
            raise ValueError(f"truth must be a SimTruth or None, got {truth!r}")
        self.flags, self.bad_frames, self.truth = flags, bad_frames, truth
        self.extras = {} if extras is None else extras
        self.readings = dict(readings or {})  # a copy: replace() must not edit the original
        for name, value in (("sonar", sonar), ("ir", ir), ("lidar", lidar),
                            ("depth_scan", depth_scan)):
            if value is not _UNSET:
                setattr(self, name, value)

    @property
    def sonar(self) -> float:
        """The sonar's range (m; clipped to 0.30..5.0, NaN when there is none)."""
        return self.readings.get(SONAR_FRAME, math.nan)  # type: ignore[return-value]

    @sonar.setter
    def sonar(self, value: float) -> None:
        self.readings[SONAR_FRAME] = value

    @property
    def ir(self) -> np.ndarray:
        """The IR ring's ranges (m), one per ``ir_k_link`` from k = 0 (a new array:
        ``inf`` nothing in 0.2..1.5 m, ``-inf`` closer than 0.2 m)."""
        values, readings = [], self.readings
        while (frame_id := _ir_frame_id(len(values))) in readings:
            values.append(readings[frame_id])
        return np.array(values, dtype=float)

    @ir.setter
    def ir(self, values: np.ndarray) -> None:
        k = 0
        while ir_frame(k) in self.readings:
            del self.readings[ir_frame(k)]
            k += 1
        for k, value in enumerate(np.asarray(values, dtype=float)):
            self.readings[ir_frame(k)] = float(value)

    @property
    def lidar(self) -> LaserScan | None:
        """The newest lidar scan, or None when the lidar is off."""
        return self.readings.get(LIDAR_FRAME)  # type: ignore[return-value]

    @lidar.setter
    def lidar(self, scan: LaserScan | None) -> None:
        self._set_scan(LIDAR_FRAME, scan)

    @property
    def depth_scan(self) -> LaserScan | None:
        """The newest depth-camera scan, or None when the camera is off."""
        return self.readings.get(DEPTH_SCAN_FRAME)  # type: ignore[return-value]

    @depth_scan.setter
    def depth_scan(self, scan: LaserScan | None) -> None:
        self._set_scan(DEPTH_SCAN_FRAME, scan)

    def _set_scan(self, frame_id: str, scan: LaserScan | None) -> None:
        if scan is None:
            self.readings.pop(frame_id, None)
        elif isinstance(scan, LaserScan):
            self.readings[frame_id] = scan
        else:
            raise ValueError(f"{frame_id} reading must be a LaserScan or None, got {scan!r}")


def make_frame(t: float = 0.0, params: ChairParams | None = None, **fields: object) -> SensorFrame:
    """A SensorFrame of a chair at rest in open space, for tests and checks.

    Defaults (from ``params``, the Sterling Ruby's by default): no encoder counts, no
    turn, the sonar at its maximum range (nothing ahead), every IR ranger ``inf``,
    joystick centred, pots neutral, no ground truth. ``fields`` override any of them
    by SensorFrame's keyword names (``sonar=1.2``, ``truth=SimTruth(Pose2D(...))``,
    ``lidar=scan``).
    """
    p = params if params is not None else default_params()
    values: dict[str, object] = dict(
        ticks_left=0, ticks_right=0, gyro_z=0.0, sonar=p.sonar.max_range,
        ir=np.full(p.ir.count, np.inf), joystick_fb=p.joystick_centre,
        joystick_lr=p.joystick_centre, pot_fb=p.pot_neutral, pot_lr=p.pot_neutral,
    )
    values.update(fields)
    return SensorFrame(t, **values)  # type: ignore[arg-type]
