"""Every grid cell a straight segment passes through, for many segments at once.

The exact cell walk of Amanatides and Woo, "A fast voxel traversal algorithm for ray
tracing" (Eurographics 1987), done for all segments in one set of array operations
instead of one loop step per cell. Coordinates are in cell units: cell ``(i, j)`` (column
``i``, row ``j``) is the square ``i <= x < i + 1``, ``j <= y < j + 1``, so a point lies
in cell ``(floor(x), floor(y))``.

A segment from ``a`` to ``b`` enters a new cell every time it crosses a grid line. It
crosses the vertical lines between ``floor(a_x)`` and ``floor(b_x)`` and the horizontal
lines between ``floor(a_y)`` and ``floor(b_y)``, at the parameters

    t = (line - a_x) / (b_x - a_x)   (vertical),   t = (line - a_y) / (b_y - a_y)   (horizontal).

Sorting every crossing of every segment by (segment, t) gives the walk's order; each
vertical crossing steps the column by ``sign(b_x - a_x)``, each horizontal one the row by
``sign(b_y - a_y)``, and a running sum of the steps from the start cell gives the cells.
Where both lines are crossed at the same ``t`` (the segment passes exactly through a
grid corner) the column steps first, as in Amanatides and Woo's ``tMaxX <= tMaxY`` test
(crossings closer than about ``1e-16 * segments`` of a segment's length count as at the
same ``t``: the sort key is ``4 segment + t``).
Each segment visits ``1 + |floor(b_x) - floor(a_x)| + |floor(b_y) - floor(a_y)|`` cells,
each once, in order from ``a``'s cell to ``b``'s.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class CellWalk:
    """The cells segments visit, segment by segment, each segment's cells in order.

    ``segment[k]`` is the segment the ``k``-th cell belongs to, ``col[k]`` and ``row[k]``
    the cell; ``start[s]`` is the index of segment ``s``'s first cell (its start cell),
    and segment ``s``'s cells run to ``start[s + 1] - 1`` (its end cell).
    """

    segment: np.ndarray  # (M,) int, which segment
    col: np.ndarray  # (M,) int, cell column (x)
    row: np.ndarray  # (M,) int, cell row (y)
    start: np.ndarray  # (S + 1,) int, where each segment's cells begin; last = M

    @property
    def is_last(self) -> np.ndarray:
        """(M,) bool: the cell is its segment's end cell (the one holding ``b``)."""
        last = np.zeros(len(self.col), dtype=bool)
        last[self.start[1:] - 1] = True
        return last


def _crossings(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The grid lines of one axis the segments cross: (segment index, t, count per segment).

    ``a`` and ``b`` are one coordinate (cell units) of the starts and ends, shape (S,).
    """
    first, last = np.floor(a), np.floor(b)
    count = np.abs(last - first).astype(np.int64)
    segment = np.repeat(np.arange(len(a)), count)
    k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)  # 0..count-1
    forward = (b > a)[segment]
    line = np.where(forward, first[segment] + 1 + k, first[segment] - k)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (line - a[segment]) / (b - a)[segment]
    return segment, t, count


def walk_cells(starts: np.ndarray, ends: np.ndarray) -> CellWalk:
    """The cells each segment ``starts[s] -> ends[s]`` passes through (cell units).

    ``starts`` and ``ends`` are (S, 2) arrays of (x, y) in cell units (a map's
    coordinates divided by its resolution); the answer lists every cell each segment
    touches, in order (Amanatides and Woo 1987, vectorised: see the module notes).
    """
    starts = np.asarray(starts, dtype=float).reshape(-1, 2)
    ends = np.asarray(ends, dtype=float).reshape(-1, 2)
    if starts.shape != ends.shape:
        raise ValueError(f"starts {starts.shape} and ends {ends.shape} must match")
    if not (np.isfinite(starts).all() and np.isfinite(ends).all()):
        raise ValueError("segment ends must be finite (cell units)")
    x_seg, x_t, x_count = _crossings(starts[:, 0], ends[:, 0])
    y_seg, y_t, y_count = _crossings(starts[:, 1], ends[:, 1])
    # every crossing in walk order: by segment, then t (0..1), vertical lines first on ties
    # (a stable sort of the key 4 s + t, the vertical crossings listed first)
    seg = np.concatenate([x_seg, y_seg])
    key = 4.0 * seg + np.concatenate([x_t, y_t])
    is_x = np.concatenate([np.ones(len(x_seg), bool), np.zeros(len(y_seg), bool)])
    order = np.argsort(key, kind="stable")
    seg, is_x = seg[order], is_x[order]
    step_col = np.sign(ends[:, 0] - starts[:, 0]).astype(np.int64)
    step_row = np.sign(ends[:, 1] - starts[:, 1]).astype(np.int64)
    # lay out each segment as [start cell, one cell per crossing], segments one after another
    per_segment = 1 + x_count + y_count
    start = np.concatenate([[0], np.cumsum(per_segment)])
    total = int(start[-1])
    first = np.zeros(total, dtype=bool)
    first[start[:-1]] = True
    segment = np.repeat(np.arange(len(starts)), per_segment)
    d_col = np.zeros(total, dtype=np.int64)
    d_row = np.zeros(total, dtype=np.int64)
    d_col[~first] = np.where(is_x, step_col[seg], 0)
    d_row[~first] = np.where(is_x, 0, step_row[seg])
    d_col[first] = np.floor(starts[:, 0]).astype(np.int64)
    d_row[first] = np.floor(starts[:, 1]).astype(np.int64)
    # running sums restarted at each segment's first cell
    col, row = np.cumsum(d_col), np.cumsum(d_row)
    before_col = (col - d_col)[start[:-1]]
    before_row = (row - d_row)[start[:-1]]
    col -= np.repeat(before_col, per_segment)
    row -= np.repeat(before_row, per_segment)
    return CellWalk(segment, col, row, start)
