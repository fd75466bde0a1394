"""Correlative scan matching: search a window of poses exhaustively, coarse to fine.

Olson, "Real-time correlative scan matching" (ICRA 2009). Where ICP follows the local
gradient from its initial guess (and lands in the wrong place when the guess is off by
more than its pairing distance), this matcher scores *every* pose of a window on a
rasterised likelihood of the reference points and takes the best:

* **The lookup table.** Each cell of a grid over the reference points holds the
  log-likelihood of a point there, ``-d^2 / (2 sigma^2)`` for the distance ``d`` to the
  nearest reference point (one Euclidean distance transform), floored at ``d = 3 sigma``
  so a point in empty space costs a fixed penalty.
* **Scoring.** A pose's score is the sum over the scan's points of the table at the
  point's cell. For each angle the points are rotated once and every translation of the
  window is scored by array indexing (no loop over translations).
* **Two resolutions.** A low-resolution table holds, in each cell, the largest value of
  the ``factor x factor`` fine cells a coarse translation step could move a point over
  (a maximum filter): a coarse pose's score is an upper bound on the scores of all the
  fine poses under it. Coarse poses are expanded best first, and a coarse pose whose
  bound is below the best fine score found so far is skipped: the answer is exactly the
  brute-force one (branch and bound; a test holds them equal).
* **Covariance** (Olson's eqn 15): over the fine poses around the best one, weighted by
  their likelihood ``p = exp(score - best)``:
  ``Sigma = K / s - u u^T / s^2``, ``K = sum p x x^T``, ``u = sum p x``, ``s = sum p``.
  A corridor scores alike all along itself, and the covariance says so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from abcwc.geometry import wrap_angle
from abcwc.mapping.grid import GridGeometry


@dataclass(frozen=True)
class CorrelativeResult:
    """The best ``pose`` (x, y, theta of the scan frame in the reference frame; m, rad),
    its ``covariance`` (3 x 3), its ``score`` (summed log-likelihood), and how many poses
    were scored at the fine resolution (``evaluated``) out of the window's (``window``)."""

    pose: np.ndarray
    covariance: np.ndarray
    score: float
    evaluated: int
    window: int


class LikelihoodField(GridGeometry):
    """The log-likelihood lookup table of reference points ``(M, 2)`` (m) on a grid of
    ``resolution`` m, reaching ``margin`` m beyond them, for point noise ``sigma`` (m)."""

    def __init__(self, points: np.ndarray, resolution: float = 0.03, sigma: float = 0.05,
                 margin: float = 2.0):
        points = np.asarray(points, dtype=float)
        if points.ndim != 2 or points.shape[1] != 2 or len(points) < 1:
            raise ValueError(f"reference points must be a non-empty (M, 2) array, "
                             f"got shape {points.shape}")
        for name, value in (("resolution", resolution), ("sigma", sigma), ("margin", margin)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a finite number > 0 m, got {value!r}")
        corner = points.min(axis=0) - margin
        size = np.ceil((points.max(axis=0) + margin - corner) / resolution).astype(int) + 1
        super().__init__(resolution, int(size[0]), int(size[1]), (corner[0], corner[1], 0.0))
        self.sigma = float(sigma)
        occupied = np.zeros(self.shape, dtype=bool)
        occupied[self.world_to_cell(points)] = True
        distance = ndimage.distance_transform_edt(~occupied) * self.resolution
        self.floor = -0.5 * 9.0  # d = 3 sigma
        self.table = np.maximum(-0.5 * (distance / sigma) ** 2, self.floor)

    def bound(self, factor: int) -> np.ndarray:
        """The low-resolution table for coarse steps of ``factor`` cells: cell ``c`` holds
        the largest fine value in cells ``c .. c + factor - 1`` (both axes)."""
        return ndimage.maximum_filter(self.table, size=factor, origin=-(factor // 2),
                                      mode="constant", cval=self.floor)

    def scores(self, table: np.ndarray, cells: np.ndarray, shifts: np.ndarray) -> np.ndarray:
        """Summed table values of point ``cells`` (P, 2: col, row) moved by each of
        ``shifts`` (T, 2 cells): (T,). Points off the table count as the floor."""
        moved = cells[None, :, :] + shifts[:, None, :]
        cols, rows = moved[..., 0], moved[..., 1]
        values = np.where(self.contains(rows, cols),
                          table[np.clip(rows, 0, self.height - 1),
                                np.clip(cols, 0, self.width - 1)], self.floor)
        return values.sum(axis=1)


def correlative_match(points: np.ndarray, field: LikelihoodField,
                      initial: tuple[float, float, float] | np.ndarray = (0.0, 0.0, 0.0), *,
                      window_xy: float = 0.5, window_theta: float = math.radians(20),
                      angle_step: float | None = None, factor: int = 8,
                      covariance_cells: int = 4) -> CorrelativeResult:
    """The pose in ``[initial +- window]`` that lays ``points`` ((N, 2), scan frame, m)
    best on ``field``; see the module notes. ``angle_step`` (rad) defaults to the angle
    that moves the farthest point by one cell; ``factor`` is the coarse step in fine
    cells (1: brute force at the fine resolution)."""
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 2 or len(points) < 3:
        raise ValueError(f"points must be an (N, 2) array of at least 3 points, "
                         f"got shape {points.shape}")
    initial = np.asarray(initial, dtype=float).reshape(3)
    if not np.isfinite(initial).all():
        raise ValueError(f"initial must be a finite (x, y, theta), got {initial!r}")
    if not (window_xy > 0 and window_theta >= 0):
        raise ValueError(f"window_xy must be > 0 m and window_theta >= 0 rad, "
                         f"got {window_xy!r}, {window_theta!r}")
    if not (isinstance(factor, int) and factor >= 1):
        raise ValueError(f"factor must be a whole number of cells >= 1, got {factor!r}")
    res = field.resolution
    reach = float(np.max(np.hypot(points[:, 0], points[:, 1])))
    step = angle_step if angle_step is not None else res / max(reach, res)
    angles = initial[2] + step * np.arange(-math.floor(window_theta / step),
                                           math.floor(window_theta / step) + 1)
    half = math.ceil(window_xy / res)  # fine cells each way
    coarse_offsets = np.arange(-half, half + 1, factor)
    coarse = np.stack(np.meshgrid(coarse_offsets, coarse_offsets, indexing="xy"),
                      axis=-1).reshape(-1, 2)
    bound = field.bound(factor) if factor > 1 else field.table
    base = field.to_cell_units(initial[:2])  # the initial translation, in cells

    rotated = []
    for theta in angles:
        c, s = math.cos(theta), math.sin(theta)
        xy = points @ np.array([[c, s], [-s, c]])  # rotate by theta
        rotated.append(np.floor(xy / res + base).astype(np.int64))
    # pad both tables so that every point of every pose falls on them: no bounds checks
    # in the inner loop (a point off the field scores the floor, as the padding does)
    low = np.min([cells.min(axis=0) for cells in rotated], axis=0) - half - factor
    high = np.max([cells.max(axis=0) for cells in rotated], axis=0) + half + factor
    pad_col = (max(0, -int(low[0])), max(0, int(high[0]) - field.width + 1))
    pad_row = (max(0, -int(low[1])), max(0, int(high[1]) - field.height + 1))
    fine_table = np.pad(field.table, (pad_row, pad_col), constant_values=field.floor)
    bound_table = np.pad(bound, (pad_row, pad_col), constant_values=field.floor)
    offset = np.array([pad_col[0], pad_row[0]])
    rotated = [cells + offset for cells in rotated]
    # the padded tables as flat arrays, cells and shifts as flat indices into them (row *
    # width + col): the same values summed in the same order, gathered six times faster
    width = fine_table.shape[1]
    fine_flat, bound_flat = fine_table.ravel(), bound_table.ravel()
    rotated_flat = [cells[:, 1] * width + cells[:, 0] for cells in rotated]

    def scores(table: np.ndarray, cells: np.ndarray, shifts: np.ndarray) -> np.ndarray:
        moved = cells[None, :] + (shifts[:, 1] * width + shifts[:, 0])[:, None]
        return np.take(table, moved).sum(axis=1)

    bounds = np.array([scores(bound_flat, cells, coarse) for cells in rotated_flat])

    best_score, best = -math.inf, (0, np.zeros(2, dtype=np.int64))
    evaluated = 0
    fine = np.stack(np.meshgrid(np.arange(factor), np.arange(factor), indexing="xy"),
                    axis=-1).reshape(-1, 2)
    for flat in np.argsort(bounds, axis=None)[::-1]:
        a, t = np.unravel_index(flat, bounds.shape)
        if bounds[a, t] <= best_score:
            break  # every coarse pose left is bounded below the best fine one
        shifts = coarse[t] + fine
        shifts = shifts[(np.abs(shifts) <= half).all(axis=1)]
        fine_scores = scores(fine_flat, rotated_flat[a], shifts)
        evaluated += len(shifts)
        k = int(np.argmax(fine_scores))
        if fine_scores[k] > best_score:
            best_score, best = float(fine_scores[k]), (int(a), shifts[k])
    rotated = [cells - offset for cells in rotated]
    a, shift = best
    pose = np.array([initial[0] + shift[0] * res, initial[1] + shift[1] * res,
                     wrap_angle(angles[a])])
    covariance = _covariance(field, rotated, angles, a, shift, best_score, res,
                             covariance_cells, initial)
    return CorrelativeResult(pose, covariance, best_score, evaluated,
                             len(angles) * (2 * half + 1) ** 2)


def _covariance(field: LikelihoodField, rotated: list[np.ndarray], angles: np.ndarray,
                a: int, shift: np.ndarray, best: float, res: float, cells: int,
                initial: np.ndarray) -> np.ndarray:
    """Olson's eqn 15 over the fine poses within ``cells`` cells and angle steps of the
    best, each weighted by ``exp(score - best)`` (``best`` the highest score among them:
    the neighbourhood reaches past the window's edge, where a pose may score higher than
    the window's best), taken about the best pose so the sums stay well scaled."""
    offsets = np.arange(-cells, cells + 1)
    shifts = shift + np.stack(np.meshgrid(offsets, offsets, indexing="xy"),
                              axis=-1).reshape(-1, 2)
    poses, all_scores = [], []
    for k in range(max(0, a - cells), min(len(angles), a + cells + 1)):
        all_scores.append(field.scores(field.table, rotated[k], shifts))
        poses.append(np.column_stack([(shifts[:, 0] - shift[0]) * res,
                                      (shifts[:, 1] - shift[1]) * res,
                                      np.full(len(shifts), angles[k] - angles[a])]))
    scores = np.concatenate(all_scores)
    x, p = np.vstack(poses), np.exp(scores - max(best, float(scores.max())))
    s = p.sum()
    u = p @ x
    second = (x * p[:, None]).T @ x
    covariance = second / s - np.outer(u, u) / s**2
    # a pose grid cannot resolve less than its own spacing: floor at a uniform cell
    step = angles[1] - angles[0] if len(angles) > 1 else 0.0
    return covariance + np.diag([res**2 / 12, res**2 / 12, step**2 / 12])
