"""Narrow passages: how wide a gap on a costmap is, and which gap a path squeezes through.

The global planner keeps the chair's centre :meth:`~abcwc.navigation.dwa.DwaPlanner.
passing_radius` from every obstacle cell, the same room its local planner needs. A path
planned with only the inscribed circle kept out (costmap_2d's rule) may still go through
a gap narrower than that; :func:`narrowest_gap` finds it, so that a failure can name it
("the 0.75 m gap at (6.00, 2.50)"), and :func:`close_gap` marks a gap the chair could not
get through impassable for the next plan (the last of the navigator's recoveries).

A gap's width is measured on the grid, from obstacle cell centre to obstacle cell centre
across the gap: the walls' own lines lie somewhere in those cells, so a width is good to
about one cell (5 cm on the navigator's maps).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from abcwc.navigation.costmap import LETHAL, Costmap


@dataclass(frozen=True)
class Gap:
    """A gap between obstacles: its ``width`` (m, obstacle cell centre to obstacle cell
    centre across it), its middle ``(x, y)`` (m, map frame: half-way between the two
    obstacle cells) and ``across`` (rad: the heading from one side to the other; the
    way through is at right angles to it)."""

    width: float
    x: float
    y: float
    across: float = 0.0

    def describe(self) -> str:
        """How a person would name it: "the 0.75 m gap at (6.00, 2.50)"."""
        return f"the {self.width:.2f} m gap at ({self.x:.2f}, {self.y:.2f})"


def minimum_clear_width(passing_radius: float) -> float:
    """m between obstacle cells: the narrowest straight gap whose centre line keeps the
    chair's centre ``passing_radius`` m from both sides (twice the radius)."""
    if not (math.isfinite(passing_radius) and passing_radius > 0):
        raise ValueError(f"passing_radius must be a finite number > 0 m, got {passing_radius!r}")
    return 2.0 * passing_radius


def gap_at(costmap: Costmap, row: int, col: int, reach: float = 1.5) -> Gap:
    """The gap at cell ``(row, col)``: from the nearest lethal cell on one side to the
    nearest on the other (the far side: lethal cells whose direction from the cell is
    more than 90 degrees from the first's), within ``reach`` m; ``inf`` wide when
    nothing lies on the far side that near (a wall to pass, not a gap)."""
    lethal = costmap.cost == LETHAL
    cells = math.ceil(reach / costmap.resolution)
    r0, c0 = max(row - cells, 0), max(col - cells, 0)
    rows, cols = np.nonzero(lethal[r0:row + cells + 1, c0:col + cells + 1])
    x, y = costmap.cell_to_world(np.array([row]), np.array([col]))[0]
    if not rows.size:
        return Gap(math.inf, float(x), float(y))
    offsets = np.column_stack([rows + r0 - row, cols + c0 - col]).astype(float)
    distance = np.hypot(offsets[:, 0], offsets[:, 1])
    first = int(np.argmin(distance))
    far = offsets @ offsets[first] < 0  # beyond the cell, seen from the first obstacle
    if not far.any():
        return Gap(math.inf, float(x), float(y))
    across = offsets[far] - offsets[first]
    nearest = int(np.argmin(np.hypot(across[:, 0], across[:, 1])))
    d_row, d_col = across[nearest]
    middle = offsets[first] + across[nearest] / 2  # (row, col) offsets from the cell
    res = costmap.resolution
    return Gap(float(math.hypot(d_row, d_col)) * res, float(x + middle[1] * res),
               float(y + middle[0] * res), math.atan2(d_row, d_col))


def narrowest_gap(costmap: Costmap, cells: np.ndarray, below: float) -> Gap | None:
    """Of the path ``cells`` (K, 2: row, col) nearer than ``below`` m to a lethal cell,
    the one in the narrowest gap (:func:`gap_at`); None if no path cell is that near an
    obstacle, or none of those lies in a gap."""
    clearance = ndimage.distance_transform_edt(costmap.cost != LETHAL) * costmap.resolution
    gaps = gaps_along(costmap, cells, clearance, below)
    return min(gaps, key=lambda g: g.width) if gaps else None


def gaps_along(costmap: Costmap, cells: np.ndarray, clearance: np.ndarray,
               below: float) -> list[Gap]:
    """The gaps a path ``cells`` (K, 2: row, col) goes through, in its order: for every
    run of consecutive path cells nearer than ``below`` m to a lethal cell
    (``clearance``, m, a distance transform of the costmap's lethal cells), the
    narrowest gap of the run (:func:`gap_at`), if it has one."""
    near = clearance[cells[:, 0], cells[:, 1]] < below
    gaps = []
    edges = np.flatnonzero(np.diff(np.concatenate([[0], near.astype(int), [0]])))
    for start, stop in zip(edges[::2], edges[1::2]):
        found = [gap_at(costmap, int(r), int(c)) for r, c in cells[start:stop]]
        found = [g for g in found if math.isfinite(g.width)]
        if found:
            gaps.append(min(found, key=lambda g: g.width))
    return gaps


def close_gap(costmap: Costmap, gap: Gap) -> Costmap:
    """A copy of ``costmap`` with the cells within half the gap's width (and a cell) of
    its narrowest point lethal: the gap shut, for a plan that must go another way."""
    closed = Costmap.like(costmap)
    closed.cost = costmap.cost.copy()
    radius = gap.width / 2 + costmap.resolution
    rows, cols = costmap.world_to_cell(np.array([[gap.x, gap.y]]))
    reach = math.ceil(radius / costmap.resolution) + 1
    r0, c0 = max(int(rows[0]) - reach, 0), max(int(cols[0]) - reach, 0)
    r1 = min(int(rows[0]) + reach + 1, costmap.height)
    c1 = min(int(cols[0]) + reach + 1, costmap.width)
    if r0 >= r1 or c0 >= c1:
        return closed
    box_rows, box_cols = np.indices((r1 - r0, c1 - c0))
    centres = costmap.cell_to_world(box_rows.ravel() + r0, box_cols.ravel() + c0)
    shut = np.hypot(centres[:, 0] - gap.x, centres[:, 1] - gap.y) <= radius
    closed.cost[box_rows.ravel()[shut] + r0, box_cols.ravel()[shut] + c0] = LETHAL
    return closed
