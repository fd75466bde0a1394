"""Checks for chapter 00, the tour: encoder geometry and reading a SensorFrame.

Exercises (thesis 4.2.1 and 2.2.5):

* ``counts_per_wheel_turn(d_wheel, d_encoder, pulses)``: encoder counts per drive-wheel
  turn, ``pulses * d_wheel / d_encoder`` (about 1258 for the Sterling Ruby);
* ``encoder_counts_to_distance(counts, counts_per_turn, d_wheel)``: tyre travel (m),
  ``counts / counts_per_turn * pi * d_wheel``; works for arrays too;
* ``distance_ahead(frame, params)``: distance (m) from base_link to what the sonar
  sees, ``frame.sonar + sonar mount x``, ``inf`` when the sonar reads its maximum.

Each ``reference_*`` function is the answer the notebook falls back on when the
exercise is not done yet.
* ``measured_counts_per_turn(log)``: the counts per drive-wheel turn a chair really gives,
  measured from a straight drive's counts (both wheels' mean) and its true path;
* ``predicted_rest_distance()``: a distance written down *before* the chair creeps at the
  wall: where base_link comes to rest (m from the wall) when the controller stops at a
  sonar distance of 1.2 m.
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
    expect_no_slip,
    expect_own,
    format_value,
)
from abcwc.params import ChairParams, default_params
from abcwc.types import Pose2D, SensorFrame, SimTruth, make_frame

__all__ = [
    "counts_measurement_check",
    "rest_prediction_check",
    "counts_per_wheel_turn",
    "distance_ahead",
    "encoder_counts_to_distance",
    "reference_counts_per_wheel_turn",
    "reference_distance_ahead",
    "reference_encoder_counts_to_distance",
]


# --- reference answers ----------------------------------------------------------------


def reference_counts_per_wheel_turn(d_wheel: float, d_encoder: float, pulses: int) -> float:
    """Encoder counts per drive-wheel turn: ``pulses * d_wheel / d_encoder`` (4.2.1)."""
    return pulses * d_wheel / d_encoder


def reference_encoder_counts_to_distance(counts, counts_per_turn: float, d_wheel: float):
    """Tyre travel (m) for ``counts`` encoder counts: one wheel turn rolls ``pi d_wheel``."""
    return counts / counts_per_turn * math.pi * d_wheel


def reference_distance_ahead(frame: SensorFrame, params: ChairParams) -> float:
    """Distance (m) from base_link to the nearest thing in the sonar's cone.

    The sonar sits ``params.sonar.mount[0]`` ahead of base_link; a reading at the
    sonar's maximum range means it saw nothing, so the answer is ``inf``.
    """
    if frame.sonar >= params.sonar.max_range:
        return math.inf
    return frame.sonar + params.sonar.mount[0]


# --- checks ---------------------------------------------------------------------------

_GEOMETRIES = (  # d_wheel (m), d_encoder (m), pulses per encoder turn
    (0.195, 0.062, 400),  # the Sterling Ruby (thesis 4.2.1)
    (0.2, 0.05, 100),
    (0.3, 0.1, 1024),
)


@checker("counts per wheel turn")
def counts_per_wheel_turn(fn: Callable[[float, float, int], float]) -> str:
    """Check ``fn(d_wheel, d_encoder, pulses)`` against ``pulses * d_wheel / d_encoder``."""
    expect_own(fn, reference_counts_per_wheel_turn)
    for d_wheel, d_encoder, pulses in _GEOMETRIES:
        expected = reference_counts_per_wheel_turn(d_wheel, d_encoder, pulses)
        got = fn(d_wheel, d_encoder, pulses)
        upside_down = pulses * d_encoder / d_wheel
        expect(not (_is_number(got) and math.isclose(float(got), upside_down, rel_tol=1e-9)),
               f"counts_per_wheel_turn({d_wheel}, {d_encoder}, {pulses}) gave "
               f"{format_value(got)}: the ratio is upside down (one turn of the big wheel "
               "turns the small encoder wheel several times)")
        expect_close(got, expected, what=f"counts_per_wheel_turn({d_wheel}, {d_encoder}, "
                     f"{pulses})", rtol=1e-6, ref="4.2.1")
    ruby = reference_counts_per_wheel_turn(*_GEOMETRIES[0])
    return (f"{len(_GEOMETRIES)} geometries match; the chair's is {ruby:.2f} counts per "
            "wheel turn")


@checker("encoder counts to distance")
def encoder_counts_to_distance(fn: Callable[..., object]) -> str:
    """Check ``fn(counts, counts_per_turn, d_wheel)``: scalars, negatives and arrays."""
    expect_own(fn, reference_encoder_counts_to_distance)
    p = default_params()
    per_turn = p.counts_per_wheel_turn
    cases = [
        (per_turn, per_turn, p.drive_wheel_diameter, "one wheel turn"),
        (0, per_turn, p.drive_wheel_diameter, "0 counts"),
        (1000, per_turn, p.drive_wheel_diameter, "1000 counts"),
        (-629, per_turn, p.drive_wheel_diameter, "-629 counts (reversing)"),
        (1242.7, 1242.7, 0.195, "one turn with the firmware's 1242.7"),
        (400, 400.0, 0.062, "one turn of the encoder wheel itself"),
    ]
    for counts, cpt, d_wheel, what in cases:
        expected = counts / cpt * math.pi * d_wheel
        expect_close(fn(counts, cpt, d_wheel), expected, what=what, rtol=1e-6, atol=1e-12,
                     unit="m", ref="4.2.1")
    counts = np.array([0, 500, 1258, 2516, -100])
    expected = counts / per_turn * math.pi * p.drive_wheel_diameter
    got = fn(counts, per_turn, p.drive_wheel_diameter)
    expect(np.shape(got) == counts.shape,
           f"an array of {len(counts)} counts gave {format_value(got)}; return one distance "
           "per count (NumPy arithmetic does that by itself)")
    expect_close(got, expected, what="array of counts", rtol=1e-6, atol=1e-12, unit="m")
    return (f"{len(cases)} values and an array match; one wheel turn rolls "
            f"{math.pi * p.drive_wheel_diameter:.4f} m")


def _frame(sonar: float, pose: Pose2D | None = None) -> SensorFrame:
    """A SensorFrame with a given sonar reading and everything else at rest."""
    return make_frame(sonar=sonar, truth=SimTruth(pose))


@checker("distance ahead")
def distance_ahead(fn: Callable[[SensorFrame, ChairParams], float]) -> str:
    """Check ``fn(frame, params)`` on made-up frames and on one from the simulator."""
    expect_own(fn, reference_distance_ahead)
    p = default_params()
    mount = p.sonar.mount[0]
    for reading in (2.605, 1.0, p.sonar.min_range):
        expect_close(fn(_frame(reading), p), reading + mount, what=f"sonar {reading:g} m",
                     rtol=0.0, atol=1e-6, unit="m", ref="the sonar sits "
                     f"{mount:.2f} m ahead of base_link")
    got = fn(_frame(p.sonar.max_range), p)
    expect(_is_number(got) and math.isinf(float(got)) and float(got) > 0,
           f"sonar {p.sonar.max_range:g} m (its maximum: nothing seen) gave "
           f"{format_value(got)}, expected inf")
    from abcwc.sim.base import SimBase

    chair = SimBase(world="lab", seed=3, start=Pose2D(7.0, 6.5, 0.0), people=False)
    frame = chair.read()
    truth = 10.0 - frame.truth.pose.x  # the lab's east wall is the line x = 10 m
    expect_close(fn(frame, chair.params), truth, what="simulated frame facing the east wall",
                 atol=0.03, unit="m", ref="ground truth 10 - x")
    return "4 made-up frames and a simulated one match (within 3 cm of the truth)"


def _is_number(value: object) -> bool:
    return isinstance(value, int | float | np.integer | np.floating) and not isinstance(
        value, bool)


# --- measure: the counts per wheel turn of this chair ---------------------------------------------


@checker("measurement")
def counts_measurement_check(measured: Callable[[object], float], log: object) -> str:
    """``measured(log)``: counts per drive-wheel turn from a straight drive's final counts
    (mean of both wheels) and its true path, against the same measurement made here."""
    p = default_params()
    value = measured(log)
    expect(isinstance(value, (int, float, np.floating)) and math.isfinite(float(value))
           and value > 0, f"measured_counts_per_turn gave {format_value(value)}; return one "
           "number of counts per wheel turn")
    value = float(value)
    turns = log.distance_travelled() / (math.pi * p.drive_wheel_diameter)
    expected = float(np.mean(log.ticks[-1]) - np.mean(log.ticks[0])) / turns
    nominal = p.counts_per_encoder_turn * p.drive_wheel_diameter / p.encoder_wheel_diameter
    if abs(value - expected) <= 0.002 * expected:
        return (f"this chair gives {value:.1f} counts per wheel turn, "
                f"{100 * (value / nominal - 1):+.1f} % from the nominal {nominal:.1f} (the "
                "thesis's firmware uses 1242.7)")
    slips = {
        f"that is the nominal {nominal:.1f} from the wheels' sizes; measure it from the log: "
        "the counts over the wheel turns the true path took": nominal,
        "that is counts per metre: one wheel turn rolls pi d_w":
            expected / (math.pi * p.drive_wheel_diameter),
        "that is metres per count, upside down": 1 / expected,
    }
    expect_no_slip(value, slips, lambda got, wrong: abs(got - wrong) <= 0.002 * abs(wrong),
                   prefix=f"{value:.6g}: ")
    raise NotYet(f"you measured {value:.1f}; the drive's mean count over its "
                 f"{turns:.2f} wheel turns gives {expected:.1f}")


# --- predict, then run: where the chair comes to rest ---------------------------------------------


@checker("prediction")
def rest_prediction_check(predicted: Callable[[], float], measured: float,
                          threshold: float = 1.2) -> str:
    """base_link's distance to the wall at rest (m), written before the run, against the
    run's; the controller stops at a sonar distance of ``threshold`` m."""
    value = predicted()
    expect(isinstance(value, (int, float)) and math.isfinite(value) and value >= 0,
           f"predicted_rest_distance() gave {format_value(value)}; write one distance in m")
    if value >= threshold - 0.03:
        raise NotYet(f"you predicted {value:.2f} m, the chair came to rest {measured:.2f} m "
                     f"from the wall: it cannot stop on the {threshold} m line. The sonar's "
                     "reading is up to 0.1 s old when the controller sees it, and the wheels "
                     "roll on after the stop command while the motors slow down")
    if abs(value - measured) <= 0.15:
        return (f"you predicted {value:.2f} m, it came to rest {measured:.2f} m from the wall: "
                f"{threshold - measured:.2f} m past the line, the reading's age and the "
                "roll-out")
    raise NotYet(f"you predicted {value:.2f} m, the chair came to rest {measured:.2f} m from "
                 f"the wall, {threshold - measured:.2f} m past the line: at 0.66 m/s a 0.1 s "
                 "old reading is 7 cm, and the roll-out after the stop a few tenths of a "
                 "second of driving")
