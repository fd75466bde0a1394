"""The safety filter: every autonomous command passes through it on its way to the pots.

A planner proposes; the filter disposes. At every control period (50 Hz) it takes the
command an autonomous behaviour wants (a :class:`~abcwc.types.Twist`) and the newest
:class:`~abcwc.types.SensorFrame`, and returns what may be sent. Its rules, in order:

1. **The joystick wins.** While the frame says the joystick drives the pots
   (``JOYSTICK_OVERRIDE``, the interface board's flag), the filter sends a stop and
   forgets its ramp; after the joystick is released it holds still for
   ``resume_delay`` s before an autonomous command may move the chair again (the
   board's own rule: an old command never resumes by itself).
2. **A stale command stops the chair.** A command decided more than ``stale_after`` s
   ago (the planner stalled or died) is replaced by a stop.
3. **Speed limits** for a person in the seat (:class:`ComfortLimits`).
4. **Obstacle stop.** Each range reading (the sonar's cone, the six IR rangers) is put
   in base_link; if it lies in the strip the chair will sweep (its width plus a margin,
   ahead when driving forward, behind when reversing) nearer than the braking distance
   at the current speed, the motion along that way is stopped at once. A reading at or
   below the sensor's minimum range (the MaxSonar reports 0.30 m for anything nearer;
   the IR rangers ``-inf``) says only that something is *at most* that far: from a
   sensor facing within 60 degrees of the way the chair is going, it counts as touching
   the chair's edge (creeping forward while the sonar reads its minimum put the chair's
   tray into a table top). NaN (no reading, as the real chair's unwired IR ring) counts
   as nothing.
5. **Acceleration and jerk limits**: the speed follows the wanted one with a
   jerk-limited ramp, the turn rate with an acceleration-limited one. A wanted stop
   (0, 0) while driving keeps to the arc the chair is on: the turn rate falls in
   proportion to the speed, so the chair brakes along the way its planner checked.
   Stops by rules 1, 2 and 4 skip the ramp: the chair's own motor controller brakes.

The braking distance comes from the chair's model (chair.toml): the sensing period, the
motor controller's input delay and the wheels' first-order lag ``tau`` (a first-order
lag stops from ``v`` in ``v tau``), plus ``stop_margin``::

    d_brake(v) = v (1 / sensor_rate + command_delay + tau) + stop_margin

Where the filter changed a command, :attr:`SafetyFilter.reason` says why, and
:attr:`SafetyFilter.interventions` counts each kind.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from abcwc.params import ChairParams, default_params
from abcwc.types import SONAR_FRAME, SensorFrame, StatusFlags, Twist

STOP_ON_ARC_ABOVE = 0.02
"""m/s: above this speed a wanted stop brakes along the present arc (rule 5)."""


@dataclass(frozen=True)
class ComfortLimits:
    """Motion limits for a seated person (SI units), and the filter's timings.

    Sources: longitudinal comfort for *standing* passengers is about 1.1-1.5 m/s^2 of
    acceleration and 0.3 g/s (2.9 m/s^3) of jerk (Hoberock, "A survey of longitudinal
    acceleration comfort studies in ground transportation vehicles", ASME J. Dyn. Sys.
    Meas. Control 99(2), 1977), the figures Gulati's comfortable-wheelchair planner
    works from (Gulati, PhD thesis, UT Austin, 2011). A wheelchair user is seated but
    rarely strapped in and may have poor trunk control, so we stay below them:
    ``max_accel`` 0.8 m/s^2, ``max_jerk`` 2.0 m/s^3, and a turn no harsher than
    ``max_accel`` sideways (``v w <= max_lateral_accel``). ``max_speed`` 1.0 m/s is a
    brisk walk indoors, below the chair's 6 km/h (1.67 m/s); reversing, with only the
    IR ring looking back, is held to a shuffle. ``max_turn_rate`` 0.8 rad/s (46 deg/s)
    is half the chair's full-deflection rate.
    """

    max_speed: float = 1.0  # m/s forward
    max_reverse_speed: float = 0.3  # m/s backward
    max_turn_rate: float = 0.8  # rad/s
    max_accel: float = 0.8  # m/s^2, speeding up and slowing down
    max_jerk: float = 2.0  # m/s^3
    max_angular_accel: float = 1.5  # rad/s^2
    max_lateral_accel: float = 0.8  # m/s^2, |v w|
    stop_margin: float = 0.15  # m kept beyond the braking distance
    side_margin: float = 0.10  # m each side of the chair's width in the swept strip
    stale_after: float = 0.5  # s a command is good for
    resume_delay: float = 1.0  # s still after the joystick is let go

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
                    math.isfinite(value) and value >= 0):
                raise ValueError(f"ComfortLimits.{name} must be a finite number >= 0, "
                                 f"got {value!r}")
        for name in ("max_speed", "max_turn_rate", "max_accel", "max_jerk",
                     "max_angular_accel", "stale_after"):
            if getattr(self, name) == 0:
                raise ValueError(f"ComfortLimits.{name} must be > 0")


class RangeSensorRay(NamedTuple):
    """A range sensor on the chair: its ``mount`` ``(x, y, yaw)`` in base_link (m, rad),
    the ``half_angle`` (rad) of its cone (0 for a ray) and its range limits (m)."""

    mount: np.ndarray
    half_angle: float
    min_range: float
    max_range: float


def range_sensor_rays(params: ChairParams) -> dict[str, RangeSensorRay]:
    """Each range sensor's frame id -> its :class:`RangeSensorRay`: the sonar and the six
    IR rangers, from chair.toml."""
    rays = {SONAR_FRAME: RangeSensorRay(np.asarray(params.sonar.mount, dtype=float),
                                        math.radians(params.sonar.half_angle_deg),
                                        params.sonar.min_range, params.sonar.max_range)}
    for frame_id, mount in zip(params.ir.frame_ids, params.ir.mounts):
        rays[frame_id] = RangeSensorRay(mount, 0.0, params.ir.min_range, params.ir.max_range)
    return rays


class SafetyFilter:
    """Apply :class:`ComfortLimits` and the stop rules to commands (module notes).

    Call :meth:`apply` once per control period with the frame and the wanted command.
    """

    def __init__(self, params: ChairParams | None = None,
                 limits: ComfortLimits | None = None):
        self.params = p = params or default_params()
        self.limits = limits or ComfortLimits()
        sensing = 1.0 / min(p.sonar.rate_hz, p.ir.rate_hz)
        self.reaction_time = sensing + p.command_delay + p.motor_time_constant  # s
        self._rays = range_sensor_rays(p)
        self._front = p.length - p.axle_to_rear  # m, base_link to the front edge
        self._rear = p.axle_to_rear
        self._half_width = p.width / 2 + self.limits.side_margin
        self.interventions: Counter[str] = Counter()
        self.reset()

    def reset(self) -> None:
        """Forget the ramp (standing still) and the last reason."""
        self.v = self.w = self.accel = 0.0
        self.reason: str | None = None
        self._released_at = -math.inf
        self._overridden = False

    # ------------------------------------------------------------------ the rules
    def braking_distance(self, speed: float) -> float:
        """m the chair travels after an obstacle is sensed at ``speed`` m/s, plus the
        stop margin (module notes)."""
        return abs(speed) * self.reaction_time + self.limits.stop_margin

    def clearance(self, frame: SensorFrame, forward: bool = True) -> tuple[float, str | None]:
        """The nearest range return in the strip the chair sweeps ahead (``forward``) or
        behind, as (m from the chair's front or rear edge; the frame id that saw it), or
        ``(inf, None)``. A cone is tried along its axis and both edges."""
        nearest, seen_by = math.inf, None
        for frame_id, (mount, half_angle, min_range, _) in self._rays.items():
            reading = frame.readings.get(frame_id, math.nan)
            if reading is None or math.isnan(reading) or reading == math.inf:
                continue
            if reading == -math.inf or reading <= min_range:  # somewhere nearer than min
                facing = math.cos(mount[2]) if forward else -math.cos(mount[2])
                if facing >= 0.5 - 1e-9 and nearest > 0.0:
                    nearest, seen_by = 0.0, frame_id
                continue
            distance = float(reading)
            yaws = mount[2] + np.array([-half_angle, 0.0, half_angle])
            x = mount[0] + distance * np.cos(yaws)
            y = mount[1] + distance * np.sin(yaws)
            ahead = (x - self._front) if forward else (-self._rear - x)
            in_strip = (np.abs(y) <= self._half_width) & (ahead >= 0)
            if in_strip.any() and ahead[in_strip].min() < nearest:
                nearest, seen_by = float(ahead[in_strip].min()), frame_id
        return nearest, seen_by

    def apply(self, frame: SensorFrame, command: Twist, decided_at: float | None = None
              ) -> Twist:
        """The command to send for ``frame`` when ``command`` (decided at ``decided_at``
        s, default now) is wanted."""
        if not isinstance(command, Twist):
            raise ValueError(f"the safety filter takes a Twist (m/s, rad/s), got "
                             f"{type(command).__name__}")
        lim, dt = self.limits, self.params.control_period
        self.reason = None
        decided_at = frame.t if decided_at is None else decided_at
        if frame.flags & StatusFlags.JOYSTICK_OVERRIDE:
            self._overridden = True
            return self._stop("joystick override")
        if self._overridden:
            self._overridden, self._released_at = False, frame.t
        if frame.t - self._released_at < lim.resume_delay:
            return self._stop("joystick just released")
        if frame.t - decided_at > lim.stale_after:
            return self._stop("stale command", f"{frame.t - decided_at:.2f} s old")

        v = min(max(command.v, -lim.max_reverse_speed), lim.max_speed)
        w = min(max(command.w, -lim.max_turn_rate), lim.max_turn_rate)
        if abs(v * w) > lim.max_lateral_accel:
            w = math.copysign(lim.max_lateral_accel / abs(v), w)
        if (v, w) != (command.v, command.w):
            self._note("speed limit")

        moving = v if abs(v) > abs(self.v) else self.v  # the faster of wanted and present
        if v != 0.0:
            gap, seen_by = self.clearance(frame, forward=v > 0)
            if gap <= self.braking_distance(moving):
                self.v = self.accel = 0.0
                self.w = self._ramp_turn(w, dt)
                self._note("obstacle", f"{gap:.2f} m {'ahead' if v > 0 else 'behind'}, "
                                       f"seen by {seen_by}")
                return Twist(0.0, self.w)
        if v == 0.0 and w == 0.0 and abs(self.v) > STOP_ON_ARC_ABOVE:
            # a stop keeps to the arc the chair is on: the turn rate slows with the
            # speed, in proportion, so the way it sweeps while braking is the way the
            # planner checked (slowing the turn faster, as the turn ramp alone would,
            # straightens the path and swings the front into what the arc avoided)
            curvature = self.w / self.v
            self.v = self._ramp_speed(0.0, dt)
            self.w = curvature * self.v
            return Twist(self.v, self.w)
        self.v = self._ramp_speed(v, dt)
        self.w = self._ramp_turn(w, dt)
        return Twist(self.v, self.w)

    # ------------------------------------------------------------------ helpers
    def _stop(self, kind: str, detail: str = "") -> Twist:
        self.v = self.w = self.accel = 0.0
        self._note(kind, detail)
        return Twist(0.0, 0.0)

    def _note(self, kind: str, detail: str = "") -> None:
        """Count an intervention of ``kind`` and add it to :attr:`reason`."""
        self.interventions[kind] += 1
        said = f"{kind} ({detail})" if detail else kind
        self.reason = said if self.reason is None else f"{self.reason}; {said}"

    def _ramp_speed(self, target: float, dt: float) -> float:
        """One period of a jerk-limited ramp towards ``target`` m/s. The acceleration
        aims at the gap but stays low enough that easing it off at the jerk limit, one
        period at a time, closes the gap as it reaches zero (``a dt / 2 + a^2 / (2 j)
        <= |gap|``), and changes by at most ``max_jerk dt`` per period, except in the
        period or two where the ramp lands on the target (by at most a quarter more)."""
        lim = self.limits
        gap = target - self.v
        if abs(gap) < 1e-12:
            self.accel = 0.0
            return target
        j = lim.max_jerk
        bound = j * (math.sqrt(dt * dt / 4 + 2 * abs(gap) / j) - dt / 2)
        wanted = math.copysign(min(lim.max_accel, bound), gap)
        self.accel = min(max(wanted, self.accel - j * dt), self.accel + j * dt)
        new = self.v + self.accel * dt
        if (target - new) * gap <= 0:  # reached or overshot: land on the target
            new, self.accel = target, gap / dt
        return new

    def _ramp_turn(self, target: float, dt: float) -> float:
        step = self.limits.max_angular_accel * dt
        return min(max(target, self.w - step), self.w + step)
