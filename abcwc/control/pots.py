"""From joystick and angles to the two digital-pot bytes (thesis 4.1.3-4.1.6).

The chair's motor controller reads two voltages from its joystick: FB (forward/back)
and LR (left/right). The interface board reads the joystick with a 10-bit ADC and
replays it through a two-channel digital pot; anything that drives the chair writes
those two pot bytes. Two scales appear:

* the **pot scale** of the joystick ADC: centre 254, 110..398 end to end, 144 points
  per 90 degrees (``degrees_scale`` = 1.6 per degree);
* the **pot byte** written to the MCP42010: 0..255, neutral 128, safe range 8..253.

Eqn 1 maps the first onto the second. Where the thesis is inconsistent, the
docstrings say so and which reading we keep.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

from abcwc.params import ChairParams, default_params
from abcwc.types import PotCommand, require_finite


def _check_range(name: str, value: float, low: float, high: float) -> float:
    number = require_finite(name, value)
    if not low <= number <= high:
        raise ValueError(f"{name} {value:g} outside {low:g}..{high:g}")
    return number


def joystick_to_pot_byte(value: float, params: ChairParams | None = None) -> int:
    """Eqn 1: pot byte = (joystick - 100) * 0.85, truncated as the firmware does.

    ``value`` is on the pot scale (110..398; 254 is the centre). The result is an
    integer byte 8..253. The arithmetic is done in integers, ``(v - 100) * 85 // 100``
    after truncating ``v``, exactly as the firmware does it, so host and chair agree.

    Worked values: 398 -> 253, 254 -> 130, 110 -> 8. Note the centre maps to 130,
    not the motor controller's neutral 128: the controller's +-2 dead band hides it.
    """
    p = params or default_params()
    number = _check_range("joystick value", value, p.joystick_min, p.joystick_max)
    multiplier_percent = round(p.eqn1_multiplier * 100)
    return (int(number) - p.eqn1_offset) * multiplier_percent // 100


def joystick_adc_to_pot_byte(adc: int, params: ChairParams | None = None) -> int:
    """What the interface board does with any joystick ADC reading: clamp it into
    the joystick's range (110..398), then eqn 1. The firmware's ``eqn1`` exactly."""
    p = params or default_params()
    return joystick_to_pot_byte(min(max(int(adc), p.joystick_min), p.joystick_max), p)


def turn_value(angle_deg: float, params: ChairParams | None = None) -> float:
    """Eqn 2: the LR pot-scale value for a turn of ``angle_deg`` degrees.

    ``turn = 254 - 1.6 * angle`` with angle in -90..90, positive to the left
    (counter-clockwise, ROS REP 103), so 0 -> 254, +90 -> 110 (full left),
    -90 -> 398 (full right). The result is clamped to 110..398.

    The thesis prints eqn 2 with the minus sign but its worked example adds
    (254 + 1.6 * 45 = 326); both are the same rule with the angle's sign flipped. We
    keep the sign of eqn 2 and of the velocity controller (A.14) and speech commands
    (A.4), where a lower LR byte turns left; table 6 lists left and right the other
    way round.
    """
    p = params or default_params()
    angle = _check_range("turn angle (deg)", angle_deg, -90.0, 90.0)
    value = p.joystick_centre - p.degrees_scale * angle
    return min(max(value, p.joystick_min), p.joystick_max)


def angle_to_lr_byte(angle_deg: float, params: ChairParams | None = None) -> int:
    """Eqn 2 then eqn 1: the LR pot byte for a turn angle (deg, + = left)."""
    return joystick_to_pot_byte(turn_value(angle_deg, params), params)


def pot_byte_to_deflection(byte: int, params: ChairParams | None = None) -> float:
    """The motor controller's reading of one pot byte as a deflection in -1..1.

    ``|byte - 128| <= dead_band`` (2) reads as 0; beyond it the deflection grows
    linearly to 1 at ``128 + 125`` (253, full forward / full right). This is our
    model of the controller, chosen so that eqn 1's centre (130) stands still and
    its ends (8, 253) are (almost) full scale.
    """
    p = params or default_params()
    offset = int(byte) - p.pot_neutral
    magnitude = abs(offset) - p.pot_dead_band
    if magnitude <= 0:
        return 0.0
    span = p.pot_full_scale_offset - p.pot_dead_band
    return math.copysign(min(magnitude / span, 1.0), offset)


def clamp_pot_byte(byte: int, params: ChairParams | None = None) -> int:
    """Clamp a byte into the safe pot range (8..253)."""
    p = params or default_params()
    return min(max(int(byte), p.pot_safe_min), p.pot_safe_max)


# Table 6 as printed: pot bytes for the four directions. "256" cannot be an 8-bit
# value; eqn 1 of the joystick's end (398) gives 253. Reverse "9" is 8.5 rounded;
# the firmware's truncation gives 8. Left and right are listed the other way round
# from eqn 2, A.4 and A.14 (see turn_value).
TABLE_6_AS_PRINTED = {
    "forward": (256, 128),
    "reverse": (9, 128),
    "right": (128, 9),
    "left": (128, 256),
}


def direction_pot_command(direction: str, params: ChairParams | None = None) -> PotCommand:
    """Table 6, corrected: full deflection in one direction as a PotCommand.

    ``direction`` is one of forward, reverse, left, right, stop. Full deflection is
    eqn 1 of the joystick's end values (398 -> 253, 110 -> 8).
    """
    p = params or default_params()
    high = joystick_to_pot_byte(p.joystick_max, p)
    low = joystick_to_pot_byte(p.joystick_min, p)
    table = {
        "forward": (high, p.pot_neutral),
        "reverse": (low, p.pot_neutral),
        "left": (p.pot_neutral, low),
        "right": (p.pot_neutral, high),
        "stop": (p.pot_neutral, p.pot_neutral),
    }
    if direction not in table:
        raise ValueError(f"direction {direction!r} is not one of {', '.join(table)}")
    return PotCommand(*table[direction])


class AvoidAction(Enum):
    """What the sonar rule of table 7 tells the chair to do."""

    FORWARD = "forward"
    TURN = "turn"
    REVERSE = "reverse"


@dataclass(frozen=True)
class SonarDecision:
    """Table 7's answer for one sonar distance: an action and a turn angle (deg)."""

    action: AvoidAction
    angle_deg: float = 0.0


def sonar_turn_angle(distance_m: float) -> SonarDecision:
    """Table 7 / eqn 3: the turn needed to clear an obstacle ``distance_m`` ahead.

    Beyond 1 m: no turn. From 1 m down to 0.2 m the angle grows linearly from 45 to
    90 degrees, 5.625 degrees per 100 mm: ``angle = 45 + (10 - d_mm / 100) * 5.625``
    (550 mm -> 70.3125 deg). Closer than 0.2 m: reverse.

    Where the thesis is not right: eqn 3 as printed leaves out the 45-degree base that
    its own worked example and A.6 add, and A.6 scales degrees by 1.711 instead of
    eqn 2's 1.6, which sends 90 degrees to 408 on the pot scale, past the 398 end, so
    the byte wraps around. We use eqn 2 (see :func:`angle_to_lr_byte`). Also, the
    MB1013 never reports less than 0.30 m, so the "reverse" row can only be reached
    with another sensor (chapter 03 uses the IR ring).
    """
    d = require_finite("sonar distance (m)", distance_m)
    if d < 0:
        raise ValueError(f"sonar distance {d:g} m outside 0..inf")
    if d > 1.0:
        return SonarDecision(AvoidAction.FORWARD, 0.0)
    if d < 0.2:
        return SonarDecision(AvoidAction.REVERSE, 0.0)
    return SonarDecision(AvoidAction.TURN, 45.0 + (10.0 - d * 1000.0 / 100.0) * 5.625)
