"""Checks for chapter 15, costmaps (thesis 3.1.3, 3.3.4, appendix A.17; ROS costmap_2d).

Exercises:

* ``inflation_cost(distance, inscribed_radius, k)``: costmap_2d's
  ``InflationLayer::computeCost`` for an array of distances (m) to the nearest lethal
  cell: 254 at 0, 253 within the inscribed radius, else 252 exp(-k (d - r_inscribed))
  cast to a byte (truncated);
* ``predicted_clearance()``: a number written down *before* the cell that measures it:
  how near a wall (m) the planner's path with A.17's costmap comes;
* ``scan_yaw_error(marks, static, lidar_xy)``: a diagnosis: by how many degrees a lidar's
  mount yaw was wrong when a local costmap was built, read off the costmap (and found on
  scans the notebook never shows);
* ``chair_costmap(walls, resolution)``: a design: a global costmap for the chair, judged
  on worlds the notebook never showed, where the chair must fit through doors of 0.85 m
  and keep off the walls of 2 m corridors.

Each ``reference_*`` function is an answer the notebook falls back on; a check handed
the library's own function (or a ``reference_*``) says so instead of passing.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from scipy import ndimage

from abcwc.checks.report import NotYet, checker, expect, expect_close, expect_own, format_value
from abcwc.navigation.costmap import (
    COST_SCALING_FACTOR,
    INSCRIBED,
    LETHAL,
    Costmap,
    chair_footprint,
    inflation_cost,
)
from abcwc.navigation.planner import NoPathError, plan
from abcwc.params import default_params
from abcwc.types import Pose2D

__all__ = [
    "DESIGN_DOOR",
    "MIN_CORRIDOR_CLEARANCE",
    "MYSTERY_CASES",
    "chair_costmap_check",
    "design_worlds",
    "inflation_check",
    "mystery_scan",
    "path_clearance",
    "prediction_check",
    "reference_chair_costmap",
    "reference_inflation_cost",
    "scan_yaw_check",
]

FOOTPRINT = chair_footprint(default_params())
DESIGN_DOOR = 0.85
"""m: the narrowest door of the design check's worlds (the chair is 0.48 m wide)."""
MIN_CORRIDOR_CLEARANCE = 0.6
"""m: how far off the walls a path along a 2 m corridor must stay (the middle is 1 m)."""


# --- reference answers ----------------------------------------------------------------


def reference_inflation_cost(distance, inscribed_radius: float,
                             k: float = COST_SCALING_FACTOR) -> np.ndarray:
    """costmap_2d's cost of each distance (m) to the nearest lethal cell (uint8)."""
    return inflation_cost(np.asarray(distance, dtype=float), inscribed_radius, k)


def reference_chair_costmap(walls: np.ndarray, resolution: float) -> Costmap:
    """The navigator's global costmap: the chair's inscribed radius (0.16 m), inflation
    to 0.7 m, costmap_2d's slope of 10 per metre."""
    costmap = Costmap.from_walls(walls, resolution)
    costmap.inflate(FOOTPRINT.inscribed_radius, 0.7, 10.0)
    return costmap


# --- exercise 1: inflation --------------------------------------------------------------


@checker("inflation cost")
def inflation_check(fn: Callable) -> str:
    """``fn(distance, inscribed_radius, k)`` against costmap_2d's computeCost."""
    expect_own(fn, reference_inflation_cost, inflation_cost)
    distances = np.concatenate([[0.0, 0.05, 0.1, 0.16, 0.1600001, 0.2, 0.33],
                                np.linspace(0.0, 1.5, 61)])
    for radius, k in ((0.16, 10.0), (0.5, 3.0), (0.0, 10.0)):
        got = np.asarray(fn(distances.copy(), radius, k))
        expected = inflation_cost(distances, radius, k).astype(float)
        expect(got.shape == expected.shape,
               f"r = {radius} m, k = {k}: gave {got.shape}, expected one cost per distance "
               f"{expected.shape}")
        got = got.astype(float)
        if got[0] == INSCRIBED and expected[0] == LETHAL:
            raise NotYet(f"r = {radius} m: distance 0 gave 253; a cell *on* an obstacle is "
                         "lethal, 254 (the check before the inscribed one)")
        rounded = np.where(distances > radius, np.round((INSCRIBED - 1) * np.exp(
            -k * (distances - radius))), expected)
        if not np.array_equal(got, expected) and np.array_equal(got, rounded):
            raise NotYet("the costs are rounded; costmap_2d casts 252 exp(...) to an "
                         "unsigned char, which truncates (floor)")
        unshifted = np.where(distances > radius, np.floor((INSCRIBED - 1) * np.exp(
            -k * distances)), expected)
        if radius > 0 and np.array_equal(got, unshifted):
            raise NotYet(f"r = {radius} m: the decay starts at the inscribed radius: "
                         "exp(-k (d - r_inscribed)), not exp(-k d)")
        expect_close(got, expected, what=f"r = {radius} m, k = {k}", atol=0.0,
                     ref="computeCost: 254 at 0, 253 within r, 252 exp(-k (d - r)) truncated")
    return f"{3 * len(distances)} distances match costmap_2d's computeCost"


# --- exercise 2: predict, then run ------------------------------------------------------


def path_clearance(points: np.ndarray, walls: np.ndarray, resolution: float = 0.02) -> float:
    """The smallest distance (m) from any of ``points`` (K, 2) to the walls ((N, 4)),
    through a distance transform of the walls rasterised at ``resolution``."""
    grid = Costmap.from_walls(walls, resolution)
    distance = ndimage.distance_transform_edt(grid.cost != LETHAL) * resolution
    rows, cols = grid.world_to_cell(np.asarray(points, dtype=float))
    return float(distance[rows, cols].min())


@checker("prediction")
def prediction_check(predicted: Callable[[], float], measured: float) -> str:
    """Compare the number written before the run with what the run measured (m)."""
    value = predicted()
    expect(isinstance(value, (int, float)) and math.isfinite(value),
           f"predicted_clearance() gave {format_value(value)}; write one number in metres")
    error = abs(value - measured)
    if error > 0.1:
        why = ("the path passes nearer than that: with A.17's 0.05 m of inflation every "
               "cell more than a cell from a wall costs nothing, so the cheapest path "
               "cuts corners as close as the cells allow"
               if value > measured else
               "the path stays farther off than that: the planner still cannot put the "
               "chair's centre on a cell the inflation marked")
        raise NotYet(f"you predicted {value:.2f} m, the path came {measured:.2f} m from a "
                     f"wall: {why}")
    return f"you predicted {value:.2f} m, the path came {measured:.2f} m from a wall"


# --- exercise 3: diagnose --------------------------------------------------------------


MYSTERY_CASES = ((Pose2D(13.0, 9.0, 0.3), -6.0),
                 (Pose2D(5.0, 4.5, 2.2), 4.5),
                 (Pose2D(24.0, 10.5, -0.6), -11.0))
"""(where the chair stood, the mount's yaw error in degrees) of each diagnosis case: the
notebook's first, then two it never shows, so no single angle passes."""


def mystery_scan(case: int = 0) -> tuple[Costmap, Costmap, np.ndarray]:
    """The diagnosis's evidence for :data:`MYSTERY_CASES` ``[case]``: ``(marks, static,
    lidar_xy)``. ``marks`` is a 5 x 5 m obstacle layer built from one lidar scan in the
    floor world with the lidar's mount yaw set wrong; ``static`` the same window of the
    map's walls; ``lidar_xy`` (m) where the lidar was. The chair's pose came from the
    simulator, so the walls and the returns would lie on each other but for the yaw."""
    from abcwc.geometry import compose
    from abcwc.sim import SimBase

    if not 0 <= case < len(MYSTERY_CASES):
        raise ValueError(f"case is 0 to {len(MYSTERY_CASES) - 1}, not {case}")
    start, yaw_error = MYSTERY_CASES[case]
    chair = SimBase("floor", seed=15, lidar=True, people=False, start=start)
    scan = chair.read().lidar
    mount = chair.params.lidar.mount
    wrong = (mount[0], mount[1], mount[2] + math.radians(yaw_error))
    marks = Costmap.rolling_window(chair.pose, 5.0, 0.05, default=0)
    marks.add_scan(scan, compose(chair.pose, wrong), 3.0, 3.5)
    static = Costmap.from_walls(chair.world.walls, 0.05)
    window = Costmap.rolling_window(chair.pose, 5.0, 0.05, default=0)
    rows, cols = np.indices(window.shape)
    centres = window.cell_to_world(rows.ravel(), cols.ravel())
    s_rows, s_cols = static.world_to_cell(centres)
    window.cost = static.cost[s_rows, s_cols].reshape(window.shape)
    lidar = np.asarray(compose(chair.pose, mount))[:2]
    return marks, window, lidar


@checker("scan yaw diagnosis")
def scan_yaw_check(fn: Callable[[Costmap, Costmap, np.ndarray], float]) -> str:
    """``fn(marks, static, lidar_xy)`` says by how many degrees the mount yaw was wrong
    (sign included), on the notebook's evidence and on two cases it never shows."""
    found = []
    for case, (_, true_error_deg) in enumerate(MYSTERY_CASES):
        marks, static, lidar_xy = mystery_scan(case)
        value = fn(marks, static, lidar_xy.copy())
        expect(isinstance(value, (int, float, np.integer, np.floating))
               and math.isfinite(value),
               f"scan_yaw_error() gave {format_value(value)}; write the angle in degrees")
        where = "the notebook's scan" if case == 0 else f"a scan you have not seen ({case})"
        if abs(value - math.radians(true_error_deg)) < 0.02:
            raise NotYet(f"on {where}: that looks like radians; the answer is asked in degrees")
        if abs(value + true_error_deg) <= 2.0:
            raise NotYet(f"on {where}: {value:.1f} deg has the wrong sign: the returns sit "
                         "turned the other way round the lidar")
        expect(abs(value - true_error_deg) <= 2.0,
               f"on {where}: {value:.1f} deg is not it: turn the scan's returns about the "
               "lidar until they lie on the static walls; the turn that fits best is the "
               "error (work it out from the layers handed in, not a number written down)")
        found.append(float(value))
    return (f"{found[0]:.1f} deg; the scan was built {MYSTERY_CASES[0][1]:.1f} deg off (and "
            f"{len(found) - 1} scans you had not seen found too)")


# --- exercise 4: design ----------------------------------------------------------------


def design_worlds(seed: int = 15) -> list[tuple[np.ndarray, tuple, tuple, list]]:
    """Worlds the notebook never shows: a 2 m corridor with rooms off it through doors of
    0.85-1.1 m. Each is ``(walls (N, 4), start, goal, corridor spans)``, start and goal in
    two rooms, the spans ``(x0, x1, y)``: stretches of corridor midline at least 1.5 m from
    any door."""
    rng = np.random.default_rng(seed)
    worlds = []
    for _ in range(3):
        length = float(rng.uniform(14.0, 20.0))
        doors = np.sort(rng.uniform(2.0, length - 2.0, 2))
        while doors[1] - doors[0] < 5.0:
            doors = np.sort(rng.uniform(2.0, length - 2.0, 2))
        widths = rng.uniform(DESIGN_DOOR, 1.1, 2)
        width_first = DESIGN_DOOR  # every world has a door as narrow as the check allows
        widths[0] = width_first
        walls = [[0, 0, length, 0], [0, 0, 0, 6], [length, 0, length, 6], [0, 6, length, 6]]
        # the corridor runs along y = 4..6; rooms below y = 4, one per door, split at x_mid
        x_mid = float((doors[0] + doors[1]) / 2)
        edges = [0.0]
        for centre, width in zip(doors, widths):
            edges += [centre - width / 2, centre + width / 2]
        edges.append(length)
        for a, b in zip(edges[0::2], edges[1::2]):
            walls.append([a, 4.0, b, 4.0])
        walls.append([x_mid, 0.0, x_mid, 4.0])
        start = (float(doors[0]), 1.5)
        goal = (float(doors[1]), 1.5)
        spans = [(float(doors[0] + 1.5), float(doors[1] - 1.5), 5.0)]
        worlds.append((np.array(walls, dtype=float), start, goal, spans))
    return worlds


@checker("chair costmap")
def chair_costmap_check(fn: Callable[[np.ndarray, float], Costmap]) -> str:
    """``fn(walls, resolution)`` gives a costmap on which the planner takes the chair
    through 0.85 m doors and along 2 m corridors at least 0.6 m off the walls."""
    expect_own(fn, reference_chair_costmap)
    worst = math.inf
    for k, (walls, start, goal, spans) in enumerate(design_worlds()):
        costmap = fn(walls.copy(), 0.05)
        expect(isinstance(costmap, Costmap),
               f"world {k}: chair_costmap gave {type(costmap).__name__}, expected a Costmap")
        try:
            path = plan(costmap, start, goal)
        except NoPathError as error:
            raise NotYet(f"world {k}: no path through its doors ({error}); a 0.85 m door "
                         "leaves 0.18 m each side of the chair: is the inscribed radius "
                         "the chair's (0.16 m), not its circumscribed one or A.17's "
                         "robot_radius?") from None
        for x0, x1, _ in spans:
            along = (path.points[:, 0] >= x0) & (path.points[:, 0] <= x1)
            if along.any():
                clearance = path_clearance(path.points[along], walls)
                worst = min(worst, clearance)
                expect(clearance >= MIN_CORRIDOR_CLEARANCE,
                       f"world {k}: along the corridor the path came {clearance:.2f} m from "
                       f"a wall; a chair with a person in it should keep at least "
                       f"{MIN_CORRIDOR_CLEARANCE} m off walls where the corridor allows: "
                       "inflate farther, or more steeply near the walls")
    return (f"{len(design_worlds())} unseen worlds: through every door, and at least "
            f"{worst:.2f} m off the corridor walls")
