"""Mapping a floor the chair does not know: a tour of given points, or frontier exploration.

The chair starts with no map. As it drives, every new lidar scan is laid into a growing
log-odds occupancy grid (:class:`~abcwc.mapping.grid.OccupancyGrid`) at the pose the
chair itself believes it has: chapter 10's EKF on wheels and gyro, corrected by matching
each scan against the grid built so far (:class:`~abcwc.navigation.localization.
MapLocalizer` on the grid's occupied cells: scan-to-map matching, as Hector SLAM does;
never the simulator's truth, never the world's walls). It drives with the navigator
(:class:`~abcwc.behaviours.navigator.Navigator`), whose static map is replaced by the
grid every ``refresh_interval`` s. Cells never seen are free to the global plan (Nav2's
``allow_unknown``); the rolling local costmap and DWA, built from the live scan, keep the
chair off what it sees, and the body's safety filter is in the loop as always.

Where it goes:

* **a tour**: the points given, in order (a world's places are only coordinates handed to
  the chair); a point the navigator cannot reach is recorded and skipped;
* **frontiers** (Yamauchi, "A frontier-based approach for autonomous exploration",
  CIRA 1997): a frontier cell is an open cell (seen free more often than occupied)
  beside an unknown one (never seen) of an unknown region of at least ``min_unknown``
  m^2 (:func:`frontier_cells`); 8-connected frontier cells form a frontier, and a
  frontier at least ``min_frontier`` m long is worth a visit.
  The chair drives to the nearest one by travel cost over the inflated costmap (a
  Dijkstra search from the chair, :func:`~abcwc.navigation.planner.dijkstra_costs`), to
  its cell nearest the chair;
  when that frontier has been seen (none of its cells is a frontier any more within
  ``frontier_reach`` m of the goal) it picks the next. A frontier the navigator failed to
  reach is not tried again. A frontier goal keeps ``turn_margin`` m more than the
  footprint's reach from the walls, and a seen frontier is given up only where the chair
  has that room: a chair stopped half-way through a door cannot turn to its next goal.
  It stops when no reachable frontier is left, or when ``time_budget`` s have passed.

Either way, ``max_failures`` goals in a row that the navigator could not reach (a chair
that is stuck) end the exploration as failed, with the navigator's reason.

The run's log then goes to :func:`abcwc.mapping.build.build_map`, which runs graph SLAM
over its scans and writes the map as map_server files; :func:`floor_map` does all of it,
or loads the saved map of a floor the chair already knows.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from abcwc.behaviours.base import LOOP_RATE_HZ, BehaviourBase, Status, finite_point
from abcwc.behaviours.navigator import Navigator, NavigatorSettings
from abcwc.estimation.ekf import ChairEkf
from abcwc.geometry import compose
from abcwc.log import RunLog
from abcwc.mapping.build import BuiltMap, build_map, load_built_map
from abcwc.mapping.grid import (
    FREE,
    FREE_THRESH,
    OCCUPIED,
    OCCUPIED_THRESH,
    UNKNOWN,
    OccupancyGrid,
    to_probability,
)
from abcwc.navigation.costmap import FREE_SPACE, INSCRIBED, LETHAL, Costmap
from abcwc.navigation.localization import MapLocalizer, occupied_points
from abcwc.navigation.planner import cell_weights, dijkstra_costs
from abcwc.params import ChairParams, default_params
from abcwc.types import LIDAR_FRAME, LaserScan, Pose2D, SensorFrame, Twist

if TYPE_CHECKING:
    from abcwc.base import Base


@dataclass(frozen=True)
class ExploreSettings:
    """The explorer's settings (m, s); see the module notes."""

    resolution: float = 0.05  # m: the grid's cells (the navigator's costmaps' too)
    reach: float = 60.0  # m each way from the start the grid covers, unless ``area``
    area: tuple[float, float, float, float] | None = None  # xmin, ymin, xmax, ymax (m)
    refresh_interval: float = 2.0  # s between the navigator's and localiser's map updates
    margin: float = 2.0  # m of grid round what has been seen that the navigator is given
    min_frontier: float = 0.75  # m: a shorter frontier is not worth a visit
    min_unknown: float = 2.0  # m^2: a smaller unknown patch is a gap between far beams
    # (or the inside of a piece of furniture), not unexplored space
    frontier_reach: float = 1.0  # m: a frontier goal with no frontier cell this near is seen
    turn_margin: float = 0.4  # m beyond the footprint's circumscribed radius that a
    # frontier goal keeps from walls: the chair can turn there to its next goal
    landmark_spacing: float = 0.1  # m: an occupied cell this near the localiser's
    # map is not added to it (the map it matches scans against is drawn once)
    max_failures: int = 3  # goals in a row not reached before the explorer gives up
    time_budget: float = 900.0  # s: the exploration ends after this long

    def __post_init__(self) -> None:
        for name in ("resolution", "reach", "refresh_interval", "margin", "min_frontier",
                     "min_unknown", "frontier_reach", "turn_margin", "landmark_spacing",
                     "max_failures",
                     "time_budget"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
                    math.isfinite(value) and value > 0):
                raise ValueError(f"ExploreSettings.{name} must be a finite number > 0, "
                                 f"got {value!r}")
        if self.area is not None:
            xmin, ymin, xmax, ymax = (float(v) for v in self.area)
            if not (xmax > xmin and ymax > ymin):
                raise ValueError(f"ExploreSettings.area is (xmin, ymin, xmax, ymax) with "
                                 f"xmin < xmax and ymin < ymax, got {self.area!r}")


@dataclass(frozen=True)
class Visit:
    """One goal the explorer drove to: where, why, how it ended (the navigator's status
    and failure) and when (s)."""

    goal: tuple[float, float]
    kind: str  # "tour" or "frontier"
    status: str  # "succeeded", "failed", or "seen" (a frontier seen before it was reached)
    failure: str | None
    started: float
    ended: float


@dataclass
class _Goal:
    point: tuple[float, float]
    kind: str
    started: float
    seen: bool = False  # a frontier seen on the way: cancelled, not failed


class Explorer(BehaviourBase):
    """Map a floor from the chair's own scans while driving by its own estimate (module
    notes). ``tour``: points (x, y) to visit in order; None explores to frontiers.
    ``ekf``: the localiser's filter (e.g. ``calibrated_ekf(chair)``); default nominal
    odometry from ``start``. Call it with every frame; it succeeds when the tour is done,
    no frontier is left or the time budget has run out (:attr:`ended_because` says
    which), and fails when the first scan sees no walls or ``max_failures`` goals in a
    row were not reached (a chair that is stuck). :attr:`visits` lists every goal."""

    def __init__(self, start: Pose2D, tour: Sequence[tuple[float, float]] | None = None,
                 params: ChairParams | None = None, ekf: ChairEkf | None = None,
                 settings: ExploreSettings | None = None,
                 navigator_settings: NavigatorSettings | None = None):
        super().__init__(rate_hz=LOOP_RATE_HZ)
        if not isinstance(start, Pose2D):
            raise ValueError(f"start must be a Pose2D (the chair's pose, m and rad), "
                             f"got {start!r}")
        self.settings = s = settings or ExploreSettings()
        self.params = params or default_params()
        self.tour = None if tour is None else [finite_point(point, "tour point")
                                               for point in tour]
        area = s.area or (start.x - s.reach, start.y - s.reach,
                          start.x + s.reach, start.y + s.reach)
        self.grid = OccupancyGrid.covering(*area, s.resolution)
        self.start = start
        self._ekf = ekf
        self._navigator_settings = navigator_settings or NavigatorSettings(
            resolution=s.resolution)
        self.navigator: Navigator | None = None  # built on the first scan
        self.visits: list[Visit] = []
        self.ended_because = ""
        self._goal: _Goal | None = None
        self._next_refresh = -math.inf
        self._last_scan = -math.inf
        self._seen_box: tuple[int, int, int, int] | None = None  # row0, row1, col0, col1
        self._failed_frontiers: list[tuple[float, float]] = []
        self._next_tour = 0
        self._failures = 0  # goals in a row the navigator failed to reach
        self._started: float | None = None
        self._track: list[tuple[float, float, float, float]] = []  # t, x, y, theta
        self._landmarks = np.zeros((0, 2))  # m: the wall cells the localiser matches against

    # ------------------------------------------------------------------ per frame
    @property
    def _nav(self) -> Navigator:
        """The navigator, once the first scan has built it."""
        if self.navigator is None:
            raise RuntimeError("the explorer has not seen its first scan yet")
        return self.navigator

    @property
    def pose(self) -> Pose2D:
        """The chair's own estimate of its pose (the start before the first frame)."""
        return self.start if self.navigator is None else self.navigator.localizer.pose

    def update(self, frame: SensorFrame) -> Twist:
        """Every frame: the navigator localises and drives, the new scan goes into the
        grid at the estimate, the navigator's map is renewed when due, and when a goal
        has ended the next is chosen."""
        if self._started is None:
            self._started = frame.t
        if self.navigator is None:
            return self._first_frame(frame)
        command = self.navigator(frame)
        pose = self.navigator.localizer.pose
        self._track.append((frame.t, pose.x, pose.y, pose.theta))
        self._integrate(frame)
        if frame.t >= self._next_refresh:
            self._refresh(frame.t)
        if self._goal is not None and self.navigator.running:
            return command  # type: ignore[return-value]
        if self._goal is not None:
            self._record(frame.t)
            if not self.running:
                return Twist(0.0, 0.0)
        if frame.t - self._started > self.settings.time_budget:
            self._finish(f"the time budget ({self.settings.time_budget:.0f} s) ended")
            return Twist(0.0, 0.0)
        self._next_goal(frame.t)
        return Twist(0.0, 0.0)

    def _first_frame(self, frame: SensorFrame) -> Twist:
        """The first scan, laid in at the start pose, gives the localiser its map."""
        scan = frame.readings.get(LIDAR_FRAME)
        if not isinstance(scan, LaserScan):
            return Twist(0.0, 0.0)  # wait for the lidar
        self._lay(scan, self.start)
        cells, geometry = self.map_cells()
        if (cells == OCCUPIED).sum() < 10:
            self.fail("the first scan saw almost nothing: no walls within the lidar's reach")
            return Twist(0.0, 0.0)
        self._landmarks = occupied_points(cells, geometry)
        localizer = MapLocalizer(self._landmarks, self.start, self.params, ekf=self._ekf)
        self.navigator = Navigator(_static(cells, geometry), localizer, self.params,
                                   self._navigator_settings)
        localizer.observe(frame)
        self._next_refresh = frame.t + self.settings.refresh_interval
        return Twist(0.0, 0.0)

    def _lay(self, scan: LaserScan, pose: Pose2D) -> None:
        """Add ``scan`` taken at base pose ``pose`` to the grid; grow the seen box."""
        self._last_scan = scan.stamp
        mount = self.params.lidar.mount
        self.grid.integrate(scan, compose(pose, mount))
        reach = scan.range_max + 0.5
        g = self.grid
        r0, c0 = g.world_to_cell(np.array([[pose.x - reach, pose.y - reach]]))
        r1, c1 = g.world_to_cell(np.array([[pose.x + reach, pose.y + reach]]))
        box = (max(int(r0[0]), 0), min(int(r1[0]) + 1, g.height),
               max(int(c0[0]), 0), min(int(c1[0]) + 1, g.width))
        if self._seen_box is None:
            self._seen_box = box
        else:
            old = self._seen_box
            self._seen_box = (min(old[0], box[0]), max(old[1], box[1]),
                              min(old[2], box[2]), max(old[3], box[3]))

    def _integrate(self, frame: SensorFrame) -> None:
        scan = frame.readings.get(LIDAR_FRAME)
        if isinstance(scan, LaserScan) and scan.stamp > self._last_scan:
            self._lay(scan, self._nav.localizer.pose)

    def estimates(self, log: RunLog) -> np.ndarray:
        """(N, 3) the chair's own pose estimate at every row of ``log`` (the run it drove):
        the latest estimate at or before each row's time, the start before the first."""
        track = np.array(self._track, dtype=float).reshape(-1, 4)
        out = np.tile(self.start.as_array(), (len(log), 1))
        if len(track):
            at = np.searchsorted(track[:, 0], np.asarray(log.t) + 1e-9, side="right") - 1
            seen = at >= 0
            out[seen] = track[at[seen], 1:]
        return out

    # ------------------------------------------------------------------ the map
    def _window(self) -> tuple[slice, slice]:
        """The part of the grid that has been seen, plus ``margin`` m, holding the chair
        and the goal."""
        g, s = self.grid, self.settings
        r0, r1, c0, c1 = self._seen_box  # type: ignore[misc]
        known_rows = np.flatnonzero(self.grid.log_odds[r0:r1, c0:c1].any(axis=1))
        known_cols = np.flatnonzero(self.grid.log_odds[r0:r1, c0:c1].any(axis=0))
        points = [(self.pose.x, self.pose.y)]
        if self._goal is not None:
            points.append(self._goal.point)
        rows, cols = g.world_to_cell(np.array(points))
        pad = math.ceil(s.margin / g.resolution)
        lo_r = min(r0 + int(known_rows.min()), int(rows.min())) - pad
        hi_r = max(r0 + int(known_rows.max()), int(rows.max())) + pad + 1
        lo_c = min(c0 + int(known_cols.min()), int(cols.min())) - pad
        hi_c = max(c0 + int(known_cols.max()), int(cols.max())) + pad + 1
        return (slice(max(lo_r, 0), min(hi_r, g.height)),
                slice(max(lo_c, 0), min(hi_c, g.width)))

    def map_cells(self) -> tuple[np.ndarray, Costmap]:
        """The seen part of the grid as trinary cells, and the empty costmap on its
        cells (their geometry)."""
        rows, cols = self._window()
        g = self.grid
        origin = g.cell_to_world(np.array([rows.start]), np.array([cols.start]))[0] \
            - g.resolution / 2
        geometry = Costmap(g.resolution, cols.stop - cols.start, rows.stop - rows.start,
                           (float(origin[0]), float(origin[1]), 0.0), default=FREE_SPACE)
        probability = to_probability(g.log_odds[rows, cols])
        cells = np.full(geometry.shape, UNKNOWN, dtype=np.int8)
        cells[probability < FREE_THRESH] = FREE
        cells[probability > OCCUPIED_THRESH] = OCCUPIED
        return cells, geometry

    def _static_map(self) -> Costmap:
        return _static(*self.map_cells())

    def _refresh(self, now: float) -> None:
        """The navigator and its localiser on the grid as it is now."""
        self._next_refresh = now + self.settings.refresh_interval
        navigator = self._nav
        cells, geometry = self.map_cells()
        navigator.replace_map(_static(cells, geometry))
        rows, cols = self._window()
        settled = self.grid.log_odds[rows, cols] >= self.grid.model.l_max
        self._extend_landmarks(geometry.cell_to_world(*np.nonzero(settled)))
        goal, costmap = self._goal, navigator.global_costmap
        if goal is not None and goal.kind == "frontier" and navigator.running:
            frontier = self.frontiers(costmap)
            cells_left = np.vstack(frontier) if frontier else np.zeros((0, 2))
            near = np.hypot(*(cells_left - goal.point).T) <= self.settings.frontier_reach \
                if len(cells_left) else np.zeros(0, dtype=bool)
            row, col = costmap.world_to_cell(np.array([self.pose.x, self.pose.y]))
            if not near.any() and costmap.contains(row, col) \
                    and self._room_to_turn(costmap)[row, col]:
                goal.seen = True  # on to the next, from where the chair can turn
                navigator.cancel()

    def _extend_landmarks(self, points: np.ndarray) -> None:
        """Give the localiser the wall cells ``points`` (settled ones: at the grid's
        clamp ``l_max``, seen occupied scan after scan, as a walking person's cells are
        not) more than ``landmark_spacing`` m from every cell it already matches
        against; those it has stay where they were first drawn. Were the wall cells
        redrawn from every scan, a small heading error would be written into the map and
        matched back out of it, and the map would turn with the estimate (measured on
        the floor's tour: 0.68 m off at 36 m from the start, 0.02 rad turned)."""
        if not len(points):
            return
        distance, _ = cKDTree(self._landmarks).query(points)
        new = points[distance > self.settings.landmark_spacing]
        if len(new):
            self._landmarks = np.vstack([self._landmarks, new])
            self._nav.localizer.replace_map(self._landmarks)

    def _room_to_turn(self, costmap: Costmap) -> np.ndarray:
        """(height, width) bool on ``costmap``'s cells: where the chair could turn on the
        spot, no wall within its circumscribed radius plus ``turn_margin``."""
        walls = costmap.cost == LETHAL
        if not walls.any():
            return np.ones(costmap.shape, dtype=bool)
        room = self._nav.footprint.circumscribed_radius + self.settings.turn_margin
        return ndimage.distance_transform_edt(~walls) * costmap.resolution >= room

    # ------------------------------------------------------------------ goals
    def _record(self, now: float) -> None:
        """The goal that just ended, in :attr:`visits`; too many failures end the run."""
        goal, navigator = self._goal, self._nav
        if goal is None:
            return
        self._goal = None
        failure = None if goal.seen else navigator.failure
        outcome = "seen" if goal.seen else navigator.status.value
        self.visits.append(Visit(goal.point, goal.kind, outcome, failure, goal.started, now))
        if navigator.status is not Status.FAILED or goal.seen:
            self._failures = 0
            return
        self._failures += 1
        if goal.kind == "frontier":
            self._failed_frontiers.append(goal.point)
        if self._failures >= self.settings.max_failures:
            pose = self.pose
            self.fail(f"{self._failures} goals in a row not reached, the last: {failure}; "
                      f"the chair is at ({pose.x:.2f}, {pose.y:.2f}) m by its estimate")

    def _next_goal(self, now: float) -> None:
        """Send the navigator to the tour's next point or the nearest frontier."""
        navigator = self._nav
        if self.tour is not None:
            if self._next_tour >= len(self.tour):
                self._finish(f"the tour of {len(self.tour)} points is done")
                return
            goal = _Goal(self.tour[self._next_tour], "tour", now)
            self._next_tour += 1
        else:
            self._refresh(now)
            found = self.nearest_frontier(navigator.global_costmap)
            if found is None:
                self._finish("no reachable frontier is left")
                return
            goal = _Goal(found, "frontier", now)
        self._goal = goal
        navigator.replace_map(self._static_map())  # the window now holds the goal
        navigator.go_to(goal.point)

    def _finish(self, reason: str) -> None:
        self.ended_because = reason
        if self.navigator is not None and self.navigator.running:
            self.navigator.cancel()
        self.succeed()

    # ------------------------------------------------------------------ frontiers
    def frontiers(self, costmap: Costmap) -> list[np.ndarray]:
        """The frontiers of the seen grid (on the cells of ``costmap``, the navigator's
        inflated one) at least ``min_frontier`` m long, each as (K, 2) map points (m) of
        its cells where the chair may stand and turn on the spot on ``costmap``
        (:func:`frontier_cells`); a frontier with no such cell is left out."""
        rows, cols = self._window()
        if (rows.stop - rows.start, cols.stop - cols.start) != costmap.shape:
            raise ValueError(f"the costmap {costmap.shape} is not on the seen grid's cells")
        cells = math.ceil(self.settings.min_unknown / self.grid.resolution ** 2)
        frontier = frontier_cells(self.grid.log_odds[rows, cols], cells)
        frontier &= costmap.cost < INSCRIBED
        labels, count = ndimage.label(frontier, structure=np.ones((3, 3)))
        if not count:
            return []
        sizes = np.bincount(labels.ravel())
        big = np.flatnonzero(sizes * costmap.resolution >= self.settings.min_frontier)
        labels[~self._room_to_turn(costmap)] = 0  # goals only where the chair can turn
        found = [costmap.cell_to_world(*np.nonzero(labels == label)) for label in big[big > 0]]
        return [points for points in found if len(points)]

    def nearest_frontier(self, costmap: Costmap) -> tuple[float, float] | None:
        """The goal on the nearest reachable frontier by travel cost from the chair over
        ``costmap`` (the frontier's cell nearest by that cost); None when none is left."""
        found = self.frontiers(costmap)
        if not found:
            return None
        weights = cell_weights(costmap, allow_unknown=True)
        rows, cols = costmap.world_to_cell(np.array([[self.pose.x, self.pose.y]]))
        start = int(rows[0]) * costmap.width + int(cols[0])
        if not math.isfinite(weights.flat[start]):  # the estimate against a wall
            weights.flat[start] = float(weights[np.isfinite(weights)].max())
        costs = dijkstra_costs(weights, start)
        best: tuple[float, tuple[float, float]] | None = None
        for points in found:
            if any(np.hypot(*(points - failed).T).min() <= self.settings.frontier_reach
                   for failed in self._failed_frontiers):
                continue
            r, c = costmap.world_to_cell(points)
            along = costs[r, c]
            k = int(np.argmin(along))
            if math.isfinite(along[k]) and (best is None or along[k] < best[0]):
                best = (float(along[k]), (float(points[k, 0]), float(points[k, 1])))
        return None if best is None else best[1]


def frontier_cells(log_odds: np.ndarray, min_unknown: int) -> np.ndarray:
    """Yamauchi's frontier cells of a log-odds grid (bool, same shape): open cells (log
    odds below the prior's 0: seen free more than occupied) beside (4-neighbours) an
    unknown cell (never updated, log odds 0) of an unknown region of at least
    ``min_unknown`` cells (8-connected). Smaller unknown patches are the gaps between
    far beams, not unexplored space."""
    unknown = log_odds == 0.0
    labels, count = ndimage.label(unknown, structure=np.ones((3, 3)))
    if count:
        sizes = np.bincount(labels.ravel())
        sizes[0] = 0
        unknown = sizes[labels] >= min_unknown
    beside = np.zeros_like(unknown)
    beside[1:] |= unknown[:-1]
    beside[:-1] |= unknown[1:]
    beside[:, 1:] |= unknown[:, :-1]
    beside[:, :-1] |= unknown[:, 1:]
    return (log_odds < 0.0) & beside


def _static(cells: np.ndarray, geometry: Costmap) -> Costmap:
    """The navigator's static map from trinary ``cells``: unknown cells free (Nav2's
    ``allow_unknown``: what the chair has not seen yet it may plan through; the live scan
    marks what is there when it comes into view)."""
    static = Costmap.like(geometry, default=FREE_SPACE)
    static.add_static(cells, track_unknown=False)
    return static


def run_exploration(chair: Base, explorer: Explorer, max_seconds: float,
                    progress: bool = False) -> RunLog:
    """Run ``explorer`` on ``chair`` (through the body's safety filter, as every run is)
    until it ends or ``max_seconds`` have passed; the drive as one RunLog. ``progress``
    shows a bar of the goals reached (the tour's points, or frontiers)."""
    if not (isinstance(max_seconds, (int, float)) and math.isfinite(max_seconds)
            and max_seconds > 0):
        raise ValueError(f"max_seconds must be a finite number > 0 s, got {max_seconds!r}")
    if not progress:
        return chair.run(explorer, max_seconds, until=lambda: not explorer.running)
    from tqdm.auto import tqdm

    total = len(explorer.tour) if explorer.tour is not None else None
    with tqdm(total=total, desc="mapping the floor", unit="goal") as bar:

        def ended() -> bool:
            if len(explorer.visits) > bar.n:
                bar.update(len(explorer.visits) - bar.n)
            return not explorer.running

        return chair.run(explorer, max_seconds, until=ended)


SLAM_END_STD = (0.02, 0.02, 0.005)
"""m, m, rad: how sure the chair's pose at the end of a mapping run is taken to be on the
map SLAM built (measured on the floor's tour: within 0.02 m and 0.002 rad of the truth)."""


@dataclass
class MappedFloor:
    """A floor's map and how it came: ``built`` (cells, grid, SLAM result, saved path);
    the exploration's ``log`` and ``explorer`` (None for a loaded map); ``wall_seconds``
    the wall-clock time it took; ``pose`` where the chair stands, in the map's frame
    (:attr:`BuiltMap.end_pose`; the start for a loaded map); ``ekf`` the chair's filter
    (its calibration and gyro bias kept) moved onto the map's frame, for
    ``Navigator.for_map(built.cells, built.grid, pose, ekf=ekf)`` to drive on from there
    (the ``ekf`` given, for a loaded map)."""

    built: BuiltMap
    log: RunLog | None
    explorer: Explorer | None
    wall_seconds: float
    pose: Pose2D
    ekf: ChairEkf | None = None


def floor_map(chair: Base, path: str | Path, start: Pose2D,
              tour: Sequence[tuple[float, float]] | None = None, ekf: ChairEkf | None = None,
              settings: ExploreSettings | None = None, max_seconds: float = 900.0,
              progress: bool = False) -> MappedFloor:
    """The map of the floor ``chair`` stands on at ``start`` (its known pose, e.g. a
    world's start place): the saved map at ``path`` (a ``.yaml``, map_server files) if
    there is one, a known floor; else the chair maps the floor by ``tour`` or by
    frontiers (:class:`Explorer`, at most ``max_seconds`` s), builds the map with graph
    SLAM (:func:`~abcwc.mapping.build.build_map`) and saves it there (``progress``: a bar
    of the goals reached). A mapping run that failed or did not end in time raises
    :class:`RuntimeError` saying why."""
    clock = time.perf_counter()
    path = Path(path)
    if path.exists():
        return MappedFloor(load_built_map(path), None, None, time.perf_counter() - clock,
                           start, ekf)
    explorer = Explorer(start, tour, chair.params, ekf, settings)
    log = run_exploration(chair, explorer, max_seconds, progress)
    if explorer.status is Status.FAILED:
        raise RuntimeError(f"mapping the floor failed: {explorer.failure}")
    if explorer.running:
        explorer.cancel()
        raise RuntimeError(f"mapping the floor did not end within {max_seconds:.0f} s "
                           f"({len(explorer.visits)} goals visited)")
    built = build_map(log, start, path, poses=explorer.estimates(log), params=chair.params)
    end, navigator = built.end_pose, explorer.navigator
    assert end is not None and navigator is not None  # a run that mapped has both
    filter_ = navigator.localizer.ekf
    # onto the map's frame: the explorer's own grid had turned a little with its drift
    filter_.reset_pose(end, np.diag(np.square(SLAM_END_STD)))
    return MappedFloor(built, log, explorer, time.perf_counter() - clock, end, filter_)
