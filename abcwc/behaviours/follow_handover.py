"""The follower's hand-over to the navigator: where her trail is blocked, a way round.

The tag follower (:class:`~abcwc.behaviours.follow.TagFollower`) drives along the trail
its person walked. Where that trail is blocked (someone stands in the door she went
through, a way the checks allow no command along), the follower has only the newest
scan and its back-off. The navigator has more: a plan over everything seen so far, door
mode and its recoveries (move_base's job). So the follower keeps what it has seen:

* **A map of its own scans**: every new lidar scan, without the returns of the people it
  tracks (they move on), is laid into a log-odds occupancy grid
  (:class:`~abcwc.mapping.grid.OccupancyGrid`, Probabilistic Robotics table 9.1) in the
  odom frame, at the follower's own pose estimate, covering ``reach`` m each way from
  where the chair was at the first scan.
* **The hand-over** (:meth:`HandOver.start`): a
  :class:`~abcwc.behaviours.navigator.Navigator` on the part of that map seen so far
  (unknown cells free to the plan, Nav2's ``allow_unknown``, as the explorer's
  navigator; its localiser matches scans against the map's occupied cells), sent to the
  first of the goals it is given that it can stand on (the follower gives her last-seen
  point, then her trail's points back towards the chair). From then on it drives
  (:meth:`HandOver.observe` calls it with every frame, as the control loop would) until
  it succeeds, fails, or the follower takes over again (:meth:`HandOver.end`).

Every command the navigator sends still passes the body's safety filter in the loop.
"""

from __future__ import annotations

import math

import numpy as np

from abcwc.behaviours.base import Status
from abcwc.behaviours.navigator import Navigator, NavigatorSettings
from abcwc.mapping.grid import OccupancyGrid
from abcwc.navigation.costmap import FREE_SPACE, LETHAL, Costmap
from abcwc.navigation.localization import MapLocalizer, occupied_points
from abcwc.params import ChairParams
from abcwc.types import LaserScan, Pose2D, SensorFrame, Twist

MAP_MARGIN = 2.0
"""m of the map round what has been seen (and round the chair and the goals) that the
navigator is given."""


class HandOver:
    """The follower's map of its own scans and the navigator it hands over to (module
    notes). ``reach`` (m) each way from the first scan's pose; cells of ``resolution``
    m."""

    def __init__(self, params: ChairParams, reach: float = 25.0, resolution: float = 0.05):
        if not (math.isfinite(reach) and reach > 0):
            raise ValueError(f"reach must be a finite number > 0 m, got {reach!r}")
        self.params = params
        self.reach = float(reach)
        self.resolution = float(resolution)
        self.grid: OccupancyGrid | None = None  # made at the first scan
        self.navigator: Navigator | None = None  # while handed over
        self.goal: tuple[float, float] | None = None
        self.command = Twist(0.0, 0.0)  # the navigator's latest command
        self.outcomes: list[tuple[float, float, str]] = []  # (started, ended, how)
        self._started = math.nan

    # ------------------------------------------------------------------ the map
    def lay(self, scan: LaserScan, sensor: Pose2D) -> None:
        """Add ``scan`` taken from the lidar at ``sensor`` (odom) to the map."""
        if self.grid is None:
            r = self.reach
            self.grid = OccupancyGrid.covering(sensor.x - r, sensor.y - r, sensor.x + r,
                                               sensor.y + r, self.resolution)
        self.grid.integrate(scan, sensor)

    def map_cells(self, around: np.ndarray) -> tuple[np.ndarray, Costmap]:
        """The seen part of the map (and ``MAP_MARGIN`` m round it and the points
        ``around``, (K, 2) m) as trinary cells, with the empty costmap on those cells."""
        if self.grid is None:
            raise RuntimeError("no scan has been laid in the map yet")
        g = self.grid
        rows, cols = np.nonzero(g.known())
        pr, pc = g.world_to_cell(np.asarray(around, dtype=float).reshape(-1, 2))
        rows, cols = np.concatenate([rows, pr]), np.concatenate([cols, pc])
        pad = math.ceil(MAP_MARGIN / g.resolution)
        r0, r1 = max(int(rows.min()) - pad, 0), min(int(rows.max()) + pad + 1, g.height)
        c0, c1 = max(int(cols.min()) - pad, 0), min(int(cols.max()) + pad + 1, g.width)
        corner = g.cell_to_world(np.array([r0]), np.array([c0]))[0] - g.resolution / 2
        geometry = Costmap(g.resolution, c1 - c0, r1 - r0,
                           (float(corner[0]), float(corner[1]), 0.0), default=FREE_SPACE)
        return g.trinary()[r0:r1, c0:c1], geometry

    # ------------------------------------------------------------------ driving
    @property
    def active(self) -> bool:
        """True while the navigator drives."""
        return self.navigator is not None

    def start(self, now: float, pose: Pose2D, goals: np.ndarray) -> str | None:
        """Hand over at ``now`` (s), the chair at ``pose`` (odom): a navigator on the map
        so far, sent to the first of ``goals`` ((K, 2) m, odom) that is on the map and
        clear of its walls by the chair's passing radius. Returns None if it is on its
        way, else why not (then nothing is handed over)."""
        goals = np.asarray(goals, dtype=float).reshape(-1, 2)
        if self.grid is None or not len(goals):
            return "no map yet" if self.grid is None else "nowhere to go"
        cells, geometry = self.map_cells(np.vstack([[pose.x, pose.y], goals]))
        static = Costmap.like(geometry, default=FREE_SPACE)
        static.add_static(cells, track_unknown=False)
        localizer = MapLocalizer(occupied_points(cells, geometry), pose, self.params)
        navigator = Navigator(static, localizer, self.params,
                              NavigatorSettings(resolution=self.resolution))
        costmap = navigator.global_costmap
        rows, cols = costmap.world_to_cell(goals)
        inside = costmap.contains(rows, cols)
        cost = np.full(len(goals), LETHAL, dtype=int)
        cost[inside] = costmap.cost[rows[inside], cols[inside]]
        standable = np.flatnonzero(cost < LETHAL - 1)
        if not len(standable):
            return "no goal the chair can stand on"
        goal = goals[int(standable[0])]
        navigator.go_to((float(goal[0]), float(goal[1])))
        if not navigator.running:
            return navigator.failure
        self.navigator, self.goal, self._started = navigator, (float(goal[0]),
                                                               float(goal[1])), now
        self.command = Twist(0.0, 0.0)
        return None

    def observe(self, frame: SensorFrame) -> None:
        """Every frame while handed over: the navigator localises and, at its rate,
        decides (:attr:`command`)."""
        if self.navigator is not None:
            command = self.navigator(frame)
            self.command = command if isinstance(command, Twist) else Twist(0.0, 0.0)

    @property
    def status(self) -> Status | None:
        """The navigator's status while handed over (None when not)."""
        return None if self.navigator is None else self.navigator.status

    @property
    def failure(self) -> str | None:
        """Why the navigator failed (None while handed over and running, or when not)."""
        return None if self.navigator is None else self.navigator.failure

    def end(self, now: float, how: str) -> None:
        """Take over again at ``now`` (s), noting ``how`` the hand-over ended."""
        if self.navigator is not None:
            self.outcomes.append((self._started, now, how))
        self.navigator, self.goal = None, None
        self.command = Twist(0.0, 0.0)


__all__ = ["MAP_MARGIN", "HandOver"]
