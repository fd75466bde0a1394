"""Wander without touching anything: the sonar rule of table 7, made safe.

The thesis's avoider (4.1.6, A.6) drives at full speed while the sonar sees nothing
within 1 m, turns by table 7's angle (45 degrees at 1 m to 90 degrees at 0.2 m) at a
slow speed when it does, and reverses when closer than 0.2 m. Three things keep our
version off the walls where the thesis's would not be:

* the MB1013 never reads below 0.30 m, so the "reverse" row is triggered by the IR
  ring instead (front and the two front-quarter sensors);
* the turn goes to the side with more room (the IR sensors at +-60 degrees), held
  until the way is clear, instead of always the same way;
* the turn speed falls with the distance, so the chair turns on the spot at 0.3 m.

On the real chair the IR ring is not wired to the firmware (its readings are NaN) and
the sonar reads NaN while it hears no echo: the avoider then runs on the sonar alone,
turning right like the thesis's, and NaN sonar counts as nothing in range.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from abcwc.behaviours.base import LOOP_RATE_HZ, BehaviourBase, positive_number
from abcwc.control.pots import AvoidAction, angle_to_lr_byte, sonar_turn_angle
from abcwc.control.velocity import twist_to_pot_command
from abcwc.params import ChairParams, default_params
from abcwc.types import NEUTRAL, PotCommand, SensorFrame, Twist

FRONT, FRONT_LEFT, FRONT_RIGHT = 0, 1, 5  # IR ring indices (0, +60, -60 degrees)


def _ir_distance(reading: float, max_range: float) -> float:
    """An IR reading as a distance: -inf (too close) -> 0, inf (clear) -> max range."""
    if reading == -math.inf:
        return 0.0
    return min(reading, max_range)


def freer_side(ir: Sequence[float], max_range: float) -> float:
    """+1 (left) or -1 (right): the side whose two IR sensors (1 and 2 on the left, 5 and
    4 on the right, section 2.2.5's ring) see more room, each reading taken as a distance
    (too close: 0, clear: ``max_range``); left on a tie."""
    left = _ir_distance(float(ir[FRONT_LEFT]), max_range) + _ir_distance(float(ir[2]), max_range)
    right = (_ir_distance(float(ir[FRONT_RIGHT]), max_range)
             + _ir_distance(float(ir[4]), max_range))
    return 1.0 if left >= right else -1.0


class SonarAvoider(BehaviourBase):
    """A behaviour (a controller for ``Base.run``): frame -> PotCommand, until cancelled.

    ``cruise`` and ``slow`` are forward speeds (m/s) in the clear and while turning
    at 1 m; ``near`` (m, 0..the IR range) is the IR distance that makes the chair back
    off for ``reverse_time`` seconds. A wander has no goal: it runs until
    :meth:`cancel`, then sends neutral pots.
    """

    def __init__(self, cruise: float = 0.6, slow: float = 0.3, near: float = 0.35,
                 reverse_time: float = 1.2, params: ChairParams | None = None,
                 rate_hz: float = LOOP_RATE_HZ):
        super().__init__(rate_hz)
        self.params = params or default_params()
        for name, value in (("cruise", cruise), ("slow", slow)):
            if not (positive_number(name, value, "m/s") <= self.params.max_speed):
                raise ValueError(f"{name} speed {value!r} outside 0..{self.params.max_speed:g} m/s")
        ir_range = self.params.ir.max_range
        if not positive_number("near", near, "m") < ir_range:
            raise ValueError(f"near must be a distance in 0..{ir_range:g} m (the IR range), "
                             f"got {near!r}")
        self.cruise, self.slow = float(cruise), float(slow)
        self.near = float(near)
        self.reverse_time = positive_number("reverse_time", reverse_time, "s")
        self.reset()

    def reset(self) -> None:
        """Start over: cruising, no turn side chosen."""
        super().reset()
        self._turn_sign = 1.0  # +1 left, -1 right
        self._turning = False
        self._reverse_until = -math.inf
        self.last_action = AvoidAction.FORWARD

    def stop_command(self) -> PotCommand:
        """Neutral pots: the chair stands still."""
        return NEUTRAL

    def _room(self, frame: SensorFrame, index: int) -> float:
        return _ir_distance(float(frame.ir[index]), self.params.ir.max_range)

    def update(self, frame: SensorFrame) -> PotCommand:
        front_near = min(self._room(frame, k) for k in (FRONT, FRONT_LEFT, FRONT_RIGHT))
        if front_near < self.near and frame.t >= self._reverse_until:
            self._reverse_until = frame.t + self.reverse_time
            self._turn_sign = self._freer_side(frame)
        if frame.t < self._reverse_until:
            self.last_action = AvoidAction.REVERSE
            return twist_to_pot_command(
                Twist(-0.3, self._turn_sign * 0.6), self.params)
        # NaN: the real chair's sonar heard no echo, so nothing is within its range
        sonar = frame.sonar if math.isfinite(frame.sonar) else self.params.sonar.max_range
        decision = sonar_turn_angle(sonar)
        if decision.action is AvoidAction.FORWARD:
            self._turning = False
            self.last_action = AvoidAction.FORWARD
            return twist_to_pot_command(Twist(self.cruise, 0.0), self.params)
        if not self._turning:
            self._turning = True
            self._turn_sign = self._freer_side(frame)
        # table 7's angle -> LR byte by eqn 2 and eqn 1; slower the nearer it is
        lr = angle_to_lr_byte(self._turn_sign * decision.angle_deg, self.params)
        closeness = (1.0 - sonar) / 0.7  # 0 at 1 m, 1 at 0.3 m
        speed = self.slow * max(0.0, 1.0 - closeness)
        fb = twist_to_pot_command(Twist(speed, 0.0), self.params).fb
        self.last_action = AvoidAction.TURN
        return PotCommand(fb, lr)

    def _freer_side(self, frame: SensorFrame) -> float:
        return freer_side(frame.ir, self.params.ir.max_range)
