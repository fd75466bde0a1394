"""The follower's trials: a person with a tag walks two minutes round the lab, or 55 s
through a building, the chair follows.

Ana wears a :class:`~abcwc.perception.tags.FollowCard` on her back and walks a loop of
the lab at 0.7 m/s, round both tables, with six turns of 90 degrees or more; Ben, who
wears nothing, hurries (1.2 m/s) back and forth across her way, between her and the
chair, three times in the two minutes, so the chair loses sight of her and must wait
for him. The chair starts 1.2 m behind her with the lidar and the colour camera (grey)
on. In the building (``data/worlds/building.json``: a corridor 2 m wide that turns north
at its east end, rooms on both sides behind 0.9 m doors) she walks along the corridor,
into the north room by one door and out by the other, into the south room and out, and
round the corner; Carl overtakes the chair from behind at 1.3 m/s, and Dora crosses the
corridor between the chair and her, through the door she takes (:func:`building_follow_world`;
nothing in the follower is set for this building). The simulator's ground truth only
*judges* the follower:

* ``distance``: from the camera to the card on Ana's back (m), every 0.1 s;
* ``seen``: whether the follower read the tag in that decision;
* ``collisions``: pymunk contacts of the chair with a wall or a person;
* ``closest_person``: the smallest gap (m) between the chair's outline and a person;
* the longest stop with the way clear (:meth:`FollowResult.longest_needless_stop`).

``abcwc followtrial`` runs both trials on three seeds, with A.13's follower on the same
walks (:func:`run_trial_in`, :func:`trials_table`).

:func:`hand_over_demo` shows the follower's hand-over to the navigator on its own: two
rooms joined by one door at the far end of the wall between them, a map of the one scan
the chair took where it stands, and the navigator sent behind the wall
(:class:`~abcwc.behaviours.follow_handover.HandOver`).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import numpy as np

from abcwc.behaviours.base import Status
from abcwc.behaviours.follow import FollowLaw, FollowSettings, TagFollower, ThesisFollower
from abcwc.behaviours.follow_handover import HandOver
from abcwc.estimation.gyro import GyroOdometry
from abcwc.experiments.disk_cache import cached_on_disk
from abcwc.experiments.navigation_trial import gap_to_people
from abcwc.geometry import compose, transform_points
from abcwc.mapping.grid import OccupancyGrid
from abcwc.paths import data_dir
from abcwc.sim import SimBase
from abcwc.sim.people import circles_of
from abcwc.sim.world import World, world_from_dict
from abcwc.types import LIDAR_FRAME, Pose2D

ANA_PATH = [[2.7, 1.4], [5.2, 1.1], [8.7, 1.0], [8.8, 3.6], [5.4, 3.9], [5.3, 6.8],
            [2.0, 6.8], [1.6, 3.5]]
"""m: Ana's loop of the lab (the chair starts at the lab's start, (1.5, 1.5))."""
BEN_PATH = [[4.0, 0.4], [4.6, 3.0]]
"""m: Ben's line across the lab's south side, walked back and forth."""
BUILDING_ANA_PATH = [[2.2, 1.2], [4.25, 1.2], [4.25, 4.0], [7.75, 4.0], [7.75, 1.2],
                     [10.95, 1.2], [10.95, -2.5], [14.55, -2.5], [14.55, 1.0], [19.0, 1.0],
                     [19.0, 8.0]]
"""m: Ana's way through the building (36.6 m, 52 s at 0.7 m/s): along the corridor,
into the north room by its west door and out by its east one, into the south room and
out, and round the corner up the north corridor."""
CARL_PATH = [[-5.5, 0.45], [18.5, 0.45], [18.5, 9.5]]
"""m: Carl's way, 1.3 m/s from behind the chair, overtaking it and Ana on their right."""
DORA_PATH = [[12.75, 4.0], [12.75, 2.4], [10.95, -0.3], [10.95, -2.0]]
"""m: Dora's way, back and forth at 1.0 m/s from the north room across the corridor into
the south room by the door Ana takes: she crosses between the chair and Ana."""
BUILDING_SECONDS = 55.0
"""s: the building trial's length (Ana reaches the end of her way at 52 s)."""


def follow_world(passer_by: bool = True) -> World:
    """The lab with Ana (tag: ArUco 7 and a QR code "ana") and, with ``passer_by``,
    Ben."""
    raw = json.loads((data_dir() / "worlds" / "lab.json").read_text())
    raw["people"] = [{"name": "ana", "speed": 0.7, "loop": True, "path": ANA_PATH,
                      "tag": {"text": "ana", "marker_id": 7, "side": 0.2}}]
    if passer_by:
        raw["people"].append({"name": "ben", "speed": 1.2, "loop": False, "path": BEN_PATH})
    raw["description"] = "The lab, with Ana (who wears a tag) and Ben walking."
    return world_from_dict(raw)


def building_follow_world(walkers: bool = True) -> World:
    """The building (``data/worlds/building.json``) with Ana (the same tag) and, with
    ``walkers``, Carl (from behind) and Dora (across)."""
    raw = json.loads((data_dir() / "worlds" / "building.json").read_text())
    raw["people"] = [{"name": "ana", "speed": 0.7, "loop": False, "path": BUILDING_ANA_PATH,
                      "tag": {"text": "ana", "marker_id": 7, "side": 0.2}}]
    if walkers:
        raw["people"] += [{"name": "carl", "speed": 1.3, "loop": False, "path": CARL_PATH},
                          {"name": "dora", "speed": 1.0, "loop": False, "path": DORA_PATH}]
    raw["description"] = "The building, with Ana (who wears a tag), Carl and Dora walking."
    return world_from_dict(raw)


@dataclass
class FollowResult:
    """One run of a follower (module notes); arrays at 10 Hz."""

    t: np.ndarray
    distance: np.ndarray  # m, camera to the card (truth)
    seen: np.ndarray  # bool: the tag read in that decision
    v: np.ndarray  # m/s sent (after the body's safety filter)
    w: np.ndarray  # rad/s sent (after the body's safety filter)
    states: list[str] = field(default_factory=list)
    collisions: int = 0
    closest_person: float = math.inf  # m
    status: str = "running"
    failure: str | None = None
    track: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # chair, truth
    people: np.ndarray = field(default_factory=lambda: np.zeros((0, 0, 2)))

    def held(self, distance: float = 1.0, tolerance: float = 0.3) -> float:
        """Fraction of the decisions with the tag read in which the chair was within
        ``tolerance`` of ``distance``."""
        inside = np.abs(self.distance - distance) <= tolerance
        return float(inside[self.seen].mean()) if self.seen.any() else 0.0

    def longest_blind(self) -> float:
        """s: the longest stretch without reading the tag."""
        stamps = np.concatenate([[self.t[0]], self.t[self.seen], [self.t[-1]]])
        return float(np.diff(stamps).max())

    def longest_needless_stop(self, clear: float = 1.5, behind: float = 1.3) -> float:
        """s: the longest stretch in which the chair stood (under 0.05 m/s and
        0.05 rad/s sent) though Ana was more than ``behind`` m ahead (distance to her
        card) and no other person was within ``clear`` m of the chair: a stop with the
        way along her trail clear (she walked it), judged by the simulator's truth."""
        if not len(self.t):
            return 0.0
        others = self.people[:, 1:] if self.people.ndim == 3 else np.zeros((len(self.t), 0, 2))
        near = (np.hypot(*(others - self.track[:, None, :2]).transpose(2, 0, 1)) < clear
                ).any(axis=1) if others.shape[1] else np.zeros(len(self.t), bool)
        still = (np.abs(self.v) < 0.05) & (np.abs(self.w) < 0.05)
        needless = still & (self.distance > behind) & ~near
        longest = run = 0
        for flag in needless:
            run = run + 1 if flag else 0
            longest = max(longest, run)
        return 0.1 * longest

    def figures(self) -> dict[str, float | int | str]:
        """The run's figures (the issue's bars): share held (%), tag read (%),
        collisions, closest to a person (m), final distance (m), longest needless stop
        (s), status."""
        return {"held_percent": 100 * self.held(), "tag_read_percent": 100 * self.seen.mean(),
                "collisions": self.collisions, "closest_person": self.closest_person,
                "final_distance": float(self.distance[-1]),
                "longest_needless_stop": self.longest_needless_stop(),
                "status": self.status + (f" ({self.failure})" if self.failure else "")}

    def summary(self) -> str:
        return "\n".join([
            f"{self.t[-1] - self.t[0] + 0.1:.0f} s; tag read in {100 * self.seen.mean():.0f} % "
            f"of the decisions; longest without it {self.longest_blind():.1f} s",
            f"distance to the tag: median {np.median(self.distance):.2f} m, "
            f"{100 * self.held():.1f} % of the readings within 1.0 +- 0.3 m",
            f"collisions: {self.collisions}; closest to a person: {self.closest_person:.2f} m",
            f"at the end {self.distance[-1]:.2f} m from her card; longest stop with the "
            f"way clear {self.longest_needless_stop():.1f} s",
            f"status: {self.status}" + (f" ({self.failure})" if self.failure else ""),
        ])


def run_follow_trial(seconds: float = 120.0, seed: int = 0, thesis: bool = False,
                     passer_by: bool = True, settings: FollowSettings | None = None,
                     law: FollowLaw | None = None, world: World | None = None
                     ) -> FollowResult:
    """Run :class:`TagFollower` (with ``law`` if given; with ``thesis``, A.13's
    :class:`ThesisFollower`) for ``seconds`` in ``world`` (default
    :func:`follow_world`; its first person wears the tag) (module notes)."""
    world = world or follow_world(passer_by)
    chair = SimBase(world, seed=seed, lidar=True, camera="gray")
    ana = chair.walkers[0]
    card = ana.spec.tag
    assert card is not None
    follower: TagFollower | ThesisFollower
    if thesis:
        follower = ThesisFollower(card, chair.params)
    else:
        follower = TagFollower(card, GyroOdometry(params=chair.params), chair.params, settings,
                               law)
    outline = np.asarray(chair.params.footprint, dtype=float)
    rows, track, people = [], [], []
    closest = math.inf
    frame = chair.read()
    every = round(0.1 / chair.period)
    for k in range(round(seconds / chair.period)):
        sent = chair.send(follower(frame), follower.decided_at)  # after the safety filter
        frame = chair.step()
        circles = circles_of(chair.walkers)
        chair_outline = transform_points(chair.pose, outline)
        closest = min(closest, gap_to_people(chair_outline, circles))
        if k % every == every - 1:
            card_target = ana.tag_target()
            origin = compose(chair.pose, chair.params.depth_scan.mount)[:2]
            distance = math.hypot(card_target.centre[0] - origin[0],
                                  card_target.centre[1] - origin[1])
            last = follower.log[-1] if follower.log else (0, math.nan, 0, 0, 0, "")
            rows.append((chair.t, distance, math.isfinite(last[1]), sent.v, sent.w))
            track.append((chair.pose.x, chair.pose.y, chair.pose.theta))
            people.append(circles[:, :2].copy())
    t, distance, seen, v, w = (np.array(c) for c in zip(*rows))
    return FollowResult(t, distance, seen.astype(bool), v, w,
                        [entry[5] for entry in follower.log], chair.collisions, closest,
                        follower.status.value, follower.failure, np.array(track),
                        np.array(people))


TRIAL_WORLDS = ("lab", "building")
"""The follow trials' worlds: :func:`follow_world` and :func:`building_follow_world`."""


def run_trial_in(where: str, seed: int = 0, thesis: bool = False) -> FollowResult:
    """The follow trial ``where`` (one of :data:`TRIAL_WORLDS`): two minutes in the lab,
    or ``BUILDING_SECONDS`` in the building, for one ``seed``. A seeded drive: its
    result is kept on disk (:func:`~abcwc.experiments.disk_cache.cached_on_disk`), so
    chapter 17, its student copy and the follower's tests drive each trial once."""
    if where not in TRIAL_WORLDS:
        raise ValueError(f"unknown follow trial {where!r}; allowed: {', '.join(TRIAL_WORLDS)}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise ValueError(f"seed must be a whole number, got {seed!r}")
    return _trial_in(where, int(seed), bool(thesis))


@cached_on_disk
def _trial_in(where: str, seed: int, thesis: bool) -> FollowResult:
    if where == "lab":
        return run_follow_trial(seconds=120.0, seed=seed, thesis=thesis)
    return run_follow_trial(seconds=BUILDING_SECONDS, seed=seed, thesis=thesis,
                            world=building_follow_world())


def trials_table(results: dict[tuple[str, str, int], FollowResult]) -> str:
    """One line per run, keyed (world, follower, seed): the figures of
    :meth:`FollowResult.figures`."""
    lines = [f"{'world':9s}{'follower':10s}{'seed':>5s}{'held %':>8s}{'tag %':>7s}"
             f"{'contacts':>9s}{'closest m':>10s}{'end m':>7s}{'stop s':>7s}  status"]
    for (where, who, seed), result in results.items():
        f = result.figures()
        lines.append(f"{where:9s}{who:10s}{seed:5d}{f['held_percent']:8.1f}"
                     f"{f['tag_read_percent']:7.1f}{f['collisions']:9d}"
                     f"{f['closest_person']:10.2f}{f['final_distance']:7.2f}"
                     f"{f['longest_needless_stop']:7.1f}  {f['status']}")
    return "\n".join(lines)


def two_rooms_world() -> World:
    """Two rooms, 4 x 6 m each, joined only by a 1 m door at the north end of the wall
    between them (x = 4 m, the door from y = 4.5 to 5.5 m); the chair in the west room
    at (1.5, 1.5), facing the wall."""
    return world_from_dict({
        "name": "two rooms", "description": "Two rooms joined by one door.", "walls": [
            [[0, 0], [8, 0], [8, 6], [0, 6], [0, 0]], [[4, 0], [4, 4.5]], [[4, 5.5], [4, 6]]],
        "places": {"start": [1.5, 1.5, 0.0]}, "people": []})


@dataclass
class HandOverDemo:
    """What :func:`hand_over_demo` drove: the map handed over (one scan), the
    navigator's first plan (K, 2) m, the chair's true track (N, 3), the goal (m), the
    seconds it took, how it ended and the contacts."""

    grid: OccupancyGrid  # the map handed over
    plan: np.ndarray
    track: np.ndarray
    goal: tuple[float, float]
    seconds: float
    status: str
    collisions: int

    def summary(self) -> str:
        end = self.track[-1]
        return (f"the navigator {self.status} in {self.seconds:.1f} s, "
                f"{math.hypot(end[0] - self.goal[0], end[1] - self.goal[1]):.2f} m from "
                f"the goal, through the door (highest y {self.track[:, 1].max():.2f} m); "
                f"contacts {self.collisions}")


def hand_over_demo(goal: tuple[float, float] = (6.0, 1.5), seconds: float = 60.0,
                   seed: int = 0) -> HandOverDemo:
    """The hand-over on its own (module notes): in :func:`two_rooms_world`, the map of
    the chair's first scan handed to the navigator, sent to ``goal`` behind the wall;
    driven until it ends or ``seconds`` have passed."""
    chair = SimBase(two_rooms_world(), seed=seed, lidar=True)
    hand_over = HandOver(chair.params)
    frame = chair.read()
    while LIDAR_FRAME not in frame.readings:
        frame = chair.step()
    start = chair.pose  # the odom frame is the world's here: the chair starts at rest
    sensor = compose(start, Pose2D(*chair.params.lidar.mount))
    hand_over.lay(frame.readings[LIDAR_FRAME], sensor)
    why_not = hand_over.start(frame.t, start, np.array([goal], dtype=float))
    if why_not is not None:
        raise ValueError(f"the hand-over could not start: {why_not}")
    assert hand_over.navigator is not None and hand_over.navigator.path is not None
    plan = hand_over.navigator.path.points.copy()
    began, track = frame.t, [chair.pose.as_array()]
    while hand_over.status is Status.RUNNING and frame.t - began < seconds:
        hand_over.observe(frame)
        chair.send(hand_over.command, frame.t)
        frame = chair.step()
        track.append(chair.pose.as_array())
    status = hand_over.status.value if hand_over.status is not None else "ended"
    assert hand_over.grid is not None
    return HandOverDemo(hand_over.grid, plan, np.array(track), goal, frame.t - began,
                        status, chair.collisions)


__all__ = ["ANA_PATH", "BEN_PATH", "BUILDING_ANA_PATH", "BUILDING_SECONDS", "CARL_PATH",
           "DORA_PATH", "TRIAL_WORLDS", "FollowResult", "HandOverDemo", "building_follow_world",
           "follow_world", "hand_over_demo", "run_follow_trial", "run_trial_in",
           "trials_table", "two_rooms_world"]
