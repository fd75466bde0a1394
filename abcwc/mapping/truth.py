"""Scoring a built map against the true walls: the walls rasterised to grid cells, and the
precision and recall of a map's occupied cells.

The walls are a world's line segments (``World.walls``, (N, 4): x1 y1 x2 y2 in m): a
cell is a true wall cell when a wall passes through it (every segment traced at once by
:func:`abcwc.mapping.raytrace.walk_cells`). A built occupied cell is correct when a true
wall cell lies within ``tolerance_cells`` of it (Euclidean, centre to centre); a true
wall cell is found when a built occupied cell lies within the same distance:

    precision = correct built cells / built cells,    recall = found wall cells / wall cells.

With a tolerance of one cell, a wall on a cell boundary counts on either side of it.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import distance_transform_edt

from abcwc.mapping.grid import GridGeometry, OccupancyGrid
from abcwc.mapping.raytrace import walk_cells


def rasterise_walls(walls: np.ndarray, grid: GridGeometry) -> np.ndarray:
    """(height, width) bool on ``grid``'s cells: True where a wall segment (N, 4: x1 y1 x2
    y2, m, map frame) passes through the cell. Parts of walls outside the grid are
    dropped."""
    walls = np.asarray(walls, dtype=float)
    if walls.ndim != 2 or walls.shape[1] != 4:
        raise ValueError(f"walls must be an (N, 4) array of x1 y1 x2 y2 (m), got {walls.shape}")
    walk = walk_cells(grid.to_cell_units(walls[:, :2]), grid.to_cell_units(walls[:, 2:]))
    inside = grid.contains(walk.row, walk.col)
    cells = np.zeros(grid.shape, dtype=bool)
    cells[walk.row[inside], walk.col[inside]] = True
    return cells


def _distance_to(cells: np.ndarray) -> np.ndarray:
    """Distance (cells) from every cell to the nearest True cell of ``cells``; inf if none."""
    if not cells.any():
        return np.full(cells.shape, np.inf)
    return distance_transform_edt(~cells)


def precision_recall(built: OccupancyGrid | np.ndarray, truth: np.ndarray,
                     tolerance_cells: float = 1.0,
                     region: np.ndarray | None = None) -> tuple[float, float]:
    """Precision and recall of a map's occupied cells against the true wall cells.

    ``built`` is an :class:`OccupancyGrid` (its cells with p > 0.65) or a (height, width)
    bool array of occupied cells; ``truth`` the true wall cells on the same cells
    (:func:`rasterise_walls`). ``region`` (bool, same shape) limits the recall to the wall
    cells inside it, e.g. those near the area the scans observed. NaN when there is no
    cell to count.
    """
    occupied = built.occupied() if isinstance(built, OccupancyGrid) else np.asarray(built)
    truth = np.asarray(truth, dtype=bool)
    if occupied.shape != truth.shape:
        raise ValueError(f"built map {occupied.shape} and true walls {truth.shape} must be "
                         f"on the same cells")
    if tolerance_cells < 0:
        raise ValueError(f"tolerance_cells must be >= 0, got {tolerance_cells}")
    occupied = occupied.astype(bool)
    wanted = truth if region is None else truth & np.asarray(region, dtype=bool)
    correct = _distance_to(truth)[occupied] <= tolerance_cells
    found = _distance_to(occupied)[wanted] <= tolerance_cells
    precision = float(correct.mean()) if correct.size else float("nan")
    recall = float(found.mean()) if found.size else float("nan")
    return precision, recall
