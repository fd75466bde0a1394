"""The navigator: move_base's job for the chair, from a goal pose to standing on it.

Given a goal (a pose, an ``(x, y)``, or a named place of the world), the navigator

1. **localises** with :class:`~abcwc.navigation.localization.MapLocalizer` (the EKF on
   wheels and gyro, corrected by laying lidar scans on the map; never the simulator's
   ground truth);
2. **plans** over the global costmap (the static map plus what the lidar sees now,
   inflated) with :func:`~abcwc.navigation.planner.plan`, again every
   ``1 / planner_frequency`` s. **One passability**: the costmap keeps the chair's
   centre :meth:`~abcwc.navigation.dwa.DwaPlanner.passing_radius` (0.38 m) from every
   wall cell, not only the inscribed radius (0.16 m), so the planner plans only through
   gaps the local planner takes (the chair needs 0.76 m between wall cells), and a gap
   it would refuse costs the planner the detour round it. In **door mode** the plan
   through a door less than ``door_margin`` each side wider than that follows the
   door's axis for ``door_approach`` m either side, and the chair slows to
   ``narrow_speed``, so that it lines up before it enters (:meth:`_through_doors`);
3. **follows** it with :class:`~abcwc.navigation.dwa.DwaPlanner` on a rolling local
   costmap (5 x 5 m) built from the static map, the newest scan and the sonar's and IR
   rangers' marks that the map does not explain (a
   :class:`~abcwc.navigation.range_layer.RangeSensorLayer`, as the thesis's costmap
   took the sonar's beam), at ``controller_frequency``, keeping out of the way of the
   people it tracks in the scan (:class:`~abcwc.navigation.people.PeopleTracker`): no
   trajectory may leave the chair unable to stop clear of where a walker will be within
   ``people_horizon`` s;
4. **slows down** for the goal (no faster than it can stop from half-way into the
   tolerance), **turns to the goal's heading** once within ``xy_goal_tolerance``, and
   succeeds within ``yaw_goal_tolerance``, standing still;
5. **re-localises** when the localiser is lost: it stops and searches round its
   estimate for where the scan fits the map (with ``relocalise_turn`` set, as the
   mission layer sets it, turning on the spot a little between searches);
6. **recovers** when no safe trajectory is left or the chair has come no
   ``oscillation_distance`` nearer the goal (the least way left on the map) in
   ``oscillation_timeout`` s (Nav2's progress checker, judged by the goal): it waits
   ``controller_patience`` s for the way to clear (people move), counted from when it
   was first blocked there (a chair that inches on between refusals has not got away
   until it is ``oscillation_distance`` from where it stood), then recovers, in
   order (after Nav2's recovery tree): backs off a little if the IR ring sees the way
   behind clear (else turns on the spot), clears the local costmap's sonar and IR marks,
   lines up with the gap ahead (door mode for it) if the map says the chair fits it and
   it was entered askew, closes the gap ahead and plans round it if the map has a way
   round, or, where the gap is the only way and nobody is in it, gives up there (the
   same refusal would follow another try); backs off again; after ``max_recoveries``
   recoveries without progress it gives up with the reason. A walker in the way is
   waited for (``people_patience`` s) before each of these: a way that people shut is no
   proof that it is too narrow.

It ends **succeeded**, or **failed** with a reason a person can act on: the goal is
off the map or in a wall, no path leads there, no passable way (naming the gap: "the
0.75 m gap at (6.03, 2.50) is narrower than the chair needs, 0.76 m"), the chair is
stuck, lost, or out of time, or the goal was cancelled. Every command it sends passes
through the body's :class:`~abcwc.control.safety.SafetyFilter` in the control loop
(:mod:`abcwc.base`): there is no way round it; its DWA plans brakes the filter's ramp
can follow.

:class:`NavigatorSettings` holds A.17's values where they suit a chair with a person
in it, and says why where they do not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np
from scipy import ndimage

from abcwc.behaviours.base import BehaviourBase
from abcwc.control.safety import ClearanceCheck, range_sensor_rays
from abcwc.estimation.ekf import ChairEkf
from abcwc.geometry import compose, densify_polyline, position_of, wrap_angle
from abcwc.mapping.grid import GridGeometry
from abcwc.navigation.costmap import (
    FREE_SPACE,
    INSCRIBED,
    LETHAL,
    NO_INFORMATION,
    Costmap,
    chair_footprint,
    footprint_cost,
    window_lattice,
)
from abcwc.navigation.dwa import DwaPlanner, DwaResult
from abcwc.navigation.localization import MapLocalizer, occupied_points, wall_points
from abcwc.navigation.passages import (
    Gap,
    close_gap,
    gaps_along,
    minimum_clear_width,
    narrowest_gap,
)
from abcwc.navigation.people import PeopleTracker, predicted_sweep, standing_still
from abcwc.navigation.planner import NoPathError, Path, costs_to_goal, plan
from abcwc.navigation.range_layer import RangeSensorLayer
from abcwc.params import ChairParams, default_params, load_navigation_params
from abcwc.types import LIDAR_FRAME, LaserScan, Pose2D, SensorFrame, Twist

if TYPE_CHECKING:
    from abcwc.sim.world import World


@dataclass(frozen=True)
class NavigatorSettings:
    """The navigator's settings (m, s, rad, Hz). Where A.17 has a value it is named.

    Changed from A.17, and why:

    * ``xy_goal_tolerance`` 0.25 m (A.17 0.5 m): half a metre leaves a person short of
      a desk or a door; a quarter is the chair's own half-width.
    * ``yaw_goal_tolerance`` 0.3 rad (A.17 3 rad, 172 degrees, which is no check at
      all): arriving facing the desk is the point of a named place.
    * ``inflation_radius`` 0.7 m (A.17 0.05 m, smaller than one of its own 0.75 m local
      cells): the planner should keep a chair with a person in it off walls and door
      frames, not graze them; 0.7 m is beyond the chair's circumscribed radius (0.51 m),
      as Nav2's tuning guide advises. ``cost_scaling_factor`` stays costmap_2d's 10: a
      gentler slope (4) makes a doorway so costly that DWA will not turn into it.
    * ``max_vel_x`` 0.8 m/s (A.17 1.28 m/s, 77 % of full speed) and ``acc_lim_x``
      0.8 m/s^2 (A.17 3.6 m/s^2, a jolt): within :class:`ComfortLimits`.
      ``min_vel_x`` 0 (A.17 -1.28): DWA never drives backwards, where the sonar cannot
      see; backing off is a recovery that checks the IR ring first.
    * ``max_vel_theta`` 0.8 rad/s (A.17 1.57): half the chair's turn rate.
    * the plan is handed to DWA as planned, not smoothed (:func:`~abcwc.navigation.
      planner.smooth`): the smoother cuts corners through cells as costly as the
      costliest the path crossed, which near a door means the door's own cost, and a
      chair that cuts towards a door from along the corridor swings its front corner
      into the frame (measured: a 1 m office door taken from the corridor, a collision
      and 14 s against the frame smoothed, none as planned).
    * ``footprint_padding`` 0.05 m (costmap_2d's default 0.01): the localisation's few
      centimetres and the lag between a command and the wheels (0.25 s) put the chair
      beside the arc DWA checked; without the margin a front corner clips door frames.
    * near obstacles the speed is scaled down (``slow_within`` 0.3 m, ``narrow_speed``
      0.3 m/s; A.17 has no such rule, Nav2's Regulated Pure Pursuit does): with a few
      centimetres each side of a door, a chair arriving at 0.8 m/s could not line up in
      time (measured: 2.3 s with a corner over a door frame's cells, arriving from a
      room at an angle). Near people the speed is scaled down too
      (``people_slow_within`` 2 m, ``people_speed`` 0.4 m/s): a walker who sees the
      chair coming may stop in its way (measured without it: three touches in 100 goals,
      each a person who stopped where they were predicted to walk on).
    * ``forward_prune_distance`` 2 m (Nav2 DWB's default; base_local_planner hands DWA
      the whole plan inside the window): DWA's goal is the plan's end inside the window,
      and its distance is measured straight, through walls; where the plan goes out of
      a door and back along a corridor, a goal at the window's edge lies behind the
      chair, and standing still scores best. Two metres of plan keep the goal ahead.
    * ``occdist_scale`` 0.01 (A.17 0.1; base_local_planner's default is 0.01): with the
      wider inflation a doorway's cells cost 30-100, and at 0.1 the obstacle term
      outweighs metres of path distance, so the chair would not turn into a door.
    * ``resolution`` 0.05 m for both costmaps (A.17 0.02 global, 0.75 local: a 0.75 m
      cell is wider than a door's clearance).
    * recoveries on (A.17 off): a chair that stops for good in a corridor because a
      person stood in its way has failed its passenger.
    * ``door_margin`` 0.15 m and ``door_approach`` 1 m (A.17 has no door mode): the
      floor's 1 m doors fall inside it; turning into one from the 2 m corridor, beside a
      walker, without it, the chair swung a corner onto a jamb and wedged there.
    * ``scan_mark_wall_distance`` 0.15 m: a return this near a mapped wall is the wall;
      marked for the plan beside it, a jamb's returns narrowed a 0.80 m door below the
      passing width, and the plan flipped between the door and the way round.
    """

    controller_frequency: float = 5.0  # Hz, A.17
    planner_frequency: float = 1.0  # Hz, A.17
    controller_patience: float = 3.0  # s, A.17: wait this long for the way to clear
    planner_patience: float = 5.0  # s, A.17: fail when no plan is found for this long
    oscillation_timeout: float = 10.0  # s, A.17
    oscillation_distance: float = 0.2  # m, A.17
    xy_goal_tolerance: float = 0.25
    yaw_goal_tolerance: float = 0.3
    resolution: float = 0.05
    local_size: float = 5.0  # m, A.17's 5 x 5 m window
    obstacle_range: float = 3.0  # m, A.17
    raytrace_range: float = 3.5  # m, A.17 3.0; a little beyond obstacle_range, as usual
    inflation_radius: float = 0.7
    cost_scaling_factor: float = 10.0
    max_vel_x: float = 0.8
    acc_lim_x: float = 0.8
    max_vel_theta: float = 0.8
    acc_lim_theta: float = 1.5  # rad/s^2, A.17
    occdist_scale: float = 0.01
    in_place_turn_rate: float = 0.5  # rad/s when turning to the goal's heading
    people_horizon: float = 3.0  # s: never stop where a tracked person will be this soon
    slow_within: float = 0.3  # m of footprint clearance below which the speed is scaled down
    narrow_speed: float = 0.3  # m/s: the scaled speed's floor
    people_slow_within: float = 2.0  # m from a person below which the speed is scaled down
    people_speed: float = 0.4  # m/s: the speed at touching distance of a person
    forward_prune_distance: float = 2.0  # m of plan handed to DWA (Nav2 DWB's default)
    footprint_padding: float = 0.05  # m round the footprint in DWA's collision check
    range_mark_wall_distance: float = 0.25  # m: sonar/IR marks this near a map wall are it
    range_mark_decay: float = 1.0  # s: time constant of the sonar/IR marks' fading
    scan_mark_wall_distance: float = 0.15  # m: lidar marks this near a map wall are it
    relocalise_patience: float = 10.0  # s of searching for the chair's place when lost
    relocalise_turn: float | None = None  # rad turned on the spot between searches when lost
    back_off_distance: float = 0.3  # m
    back_off_speed: float = 0.15  # m/s
    max_recoveries: int = 4
    people_in_the_way: float = 1.0  # m from the plan's next people_look_ahead m: in the way
    people_look_ahead: float = 3.0  # m of plan ahead where a person blocks the chair's way
    people_patience: float = 20.0  # s a person may keep the way shut before recoveries count
    gap_look_ahead: float = 1.5  # m of plan ahead searched for the gap a recovery closes
    gap_width: float = 1.5  # m: a gap at most this wide may be closed by a recovery
    door_margin: float = 0.15  # m each side beyond the chair's need: narrower is a door
    door_approach: float = 1.0  # m each side of a door's middle followed along its axis
    doubt_after: int = 3  # scans in a row that do not fit the map: drive at narrow_speed
    goal_timeout: float | None = None  # s; None: 60 s + 3 x the plan's length / max_vel_x

    def __post_init__(self) -> None:
        for name, value in vars(self).items():
            if value is None:
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
                    math.isfinite(value) and value > 0):
                raise ValueError(f"NavigatorSettings.{name} must be a finite number > 0, "
                                 f"got {value!r}")


@dataclass(frozen=True)
class Feedback:
    """What the navigator is doing (move_base's feedback, and a little more)."""

    t: float  # s
    phase: str  # "driving", "turning to the goal's heading", "waiting", "backing off", ...
    pose: Pose2D  # the estimate the navigator drives by
    distance_remaining: float  # m along the current plan (inf before the first plan)
    recoveries: int  # since the chair last made progress


class Navigator(BehaviourBase):
    """Drive to goals on a known map (module notes). A behaviour: call it with every frame.

    ``static_map`` is the global costmap's static layer (``LETHAL`` walls, ``FREE_SPACE``
    floor, ``NO_INFORMATION`` unknown) and ``localizer`` the pose estimator; most
    callers build both with :meth:`for_world` or :meth:`for_map`. ``places`` names goals.
    """

    def __init__(self, static_map: Costmap, localizer: MapLocalizer,
                 params: ChairParams | None = None, settings: NavigatorSettings | None = None,
                 places: dict[str, Pose2D] | None = None, allow_unknown: bool = True):
        self.settings = s = settings or NavigatorSettings()
        super().__init__(rate_hz=s.controller_frequency)
        self.params = p = params or default_params()
        self.localizer = localizer
        self.places = dict(places or {})
        # whether a plan may cross unknown cells (global_planner's allow_unknown): yes
        # while a map grows, no on a finished map, where unknown is a wall's shadow or
        # the far side of the building's outer wall, never a way
        self.allow_unknown = bool(allow_unknown)
        self.footprint = chair_footprint(p)
        self.stopping = ClearanceCheck(p)  # what the body's safety filter will stop for
        nav = load_navigation_params()
        local = replace(nav.local_planner, max_vel_x=s.max_vel_x, min_vel_x=0.0,
                        acc_lim_x=s.acc_lim_x, max_vel_theta=s.max_vel_theta,
                        acc_lim_theta=s.acc_lim_theta, occdist_scale=s.occdist_scale)
        self.dwa = DwaPlanner(self.footprint, replace(
            nav, move_base=replace(nav.move_base, controller_frequency=s.controller_frequency)),
            local, padding=s.footprint_padding,
            braking_delay=(self.stopping.reaction_time
                           + s.acc_lim_x / self.stopping.limits.max_jerk))
        # the planner keeps the chair's centre as far from obstacles as DWA's check does
        # (module notes, "one passability")
        self.passing_radius = self.dwa.passing_radius(static_map.resolution)
        self._rays = range_sensor_rays(p)
        self._use_map(static_map)
        self._last_scan_stamp = -math.inf
        self.goal: Pose2D | None = None
        self.path: Path | None = None
        self.local_costmap: Costmap | None = None
        self.feedback: Feedback | None = None
        self._clear_goal_state()

    # ------------------------------------------------------------------ building
    @classmethod
    def for_world(cls, world: World, start: Pose2D | str | None = None,
                  params: ChairParams | None = None, ekf: ChairEkf | None = None,
                  settings: NavigatorSettings | None = None) -> Navigator:
        """A navigator on a simulated world's walls (the map a survey would draw),
        starting at ``start`` (a pose or a place name; default the world's start), its
        localiser's filter ``ekf`` (default: nominal odometry from ``start``)."""
        settings = settings or NavigatorSettings()
        start_pose = _place(world.places, start if start is not None else "start")
        static = Costmap.from_walls(world.walls, settings.resolution)
        localizer = MapLocalizer(wall_points(world.walls), start_pose, params, ekf=ekf)
        return cls(static, localizer, params, settings, places=world.places)

    @classmethod
    def for_map(cls, cells: np.ndarray, grid: GridGeometry, start: Pose2D,
                params: ChairParams | None = None, ekf: ChairEkf | None = None,
                settings: NavigatorSettings | None = None) -> Navigator:
        """A navigator on a built map: trinary ``cells`` (a map file's, or
        ``OccupancyGrid.trinary()``) on ``grid``, starting at ``start``. The map is
        finished: no plan crosses its unknown cells."""
        static = Costmap.like(grid)
        static.add_static(cells)
        localizer = MapLocalizer(occupied_points(cells, grid), start, params, ekf=ekf)
        return cls(static, localizer, params, settings, allow_unknown=False)

    def replace_map(self, static_map: Costmap) -> None:
        """Drive on ``static_map`` from now on (a map that grows as the chair explores):
        the global costmap, the people tracker's walls, the range layer and the wall
        distances follow it; the goal stays and is planned again at the next decision.
        The localiser keeps its own map (see :meth:`MapLocalizer.replace_map`)."""
        self._use_map(static_map)
        self._next_plan = -math.inf

    def _use_map(self, static_map: Costmap) -> None:
        """Everything the navigator derives from its static map."""
        self.static_map = static_map
        # the local windows on the map's own cells where they can be (same resolution,
        # axis-aligned): else each window cell straddles map cells (Costmap.rolling_window)
        self._lattice = window_lattice(static_map, self.settings.resolution)
        self.global_costmap = self._inflated(static_map.cost.copy(), static_map)
        self._map_costmap = self.global_costmap  # without what avoid() added for a goal
        self.avoided = np.zeros(static_map.shape, dtype=bool)  # cells avoid() made walls
        self.people = PeopleTracker(static_map.cost == LETHAL, static_map)
        self.range_layer = RangeSensorLayer(static_map)
        self._range_stamp: float | None = None
        self._inscribed_costmap: Costmap | None = None  # built when a plan fails
        # m from each map cell to the nearest wall: range marks this near are the wall's
        self._wall_distance = ndimage.distance_transform_edt(
            static_map.cost != LETHAL) * static_map.resolution

    # ------------------------------------------------------------------ goals
    def go_to(self, goal: Pose2D | tuple[float, ...] | str) -> None:
        """Start driving to ``goal``: a Pose2D, an ``(x, y)`` (any heading will do), an
        ``(x, y, theta)``, or a place name. A goal off the map, in a wall, or that no
        path reaches makes the navigator fail at once, saying which."""
        goal_pose = _place(self.places, goal)
        self.reset()
        self._clear_goal_state()
        self.global_costmap = self._map_costmap  # what avoid() added was for the last goal
        self.avoided = np.zeros(self.static_map.shape, dtype=bool)
        self.goal = goal_pose
        self._keep_heading = not (isinstance(goal, tuple) and len(goal) == 2)
        gx, gy = self.goal.x, self.goal.y
        rows, cols = self.global_costmap.world_to_cell(np.array([[gx, gy]]))
        if not self.global_costmap.contains(rows[0], cols[0]):
            self.fail(f"the goal ({gx:.2f}, {gy:.2f}) m is off the map")
            return
        cost = int(self.global_costmap.cost[rows[0], cols[0]])
        if cost == LETHAL or cost == NO_INFORMATION:
            where = "inside a wall" if cost == LETHAL else "on unknown ground"
            self.fail(f"the goal ({gx:.2f}, {gy:.2f}) m is {where}")
            return
        if cost >= LETHAL - 1:
            self.fail(f"the goal ({gx:.2f}, {gy:.2f}) m is too close to a wall for the "
                      f"chair (closer than the {self.passing_radius:.2f} m its centre keeps "
                      f"from walls)")
            return
        self._replan(self.localizer.pose, math.nan)

    def cancel(self) -> None:
        """Stop driving to the goal (status failed, reason "cancelled")."""
        super().cancel()

    def seen_off_map(self) -> np.ndarray:
        """(height, width) bool on the static map: the cells the newest scan marks
        farther than ``range_mark_wall_distance`` from the map's walls (nearer, they are
        the wall's own echo), the tracked people's discs (and 0.3 m round them) left out:
        what blocks the way that the map does not have (all False before a decision)."""
        if self.local_costmap is None:
            return np.zeros(self.static_map.shape, dtype=bool)
        marks = (self._seen_on_map(self.local_costmap)
                 & (self._wall_distance > self.settings.range_mark_wall_distance))
        rows, cols = np.nonzero(marks)
        if rows.size and len(discs := self.people.moving_discs()):
            centres = self.static_map.cell_to_world(rows, cols)
            gaps = np.hypot(centres[:, None, 0] - discs[None, :, 0],
                            centres[:, None, 1] - discs[None, :, 1]) - discs[None, :, 4]
            person = (gaps <= 0.3).any(axis=1)
            marks[rows[person], cols[person]] = False
        return marks

    def avoid(self, marks: np.ndarray) -> int:
        """Treat the ``marks`` cells ((height, width) bool on the static map) as walls
        until the next goal: what the newest scan alone marks is forgotten once the chair
        turns away, and a way blocked by it would be planned again as soon as it is out
        of sight. Returns how many cells were new; if any, the plan is made again at the
        next decision."""
        marks = np.asarray(marks, dtype=bool)
        if marks.shape != self.static_map.shape:
            raise ValueError(f"marks must be a bool array of the static map's shape "
                             f"{self.static_map.shape}, got {marks.shape}")
        new = marks & (self.static_map.cost != LETHAL) & ~self.avoided
        if not new.any():
            return 0
        self.avoided |= new
        self.global_costmap = self._with_obstacles(new)
        self._next_plan = -math.inf
        self._blocked_at = None
        self._phase = "planning round what blocks the way"
        return int(new.sum())

    # ------------------------------------------------------------------ per frame
    def observe(self, frame: SensorFrame) -> None:
        """Every frame: the localiser integrates the wheels and gyro and matches scans;
        each new scan updates the people's tracks."""
        self.localizer.observe(frame)
        scan = frame.readings.get(LIDAR_FRAME)
        if isinstance(scan, LaserScan) and scan.stamp > self._last_scan_stamp:
            self._last_scan_stamp = scan.stamp
            sensor = compose(self.localizer.pose, self.params.lidar.mount)
            self.people.update(scan, sensor, scan.stamp)

    def __call__(self, frame: SensorFrame) -> Twist:
        command = super().__call__(frame)
        pose = self.localizer.pose
        self.feedback = Feedback(frame.t, self._phase if self.running else self.status.value,
                                 pose, self._distance_remaining(pose), self._recoveries)
        return command  # type: ignore[return-value]

    def update(self, frame: SensorFrame) -> Twist:
        """One decision (at ``controller_frequency``)."""
        if self.goal is None:
            self.fail("no goal: call go_to(goal) first")
            return Twist(0.0, 0.0)
        if self._started is None:
            self._started = frame.t
            self._anchor = (frame.t, self.localizer.pose)
        s, pose = self.settings, self.localizer.pose
        if frame.t - self._started > self._timeout:
            self.fail(f"out of time: {self._timeout:.0f} s without reaching the goal")
            return Twist(0.0, 0.0)
        if self.localizer.lost:
            return self._relocalise(frame)
        self._lost_since = None

        if math.hypot(self.goal.x - pose.x, self.goal.y - pose.y) <= s.xy_goal_tolerance:
            return self._turn_to_goal_heading(pose)

        self.local_costmap = local = self._build_local_costmap(frame, pose)
        if self._recovery is not None:
            return self._recover(frame, pose)
        if frame.t >= self._next_plan or (self._people_moving() and
                                           frame.t >= self._next_plan - 0.5 / s.planner_frequency):
            self._replan(pose, frame.t, local)
            if not self.running:
                return Twist(0.0, 0.0)
        if self.path is None:
            return Twist(0.0, 0.0)
        pruned = self._path_ahead(pose, within=s.forward_prune_distance)
        # people are those seen walking; a track that never walked is a thing the map
        # lacks (a door frame a self-made map drew short), and its returns are in the
        # local costmap as any obstacle's: kept out of, not given a person's berth
        result = self.dwa.plan(local, pose, self.localizer.velocity, pruned,
                               self.people.moving_discs(walked_only=True), s.people_horizon)
        no_progress = self._oscillating(frame.t, pose)
        if result.evading and not no_progress:
            self._phase = "keeping out of a person's way"
            return result.command
        # evading that gets nowhere for oscillation_timeout s is being stuck, too: a
        # person who stands in a doorway would keep the chair out of her way for ever
        if not result.stuck and not no_progress:
            self._phase = "driving"
            if self._blocked_at is not None and math.hypot(
                    pose.x - self._blocked_at[1].x, pose.y - self._blocked_at[1].y
            ) > s.oscillation_distance:
                self._blocked_at = None  # it got away from where it was blocked
            return self._slowed_for_the_goal(self._regulated(result, pose), pose)
        return self._blocked(frame, pose)

    def _relocalise(self, frame: SensorFrame) -> Twist:
        """Lost: stand still and search round the estimate for where the scan fits the
        map (:meth:`MapLocalizer.recover`), once a second; with ``relocalise_turn`` set,
        after each search that finds nothing, once the chair stands, turn that far on
        the spot (left) where the
        newest scan shows room for it, so the next search sees other walls (a corridor
        that fits many places along it, a person hiding the walls). Fail after
        ``relocalise_patience`` s without a place."""
        s = self.settings
        if self._lost_since is None:
            self._lost_since, self._next_search = frame.t, frame.t
            self._turn_until = -math.inf
        if frame.t < self._turn_until:
            self._phase = "turning to re-localise"
            return Twist(0.0, s.in_place_turn_rate)
        self._phase = "relocalising"
        scan = frame.readings.get(self.localizer.scan_frame)
        if frame.t >= self._next_search and isinstance(scan, LaserScan):
            self._next_search = frame.t + 1.0
            if self.localizer.recover(scan):
                self._lost_since = None
                self._next_plan = -math.inf  # plan again from where the chair really is
                self._anchor = (frame.t, self.localizer.pose)
                return Twist(0.0, 0.0)
            standing = abs(self.localizer.velocity[0]) < 0.05  # stop first, then turn
            if (s.relocalise_turn is not None and standing
                    and self._room_to_turn(frame, s.relocalise_turn)):
                self._turn_until = frame.t + s.relocalise_turn / s.in_place_turn_rate
                # search again once the turn is done and a scan has been taken standing
                self._next_search = self._turn_until + 0.5
        if frame.t - self._lost_since > s.relocalise_patience:
            turning = ", turning on the spot" if s.relocalise_turn is not None else ""
            self.fail("lost: the scans no longer fit the map where the chair thinks it is, "
                      f"and no place within reach fits them either "
                      f"({s.relocalise_patience:.0f} s of searching{turning})")
        return Twist(0.0, 0.0)

    def _room_to_turn(self, frame: SensorFrame, angle: float) -> bool:
        """Whether the footprint turned by up to ``angle`` (rad, left) stays off what the
        newest lidar scan sees. The scan alone, laid round the chair: while lost, the
        map's walls are not where the estimate would put them."""
        s, pose = self.settings, self.localizer.pose
        scan = frame.readings.get(LIDAR_FRAME)
        if not isinstance(scan, LaserScan):
            return False
        around = Costmap.rolling_window(pose, s.local_size, s.resolution, default=FREE_SPACE,
                                        lattice=self._lattice)
        around.add_scan(scan, compose(pose, self.params.lidar.mount), s.obstacle_range,
                        s.raytrace_range)
        return all(footprint_cost(around, self.footprint,
                                  compose(pose, (0.0, 0.0, angle * k / 4))) < LETHAL
                   for k in range(1, 5))

    def _regulated(self, result: DwaResult, pose: Pose2D) -> Twist:
        """DWA's command, slowed along its own arc (the same curvature, so on the way it
        checked) near obstacles and near people:

        * within ``slow_within`` m of what the footprint may not come nearer, to at most
          ``max_vel_x * gap / slow_within``, and not below ``narrow_speed`` (Nav2's
          Regulated Pure Pursuit, "cost-regulated velocity scaling": Macenski et al.,
          "Regulated pure pursuit for robot path tracking", Autonomous Robots 47, 2023).
          Through a door the chair has a few centimetres on each side: slowly, DWA has
          more cycles to line it up, and a stop is short;
        * within ``people_slow_within`` m of a tracked person (the covering circles to
          their body, as they stand), from ``max_vel_x`` down to ``people_speed`` at
          touching distance, as human-aware navigation slows near people (Kruse et al.,
          "Human-aware robot navigation: a survey", Robotics and Autonomous Systems
          61(12), 2013). A person who sees the chair coming may stop in its way, which
          no prediction at constant velocity foresees; at a walking-beside speed the
          chair still stops short. Only people seen walking count: a track that never
          walked is a post, and the gap above already holds it;
        * at ``narrow_speed`` while the localiser's last ``doubt_after`` scans in a row
          did not fit the map (beams through its walls): a chair carried or slipped off
          its place drives on by a wrong estimate until the localiser says lost, and the
          slower it goes the nearer it stays to where its search looks."""
        s, command = self.settings, result.command
        cap = max(s.narrow_speed, s.max_vel_x * max(result.gap, 0.0) / s.slow_within)
        near_door = min((math.hypot(pose.x - door.x, pose.y - door.y) for door in self.doors),
                        default=math.inf)
        if near_door < 2 * s.door_approach:  # door mode: slowly, to line up, from a
            # door_approach out (where the axis begins), at narrow_speed inside it
            cap = min(cap, s.narrow_speed + (s.max_vel_x - s.narrow_speed)
                      * max(near_door / s.door_approach - 1.0, 0.0))
        discs = self.people.moving_discs(walked_only=True)
        if len(discs):
            near = float(self.dwa.people_gap(pose, np.zeros((1, 2)), standing_still(discs),
                                             0.0)[0])
            cap = min(cap, s.people_speed + (s.max_vel_x - s.people_speed)
                      * min(max(near, 0.0) / s.people_slow_within, 1.0))
        if self.localizer.rejected_in_a_row >= s.doubt_after:
            # scans refused with beams through the map's walls: the estimate is in doubt
            # (a chair carried off its place, or slipped), so slowly until it is settled
            cap = min(cap, s.narrow_speed)
        if command.v <= cap:
            return command
        return Twist(cap, command.w * cap / command.v)

    def _slowed_for_the_goal(self, command: Twist, pose: Pose2D) -> Twist:
        """At most the speed from which braking at half ``acc_lim_x`` stops the chair
        half-way into the goal tolerance: it arrives, rather than passes through."""
        s = self.settings
        distance = math.hypot(self.goal.x - pose.x, self.goal.y - pose.y)  # type: ignore[union-attr]
        cap = math.sqrt(s.acc_lim_x * max(distance - s.xy_goal_tolerance / 2, 0.0))
        return Twist(min(command.v, cap), command.w) if command.v > cap else command

    # ------------------------------------------------------------------ the parts
    def _clear_goal_state(self) -> None:
        self._lost_since: float | None = None
        self._turn_until = -math.inf
        self._next_search = -math.inf
        self._started: float | None = None
        self._timeout = math.inf
        self._next_plan = -math.inf
        self._plan_failing_since: float | None = None
        self._blocked_at: tuple[float, Pose2D] | None = None  # since when, and where it stood
        self._recovery: tuple[str, float, Pose2D] | None = None
        self._recoveries = 0
        self._people_wait_since: float | None = None  # blocked by people since, s
        self._stuck_at = math.inf  # m to go (_to_go) when the first recovery began
        self._closed: list[Gap] = []  # gaps closed by a recovery, for this goal
        self._only_way: Gap | None = None  # a gap the chair is stuck at with no way round
        self.recoveries_used: dict[str, int] = {}  # this goal's recoveries, by kind
        self._best_remaining = math.inf  # m to go (_to_go) at the last progress
        self._to_goal: np.ndarray | None = None  # m to go from every cell
        self.doors: list[Gap] = []  # the narrow doors on the plan (door mode)
        self._lined_up: list[Gap] = []  # gaps a recovery put in door mode, for this goal
        self._anchor: tuple[float, Pose2D] | None = None
        self._phase = "planning"
        self._keep_heading = True
        self.path = None

    def _inflated(self, cost: np.ndarray, grid: GridGeometry,
                  keep_out: bool = True) -> Costmap:
        """``cost`` inflated; with ``keep_out`` the centre is kept ``passing_radius`` m
        from obstacles (the planner's map), else only the inscribed radius (costmap_2d's
        rule, which names the gap a refused plan would have squeezed through)."""
        costmap = Costmap.like(grid)
        costmap.cost = cost
        costmap.inflate(self.footprint.inscribed_radius, self.settings.inflation_radius,
                        self.settings.cost_scaling_factor,
                        keep_out_radius=self.passing_radius if keep_out else 0.0)
        return costmap

    def _with_obstacles(self, marks: np.ndarray) -> Costmap:
        """The global costmap with the ``marks`` cells lethal and inflated: only the box
        they span (plus the inflation radius) is inflated again."""
        grid, reach = self.static_map, math.ceil(self.settings.inflation_radius
                                                 / self.static_map.resolution) + 1
        rows, cols = np.nonzero(marks)
        r0, r1 = max(rows.min() - reach, 0), min(rows.max() + reach + 1, grid.height)
        c0, c1 = max(cols.min() - reach, 0), min(cols.max() + reach + 1, grid.width)
        box = np.s_[r0:r1, c0:c1]
        patch = Costmap(grid.resolution, c1 - c0, r1 - r0, grid.origin)  # cells alone matter
        patch.cost = np.where(marks[box], LETHAL, grid.cost[box]).astype(np.uint8)
        patch.inflate(self.footprint.inscribed_radius, self.settings.inflation_radius,
                      self.settings.cost_scaling_factor, keep_out_radius=self.passing_radius)
        costmap = Costmap.like(grid)
        costmap.cost = self.global_costmap.cost.copy()
        costmap.cost[box] = np.maximum(costmap.cost[box], patch.cost)
        return costmap

    def _build_local_costmap(self, frame: SensorFrame, pose: Pose2D) -> Costmap:
        """The rolling window: the static map's cells under it, the newest scan's returns
        marked (and its beams cleared), then inflation. As costmap_2d's layers combine
        (``updateWithMax``), what the scan saw overrides the map's *unknown* cells: a
        speck the survey never saw (a walker stood in the lidar's way while it mapped)
        is free where the scan's beams now cross it, instead of a wall no plan knows of."""
        s = self.settings
        local = Costmap.rolling_window(pose, s.local_size, s.resolution,
                                       default=NO_INFORMATION, lattice=self._lattice)
        rows, cols = np.indices(local.shape)
        centres = local.cell_to_world(rows.ravel(), cols.ravel())
        g_rows, g_cols = self.static_map.world_to_cell(centres)
        on_map = self.static_map.contains(g_rows, g_cols)
        static = np.full(local.shape[0] * local.shape[1], NO_INFORMATION, dtype=np.uint8)
        static[on_map] = self.static_map.cost[g_rows[on_map], g_cols[on_map]]
        static = static.reshape(local.shape)
        scan = frame.readings.get(LIDAR_FRAME)
        if isinstance(scan, LaserScan):
            sensor = compose(pose, self.params.lidar.mount)
            local.add_scan(scan, sensor, s.obstacle_range, s.raytrace_range)
        self._seen = local.cost == LETHAL  # what the scan marks, walls included
        seen = local.cost != NO_INFORMATION
        known = np.where(static == NO_INFORMATION, FREE_SPACE, static)
        local.cost = np.where(seen, np.maximum(local.cost, known), static)
        self._add_range_marks(frame, pose, local)
        local.inflate(self.footprint.inscribed_radius, s.inflation_radius,
                      s.cost_scaling_factor)
        return local

    def _add_range_marks(self, frame: SensorFrame, pose: Pose2D, local: Costmap) -> None:
        """The sonar's and IR rangers' readings into the range sensor layer, and its marks
        into the local costmap, except those the map explains (within the echo's zone of
        a wall: a sonar cone's arc spreads a wall's echo across a doorway)."""
        if self._range_stamp is not None:
            self.range_layer.decay(frame.t - self._range_stamp, self.settings.range_mark_decay)
        self._range_stamp = frame.t
        self.range_layer.add_frame(frame, pose, self._rays)
        marks = Costmap.like(local, default=FREE_SPACE)
        self.range_layer.update_costs(marks)
        rows, cols = np.nonzero(marks.cost == LETHAL)
        if not rows.size:
            return
        g_rows, g_cols = self.static_map.world_to_cell(local.cell_to_world(rows, cols))
        on_map = self.static_map.contains(g_rows, g_cols)
        near_wall = np.zeros(rows.size, dtype=bool)
        near_wall[on_map] = (self._wall_distance[g_rows[on_map], g_cols[on_map]]
                             <= self.settings.range_mark_wall_distance)
        local.cost[rows[~near_wall], cols[~near_wall]] = LETHAL

    def _replan(self, pose: Pose2D, now: float, local: Costmap | None = None) -> None:
        """A new global plan from ``pose``, around what the newest scan saw."""
        s = self.settings
        self._next_plan = (now if math.isfinite(now) else -math.inf) + 1.0 / s.planner_frequency
        costmap = self.global_costmap
        if local is not None:
            marks = self._seen_on_map(local)
            # where people will walk: the plan goes round it, not into their way
            marks |= predicted_sweep(self.people.moving_discs(), self.static_map,
                                     s.people_horizon)
            # a return this near a mapped wall is the wall (the estimate's few cm): marked
            # beside it, it would narrow every door by a cell
            marks &= self._wall_distance > s.scan_mark_wall_distance
            if marks.any():
                costmap = self._with_obstacles(marks)
        # what the scan sees may be people in a doorway: if it blocks every way, plan on
        # the map alone and let the local planner wait for them to pass
        found, reason = None, ""
        for candidate in dict.fromkeys([costmap, self.global_costmap]):
            try:
                found, costmap = self._plan_on(candidate, pose), candidate
                break
            except NoPathError as error:
                reason = str(error)
        if found is None:
            if local is None:  # the first plan: the goal cannot be reached from here
                self.fail(self._no_way(pose, reason))
                return
            if self._plan_failing_since is None:
                self._plan_failing_since = now
            if now - self._plan_failing_since > s.planner_patience:
                self.fail(f"{self._no_way(pose, reason)} (for "
                          f"{now - self._plan_failing_since:.0f} s)")
            return
        self._plan_failing_since = None
        # followed as planned (see NavigatorSettings on smoothing), but straight along
        # the axis of every narrow door
        self.path = self._through_doors(found, costmap)
        if self._to_goal is None:  # the progress check's measure, for this goal
            self._to_goal = costs_to_goal(self._closed_map(self.global_costmap), self.goal,
                                          allow_unknown=self.allow_unknown)
        if not math.isfinite(self._timeout):
            self._timeout = (self.settings.goal_timeout if self.settings.goal_timeout
                             else 60.0 + 3.0 * self.path.length / s.max_vel_x)

    def _seen_on_map(self, local: Costmap) -> np.ndarray:
        """The newest scan's marks in ``local`` as cells of the static map (walls too)."""
        marks = np.zeros(self.static_map.shape, dtype=bool)
        rows, cols = np.nonzero(self._seen)
        g_rows, g_cols = self.static_map.world_to_cell(local.cell_to_world(rows, cols))
        inside = self.static_map.contains(g_rows, g_cols)
        marks[g_rows[inside], g_cols[inside]] = True
        return marks

    def _people_moving(self) -> bool:
        """Whether a tracked person is walking: then the plan is renewed twice as often."""
        discs = self.people.moving_discs()
        return bool(len(discs)) and bool((np.hypot(discs[:, 2], discs[:, 3]) > 0.2).any())

    def _plan_on(self, costmap: Costmap, pose: Pose2D) -> Path:
        costmap = self._closed_map(costmap)
        return plan(costmap, _free_start(costmap, pose), self.goal,
                    allow_unknown=self.allow_unknown)

    def _closed_map(self, costmap: Costmap) -> Costmap:
        """``costmap`` with the gaps a recovery closed shut."""
        for gap in self._closed:
            costmap = close_gap(costmap, gap)
        return costmap

    def _to_go(self, pose: Pose2D) -> float:
        """m (free floor metres) of the least way from the chair to the goal on the
        planner's map: the progress check's measure, which does not change with the
        plan (a plan that flips between two ways would otherwise reset it)."""
        if self._to_goal is None:
            return math.inf
        x, y = _free_start(self.global_costmap, pose)
        rows, cols = self.global_costmap.world_to_cell(np.array([[x, y]]))
        if not self.global_costmap.contains(rows[0], cols[0]):
            return math.inf
        return float(self._to_goal[rows[0], cols[0]])

    def _no_way(self, pose: Pose2D, reason: str) -> str:
        """Why no plan keeps the chair's centre ``passing_radius`` from walls: the gap the
        way would have to squeeze through, found by planning with only the inscribed
        circle kept out (costmap_2d's rule), or the planner's own ``reason``."""
        if self._inscribed_costmap is None:
            self._inscribed_costmap = self._inflated(self.static_map.cost.copy(),
                                                     self.static_map, keep_out=False)
        refused = ", ".join(gap.describe() for gap in self._closed)
        refused = (f"the chair found no safe way through {refused} "
                   f"({self._recoveries} recoveries)" if refused else "")
        try:
            squeezed = self._plan_on(self._inscribed_costmap, pose)
        except NoPathError:
            if refused:
                return f"no passable way to the goal: {refused}, and no other way leads there"
            return f"no path to the goal: {reason}"
        gap = narrowest_gap(self.static_map, squeezed.cells, self.passing_radius)
        needs = minimum_clear_width(self.passing_radius)
        if gap is None:
            narrow = (f"the only way passes closer to a wall than the "
                      f"{self.passing_radius:.2f} m the chair's centre keeps")
        elif gap.width < needs:
            narrow = f"{gap.describe()} is narrower than the chair needs, {needs:.2f} m"
        else:
            # wide enough across, but the map's cells cross it at an angle, and none of
            # them lies the passing radius from both of its sides
            narrow = (f"{gap.describe()} has no cell of the map {self.passing_radius:.2f} m "
                      f"from both its sides, as the chair's centre needs (a gap at an "
                      f"angle to the map's {self.static_map.resolution:.2f} m cells may "
                      f"need a few cm more than {needs:.2f} m)")
        if refused:
            return f"no passable way to the goal: {refused}, and the other way: {narrow}"
        return f"no {'passable way' if gap else 'path'} to the goal: {narrow}"

    def _through_doors(self, path: Path, costmap: Costmap) -> Path:
        """Door mode: where the path goes through a gap less than ``door_margin`` m each
        side wider than the chair needs, the path within ``door_approach`` m of the
        gap's middle is replaced by the gap's axis, so that the chair lines up with the
        opening before it enters and follows its centre line through (as a person
        pushing a wheelchair does; the last metre of Nav2's docking approach). Each side
        of the axis is cut short where it would leave the planner's free cells."""
        s = self.settings
        narrow = minimum_clear_width(self.passing_radius) + 2 * s.door_margin
        doors = [g for g in gaps_along(self.static_map, path.cells, self._wall_distance,
                                       narrow / 2) if g.width < narrow]
        for gap in self._lined_up:  # wider on the map, but the chair could not get in
            if (np.hypot(*(path.points - (gap.x, gap.y)).T).min() < s.door_approach
                    and not any(_same_gap(gap, door) for door in doors)):
                doors.append(gap)
        doors.sort(key=lambda g: int(np.argmin(np.hypot(*(path.points - (g.x, g.y)).T))))
        self.doors = doors
        points = path.points
        for door in doors:
            across = np.array([math.cos(door.across), math.sin(door.across)])
            centre = self._centred_in_view(np.array([door.x, door.y]), across)
            unit = np.array([-across[1], across[0]])
            distance = np.hypot(*(points - centre).T)
            k = int(np.argmin(distance))
            outside = distance > s.door_approach
            i0 = int(np.flatnonzero(outside[:k])[-1]) if outside[:k].any() else 0
            i1 = k + int(np.flatnonzero(outside[k:])[0]) if outside[k:].any() else len(points) - 1
            if (points[i1] - points[i0]) @ unit < 0:  # the axis the way the path goes
                unit = -unit
            before = self._free_along(costmap, centre, -unit)
            after = self._free_along(costmap, centre, unit)
            if i0 == 0:  # the path starts near the door: the axis from level with it
                before = min(before, max(-float((points[0] - centre) @ unit), 0.0))
            if i1 == len(points) - 1:  # and ends near it: the axis up to level with its end
                after = min(after, max(float((points[-1] - centre) @ unit), 0.0))
            along = np.arange(-before, after + s.resolution / 2, s.resolution)
            points = np.concatenate([points[:i0 + 1], centre + along[:, None] * unit,
                                     points[i1:]])
        if not doors:
            return path
        rows, cols = self.static_map.world_to_cell(points)
        return Path(np.column_stack([rows, cols]), points, path.cost)

    def _centred_in_view(self, centre: np.ndarray, across: np.ndarray,
                         reach: float = 0.3) -> np.ndarray:
        """``centre`` moved up to ``reach`` m along ``across`` (a unit vector from one
        side of a door to the other) to the point farthest from both sides as the local
        costmap sees them now: a map the chair made itself may place a door's frame a
        cell or more off (scans graze it), and the lidar sees where it truly is."""
        local = self.local_costmap
        if local is None:
            return centre
        offsets = np.arange(-reach, reach + local.resolution / 2, local.resolution)
        points = centre + offsets[:, None] * across
        rows, cols = local.world_to_cell(points)
        if not local.contains(rows, cols).all():
            return centre
        clearance = ndimage.distance_transform_edt(local.cost != LETHAL)[rows, cols]
        best = np.flatnonzero(clearance == clearance.max())
        return points[best[np.argmin(np.abs(offsets[best]))]]

    def _free_along(self, costmap: Costmap, centre: np.ndarray, unit: np.ndarray) -> float:
        """m from ``centre`` along ``unit`` (up to ``door_approach``) over cells the
        planner may cross."""
        s = self.settings
        steps = np.arange(0.0, s.door_approach + s.resolution / 2, s.resolution)
        rows, cols = costmap.world_to_cell(centre + steps[:, None] * unit)
        inside = costmap.contains(rows, cols)
        free = np.zeros(len(steps), dtype=bool)
        free[inside] = costmap.cost[rows[inside], cols[inside]] < INSCRIBED
        blocked = np.flatnonzero(~free)
        return float(steps[blocked[0] - 1]) if blocked.size and blocked[0] > 0 else (
            0.0 if blocked.size else float(steps[-1]))

    def _gap_ahead(self, pose: Pose2D) -> Gap | None:
        """The narrowest gap on the map the plan passes within ``gap_look_ahead`` m."""
        if self.path is None:
            return None
        ahead = self._path_ahead(pose, within=self.settings.gap_look_ahead)
        rows, cols = self.static_map.world_to_cell(ahead)
        inside = self.static_map.contains(rows, cols)
        cells = np.column_stack([rows[inside], cols[inside]])
        gap = narrowest_gap(self.static_map, cells, self.settings.gap_width / 2)
        return gap if gap is not None and gap.width <= self.settings.gap_width else None

    def _path_ahead(self, pose: Pose2D, within: float = math.inf) -> np.ndarray:
        """The plan from its point nearest the chair on, as points every resolution, up
        to ``within`` m along it."""
        points = densify_polyline(self.path.points, self.settings.resolution)  # type: ignore[union-attr]
        nearest = int(np.argmin(np.hypot(points[:, 0] - pose.x, points[:, 1] - pose.y)))
        ahead = points[nearest:]
        if math.isinf(within):
            return ahead
        along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(ahead, axis=0).T))])
        return ahead[along <= within]

    def _distance_remaining(self, pose: Pose2D) -> float:
        if self.path is None:
            return math.inf
        ahead = self._path_ahead(pose)
        return float(np.hypot(*np.diff(ahead, axis=0).T).sum()
                     + math.hypot(ahead[0, 0] - pose.x, ahead[0, 1] - pose.y))

    def _turn_to_goal_heading(self, pose: Pose2D) -> Twist:
        s = self.settings
        error = float(wrap_angle(self.goal.theta - pose.theta))  # type: ignore[union-attr]
        if not self._keep_heading or abs(error) <= s.yaw_goal_tolerance:
            if abs(self.localizer.velocity[0]) > 0.05:  # arrived means standing there
                self._phase = "stopping at the goal"
                return Twist(0.0, 0.0)
            self._phase = "arrived"
            self.succeed()
            return Twist(0.0, 0.0)
        self._phase = "turning to the goal's heading"
        return Twist(0.0, math.copysign(min(s.in_place_turn_rate, 2.0 * abs(error)), error))

    def _oscillating(self, now: float, pose: Pose2D) -> bool:
        """The progress check (move_base's oscillation check, Nav2's progress checker),
        judged by the way left to the goal (:meth:`_to_go`), not by moving: no progress
        when it has not fallen ``oscillation_distance`` below its best in
        ``oscillation_timeout`` s (a chair that circles in front of a door moves all the
        time, and gets nowhere). The recovery count resets only when the chair gets
        ``oscillation_distance`` nearer than where its first recovery began: backing off
        from a gap and driving up to it again is not progress."""
        t0, _ = self._anchor  # type: ignore[misc]
        s = self.settings
        remaining = self._to_go(pose)
        if remaining < self._best_remaining - s.oscillation_distance:
            self._anchor, self._best_remaining = (now, pose), remaining
            if remaining < self._stuck_at - s.oscillation_distance:
                self._recoveries, self._stuck_at, self._only_way = 0, math.inf, None
            self._people_wait_since = None
            return False
        return now - t0 > s.oscillation_timeout

    def _blocked(self, frame: SensorFrame, pose: Pose2D) -> Twist:
        """No safe trajectory (or no progress): wait for the way to clear, then recover."""
        s = self.settings
        if self._blocked_at is None:
            self._blocked_at = (frame.t, pose)
            self._next_plan = frame.t  # plan round what blocks it at the next decision
        if frame.t - self._blocked_at[0] < s.controller_patience:
            self._phase = "waiting for the way to clear"
            return Twist(0.0, 0.0)
        people = self._person_in_the_way(pose)
        if not people:
            self._people_wait_since = None
        elif self._people_wait_since is None:
            self._people_wait_since = frame.t
        if people and frame.t - self._people_wait_since < s.people_patience:
            # people move: a way they shut is no proof that it is too narrow, so waiting
            # for them is no recovery (a walker in the simulator, as a person, turns back
            # within seconds); after people_patience s of it, a recovery makes room
            self._phase = "waiting for people to pass"
            self._anchor = (frame.t, pose)  # no progress is owed while they pass
            return Twist(0.0, 0.0)
        self._people_wait_since = None  # the next recovery, too, only after a wait
        if self._recoveries >= s.max_recoveries:
            if people:
                self.fail(f"blocked by people: they kept the way shut through "
                          f"{self._recoveries} recoveries")
                return Twist(0.0, 0.0)
            if self._only_way is not None:
                return self._no_way_through(self._only_way)
            gap = self._gap_ahead(pose)
            where = f" at {gap.describe()}" if gap else ""
            self.fail(f"stuck{where}: no safe way on after {self._recoveries} recoveries")
            return Twist(0.0, 0.0)
        self._recoveries += 1
        self._blocked_at = None
        self._anchor = (frame.t, pose)
        self._stuck_at = min(self._stuck_at, self._to_go(pose))
        if self._recoveries == 2:  # the second: forget what the rangers marked, re-plan
            self._used("clearing the local costmap")
            self.range_layer = RangeSensorLayer(self.static_map)
            self._next_plan = frame.t
            return Twist(0.0, 0.0)
        gap = self._gap_ahead(pose) if self._recoveries >= 3 else None
        if gap is not None and not any(_same_gap(gap, door) for door in self.doors) \
                and gap.width >= minimum_clear_width(self.passing_radius):
            # a gap the map says the chair fits, entered askew: line up on its axis
            # (door mode for it) and try again before giving it up
            self._used("lining up with the gap")
            self._lined_up.append(gap)
            self._replan(pose, frame.t)
            gap = None
        elif gap is not None and self._way_round(gap, pose):
            # the gap ahead (in door mode, and still refused) is closed, and the plan
            # goes round it
            self._used("closing the gap ahead")
            self._closed.append(gap)
            self._to_goal = None  # measured again on the map with the gap shut
            self._replan(pose, frame.t)
            if self.running:  # a new way: progress and the count are measured along it
                self._best_remaining = self._stuck_at = self._to_go(pose)
            return Twist(0.0, 0.0)
        if gap is not None:  # the only way: keep trying it while people are in it
            self._only_way = gap
            if not people:
                # refused in door mode after a back-off and a cleared costmap, with no way
                # round and nobody in it who might move: another try would find the same
                return self._no_way_through(gap)
        behind, _ = self.stopping.clearance(frame, forward=False)
        back = compose(pose, (-s.back_off_distance, 0.0, 0.0))
        if (behind > s.back_off_distance + self.stopping.braking_distance(s.back_off_speed)
                and self._footprint_free([back])):
            self._recovery = ("backing off", frame.t, pose)
        elif self._footprint_free([compose(pose, (0.0, 0.0, side * k * math.pi / 12))
                                   for k in range(1, 7) for side in (1, -1)]):
            self._recovery = ("turning on the spot", frame.t, pose)
        else:  # no room to move: keep waiting, which counts as a try
            self._phase = "waiting: no room to back off or turn"
            self._used("waiting")
            return Twist(0.0, 0.0)
        self._used(self._recovery[0])
        return self._recover(frame, pose)

    def _no_way_through(self, gap: Gap) -> Twist:
        """Fail: ``gap`` is the only way, and the chair found no safe way through it."""
        self.fail(f"no passable way to the goal: the chair found no safe way through "
                  f"{gap.describe()} ({self._recoveries} recoveries), and no other way "
                  f"leads there")
        return Twist(0.0, 0.0)

    def _person_in_the_way(self, pose: Pose2D) -> bool:
        """Whether a tracked person (one seen walking: :meth:`PeopleTracker.walkers`)
        stands or walks within ``people_in_the_way`` m of the plan's next
        ``people_look_ahead`` m (or of the chair, with no plan)."""
        discs = self.people.walkers()
        if not len(discs):
            return False
        s = self.settings
        way = np.array([[pose.x, pose.y]])
        if self.path is not None and len(self.path.points) > 1:
            way = np.vstack([way, self._path_ahead(pose, within=s.people_look_ahead)])
        gaps = np.hypot(*(discs[:, None, :2] - way[None, :, :]).transpose(2, 0, 1))
        return bool((gaps.min(axis=1) - discs[:, 2] <= s.people_in_the_way).any())

    def _used(self, recovery: str) -> None:
        self.recoveries_used[recovery] = self.recoveries_used.get(recovery, 0) + 1

    def _way_round(self, gap: Gap, pose: Pose2D) -> bool:
        """Whether the map has a way to the goal with ``gap`` closed too."""
        costmap = close_gap(self._closed_map(self.global_costmap), gap)
        try:
            plan(costmap, _free_start(costmap, pose), self.goal)
        except NoPathError:
            return False
        return True

    def _footprint_free(self, poses: list) -> bool:
        """Whether the footprint at every pose is off lethal cells of the local costmap."""
        local = self.local_costmap
        return local is not None and all(
            footprint_cost(local, self.footprint, p) < LETHAL for p in poses)

    def _recover(self, frame: SensorFrame, pose: Pose2D) -> Twist:
        """Back off ``back_off_distance``, or turn a quarter turn towards the plan."""
        kind, since, start = self._recovery  # type: ignore[misc]
        s = self.settings
        self._phase = kind
        elapsed = frame.t - since
        if kind == "backing off":
            moved = math.hypot(pose.x - start.x, pose.y - start.y)
            if moved < s.back_off_distance and elapsed < 3 * s.back_off_distance / s.back_off_speed:
                return Twist(-s.back_off_speed, 0.0)
        elif elapsed < (math.pi / 2) / s.in_place_turn_rate:
            side = 1.0
            if self.path is not None and len(self.path.points) > 1:
                points = self._path_ahead(pose)
                ahead = points[min(20, len(points) - 1)]
                side = math.copysign(1.0, wrap_angle(
                    math.atan2(ahead[1] - pose.y, ahead[0] - pose.x) - pose.theta))
            return Twist(0.0, side * s.in_place_turn_rate)
        self._recovery = None
        self._next_plan = frame.t
        return Twist(0.0, 0.0)


# ---------------------------------------------------------------------- helpers
def _place(places: dict[str, Pose2D], goal: object) -> Pose2D:
    """A goal as a Pose2D: a place's name, a Pose2D, or an (x, y[, theta]) (m, rad)."""
    if isinstance(goal, str):
        if goal not in places:
            known = ", ".join(places) or "none"
            raise ValueError(f"unknown place {goal!r}; places: {known}")
        return places[goal]
    if isinstance(goal, Pose2D):
        values = (goal.x, goal.y, goal.theta)
    else:
        try:
            values = tuple(float(v) for v in goal)  # type: ignore[union-attr]
        except (TypeError, ValueError):
            values = ()
        if len(values) == 2:
            values = (*values, 0.0)
    if len(values) != 3 or not all(math.isfinite(v) for v in values):
        raise ValueError(f"a goal is a place name, a Pose2D or a finite (x, y) or "
                         f"(x, y, theta) in m and rad, got {goal!r}")
    return Pose2D(*values)


def _same_gap(a: Gap, b: Gap, within: float = 0.5) -> bool:
    """Whether two gaps found on different plans are the same opening (middles within
    ``within`` m)."""
    return math.hypot(a.x - b.x, a.y - b.y) < within


def _free_start(costmap: Costmap, pose: Pose2D) -> tuple[float, float]:
    """The chair's position, or, if it lies on an impassable cell (the estimate puts it
    against a wall), the nearest passable cell within 0.5 m: move_base would refuse to
    plan, and a chair that brushed a door frame must still find its way on."""
    xy = position_of(pose, "start")
    rows, cols = costmap.world_to_cell(xy[None])
    if costmap.contains(rows[0], cols[0]) and costmap.cost[rows[0], cols[0]] < LETHAL - 1:
        return float(xy[0]), float(xy[1])
    reach = max(1, round(0.5 / costmap.resolution))
    r0, c0 = int(rows[0]), int(cols[0])
    window = np.s_[max(r0 - reach, 0):r0 + reach + 1, max(c0 - reach, 0):c0 + reach + 1]
    free = costmap.cost[window] < LETHAL - 1
    if not free.any():
        return float(xy[0]), float(xy[1])
    rr, cc = np.nonzero(free)
    rr, cc = rr + max(r0 - reach, 0), cc + max(c0 - reach, 0)
    k = int(np.argmin((rr - r0) ** 2 + (cc - c0) ** 2))
    x, y = costmap.cell_to_world(np.array([rr[k]]), np.array([cc[k]]))[0]
    return float(x), float(y)
