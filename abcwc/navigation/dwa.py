"""The Dynamic Window Approach local planner, as ROS's base_local_planner runs it with
``dwa: true`` (Fox, Burgard and Thrun, "The dynamic window approach to collision
avoidance", IEEE Robotics and Automation Magazine 4(1), 1997).

Every control cycle (``controller_frequency``, 5 Hz in the thesis's A.17):

1. **The window.** Only velocities reachable within one cycle are sampled:
   ``v in [v0 - acc_lim_x / f, v0 + acc_lim_x / f]`` and likewise ``w`` with
   ``acc_lim_theta``, clipped to the limits; ``vx_samples x vtheta_samples`` pairs
   (A.17: 8 x 20).
2. **Roll-out.** Each pair is held for ``sim_time`` (1 s) along its exact arc,
   ``x(t) = x0 + v/w (sin(th0 + w t) - sin th0)``, ``y(t) = y0 - v/w (cos(th0 + w t) -
   cos th0)``, sampled so that neighbouring points lie at most ``sim_granularity`` m and
   ``angular_sim_granularity`` rad apart (one step count for all pairs: the largest
   any of them needs).
3. **Scoring.** A trajectory whose footprint comes within reach of a lethal or unknown
   cell, or leaves the costmap, is dropped (if the chair is already that near, as after
   a push or a swerve, a trajectory counts if it never brings it nearer, ends half a
   cell farther away, and keeps the footprint's outline itself off every obstacle: it
   can get away instead of freezing, but not by swinging a corner into what the
   circles already overlap). The footprint is checked as three equal circles that
   cover its rectangle (:func:`covering_circles`), against a distance transform of the
   obstacles: a few centimetres more cautious at the corners than base_local_planner's
   outline check, and one array lookup per circle. The transform measures from cell
   centre to cell centre, so a circle's clearance is taken as the transform at its
   cell less its centre's distance from that cell's centre, and must exceed its radius
   by half a cell's diagonal (where in its cell the obstacle may lie): a bound, not an
   estimate, so the outline never reaches an obstacle's cell. A trajectory must also
   leave the chair room to stop: the way it would brake to a stand after taking the
   sample (the wheels' lag, then ``acc_lim_x``) is checked the same way, Fox's
   "admissible" velocities (:meth:`DwaPlanner.check`). The others
   cost (base_local_planner's ``meter_scoring``)::

       pdist_scale * path_distance + gdist_scale * goal_distance + occdist_scale * max_cost

   with ``path_distance`` and ``goal_distance`` (m) from the nearest cell of the global
   path and from the local goal (the last path point inside the window), each summed
   over two points: the trajectory's end, and the point ``heading_lookahead`` (A.17:
   0.325 m) ahead of it along its final heading (dwa_local_planner's "forward point",
   its ``goal_front`` and ``alignment`` costs). Without the forward point every turn on
   the spot ends where it began and scores as standing still, so a chair facing away
   from its path would never turn to it. Within 0.5 m of the path's end both points are
   the trajectory's end: a forward point that passes a goal less than 0.325 m ahead
   would score driving on as no better than standing. ``max_cost`` is the highest costmap value
   under the footprint. The two distances are straight lines from the point's cell to
   the nearest path cell and to the goal cell (centre to centre), where
   base_local_planner's ``MapGrid`` runs a wavefront around obstacles: a trajectory
   ending behind a thin wall looks closer here than it is, and the global path, which
   goes round the wall, is what keeps that from mattering.
4. **The command** is the cheapest trajectory's ``(v, w)``; with none left the chair
   stops and :attr:`DwaResult.stuck` says so (move_base would start its recoveries).

Every trajectory is rolled out and scored in one set of array operations.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from abcwc.geometry import PoseLike
from abcwc.navigation.costmap import LETHAL, Costmap, Footprint
from abcwc.navigation.people import standing_still
from abcwc.params import LocalPlannerParams, NavigationParams, load_navigation_params
from abcwc.types import Pose2D, Twist


@dataclass(frozen=True)
class DwaResult:
    """One cycle's outcome: the ``command``; every sampled ``(v, w)`` (S, 2), its
    trajectory ``poses`` (S, T, 3), ``valid`` mask and ``cost`` (inf where invalid), and
    ``best`` (index into the samples, -1 when ``stuck``). ``terms`` splits every
    sample's cost into its three scaled parts, ``"path"``, ``"goal"`` and
    ``"occupancy"`` (each (S,), summing to ``cost`` where valid)."""

    command: Twist
    samples: np.ndarray
    poses: np.ndarray
    valid: np.ndarray
    cost: np.ndarray
    best: int
    evading: bool = False  # no trajectory keeps clear of people: the one farthest from them
    # and from walls
    terms: dict[str, np.ndarray] = field(default_factory=dict)
    gap: float = math.inf  # m: how much nearer the chair's covering circles could come to
    # an obstacle where they are now before the check refuses them (< 0: already nearer)

    @property
    def stuck(self) -> bool:
        """True when every sampled trajectory collides: the chair is told to stop."""
        return self.best < 0


def covering_circles(footprint: Footprint, count: int = 3) -> tuple[np.ndarray, float]:
    """``(centres (count, 2), radius)``: equal circles along the footprint's length that
    together cover its bounding rectangle (m, base_link). Checking a few circles against
    a distance-to-obstacle map is what makes every trajectory's check one array lookup."""
    xs, ys = footprint.polygon[:, 0], footprint.polygon[:, 1]
    length, half_width = xs.max() - xs.min(), (ys.max() - ys.min()) / 2
    step = length / count
    centres = np.column_stack([xs.min() + step * (np.arange(count) + 0.5),
                               np.full(count, (ys.max() + ys.min()) / 2)])
    return centres, float(math.hypot(step / 2, half_width))


def roll_out(pose: PoseLike, samples: np.ndarray, sim_time: float, steps: int) -> np.ndarray:
    """The exact arcs (S, steps + 1, 3) of holding each ``(v, w)`` sample for ``sim_time``
    s from ``pose``, at ``steps`` equal time steps (the first point is the pose itself)."""
    x0, y0, th0 = (pose.x, pose.y, pose.theta) if isinstance(pose, Pose2D) else pose
    v, w = samples[:, :1], samples[:, 1:]
    t = np.linspace(0.0, sim_time, steps + 1)[None, :]
    theta = th0 + w * t
    turning = np.abs(w) > 1e-9
    safe_w = np.where(turning, w, 1.0)
    x = np.where(turning, x0 + v / safe_w * (np.sin(theta) - math.sin(th0)),
                 x0 + v * t * math.cos(th0))
    y = np.where(turning, y0 - v / safe_w * (np.cos(theta) - math.cos(th0)),
                 y0 + v * t * math.sin(th0))
    return np.stack([x, y, theta], axis=-1)


@dataclass(frozen=True)
class FootprintCheck:
    """Roll-outs and their collision check: ``poses`` (S, T + 1, 3), the covering
    circles' flat costmap ``cells`` (``row * width + col``: circles x S x (T + 1)), each
    circle's ``clearance`` there (m, the same shape: a lower bound of its centre's
    distance to the nearest lethal or unknown cell's centre, -inf off the map), the
    clearance each circle ``needed`` (m) and which samples are ``valid`` (S,)."""

    poses: np.ndarray
    cells: np.ndarray
    clearance: np.ndarray
    needed: float
    valid: np.ndarray

    @property
    def gap(self) -> float:
        """m the covering circles could come nearer an obstacle where they are now
        before the check refuses them (< 0: already nearer)."""
        return float(self.clearance[:, 0, 0].min() - self.needed)


class DwaPlanner:
    """base_local_planner's DWA with A.17's parameters by default (``params``), for a
    chair of ``footprint`` grown by ``padding`` m (costmap_2d's ``footprint_padding``:
    room for the pose estimate's error and for the chair not following the arcs
    exactly). Call :meth:`plan` once per control cycle."""

    def __init__(self, footprint: Footprint, params: NavigationParams | None = None,
                 local: LocalPlannerParams | None = None, padding: float = 0.0,
                 braking_delay: float = 0.0):
        nav = params or load_navigation_params()
        self.local = local or nav.local_planner
        self.frequency = nav.move_base.controller_frequency
        self.footprint = footprint
        if not (math.isfinite(padding) and padding >= 0):
            raise ValueError(f"padding must be a finite number >= 0 m, got {padding!r}")
        self._circles, radius = covering_circles(footprint)
        self._outline = _outline_points(footprint.polygon, spacing=0.025)
        self._radius = radius + padding  # costmap_2d's footprint_padding
        if not (math.isfinite(braking_delay) and braking_delay >= 0):
            raise ValueError(f"braking_delay must be a finite number >= 0 s, "
                             f"got {braking_delay!r}")
        self.braking_delay = braking_delay  # s from deciding to stop to full braking
        # m: closer than this to the path's end, both scored points are the trajectory's
        # end (Nav2 DWB's PathAlign and GoalAlign critics stop within their
        # threshold_to_consider, 0.5 m): with the goal less than heading_lookahead ahead,
        # a forward point that passes it scores driving on as no better than standing
        self.forward_point_within = 0.5
        lp = self.local
        if not (lp.vx_samples >= 1 and lp.vtheta_samples >= 1):
            raise ValueError("vx_samples and vtheta_samples must be >= 1")
        if not (lp.sim_time > 0 and lp.sim_granularity > 0 and lp.angular_sim_granularity > 0):
            raise ValueError("sim_time and the sim granularities must be > 0")

    def passing_radius(self, resolution: float) -> float:
        """m: how far from the nearest obstacle cell's centre the chair's centre must be,
        anywhere in a cell of ``resolution`` m, for this planner's check to let it
        stand there in its best heading: the covering circles' radius plus the padding
        (all three circles sit on the chair's centre line, so lined up with a gap they
        need what one does), half a cell's diagonal for where in its cell the obstacle
        lies (the check's own slack), and half a diagonal more for where in its cell the
        chair is. A global planner that keeps its path's cells this far out
        (:meth:`~abcwc.navigation.costmap.Costmap.inflate`'s ``keep_out_radius``) plans
        only through gaps this planner will take."""
        if not (math.isfinite(resolution) and resolution > 0):
            raise ValueError(f"resolution must be a finite number > 0 m, got {resolution!r}")
        return self._radius + resolution * math.sqrt(2)

    def window(self, velocity: tuple[float, float]) -> np.ndarray:
        """The (S, 2) ``(v, w)`` samples reachable in one cycle from ``velocity``."""
        v0, w0 = velocity
        if not (math.isfinite(v0) and math.isfinite(w0)):
            raise ValueError(f"velocity must be a finite (v m/s, w rad/s), got {velocity!r}")
        lp, period = self.local, 1.0 / self.frequency
        v_lo = max(lp.min_vel_x, v0 - lp.acc_lim_x * period)
        v_hi = min(lp.max_vel_x, v0 + lp.acc_lim_x * period)
        w_lo = max(-lp.max_vel_theta, w0 - lp.acc_lim_theta * period)
        w_hi = min(lp.max_vel_theta, w0 + lp.acc_lim_theta * period)
        v, w = np.meshgrid(np.linspace(min(v_lo, v_hi), v_hi, lp.vx_samples),
                           np.linspace(min(w_lo, w_hi), w_hi, lp.vtheta_samples),
                           indexing="ij")
        return np.column_stack([v.ravel(), w.ravel()])

    def plan(self, costmap: Costmap, pose: PoseLike, velocity: tuple[float, float],
             path: np.ndarray, people: np.ndarray | None = None,
             people_horizon: float = 3.0, people_margin: float = 0.1) -> DwaResult:
        """One cycle: the command that follows ``path`` ((K, 2) map points, m, from the
        global planner) from ``pose`` at ``velocity`` without touching an obstacle.

        ``people`` ((M, 5): x, y, vx, vy, radius; m, m/s) are moving discs, each
        predicted at constant velocity: a trajectory must keep its covering circles
        ``people_margin`` m clear of every disc along its roll-out and for
        ``people_horizon`` s after it (the chair braking to a stop on it,
        :meth:`people_gap`), so that it never stops where a walker is about to be. If no
        trajectory can, the chair is ``evading``, and each way is scored by the nearer of
        walls and people, people judged both walking on and standing where they are (a
        person who sees the chair in the way stops): if the chair is moving and could
        still stop clear of where people stand, it slows as hard as the window allows,
        on the best-scored arc of that speed; otherwise it takes the slowest of the ways
        scored about as well as the best."""
        path = np.asarray(path, dtype=float).reshape(-1, 2)
        if not len(path) or not np.isfinite(path).all():
            raise ValueError("path must be a non-empty (K, 2) array of finite map points (m)")
        lp = self.local
        samples = self.window(velocity)
        check = self.check(costmap, pose, samples, stopping=True)
        poses, clearance, needed = check.poses, check.clearance, check.needed
        gap_now = check.gap
        worst = costmap.cost.ravel()[check.cells].max(axis=(0, 2))
        valid = check.valid.copy()

        path_cells, goal_cell = self._path_cells(costmap, path)
        ends = poses[:, -1]
        fronts = ends[:, :2] + lp.heading_lookahead * np.column_stack(
            [np.cos(ends[:, 2]), np.sin(ends[:, 2])])
        x0, y0 = poses[0, 0, :2]
        if math.hypot(path[-1, 0] - x0, path[-1, 1] - y0) < self.forward_point_within:
            fronts = ends[:, :2].copy()  # near the goal the forward point only overshoots
        points = np.concatenate([ends[:, :2], fronts])  # both points of every sample
        p_rows, p_cols = costmap.xy_to_cell(points[:, 0], points[:, 1])
        inside = costmap.contains(p_rows, p_cols).reshape(2, -1).all(axis=0)
        cells = np.column_stack([np.clip(p_rows, 0, costmap.height - 1),
                                 np.clip(p_cols, 0, costmap.width - 1)])
        res = costmap.resolution
        to_path = lp.pdist_scale * _nearest_distance(cells, path_cells).reshape(2, -1) * res
        to_goal = lp.gdist_scale * _nearest_distance(cells, goal_cell).reshape(2, -1) * res
        terms = {"path": to_path[0] + to_path[1], "goal": to_goal[0] + to_goal[1]}
        terms["occupancy"] = lp.occdist_scale * worst
        cost = terms["path"] + terms["goal"] + terms["occupancy"]
        valid &= inside
        evading = False
        if people is not None and len(people):
            walking = np.asarray(people, float)
            gap = self.people_gap(pose, samples, walking, people_horizon)
            clear_of_people = gap > people_margin
            if valid.any() and not (valid & clear_of_people).any():
                # the way that keeps farthest from both: a chair that flees a person
                # only to graze a wall, with the wheels' lag behind the command, hits it
                evading = True
                wall_gap = clearance.min(axis=(0, 2)) - needed
                # people judged twice, walking on and standing where they are: a person
                # who sees the chair in the way stops, and a way clear only of where
                # they would have walked runs into where they stand
                standing_gap = self.people_gap(pose, samples, standing_still(walking),
                                               people_horizon)
                score = np.where(valid, np.minimum(np.minimum(gap, standing_gap), wall_gap),
                                 -np.inf)
                if velocity[0] > 0.05 and (valid & (standing_gap > people_margin)).any():
                    # the chair could stop clear of where people are, but not of where
                    # they walk: slow down as hard as the window allows, steering for
                    # the widest gap
                    slowest = valid & (samples[:, 0] <= samples[valid, 0].min())
                    best = int(np.argmax(np.where(slowest, score, -np.inf)))
                    return DwaResult(Twist(float(samples[best, 0]), float(samples[best, 1])),
                                     samples, poses, valid, np.where(valid, cost, np.inf),
                                     best, evading, terms, gap_now)
                # of the ways about as good as the best, the slowest: standing off
                # rather than driving on when driving on gains nothing
                near_best = score >= score.max() - costmap.resolution
                best = int(np.argmin(np.where(near_best, samples[:, 0], np.inf)))
                # the arc as checked: asking for a stop on it instead (v 0, the same
                # turn rate) would tighten the turn as the wheels slow and swing a corner
                # of the chair off the checked arc, into a wall beside it
                return DwaResult(Twist(float(samples[best, 0]), float(samples[best, 1])),
                                 samples, poses, valid, np.where(valid, cost, np.inf), best,
                                 evading, terms, gap_now)
            valid &= clear_of_people
        cost = np.where(valid, cost, np.inf)
        if not valid.any():
            return DwaResult(Twist(0.0, 0.0), samples, poses, valid, cost, -1, terms=terms,
                             gap=gap_now)
        best = int(np.argmin(cost))
        return DwaResult(Twist(float(samples[best, 0]), float(samples[best, 1])), samples,
                         poses, valid, cost, best, evading, terms, gap_now)

    def check(self, costmap: Costmap, pose: PoseLike, samples: np.ndarray,
              stopping: bool = False) -> FootprintCheck:
        """Roll each ``(v, w)`` of ``samples`` (S, 2) out from ``pose`` for ``sim_time``
        and check the footprint's covering circles along it against ``costmap``'s
        lethal and unknown cells (module notes, step 3). With ``stopping``, the way the
        chair would stop after taking the sample (:meth:`stopping_paths`) must be clear
        too: the dynamic window's "admissible" velocities, from which the robot can
        still stop before an obstacle (Fox, Burgard and Thrun 1997). A
        second of constant speed is not enough: at 0.8 m/s the wheels' lag and braking
        at 0.8 m/s^2 take 0.9 m, so a chair that finds no way clear the cycle after
        taking one slides past what the second covered."""
        lp = self.local
        reach = np.abs(samples).max(axis=0) * lp.sim_time
        steps = max(1, math.ceil(max(reach[0] / lp.sim_granularity,
                                     reach[1] / lp.angular_sim_granularity)))
        poses = roll_out(pose, samples, lp.sim_time, steps)
        # the footprint as covering circles at every pose: clear if every circle's centre
        # is farther than its radius from the nearest lethal or unknown cell
        clearance = ndimage.distance_transform_edt(costmap.cost < LETHAL) * costmap.resolution
        cells, near = _clearance_of(costmap, clearance, poses, self._circles)
        nearest = np.minimum.reduce(near)  # (S, T): the nearest circle; off the map: out
        # an obstacle lies anywhere in its cell: up to half the cell's diagonal nearer
        # than the cell's centre, from which the distance transform measures
        slack = costmap.resolution / math.sqrt(2)
        needed = self._radius + slack
        here = float(nearest[0, 0])  # the chair's circles now
        if here <= needed:  # already closer than allowed: only ways that get away count
            along = nearest
            clear = (along >= here) & (along[:, -1:] >= here + costmap.resolution / 2)
            # that close, a circle may already overlap an obstacle the outline is clear
            # of, and a way that keeps the circles no nearer can still swing a corner
            # into it: the outline itself must stay off every obstacle
            _, outline = _clearance_of(costmap, clearance, poses, self._outline)
            clear &= np.minimum.reduce(outline) > slack
        else:
            clear = nearest > needed
        valid = clear.all(axis=1)
        if stopping and here > needed and valid.any():
            horizon = (1.0 / self.frequency + self.braking_delay
                       + float(np.abs(samples[:, 0]).max()) / lp.acc_lim_x)
            _, paths = self.stopping_paths(pose, samples[valid], horizon)
            _, stop_near = _clearance_of(costmap, clearance, paths, self._circles)
            valid[valid] = (np.minimum.reduce(stop_near) > needed).all(axis=1)
        return FootprintCheck(poses, cells, near, needed, valid)

    def stopping_paths(self, pose: PoseLike, samples: np.ndarray, horizon: float,
                       dt: float = 0.05) -> tuple[np.ndarray, np.ndarray]:
        """``(times (T,), poses (S, T, 3))``: the chair holding each ``(v, w)`` sample for
        one control period and ``braking_delay`` s more (the wheels' lag behind a stop
        command), then braking to a stop at ``acc_lim_x`` and ``acc_lim_theta`` along its
        way, and standing, until ``horizon`` s, sampled every ``dt`` s."""
        lp, period = self.local, 1.0 / self.frequency
        x0, y0, th0 = (pose.x, pose.y, pose.theta) if isinstance(pose, Pose2D) else pose
        times = np.arange(0.0, max(horizon, period) + dt / 2, dt)  # (T,)
        braking = np.maximum(times - period - self.braking_delay, 0.0)
        v = np.maximum(samples[:, :1] - lp.acc_lim_x * braking, 0.0)  # (S, T): v >= 0
        w = np.sign(samples[:, 1:]) * np.maximum(
            np.abs(samples[:, 1:]) - lp.acc_lim_theta * braking, 0.0)
        theta = th0 + np.concatenate([np.zeros((len(samples), 1)),
                                      np.cumsum(w[:, :-1] * dt, axis=1)], axis=1)
        step_x, step_y = v * np.cos(theta) * dt, v * np.sin(theta) * dt
        x = x0 + np.concatenate([np.zeros((len(samples), 1)),
                                 np.cumsum(step_x[:, :-1], axis=1)], axis=1)
        y = y0 + np.concatenate([np.zeros((len(samples), 1)),
                                 np.cumsum(step_y[:, :-1], axis=1)], axis=1)
        return times, np.stack([x, y, theta], axis=-1)

    def people_gap(self, pose: PoseLike, samples: np.ndarray, people: np.ndarray,
                    horizon: float, dt: float = 0.05) -> np.ndarray:
        """(S,) the smallest gap (m) between the chair's covering circles and the people's
        discs (moved on at their velocities) if the chair holds each sample for one
        control period and ``braking_delay`` s more (the wheels' lag behind a stop
        command), then brakes to a stop at ``acc_lim_x`` and ``acc_lim_theta`` along its
        way, and stands until ``horizon`` s.

        A trajectory is judged by whether the chair can still stop clear of everyone
        after taking it, not by whether it is clear at constant speed: a state from
        which every way ends in a collision is an inevitable collision state (Fraichard
        and Asama, "Inevitable collision states - a step towards safer robots?",
        Advanced Robotics 18(10), 2004), and a chair driving on at constant speed
        towards a walker's path reaches one before its constant-speed arcs show it."""
        times, stopping = self.stopping_paths(pose, samples, horizon, dt)
        x, y, theta = stopping[..., 0], stopping[..., 1], stopping[..., 2]
        c, s = np.cos(theta)[..., None], np.sin(theta)[..., None]
        cx = x[..., None] + c * self._circles[:, 0] - s * self._circles[:, 1]  # (S, T, C)
        cy = y[..., None] + s * self._circles[:, 0] + c * self._circles[:, 1]
        px = people[:, 0] + people[:, 2] * times[:, None]  # (T, M)
        py = people[:, 1] + people[:, 3] * times[:, None]
        distance = np.hypot(cx[..., None] - px[None, :, None, :],
                            cy[..., None] - py[None, :, None, :])  # (S, T, C, M)
        return (distance - people[:, 4] - self._radius).min(axis=(1, 2, 3))

    @staticmethod
    def _path_cells(costmap: Costmap, path: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(K, 2) rows and columns of the path's cells inside the window, and (1, 2) the
        local goal's (the last path point inside it, or the path point nearest the
        window, clipped in)."""
        rows, cols = costmap.world_to_cell(path)
        inside = costmap.contains(rows, cols)
        if inside.any():
            cells = np.column_stack([rows[inside], cols[inside]])
            return cells, cells[-1:]
        centre = costmap.cell_to_world(costmap.height // 2, costmap.width // 2)
        nearest = int(np.argmin(np.hypot(*(path - centre).T)))
        goal = np.array([[np.clip(rows[nearest], 0, costmap.height - 1),
                          np.clip(cols[nearest], 0, costmap.width - 1)]])
        return goal, goal


def _clearance_of(costmap: Costmap, clearance: np.ndarray, poses: np.ndarray,
                  points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For ``points`` (P, 2, base_link) at every pose (S, T, 3): each point's flat cell
    index into the map (``row * width + col``, clipped to the map) and a lower bound of
    its distance (m) to the nearest lethal cell's centre, the distance transform at its
    cell's centre less the point's own distance from that centre (-inf off the map);
    both (P, S, T), point by point, so that a minimum over the points is one pass over
    whole slabs."""
    if costmap.origin.theta != 0.0:  # a turned grid: the general transforms
        c, s = np.cos(poses[..., 2]), np.sin(poses[..., 2])
        x = poses[..., 0] + c * points[:, :1, None] - s * points[:, 1:, None]
        y = poses[..., 1] + s * points[:, :1, None] + c * points[:, 1:, None]
        rows, cols = costmap.xy_to_cell(x, y)
        centres = costmap.cell_to_world(rows, cols)
        off = np.hypot(x - centres[..., 0], y - centres[..., 1])
    else:  # in cell units (single precision: a cell is 1, the map a few hundred): the
        # cell is the floor, its centre half a cell on
        scale = 1.0 / costmap.resolution
        heading = poses[..., 2].astype(np.float32)
        c, s = np.cos(heading), np.sin(heading)
        px, py = (points * scale).astype(np.float32)[..., None, None].transpose(1, 0, 2, 3)
        u = ((poses[..., 0] - costmap.origin.x) * scale).astype(np.float32) + (c * px - s * py)
        v = ((poses[..., 1] - costmap.origin.y) * scale).astype(np.float32) + (s * px + c * py)
        floor_u, floor_v = np.floor(u), np.floor(v)
        u -= floor_u
        u -= 0.5
        v -= floor_v
        v -= 0.5
        u *= u
        v *= v
        u += v
        off = np.sqrt(u, out=u)
        off *= np.float32(costmap.resolution)
        cols, rows = floor_u.astype(np.intp), floor_v.astype(np.intp)
    off_map = (rows < 0) | (rows >= costmap.height) | (cols < 0) | (cols >= costmap.width)
    np.clip(rows, 0, costmap.height - 1, out=rows)
    np.clip(cols, 0, costmap.width - 1, out=cols)
    cells = rows * costmap.width + cols
    near = clearance.ravel()[cells]
    near -= off
    near[off_map] = -np.inf
    return cells, near


def _outline_points(polygon: np.ndarray, spacing: float) -> np.ndarray:
    """(P, 2) points along a closed polygon's edges, at most ``spacing`` m apart."""
    points = []
    for a, b in zip(polygon, np.roll(polygon, -1, axis=0)):
        count = max(1, math.ceil(np.hypot(*(b - a)) / spacing))
        points.append(a + np.linspace(0.0, 1.0, count, endpoint=False)[:, None] * (b - a))
    return np.vstack(points)


def _nearest_distance(cells: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """(N,) the distance (cells, centre to centre) from each of ``cells`` (N, 2) to the
    nearest of ``targets`` (K, 2): what a Euclidean distance transform of the targets
    holds at those cells, computed for the few cells asked about instead of all."""
    row_gaps = cells[:, :1].astype(float) - targets[:, 0]
    col_gaps = cells[:, 1:].astype(float) - targets[:, 1]
    row_gaps *= row_gaps
    col_gaps *= col_gaps
    row_gaps += col_gaps
    return np.sqrt(row_gaps.min(axis=1))
