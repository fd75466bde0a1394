"""Costmaps as ROS costmap_2d builds them: static, obstacle and inflation layers.

A costmap is a grid (:class:`~abcwc.mapping.grid.GridGeometry`) of one byte per cell
with costmap_2d's meaning (``costmap_2d/cost_values.h``):

* ``FREE_SPACE`` 0: the chair's centre may be here;
* 1..252: near an obstacle, the nearer the costlier (the inflation layer);
* ``INSCRIBED`` 253: the centre here puts the footprint's inscribed circle on an obstacle;
* ``LETHAL`` 254: an obstacle in the cell itself;
* ``NO_INFORMATION`` 255: never seen.

Layers write into the master grid in order, as costmap_2d's ``LayeredCostmap`` does:

* :meth:`Costmap.add_static` (``StaticLayer``): a map's occupied cells lethal, free cells
  free, unknown cells unknown (``track_unknown_space``) or free;
* :meth:`Costmap.add_scan` (``ObstacleLayer``): a range scan marks the cells of its returns
  within ``obstacle_range`` lethal and clears the cells its beams crossed within
  ``raytrace_range``; every beam traced at once
  (:func:`abcwc.mapping.raytrace.walk_cells`);
* :meth:`Costmap.inflate` (``InflationLayer``): every cell within ``inflation_radius`` of a
  lethal cell gets :func:`inflation_cost` of its distance, found for all cells at once with
  a Euclidean distance transform (:func:`scipy.ndimage.distance_transform_edt`) instead of
  costmap_2d's cell-by-cell wavefront.

A local costmap is a rolling window (:meth:`Costmap.rolling_window`): a fixed-size grid
re-centred on the chair, its origin snapped to the resolution as costmap_2d's
``updateOrigin`` does. :func:`footprint_cost` is the highest cost under the chair's
footprint at a pose (costmap_2d's footprint check).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from abcwc.geometry import PoseLike, position_of, transform_points
from abcwc.mapping.grid import FREE, OCCUPIED, UNKNOWN, GridGeometry
from abcwc.mapping.raytrace import walk_cells
from abcwc.mapping.truth import rasterise_walls
from abcwc.params import ChairParams
from abcwc.types import LaserScan

FREE_SPACE = 0
INSCRIBED = 253
LETHAL = 254
NO_INFORMATION = 255
COST_SCALING_FACTOR = 10.0
"""1/m: costmap_2d's default ``cost_scaling_factor`` (the thesis's A.17 does not set it)."""


# --------------------------------------------------------------------- the footprint
@dataclass(frozen=True)
class Footprint:
    """The chair's outline in base_link (x forward, y left; m), and its two radii.

    ``inscribed_radius`` is the largest circle about base_link inside the polygon,
    ``circumscribed_radius`` the smallest about base_link that holds it (costmap_2d's
    ``calculateMinAndMaxDistances``).
    """

    polygon: np.ndarray  # (N, 2) corners, in order

    @property
    def inscribed_radius(self) -> float:
        """m: the shortest distance from base_link to an edge of the polygon."""
        a = self.polygon
        b = np.roll(a, -1, axis=0)
        edge = b - a
        t = np.clip(np.einsum("ij,ij->i", -a, edge) / np.einsum("ij,ij->i", edge, edge), 0, 1)
        closest = a + t[:, None] * edge
        return float(np.min(np.hypot(closest[:, 0], closest[:, 1])))

    @property
    def circumscribed_radius(self) -> float:
        """m: the farthest corner from base_link."""
        return float(np.max(np.hypot(self.polygon[:, 0], self.polygon[:, 1])))


def chair_footprint(params: ChairParams, padding: float = 0.0) -> Footprint:
    """The chair's rectangle (``length`` x ``width``, base_link ``axle_to_rear`` from the
    back; chair.toml ``[body]``) grown by ``padding`` m on every side (costmap_2d's
    ``footprint_padding``)."""
    if not (math.isfinite(padding) and padding >= 0):
        raise ValueError(f"padding must be a finite number >= 0 m, got {padding!r}")
    back, front = -params.axle_to_rear - padding, params.length - params.axle_to_rear + padding
    side = params.width / 2 + padding
    return Footprint(np.array([[front, side], [back, side], [back, -side], [front, -side]]))


# --------------------------------------------------------------------- inflation
def inflation_cost(distance: np.ndarray, inscribed_radius: float,
                   cost_scaling_factor: float = COST_SCALING_FACTOR) -> np.ndarray:
    """costmap_2d's ``InflationLayer::computeCost`` for distances (m) to the nearest lethal
    cell: ``LETHAL`` at 0, ``INSCRIBED`` within the inscribed radius, else
    ``(unsigned char)(252 exp(-k (d - r_inscribed)))`` (truncated, not rounded)."""
    d = np.asarray(distance, dtype=float)
    factor = np.exp(-cost_scaling_factor * (d - inscribed_radius))
    cost = np.floor((INSCRIBED - 1) * factor)
    cost = np.where(d <= inscribed_radius, INSCRIBED, cost)
    return np.where(d == 0, LETHAL, cost).astype(np.uint8)


class Costmap(GridGeometry):
    """A costmap_2d-style master grid: ``cost`` is (height, width) uint8, ``[row, col]``.

    Every cell starts at ``default`` (``NO_INFORMATION`` when unknown space is tracked,
    as costmap_2d's ``track_unknown_space``; else ``FREE_SPACE``).
    """

    def __init__(self, resolution: float, width: int, height: int,
                 origin: PoseLike = (0.0, 0.0, 0.0), default: int = NO_INFORMATION):
        super().__init__(resolution, width, height, origin)
        if default not in (FREE_SPACE, NO_INFORMATION):
            raise ValueError(f"default must be FREE_SPACE (0) or NO_INFORMATION (255), "
                             f"got {default!r}")
        self.default = default
        self.cost = np.full((self.height, self.width), default, dtype=np.uint8)

    @classmethod
    def like(cls, grid: GridGeometry, default: int = NO_INFORMATION) -> Costmap:
        """A costmap over the same cells as ``grid`` (a map, another costmap)."""
        return cls(grid.resolution, grid.width, grid.height, grid.origin, default)

    @classmethod
    def from_walls(cls, walls: np.ndarray, resolution: float, margin: float = 0.5) -> Costmap:
        """A costmap over a known world's wall segments ((N, 4): x1 y1 x2 y2, m) grown by
        ``margin`` m: the cells a wall passes through lethal, every other cell free (the
        static layer of a map drawn from the world instead of built by mapping)."""
        walls = np.asarray(walls, dtype=float)
        if walls.ndim != 2 or walls.shape[1] != 4 or not len(walls):
            raise ValueError(f"walls must be a non-empty (N, 4) array of x1 y1 x2 y2 (m), "
                             f"got shape {walls.shape}")
        xs, ys = walls[:, [0, 2]], walls[:, [1, 3]]
        width, height, origin = cls.extent(xs.min(), ys.min(), xs.max(), ys.max(), resolution,
                                           margin)
        costmap = cls(resolution, width, height, origin, default=FREE_SPACE)
        costmap.cost[rasterise_walls(walls, costmap)] = LETHAL
        return costmap

    @classmethod
    def rolling_window(cls, centre: PoseLike, size: float, resolution: float,
                       default: int = NO_INFORMATION, lattice: GridGeometry | None = None
                       ) -> Costmap:
        """A ``size`` x ``size`` m local costmap (axis-aligned) centred on ``centre``'s
        position, its origin snapped down onto a lattice of cells (costmap_2d's rolling
        window: cells keep their place in the map as the window moves): multiples of the
        resolution, or, given a map's ``lattice`` (axis-aligned, the same resolution),
        that map's own cells. A window whose cells straddle the map's would take each
        of its cells from one of two map cells, and a wall drawn from the map would lie
        half a cell from the same wall drawn from a scan: door jambs a cell thicker, a
        door a cell narrower to the local planner than to the global one."""
        x, y = position_of(centre, "centre")
        if not (math.isfinite(size) and size > 0):
            raise ValueError(f"size must be a finite number > 0 m, got {size!r}")
        x_anchor = y_anchor = 0.0
        if lattice is not None:
            if window_lattice(lattice, resolution) is None:
                raise ValueError(f"the lattice must be axis-aligned with the window's "
                                 f"resolution {resolution:g} m, got yaw "
                                 f"{lattice.origin.theta:g} rad and {lattice.resolution:g} m")
            # the map's offset from the multiples of the resolution (none: as without it)
            x_anchor, y_anchor = (
                0.0 if abs(offset) < 1e-9 else offset
                for offset in (value - round(value / resolution) * resolution
                               for value in (lattice.origin.x, lattice.origin.y)))
        cells = max(1, round(size / resolution))
        x0 = x_anchor + math.floor((x - size / 2 - x_anchor) / resolution) * resolution
        y0 = y_anchor + math.floor((y - size / 2 - y_anchor) / resolution) * resolution
        return cls(resolution, cells, cells, (x0, y0, 0.0), default)

    # ------------------------------------------------------------ layers
    def add_static(self, cells: np.ndarray, track_unknown: bool = True) -> None:
        """Write a trinary map (``OCCUPIED``/``FREE``/``UNKNOWN`` on this costmap's cells,
        e.g. ``OccupancyGrid.trinary()`` or a map file's) as costmap_2d's static layer:
        occupied -> ``LETHAL``, free -> ``FREE_SPACE``, unknown -> ``NO_INFORMATION`` (or
        free when ``track_unknown`` is False)."""
        cells = np.asarray(cells)
        if cells.shape != self.shape:
            raise ValueError(f"the map is {cells.shape} cells, the costmap {self.shape}")
        if not np.isin(cells, (OCCUPIED, FREE, UNKNOWN)).all():
            raise ValueError(f"a static map holds only {OCCUPIED}, {FREE} and {UNKNOWN}")
        unknown = NO_INFORMATION if track_unknown else FREE_SPACE
        layer = np.select([cells == OCCUPIED, cells == FREE], [LETHAL, FREE_SPACE], unknown)
        self._update_with_max(layer.astype(np.uint8))

    def add_scan(self, scan: LaserScan, sensor_pose: PoseLike, obstacle_range: float,
                 raytrace_range: float) -> None:
        """costmap_2d's obstacle layer for one scan from ``sensor_pose`` (the scanner's pose
        in this costmap's frame): cells its beams crossed within ``raytrace_range`` (m)
        become free, then the cells of its returns within ``obstacle_range`` (m) lethal."""
        for name, value in (("obstacle_range", obstacle_range),
                            ("raytrace_range", raytrace_range)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a finite number > 0 m, got {value!r}")
        origin = self.to_cell_units(transform_points(sensor_pose, np.zeros(2)))
        # a beam that saw nothing within the limit is clear to the limit
        ends = transform_points(sensor_pose, scan.points(raytrace_range, with_misses=True))
        walk = walk_cells(np.broadcast_to(origin, ends.shape), self.to_cell_units(ends))
        keep = ~walk.is_last & self.contains(walk.row, walk.col)  # the end cell: not cleared
        self.cost[walk.row[keep], walk.col[keep]] = FREE_SPACE
        hits = transform_points(sensor_pose, scan.points(obstacle_range))
        rows, cols = self.world_to_cell(hits)
        inside = self.contains(rows, cols)
        self.cost[rows[inside], cols[inside]] = LETHAL

    def inflate(self, inscribed_radius: float, inflation_radius: float,
                cost_scaling_factor: float = COST_SCALING_FACTOR,
                inflate_unknown: bool = False, keep_out_radius: float = 0.0) -> None:
        """costmap_2d's inflation layer: every cell within ``inflation_radius`` (m) of a
        lethal cell takes the higher of its cost and :func:`inflation_cost` of its
        distance (cell centre to cell centre). An unknown cell takes the inflation cost
        only from ``INSCRIBED`` up (any cost above free with ``inflate_unknown``), as
        costmap_2d's ``updateCosts`` does.

        ``keep_out_radius`` (m, at most ``inflation_radius``) widens the impassable
        band: cells nearer than it to a lethal cell are ``INSCRIBED`` too, whatever the
        inscribed radius. A chair whose local planner checks more than its inscribed
        circle (:meth:`~abcwc.navigation.dwa.DwaPlanner.passing_radius`) has the global
        planner keep its centre as far out, so that the two agree on which gaps are
        passable; the costs beyond it still fall off from the inscribed radius."""
        if not (math.isfinite(inscribed_radius) and inscribed_radius >= 0):
            raise ValueError(f"inscribed_radius must be a finite number >= 0 m, "
                             f"got {inscribed_radius!r}")
        if not (math.isfinite(inflation_radius) and inflation_radius >= inscribed_radius):
            raise ValueError(f"inflation_radius {inflation_radius!r} m must be finite and at "
                             f"least the inscribed radius {inscribed_radius:g} m")
        if not (math.isfinite(keep_out_radius) and 0 <= keep_out_radius <= inflation_radius):
            raise ValueError(f"keep_out_radius must be a finite number from 0 to the "
                             f"inflation radius {inflation_radius:g} m, got {keep_out_radius!r}")
        lethal = self.cost == LETHAL
        if not lethal.any():
            return
        cells = ndimage.distance_transform_edt(~lethal)  # in cells, to the nearest lethal
        reach = math.ceil(inflation_radius / self.resolution)  # costmap_2d's cellDistance
        near = cells <= reach
        cost = np.zeros_like(self.cost)
        cost[near] = inflation_cost(cells[near] * self.resolution, inscribed_radius,
                                    cost_scaling_factor)
        kept_out = near & (cells * self.resolution < keep_out_radius) & ~lethal
        cost[kept_out] = np.maximum(cost[kept_out], INSCRIBED)
        unknown = self.cost == NO_INFORMATION
        take = cost > FREE_SPACE if inflate_unknown else cost >= INSCRIBED
        self.cost = np.where(unknown, np.where(take, cost, self.cost),
                             np.maximum(self.cost, cost))

    def _update_with_max(self, layer: np.ndarray) -> None:
        """costmap_2d's ``updateWithMax``: unknown in the layer changes nothing; unknown in
        the master takes the layer's value; otherwise the higher cost wins."""
        master = self.cost
        self.cost = np.where(layer == NO_INFORMATION, master,
                             np.where(master == NO_INFORMATION, layer,
                                      np.maximum(master, layer))).astype(np.uint8)


def window_lattice(grid: GridGeometry, resolution: float) -> GridGeometry | None:
    """``grid`` if rolling windows of ``resolution`` m cells can lie on its cells
    (:meth:`Costmap.rolling_window`'s ``lattice``: axis-aligned, the same resolution),
    else None."""
    same = grid.origin.theta == 0.0 and math.isclose(grid.resolution, resolution)
    return grid if same else None


# --------------------------------------------------------------------- footprint checks
def footprint_cells(grid: GridGeometry, footprint: Footprint,
                    pose: PoseLike) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of the cells the footprint covers at ``pose`` (map frame): the
    cells its outline passes through (costmap_2d's footprint lines) and every cell whose
    centre lies inside it. Cells off the grid are included (check ``grid.contains``)."""
    units = grid.to_cell_units(transform_points(pose, footprint.polygon))
    outline = walk_cells(units, np.roll(units, -1, axis=0))
    lo = np.floor(units.min(axis=0)).astype(int)
    hi = np.floor(units.max(axis=0)).astype(int)
    cols, rows = np.meshgrid(np.arange(lo[0], hi[0] + 1), np.arange(lo[1], hi[1] + 1))
    cols, rows = cols.ravel(), rows.ravel()
    inside = _inside_polygon(np.column_stack([cols + 0.5, rows + 0.5]), units)
    return (np.concatenate([outline.row, rows[inside]]),
            np.concatenate([outline.col, cols[inside]]))


def footprint_cost(costmap: Costmap, footprint: Footprint, pose: PoseLike) -> int:
    """The worst cost under the footprint at ``pose``: ``LETHAL`` if the chair would
    overlap an obstacle; else ``NO_INFORMATION`` if part of it is unknown or off the map;
    else the highest cost it covers (``INSCRIBED`` and below)."""
    rows, cols = footprint_cells(costmap, footprint, pose)
    on_map = costmap.contains(rows, cols)
    covered = costmap.cost[rows[on_map], cols[on_map]]
    if (covered == LETHAL).any():
        return LETHAL
    if not on_map.all():
        return NO_INFORMATION
    return int(covered.max())


def _inside_polygon(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """Crossing-number test of ``points`` (M, 2) against a closed ``polygon`` (N, 2)."""
    a, b = polygon, np.roll(polygon, -1, axis=0)
    px, py = points[:, None, 0], points[:, None, 1]
    straddles = (a[:, 1] > py) != (b[:, 1] > py)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = a[:, 0] + (py - a[:, 1]) * (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    return (straddles & (px < x_cross)).sum(axis=1) % 2 == 1
