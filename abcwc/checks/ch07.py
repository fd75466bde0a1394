"""Checks for chapter 07, going to a landmark (thesis 4.2.2, eqns 11-12, A.10).

Exercises:

* ``distance_and_bearing(pose, goal)``: ``(rho, alpha)``, the distance (m) to the goal
  and the heading error (rad), wrapped to (-pi, pi] (eqns 11-12);
* ``turn_then_drive(state, rho, alpha, *, tolerance, heading_tolerance,
  align_tolerance, speed, turn_rate)``: one period of the turn-then-drive state machine
  (A.10, fixed), returning the new state (``"turn"``, ``"drive"`` or ``"reached"``) and
  the Twist to send;
* ``proportional_command(rho, alpha, *, k_rho, k_alpha, max_speed, max_turn_rate,
  decel)``: the proportional go-to-goal command with its limits.

The ``reference_*`` answers the notebook falls back on are the library's own
(:mod:`abcwc.behaviours.landmark`).
* ``predicted_tight_errors()``: two distances written down *before* both controllers are
  asked for 2 cm: each one's mean final error (m), judged against the run.
* ``degrees_per_corner(corner_gaps)``: the heading error the worn chair's odometry gains
  per corner, measured from the corners it reached before the safety filter stopped it
  at the shelf, and compared with its geometry (every turn counted about 1.7 % too
  large).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from abcwc.behaviours import landmark
from abcwc.checks.report import (
    NotYet,
    checker,
    expect,
    expect_close,
    expect_equal,
    expect_own,
    format_value,
    numbers,
)
from abcwc.types import Pose2D

__all__ = [
    "corner_gain_check",
    "tight_prediction_check",
    "THESIS_MACHINE",
    "distance_and_bearing_check",
    "proportional_command_check",
    "reference_distance_and_bearing",
    "reference_proportional_command",
    "reference_turn_then_drive",
    "turn_then_drive_check",
]

reference_distance_and_bearing = landmark.distance_and_bearing
reference_turn_then_drive = landmark.turn_then_drive
reference_proportional_command = landmark.proportional_command

THESIS_MACHINE = {"tolerance": 0.5, "heading_tolerance": 0.3, "align_tolerance": 0.1,
                  "speed": 0.5, "turn_rate": 0.5}
"""The chapter's turn-then-drive settings: A.10's numbers plus a 0.1 rad hysteresis."""

_ATOL = 1e-9


def _pair(got: Any, what: str) -> tuple[float, float]:
    """``got`` as two floats, or a NotYet saying what came back instead."""
    try:
        first, second = got
        return float(first), float(second)
    except (TypeError, ValueError):
        raise NotYet(f"{what} gave {format_value(got)}, expected a pair (rho, alpha)") from None


# --- exercise 1: eqns 11-12 -----------------------------------------------------------

# (pose, goal, what the case is about); expected values come from the library.
_BEARING_CASES = (
    (Pose2D(1.0, 2.0, 0.0), (4.0, 6.0), "a 3-4-5 triangle, facing +x"),
    (Pose2D(0.0, 0.0, math.pi / 2), (3.0, 0.0), "facing +y, goal to the right"),
    (Pose2D(5.0, 4.0, 0.0), (1.0, 3.8), "goal almost straight behind, slightly right"),
    (Pose2D(0.0, 0.0, 3.0), (-1.0, -0.1), "facing west, goal just left: wrap needed"),
    (Pose2D(2.0, 2.0, -3.0), (1.0, 2.2), "facing west, goal just right: wrap needed"),
    (Pose2D(-1.5, 0.5, -2.0), (-1.5, -1.5), "facing down-left, goal straight down"),
)


@checker("distance and bearing")
def distance_and_bearing_check(fn: Callable[[Pose2D, tuple[float, float]], Any]) -> str:
    """Compare ``fn(pose, goal)`` with eqns 11-12 (alpha wrapped) on hand-worked and
    random cases."""
    expect_own(fn, reference_distance_and_bearing)
    rng = np.random.default_rng(7)
    cases = [(pose, goal, why) for pose, goal, why in _BEARING_CASES]
    for _ in range(200):
        x, y, gx, gy = rng.uniform(-10.0, 10.0, 4)
        cases.append((Pose2D(x, y, rng.uniform(-math.pi, math.pi)), (gx, gy), "random"))
    for pose, goal, why in cases:
        rho, alpha = reference_distance_and_bearing(pose, goal)
        if math.pi - abs(alpha) < 1e-6:
            continue  # exactly behind: pi and -pi are the same direction
        what = (f"pose ({pose.x:.3g}, {pose.y:.3g}, {pose.theta:.3g}), "
                f"goal ({goal[0]:.3g}, {goal[1]:.3g})")
        got_rho, got_alpha = _pair(fn(pose, goal), what)
        dx, dy = goal[0] - pose.x, goal[1] - pose.y
        expect(not (abs(dy) > 1e-3 and math.isclose(got_rho, abs(dx), abs_tol=1e-9)),
               f"{what} gave rho {got_rho:.6g} m = |x_d - x_0| only: eqn 11 as printed has "
               "y_d - y_d, read y_d - y_0")
        expect_close(got_rho, rho, what=f"{what}: rho", rtol=1e-9, atol=_ATOL, unit="m",
                     ref=f"eqn 11; {why}")
        unwrapped = math.atan2(dy, dx) - pose.theta
        expect(not (abs(unwrapped) > math.pi
                    and math.isclose(got_alpha, unwrapped, abs_tol=1e-9)),
               f"{what} gave alpha {got_alpha:.6g} rad, outside (-pi, pi]: wrap it to "
               f"{alpha:.6g} rad (eqn 12; {why})")
        expect_close(got_alpha, alpha, what=f"{what}: alpha", rtol=0.0, atol=1e-9,
                     unit="rad", ref=f"eqn 12, wrapped to (-pi, pi]; {why}")
    rho, alpha = reference_distance_and_bearing(*_BEARING_CASES[3][:2])
    return (f"{len(cases)} poses match, e.g. facing 3.0 rad with the goal at (-1, -0.1): "
            f"rho {rho:.4f} m, alpha {alpha:+.4f} rad")


# --- exercise 2: the turn-then-drive state machine ------------------------------------

_STATE_CASES = (  # (state, rho m, alpha rad, what the case is about)
    ("turn", 2.0, 0.0, "facing the goal: drive"),
    ("turn", 2.0, 0.2, "still 0.2 rad off while turning: keep turning down to align_tolerance"),
    ("drive", 2.0, 0.2, "driving, 0.2 rad off: keep driving"),
    ("drive", 2.0, -0.35, "driving, goal 0.35 rad to the right: turn right"),
    ("turn", 2.0, -0.05, "turning, aligned within 0.1 rad: drive"),
    ("turn", 3.0, math.pi, "goal straight behind: turn left"),
    ("drive", 0.4, 0.0, "within 0.5 m: reached, stop"),
    ("turn", 0.3, 2.5, "within 0.5 m while turning: reached, stop"),
    ("reached", 3.0, 1.0, "reached is for good: stay stopped"),
)


def _state_and_twist(got: Any, what: str) -> tuple[str, float, float]:
    try:
        state, twist = got
        return state, float(twist.v), float(twist.w)
    except (TypeError, ValueError, AttributeError):
        raise NotYet(f"{what} gave {format_value(got)}, expected (state, Twist(v, w))") from None


@checker("turn then drive")
def turn_then_drive_check(fn: Callable[..., Any]) -> str:
    """Compare ``fn(state, rho, alpha, **settings)`` with the state machine, case by case.

    Hand-worked cases with :data:`THESIS_MACHINE`, the same with A.10's single
    threshold (``align_tolerance = heading_tolerance``), then a random sweep.
    """
    expect_own(fn, reference_turn_then_drive)
    single = dict(THESIS_MACHINE, align_tolerance=THESIS_MACHINE["heading_tolerance"])
    rng = np.random.default_rng(7)
    cases = [(state, rho, alpha, why, THESIS_MACHINE) for state, rho, alpha, why in _STATE_CASES]
    cases.append(("turn", 2.0, 0.2, "A.10's single threshold: 0.2 rad is good enough",
                  single))
    for _ in range(300):
        settings = {"tolerance": rng.uniform(0.05, 1.0), "speed": rng.uniform(0.1, 1.0),
                    "turn_rate": rng.uniform(0.1, 1.5),
                    "heading_tolerance": rng.uniform(0.1, 0.6)}
        settings["align_tolerance"] = settings["heading_tolerance"] * rng.uniform(0.2, 1.0)
        state = str(rng.choice(landmark.STATES))
        cases.append((state, rng.uniform(0.0, 3.0), rng.uniform(-math.pi, math.pi),
                      "random settings", settings))
    for state, rho, alpha, why, settings in cases:
        expected_state, expected = reference_turn_then_drive(state, rho, alpha, **settings)
        what = f"turn_then_drive({state!r}, rho={rho:.3g}, alpha={alpha:+.3g})"
        got_state, v, w = _state_and_twist(fn(state, rho, alpha, **settings), what)
        expect_equal(got_state, expected_state, what=f"{what}: state", ref=why)
        expect_close(v, expected.v, what=f"{what}: v", rtol=0.0, atol=1e-9, unit="m/s",
                     ref=why)
        expect_close(w, expected.w, what=f"{what}: w", rtol=0.0, atol=1e-9, unit="rad/s",
                     ref=why + ("; positive w turns left" if expected.w else ""))
    return f"{len(cases)} periods match, hysteresis, latch and turn directions included"


# --- exercise 3: the proportional law ---------------------------------------------------

_DEFAULTS = {"k_rho": 0.8, "k_alpha": 1.5, "max_speed": 0.8, "max_turn_rate": 0.8,
             "decel": 0.5}
_LAW_CASES = (  # (rho m, alpha rad, settings changed from the defaults, what it shows)
    (2.0, 0.2, {}, "far: speed at its limit, times cos alpha"),
    (0.3, 0.0, {}, "near: v = k_rho rho"),
    (0.5, 0.3, {}, "w = k_alpha alpha"),
    (3.0, -1.0, {}, "turn rate clipped to -max_turn_rate"),
    (2.0, 2.0, {}, "goal behind: no forward speed"),
    (0.5, 0.0, {"k_rho": 2.0}, "braking limit sqrt(2 decel rho)"),
    (0.18, 0.1, {"k_rho": 2.0}, "near again: k_rho rho below the braking limit"),
)


@checker("proportional go-to-goal")
def proportional_command_check(fn: Callable[..., Any]) -> str:
    """Compare ``fn(rho, alpha, **gains)`` with the limited proportional law."""
    expect_own(fn, reference_proportional_command)
    rng = np.random.default_rng(7)
    cases = [(rho, alpha, dict(_DEFAULTS, **changes), why)
             for rho, alpha, changes, why in _LAW_CASES]
    for _ in range(300):
        gains = {"k_rho": rng.uniform(0.2, 3.0), "k_alpha": rng.uniform(0.5, 4.0),
                 "max_speed": rng.uniform(0.2, 1.5), "max_turn_rate": rng.uniform(0.3, 1.5),
                 "decel": rng.uniform(0.2, 1.5)}
        cases.append((rng.uniform(0.0, 5.0), rng.uniform(-math.pi, math.pi), gains, "random"))
    for rho, alpha, gains, why in cases:
        expected = reference_proportional_command(rho, alpha, **gains)
        what = f"proportional_command(rho={rho:.3g}, alpha={alpha:+.3g})"
        got = fn(rho, alpha, **gains)
        try:
            v, w = float(got.v), float(got.w)
        except (TypeError, ValueError, AttributeError):
            raise NotYet(f"{what} gave {format_value(got)}, expected a Twist(v, w)") from None
        expect_close(v, expected.v, what=f"{what}: v", rtol=0.0, atol=1e-9, unit="m/s",
                     ref=why)
        expect_close(w, expected.w, what=f"{what}: w", rtol=0.0, atol=1e-9, unit="rad/s",
                     ref=why)
    example = reference_proportional_command(2.0, 0.2, **_DEFAULTS)
    return (f"{len(cases)} commands match, e.g. 2 m away and 0.2 rad off: "
            f"v {example.v:.3f} m/s, w {example.w:.3f} rad/s")


# --- predict, then run: a 2 cm tolerance -------------------------------------------------------


@checker("prediction")
def tight_prediction_check(predicted: Callable[[], tuple[float, float]],
                           turn_then_drive: float, proportional: float) -> str:
    """(turn-then-drive, proportional) mean final errors (m) at a 2 cm tolerance, written
    before the run, against the run's."""
    value = predicted()
    guess_ttd, guess_prop = numbers(value, 2, "predicted_tight_errors()",
                                    "return two distances in m: (turn-then-drive, proportional)")
    expect(all(math.isfinite(g) and g >= 0 for g in (guess_ttd, guess_prop)),
           f"predicted ({guess_ttd}, {guess_prop}); both are distances in m, >= 0")
    notes = []
    if guess_ttd < 0.5 * turn_then_drive:
        notes.append("turn-then-drive cannot stop within 2 cm from 0.5 m/s: the safety "
                     "filter brakes it comfortably and it rolls on after its stop command "
                     "(section 5 measured how far), so it ends far outside its tolerance")
    elif guess_ttd > 3 * turn_then_drive:
        notes.append("turn-then-drive: it overshoots, but it still comes to rest after the "
                     "stop, one roll-out from where it stopped")
    if abs(guess_prop - proportional) > 0.02:
        notes.append("the proportional law slows down as it closes in (v = k_rho rho), so it "
                     "stops about where it means to, inside its tolerance")
    if notes:
        raise NotYet(f"you predicted {guess_ttd:.3f} and {guess_prop:.3f} m, the run ended "
                     f"{turn_then_drive:.3f} and {proportional:.3f} m off: " + "; ".join(notes))
    return (f"you predicted {guess_ttd:.3f} m and {guess_prop:.3f} m; the run ended "
            f"{turn_then_drive:.3f} m and {proportional:.3f} m off")


# --- measure: the heading error gained per corner ----------------------------------------------


@checker("measurement")
def corner_gain_check(fn: Callable[[list], float], corner_gaps: list) -> str:
    """``fn(corner_gaps)``: degrees of heading error gained per corner, from every corner of
    ``corner_gaps`` ((position m, heading rad) at each corner reached, in order); against a
    straight-line fit here and the worn chair's geometry."""
    value = fn(list(corner_gaps))
    expect(isinstance(value, (int, float, np.floating)) and math.isfinite(float(value)),
           f"degrees_per_corner gave {format_value(value)}; return one number of degrees")
    value = float(value)
    expect(len(corner_gaps) >= 3, f"{len(corner_gaps)} corners are too few for a line")
    corners = np.arange(len(corner_gaps))
    headings = np.degrees([turn for _, turn in corner_gaps])
    slope, intercept = (float(c) for c in np.polyfit(corners, headings, 1))
    from abcwc.sim import ChairErrors

    worn = ChairErrors.worn()
    geometry = 90.0 * (worn.wheel_base / ((worn.encoder_wheel_left + worn.encoder_wheel_right)
                                         / 2) - 1)
    if abs(value - slope) <= 0.25:
        return (f"{value:.2f} deg a corner; the worn chair's geometry says {geometry:.2f} "
                "(a 3 % wider wheel base against encoder wheels 1.2 % large: each 90 deg "
                "turn counted 1.7 % too large)")
    if abs(value - math.radians(slope)) <= 0.005:
        raise NotYet("that is in radians; the check wants degrees")
    if abs(value - (headings[-1] - headings[0])) <= 0.5:
        raise NotYet(f"{value:.1f} deg is the gain over all {len(corner_gaps)} corners; divide "
                     "by the number of corners between the first and the last")
    if abs(value - intercept) <= 0.05:
        raise NotYet("that is the line's intercept, the heading error at the first corner "
                     "(np.polyfit's second number); the slope is its first")
    positions = [gap for gap, _ in corner_gaps]
    if abs(value - float(np.polyfit(corners, positions, 1)[0])) <= 0.02:
        raise NotYet("that fits the position errors (m), the first of each pair; the heading "
                     "error (rad) is the second")
    raise NotYet(f"{value:.2f} deg a corner; a straight line through the heading errors of "
                 f"the {len(corner_gaps)} corners has another slope")
