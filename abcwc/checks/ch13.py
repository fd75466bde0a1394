"""Checks for chapter 13, occupancy grid mapping (Probabilistic Robotics ch. 9; thesis
3.1.1, 4.3.8; ROS map_server).

Exercises:

* ``update_log_odds(log_odds, passed, returned, l_occ, l_free, l_min, l_max)``: one
  scan's update of a flat log-odds array (table 9.1 with the inverse sensor model of the
  module ``abcwc.mapping.grid``): each cell once, a return wins over a pass, clamped;
* ``predicted_scans()``: a number written down *before* the run that counts it: how many
  scans through a cell that sits at the clamp ``l_max`` until map_server calls it free;
* ``measured_scores()``: a measurement: precision and recall of the lab's map built at
  the EKF's poses (chapter 10), against the true walls.

Each ``reference_*`` function is an answer the notebook falls back on; a check handed
the library's own function (or a ``reference_*``) says so instead of passing.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import lru_cache

import numpy as np
from scipy.ndimage import binary_dilation

from abcwc.checks.report import (
    NotYet,
    checker,
    expect,
    expect_no_slip,
    expect_own,
    format_value,
    numbers,
)
from abcwc.mapping.grid import FREE_THRESH, InverseSensorModel, OccupancyGrid, integrate_log

__all__ = [
    "clearing_scans",
    "ekf_map_scores",
    "log_odds_cases",
    "prediction_check",
    "reference_update_log_odds",
    "scores_check",
    "survey",
    "update_check",
]


def reference_update_log_odds(log_odds, passed, returned, l_occ: float, l_free: float,
                              l_min: float, l_max: float) -> np.ndarray:
    """A new flat array: every passed cell ``+ l_free`` once, every returned cell
    ``+ l_occ`` once (and not ``l_free`` as well), clamped to ``[l_min, l_max]``."""
    out = np.array(log_odds, dtype=float)
    passed, returned = np.unique(passed), np.unique(returned)
    passed = np.setdiff1d(passed, returned)
    out[passed] = np.maximum(out[passed] + l_free, l_min)
    out[returned] = np.minimum(out[returned] + l_occ, l_max)
    return out


# --- exercise 1: the log-odds update -------------------------------------------------------


def log_odds_cases() -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(log_odds, passed, returned) the check tries: cells passed by several beams, a
    cell both passed and returned, cells near both clamps, and seeded random scans."""
    model = InverseSensorModel()
    rng = np.random.default_rng(13)
    cases = [(np.zeros(10), np.array([1, 2, 2, 3, 3, 3]), np.array([4, 4])),
             (np.zeros(6), np.array([0, 1, 2]), np.array([2, 5])),
             (np.array([model.l_min + 0.1, model.l_max - 0.1, 0.0, 1.0]),
              np.array([0, 2]), np.array([1, 3]))]
    for _ in range(3):
        size = 200
        cases.append((rng.uniform(model.l_min, model.l_max, size),
                      rng.integers(0, size, 300), rng.integers(0, size, 40)))
    return cases


@checker("log-odds update")
def update_check(fn: Callable) -> str:
    """``fn(log_odds, passed, returned, l_occ, l_free, l_min, l_max)`` against the rule."""
    expect_own(fn, reference_update_log_odds, OccupancyGrid.integrate)
    m = InverseSensorModel()
    for log_odds, passed, returned in log_odds_cases():
        expected = reference_update_log_odds(log_odds, passed, returned, m.l_occ, m.l_free,
                                             m.l_min, m.l_max)
        before = log_odds.copy()
        got = fn(log_odds.copy(), passed.copy(), returned.copy(), m.l_occ, m.l_free,
                 m.l_min, m.l_max)
        try:
            got = np.asarray(got, dtype=float)
        except (TypeError, ValueError):
            raise NotYet(f"update_log_odds gave {format_value(got)}; return the new "
                         "array") from None
        expect(got.shape == expected.shape, f"update_log_odds gave shape {got.shape}; "
               f"return the whole array, shape {expected.shape}")
        if np.allclose(got, expected):
            continue
        _explain(before, passed, returned, m, got, expected)
    return f"{len(log_odds_cases())} scans: each cell once, returns over passes, clamped"


def _explain(before, passed, returned, m, got, expected) -> None:
    def added(cells, amount):
        out = before.copy()
        np.add.at(out, cells, amount)
        return out

    twice = np.clip(added(returned, m.l_occ) + (added(passed, m.l_free) - before),
                    m.l_min, m.l_max)
    slips = {
        "a cell both passed and returned got l_free as well as l_occ: a return wins":
            np.clip(reference_update_log_odds(before, passed, np.array([], int), m.l_occ,
                                              m.l_free, m.l_min, m.l_max)
                    + np.isin(np.arange(len(before)), returned) * m.l_occ, m.l_min, m.l_max),
        "a cell that several beams passed moved once per beam: within one scan each cell "
        "is updated once (np.add.at counts repeats; fancy assignment does not)": twice,
        "nothing is clamped: log odds stay in [l_min, l_max], so a cell can change its "
        "mind": reference_update_log_odds(before, passed, returned, m.l_occ, m.l_free,
                                          -np.inf, np.inf),
    }
    expect_no_slip(got, slips, np.allclose)
    cell = int(np.argmax(~np.isclose(got, expected)))
    raise NotYet(f"cell {cell}: from {before[cell]:.3f} you gave {got[cell]:.3f}, expected "
                 f"{expected[cell]:.3f}")


# --- exercise 2: predict the clearing -------------------------------------------------------


def clearing_scans(model: InverseSensorModel | None = None) -> int:
    """Passes that take a cell from ``l_max`` to below map_server's free threshold."""
    m = model or InverseSensorModel()
    free = math.log(FREE_THRESH / (1 - FREE_THRESH))
    return math.floor((m.l_max - free) / -m.l_free) + 1


@checker("prediction")
def prediction_check(predicted: Callable[[], int], counted: int) -> str:
    """The number written before the run against the count."""
    value = predicted()
    expect(isinstance(value, (int, float)) and math.isfinite(value) and value >= 0,
           f"predicted_scans() gave {format_value(value)}; write a number of scans")
    m = InverseSensorModel()
    free = math.log(FREE_THRESH / (1 - FREE_THRESH))
    if abs(value - counted) <= 1:
        return f"you predicted {value:g} scans, it took {counted}"
    if value > 50:
        raise NotYet(f"you predicted {value:g}: without the clamp a wall seen a hundred times "
                     f"would take that long to clear; the clamp at l_max = {m.l_max} keeps it "
                     f"to {counted} scans ({m.l_max} - ({free:.2f}) over {-m.l_free} a scan)")
    raise NotYet(f"you predicted {value:g}, it took {counted}: from l_max = {m.l_max} down "
                 f"past log(0.196 / 0.804) = {free:.2f} at {m.l_free} a scan")


# --- exercise 3: measure a map made at the EKF's poses ---------------------------------------


@lru_cache(maxsize=1)
def survey():
    """The chapter's drive: 90 s of chapter 03's sonar avoider in the lab (seed 13) with
    the lidar on, through the body's safety filter (as the chair drives), and the EKF's
    poses over it (wheels and gyro, chapter 10)."""
    from abcwc.behaviours.sonar_avoid import SonarAvoider
    from abcwc.estimation.ekf import ChairEkf, run_ekf
    from abcwc.sim import SimBase

    chair = SimBase("lab", seed=13, lidar=True, people=False)
    log = chair.run(SonarAvoider(), 90.0)
    states, _ = run_ekf(log, ChairEkf(chair.world.start))
    return chair.world, log, states[:, :3]


@lru_cache(maxsize=1)
def _survey_maps() -> dict[str, OccupancyGrid]:
    """The survey's scans laid into 0.05 m grids at the EKF's poses and at the true ones."""
    world, log, poses = survey()
    maps = {}
    for name, at in (("the EKF", poses), ("true poses", log.pose)):
        grid = OccupancyGrid.covering(*world.bounds, 0.05, margin=1.0)
        integrate_log(grid, log, poses=at)
        maps[name] = grid
    return maps


def _scores(name: str, tolerance: int = 1) -> tuple[float, float]:
    """(precision, recall) of the map at ``name``'s poses against the true walls, within
    ``tolerance`` cells, over the walls near what that map's own scans saw."""
    from abcwc.mapping.truth import precision_recall, rasterise_walls

    world = survey()[0]
    grid = _survey_maps()[name]
    seen = binary_dilation(grid.known(), iterations=2)
    return precision_recall(grid, rasterise_walls(world.walls, grid), tolerance, region=seen)


def ekf_map_scores() -> tuple[float, float]:
    """(precision, recall) of the survey's map at the EKF's poses, 0.05 m cells, one
    cell's tolerance, the recall over the walls near what the scans observed."""
    return _scores("the EKF")


def _same_scores(got: tuple[float, float], other: tuple[float, float]) -> bool:
    return abs(got[0] - other[0]) <= 0.02 and abs(got[1] - other[1]) <= 0.02


@checker("measurement")
def scores_check(measured: Callable[[], tuple[float, float]]) -> str:
    """The two figures read off the run against the same measurement made here. A wrong
    pair is named by the slip it is, never answered with the right figures: a failure
    message must not be an answer to copy."""
    value = measured()
    got = numbers(value, 2, "measured_scores()", "write (precision, recall)")
    true_precision, true_recall = ekf_map_scores()
    if _same_scores(got, (true_precision, true_recall)):
        return (f"precision {true_precision:.2f}, recall {true_recall:.2f}: far below the "
                "0.9 a map needs")
    slips = {
        "precision and recall are swapped: precision is the share of the map's occupied "
        "cells that are walls, recall the share of the walls the map found":
            (true_recall, true_precision),
        "those are the scores of the map at the true poses; score maps[\"the EKF\"]":
            _scores("true poses"),
        "that counts an occupied cell correct only on a wall cell itself; allow one cell's "
        "tolerance, as the cell above does": _scores("the EKF", tolerance=0),
    }
    expect_no_slip(got, slips, _same_scores, prefix=f"you wrote ({got[0]:.2f}, {got[1]:.2f}): ")
    raise NotYet(f"you wrote ({got[0]:.2f}, {got[1]:.2f}), which is not what the EKF's map "
                 "scores: measure maps[\"the EKF\"] as the cell above measures the others "
                 "(0.05 m cells, one cell's tolerance, recall over the walls near what its "
                 "own scans saw) and write what the measurement gives")
