"""Checks for chapter 02, speed and turn control (thesis 4.1.5, 4.3.4, A.5, A.14).

* :func:`turn_value_check` — eqn 2, ``turn = 254 - 1.6 * angle`` (angle in degrees,
  positive to the left), against the thesis's worked example and both ends of the
  joystick's range.
* :func:`twist_to_pots_check` — the calibrated velocity controller, ``(v, w) ->
  PotCommand``, the inverse of the motor controller's model, compared with
  :func:`abcwc.control.twist_to_pot_command` over a sweep of speeds and turn rates.
* :func:`t63_check` — the time (s) after a step command at which the chair has 63.2 % of
  its final speed, measured from the step response, against the response itself and
  the model's ``L + tau``.
* :func:`coast_prediction_check` — a distance written down *before* the run that
  measures it: how far the chair still rolls after a stop sent at 1.0 m/s, from the
  step response's dead time and lag, judged against the run.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from abcwc.checks.report import (
    NotYet,
    checker,
    expect,
    expect_close,
    expect_equal,
    expect_no_slip,
    expect_own,
    format_value,
)
from abcwc.control.pots import turn_value
from abcwc.control.velocity import twist_to_pot_command
from abcwc.params import default_params
from abcwc.types import Twist

__all__ = ["TURN_VALUES", "coast_prediction_check", "t63_check", "turn_value_check",
           "twist_to_pots_check"]

# (angle in degrees, + = left; pot-scale value; where it comes from)
TURN_VALUES = (
    (0.0, 254.0, "straight ahead: the centre"),
    (-45.0, 326.0, "the thesis's worked example, 254 + 1.6 * 45, a right turn"),
    (45.0, 182.0, "the same turn to the left"),
    (90.0, 110.0, "full left, the joystick's end"),
    (-90.0, 398.0, "full right, the joystick's end"),
)


@checker("eqn 2, turn value")
def turn_value_check(fn: Callable[[float], float]) -> str:
    """Compare ``fn(angle_deg)`` with eqn 2 at the thesis's values and every 7.5 degrees."""
    expect_own(fn, turn_value)
    for angle, expected, why in TURN_VALUES:
        expect_close(fn(angle), expected, what=f"angle {angle:+g} deg", rtol=0.0, atol=1e-6,
                     ref=f"eqn 2; {why}")
    sweep = [float(a) for a in np.arange(-90.0, 90.0 + 1e-9, 7.5)] + [1.0, -12.5, 33.3, -71.1]
    for angle in sweep:
        expect_close(fn(angle), turn_value(angle), what=f"angle {angle:+g} deg", rtol=0.0,
                     atol=1e-6, ref="eqn 2, not rounded: eqn 1 truncates later")
    return (f"the worked example (326), both ends (110, 398) and {len(sweep)} angles "
            "from -90 to +90 deg match")


def _byte(value: object, what: str) -> int:
    """A pot byte from the student's answer, or NotYet saying what came back."""
    expect(isinstance(value, int | np.integer) and not isinstance(value, bool),
           f"{what} is {format_value(value)}; pot bytes are whole numbers (int)")
    return int(value)


def _pots(fn: Callable[[float, float], object], v: float, w: float) -> tuple[int, int]:
    command = fn(v, w)
    what = f"twist_to_pots({v:g}, {w:g})"
    expect(hasattr(command, "fb") and hasattr(command, "lr"),
           f"{what} returned {format_value(command)}; return a PotCommand(fb, lr)")
    return _byte(command.fb, f"{what}.fb"), _byte(command.lr, f"{what}.lr")


@checker("calibrated velocity controller")
def twist_to_pots_check(fn: Callable[[float, float], object]) -> str:
    """Compare ``fn(v, w) -> PotCommand`` with :func:`twist_to_pot_command`.

    Standing still must give exactly (128, 128), and the direction of each axis must
    be right (FB above 128 = forward, LR below 128 = left). Over a sweep of speeds
    (-2..2 m/s), turn rates (-2..2 rad/s) and a grid of both together, every byte may
    differ from the library's by at most 1: where a request falls half-way between
    two bytes, rounding in m/s, in mm/s, or Python's round-half-to-even may pick
    either neighbour, and one byte is only 14 mm/s or 0.7 deg/s.
    """
    expect_own(fn, twist_to_pot_command)
    p = default_params()
    expect_equal(_pots(fn, 0.0, 0.0), (p.pot_neutral, p.pot_neutral),
                 what="standing still, (fb, lr)", ref="both pots at neutral")
    fb, _ = _pots(fn, 0.5, 0.0)
    expect(fb > p.pot_neutral,
           f"0.5 m/s forward gave fb {fb}; forward is FB above {p.pot_neutral}")
    _, lr = _pots(fn, 0.0, 0.5)
    expect(lr < p.pot_neutral,
           f"w = +0.5 rad/s (a left turn) gave lr {lr}; a left turn is LR below "
           f"{p.pot_neutral}")
    axis = np.round(np.arange(-2.0, 2.0 + 1e-9, 0.01), 2)
    both = np.round(np.arange(-1.5, 1.5 + 1e-9, 0.25), 2)
    cases = ([(float(v), 0.0) for v in axis] + [(0.0, float(w)) for w in axis]
             + [(float(v), float(w)) for v in both for w in both])
    exact = 0
    for v, w in cases:
        got = _pots(fn, v, w)
        expected = twist_to_pot_command(Twist(v, w))
        for name, g, e in zip(("fb", "lr"), got, (expected.fb, expected.lr)):
            expect(abs(g - e) <= 1,
                   f"twist_to_pots({v:g}, {w:g}).{name} gave {g}, expected {e} ± 1 "
                   f"(the motor model: 128 ± (2 + 123 |value| / full scale), "
                   f"kept in {p.pot_safe_min}..{p.pot_safe_max})")
        exact += got == (expected.fb, expected.lr)
    return (f"{len(cases)} commands within ±1 byte of abcwc's controller "
            f"({exact} of them exactly equal)")


@checker("prediction")
def coast_prediction_check(predicted: Callable[[], float], measured: float,
                           speed: float = 1.0, dead_time: float = 0.06, tau: float = 0.25
                           ) -> str:
    """The distance (m) the chair rolls after a stop at ``speed`` m/s, written before the
    run, against the run's ``measured`` distance; ``dead_time`` and ``tau`` (s) are the
    step response's, for naming the slips."""
    value = predicted()
    expect(isinstance(value, (int, float)) and math.isfinite(value) and value >= 0,
           f"predicted_coast() gave {format_value(value)}; write one distance in metres")
    if abs(value - measured) <= 0.04:
        return (f"you predicted {value:.2f} m; the chair rolled {measured:.3f} m after the "
                f"stop at {speed:g} m/s")
    slips = {
        "only the lag: the command also waits the dead time before the wheels hear it":
            speed * tau,
        "only the dead time: after it the wheels still take their lag to slow down":
            speed * dead_time,
        "that is the settling time (L + 5 tau) times the speed; the distance is the "
        "area between the step and the response, v (L + tau)": speed * (dead_time + 5 * tau),
        "half of it: the response is an exponential, not a straight ramp, and its area "
        "behind the step is v tau, not v tau / 2": speed * (dead_time + tau / 2),
    }
    expect_no_slip(value, slips, lambda got, wrong: abs(got - wrong) <= 0.02,
                   prefix=f"you predicted {value:.2f} m, the chair rolled {measured:.3f} m: ")
    raise NotYet(f"you predicted {value:.2f} m, the chair rolled {measured:.3f} m: at "
                 f"{speed:g} m/s the wheels run on through the dead time and then slow with "
                 "the lag; add up the distance each part covers")


@checker("measurement")
def t63_check(measured: Callable[[np.ndarray, np.ndarray], float], t: np.ndarray,
              v: np.ndarray, dead_time: float = 0.06, tau: float = 0.25) -> str:
    """``measured(t, v)``: the time after the command (s) at which the step response
    ``v`` (m/s at times ``t``, s from the command) first reaches 63.2 % of its final
    value, against the response (interpolated) and the model's ``L + tau``."""
    value = measured(np.array(t), np.array(v))
    expect(isinstance(value, (int, float, np.floating)) and math.isfinite(float(value)),
           f"time_to_63(t, v) gave {format_value(value)}; return one time in s")
    value = float(value)
    final = float(np.mean(v[-25:]))
    after = t > 0
    expected = float(np.interp(0.632 * final, v[after], t[after]))
    if abs(value - expected) <= 0.02:
        return (f"{value:.3f} s after the command; the model says L + tau = "
                f"{dead_time + tau:.2f} s: the lag's tau is measured from when the wheels "
                "hear the command, not from when it is sent")
    slips = {
        "that is tau alone: the clock starts when the command is sent, and the wheels "
        "hear it only after the dead time": tau,
        "that is the dead time, when the speed starts to rise": dead_time,
        "that is the settling time, 99 %, not 63.2 %": dead_time + 5 * tau,
        "that is when the step was sent on the log's own clock (t0 = 0.5 s): measure from "
        "the command": expected + 0.5,
    }
    expect_no_slip(value, slips, lambda got, wrong: abs(got - wrong) <= 0.02,
                   prefix=f"{value:.3f} s: ",
                   suffix=f" (the response reaches 63.2 % at {expected:.3f} s)")
    raise NotYet(f"{value:.3f} s; the response reaches 63.2 % of its final "
                 f"{final:.3f} m/s at {expected:.3f} s after the command")
