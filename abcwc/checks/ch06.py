"""Checks for chapter 06, wheel odometry (thesis 4.2.1, eqns 6-10, A.9).

Exercises:

* ``wheel_travel(ticks, distance_per_count, bits)``: per-period wheel travel (m),
  ``(N - 1, 2)``, from a log's ``(N, 2)`` cumulative counts, correct across the
  counter's wrap at ``bits`` width;
* ``odometry_step(pose, d_left, d_right, wheel_base)``: the pose after one period,
  eqns 6-10 as printed (the chord along the heading before the step), heading
  wrapped to (-pi, pi];
* ``integrate_arcs(d_left, d_right, wheel_base, start)``: every pose of a whole log at
  once, ``(N + 1, 3)``, with NumPy's ``cumsum`` and the exact-arc update.

The ``reference_*`` answers the notebook falls back on are the library's own
(:mod:`abcwc.estimation.odometry`).
* ``predicted_euler_error()``: a number written down *before* the longer periods are
  run: euler's end error (% of the distance) at a 0.5 s period, from its error at 20 ms
  and the order the text derived;
* ``diagnosis()``: which fault a log's encoder counts have (the channels swapped, or one
  of them counting backwards), judged against the fault put into it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from abcwc.checks.report import (
    NotYet,
    checker,
    expect,
    expect_close,
    expect_no_slip,
    expect_own,
    format_value,
)
from abcwc.estimation import odometry
from abcwc.geometry import wrap_angle
from abcwc.params import default_params
from abcwc.types import Pose2D

__all__ = [
    "FAULTS",
    "diagnosis_check",
    "euler_prediction_check",
    "faulty_log",
    "integrate_arcs_check",
    "odometry_step_check",
    "reference_integrate_arcs",
    "reference_odometry_step",
    "reference_wheel_travel",
    "wheel_travel_check",
]

reference_wheel_travel = odometry.wheel_travel
reference_odometry_step = odometry.odometry_step


def reference_integrate_arcs(d_left: np.ndarray, d_right: np.ndarray, wheel_base: float,
                             start: Pose2D | None = None) -> np.ndarray:
    """Every pose, ``(N + 1, 3)``, by exact arcs: :func:`abcwc.estimation.integrate_odometry`."""
    return odometry.integrate_odometry(d_left, d_right, wheel_base, start, method="exact")


_B = default_params().wheel_base  # m, the chair's nominal wheel base


def _array(got: Any, shape: tuple[int, ...], what: str, rows_hint: str) -> np.ndarray:
    """``got`` as a float array of ``shape``, or a NotYet saying what came back."""
    try:
        array = np.asarray(got, dtype=float)
    except (TypeError, ValueError):
        raise NotYet(f"{what} gave {format_value(got)}, expected an array of shape "
                     f"{shape}") from None
    if array.shape != shape:
        hint = f"; {rows_hint}" if array.ndim == 2 and array.shape[0] != shape[0] else ""
        raise NotYet(f"{what} gave an array of shape {array.shape}, expected {shape}{hint}")
    return array


# --- exercise 1: counts -> travel -----------------------------------------------------


def _wrap_to(counts: np.ndarray, bits: int) -> np.ndarray:
    """What a signed ``bits``-bit counter holds for true counts ``counts``."""
    half = 1 << (bits - 1)
    return (counts + half) % (1 << bits) - half


@checker("wheel travel")
def wheel_travel_check(fn: Callable[..., np.ndarray]) -> str:
    """Check ``fn(ticks, distance_per_count, bits)`` on hand cases, wraps and a long log."""
    expect_own(fn, reference_wheel_travel)
    per_count = default_params().distance_per_count
    rng = np.random.default_rng(6)
    steps = np.column_stack([rng.integers(-20, 61, 300), rng.integers(-60, 21, 300)])
    true_counts = np.cumsum(np.vstack([[30_000, -30_000], steps]), axis=0)
    cases = [
        (np.array([[0, 0], [10, 12], [25, 20], [25, 30], [13, 30]]), 0.001, 32,
         np.array([[0.010, 0.012], [0.015, 0.008], [0.0, 0.010], [-0.012, 0.0]]),
         "a hand-worked log (1 mm per count)"),
        (np.full((4, 2), 777), per_count, 32, np.zeros((3, 2)), "standing still"),
        (np.array([[0, 0], [1258, 1258]]), per_count, 32,
         np.full((1, 2), 1258 * per_count), "one wheel turn, 1258 counts (4.2.1)"),
        (np.array([[32760, -32760], [-32766, 32766]]), per_count, 16,
         np.array([[10, -10]]) * per_count,
         "a 16-bit counter wrapping: 32760 -> -32766 is +10 counts"),
        (np.array([[2**31 - 5, -(2**31) + 2], [-(2**31) + 3, 2**31 - 1]]), per_count, 32,
         np.array([[8, -3]]) * per_count, "a 32-bit counter wrapping"),
        (_wrap_to(true_counts, 16), per_count, 16, steps * per_count,
         "300 periods of 16-bit counters that wrap, one up and one down"),
    ]
    for ticks, dpc, bits, expected, what in cases:
        got = _array(fn(ticks.astype(np.int64), dpc, bits), expected.shape, what,
                     "N rows of counts give N - 1 travels, one per period between two rows")
        raw = np.diff(ticks.astype(float), axis=0) * dpc
        if bits < 64 and not np.allclose(expected, raw) and np.allclose(got, raw, atol=1e-9):
            raise NotYet(f"{what}: you took the plain difference, so a counter wrapping from "
                         f"{2**(bits - 1) - 1} to {-2**(bits - 1)} looks like a jump of "
                         f"{2**bits} counts backwards; take each difference modulo 2**{bits} "
                         f"into {-2**(bits - 1)}..{2**(bits - 1) - 1}")
        expect_close(got, expected, what=what, rtol=1e-9, atol=1e-12, unit="m", ref="4.2.1")
    return (f"{len(cases)} logs match, 16- and 32-bit wraps included; one wheel turn rolls "
            f"{1258 * per_count:.4f} m")


# --- exercise 2: one step of eqns 6-10 ------------------------------------------------


def _as_pose(got: Any, what: str) -> Pose2D:
    """A Pose2D (or ``(x, y, theta)``) from the student's answer, else NotYet."""
    if all(hasattr(got, name) for name in ("x", "y", "theta")):
        values = (got.x, got.y, got.theta)
    else:
        try:
            values = tuple(got)
        except TypeError:
            raise NotYet(f"{what} gave {format_value(got)}, expected a Pose2D") from None
    try:
        x, y, theta = (float(v) for v in values)
    except (TypeError, ValueError):
        raise NotYet(f"{what} gave {format_value(got)}, expected a Pose2D(x, y, theta)") from None
    expect(all(map(math.isfinite, (x, y, theta))),
           f"{what} gave ({x:g}, {y:g}, {theta:g}); a pose is three finite numbers")
    return Pose2D(x, y, theta)


def _step_hint(got: Pose2D, pose: Pose2D, d_left: float, d_right: float, b: float) -> str:
    """Name a common slip if ``got`` is what it would give, else ''."""
    d_c, phi = (d_right + d_left) / 2.0, (d_right - d_left) / b

    def same(x: float, y: float, theta: float | None = None) -> bool:
        close = math.isclose(got.x, x, abs_tol=1e-9) and math.isclose(got.y, y, abs_tol=1e-9)
        return close and (theta is None or math.isclose(got.theta, theta, abs_tol=1e-9))

    if phi == 0.0:
        return ""
    new = pose.theta + phi
    turned = wrap_angle(new)
    if same(pose.x + d_c * math.cos(new), pose.y + d_c * math.sin(new), turned):
        return ("you moved along the heading after the turn, theta' (as A.9's code does); "
                "eqns 9-10 use theta, the heading before it")
    mid = pose.theta + phi / 2
    if same(pose.x + d_c * math.cos(mid), pose.y + d_c * math.sin(mid), turned) or same(
            pose.x + d_c * math.sin(phi / 2) / (phi / 2) * math.cos(mid),
            pose.y + d_c * math.sin(phi / 2) / (phi / 2) * math.sin(mid), turned):
        return ("you pointed the chord at theta + phi/2, the better rule of section 4; this "
                "exercise is eqns 9-10 as printed, along theta")
    if same(pose.x + d_c * math.cos(pose.theta), pose.y + d_c * math.sin(pose.theta),
            wrap_angle(pose.theta - phi)):
        return ("the heading turned the wrong way: phi = (d_r - d_l) / b is positive (left, "
                "counter-clockwise) when the right wheel travels further")
    if same(pose.x + d_c * math.cos(pose.theta), pose.y + d_c * math.sin(pose.theta),
            new) and not math.isclose(new, turned):
        return "wrap the new heading into (-pi, pi] (abcwc.geometry.wrap_angle does it)"
    return ""


@checker("one odometry step")
def odometry_step_check(fn: Callable[..., Any]) -> str:
    """Check ``fn(pose, d_left, d_right, wheel_base)`` against eqns 6-10 and the library."""
    expect_own(fn, reference_odometry_step)
    c30, s30 = math.cos(math.pi / 6), math.sin(math.pi / 6)
    cases = [  # pose, d_left, d_right, wheel base, expected (x, y, theta), what
        (Pose2D(0.0, 0.0, 0.0), 0.5, 0.5, _B, (0.5, 0.0, 0.0), "straight ahead"),
        (Pose2D(1.0, 2.0, math.pi / 6), 0.3, 0.3, _B, (1.0 + 0.3 * c30, 2.0 + 0.3 * s30,
                                                       math.pi / 6), "straight at 30 deg"),
        (Pose2D(1.0, 2.0, -2.0), -0.2, -0.2, _B,
         (1.0 - 0.2 * math.cos(-2.0), 2.0 - 0.2 * math.sin(-2.0), -2.0), "reversing"),
        (Pose2D(1.0, 2.0, 0.3), -0.11, 0.11, _B, (1.0, 2.0, 0.8), "turning on the spot, left"),
        (Pose2D(0.0, 0.0, 0.0), 0.4, 0.6, _B, (0.5, 0.0, 0.2 / _B),
         "an arc to the left: eqn 9-10 move along the old heading"),
        (Pose2D(-1.0, 0.5, 3.0), 0.05, 0.27, 0.462, None, "past +pi (b = 462 mm)"),
        (Pose2D(0.0, 0.0, -3.1), 0.2, 0.1, _B, None, "past -pi, to the right"),
    ]
    rng = np.random.default_rng(61)
    for _ in range(20):
        pose = Pose2D(*rng.uniform(-5, 5, 2), rng.uniform(-math.pi, math.pi))
        d_left, d_right = rng.uniform(-0.05, 0.05, 2)
        cases.append((pose, float(d_left), float(d_right), _B, None, "a random step"))
    for pose, d_left, d_right, b, closed, what in cases:
        expected = reference_odometry_step(pose, d_left, d_right, b).as_array()
        if closed is not None:
            expected = np.array(closed)
        call = f"{what}: odometry_step({pose.x:g}, {pose.y:g}, {pose.theta:.4g}; " \
               f"{d_left:.4g}, {d_right:.4g})"
        got = _as_pose(fn(pose, d_left, d_right, b), call)
        if not np.allclose(got.as_array(), expected, rtol=0.0, atol=1e-9):
            hint = _step_hint(got, pose, d_left, d_right, b)
            expect(not hint, f"{call}: {hint}")
        expect_close(got.as_array(), expected, what=call, rtol=0.0, atol=1e-9,
                     ref="eqns 6-10")
    return f"{len(cases)} steps match: straight, reversing, on the spot, arcs and wraps"


# --- exercise 3: the whole log with cumsum, exact arcs --------------------------------


def _circle(start: Pose2D, radius: float, phis: np.ndarray) -> np.ndarray:
    """Poses on the circle through ``start``: turned by each of ``phis`` (rad).

    ``radius`` > 0 turns left; the centre is ``radius`` to the chair's left.
    """
    cx = start.x - radius * math.sin(start.theta)
    cy = start.y + radius * math.cos(start.theta)
    theta = start.theta + phis
    return np.column_stack([cx + radius * np.sin(theta), cy - radius * np.cos(theta),
                            np.angle(np.exp(1j * theta))])


def _arc_case(start: Pose2D, radius: float, arc: float, steps: int, speed_sign: float = 1.0
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Wheel travels for ``steps`` equal steps round ``arc`` (m of centre travel)."""
    d_c = speed_sign * arc / steps
    phi = d_c / radius
    d_left = np.full(steps, d_c - phi * _B / 2)
    d_right = np.full(steps, d_c + phi * _B / 2)
    return d_left, d_right, _circle(start, radius, phi * np.arange(steps + 1))


def _integrate_hint(got: np.ndarray, d_left: np.ndarray, d_right: np.ndarray, b: float,
                    start: Pose2D) -> str:
    """Name a common slip if ``got`` is what it would give, else ''."""
    if not np.isfinite(got).all():
        return ("some poses are NaN: a straight step has phi = 0 and sin(phi/2)/(phi/2) is "
                "0/0 there; np.sinc(phi / (2 pi)) is the same factor and 1 at phi = 0")
    if not np.allclose(got[0], start.as_array(), atol=1e-12):
        return "row 0 must be the start pose, row k the pose after step k"
    want = reference_integrate_arcs(d_left, d_right, b, start)
    if np.allclose(got[:, :2], want[:, :2], atol=1e-9):
        heading_gap = np.angle(np.exp(1j * (got[:, 2] - want[:, 2])))
        if np.allclose(heading_gap, 0.0, atol=1e-9):
            return ("wrap the headings into (-pi, pi]: np.angle(np.exp(1j * theta)) does a "
                    "whole array")
        return ""
    for method, hint in (
            ("euler", "each chord points along the heading before its step (eqns 9-10); "
                      "point it at theta + phi/2"),
            ("midpoint", "the chord points the right way but is as long as the arc; a chord "
                         "is shorter: multiply by sin(phi/2)/(phi/2)")):
        other = odometry.integrate_odometry(d_left, d_right, b, start, method)
        if np.allclose(got[:, :2], other[:, :2], atol=1e-9):
            return hint
    return ""


@checker("whole log, exact arcs")
def integrate_arcs_check(fn: Callable[..., np.ndarray]) -> str:
    """Check ``fn(d_left, d_right, wheel_base, start)`` on closed forms and the library."""
    expect_own(fn, reference_integrate_arcs, odometry.integrate_odometry)
    cases = []
    start = Pose2D(1.0, 2.0, math.pi / 4)
    d = np.full(50, 0.02)
    line = np.column_stack([1.0 + np.arange(51) * 0.02 * math.cos(math.pi / 4),
                            2.0 + np.arange(51) * 0.02 * math.sin(math.pi / 4),
                            np.full(51, math.pi / 4)])
    cases.append((d, d, start, line, "a straight line (phi = 0 every step)"))
    spin = np.full(100, 0.01)
    turns = np.arange(101) * 0.02 / _B
    cases.append((-spin, spin, Pose2D(0.5, 0.5, 0.0),
                  np.column_stack([np.full(101, 0.5), np.full(101, 0.5),
                                   np.angle(np.exp(1j * turns))]),
                  "turning on the spot, 0.7 turns"))
    start = Pose2D(2.0, -1.0, 0.7)
    left, right, truth = _arc_case(start, 1.5, 1.5 * 1.5 * math.pi, 150)
    cases.append((left, right, start, truth, "3/4 of a circle of radius 1.5 m, left"))
    start = Pose2D(-3.0, 4.0, -2.5)
    left, right, truth = _arc_case(start, -0.8, 0.8 * 2.5, 40)
    cases.append((left, right, start, truth, "an arc of radius 0.8 m, right"))
    left, right, truth = _arc_case(start, 1.0, 1.0 * 1.2, 30, speed_sign=-1.0)
    cases.append((left, right, start, truth, "reversing round an arc"))
    rng = np.random.default_rng(62)
    left = rng.uniform(-0.03, 0.05, 400)
    right = np.where(rng.random(400) < 0.2, left, rng.uniform(-0.03, 0.05, 400))
    start = Pose2D(3.0, 4.0, -2.0)
    cases.append((left, right, start, reference_integrate_arcs(left, right, _B, start),
                  "400 random steps (abcwc's integrate_odometry, exact)"))
    for d_left, d_right, start, expected, what in cases:
        got = _array(fn(d_left.copy(), d_right.copy(), _B, start), expected.shape, what,
                     "N steps give N + 1 poses: the start, then one after each step")
        if not np.allclose(got, expected, rtol=0.0, atol=1e-9):
            hint = _integrate_hint(got, d_left, d_right, _B, start)
            expect(not hint, f"{what}: {hint}")
        expect_close(got, expected, what=what, rtol=0.0, atol=1e-9, ref="exact arcs")
    return (f"{len(cases)} logs match: a line, a spin, three arcs on their circles to "
            "1e-9 m, 400 random steps")


# --- predict, then run: euler at a longer period ---------------------------------------------


@checker("prediction")
def euler_prediction_check(predicted: Callable[[], float], measured: float,
                           at_20_ms: float) -> str:
    """Euler's end error at 0.5 s (% of the distance) written before the run, against the
    run's ``measured`` value; ``at_20_ms`` is the notebook's error at 20 ms, for the
    slips (euler's error grows in proportion to the period: 25 times from 20 ms)."""
    value = predicted()
    expect(isinstance(value, (int, float)) and math.isfinite(value) and value >= 0,
           f"predicted_euler_error() gave {format_value(value)}; write one percentage")
    if abs(value - measured) <= 0.15 * measured:
        return (f"you predicted {value:.3f} %; at 0.5 s euler ended {measured:.3f} % off "
                f"({measured / at_20_ms:.0f} times its {at_20_ms:.3f} % at 20 ms)")
    slips = {
        "that is its error at 20 ms: each step's error grows with the period, and the "
        "steps are fewer, but they all push the same way": at_20_ms,
        "that is the square of the period's ratio: a step's error d phi / 2 grows with the "
        "square, but there are 25 times fewer steps": at_20_ms * 25**2,
        "that is the percentage as a fraction: the check wants percent": at_20_ms * 25 / 100,
    }
    expect_no_slip(value, slips, lambda got, wrong: abs(got - wrong) <= 0.15 * wrong,
                   prefix=f"you predicted {value:.3f} %, euler ended {measured:.3f} % off: ")
    raise NotYet(f"you predicted {value:.3f} %, euler ended {measured:.3f} % off. It is "
                 "first order: its end error is in proportion to the period")


# --- diagnose: a log with a fault in its counts ----------------------------------------------

FAULTS = ("channels swapped", "left counts backwards", "right counts backwards")
_FAULT = "channels swapped"


def faulty_log():  # noqa: ANN201 - a RunLog, imported lazily
    """20 s of chapter 06's curvy test drive on the ideal chair in an empty hall, its
    encoder counts spoiled by one of :data:`FAULTS` (which one is the exercise)."""
    import dataclasses

    import abcwc
    from abcwc.sim.world import box_world
    from abcwc.types import Twist

    hall = box_world(120, 120, centred=True, name="hall")
    chair = abcwc.connect(world=hall, errors="ideal", seed=6, people=False)
    log = chair.run(lambda frame: Twist(0.8, 0.35 * math.sin(frame.t / 3.0) + 0.1), 20.0)
    return dataclasses.replace(log, ticks=log.ticks[:, ::-1].copy())


@checker("diagnosis")
def diagnosis_check(diagnosis: Callable[[], str]) -> str:
    """``diagnosis()`` names the fault of :func:`faulty_log`."""
    said = diagnosis()
    expect(said in FAULTS, f"diagnosis() gave {format_value(said)}; say one of {FAULTS}")
    if said == _FAULT:
        return ("right: the channels are swapped. The odometry drives the right distance "
                "but every turn the other way, a mirror image of the true path")
    raise NotYet(f"not {said!r}: with one wheel counting backwards the mean travel would be "
                 "near zero and the odometry would spin on the spot; this log's odometry "
                 "drives the right distance. Compare its turns with the true path's")
