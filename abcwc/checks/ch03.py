"""Checks for chapter 03, sonar obstacle avoidance (thesis 4.1.6, table 7, eqn 3, A.6).

* :func:`turn_angle_check` — table 7: the turn angle (degrees) for a sonar distance
  (metres), ``0.0`` beyond 1 m and ``None`` (reverse) closer than 0.2 m.
* :func:`wander_check` — a wander controller drives the simulated lab twice for a
  minute, from two places, without touching anything and without standing still.
"""

from __future__ import annotations

import dataclasses
import inspect
from collections.abc import Callable

from abcwc.checks.report import checker, expect, expect_close, format_value
from abcwc.control.pots import AvoidAction, sonar_turn_angle
from abcwc.types import SensorFrame

__all__ = [
    "TABLE_7",
    "WANDER_MIN_DISTANCE",
    "WANDER_RUNS",
    "WANDER_SECONDS",
    "table7_turn_angle",
    "turn_angle_check",
    "wander_check",
]

# Table 7 (distance in mm -> turn angle in degrees); None = reverse. Rows 1 and 11
# ("> 1000" and "< 200") are represented by a value just past each boundary.
TABLE_7 = (
    (1001, 0.0), (1000, 45.0), (900, 50.625), (800, 56.25), (700, 61.875), (600, 67.5),
    (500, 73.125), (400, 78.75), (300, 84.375), (200, 90.0), (199, None),
)
WANDER_SECONDS = 60.0
WANDER_MIN_DISTANCE = 15.0  # m per run: 0.25 m/s on average
WANDER_RUNS = (("start", 1), ("centre", 2))  # (place in the lab, seed)


def table7_turn_angle(distance_m: float) -> float | None:
    """Table 7 / eqn 3: turn angle (deg) for an obstacle ``distance_m`` ahead.

    ``0.0`` beyond 1 m (no turn), 45..90 degrees from 1 m down to 0.2 m, ``None``
    closer than 0.2 m (reverse). Built on :func:`abcwc.control.sonar_turn_angle`.
    """
    decision = sonar_turn_angle(distance_m)
    if decision.action is AvoidAction.REVERSE:
        return None
    return decision.angle_deg


@checker("table 7, turn angle")
def turn_angle_check(fn: Callable[[float], float | None]) -> str:
    """Compare ``fn(distance_m)`` with every row of table 7, the worked example and more."""
    cases = [(mm / 1000.0, angle, f"table 7, {mm} mm") for mm, angle in TABLE_7]
    cases += [(0.55, 70.3125, "the thesis's worked example, 550 mm"),
              (5.0, 0.0, "nothing within 1 m: no turn"),
              (0.05, None, "closer than 0.2 m: reverse")]
    cases += [(mm / 1000.0, table7_turn_angle(mm / 1000.0), "eqn 3")
              for mm in range(210, 1000, 35)]
    for distance, expected, ref in cases:
        got = fn(distance)
        what = f"{distance:g} m"
        if expected is None:
            expect(got is None,
                   f"{what} gave {format_value(got)}, expected None ({ref})")
            continue
        expect(got is not None, f"{what} gave None (reverse), expected {expected:g} deg ({ref})")
        expect_close(got, expected, what=what, rtol=0.0, atol=1e-6, unit="deg",
                     ref=ref)
    return f"all {len(TABLE_7)} rows of table 7, 70.3125 deg at 550 mm and {len(cases)} checks"


def _make_controller(make: object) -> Callable[[SensorFrame], object]:
    """A fresh controller from a class or zero-argument factory, or ``make`` itself."""
    if inspect.isclass(make):
        return make()
    if not callable(make):
        raise TypeError(f"expected a controller class or function, got {format_value(make)}")
    try:
        required = [p for p in inspect.signature(make).parameters.values()
                    if p.default is p.empty
                    and p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD)]
    except (TypeError, ValueError):
        required = [None]
    return make() if not required else make


def _without_ground_truth(controller: Callable[[SensorFrame], object]
                          ) -> Callable[[SensorFrame], object]:
    """``controller`` fed frames without the simulator's ground-truth pose."""
    def blind(frame: SensorFrame) -> object:
        return controller(dataclasses.replace(frame, pose=None))

    return blind


@checker("wander the lab")
def wander_check(make_controller: object) -> str:
    """Drive the lab for :data:`WANDER_SECONDS` from each of :data:`WANDER_RUNS`.

    ``make_controller`` is a controller class (or a function returning a fresh
    controller; a controller itself is used as it is). A controller maps a
    SensorFrame to a PotCommand or Twist. It sees the sensors only: the ground-truth
    pose is removed from every frame, as on the real chair. Each run must end with no
    collision and at least :data:`WANDER_MIN_DISTANCE` metres driven.
    """
    from abcwc.connect import connect

    total = 0.0
    for place, seed in WANDER_RUNS:
        controller = _make_controller(make_controller)
        chair = connect(world="lab", seed=seed, start=place)
        log = chair.run(_without_ground_truth(controller), WANDER_SECONDS)
        collisions = int(log.collisions[-1])
        distance = log.distance_travelled()
        if collisions:
            first = float(log.t[log.collisions > 0][0])
            x, y, _ = log.pose[log.collisions > 0][0]
            expect(False, f"from '{place}' the chair touched something at t = {first:.1f} s, "
                          f"near ({x:.1f}, {y:.1f}) m ({collisions} collisions in "
                          f"{WANDER_SECONDS:g} s)")
        expect(distance >= WANDER_MIN_DISTANCE,
               f"from '{place}' the chair drove only {distance:.1f} m in {WANDER_SECONDS:g} s; "
               f"a wanderer should cover at least {WANDER_MIN_DISTANCE:g} m "
               "(standing still never collides)")
        total += distance
    return (f"{len(WANDER_RUNS)} runs of {WANDER_SECONDS:g} s, {total:.1f} m driven, "
            "0 collisions")
