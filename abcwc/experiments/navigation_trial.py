"""The navigator's trial: seeded random goals across a world with its people walking.

One chair, one navigator, goal after goal (each starts where the last ended): a goal is
a random free pose at least ``clearance`` m from any wall that the static map's planner
can reach from the start. The navigator localises itself (the EKF and scan matching);
the simulator's ground truth is used only to *judge* it:

* ``reached``: the navigator said succeeded and the chair (true pose) is within the
  goal tolerance (plus the estimate's error, measured separately);
* ``collisions``: pymunk contacts of the chair with a wall or a person;
* ``lethal``: control periods in which the true footprint covers a wall cell of the
  static map (costmap_2d's footprint check on the true pose);
* ``closest_person``: the smallest gap (m) between the chair's outline and a person's
  disc;
* ``path_ratio``: the distance the chair drove over the straight line from its start to
  the goal (the optimum no chair can beat where walls are in the way), and over the
  static map's shortest plan;
* ``localisation``: the largest distance between the estimate and the truth;
* ``recoveries``: the navigator's recoveries by kind (backing off, clearing the local
  costmap, closing the gap ahead, ...), and each goal not reached with its reason.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np

from abcwc.behaviours.base import Status
from abcwc.behaviours.navigator import Navigator, NavigatorSettings
from abcwc.estimation.ekf import ChairEkf, gyro_bias_prior, noise_from_models
from abcwc.experiments.nees import STILL_SECONDS, OdometryCalibration, calibrate_worn_chair
from abcwc.geometry import transform_points
from abcwc.navigation.costmap import FREE_SPACE, LETHAL, footprint_cost
from abcwc.navigation.planner import NoPathError, plan
from abcwc.sim import SimBase
from abcwc.sim.people import circles_of
from abcwc.sim.world import PersonSpec
from abcwc.types import Pose2D, Twist


@dataclass(frozen=True)
class GoalOutcome:
    """One goal's result (module notes for the measures)."""

    goal: Pose2D
    status: str  # "succeeded" or "failed"
    reason: str | None
    seconds: float
    driven: float  # m, the true path's length
    straight: float  # m, start to goal
    planned: float  # m, the static map's shortest plan from the start
    final_error: float  # m, true position to the goal
    final_heading_error: float  # rad
    collisions: int
    lethal_periods: int
    closest_person: float  # m, inf without people
    max_localisation_error: float  # m
    tolerance: float  # m, the goal tolerance
    phases: dict[str, float] = field(default_factory=dict)  # s in each navigator phase
    track: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # true poses, 10 Hz
    estimates: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # the navigator's
    people: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 2)))  # (K, M, 2) walkers
    recoveries: dict[str, int] = field(default_factory=dict)  # the navigator's, by kind

    @property
    def reached(self) -> bool:
        """Succeeded by the navigator's word, and the true position within tolerance."""
        return self.status == "succeeded" and self.final_error <= self.tolerance


@dataclass
class TrialResult:
    """All goals of one trial, and its summary figures."""

    outcomes: list[GoalOutcome] = field(default_factory=list)
    tolerance: float = 0.25

    @property
    def success_rate(self) -> float:
        return sum(o.reached for o in self.outcomes) / max(len(self.outcomes), 1)

    @property
    def collisions(self) -> int:
        return sum(o.collisions for o in self.outcomes)

    @property
    def lethal_periods(self) -> int:
        return sum(o.lethal_periods for o in self.outcomes)

    @property
    def closest_person(self) -> float:
        return min((o.closest_person for o in self.outcomes), default=math.inf)

    def summary(self) -> str:
        reached = [o for o in self.outcomes if o.reached]
        ratios = np.array([o.driven / o.straight for o in reached if o.straight > 0])
        planned = np.array([o.driven / o.planned for o in reached if o.planned > 0])
        seconds = np.array([o.seconds for o in reached])
        lines = [
            f"goals: {len(self.outcomes)}, reached {len(reached)} "
            f"({100 * self.success_rate:.0f} %)",
            f"collisions: {self.collisions}; periods with the footprint on a wall cell: "
            f"{self.lethal_periods}",
            f"closest approach to a person: {self.closest_person:.2f} m",
        ]
        if len(reached):
            lines += [
                f"time per goal: median {np.median(seconds):.1f} s, max {seconds.max():.1f} s",
                f"driven / straight line: median {np.median(ratios):.2f}, "
                f"max {ratios.max():.2f}",
                f"driven / shortest plan: median {np.median(planned):.2f}, "
                f"max {planned.max():.2f}",
                f"final position error: max "
                f"{max(o.final_error for o in reached):.3f} m; heading max "
                f"{max(abs(o.final_heading_error) for o in reached):.3f} rad",
            ]
        totals: dict[str, float] = {}
        for o in self.outcomes:
            for phase, seconds in o.phases.items():
                totals[phase] = totals.get(phase, 0.0) + seconds
        whole = sum(totals.values()) or 1.0
        lines.append("time by phase: " + ", ".join(
            f"{phase} {100 * seconds / whole:.1f} %"
            for phase, seconds in sorted(totals.items(), key=lambda kv: -kv[1])
            if seconds >= 0.001 * whole))
        used: dict[str, int] = {}
        for o in self.outcomes:
            for kind, count in o.recoveries.items():
                used[kind] = used.get(kind, 0) + count
        lines.append("recoveries: " + (", ".join(
            f"{kind} {count} ({sum(kind in o.recoveries for o in self.outcomes)} goals)"
            for kind, count in sorted(used.items(), key=lambda kv: -kv[1])) or "none"))
        lines.append("largest localisation error: "
                     f"{max((o.max_localisation_error for o in self.outcomes), default=0):.3f} m")
        for k, o in enumerate(self.outcomes):
            if not o.reached:
                why = o.reason or f"ended {o.final_error:.2f} m from the goal"
                lines.append(f"goal {k} ({o.goal.x:.1f}, {o.goal.y:.1f}) not reached: {why}")
        return "\n".join(lines)


def random_goals(navigator: Navigator, count: int, seed: int, start: Pose2D,
                 people: tuple[PersonSpec, ...] = (), clearance: float = 0.8,
                 off_walkways: float = 1.1) -> list[Pose2D]:
    """``count`` seeded random goal poses on free floor ``clearance`` m or more from any
    wall and ``off_walkways`` m or more from the lines ``people`` walk, each reachable
    from ``start`` on the static map. (The simulator's walkers follow their lines blindly
    and would walk into a chair parked on one, where a real person steps round it: so
    no goal is set on a walker's line. The chair still crosses and shares them.)"""
    static = navigator.static_map
    from scipy import ndimage

    distance = ndimage.distance_transform_edt(static.cost != LETHAL) * static.resolution
    rows, cols = np.nonzero((distance >= clearance) & (static.cost == FREE_SPACE))
    points = static.cell_to_world(rows, cols)
    for person in people:
        path = np.asarray(person.path, dtype=float)
        ends = np.vstack([path, path[:1]]) if person.loop else path
        for a, b in zip(ends[:-1], ends[1:]):
            along = b - a
            t = np.clip((points - a) @ along / max(along @ along, 1e-12), 0.0, 1.0)
            gap = np.hypot(*(points - (a + t[:, None] * along)).T)
            points = points[gap >= off_walkways]
    rng = np.random.default_rng(seed)
    goals: list[Pose2D] = []
    while len(goals) < count:
        x, y = points[int(rng.integers(len(points)))]
        theta = float(rng.uniform(-math.pi, math.pi))
        try:
            plan(navigator.global_costmap, (start.x, start.y), (x, y))
        except NoPathError:
            continue
        goals.append(Pose2D(float(x), float(y), theta))
    return goals


def gap_to_people(outline: np.ndarray, circles: np.ndarray) -> float:
    """Smallest distance (m) from a closed polygon (N, 2) to the edge of discs (M, 3)."""
    if not len(circles):
        return math.inf
    a, b = outline, np.roll(outline, -1, axis=0)
    centres = circles[:, None, :2]
    edge = b - a
    t = np.clip(np.einsum("mnk,nk->mn", centres - a, edge) / np.einsum("nk,nk->n", edge, edge),
                0.0, 1.0)
    nearest = a + t[..., None] * edge
    return float(np.min(np.hypot(*(centres - nearest).transpose(2, 0, 1)).min(axis=1)
                        - circles[:, 2]))


@lru_cache(maxsize=1)
def _worn_chair_calibration() -> OdometryCalibration:
    return calibrate_worn_chair()


def calibrated_ekf(chair: SimBase, still_seconds: float = STILL_SECONDS) -> ChairEkf:
    """Chapter 10's filter for ``chair``: UMBmark's correction and wheel base (chapter
    08, measured on the worn chair in a hall), and the gyro's bias from standing still
    for ``still_seconds`` first (the chair stands still that long)."""
    bias, bias_std = gyro_bias_prior(chair.drive(Twist(0.0, 0.0), still_seconds).gyro_z)
    calibration = _worn_chair_calibration()
    return ChairEkf(chair.pose, chair.params, start_std=(0.05, 0.05, 0.02),
                    correction=calibration.correction, wheel_base=calibration.wheel_base,
                    gyro_bias=bias, gyro_bias_std=bias_std,
                    noise=noise_from_models(chair.params, residual_rel=calibration.residual_rel,
                                            horizon=1.0))


def run_trial(goals: int = 50, seed: int = 0, world: str = "floor", people: bool = True,
              settings: NavigatorSettings | None = None, progress: bool = False
              ) -> TrialResult:
    """Drive to ``goals`` seeded random goals one after another (module notes)."""
    chair = SimBase(world, seed=seed, lidar=True, people=people)
    navigator = Navigator.for_world(chair.world, ekf=calibrated_ekf(chair), settings=settings)
    targets = random_goals(navigator, goals, seed, chair.pose, chair.world.people)
    result = TrialResult(tolerance=navigator.settings.xy_goal_tolerance)
    iterator = targets
    if progress:
        from tqdm.auto import tqdm

        iterator = tqdm(targets, desc="goals", unit="goal")
    frame = chair.read()
    for goal in iterator:
        result.outcomes.append(drive_to_goal(chair, navigator, goal, frame))
        frame = chair.read()
    return result


def drive_to_goal(chair: SimBase, navigator: Navigator, goal: Pose2D | str,
                  frame: object | None = None, timeout: float = 600.0) -> GoalOutcome:
    """Send ``navigator`` to ``goal`` (a pose or a place name) and step the simulated
    ``chair`` until it ends (or ``timeout`` s), judging it by the ground truth (module
    notes); the truth, the estimate and the walkers are kept every 0.1 s."""
    if isinstance(goal, str):
        goal = chair.world.places[goal]
    frame = chair.read() if frame is None else frame
    start, t0, collisions0 = chair.pose, chair.t, chair.collisions
    try:
        planned = plan(navigator.global_costmap, (start.x, start.y), (goal.x, goal.y)).length
    except NoPathError:
        planned = math.nan
    navigator.go_to(goal)
    driven, lethal, closest, worst = 0.0, 0, math.inf, 0.0
    phases: dict[str, float] = {}
    outline = navigator.footprint.polygon
    last = start
    track, estimates, people = [], [], []
    every = max(1, round(0.1 / chair.period))
    while navigator.running and chair.t - t0 < timeout:
        chair.send(navigator(frame), navigator.decided_at)
        frame = chair.step()
        if round((chair.t - t0) / chair.period) % every == 0:
            truth, estimate = chair.pose, navigator.localizer.pose
            track.append((truth.x, truth.y, truth.theta))
            estimates.append((estimate.x, estimate.y, estimate.theta))
            people.append(circles_of(chair.walkers)[:, :2] if chair.walkers else
                          np.zeros((0, 2)))
        phase = navigator.feedback.phase  # type: ignore[union-attr]
        phases[phase] = phases.get(phase, 0.0) + chair.period
        pose = chair.pose
        driven += math.hypot(pose.x - last.x, pose.y - last.y)
        last = pose
        if footprint_cost(navigator.static_map, navigator.footprint, pose) == LETHAL:
            lethal += 1
        if chair.walkers:
            closest = min(closest, gap_to_people(transform_points(pose, outline),
                                                  circles_of(chair.walkers)))
        estimate = navigator.localizer.pose
        worst = max(worst, math.hypot(estimate.x - pose.x, estimate.y - pose.y))
    if navigator.running:
        navigator.cancel()
    for _ in range(25):  # let the chair come to rest before the next goal
        chair.send(navigator(frame), navigator.decided_at)
        frame = chair.step()
    end = chair.pose
    return GoalOutcome(
        goal, navigator.status.value, navigator.failure, chair.t - t0, driven,
        math.hypot(goal.x - start.x, goal.y - start.y), planned,
        math.hypot(goal.x - end.x, goal.y - end.y),
        float(np.angle(np.exp(1j * (goal.theta - end.theta)))),
        chair.collisions - collisions0, lethal, closest, worst,
        navigator.settings.xy_goal_tolerance, phases, np.array(track).reshape(-1, 3),
        np.array(estimates).reshape(-1, 3), np.array(people), dict(navigator.recoveries_used))


__all__ = ["GoalOutcome", "Status", "TrialResult", "drive_to_goal", "gap_to_people",
           "random_goals", "run_trial"]
