"""From a Twist (v, w) to the two pot bytes: the velocity controller.

Two controllers:

* :func:`thesis_twist_to_pots` reproduces appendix A.14 exactly (with the decimal
  handling its listing intends): speed in cm/s and turn rate in deg/s are both put on
  the pot scale at 1.6 points per unit, clamped to 110..398, then eqn 1. It is not a
  speed controller: 0.9 m/s already asks for full deflection, which is 6 km/h.
* :func:`twist_to_pot_command` is calibrated against the motor controller's model
  (:func:`abcwc.control.pots.pot_byte_to_deflection`): full deflection is
  ``max_speed`` (6 km/h) and ``max_turn_rate`` (90 deg/s), so the chair's
  steady-state speed is the one asked for. It works in integers (mm/s, mrad/s) and is
  the same code as the firmware's ``velocity_controller`` (firmware/core), bit for bit.
"""

from __future__ import annotations

import math

from abcwc.control.pots import clamp_pot_byte, pot_byte_to_deflection
from abcwc.params import ChairParams, default_params
from abcwc.types import PotCommand, Twist


def _axis_offset(value: int, full_scale: int, span: int, dead_band: int) -> int:
    """Distance of a pot byte from neutral for an integer command on one axis."""
    if value == 0:
        return 0
    magnitude = (abs(value) * span + full_scale // 2) // full_scale
    return dead_band + magnitude if magnitude else 0


def twist_to_pot_bytes_int(
    v_mm_s: int, w_mrad_s: int, params: ChairParams | None = None
) -> tuple[int, int]:
    """Integer velocity controller: (mm/s, mrad/s) -> (fb, lr) bytes in 8..253.

    ``offset = dead_band + round(|value| * 123 / full_scale)`` away from 128: FB up for
    forward, LR down for a left (positive) turn. Clamped to the safe range.
    """
    p = params or default_params()
    span = p.pot_full_scale_offset - p.pot_dead_band
    v_full = round(p.max_speed * 1000)
    w_full = round(p.max_turn_rate * 1000)
    fb = p.pot_neutral + int(math.copysign(1, v_mm_s)) * _axis_offset(
        int(v_mm_s), v_full, span, p.pot_dead_band
    )
    lr = p.pot_neutral - int(math.copysign(1, w_mrad_s)) * _axis_offset(
        int(w_mrad_s), w_full, span, p.pot_dead_band
    )
    return clamp_pot_byte(fb, p), clamp_pot_byte(lr, p)


def twist_to_wire_units(twist: Twist) -> tuple[int, int]:
    """A twist quantised as it goes over the wire: whole mm/s and mrad/s, int16."""
    v_mm = max(-32767, min(32767, round(twist.v * 1000)))
    w_mrad = max(-32767, min(32767, round(twist.w * 1000)))
    return v_mm, w_mrad


def twist_to_pot_command(twist: Twist, params: ChairParams | None = None) -> PotCommand:
    """Calibrated velocity controller: Twist (m/s, rad/s) -> PotCommand.

    The twist is quantised to whole mm/s and mrad/s (what goes over the wire to the
    firmware) and mapped by :func:`twist_to_pot_bytes_int`. Speeds beyond the chair's
    limits saturate at full deflection.
    """
    return PotCommand(*twist_to_pot_bytes_int(*twist_to_wire_units(twist), params))


def pot_command_to_twist(pots: PotCommand, params: ChairParams | None = None) -> Twist:
    """The steady speed (m/s) and turn rate (rad/s) the motor controller makes of pot
    bytes: each byte's deflection (:func:`~abcwc.control.pots.pot_byte_to_deflection`)
    times full speed and full turn rate, an LR byte below 128 turning left (positive).
    The inverse of :func:`twist_to_pot_command` up to its rounding; a frame's ``pot_fb``
    and ``pot_lr`` read this way give what the chair is being driven at now."""
    p = params or default_params()
    return Twist(pot_byte_to_deflection(pots.fb, p) * p.max_speed,
                 -pot_byte_to_deflection(pots.lr, p) * p.max_turn_rate)


def thesis_twist_to_pots(twist: Twist, params: ChairParams | None = None) -> PotCommand:
    """Appendix A.14's velocity controller, reproduced.

    ``lr = int(254 - deg(w) * 1.6)``, ``fb = int(254 + int(100 v) * 1.6)``, each clamped
    to 110..398 (the A.18 listing; A.14's own listing clamps at 10 below, which eqn 1
    would turn into a negative byte), then eqn 1 with C truncation. The listing
    computes the decimal part from an uninitialised variable; we use what it
    intends, ``int(100 v)``.
    """
    p = params or default_params()
    degrees = twist.w * 57.2958
    rotational = int(p.joystick_centre - degrees * p.degrees_scale)
    linear_cm = int(twist.v * 100)
    linear = int(p.joystick_centre + linear_cm * p.degrees_scale)
    clamp = lambda s: min(max(s, p.joystick_min), p.joystick_max)  # noqa: E731
    to_byte = lambda s: int((s - p.eqn1_offset) * p.eqn1_multiplier)  # noqa: E731
    return PotCommand(to_byte(clamp(linear)), to_byte(clamp(rotational)))
