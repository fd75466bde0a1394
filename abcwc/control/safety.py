"""The safety filter: every command from software passes through it on its way to the pots.

A planner proposes; the filter disposes. Every chair body owns one
(:attr:`abcwc.base.BodyMixin.safety`) and its ``send`` passes each command through it,
so every controller, behaviour and notebook cell is filtered in the one control loop,
as Nav2's collision monitor sits between every controller and the base. At every
control period (50 Hz) it takes the command wanted (a :class:`~abcwc.types.Twist` or a
:class:`~abcwc.types.PotCommand`) and the newest :class:`~abcwc.types.SensorFrame`, and
returns what may be sent. A teaching experiment that needs the bare chair asks for it
by name (``chair.run(controller, seconds, safety=None)``). Its rules for a Twist, in
order:

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
   ahead when driving forward, behind when reversing: the way it is asked to go, and
   the way it still rolls while braking) nearer than the braking distance at the
   current speed, the motion along that way is stopped at once, without the ramp: a
   stop asked for near something is not left to the comfort ramp either. A reading at or
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

**Raw pot bytes** (a :class:`~abcwc.types.PotCommand`, chapter 01's bytes) get rules 1,
2, 4 and the speed cap of rule 3, not the ramps of rule 5: the bytes are what the
chapter teaches, and the motor controller's own lag (``motor_time_constant``) shapes
them. The bytes are read as the steady speed the motor controller makes of them
(:func:`~abcwc.control.velocity.pot_command_to_twist`); a byte beyond the one the
velocity controller (:func:`~abcwc.control.velocity.twist_to_pot_command`) gives for a
:class:`ComfortLimits` speed or turn rate is brought back to that byte; an
obstacle stop puts the FB byte at neutral and keeps the LR byte (turning on the spot
sweeps no strip ahead); a joystick or stale-command stop sends neutral pots.

The braking distance comes from the chair's model (chair.toml): the sensing period, the
motor controller's input delay and the wheels' first-order lag ``tau`` (a first-order
lag stops from ``v`` in ``v tau``), plus ``stop_margin``::

    d_brake(v) = v (1 / sensor_rate + command_delay + tau) + stop_margin

Where the filter changed a command, :attr:`SafetyFilter.reason` says why (a control
loop records it in the RunLog's ``safety`` channel), and
:attr:`SafetyFilter.interventions` counts each kind. :class:`ClearanceCheck` is the
geometry of rule 4 alone (the swept strip, the braking distance), for planners that
must foresee what the filter will let through.
"""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from abcwc.control.velocity import pot_command_to_twist, twist_to_pot_command
from abcwc.params import ChairParams, default_params
from abcwc.types import SONAR_FRAME, PotCommand, SensorFrame, StatusFlags, Twist

STOP_ON_ARC_ABOVE = 0.02
"""m/s: above this speed a wanted stop brakes along the present arc (rule 5), and the way
the chair still rolls is checked for obstacles (rule 4)."""


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


class ClearanceCheck:
    """Rule 4's geometry: how far the strip the chair sweeps ahead (or behind) is clear
    by its range sensors, and how far it needs to stop (module notes).

    ``reaction_time`` (s) is the sensing period, the motor controller's input delay and
    the wheels' lag; :meth:`braking_distance` and :meth:`clearance` are what the safety
    filter compares. Planners that must foresee the filter (the tag follower, the
    navigator's back-off) use the same check.
    """

    def __init__(self, params: ChairParams | None = None,
                 limits: ComfortLimits | None = None):
        self.params = p = params or default_params()
        self.limits = limits or ComfortLimits()
        sensing = 1.0 / min(p.sonar.rate_hz, p.ir.rate_hz)
        self.reaction_time = sensing + p.command_delay + p.motor_time_constant  # s
        rays = range_sensor_rays(p)
        self.frame_ids = tuple(rays)
        # per sensor: its mount's x, y, the cosine of its yaw (> 0: it looks forward), its
        # minimum range, and the direction (cos, sin) of its axis and both cone edges
        self._rays = tuple(
            (frame_id, float(ray.mount[0]), float(ray.mount[1]), math.cos(ray.mount[2]),
             ray.min_range, tuple((math.cos(ray.mount[2] + k * ray.half_angle),
                                   math.sin(ray.mount[2] + k * ray.half_angle))
                                  for k in (-1.0, 0.0, 1.0)))
            for frame_id, ray in rays.items())
        self._front = p.length - p.axle_to_rear  # m, base_link to the front edge
        self._rear = p.axle_to_rear
        self._half_width = p.width / 2 + self.limits.side_margin

    def braking_distance(self, speed: float) -> float:
        """m the chair travels after an obstacle is sensed at ``speed`` m/s, plus the
        stop margin (module notes)."""
        return abs(speed) * self.reaction_time + self.limits.stop_margin

    def clearance(self, frame: SensorFrame, forward: bool = True) -> tuple[float, str | None]:
        """The nearest range return in the strip the chair sweeps ahead (``forward``) or
        behind, as (m from the chair's front or rear edge; the frame id that saw it), or
        ``(inf, None)``. A cone is tried along its axis and both edges; a reading at or
        below the sensor's minimum, from a sensor facing within 60 degrees of the way,
        counts as touching (0 m). (Seven sensors, three directions each: plain Python
        runs this every period faster than array calls would.)"""
        readings = frame.readings
        nearest, seen_by = math.inf, None
        for frame_id, x0, y0, facing, min_range, directions in self._rays:
            reading = _range_of(readings.get(frame_id))
            if reading == -math.inf or (math.isfinite(reading) and reading <= min_range):
                if (facing if forward else -facing) >= 0.5 - 1e-9:
                    return 0.0, frame_id  # something at most min_range away: touching
                continue
            if not math.isfinite(reading):  # NaN: no reading; inf: nothing in range
                continue
            for cos_yaw, sin_yaw in directions:
                x, y = x0 + reading * cos_yaw, y0 + reading * sin_yaw
                ahead = (x - self._front) if forward else (-self._rear - x)
                if 0.0 <= ahead < nearest and abs(y) <= self._half_width:
                    nearest, seen_by = ahead, frame_id
        return nearest, seen_by


def joystick_overrides(frame: SensorFrame) -> bool:
    """Whether the person in the seat is driving: the frame's ``JOYSTICK_OVERRIDE`` flag,
    set by the interface board (the simulator's, or the firmware's) while the joystick
    is deflected out of its dead band. Rule 1 and the mission layer ask this one question."""
    return bool(frame.flags & StatusFlags.JOYSTICK_OVERRIDE)


def _range_of(reading: object) -> float:
    """A range reading as a float: NaN for none (or a reading that is not a range)."""
    return float(reading) if isinstance(reading, (int, float)) else math.nan


class SafetyFilter:
    """Apply :class:`ComfortLimits` and the stop rules to commands (module notes).

    Call :meth:`apply` once per control period with the frame and the wanted command;
    a body does it in its ``send``. :attr:`check` is the :class:`ClearanceCheck` the
    obstacle stop uses.
    """

    def __init__(self, params: ChairParams | None = None,
                 limits: ComfortLimits | None = None):
        self.check = ClearanceCheck(params, limits)
        self.params, self.limits = p, lim = self.check.params, self.check.limits
        # the velocity controller's bytes for the limits: raw bytes beyond are brought back
        self._limit_bytes = (
            twist_to_pot_command(Twist(lim.max_speed, lim.max_turn_rate), p),
            twist_to_pot_command(Twist(-lim.max_reverse_speed, -lim.max_turn_rate), p))
        self.interventions: Counter[str] = Counter()
        self.reset()

    def reset(self) -> None:
        """Forget the ramp (standing still), the joystick's release and the last reason."""
        self.v = self.w = self.accel = 0.0
        self.reason: str | None = None
        self._released_at = -math.inf
        self._overridden = False

    def stopped(self) -> None:
        """The chair was stopped outside the filter (``Base.stop``): the ramp starts
        again from standing; the joystick's release is remembered."""
        self.v = self.w = self.accel = 0.0

    def apply(self, frame: SensorFrame, command: Twist | PotCommand,
              decided_at: float | None = None) -> Twist | PotCommand:
        """The command to send for ``frame`` when ``command`` (decided at ``decided_at``
        s, default now) is wanted: a Twist for a Twist, pot bytes for pot bytes."""
        if not isinstance(command, (Twist, PotCommand)):
            raise ValueError(f"the safety filter takes a Twist (m/s, rad/s) or a PotCommand "
                             f"(bytes 0..255), got {type(command).__name__}")
        self.reason = None
        decided_at = frame.t if decided_at is None else decided_at
        held = self._held(frame, decided_at)
        if held is not None:
            self._stop(*held)
            return Twist(0.0, 0.0) if isinstance(command, Twist) else self._neutral()
        if isinstance(command, PotCommand):
            return self._apply_pots(frame, command)
        return self._apply_twist(frame, command)

    def _held(self, frame: SensorFrame, decided_at: float) -> tuple[str, str] | None:
        """Rules 1 and 2: (kind, detail) of a stop the joystick or a stale command
        calls for, or None."""
        lim = self.limits
        if joystick_overrides(frame):
            self._overridden = True
            return "joystick override", ""
        if self._overridden:
            self._overridden, self._released_at = False, frame.t
        if frame.t - self._released_at < lim.resume_delay:
            return "joystick just released", ""
        if frame.t - decided_at > lim.stale_after:
            return "stale command", f"{frame.t - decided_at:.2f} s old"
        return None

    def _apply_twist(self, frame: SensorFrame, command: Twist) -> Twist:
        """Rules 3-5 for a Twist."""
        lim, dt = self.limits, self.params.control_period
        v = min(max(command.v, -lim.max_reverse_speed), lim.max_speed)
        w = min(max(command.w, -lim.max_turn_rate), lim.max_turn_rate)
        if abs(v * w) > lim.max_lateral_accel:
            w = math.copysign(lim.max_lateral_accel / abs(v), w)
        if (v, w) != (command.v, command.w):
            self._note("speed limit")

        moving = v if abs(v) > abs(self.v) else self.v  # the faster of wanted and present
        # the ways the chair goes: where it is asked to, and where it still rolls while
        # the ramp brakes it (a stop wanted near something must not take the comfort ramp)
        ways = [v] if v != 0.0 else []
        if abs(self.v) > STOP_ON_ARC_ABOVE and (v == 0.0 or (v > 0) != (self.v > 0)):
            ways.append(self.v)
        if any(self._obstacle_stop(frame, way, moving) for way in ways):
            self.v = self.accel = 0.0
            self.w = self._ramp_turn(w, dt)
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

    def _apply_pots(self, frame: SensorFrame, command: PotCommand) -> PotCommand:
        """Rule 3's speed cap and rule 4 for raw pot bytes (module notes); no ramps."""
        p = self.params
        fb, lr = command.fb, command.lr
        steady = pot_command_to_twist(command, p)
        v, w = steady.v, steady.w
        fastest, slowest = self._limit_bytes
        fb = min(max(fb, slowest.fb), fastest.fb)
        lr = min(max(lr, fastest.lr), slowest.lr)  # LR below 128 turns left
        if (fb, lr) != (command.fb, command.lr):
            self._note("speed limit")
            steady = pot_command_to_twist(PotCommand(fb, lr), p)
            v, w = steady.v, steady.w
        moving = v if abs(v) > abs(self.v) else self.v
        if v != 0.0 and self._obstacle_stop(frame, v, moving):
            fb, v = p.pot_neutral, 0.0
        self.v, self.w, self.accel = v, w, 0.0
        return PotCommand(fb, lr)

    def _obstacle_stop(self, frame: SensorFrame, v: float, moving: float) -> bool:
        """Rule 4: whether something is within braking distance (at ``moving`` m/s) in
        the strip the chair sweeps going at ``v``; notes it if so."""
        gap, seen_by = self.check.clearance(frame, forward=v > 0)
        if gap > self.check.braking_distance(moving):
            return False
        self._note("obstacle", f"{gap:.2f} m {'ahead' if v > 0 else 'behind'}, "
                               f"seen by {seen_by}")
        return True

    # ------------------------------------------------------------------ helpers
    def _stop(self, kind: str, detail: str = "") -> None:
        self.v = self.w = self.accel = 0.0
        self._note(kind, detail)

    def _neutral(self) -> PotCommand:
        return PotCommand(self.params.pot_neutral, self.params.pot_neutral)

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
