"""The ABC concept end to end: a chair that maps a floor, is told where to go, and goes.

The thesis opens with the idea the whole project exists to make real (its figures 1-2):
a person picks a task by touch, voice or gaze; the chair plans a route, drives itself
among people, calls the lift on its way, and hands control back the moment the joystick
moves. An errand here is that, in the simulator:

1. **Map.** The chair maps the floor it does not know from its own lidar scans
   (:mod:`abcwc.behaviours.explore`, then graph SLAM) and saves the map as map_server
   files; or a saved map of a known floor is loaded.
2. **Be told.** "go to the <place>" is spoken (flite synthesises it, the command
   recogniser hears it), or typed when no synthesiser is installed: the same grammar.
3. **Go.** The :class:`~abcwc.behaviours.mission.Mission` drives there by the chair's
   own map and estimate, among the world's walking people, with the body's safety filter
   in the loop; "lift requested" fires near the lift.

The simulator's ground truth only *judges* it: whether it arrived (the true position
within the navigator's tolerance), the distance driven, the closest approach to a
person (the chair's outline to a walker's disc), the collisions, and how far the
estimate strayed from the truth.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from abcwc.behaviours.explore import MappedFloor, floor_map
from abcwc.behaviours.mission import Mission, MissionState
from abcwc.estimation.ekf import ChairEkf
from abcwc.experiments.navigation_trial import calibrated_ekf, gap_to_people
from abcwc.geometry import transform_points
from abcwc.log import RunLog
from abcwc.mapping.grid import OccupancyGrid
from abcwc.navigation.costmap import chair_footprint
from abcwc.perception.speech.synthesis import Voice
from abcwc.sim import SimBase
from abcwc.sim.people import circles_of
from abcwc.sim.world import World
from abcwc.types import Pose2D, SensorFrame

ENDED = (MissionState.ARRIVED, MissionState.FAILED)
ERRAND_VOICE = Voice("slt", engine="flite")
"""The voice an errand's command is spoken in: flite's slt, near a person's (espeak-ng's
formant voices are the recogniser's stress test, and its thresholds refuse most of
them, as chapter 04 shows)."""


@dataclass
class ErrandResult:
    """One errand, judged by the simulator's truth (module notes)."""

    world: str
    destination: str
    heard: str  # the phrase the mission obeyed
    heard_by: str  # "spoken" (synthesised and recognised) or "typed"
    state: str  # the mission's state at the end: "arrived", "failed", ...
    reason: str  # the mission's last reason
    seconds: float  # s of simulated time from the command to the end
    started_at: float  # s, the simulator's clock when the command was given
    wall_seconds: float  # s of wall time, mapping included
    distance: float  # m the chair drove (truth)
    final_error: float  # m from the true position to the destination
    tolerance: float  # m, the navigator's goal tolerance
    closest_person: float  # m, the chair's outline to the nearest walker (inf: none)
    interventions: int  # control periods the safety filter changed the command
    collisions: int  # contacts of the chair with anything
    max_localisation_error: float  # m, the estimate against the truth
    events: list[tuple[float, str, float, float]] = field(default_factory=list)  # t from
    # the command (s), name, the place's x, y (m)
    transitions: list[str] = field(default_factory=list)  # "t s: before -> after: reason"
    log: RunLog | None = None
    track: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    estimates: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    mapping_seconds: float = 0.0  # s of simulated time the mapping took (0: map loaded)
    mapping_collisions: int = 0  # contacts while mapping

    @property
    def arrived(self) -> bool:
        """The mission said arrived and the true position is within the tolerance."""
        return self.state == MissionState.ARRIVED.value and self.final_error <= self.tolerance

    def figures(self) -> dict[str, object]:
        """The errand's figures, as the report's table and ``--json`` give them."""
        return {
            "world": self.world, "destination": self.destination, "heard": self.heard,
            "heard_by": self.heard_by, "state": self.state, "arrived": self.arrived,
            "reason": self.reason, "seconds": round(self.seconds, 2),
            "mapping_seconds": round(self.mapping_seconds, 2),
            "mapping_collisions": self.mapping_collisions,
            "wall_seconds": round(self.wall_seconds, 1), "distance_m": round(self.distance, 2),
            "final_error_m": round(self.final_error, 3),
            "closest_person_m": round(self.closest_person, 3),
            "safety_interventions": self.interventions, "collisions": self.collisions,
            "max_localisation_error_m": round(self.max_localisation_error, 3),
            "events": [f"{name} at {t:.1f} s" for t, name, _, _ in self.events],
        }

    def summary(self) -> str:
        """One line: where, whether it arrived, in how long, and the safety figures."""
        outcome = "arrived" if self.arrived else f"FAILED ({self.reason})"
        events = "".join(f", {name} at {t:.1f} s" for t, name, _, _ in self.events)
        return (f"errand to the {self.destination} in {self.world} ({self.heard_by} "
                f'"{self.heard}"): {outcome} in {self.seconds:.1f} s, {self.distance:.1f} m, '
                f"{self.collisions} collisions, closest person {self.closest_person:.2f} m, "
                f"{self.interventions} safety interventions, localisation error max "
                f"{self.max_localisation_error:.3f} m{events}")


class ErrandJudge:
    """A controller around the mission that also keeps, every 0.1 s, the truth, the
    estimate and the closest approach to a person: the experiment's judge, not part of
    the chair (it reads the simulator's truth)."""

    def __init__(self, chair: SimBase, mission: Mission):
        self.chair, self.mission = chair, mission
        self.outline = chair_footprint(chair.params).polygon
        self.closest = math.inf
        self.worst = 0.0
        self.track: list[tuple[float, float, float]] = []
        self.estimates: list[tuple[float, float, float]] = []
        self._every = max(1, round(0.1 / chair.period))
        self._calls = 0

    @property
    def decided_at(self) -> float | None:
        return self.mission.decided_at

    def log_fields(self) -> dict[str, str]:
        return self.mission.log_fields()

    def __call__(self, frame: SensorFrame):
        command = self.mission(frame)
        truth, estimate = self.chair.pose, self.mission.navigator.localizer.pose
        if self.chair.walkers:
            self.closest = min(self.closest, gap_to_people(
                transform_points(truth, self.outline), circles_of(self.chair.walkers)))
        self.worst = max(self.worst, math.hypot(estimate.x - truth.x, estimate.y - truth.y))
        if self._calls % self._every == 0:
            self.track.append((truth.x, truth.y, truth.theta))
            self.estimates.append((estimate.x, estimate.y, estimate.theta))
        self._calls += 1
        return command


def spoken_command(text: str, places: dict[str, Pose2D]) -> tuple[object, str]:
    """``text`` synthesised in :data:`ERRAND_VOICE` and heard by the command recogniser:
    the recogniser's command and "spoken"; when that voice's synthesiser is not
    installed, a place's name is not in the recogniser's pronunciation dictionary, or the
    recogniser refuses what it heard, the typed path: ``text`` itself and "typed"."""
    from abcwc.perception.speech.commands import CommandSet
    from abcwc.perception.speech.recognizer import CommandRecognizer
    from abcwc.perception.speech.synthesis import engine_available, speak

    if not engine_available(ERRAND_VOICE.engine):
        return text, "typed"
    try:
        recogniser = CommandRecognizer(CommandSet(places))
    except ValueError:  # a place's name the recogniser has no pronunciation for
        return text, "typed"
    heard = recogniser.recognise(speak(text, ERRAND_VOICE))
    if heard.command is None:
        return text, "typed"
    return heard.command, "spoken"


def run_errand(mission: Mission, chair: SimBase, destination: str, spoken: bool = True,
               timeout: float = 300.0, progress: bool = False,
               on_event: Callable[[object], None] | None = None) -> ErrandResult:
    """Tell ``mission`` (on ``chair``) "go to the <destination>", spoken or typed, and
    drive until it arrives or fails (or ``timeout`` s); judged by the truth."""
    from abcwc.perception.speech.commands import place_phrase

    if destination not in mission.destinations:
        raise ValueError(f"no place {destination!r} on this floor; its places: "
                         f"{', '.join(sorted(mission.destinations))}")
    wall_start = time.perf_counter()
    text = f"go to the {place_phrase(destination)}"
    command, heard_by = spoken_command(text, mission.destinations) if spoken else (text, "typed")
    if on_event is not None:
        mission.subscribe(on_event)
    heard = mission.command(command)
    judge = ErrandJudge(chair, mission)
    collisions0, t0, start = chair.collisions, chair.t, chair.pose
    log = chair.run(judge, timeout, progress=progress,
                    until=lambda: mission.state in ENDED)
    state, reason = mission.state.value, mission.reason
    if mission.state not in ENDED:  # out of time: the chair stands, the errand failed
        mission.stop(f"out of time: {timeout:g} s without arriving")
        state, reason = MissionState.FAILED.value, mission.reason
    end = chair.pose
    goal = mission.destinations[destination]
    path = np.vstack([[start.x, start.y], log.pose[:, :2]])
    distance = float(np.sum(np.hypot(*np.diff(path, axis=0).T)))
    return ErrandResult(
        world=chair.world.name, destination=destination, heard=heard.phrase,
        heard_by=heard_by, state=state, reason=reason,
        seconds=chair.t - t0, started_at=t0, wall_seconds=time.perf_counter() - wall_start,
        distance=distance, final_error=math.hypot(goal.x - end.x, goal.y - end.y),
        tolerance=mission.navigator.settings.xy_goal_tolerance,
        closest_person=judge.closest, interventions=log.safety_interventions(),
        collisions=chair.collisions - collisions0, max_localisation_error=judge.worst,
        events=[(e.t - t0, e.name, *_place_xy(mission, e.place))
                for e in mission.events_fired if e.t >= t0],
        transitions=[f"{tr.t - t0:7.1f} s  {tr.before.value} -> {tr.after.value}: "
                     f"{tr.reason}" for tr in mission.transitions if tr.t >= t0],
        log=log, track=np.array(judge.track).reshape(-1, 3),
        estimates=np.array(judge.estimates).reshape(-1, 3))


def _place_xy(mission: Mission, place: str) -> tuple[float, float]:
    pose = mission.destinations[place]
    return pose.x, pose.y


def errand_destination(world: World, to: str | None) -> str:
    """The errand's destination in ``world``: ``to`` (a place of it), by default the
    cafeteria; ValueError naming the world's places otherwise."""
    choices = sorted(name for name in world.places if name != "start")
    if to is None:
        if "cafeteria" not in world.places:
            raise ValueError(f"{world.name} has no cafeteria: choose the errand's "
                             f"destination with --to, one of: {', '.join(choices)}")
        return "cafeteria"
    if to not in world.places or to == "start":
        raise ValueError(f"no place {to!r} in {world.name}; its places: {', '.join(choices)}")
    return to


def tour_of(world: World, start: Pose2D) -> list[tuple[float, float]]:
    """The points a mapping tour visits: the world's places (their coordinates are all
    the chair is told of the floor), nearest first from ``start``, then each next the
    nearest not yet visited, ending back at the start."""
    left = [(p.x, p.y) for name, p in world.places.items() if name != "start"]
    here, tour = (start.x, start.y), []
    while left:
        nearest = min(left, key=lambda q: math.hypot(q[0] - here[0], q[1] - here[1]))
        left.remove(nearest)
        tour.append(nearest)
        here = nearest
    return [*tour, (start.x, start.y)]


def mission_on_its_own_map(chair: SimBase, world: World, map_path: Path, ekf: ChairEkf,
                           progress: bool = False) -> tuple[Mission, MappedFloor]:
    """``chair`` (at ``world``'s start, its filter ``ekf``) maps the floor by a tour of its
    places (:func:`tour_of`, :func:`~abcwc.behaviours.explore.floor_map`, the map files
    at ``map_path``), and the mission that drives by that map, from where the mapping
    left the chair, to ``world``'s places."""
    floor = floor_map(chair, map_path, world.start, tour=tour_of(world, world.start),
                      ekf=ekf, progress=progress)
    mission = Mission.for_map(floor.built.cells, floor.built.grid, floor.pose,
                              dict(world.places), chair.params, ekf=floor.ekf)
    return mission, floor


def capstone_errand(world: World, destination: str, seed: int = 0, out: str | Path | None = None,
                    spoken: bool = True, people: bool = True, progress: bool = False,
                    timeout: float = 300.0) -> tuple[ErrandResult, OccupancyGrid, list[str]]:
    """The capstone (module notes): on ``world``'s simulator (its walkers walking unless
    ``people`` is False; lidar on; seed ``seed``) the chair learns its gyro's bias
    standing still, maps the floor by a tour of its places (map_server files
    ``map.yaml``/``map.pgm`` in ``out``), and is then told, spoken unless ``spoken`` is
    False, to go to ``destination``. With ``out`` the map files and the errand's RunLog
    (``errand.npz``) are written there (the report is :func:`abcwc.viz.report.
    write_errand_report`'s). Returns the result, the chair's map and the files written."""
    import tempfile

    wall_start = time.perf_counter()
    chair = SimBase(world, seed=seed, lidar=True, people=people)
    ekf = calibrated_ekf(chair)
    with tempfile.TemporaryDirectory() as scratch:
        folder = Path(out) if out is not None else Path(scratch)
        folder.mkdir(parents=True, exist_ok=True)
        map_path = folder / "map.yaml"
        for stale in (map_path, map_path.with_suffix(".pgm")):
            stale.unlink(missing_ok=True)  # the demo maps the floor every time
        mapping_t0, contacts0 = chair.t, chair.collisions
        mission, floor = mission_on_its_own_map(chair, world, map_path, ekf, progress)
        mapping_seconds = chair.t - mapping_t0
        result = run_errand(mission, chair, destination, spoken=spoken, timeout=timeout,
                            progress=progress)
        result.mapping_seconds = mapping_seconds
        result.mapping_collisions = chair.collisions - contacts0 - result.collisions
        result.wall_seconds = time.perf_counter() - wall_start
        files: list[str] = []
        if out is not None:
            log_path = result.log.save(folder / "errand.npz")  # type: ignore[union-attr]
            files = [str(map_path), str(log_path)]
    return result, floor.built.grid, files


def run_errands(count: int = 20, seed: int = 0, world: World | str = "floor",
                progress: bool = False) -> list[ErrandResult]:
    """``count`` errands one after another on ``world`` among its walking people, each to
    a seeded random place (not the one the chair is at), typed, from the map the chair
    made itself by a tour (:func:`capstone_errand`'s mapping, once): the capstone's
    trial. Each result is judged by the simulator's truth."""
    import tempfile

    from abcwc.sim.world import load_world

    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        raise ValueError(f"count must be a whole number >= 1, got {count!r}")
    world = load_world(world) if isinstance(world, str) else world
    names = sorted(name for name in world.places if name != "start")
    if len(names) < 2:
        raise ValueError(f"{world.name} needs two places besides the start for errands")
    chair = SimBase(world, seed=seed, lidar=True, people=True)
    ekf = calibrated_ekf(chair)
    with tempfile.TemporaryDirectory() as scratch:
        mission, _ = mission_on_its_own_map(chair, world, Path(scratch) / "map.yaml", ekf,
                                            progress)
    rng = np.random.default_rng(seed)
    results: list[ErrandResult] = []
    here: str | None = None
    steps = range(count)
    if progress:
        from tqdm.auto import tqdm

        steps = tqdm(steps, desc="errands", unit="errand")
    for _ in steps:
        choices = [name for name in names if name != here]
        here = choices[int(rng.integers(len(choices)))]
        results.append(run_errand(mission, chair, here, spoken=False))
    return results


def errands_table(results: list[ErrandResult]) -> str:
    """The trial's results, one line per errand, then the totals."""
    lines = [f"{'#':>2}  {'to':<14}{'outcome':<10}{'s':>7}{'m':>7}{'closest':>9}"
             f"{'loc err':>9}{'contacts':>9}"]
    for k, r in enumerate(results):
        lines.append(f"{k:>2}  {r.destination:<14}{'arrived' if r.arrived else 'FAILED':<10}"
                     f"{r.seconds:>7.1f}{r.distance:>7.1f}{r.closest_person:>9.2f}"
                     f"{r.max_localisation_error:>9.3f}{r.collisions:>9d}")
    arrived = sum(r.arrived for r in results)
    lines.append(f"arrived {arrived} of {len(results)}; contacts "
                 f"{sum(r.collisions for r in results)}; closest person "
                 f"{min(r.closest_person for r in results):.2f} m; localisation error max "
                 f"{max(r.max_localisation_error for r in results):.3f} m")
    for k, r in enumerate(results):
        if not r.arrived:
            lines.append(f"errand {k} to the {r.destination}: {r.reason}")
    return "\n".join(lines)


__all__ = ["ENDED", "ERRAND_VOICE", "ErrandJudge", "ErrandResult", "capstone_errand",
           "errand_destination", "errands_table", "mission_on_its_own_map", "run_errand",
           "run_errands", "spoken_command", "tour_of"]
