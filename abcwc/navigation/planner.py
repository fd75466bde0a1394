"""The global planner: the cheapest path over a costmap, as ROS's navfn/global_planner do.

Each cell costs to cross in proportion to its costmap value, so the path keeps away from
walls where it can and squeezes past them only where it must (navfn's cost-aware
traversal, Konolige's gradient planner without the interpolation)::

    weight(cell) = neutral + factor * cost(cell)        (navfn: COST_NEUTRAL 50, factor 0.8)

Cells at ``INSCRIBED`` (253) and above are impassable (the chair's centre there puts its
inscribed circle on an obstacle); unknown cells (255) are crossed at weight 253 (navfn's
``COST_OBS - 1``, a weight, not a cost: dearer than every known passable cell) when
``allow_unknown`` is set (global_planner's ``allow_unknown``), else blocked.
Moves go to the 8 neighbours; a move from cell ``a`` to ``b`` costs its length in cells
times the mean of the two weights, so a path's cost does not depend on its direction.

The search is A* (Hart, Nilsson and Raphael 1968), :func:`astar_search`, with the
octile distance times ``neutral`` as its heuristic: never more than the true cost, so the
first time the goal is taken from the queue its cost is the least. It is written once, as
plain Python that reads top to bottom, and compiled by numba so that a plan across a
500 x 500 costmap takes tens of milliseconds (``astar_search.py_func`` runs the same
lines uncompiled). The tests hold its cost equal to scipy's shortest paths on random
grids.

:func:`smooth` then shortens the cell path by cutting corners where the straight line
between two path cells crosses no costlier cells than the path itself did.

:func:`costs_to_goal` runs the same moves from the goal until every cell is settled
(Dijkstra, :func:`dijkstra_costs`): each cell's least cost to the goal, the measure the
navigator's progress check reads, which does not change when the plan does.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numba
import numpy as np

from abcwc.geometry import position_of
from abcwc.mapping.raytrace import walk_cells
from abcwc.navigation.costmap import INSCRIBED, NO_INFORMATION, Costmap

COST_NEUTRAL = 50.0
"""navfn's cost of crossing a free cell."""
COST_FACTOR = 0.8
"""navfn's weight per unit of costmap cost."""
UNKNOWN_WEIGHT = 253.0
"""navfn's weight of an unknown cell it may cross (``COST_OBS - 1``, navfn.cpp's
``setCostmap``)."""

class NoPathError(ValueError):
    """There is no way from the start to the goal (or one of them is blocked)."""


@dataclass(frozen=True)
class Path:
    """A planned path: ``cells`` (K, 2) as (row, col), ``points`` (K, 2) their centres in
    the map frame (m), and its ``cost`` (weight x cells, see the module notes)."""

    cells: np.ndarray
    points: np.ndarray
    cost: float

    @property
    def length(self) -> float:
        """m along the points."""
        return float(np.hypot(*np.diff(self.points, axis=0).T).sum()) if len(self.points) else 0.0


def cell_weights(costmap: Costmap, neutral: float = COST_NEUTRAL, factor: float = COST_FACTOR,
                 allow_unknown: bool = True) -> np.ndarray:
    """(height, width) float: the weight of crossing each cell; ``inf`` where impassable."""
    if not (neutral > 0 and factor >= 0):
        raise ValueError(f"neutral must be > 0 and factor >= 0, got {neutral!r}, {factor!r}")
    unknown = costmap.cost == NO_INFORMATION
    weights = neutral + factor * costmap.cost.astype(float)
    # navfn's 253, or the dearest passable cell's weight if other scales make it dearer
    weights[unknown] = max(UNKNOWN_WEIGHT, neutral + factor * (INSCRIBED - 1))
    blocked = (costmap.cost >= INSCRIBED) & ~unknown
    if not allow_unknown:
        blocked |= unknown
    weights[blocked] = np.inf
    return weights


def _endpoint(costmap: Costmap, weights: np.ndarray, point: object, name: str) -> tuple[int, int]:
    xy = position_of(point, name)
    rows, cols = costmap.world_to_cell(xy[None])
    row, col = int(rows[0]), int(cols[0])
    if not costmap.contains(row, col):
        raise NoPathError(f"the {name} ({xy[0]:.2f}, {xy[1]:.2f}) m is off the costmap")
    if not np.isfinite(weights[row, col]):
        raise NoPathError(f"the {name} ({xy[0]:.2f}, {xy[1]:.2f}) m is in an obstacle "
                          f"(cost {costmap.cost[row, col]})")
    return row, col


def _as_path(costmap: Costmap, cells: list[tuple[int, int]], cost: float) -> Path:
    array = np.array(cells, dtype=int).reshape(-1, 2)
    return Path(array, costmap.cell_to_world(array[:, 0], array[:, 1]), float(cost))


@numba.njit(cache=True)
def least_costs(weights: np.ndarray, start: int, goal: int,
                neutral: float) -> tuple[np.ndarray, np.ndarray]:
    """A* over the 8-connected grid of ``weights`` (Hart, Nilsson and Raphael 1968), from
    cell ``start`` towards cell ``goal`` (flat indices ``row * width + col``); with no
    goal (-1) and ``neutral`` 0 it is Dijkstra's search (1959), run until the queue is
    empty.

    A move to a neighbour costs its length in cells times the mean of the two cells'
    weights (inf: impassable). The heuristic is the octile distance times ``neutral``,
    the cheapest weight: never more than the true cost and consistent, so a cell's cost
    is final the first time it leaves the queue. Returns ``best`` (each cell's least
    cost found, flat; final for the goal and every cell settled before it) and
    ``came_from`` (for each cell the cell it was reached from, -1 where none).

    Compiled by numba; ``least_costs.py_func`` is the same code run by Python, for
    reading and stepping through on small grids.
    """
    height, width = weights.shape
    flat = weights.ravel()
    best = np.full(height * width, np.inf)
    came_from = np.full(height * width, -1, np.int64)
    goal_row, goal_col = goal // width, goal % width
    best[start] = 0.0
    queue = [(0.0, 0.0, start)]  # (cost so far + heuristic, cost so far, cell)
    while queue:
        _, cost, cell = heapq.heappop(queue)
        if cell == goal:
            break
        if cost > best[cell]:
            continue  # a cheaper way here was found after this entry was queued
        row, col = cell // width, cell % width
        for d_row in range(-1, 2):
            for d_col in range(-1, 2):
                next_row, next_col = row + d_row, col + d_col
                if ((d_row == 0 and d_col == 0) or not 0 <= next_row < height
                        or not 0 <= next_col < width):
                    continue
                nxt = next_row * width + next_col
                length = math.sqrt(2.0) if d_row != 0 and d_col != 0 else 1.0
                new_cost = cost + length * (flat[cell] + flat[nxt]) / 2  # inf: impassable
                if new_cost < best[nxt]:
                    best[nxt] = new_cost
                    came_from[nxt] = cell
                    across, along = abs(next_row - goal_row), abs(next_col - goal_col)
                    heuristic = neutral * (max(across, along)
                                           + (math.sqrt(2.0) - 1.0) * min(across, along))
                    heapq.heappush(queue, (new_cost + heuristic, new_cost, nxt))
    return best, came_from


@numba.njit(cache=True)
def astar_search(weights: np.ndarray, start: int, goal: int,
                 neutral: float) -> tuple[float, np.ndarray]:
    """A* from cell ``start`` to cell ``goal`` (:func:`least_costs`): the least cost
    (``inf`` when the goal cannot be reached) and ``came_from``. About 30 ms across
    500 x 500 cells."""
    best, came_from = least_costs(weights, start, goal, neutral)
    return best[goal], came_from


def dijkstra_costs(weights: np.ndarray, source: int) -> np.ndarray:
    """(height, width): the least cost from every cell to cell ``source`` (flat index)
    over the 8-connected grid of ``weights``, the same moves and costs as
    :func:`astar_search` (:func:`least_costs` with no goal and no heuristic: Dijkstra's
    search); ``inf`` where no way leads. A move's cost does not depend on its direction,
    so this is also every cell's cost *to* ``source``."""
    best, _ = least_costs(weights, source, -1, 0.0)
    return best.reshape(weights.shape)


def costs_to_goal(costmap: Costmap, goal: object, allow_unknown: bool = True) -> np.ndarray:
    """(height, width) every cell's least path cost to ``goal`` (a map point) in free
    floor metres (the cost over ``COST_NEUTRAL`` per cell, times the resolution: a
    free straight metre counts 1); ``inf`` where no way leads."""
    weights = cell_weights(costmap, allow_unknown=allow_unknown)
    row, col = _endpoint(costmap, weights, goal, "goal")
    costs = dijkstra_costs(weights, row * costmap.width + col)
    return costs * (costmap.resolution / COST_NEUTRAL)


def plan(costmap: Costmap, start: object, goal: object, **weight_options: object) -> Path:
    """The cheapest 8-connected path from ``start`` to ``goal`` (map points, m), searched
    by :func:`astar_search`; :class:`NoPathError` when there is none."""
    weights = cell_weights(costmap, **weight_options)  # type: ignore[arg-type]
    s = _endpoint(costmap, weights, start, "start")
    g = _endpoint(costmap, weights, goal, "goal")
    width = costmap.width
    neutral = float(weight_options.get("neutral", COST_NEUTRAL))  # type: ignore[arg-type]
    source, target = s[0] * width + s[1], g[0] * width + g[1]
    cost, came_from = astar_search(weights, source, target, neutral)
    if not math.isfinite(cost):
        raise NoPathError("no way from the start to the goal: the goal is walled off")
    chain = [target]
    while chain[-1] != source:
        chain.append(int(came_from[chain[-1]]))
    cells = [(node // width, node % width) for node in reversed(chain)]
    return _as_path(costmap, cells, cost)


def smooth(costmap: Costmap, path: Path, max_jump: int = 80) -> Path:
    """Cut the path's corners: from each kept cell, jump to the farthest of the next
    ``max_jump`` path cells whose straight line crosses no cell costlier than the worst
    the path itself crossed between them (all candidate lines traced at once). The result
    keeps the original ``cost``."""
    if not (isinstance(max_jump, int) and max_jump >= 1):
        raise ValueError(f"max_jump must be a whole number of cells >= 1, got {max_jump!r}")
    cells = path.cells
    if len(cells) <= 2:
        return path
    along = costmap.cost[cells[:, 0], cells[:, 1]]
    centres = cells[:, ::-1] + 0.5  # (x, y) in cell units
    kept = [0]
    while kept[-1] < len(cells) - 1:
        i = kept[-1]
        later = np.arange(i + 1, min(len(cells), i + 1 + max_jump))
        walk = walk_cells(np.broadcast_to(centres[i], (len(later), 2)), centres[later])
        crossed = np.maximum.reduceat(costmap.cost[walk.row, walk.col], walk.start[:-1])
        allowed = np.maximum.accumulate(along[i:later[-1] + 1])[1:]
        fine = np.flatnonzero(crossed <= allowed)
        # a diagonal step's line grazes a side cell at the corner: the next cell then
        # may not qualify as a line, but it is the path's own step
        kept.append(int(later[fine[-1]]) if fine.size else i + 1)
    cells = cells[kept]
    return Path(cells, costmap.cell_to_world(cells[:, 0], cells[:, 1]), path.cost)
