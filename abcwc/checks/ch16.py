"""Checks for chapter 16, planning and the navigator (thesis 3.1.3, 3.3.5, 4.3.9, A.17;
ROS navfn, base_local_planner, move_base).

Exercises:

* ``cheapest_path_cost(weights, start, goal)``: the least cost of an 8-connected path
  over a grid of cell weights (``inf`` impassable) from cell ``start`` to cell ``goal``
  (``(row, col)``), a move costing its length in cells times the mean of the two cells'
  weights; ``inf`` when the goal cannot be reached;
* ``predicted_fraction()``: a number written down *before* the cell that measures it:
  the fraction of the cells Dijkstra touches that A* touches on the way to the cafeteria;
* ``culprit()`` and ``door_scales()``: a diagnosis and its fix: which of A.17's DWA
  scales keeps the chair from turning into a doorway, and scales that take it through
  doors the notebook never showed;
* ``clear_width(length, width, padding, resolution)``: the narrowest door (m, wall cell
  to wall cell) a chair of that outline can be planned through, by the local planner's
  model of it (three covering circles, the padding, the grid);
* ``doors_it_takes()``: written down *before* the run: which of the 0.75, 0.80, 0.85 and
  0.90 m doors of :func:`narrow_door_world` the chair drives through (the others it goes
  round).

Each ``reference_*`` function is an answer the notebook falls back on; a check handed
the library's own function (or a ``reference_*``) says so instead of passing.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra

from abcwc.checks.report import NotYet, checker, expect, expect_no_slip, expect_own, format_value
from abcwc.geometry import densify_polyline
from abcwc.navigation.costmap import (
    FREE_SPACE,
    LETHAL,
    Costmap,
    Footprint,
    chair_footprint,
    footprint_cost,
    window_lattice,
)
from abcwc.navigation.dwa import DwaPlanner, DwaResult
from abcwc.navigation.passages import minimum_clear_width
from abcwc.navigation.planner import astar_search, plan
from abcwc.params import default_params, load_navigation_params
from abcwc.sim.world import World, world_from_dict

__all__ = [
    "A17_SCALES",
    "DOOR_FAMILY",
    "DoorRun",
    "clear_width_check",
    "culprit_check",
    "door_decision",
    "door_planner",
    "door_run",
    "door_scales_check",
    "door_world",
    "doors_prediction_check",
    "narrow_door_world",
    "path_cost_check",
    "prediction_check",
    "reference_cheapest_path_cost",
    "reference_clear_width",
    "reference_door_scales",
    "shown_door",
    "unseen_doors",
]

FOOTPRINT = chair_footprint(default_params())
NAV = load_navigation_params()
A17_SCALES = {"pdist_scale": NAV.local_planner.pdist_scale,
              "gdist_scale": NAV.local_planner.gdist_scale,
              "occdist_scale": NAV.local_planner.occdist_scale}
"""A.17's DWA scoring scales (path 0.8, goal 0.6, occupancy 0.1)."""
_MOVES = [(dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc]


# --- reference answers ----------------------------------------------------------------


def reference_cheapest_path_cost(weights: np.ndarray, start: tuple[int, int],
                                 goal: tuple[int, int]) -> float:
    """The least path cost by abcwc's A* (``inf`` when there is none)."""
    weights = np.asarray(weights, dtype=float)
    width = weights.shape[1]
    cost, _ = astar_search(weights, start[0] * width + start[1], goal[0] * width + goal[1],
                           float(np.nanmin(weights[np.isfinite(weights)], initial=1.0)))
    return float(cost)


def reference_door_scales() -> dict[str, float]:
    """The navigator's scales: A.17's but an occupancy scale of 0.01 (base_local_planner's
    default)."""
    return {**A17_SCALES, "occdist_scale": 0.01}


# --- exercise 1: the cheapest path ------------------------------------------------------


def _graph_cost(weights: np.ndarray, start: tuple[int, int], goal: tuple[int, int],
                moves: list[tuple[int, int]], step: Callable) -> float:
    """The least cost over ``moves`` with ``step(length, w_from, w_to)`` per move, by
    scipy's Dijkstra on a sparse graph built here (the check's own reference)."""
    height, width = weights.shape
    rows, cols = np.indices(weights.shape)
    sources, targets, costs = [], [], []
    for dr, dc in moves:
        r2, c2 = rows + dr, cols + dc
        ok = (r2 >= 0) & (r2 < height) & (c2 >= 0) & (c2 < width)
        a = rows[ok] * width + cols[ok]
        b = r2[ok] * width + c2[ok]
        cost = step(math.hypot(dr, dc), weights.ravel()[a], weights.ravel()[b])
        keep = np.isfinite(cost)
        sources.append(a[keep])
        targets.append(b[keep])
        costs.append(cost[keep])
    n = height * width
    graph = coo_matrix((np.concatenate(costs), (np.concatenate(sources),
                                                np.concatenate(targets))), shape=(n, n))
    distances = dijkstra(graph.tocsr(), indices=start[0] * width + start[1])
    return float(distances[goal[0] * width + goal[1]])


def _mean_step(length: float, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return length * (a + b) / 2


def _random_weights(rng: np.random.Generator, size: int) -> np.ndarray:
    cost = rng.integers(0, 253, size=(size, size)).astype(float)
    cost[rng.random((size, size)) < 0.5] = 0.0
    weights = 50.0 + 0.8 * cost
    weights[rng.random((size, size)) < 0.2] = np.inf
    return weights


def path_cost_grids(seed: int = 16) -> list[tuple[np.ndarray, tuple[int, int], tuple[int, int]]]:
    """Seeded random weight grids with a start and a goal: some reachable, one walled off."""
    rng = np.random.default_rng(seed)
    grids = []
    for size in (6, 12, 20, 20, 28):
        weights = _random_weights(rng, size)
        start, goal = (0, 0), (size - 1, size - 1)
        weights[start] = weights[goal] = 50.0
        grids.append((weights, start, goal))
    walled = np.full((10, 10), 50.0)
    walled[:, 5] = np.inf
    grids.append((walled, (4, 1), (4, 8)))
    return grids


@checker("cheapest path")
def path_cost_check(fn: Callable) -> str:
    """``fn(weights, start, goal)`` against scipy's Dijkstra on the same grid."""
    expect_own(fn, reference_cheapest_path_cost, astar_search, plan)
    grids = path_cost_grids()
    for weights, start, goal in grids:
        expected = _graph_cost(weights, start, goal, _MOVES, _mean_step)
        got = fn(weights.copy(), start, goal)
        expect(isinstance(got, (int, float, np.floating)),
               f"a {weights.shape[0]} x {weights.shape[1]} grid gave {format_value(got)}; "
               "return the cost as one number (math.inf when there is no way)")
        got = float(got)
        if math.isinf(expected):
            expect(math.isinf(got), f"the goal {goal} is walled off, but you returned "
                   f"{got:g}: return math.inf when the search runs out of cells")
            continue
        if math.isclose(got, expected, rel_tol=1e-9):
            continue
        variants = {
            "only 4 moves: the diagonal moves are missing (8 neighbours, the diagonal "
            "ones sqrt(2) long)": ([(-1, 0), (1, 0), (0, -1), (0, 1)], _mean_step),
            "the diagonal moves cost as much as the straight ones: a diagonal step is "
            "sqrt(2) cells long": (_MOVES, lambda length, a, b: (a + b) / 2),
            "each move costs the weight of the cell it enters; navfn's move costs the "
            "mean of the two cells' weights (so a path costs the same both ways)":
                (_MOVES, lambda length, a, b: length * b),
        }
        slips = {slip: _graph_cost(weights, start, goal, moves, step)
                 for slip, (moves, step) in variants.items()}
        expect_no_slip(got, slips, lambda got, wrong: math.isclose(got, wrong, rel_tol=1e-9),
                       suffix=f" ({weights.shape[0]} x {weights.shape[1]} grid: gave "
                              f"{got:.1f}, expected {expected:.1f})")
        if got < expected:
            raise NotYet(f"a {weights.shape[0]} x {weights.shape[1]} grid gave {got:.1f}, "
                         f"less than the least possible {expected:.1f}: does the search step "
                         "into impassable (inf) cells or off the grid?")
        raise NotYet(f"a {weights.shape[0]} x {weights.shape[1]} grid gave {got:.1f}, "
                     f"expected {expected:.1f}: a cheaper path exists (is a cell's cost "
                     "final only when it leaves the queue, and is the heuristic never more "
                     "than the true cost?)")
    return f"{len(grids)} grids: the least cost every time, and inf where walled off"


# --- exercise 2: predict, then run ----------------------------------------------------


@checker("prediction")
def prediction_check(predicted: Callable[[], float], measured: float) -> str:
    """Compare the fraction written before the run with the measured one."""
    value = predicted()
    expect(isinstance(value, (int, float)) and math.isfinite(value) and 0 <= value <= 1,
           f"predicted_fraction() gave {format_value(value)}; write one fraction in 0..1")
    if abs(value - measured) > 0.1:
        why = ("A* touches more than that: its heuristic counts 50 a cell in a straight "
               "line, through walls, so every room on the goal's side of the corridor "
               "looks promising and is searched before the search learns its only door "
               "leads back"
               if value < measured else
               "A* touches fewer than that: the heuristic pulls the search towards the "
               "goal, and Dijkstra spreads in every direction until it gets there")
        raise NotYet(f"you predicted {value:.2f}, A* touched {measured:.2f} of Dijkstra's "
                     f"cells: {why}")
    return f"you predicted {value:.2f}, A* touched {measured:.2f} of Dijkstra's cells"


# --- exercise 3: diagnose and fix the DWA's scales --------------------------------------


def door_world(door_x: float, door_width: float) -> np.ndarray:
    """Walls (N, 4; m) of a 12 m x 2 m corridor (y 0..2) with a room above it (y 2..6)
    entered by a door of ``door_width`` m centred at ``door_x``."""
    return np.array([[0, 0, 12, 0], [12, 0, 12, 6], [12, 6, 0, 6], [0, 6, 0, 0],
                     [0, 2, door_x - door_width / 2, 2], [door_x + door_width / 2, 2, 12, 2]],
                    dtype=float)


@dataclass(frozen=True)
class DoorRun:
    """One run of :func:`door_run`."""

    reached: bool
    seconds: float
    poses: np.ndarray  # (K, 3) every control cycle
    plan: np.ndarray  # (P, 2) the global plan
    worst_cost: int  # the highest static-costmap cost under the footprint on the way
    costmap: Costmap


def door_planner(scales: dict[str, float]) -> DwaPlanner:
    """DWA with the navigator's limits (0.8 m/s, 0.8 rad/s, no reversing, 0.05 m of
    footprint padding) and the given scoring ``scales``."""
    local_params = replace(NAV.local_planner, max_vel_x=0.8, min_vel_x=0.0, acc_lim_x=0.8,
                           max_vel_theta=0.8, acc_lim_theta=1.5, **scales)
    return DwaPlanner(FOOTPRINT, NAV, local_params, padding=0.05)


def door_decision(planner: DwaPlanner, static: Costmap, path: np.ndarray, pose: np.ndarray,
                  velocity: tuple[float, float]) -> tuple[DwaResult, Costmap]:
    """One DWA cycle at ``pose``: the 5 x 5 m local costmap cut from ``static`` (cells off
    it lethal) and the next 2 m of ``path`` from its point nearest the chair."""
    local = Costmap.rolling_window(pose, 5.0, static.resolution, default=FREE_SPACE,
                                   lattice=window_lattice(static, static.resolution))
    rows, cols = np.indices(local.shape)
    g_rows, g_cols = static.world_to_cell(local.cell_to_world(rows.ravel(), cols.ravel()))
    on_map = static.contains(g_rows, g_cols)
    cost = np.full(rows.size, LETHAL, dtype=np.uint8)
    cost[on_map] = static.cost[g_rows[on_map], g_cols[on_map]]
    local.cost = cost.reshape(local.shape)
    nearest = int(np.argmin(np.hypot(path[:, 0] - pose[0], path[:, 1] - pose[1])))
    ahead = path[nearest:]
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(ahead, axis=0).T))])
    return planner.plan(local, tuple(pose), velocity, ahead[along <= 2.0]), local


def door_run(walls: np.ndarray, start: tuple[float, float, float],
             goal: tuple[float, float], scales: dict[str, float],
             seconds: float = 40.0, tolerance: float = 0.4) -> DoorRun:
    """Drive from ``start`` to ``goal`` with the global plan (the chair's costmap, as in
    chapter 15) followed by :func:`door_planner`; the chair moves exactly as commanded (a
    kinematic chair, no physics), five decisions a second. ``reached`` when within
    ``tolerance`` m of the goal before ``seconds``."""
    static = Costmap.from_walls(walls, 0.05)
    static.inflate(FOOTPRINT.inscribed_radius, 0.7, 10.0)
    path = densify_polyline(plan(static, start[:2], goal).points, 0.05)
    planner = door_planner(scales)
    period = 1.0 / planner.frequency
    pose, velocity, t, worst = np.array(start, dtype=float), (0.0, 0.0), 0.0, 0
    poses = [pose.copy()]
    while t < seconds:
        if math.hypot(goal[0] - pose[0], goal[1] - pose[1]) <= tolerance:
            return DoorRun(True, t, np.array(poses), path, worst, static)
        result, _ = door_decision(planner, static, path, pose, velocity)
        v, w = result.command.v, result.command.w
        for _ in range(10):  # the cycle's arc in ten steps, each footprint checked
            dt = period / 10
            pose = pose + np.array([v * math.cos(pose[2]) * dt, v * math.sin(pose[2]) * dt,
                                    w * dt])
            worst = max(worst, footprint_cost(static, FOOTPRINT, tuple(pose)))
        velocity, t = (v, w), t + period
        poses.append(pose.copy())
    return DoorRun(False, t, np.array(poses), path, worst, static)


def shown_door() -> tuple[np.ndarray, tuple[float, float, float], tuple[float, float]]:
    """The notebook's door: 1 m wide at x = 6 m, the chair starting 5 m down the corridor."""
    return door_world(6.0, 1.0), (1.0, 1.0, 0.0), (6.0, 4.0)


def unseen_doors(seed: int = 1616, count: int = 6) -> list[tuple[np.ndarray, tuple, tuple]]:
    """Seeded doors 0.95-1.1 m wide the notebook never showed, the chair starting at least
    2.5 m down the corridor and facing them."""
    rng = np.random.default_rng(seed)
    doors = []
    while len(doors) < count:
        door_x, width = rng.uniform(3.0, 9.0), rng.uniform(0.95, 1.1)
        start_x = rng.uniform(1.0, 11.0)
        if abs(start_x - door_x) < 2.5:
            continue
        heading = 0.0 if door_x > start_x else math.pi
        doors.append((door_world(door_x, width), (start_x, 1.0, heading), (door_x, 4.0)))
    return doors


@checker("culprit")
def culprit_check(fn: Callable[[], str]) -> str:
    """``fn()`` names the scale that keeps A.17's chair out of the door."""
    answer = fn()
    expect(isinstance(answer, str), f"culprit() gave {format_value(answer)}; return one of "
           "'pdist_scale', 'gdist_scale', 'occdist_scale'")
    answer = answer.strip()
    if answer == "occdist_scale":
        return ("occdist_scale: at 0.1 one unit of cost under the chair weighs as much as "
                "1/6 m of goal distance (0.1 / 0.6); towards a door the cost climbs faster "
                "than the goal comes nearer, so standing still scores best")
    hints = {
        "pdist_scale": "the path term pulls the chair *along* the plan, which turns into "
                       "the door: it argues for the door, not against it",
        "gdist_scale": "the goal term favours trajectories ending nearer the local goal, "
                       "which lies through the door: it argues for the door too",
    }
    expect(answer in hints, f"culprit() gave {answer!r}; return one of 'pdist_scale', "
           "'gdist_scale', 'occdist_scale'")
    raise NotYet(f"not {answer}: {hints[answer]}; look at which term is largest for the "
                 "trajectories that turn in")


@checker("door scales")
def door_scales_check(fn: Callable[[], dict]) -> str:
    """``fn()`` gives DWA scales that take the chair through the shown door and through
    doors it never saw, without touching a wall."""
    scales = fn()
    expect(isinstance(scales, dict) and set(scales) == set(A17_SCALES),
           f"door_scales() gave {format_value(scales)}; return a dict with exactly the keys "
           f"{sorted(A17_SCALES)}")
    for name, value in scales.items():
        expect(isinstance(value, (int, float)) and math.isfinite(value) and value >= 0,
               f"{name} = {format_value(value)}: each scale is a finite number >= 0")
    if scales == A17_SCALES:
        raise NotYet("these are A.17's scales, which keep the chair out of the shown door")
    for k, (walls, start, goal) in enumerate([shown_door(), *unseen_doors()]):
        run = door_run(walls, start, goal, {k: float(v) for k, v in scales.items()})
        where = "the shown door" if k == 0 else (
            f"an unseen door {walls[5, 0] - walls[4, 2]:.2f} m wide at x = "
            f"{(walls[4, 2] + walls[5, 0]) / 2:.1f} m")
        expect(run.worst_cost < LETHAL, f"{where}: the footprint touched a wall")
        expect(run.reached, f"{where}: the chair did not get through in {run.seconds:.0f} s "
               f"(it ended {math.hypot(goal[0] - run.poses[-1, 0], goal[1] - run.poses[-1, 1]):.1f}"
               " m from the goal)")
    return f"through the shown door and {len(unseen_doors())} unseen ones, touching nothing"


# --- exercise 5: the chair's minimum clear width -------------------------------------------

DOOR_FAMILY = (0.75, 0.80, 0.85, 0.90)
"""m: the doors of :func:`narrow_door_world` the notebook drives through (or round)."""


def reference_clear_width(length: float, width: float, padding: float,
                          resolution: float) -> float:
    """m: twice the local planner's passing radius for a ``length`` x ``width`` chair
    grown by ``padding``, on cells of ``resolution`` m."""
    half_length, half_width = length / 2, width / 2
    outline = Footprint(np.array([[half_length, half_width], [-half_length, half_width],
                                  [-half_length, -half_width], [half_length, -half_width]]))
    return minimum_clear_width(DwaPlanner(outline, NAV, padding=padding)
                               .passing_radius(resolution))


def clear_width_cases(seed: int = 1617) -> list[tuple[float, float, float, float]]:
    """The chair of table 2 and seeded other outlines: (length, width, padding,
    resolution), m."""
    rng = np.random.default_rng(seed)
    cases = [(0.61, 0.482, 0.05, 0.05)]
    for _ in range(5):
        cases.append((float(rng.uniform(0.8, 1.3)), float(rng.uniform(0.55, 0.7)),
                      float(rng.choice([0.0, 0.02, 0.05])), float(rng.choice([0.025, 0.05]))))
    return cases


@checker("minimum clear width")
def clear_width_check(fn: Callable) -> str:
    """``fn(length, width, padding, resolution)`` against the local planner's passing
    radius, for table 2's chair and outlines the notebook never showed."""
    expect_own(fn, reference_clear_width, minimum_clear_width, DwaPlanner.passing_radius)
    for length, width, padding, resolution in clear_width_cases():
        got = fn(length, width, padding, resolution)
        chair = f"a {length:.2f} x {width:.2f} m chair, {padding:.2f} m padding, " \
                f"{resolution:.3f} m cells"
        expect(isinstance(got, (int, float, np.floating)) and math.isfinite(float(got)),
               f"{chair} gave {format_value(got)}; return the width as one number, m")
        got = float(got)
        expected = reference_clear_width(length, width, padding, resolution)
        if math.isclose(got, expected, abs_tol=1e-6):
            continue
        circle = math.hypot(length / 6, width / 2)
        half_diagonal = resolution / math.sqrt(2)
        slips = {
            "that is the chair's own width with its padding: the local planner checks "
            "circles that cover the chair, and they stick out past its sides":
                width + 2 * padding,
            "that is the width the chair sweeps turning on the spot: through a door it "
            "goes straight, lined up with the opening": 2 * (math.hypot(length / 2, width / 2)
                                                            + padding),
            "one circle round the whole chair: the local planner covers it with three, "
            "each over a third of its length": 2 * (math.hypot(length / 2, width / 2)
                                                    + padding + 2 * half_diagonal),
            "the grid is missing: a wall lies somewhere in its cell and the chair "
            "somewhere in its own, half a cell's diagonal each": 2 * (circle + padding),
            "only one half-diagonal of the grid: the wall's cell and the chair's cell "
            "each add one": 2 * (circle + padding + half_diagonal),
            "that is a radius: a door has a wall on both sides":
                circle + padding + 2 * half_diagonal,
            "the padding counts once: it grows the chair on both sides":
                2 * (circle + 2 * half_diagonal) + padding,
        }
        expect_no_slip(got, slips, lambda got, wrong: math.isclose(got, wrong, abs_tol=1e-6),
                       suffix=f" ({chair})")
        raise NotYet(f"{chair}: you gave {got:.3f} m, which is not the width the local "
                     "planner needs: three circles along the chair, each over a third of "
                     "its length and its whole width, grown by the padding, and a cell's "
                     "diagonal for the grid")
    return (f"{len(clear_width_cases())} outlines: the width the local planner needs, "
            "every time")


# --- exercise 6: predict, then run: which doors does the chair take? ------------------------


def narrow_door_world(width: float, way_round: bool = True) -> World:
    """Two 6 x 5 m rooms joined by a ``width`` m door at (6, 2.5) m, and (``way_round``)
    a 2 m corridor along their north side that both open on through 1.2 m gaps; the
    chair starts at (2, 1) m in the west room, the ``office`` goal is (10, 4) m."""
    low, high = 2.5 - width / 2, 2.5 + width / 2
    walls = [[[0, 0], [12, 0], [12, 7], [0, 7], [0, 0]],
             [[6, 0], [6, low]], [[6, high], [6, 5 if way_round else 7]]]
    walls += ([[[0, 5], [1.0, 5]], [[2.2, 5], [9.6, 5]], [[10.8, 5], [12, 5]]] if way_round
              else [[[0, 5], [12, 5]]])
    return world_from_dict({"name": f"two rooms, a {width:.2f} m door", "walls": walls,
                            "places": {"start": [2.0, 1.0, 0.5], "office": [10.0, 4.0, 0.0]}})


def _planned_through(width: float) -> bool:
    """Whether the navigator's first plan to the office goes through the door."""
    from abcwc.behaviours.navigator import Navigator

    navigator = Navigator.for_world(narrow_door_world(width))
    navigator.go_to("office")
    points = navigator.path.points  # type: ignore[union-attr]
    at_door = np.abs(points[:, 0] - 6.0) < 0.1
    return bool(at_door.any() and points[at_door, 1].max() < 5.0)


@checker("doors")
def doors_prediction_check(predicted: Callable[[], object],
                           measured: dict[float, bool]) -> str:
    """The doors written down before the run against the doors the chair drove through
    (``measured``: width -> through it), which the check confirms from the navigator's
    own plans."""
    answer = predicted()
    try:
        chosen = {round(float(w), 2) for w in answer}  # type: ignore[union-attr]
    except (TypeError, ValueError):
        chosen = None
    expect(chosen is not None and chosen <= set(DOOR_FAMILY),
           f"doors_it_takes() gave {format_value(answer)}; return the widths (m) of the "
           f"doors the chair goes through, from {list(DOOR_FAMILY)}")
    for width in DOOR_FAMILY:
        expect(measured.get(width) == _planned_through(width),
               f"the measured runs handed to the check do not match the navigator's own "
               f"plans at the {width:.2f} m door: run the cell above again")
    taken = {w for w in DOOR_FAMILY if measured[w]}
    if chosen == taken:
        return (f"you predicted {sorted(chosen)}, and the chair drove through exactly those "
                "doors and round the others")
    missed, extra = sorted(taken - chosen), sorted(chosen - taken)
    why = []
    if extra:
        why.append(f"{extra} it went round: narrower than the width it needs, which is more "
                   "than its 0.48 m, with the covering circles, the padding and the grid")
    if missed:
        why.append(f"{missed} it drove through: the chair needs less than those, lined up "
                   "with the door (it need not turn in it)")
    raise NotYet(f"you predicted {sorted(chosen)}: " + "; ".join(why))
