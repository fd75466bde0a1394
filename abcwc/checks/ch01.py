"""Checks for chapter 01, joystick to wheels (thesis 4.1.3-4.1.4, table 6, A.3).

Exercises:

* ``joystick_to_pot(value)``: eqn 1, ``(value - 100) * 0.85`` truncated to an integer;
* ``table_6(direction)``: table 6 corrected, the full-deflection PotCommand for
  forward, reverse, left, right and stop;
* ``square_sequence(t)``: the open-loop square of appendix A.3 as a function of time:
  forward 5 s, left 2 s, three times, then forward 2.5 s and stop;
* ``measured_corners()``: one corner of the square measured on the simulated chairs
  (LEFT for 2 s from standstill, then stopped): the degrees turned by the worn chair and
  by the ideal one, against the motor model and the worn chair's faults;
* ``predicted_clockwise_heading_error()``: a number written down *before* the clockwise
  square is driven: the worn chair's heading error at its end (worn minus ideal, degrees,
  positive to the left), from the error budget the chapter works out for the
  counter-clockwise square.

:func:`reference_square_sequence` is the answer the notebook falls back on; the pot
functions fall back on :mod:`abcwc.control`.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from abcwc.checks.report import (
    NotYet,
    checker,
    expect,
    expect_equal,
    expect_no_slip,
    expect_own,
    format_value,
    numbers,
)
from abcwc.control import direction_pot_command, joystick_to_pot_byte
from abcwc.control.pots import pot_byte_to_deflection
from abcwc.control.safety import ComfortLimits
from abcwc.params import default_params
from abcwc.types import PotCommand

__all__ = [
    "FORWARD_FB",
    "LEFT_LR",
    "SQUARE_PHASES",
    "THESIS_EQN1_VALUES",
    "clockwise_budget",
    "clockwise_prediction_check",
    "corners_check",
    "pot_mapping",
    "reference_square_sequence",
    "square_phase",
    "square_sequence",
    "table_6",
]

# Eqn 1's worked values: the joystick's ends and centre (4.1.3, 4.1.5).
THESIS_EQN1_VALUES = ((398, 253), (254, 130), (110, 8))

# Appendix A.3: (what, seconds), in order; after the last phase the chair stops.
SQUARE_PHASES = (
    ("forward", 5.0), ("left", 2.0),
    ("forward", 5.0), ("left", 2.0),
    ("forward", 5.0), ("left", 2.0),
    ("forward", 2.5),
)
SQUARE_DURATION = sum(seconds for _, seconds in SQUARE_PHASES)  # 23.5 s

# The reference answer's bytes: 0.515 m/s forward, 0.79 rad/s (45 deg/s) to the left.
FORWARD_FB = 168
LEFT_LR = 64


def square_phase(t: float) -> str:
    """Which phase of A.3 the time ``t`` (s since the start) falls in, or ``"stop"``."""
    end = 0.0
    for name, seconds in SQUARE_PHASES:
        end += seconds
        if 0.0 <= t < end:
            return name
    return "stop"


def reference_square_sequence(t: float) -> PotCommand:
    """A.3's square as pot bytes at time ``t`` (s): forward (168, 128), left (128, 64)."""
    phase = square_phase(t)
    if phase == "forward":
        return PotCommand(FORWARD_FB, 128)
    if phase == "left":
        return PotCommand(128, LEFT_LR)
    return PotCommand(128, 128)


# --- checks ---------------------------------------------------------------------------


@checker("pot mapping")
def pot_mapping(fn: Callable[[int], int]) -> str:
    """Check eqn 1 at the thesis's worked values, then over the joystick's whole range."""
    expect_own(fn, joystick_to_pot_byte)
    for joystick, expected in THESIS_EQN1_VALUES:
        got = fn(joystick)
        _expect_int(got, joystick)
        if joystick == 254 and got == 131:
            expect(False, "joystick 254 gave 131, expected 130 (eqn 1: 154 * 0.85 = 130.9; "
                          "the firmware stores it in a byte, which truncates, not rounds)")
        expect_equal(got, expected, what=f"joystick {joystick}", ref="eqn 1")
    p = default_params()
    values = range(p.joystick_min, p.joystick_max + 1)
    for joystick in values:
        got = fn(joystick)
        _expect_int(got, joystick)
        expect_equal(got, joystick_to_pot_byte(joystick, p), what=f"joystick {joystick}",
                     ref="eqn 1, truncated")
    return (f"{len(THESIS_EQN1_VALUES)} thesis values and all {len(values)} joystick values "
            f"{p.joystick_min}..{p.joystick_max} match")


def _expect_int(got: object, joystick: int) -> None:
    expect(isinstance(got, int | np.integer) and not isinstance(got, bool),
           f"joystick {joystick} gave {format_value(got)} ({type(got).__name__}); a pot byte "
           "is a whole number: truncate with int(...)")


def _as_pair(command: object) -> tuple[int, int] | None:
    if isinstance(command, PotCommand):
        return command.fb, command.lr
    return None


@checker("table 6 corrected")
def table_6(fn: Callable[[str], PotCommand]) -> str:
    """Check the corrected table 6: full deflection per direction, as PotCommands."""
    expect_own(fn, direction_pot_command)
    directions = ("forward", "reverse", "left", "right", "stop")
    for direction in directions:
        got = fn(direction)
        pair = _as_pair(got)
        expect(pair is not None, f"{direction} gave {format_value(got)}; return a "
                                 "PotCommand(fb, lr)")
        expected = direction_pot_command(direction)
        other = {"left": "right", "right": "left"}.get(direction)
        if other and pair == (expected.fb, direction_pot_command(other).lr):
            expect(False, f"{direction} gave (fb {pair[0]}, lr {pair[1]}): that is table 6's "
                          "left/right as printed; eqn 2, A.4 and A.14 turn left with LR "
                          "below 128")
        expect_equal(pair, (expected.fb, expected.lr), what=f"{direction} (fb, lr)",
                     ref="eqn 1 of the joystick's ends")
    return "forward, reverse, left, right and stop match"


def _standing(byte: int) -> bool:
    """True when the motor controller reads ``byte`` as neutral (its +-2 dead band)."""
    p = default_params()
    return abs(byte - p.pot_neutral) <= p.pot_dead_band


@checker("square sequence")
def square_sequence(fn: Callable[[float], PotCommand]) -> str:
    """Check A.3's timing and directions at times inside every phase and after it.

    The bytes are the student's choice: forward needs FB above the dead band with LR
    neutral; left needs LR below it with FB neutral (128 +- 2); every forward phase must
    send the same bytes, and so must every turn. And someone sits in the chair: forward
    at most the safety filter's comfort speed and the turn at most its comfort turn
    rate (:class:`abcwc.control.safety.ComfortLimits`: 1.0 m/s and 0.8 rad/s), read
    through the motor controller's model (:func:`abcwc.control.pot_byte_to_deflection`
    times the chair's full-deflection speed and turn rate).
    """
    expect_own(fn, reference_square_sequence)
    p = default_params()
    seen: dict[str, tuple[int, int]] = {}
    samples = 0
    start = 0.0
    for number, (phase, seconds) in enumerate(SQUARE_PHASES, start=1):
        for t in (start + 0.01, start + seconds / 2, start + seconds - 0.01):
            samples += 1
            _check_sample(fn, t, phase, f"phase {number}: {phase} {seconds:g} s", seen, p)
        start += seconds
    for t in (SQUARE_DURATION + 0.01, SQUARE_DURATION + 1.0, 60.0):
        samples += 1
        _check_sample(fn, t, "stop", "after the square", seen, p)
    fb, lr = seen["forward"][0], seen["left"][1]
    return (f"{samples} sample times right: forward fb {fb}, left lr {lr}, "
            f"stop after {SQUARE_DURATION:g} s")


def _largest_byte(deflection: float, p: object) -> int:
    """The largest pot byte above 128 whose deflection is at most ``deflection``."""
    return max(b for b in range(129, 254) if pot_byte_to_deflection(b, p) <= deflection + 1e-12)


def _check_sample(fn: Callable[[float], PotCommand], t: float, phase: str, where: str,
                  seen: dict[str, tuple[int, int]], p: object) -> None:
    got = fn(t)
    pair = _as_pair(got)
    expect(pair is not None, f"t = {t:.2f} s gave {format_value(got)}; return a "
                             "PotCommand(fb, lr)")
    fb, lr = pair
    said = f"t = {t:.2f} s ({where}) gave (fb {fb}, lr {lr})"
    limits = ComfortLimits()
    if phase == "forward":
        expect(fb > 130 and _standing(lr),
               f"{said}; forward needs fb above 130 (past the dead band) and lr 128")
        speed = pot_byte_to_deflection(fb, p) * p.max_speed
        fastest = _largest_byte(limits.max_speed / p.max_speed, p)
        expect(speed <= limits.max_speed + 1e-9,
               f"{said}: that is {speed:.2f} m/s ({speed * 3.6:.1f} km/h) with a person in "
               f"the seat; keep forward at or below {limits.max_speed:g} m/s, the comfort "
               f"limit the safety filter holds (fb {fastest} at most)")
    elif phase == "left":
        expect(lr < 126 and _standing(fb),
               f"{said}; a left turn on the spot needs lr below 126 and fb 128 "
               "(LR below 128 turns left, eqn 2)")
        rate = -pot_byte_to_deflection(lr, p) * p.max_turn_rate
        expect(rate <= limits.max_turn_rate + 1e-9,
               f"{said}: that turns at {rate:.2f} rad/s ({math.degrees(rate):.0f} deg/s) with "
               f"a person in the seat; keep it at or below {limits.max_turn_rate:g} rad/s, "
               f"the safety filter's comfort limit (lr "
               f"{256 - _largest_byte(limits.max_turn_rate / p.max_turn_rate, p)} at least)")
    else:
        expect(_standing(fb) and _standing(lr), f"{said}; the chair should stop: (128, 128)")
    if phase in seen:
        expect(seen[phase] == pair, f"{said}, but earlier {phase} sent (fb {seen[phase][0]}, "
                                    f"lr {seen[phase][1]}); use the same bytes every time")
    seen[phase] = pair


# --- exercise 4: measure one corner -------------------------------------------------------


@checker("measurement")
def corners_check(measured: Callable[[], tuple[float, float]]) -> str:
    """``measured()`` = (worn, ideal) degrees turned by one 2 s corner, against the motor
    model (ideal: ``omega x 2 s``) and the worn chair's budget."""
    value = measured()
    worn, ideal = numbers(value, 2, "measured_corners()",
                          "return two angles in degrees: (worn chair, ideal chair)")
    expect(math.isfinite(worn) and math.isfinite(ideal),
           f"measured ({worn}, {ideal}); both must be finite numbers of degrees")
    budget = clockwise_budget()
    p = default_params()
    model = math.degrees(-pot_byte_to_deflection(LEFT_LR, p) * p.max_turn_rate * 2.0)
    expected_worn = model - budget["corner_short"]
    if max(abs(worn), abs(ideal)) < 2 * math.pi + 0.1 and abs(ideal) > 1.0:
        raise NotYet(f"({worn:.2f}, {ideal:.2f}) look like radians; the check wants degrees "
                     f"(the ideal corner is {model:.1f} deg)")
    if abs(ideal - model) > 0.5:
        if abs(ideal - model / 2) < 1.0:
            raise NotYet(f"the ideal chair turned {ideal:.1f} deg by your measurement, half "
                         f"the model's {model:.1f}: the corner's command lasts 2 s")
        unfinished = model * (2.0 - p.command_delay - p.control_period
                              - p.motor_time_constant) / 2.0
        if abs(ideal - unfinished) < 2.0:
            raise NotYet(f"the ideal chair turned {ideal:.1f} deg by your measurement, the "
                         f"model says {model:.1f}: read the heading once the chair has come "
                         "to rest; when the command ends, the wheels still lag behind it")
        raise NotYet(f"the ideal chair turned {ideal:.1f} deg by your measurement, the model "
                     f"says {model:.1f} (omega x 2 s): measure the heading change from the "
                     "simulator's true pose, unwrapped, after the chair has stopped")
    if abs(worn - expected_worn) > 0.7:
        if abs(worn - ideal) < 0.3:
            raise NotYet(f"the worn chair turned {worn:.1f} deg, as much as the ideal: was it "
                         "the worn chair (errors=\"worn\")?")
        raise NotYet(f"the worn chair turned {worn:.1f} deg; its wider wheel base and larger "
                     f"tyre give {expected_worn:.1f}")
    return (f"worn {worn:.1f} deg, ideal {ideal:.1f} deg: each of the worn chair's corners "
            f"is {ideal - worn:.1f} deg short")


# --- exercise 5: predict the clockwise square's heading error -------------------------------


def clockwise_budget() -> dict[str, float]:
    """The worn chair's heading-error budget for A.3's square with the reference bytes
    (degrees, positive to the left): each 5 s straight curves left by the tyres'
    difference over the effective wheel base, each 2 s corner comes out short by the
    wheel base's excess (a little less: the larger tyre helps), 3.5 straights and 3
    corners. Clockwise, a short right corner leaves the chair pointing too far left."""
    from abcwc.sim import ChairErrors

    p, errors = default_params(), ChairErrors.worn()
    b_eff = p.wheel_base * errors.wheel_base
    side = pot_byte_to_deflection(FORWARD_FB, p) * p.max_speed * 5.0
    straight = math.degrees(side * (errors.drive_wheel_right - errors.drive_wheel_left) / b_eff)
    turn = math.degrees(-pot_byte_to_deflection(LEFT_LR, p) * p.max_turn_rate * 2.0)
    tyre_mean = (errors.drive_wheel_left + errors.drive_wheel_right) / 2
    corner_short = turn - turn * tyre_mean / errors.wheel_base  # > 0: each corner short by
    return {"straight": straight, "corner_short": corner_short,
            "clockwise": 3.5 * straight + 3 * corner_short,
            "counter_clockwise": 3.5 * straight - 3 * corner_short}


@checker("prediction")
def clockwise_prediction_check(predicted: Callable[[], float], measured: float) -> str:
    """The clockwise square's heading error written before the run, against the budget
    and against ``measured`` (worn minus ideal at the end, degrees)."""
    value = predicted()
    expect(isinstance(value, (int, float)) and math.isfinite(value),
           f"predicted_clockwise_heading_error() gave {format_value(value)}; write one "
           "number of degrees")
    budget = clockwise_budget()
    straights, corners = 3.5 * budget["straight"], 3 * budget["corner_short"]
    if abs(value - measured) <= 1.5:
        return (f"you predicted {value:+.1f} deg; the run measured {measured:+.1f} deg "
                f"(straights {straights:+.1f}, short right corners {corners:+.1f})")
    slips = {
        "that is the counter-clockwise square's error: turning right, a short corner "
        "leaves the chair pointing too far *left*, the same way the straights curve":
            budget["counter_clockwise"],
        "the sign: the straights still curve left (the right tyre is larger) and the "
        "short right corners leave it pointing left too, so the error is positive":
            -budget["clockwise"],
        "only the straights: each of the three corners comes out short too":
            straights,
        "only the corners: the 3.5 straights curve left as well": corners,
    }
    expect_no_slip(value, slips, lambda got, wrong: abs(got - wrong) <= 1.5,
                   prefix=f"you predicted {value:+.1f} deg, the run measured "
                          f"{measured:+.1f} deg: ")
    raise NotYet(f"you predicted {value:+.1f} deg; the run measured {measured:+.1f} deg. "
                 f"Budget it as section 5 did: 3.5 straights of {budget['straight']:+.2f} "
                 f"deg each, and 3 corners each {budget['corner_short']:.2f} deg short")
