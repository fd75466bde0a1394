"""The motor controller and drive train: pot bytes in, wheel motion out.

Model (per control period ``dt``):

1. the bytes wait ``command_delay`` in a queue (the controller's input latency);
2. each byte becomes a deflection (:func:`abcwc.control.pots.pot_byte_to_deflection`):
   FB -> ``v = u_fb * max_speed``, LR -> ``w = -u_lr * max_turn_rate``;
3. the controller mixes them into wheel set-points with the nominal wheel base
   ``b``: ``v_r,l = v +- w b / 2``, scaled down together if one exceeds
   ``max_speed`` (so the curvature is kept);
4. each motor follows its set-point with a first-order lag, exactly discretised:
   ``s += (set - s) (1 - exp(-dt / tau))``;
5. a tyre of actual diameter ``k d_w`` turns the motor's nominal surface speed into
   ``k s``; random slip scales the ground speed by ``1 + N(0, slip_std)``.

The chair's motion is then ``v = (g_r + g_l) / 2`` and ``w = (g_r - g_l) / b_eff``
with the effective wheel base ``b_eff``. The wheel-on-wheel encoders roll on the
tyre surface, so they measure the tyre's travel before slip.
"""

from __future__ import annotations

import math
import numbers
from collections import deque
from dataclasses import dataclass, fields, replace

import numpy as np

from abcwc.control.pots import pot_byte_to_deflection
from abcwc.params import ChairParams
from abcwc.types import PotCommand


@dataclass(frozen=True)
class ChairErrors:
    """Systematic and random errors of a simulated chair (1.0 = as nominal).

    * ``drive_wheel_left/right``: actual / nominal drive-tyre diameter; unequal tyres
      make equal pots drive a curve.
    * ``encoder_wheel_left/right``: actual / nominal encoder-wheel diameter; they
      scale what the encoders count per metre (what UMBmark's E_d corrects).
    * ``wheel_base``: effective / nominal wheel base (UMBmark's E_b).
    * ``slip_std``: random slip, 1-sigma relative ground-speed error per wheel per step.
    """

    drive_wheel_left: float = 1.0
    drive_wheel_right: float = 1.0
    encoder_wheel_left: float = 1.0
    encoder_wheel_right: float = 1.0
    wheel_base: float = 1.0
    slip_std: float = 0.0

    def __post_init__(self) -> None:
        """Check every field is a real number in its range; store it as a float
        (so numpy scalars, an ``np.uint8(1)`` too, become plain floats)."""
        for f in fields(self):
            value = getattr(self, f.name)
            low, high, unit = ((0.0, 0.2, "") if f.name == "slip_std"
                               else (0.5, 1.5, " (a ratio)"))
            if isinstance(value, bool) or not isinstance(value, numbers.Real) \
                    or not low <= value <= high:
                raise ValueError(f"ChairErrors.{f.name} {value!r} outside {low:g}..{high:g}{unit}")
            object.__setattr__(self, f.name, float(value))

    @classmethod
    def ideal(cls) -> ChairErrors:
        """A perfect chair: no systematic error, no slip."""
        return cls()

    @classmethod
    def worn(cls) -> ChairErrors:
        """A seven-year-old chair like the thesis's: the right tyre 1 % larger, encoder
        wheels that count about 1.2 % short (the firmware's 1242.7 vs 1258 counts per
        turn), a 3 % larger effective wheel base, and a little slip."""
        return cls(1.0, 1.01, 1.0123, 1.0124, 1.03, 0.003)

    def with_(self, **changes: float) -> ChairErrors:
        """A copy with some fields changed."""
        return replace(self, **changes)


def resolve_errors(errors: ChairErrors | str | None) -> ChairErrors:
    """Accept a ChairErrors, or the preset names ``"ideal"`` / ``"worn"``."""
    if errors is None or errors == "ideal":
        return ChairErrors.ideal()
    if errors == "worn":
        return ChairErrors.worn()
    if isinstance(errors, ChairErrors):
        return errors
    raise ValueError(f"errors {errors!r} is not a ChairErrors or one of 'ideal', 'worn'")


@dataclass(frozen=True)
class WheelMotion:
    """One period's wheel motion (m/s): tyre surface speeds and ground speeds."""

    surface_left: float
    surface_right: float
    ground_left: float
    ground_right: float
    v: float  # body forward speed (m/s)
    w: float  # body turn rate (rad/s)


class MotorController:
    """Pot bytes -> wheel speeds, with delay, lag, tyre sizes and slip."""

    def __init__(self, params: ChairParams, errors: ChairErrors, period: float,
                 rng: np.random.Generator):
        self.params = params
        self.errors = errors
        self.period = period
        delay_steps = max(0, round(params.command_delay / period))
        neutral = PotCommand(params.pot_neutral, params.pot_neutral)
        self._queue: deque[PotCommand] = deque([neutral] * delay_steps)
        self._alpha = 1.0 - math.exp(-period / params.motor_time_constant)
        self._left = 0.0  # motor speeds as nominal tyre surface speeds (m/s)
        self._right = 0.0
        self._rng = rng
        self._slip = np.zeros((0, 2))
        self._slip_index = 0
        self.wheel_base = params.wheel_base * errors.wheel_base

    def _next_slip(self) -> tuple[float, float]:
        if self.errors.slip_std == 0.0:
            return 0.0, 0.0
        if self._slip_index >= len(self._slip):
            self._slip = self._rng.normal(0.0, self.errors.slip_std, size=(1024, 2))
            self._slip_index = 0
        left, right = self._slip[self._slip_index]
        self._slip_index += 1
        return float(left), float(right)

    def setpoints(self, pots: PotCommand) -> tuple[float, float]:
        """Steady-state wheel set-points (m/s, left and right) for a pair of bytes."""
        p = self.params
        v = pot_byte_to_deflection(pots.fb, p) * p.max_speed
        w = -pot_byte_to_deflection(pots.lr, p) * p.max_turn_rate
        half = w * p.wheel_base / 2.0
        left, right = v - half, v + half
        biggest = max(abs(left), abs(right))
        if biggest > p.max_speed:
            scale = p.max_speed / biggest
            left, right = left * scale, right * scale
        return left, right

    def advance(self, pots: PotCommand) -> WheelMotion:
        """Feed this period's bytes; return the wheel motion over the period."""
        if self._queue:
            self._queue.append(pots)
            pots = self._queue.popleft()
        set_left, set_right = self.setpoints(pots)
        self._left += (set_left - self._left) * self._alpha
        self._right += (set_right - self._right) * self._alpha
        surface_left = self._left * self.errors.drive_wheel_left
        surface_right = self._right * self.errors.drive_wheel_right
        slip_left, slip_right = self._next_slip()
        ground_left = surface_left * (1.0 + slip_left)
        ground_right = surface_right * (1.0 + slip_right)
        return WheelMotion(
            surface_left,
            surface_right,
            ground_left,
            ground_right,
            (ground_left + ground_right) / 2.0,
            (ground_right - ground_left) / self.wheel_base,
        )
