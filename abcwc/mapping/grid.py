"""Log-odds occupancy grids built from range scans (Thrun, Burgard and Fox, Probabilistic
Robotics, 2005, ch. 9; thesis 3.1.1 and 4.3.8).

Each cell ``m_i`` holds the log odds ``l = log(p / (1 - p))`` that it is occupied, and a
scan ``z_t`` taken from a known pose ``x_t`` adds the inverse sensor model to every cell
it saw (the occupancy grid mapping algorithm, table 9.1, eqn 9.7):

    l_{t,i} = l_{t-1,i} + inverse_sensor_model(m_i, x_t, z_t) - l_0,    l_0 = 0 (p = 0.5).

The inverse sensor model is table 9.2's with an obstacle depth ``alpha`` of one cell:
along each beam the cells before the one holding the return get ``l_free``, the return's
cell gets ``l_occ``, cells beyond are untouched. A beam with no return (``inf`` or beyond
``range_max``) clears the cells up to ``range_max`` and marks none; a beam closer than
``range_min`` (``-inf``) or NaN says nothing. Within one scan each cell is updated once:
a cell that holds a return is occupied even if another beam passed through it (hits win,
as in Cartographer). The log odds are clamped to ``[l_min, l_max]`` so a cell can change
its mind quickly when the world changes (as OctoMap and costmap_2d's voxel layer do).

The grid follows ROS (map_server, nav_msgs/OccupancyGrid): ``origin`` is the map-frame
pose (x, y, yaw) of the corner of cell (0, 0); column ``i`` runs along the grid's x axis
and row ``j`` along its y axis, so ``log_odds[j, i]`` is the cell whose corner is
``(i * resolution, j * resolution)`` in the grid frame and row 0 is the lowest y. (Images
put the largest y on top: :mod:`abcwc.mapping.map_io` flips rows when it writes one.)

The extent is fixed at construction (:meth:`OccupancyGrid.covering` sizes a grid to a
rectangle of the map): scan cells outside it are dropped, the rest of each beam is used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from abcwc.geometry import PoseLike, compose, inverse_transform_points, transform_points
from abcwc.log import RunLog
from abcwc.mapping.raytrace import walk_cells
from abcwc.params import ChairParams, default_params
from abcwc.types import LIDAR_FRAME, LaserScan, Pose2D

FREE = 0
"""Trinary value of a free cell (nav_msgs/OccupancyGrid's 0)."""
OCCUPIED = 100
"""Trinary value of an occupied cell (nav_msgs/OccupancyGrid's 100)."""
UNKNOWN = -1
"""Trinary value of a cell neither free nor occupied (nav_msgs/OccupancyGrid's -1)."""
OCCUPIED_THRESH = 0.65
"""map_server's default: a cell is occupied when p(occupied) > 0.65."""
FREE_THRESH = 0.196
"""map_server's default: a cell is free when p(occupied) < 0.196 (just below 205's 0.19608)."""


def to_log_odds(p: float | np.ndarray) -> float | np.ndarray:
    """``l = log(p / (1 - p))``: a probability as log odds (Probabilistic Robotics eqn 9.5)."""
    l_odds = np.log(p) - np.log1p(-np.asarray(p, dtype=float))
    return l_odds if isinstance(p, np.ndarray) else float(l_odds)


def to_probability(l_odds: float | np.ndarray) -> float | np.ndarray:
    """``p = 1 - 1 / (1 + exp(l))``: log odds back to a probability (eqn 9.6)."""
    p = 1.0 / (1.0 + np.exp(-np.asarray(l_odds, dtype=float)))
    return p if isinstance(l_odds, np.ndarray) else float(p)


@dataclass(frozen=True)
class InverseSensorModel:
    """Log-odds increments for a beam's return cell (``l_occ`` > 0) and the cells it
    crossed (``l_free`` < 0), and the clamp ``[l_min, l_max]`` (all in log odds; the prior
    ``l_0`` is 0). Defaults are OctoMap's: p = 0.7 for a hit and 0.4 for a pass (l = 0.85,
    -0.4), clamped to p in [0.12, 0.97]. With them a cell reads free (p < 0.196) after four
    passes and occupied (p > 0.65) after one return."""

    l_occ: float = 0.85
    l_free: float = -0.4
    l_min: float = -2.0
    l_max: float = 3.5

    def __post_init__(self) -> None:
        values = (self.l_occ, self.l_free, self.l_min, self.l_max)
        if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in values):
            raise ValueError(f"inverse sensor model values must be finite numbers, got {self}")
        if not (self.l_min < 0 < self.l_max and self.l_free < 0 < self.l_occ):
            raise ValueError(f"need l_min < 0 < l_max and l_free < 0 < l_occ (log odds), "
                             f"got {self}")


class GridGeometry:
    """A fixed-extent grid of cells: ``height`` rows by ``width`` columns of ``resolution``
    m, the corner of cell (0, 0) at map pose ``origin`` (x m, y m, yaw rad), as map_server
    and costmap_2d lay them out. Arrays over it are indexed ``[row, col]`` (row = y).
    Occupancy grids and costmaps are grids of this shape.
    """

    def __init__(self, resolution: float, width: int, height: int,
                 origin: PoseLike = (0.0, 0.0, 0.0)):
        if not (isinstance(resolution, (int, float)) and math.isfinite(resolution)
                and resolution > 0):
            raise ValueError(f"resolution must be a finite number > 0 m/cell, got {resolution!r}")
        for name, value in (("width", width), ("height", height)):
            if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
                raise ValueError(f"{name} must be a whole number of cells >= 1, got {value!r}")
        values = _pose_array(origin)
        if values.shape != (3,) or not np.isfinite(values).all():
            raise ValueError(f"origin must be a finite (x m, y m, yaw rad), got {origin!r}")
        pose = Pose2D(*map(float, values))
        self.resolution = float(resolution)
        self.width, self.height = int(width), int(height)
        self.origin = pose

    @staticmethod
    def extent(xmin: float, ymin: float, xmax: float, ymax: float, resolution: float,
               margin: float = 0.0) -> tuple[int, int, tuple[float, float, float]]:
        """``(width, height, origin)`` of an axis-aligned grid (yaw 0) over the map rectangle
        ``[xmin, xmax] x [ymin, ymax]`` grown by ``margin`` m on every side (all m)."""
        if not (xmax > xmin and ymax > ymin):
            raise ValueError(f"need xmin < xmax and ymin < ymax, got "
                             f"({xmin}, {ymin}) .. ({xmax}, {ymax})")
        x0, y0 = xmin - margin, ymin - margin
        width = math.ceil((xmax + margin - x0) / resolution - 1e-9)
        height = math.ceil((ymax + margin - y0) / resolution - 1e-9)
        return max(width, 1), max(height, 1), (x0, y0, 0.0)

    # ------------------------------------------------------------ geometry
    @property
    def shape(self) -> tuple[int, int]:
        """``(height, width)``: rows, columns."""
        return self.height, self.width

    def to_cell_units(self, points: np.ndarray) -> np.ndarray:
        """Map-frame points ``(..., 2)`` (m) in grid units: their x, y in the grid's frame
        (from ``origin``) divided by the resolution, so their cell is ``(col, row) = floor``
        of the answer."""
        points = np.asarray(points, float)
        if self.origin.theta == 0.0:  # axis-aligned (as most are): a shift, the same numbers
            return (points - (self.origin.x, self.origin.y)) / self.resolution
        return inverse_transform_points(self.origin, points) / self.resolution

    def world_to_cell(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Rows and columns (int arrays of shape ``points.shape[:-1]``) of the cells holding
        map points ``(..., 2)`` (m); cells outside the grid too (see :meth:`contains`)."""
        units = np.floor(self.to_cell_units(points)).astype(np.int64)
        return units[..., 1], units[..., 0]

    def xy_to_cell(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`world_to_cell` for coordinates held in two arrays of one shape (m), without
        stacking them first (the same numbers; for hot loops over many points)."""
        if self.origin.theta != 0.0:
            return self.world_to_cell(np.stack([x, y], axis=-1))
        cols = np.floor((x - self.origin.x) / self.resolution).astype(np.int64)
        rows = np.floor((y - self.origin.y) / self.resolution).astype(np.int64)
        return rows, cols

    def cell_to_world(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Map coordinates ``(..., 2)`` (m) of the centres of cells ``(rows, cols)``."""
        local = np.stack([np.asarray(cols) + 0.5, np.asarray(rows) + 0.5], axis=-1)
        return transform_points(self.origin, local * self.resolution)

    def contains(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Whether cells ``(rows, cols)`` lie inside the grid (bool array)."""
        rows, cols = np.asarray(rows), np.asarray(cols)
        return (rows >= 0) & (rows < self.height) & (cols >= 0) & (cols < self.width)

    # ------------------------------------------------------------ scans
    def scan_cells(self, scan: LaserScan,
                   sensor_pose: PoseLike) -> tuple[np.ndarray, np.ndarray]:
        """Flat indices (``row * width + col``) of the grid cells one scan's beams passed
        through and of the cells holding its returns (either may repeat a cell, and a cell
        may be in both: the update counts it as a return).

        ``sensor_pose`` is the scanner's pose in the map frame (the pose of the scan's
        ``frame_id``, e.g. ``compose(base_pose, mount)``). Every beam is traced at once
        (:func:`abcwc.mapping.raytrace.walk_cells`); cells outside the grid are dropped.
        """
        hit = scan.hits()
        traced = hit | scan.misses()  # a miss is traced to range_max and marks nothing
        ends = transform_points(sensor_pose, scan.points(with_misses=True))
        start = self.to_cell_units(transform_points(sensor_pose, np.zeros(2)))
        walk = walk_cells(np.broadcast_to(start, ends.shape), self.to_cell_units(ends))
        returned = hit[traced][walk.segment] & walk.is_last
        inside = self.contains(walk.row, walk.col)
        flat = walk.row * self.width + walk.col
        return flat[~returned & inside], flat[returned & inside]

class OccupancyGrid(GridGeometry):
    """A fixed-extent log-odds occupancy grid (see :class:`GridGeometry` for its cells).

    ``log_odds`` is the (height, width) float array, indexed ``[row, col]`` (row = y).
    """

    def __init__(self, resolution: float, width: int, height: int,
                 origin: PoseLike = (0.0, 0.0, 0.0),
                 model: InverseSensorModel | None = None):
        super().__init__(resolution, width, height, origin)
        self.model = model or InverseSensorModel()
        self.log_odds = np.zeros((self.height, self.width))

    @classmethod
    def covering(cls, xmin: float, ymin: float, xmax: float, ymax: float, resolution: float,
                 margin: float = 0.0, model: InverseSensorModel | None = None) -> OccupancyGrid:
        """An axis-aligned grid (yaw 0) over the map rectangle ``[xmin, xmax] x [ymin, ymax]``
        grown by ``margin`` m on every side (all m)."""
        width, height, origin = cls.extent(xmin, ymin, xmax, ymax, resolution, margin)
        return cls(resolution, width, height, origin, model)

    def integrate(self, scan: LaserScan, sensor_pose: PoseLike) -> None:
        """Add one scan taken from ``sensor_pose`` (the scanner's map pose) to the grid:
        ``l += l_free`` on the cells it saw free, ``l += l_occ`` on its returns' cells, each
        cell once and a return's cell only as a return, then clamp (Probabilistic Robotics
        table 9.1 with the model in the module notes)."""
        passed, returned = self.scan_cells(scan, sensor_pose)
        flat = self.log_odds.reshape(-1)
        m = self.model
        # a cell listed twice is read twice before either write, so it moves once; the
        # returns' cells are read before the pass update and written after it, so a
        # cell both passed and returned moves by l_occ alone
        before = flat[returned]
        flat[passed] = np.maximum(flat[passed] + m.l_free, m.l_min)
        flat[returned] = np.minimum(before + m.l_occ, m.l_max)
        self.log_odds = flat.reshape(self.shape)  # the same array unless it was a copy

    def integrate_from_base(self, scan: LaserScan, base_pose: PoseLike,
                            mount: PoseLike) -> None:
        """:meth:`integrate` a scan from a scanner at ``mount`` (x, y, yaw in base_link)
        on a chair at ``base_pose`` (map frame)."""
        self.integrate(scan, compose(_pose_array(base_pose), _pose_array(mount)))

    # ------------------------------------------------------------ views
    def probability(self) -> np.ndarray:
        """p(occupied) of every cell, (height, width)."""
        return to_probability(self.log_odds)  # type: ignore[return-value]

    def trinary(self, occupied_thresh: float = OCCUPIED_THRESH,
                free_thresh: float = FREE_THRESH) -> np.ndarray:
        """Every cell as :data:`OCCUPIED` (p > ``occupied_thresh``), :data:`FREE`
        (p < ``free_thresh``) or :data:`UNKNOWN` (int8, (height, width)): the values of a
        nav_msgs/OccupancyGrid, map_server's trinary rule."""
        if not 0.0 <= free_thresh <= occupied_thresh <= 1.0:
            raise ValueError(f"need 0 <= free_thresh <= occupied_thresh <= 1, got "
                             f"{free_thresh}, {occupied_thresh}")
        p = self.probability()
        out = np.full(self.shape, UNKNOWN, dtype=np.int8)
        out[p < free_thresh] = FREE
        out[p > occupied_thresh] = OCCUPIED
        return out

    def occupied(self, occupied_thresh: float = OCCUPIED_THRESH) -> np.ndarray:
        """(height, width) bool: the cells with p(occupied) > ``occupied_thresh``."""
        return self.probability() > occupied_thresh

    def known(self) -> np.ndarray:
        """(height, width) bool: the cells some scan has updated (log odds not 0)."""
        return self.log_odds != 0.0

    @classmethod
    def from_trinary(cls, cells: np.ndarray, resolution: float,
                     origin: PoseLike = (0.0, 0.0, 0.0),
                     model: InverseSensorModel | None = None) -> OccupancyGrid:
        """A grid whose occupied cells sit at ``l_max``, free ones at ``l_min`` and unknown
        ones at 0, from trinary ``cells`` ((height, width) of OCCUPIED, FREE, UNKNOWN; row 0
        the lowest y): a loaded map, ready to be updated or thresholded again."""
        cells = np.asarray(cells)
        if cells.ndim != 2 or not np.isin(cells, (OCCUPIED, FREE, UNKNOWN)).all():
            raise ValueError(f"trinary cells must be a 2-D array of {OCCUPIED}, {FREE}, "
                             f"{UNKNOWN}")
        grid = cls(resolution, cells.shape[1], cells.shape[0], origin, model)
        m = grid.model
        if not to_probability(m.l_min) < FREE_THRESH < OCCUPIED_THRESH < to_probability(m.l_max):
            raise ValueError(f"the model's clamp [{m.l_min}, {m.l_max}] (log odds) must reach "
                             f"past the default thresholds p = {FREE_THRESH}, {OCCUPIED_THRESH}")
        grid.log_odds[cells == OCCUPIED] = grid.model.l_max
        grid.log_odds[cells == FREE] = grid.model.l_min
        return grid


def _pose_array(pose: PoseLike) -> np.ndarray:
    """A pose as a (3,) array (from a Pose2D or a sequence)."""
    if isinstance(pose, Pose2D):
        return pose.as_array()
    return np.asarray(pose, dtype=float)


def scan_rows(log: RunLog, frame_id: str = LIDAR_FRAME) -> np.ndarray:
    """For each scan of ``frame_id`` in ``log``, the row of the log's channels nearest its
    stamp (the row it was taken in, for the simulator's logs)."""
    scans = log.scans.get(frame_id)
    if scans is None:
        raise ValueError(f"the log has no scans of {frame_id!r}; it has {sorted(log.scans)}")
    t = log.t
    if len(t) < 2:
        return np.zeros(len(scans.stamps), dtype=np.int64)
    right = np.clip(np.searchsorted(t, scans.stamps), 1, len(t) - 1)
    left = right - 1
    return np.where(np.abs(t[left] - scans.stamps) <= np.abs(t[right] - scans.stamps),
                    left, right)


def integrate_log(grid: OccupancyGrid, log: RunLog, frame_id: str = LIDAR_FRAME,
                  poses: np.ndarray | None = None,
                  params: ChairParams | None = None) -> int:
    """Add every scan of ``frame_id`` in ``log`` to ``grid``, each from the chair's pose in
    the row nearest its stamp: ``poses`` ((N, 3) map poses, one per log row, e.g. an
    estimate) or the log's ground truth ``pose``; the scanner's mount comes from
    ``params`` (the chair's by default). Returns how many scans were added."""
    p = params or default_params()
    mount = p.sensors[frame_id].mount  # type: ignore[union-attr]
    rows = scan_rows(log, frame_id)
    poses = np.asarray(log.pose if poses is None else poses, dtype=float)
    if poses.shape != (len(log), 3):
        raise ValueError(f"poses must be (N, 3), one per log row ({len(log)}), "
                         f"got {poses.shape}")
    base = poses[rows]
    if not np.isfinite(base).all():
        raise ValueError("a scan's pose is not finite (a real chair's log has no ground "
                         "truth: give poses, e.g. an estimate)")
    scanner = compose(base, np.broadcast_to(np.asarray(mount, dtype=float), base.shape))
    scans = log.scans[frame_id]
    for k in range(len(rows)):  # one scan at a time: each is one whole-array update
        grid.integrate(scans.scan(k), scanner[k])
    return len(rows)
