"""Message types shared by every layer, mirroring ROS field meanings.

SI units throughout; ROS REP 103 frames: x forward, y left, yaw counter-clockwise,
angles wrapped to (-pi, pi].
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import IntFlag

import numpy as np


def require_finite(name: str, value: float) -> float:
    """Return ``value`` as float, or raise ValueError if it is not a finite number."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return number


@dataclass(frozen=True)
class Pose2D:
    """A planar pose: position (m) and heading (rad, counter-clockwise from x)."""

    x: float = 0.0
    y: float = 0.0
    theta: float = 0.0

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

    ``ranges`` holds metres; ``inf`` means no return within ``range_max``.
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


@dataclass
class SensorFrame:
    """Everything the chair reports in one control period.

    The first block is what the real chair's firmware sends; the simulator fills the
    ``sim extras`` too (ground truth and the heavier sensors).
    """

    t: float  # s since start
    ticks_left: int  # cumulative encoder counts (x1 decoding, + = wheel forward)
    ticks_right: int
    gyro_z: float  # rad/s, counter-clockwise positive
    sonar: float  # m, latest MB1013 reading (clipped to 0.30..5.0)
    ir: np.ndarray  # (6,) m; inf = nothing in 0.2..1.5 m, -inf = closer than 0.2 m
    joystick_fb: int  # joystick ADC (pot scale: centre 254, 110..398)
    joystick_lr: int
    pot_fb: int  # bytes on the digital pot now
    pot_lr: int
    flags: StatusFlags = StatusFlags.NONE
    bad_frames: int = 0
    # sim extras
    pose: Pose2D | None = None  # ground truth (map frame)
    lidar: LaserScan | None = None  # newest scan, when the sensor is enabled
    depth_scan: LaserScan | None = None
    collisions: int = 0  # collisions so far
    extras: dict = field(default_factory=dict)
