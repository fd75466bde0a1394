"""The global planner: the cheapest path over a costmap, as ROS's navfn/global_planner do.

Each cell costs to cross in proportion to its costmap value, so the path keeps away from
walls where it can and squeezes past them only where it must (navfn's cost-aware
traversal, Konolige's gradient planner without the interpolation)::

    weight(cell) = neutral + factor * cost(cell)        (navfn: COST_NEUTRAL 50, factor 0.8)

Cells at ``INSCRIBED`` (253) and above are impassable (the chair's centre there puts its
inscribed circle on an obstacle); unknown cells (255) are crossed at the weight of cost
252 when ``allow_unknown`` is set (global_planner's ``allow_unknown``), else blocked.
Moves go to the 8 neighbours; a move from cell ``a`` to ``b`` costs its length in cells
times the mean of the two weights, so a path's cost does not depend on its direction.

Two searches give the same cost (a test holds them equal on random grids):

* :func:`astar` is A* written out (Hart, Nilsson and Raphael 1968) with the octile
  distance times ``neutral`` as its heuristic: never more than the true cost, so the first
  time the goal is taken from the queue its cost is the least. It reads top to bottom and
  is what the chapter teaches; it is slow in Python on large grids.
* :func:`plan` builds the same graph as a sparse matrix, all edges at once, and lets
  :func:`scipy.sparse.csgraph.dijkstra` (C) search it: the one to drive with.

:func:`smooth` then shortens the cell path by cutting corners where the straight line
between two path cells crosses no costlier cells than the path itself did.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np
from scipy.sparse import dia_matrix
from scipy.sparse.csgraph import dijkstra

from abcwc.geometry import position_of
from abcwc.mapping.raytrace import walk_cells
from abcwc.navigation.costmap import INSCRIBED, NO_INFORMATION, Costmap

COST_NEUTRAL = 50.0
"""navfn's cost of crossing a free cell."""
COST_FACTOR = 0.8
"""navfn's weight per unit of costmap cost."""

_MOVES = [(-1, -1), (-1, 0), (-1, 1), (0, -1), (0, 1), (1, -1), (1, 0), (1, 1)]


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
    cost = costmap.cost.astype(float)
    unknown = costmap.cost == NO_INFORMATION
    cost[unknown] = INSCRIBED - 1
    weights = neutral + factor * cost
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


def astar(costmap: Costmap, start: object, goal: object, **weight_options: object) -> Path:
    """A* from ``start`` to ``goal`` (map points, m), written out for reading."""
    weights = cell_weights(costmap, **weight_options)  # type: ignore[arg-type]
    s = _endpoint(costmap, weights, start, "start")
    g = _endpoint(costmap, weights, goal, "goal")
    neutral = float(weight_options.get("neutral", COST_NEUTRAL))

    def heuristic(cell: tuple[int, int]) -> float:  # octile distance x the cheapest weight
        dr, dc = abs(cell[0] - g[0]), abs(cell[1] - g[1])
        return neutral * (max(dr, dc) + (math.sqrt(2) - 1) * min(dr, dc))

    best = {s: 0.0}
    came_from: dict[tuple[int, int], tuple[int, int]] = {}
    queue = [(heuristic(s), 0.0, s)]
    while queue:
        _, cost, cell = heapq.heappop(queue)
        if cell == g:
            path = [cell]
            while path[-1] != s:
                path.append(came_from[path[-1]])
            return _as_path(costmap, path[::-1], cost)
        if cost > best[cell]:
            continue  # a cheaper way here was found after this entry was queued
        for dr, dc in _MOVES:
            nxt = (cell[0] + dr, cell[1] + dc)
            if not (0 <= nxt[0] < costmap.height and 0 <= nxt[1] < costmap.width):
                continue
            step = math.hypot(dr, dc) * (weights[cell] + weights[nxt]) / 2
            if not math.isfinite(step):
                continue
            if cost + step < best.get(nxt, math.inf):
                best[nxt] = cost + step
                came_from[nxt] = cell
                heapq.heappush(queue, (cost + step + heuristic(nxt), cost + step, nxt))
    raise NoPathError("no way from the start to the goal: the goal is walled off")


def grid_graph(weights: np.ndarray) -> dia_matrix:
    """The 8-connected graph of ``weights`` as a sparse (cells x cells) matrix: edge
    ``a -> b`` weighs ``|move| (w_a + w_b) / 2``, no edge into or out of an impassable
    cell. Each of the 8 moves is one diagonal band of the matrix, built in one array
    operation (a band's entry at column ``b`` is the edge from ``b - offset`` to ``b``)."""
    height, width = weights.shape
    n = height * width
    flat = weights.ravel()
    column = np.tile(np.arange(width), height)
    target = np.arange(n)
    offsets, bands = [], []
    for dr, dc in _MOVES:
        offset = dr * width + dc
        source = target - offset
        ok = (source >= 0) & (source < n)
        ok[ok] &= column[source[ok]] + dc == column[ok]  # no wrapping round a row's end
        band = np.zeros(n)
        band[ok] = math.hypot(dr, dc) * (flat[source[ok]] + flat[target[ok]]) / 2
        band[~np.isfinite(band)] = 0.0  # zero: no edge
        offsets.append(offset)
        bands.append(band)
    return dia_matrix((np.array(bands), np.array(offsets)), shape=(n, n))


def plan(costmap: Costmap, start: object, goal: object, **weight_options: object) -> Path:
    """The cheapest 8-connected path from ``start`` to ``goal`` (map points, m), searched
    by scipy's Dijkstra on :func:`grid_graph`; :class:`NoPathError` when there is none."""
    weights = cell_weights(costmap, **weight_options)  # type: ignore[arg-type]
    s = _endpoint(costmap, weights, start, "start")
    g = _endpoint(costmap, weights, goal, "goal")
    width = costmap.width
    source, target = s[0] * width + s[1], g[0] * width + g[1]
    distances, predecessors = dijkstra(grid_graph(weights).tocsr(), indices=source,
                                       return_predecessors=True)
    if not np.isfinite(distances[target]):
        raise NoPathError("no way from the start to the goal: the goal is walled off")
    chain = [target]
    while chain[-1] != source:
        chain.append(int(predecessors[chain[-1]]))
    cells = [(node // width, node % width) for node in reversed(chain)]
    return _as_path(costmap, cells, distances[target])


def smooth(costmap: Costmap, path: Path) -> Path:
    """Cut the path's corners: from each kept cell, jump to the farthest later cell whose
    straight line crosses no cell costlier than the worst the path itself crossed between
    them (all candidate lines traced at once). The result keeps the original ``cost``."""
    cells = path.cells
    if len(cells) <= 2:
        return path
    along = costmap.cost[cells[:, 0], cells[:, 1]]
    centres = cells[:, ::-1] + 0.5  # (x, y) in cell units
    kept = [0]
    while kept[-1] < len(cells) - 1:
        i = kept[-1]
        later = np.arange(i + 1, len(cells))
        walk = walk_cells(np.broadcast_to(centres[i], (len(later), 2)), centres[later])
        crossed = np.maximum.reduceat(costmap.cost[walk.row, walk.col], walk.start[:-1])
        allowed = np.maximum.accumulate(along[i:])[1:]
        fine = np.flatnonzero(crossed <= allowed)
        # a diagonal step's line grazes a side cell at the corner: the next cell then
        # may not qualify as a line, but it is the path's own step
        kept.append(int(later[fine[-1]]) if fine.size else i + 1)
    cells = cells[kept]
    return Path(cells, costmap.cell_to_world(cells[:, 0], cells[:, 1]), path.cost)
