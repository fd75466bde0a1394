"""Drive the UMBmark square by odometry (Borenstein and Feng 1996; thesis 4.2.3).

:class:`SquareDriver` drives one ``L x L`` square clockwise or counter-clockwise by its
own odometry and turns back to the start heading; where the chair *really* ends is
what UMBmark measures (:mod:`abcwc.estimation.umbmark` has the maths,
:mod:`abcwc.experiments.umbmark_trials` runs the trials).
"""

from __future__ import annotations

import math

from abcwc.behaviours.base import LOOP_RATE_HZ, BehaviourBase, positive_number
from abcwc.estimation.odometry import Odometry
from abcwc.estimation.umbmark import THESIS_SIDE
from abcwc.geometry import wrap_angle
from abcwc.types import Pose2D, SensorFrame, Twist

DRIVE, TURN = "drive", "turn"
"""The driver's phases: along a leg, or turning on the spot at a corner."""

_AT_CORNER = 0.002  # m left along the leg that counts as at the corner
_AIM_AT_CORNER_BEYOND = 0.3  # m: farther than this from the corner, steer at it
_HEADING_TOLERANCE = 0.0017  # rad (0.1 degree): a corner turn is finished
_MIN_SPEED = 0.03  # m/s, the least forward speed near a corner
_MIN_TURN_RATE = 0.02  # rad/s, the least turn rate near the end of a turn


class SquareDriver(BehaviourBase):
    """Drive one L x L square by odometry, then turn back to the start heading.

    Each leg: steer at the corner (proportional in heading), slow down in proportion
    to the distance left, stop on it; wait until the wheels stand still; turn on the
    spot to the next heading (proportional, 0.1 degree tolerance); wait again. The
    odometry is fed every frame; the status is succeeded after the fourth turn.

    ``side`` (m), ``direction`` ``"cw"`` or ``"ccw"``; ``speed`` (m/s) and
    ``turn_rate`` (rad/s) are the most it asks for; ``settle`` (s) the waits;
    ``brake_gain`` (1/s) the speed per metre left near a corner and ``turn_gain``
    (1/s) the turn rate per radian left (higher: quicker, less gentle).
    """

    def __init__(self, odometry: Odometry, side: float = THESIS_SIDE, direction: str = "ccw",
                 speed: float = 0.5, turn_rate: float = 0.5, settle: float = 0.6,
                 brake_gain: float = 0.8, turn_gain: float = 1.5,
                 rate_hz: float = LOOP_RATE_HZ):
        super().__init__(rate_hz)
        if direction not in ("cw", "ccw"):
            raise ValueError(f"direction must be 'cw' or 'ccw', got {direction!r}")
        self.odometry = odometry
        self.side = positive_number("side", side, "m")
        self.speed = positive_number("speed", speed, "m/s")
        self.turn_rate = positive_number("turn_rate", turn_rate, "rad/s")
        if isinstance(settle, bool) or not (math.isfinite(settle) and settle >= 0):
            raise ValueError(f"settle must be a finite number >= 0 s, got {settle!r}")
        self.settle = float(settle)
        self.brake_gain = positive_number("brake_gain", brake_gain, "1/s")
        self.turn_gain = positive_number("turn_gain", turn_gain, "1/s")
        self.sign = 1.0 if direction == "ccw" else -1.0
        self.pose = Pose2D()
        self.reset()

    def reset(self) -> None:
        """Start a new square from wherever the odometry is at the next frame."""
        super().reset()
        self.start: Pose2D | None = None
        self.leg = 0  # legs finished (0..4)
        self.phase = DRIVE
        self._wait_until = -math.inf

    def _corner(self, i: int) -> tuple[float, float, float]:
        """Corner ``i`` (1..4) in the odometry frame, and the heading (rad) of leg ``i``."""
        assert self.start is not None
        unit_corners = [(0, 0), (1, 0), (1, self.sign), (0, self.sign), (0, 0)]
        px, py = unit_corners[i]
        s = self.start  # the corner (side px, side py) of the start frame, in the odometry's
        c, sn = math.cos(s.theta), math.sin(s.theta)
        x = s.x + self.side * (c * px - sn * py)
        y = s.y + self.side * (sn * px + c * py)
        return x, y, wrap_angle(s.theta + self.sign * (i - 1) * math.pi / 2)

    def observe(self, frame: SensorFrame) -> None:
        self.odometry.observe(frame)
        self.pose = self.odometry.pose
        if self.start is None:
            self.start = self.pose

    def update(self, frame: SensorFrame) -> Twist:
        if frame.t < self._wait_until:
            return Twist(0.0, 0.0)
        return self._drive(frame.t) if self.phase == DRIVE else self._turn(frame.t)

    def _drive(self, t: float) -> Twist:
        pose = self.pose
        gx, gy, leg_heading = self._corner(self.leg + 1)
        along = (gx - pose.x) * math.cos(leg_heading) + (gy - pose.y) * math.sin(leg_heading)
        if along <= _AT_CORNER:
            self.phase, self._wait_until = TURN, t + self.settle
            return Twist(0.0, 0.0)
        aim = (math.atan2(gy - pose.y, gx - pose.x) if along > _AIM_AT_CORNER_BEYOND
               else leg_heading)
        w = _clip(2.0 * wrap_angle(aim - pose.theta), self.turn_rate)
        return Twist(min(self.speed, max(_MIN_SPEED, self.brake_gain * along)), w)

    def _turn(self, t: float) -> Twist:
        assert self.start is not None
        target = self._corner(self.leg + 2)[2] if self.leg < 3 else self.start.theta
        error = wrap_angle(target - self.pose.theta)
        if abs(error) <= _HEADING_TOLERANCE:
            self.leg += 1
            self.phase, self._wait_until = DRIVE, t + self.settle
            if self.leg == 4:
                self.succeed()
            return Twist(0.0, 0.0)
        rate = max(_MIN_TURN_RATE, min(self.turn_rate, self.turn_gain * abs(error)))
        return Twist(0.0, math.copysign(rate, error))


def _clip(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))
