"""Graph SLAM over a laser log: keyframes, scan-matched edges, loop closures, one solve.

The graph-based formulation of Grisetti, Kümmerle, Stachniss and Burgard, "A tutorial
on graph-based SLAM" (IEEE ITS Magazine, 2010): the front end turns scans into a pose
graph, the back end (:func:`abcwc.mapping.posegraph.optimise`) finds the poses that
agree best with all its edges.

Front end, scan by scan:

1. **Keyframes.** A scan becomes a keyframe when odometry says the robot moved
   ``linear_update`` m or turned ``angular_update`` rad since the last one (RTAB-Map's
   ``RGBD/LinearUpdate`` and ``RGBD/AngularUpdate``); the scans between ride on it.
2. **Odometry edges.** The new keyframe's scan is matched by point-to-line ICP
   (:func:`abcwc.mapping.icp.icp`) against a local submap: the last ``submap_size``
   keyframes' points in the current estimate's frame, starting from where odometry puts
   it. The edge to the previous keyframe is the matched relative pose; a failed match
   keeps odometry's. ICP's Hessian covariance is optimistic by orders of magnitude
   along corridors, so each edge gets a fixed information (``edge_sigma``) instead.
3. **Loop closures.** Older keyframes (at least ``loop_separation`` keyframes back)
   whose estimate lies within ``loop_radius`` m of the new one are candidates; the new
   scan is matched against a submap around each, and kept as an edge when enough of its
   points pair up (``loop_fitness``) closely (``loop_rms``) and the match is pinned down
   in every direction (ICP's position covariance no more than ``loop_anisotropy`` times
   longer than wide: a corridor matches anywhere along itself). Loop edges go to the solver
   with a robust kernel (``robust``), so a wrong one that slips through cannot bend the
   map.
4. **Solving.** After a keyframe that closed a loop the graph is solved again from the
   current estimate; at the end once more. Every scan's pose is then its keyframe's
   pose composed with odometry's motion since the keyframe.

All settings are one set of defaults for every log; the only facts given per log are
those the file does not carry (its laser's maximum range and mounting).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from abcwc.geometry import compose, inverse_transform_points, relative, transform_points
from abcwc.mapping.carmen import CarmenLog
from abcwc.mapping.g2o import PoseGraph
from abcwc.mapping.grid import OccupancyGrid
from abcwc.mapping.icp import IcpResult, TooFewPairsError, icp
from abcwc.mapping.posegraph import optimise


@dataclass(frozen=True)
class SlamSettings:
    """The front end's settings (m, rad); see the module notes."""

    linear_update: float = 0.2
    angular_update: float = 0.2
    submap_size: int = 6
    point_spacing: float = 0.05  # m: submap points thinned to about one per this
    loop_radius: float = 4.0
    loop_separation: int = 20
    loop_candidates: int = 3
    loop_fitness: float = 0.7
    loop_rms: float = 0.05
    loop_anisotropy: float = 25.0  # largest / smallest position variance a loop may show
    edge_sigma: tuple[float, float, float] = (0.05, 0.05, 0.01)
    loop_sigma: tuple[float, float, float] = (0.1, 0.1, 0.02)
    robust: str | None = "cauchy"
    max_correspondence_distance: float = 0.5


@dataclass
class SlamResult:
    """What a run built: ``keyframes`` (scan index of each), their optimised ``poses``
    (K, 3), the pose ``graph`` (initial poses: the front end's), every scan's ``scan_poses``
    (N, 3), the wall-clock ``seconds``, and the closed loops as keyframe pairs
    (``loop_edges``)."""

    keyframes: np.ndarray
    poses: np.ndarray
    graph: PoseGraph
    scan_poses: np.ndarray
    seconds: float
    loop_edges: list[tuple[int, int]] = field(default_factory=list)

    @property
    def loops(self) -> int:
        """How many loop closures were kept."""
        return len(self.loop_edges)


def _information(sigma: tuple[float, float, float]) -> np.ndarray:
    return np.diag(1.0 / np.square(np.asarray(sigma, dtype=float)))


def thin(points: np.ndarray, spacing: float) -> np.ndarray:
    """One point per ``spacing`` m square (the first), so dense stretches do not outvote
    sparse ones and the KD-trees stay small."""
    if len(points) == 0:
        return points
    keys = np.floor(points / spacing).astype(np.int64)
    _, first = np.unique(keys, axis=0, return_index=True)
    return points[np.sort(first)]


def select_keyframes(odometry: np.ndarray, linear: float, angular: float) -> np.ndarray:
    """Scan indices where the robot has moved ``linear`` m or turned ``angular`` rad
    (by odometry) since the previous keyframe; scan 0 is the first."""
    keyframes = [0]
    last = odometry[0]
    for k in range(1, len(odometry)):
        step = np.asarray(relative(last, odometry[k]))
        if math.hypot(step[0], step[1]) >= linear or abs(step[2]) >= angular:
            keyframes.append(k)
            last = odometry[k]
    return np.array(keyframes)


class _Submaps:
    """Each keyframe's thinned points (robot frame) and the current pose estimates."""

    def __init__(self, spacing: float):
        self.spacing = spacing
        self.points: list[np.ndarray] = []

    def around(self, poses: np.ndarray, keyframes: range) -> np.ndarray:
        """The points of ``keyframes`` in the map frame, thinned."""
        clouds = [transform_points(poses[k], self.points[k]) for k in keyframes]
        return thin(np.vstack(clouds), self.spacing) if clouds else np.zeros((0, 2))


def run_slam(log: CarmenLog, settings: SlamSettings | None = None,
             progress: bool = False) -> SlamResult:
    """Graph SLAM over ``log``; see the module notes. ``progress`` shows a tqdm bar."""
    s = settings or SlamSettings()
    start_time = time.perf_counter()
    odometry = np.asarray(log.odometry, dtype=float)
    keyframes = select_keyframes(odometry, s.linear_update, s.angular_update)
    submaps = _Submaps(s.point_spacing)
    poses = np.zeros((len(keyframes), 3))
    poses[0] = odometry[0]
    edges: list[tuple[int, int]] = []
    measurements: list[np.ndarray] = []
    informations: list[np.ndarray] = []
    loop_edges: list[tuple[int, int]] = []
    edge_info, loop_info = _information(s.edge_sigma), _information(s.loop_sigma)
    iterator = range(len(keyframes))
    if progress:
        from tqdm.auto import tqdm

        iterator = tqdm(iterator, desc="SLAM", unit="keyframe")
    for k in iterator:
        scan = keyframes[k]
        points = thin(log.points(scan, frame="base"), s.point_spacing)
        submaps.points.append(points)
        if k == 0:
            continue
        guess = np.asarray(compose(poses[k - 1], relative(odometry[keyframes[k - 1]],
                                                          odometry[scan])))
        matched = _match(points, submaps.around(poses, range(max(0, k - s.submap_size), k)),
                         guess, s)
        poses[k] = guess if matched is None else matched.pose
        edges.append((k - 1, k))
        measurements.append(np.asarray(relative(poses[k - 1], poses[k])))
        informations.append(edge_info)
        closed = _close_loops(k, points, poses, submaps, s)
        for candidate, measured in closed:
            edges.append((candidate, k))
            measurements.append(measured)
            informations.append(loop_info)
            loop_edges.append((candidate, k))
        if closed:
            poses[: k + 1] = _solve(_graph(poses[: k + 1], edges, measurements, informations),
                                    s)
    graph = _graph(poses, edges, measurements, informations)
    if edges:
        poses = _solve(graph, s)
    return SlamResult(keyframes, poses, graph, scan_poses(poses, keyframes, odometry),
                      time.perf_counter() - start_time, loop_edges)


def _match(points: np.ndarray, submap: np.ndarray, guess: np.ndarray,
           s: SlamSettings) -> IcpResult | None:
    """ICP of ``points`` (robot frame) onto ``submap`` (map frame) from the map pose
    ``guess``; the result's pose is the matched map pose. None if ICP cannot pair enough
    points. The match runs in the guess's own frame: rotations about a map origin
    hundreds of metres away would make each linearised step needlessly poor."""
    if len(points) < 3 or len(submap) < 3:
        return None
    try:
        result = icp(points, inverse_transform_points(guess, submap), (0.0, 0.0, 0.0),
                     max_correspondence_distance=s.max_correspondence_distance)
    except TooFewPairsError:
        return None
    return replace(result, pose=np.asarray(compose(guess, result.pose)))


def _close_loops(k: int, points: np.ndarray, poses: np.ndarray, submaps: _Submaps,
                 s: SlamSettings) -> list[tuple[int, np.ndarray]]:
    """Verified loop edges ``(candidate, measured relative pose)`` from keyframe ``k``."""
    older = k - s.loop_separation
    if older <= 0 or len(points) < 3:
        return []
    distances = np.hypot(*(poses[:older, :2] - poses[k, :2]).T)
    near = np.flatnonzero(distances < s.loop_radius)
    closed = []
    for candidate in near[np.argsort(distances[near])][: s.loop_candidates]:
        window = range(max(0, candidate - s.submap_size // 2),
                       min(older, candidate + s.submap_size // 2 + 1))
        result = _match(points, submaps.around(poses, window), poses[k], s)
        if result is not None and _trustworthy(result, s):
            closed.append((int(candidate), np.asarray(relative(poses[candidate], result.pose))))
    return closed


def _trustworthy(result: IcpResult, s: SlamSettings) -> bool:
    """A loop match is kept when most points pair up closely and the match is fixed in
    every direction: in a corridor ICP finds a perfect fit anywhere along it, which shows
    as a position covariance far longer than it is wide (the classic false loop)."""
    if result.fitness < s.loop_fitness or result.rms > s.loop_rms:
        return False
    variances = np.linalg.eigvalsh(result.covariance[:2, :2])
    return bool(variances[0] > 0 and variances[1] <= s.loop_anisotropy * variances[0])


def _graph(poses: np.ndarray, edges: list[tuple[int, int]], measurements: list[np.ndarray],
           informations: list[np.ndarray]) -> PoseGraph:
    n = len(poses)
    return PoseGraph(np.arange(n), poses.copy(), np.array(edges, dtype=np.int64).reshape(-1, 2),
                     np.array(measurements).reshape(-1, 3),
                     np.array(informations).reshape(-1, 3, 3))


def _solve(graph: PoseGraph, s: SlamSettings) -> np.ndarray:
    """The graph's poses optimised from where they are, with the settings' kernel."""
    solved, _ = optimise(graph, robust=s.robust, initial="given")
    return solved


def scan_poses(keyframe_poses: np.ndarray, keyframes: np.ndarray,
               odometry: np.ndarray) -> np.ndarray:
    """Every scan's pose (N, 3): its latest keyframe's pose composed with odometry's
    motion from that keyframe to the scan."""
    owner = np.searchsorted(keyframes, np.arange(len(odometry)), side="right") - 1
    since = relative(odometry[keyframes[owner]], odometry)
    return np.asarray(compose(keyframe_poses[owner], since))


def render(log: CarmenLog, poses: np.ndarray, scans: np.ndarray | None = None,
           resolution: float = 0.05) -> OccupancyGrid:
    """An occupancy grid from ``scans`` (indices; default every scan) at ``poses`` (one
    robot pose per scan of the log)."""
    laser = np.asarray(compose(poses, log.laser_offset))
    rows = np.arange(len(log)) if scans is None else np.asarray(scans)
    ends = np.vstack([transform_points(laser[k], log.points(k)) for k in rows]
                     + [laser[rows, :2]])
    grid = OccupancyGrid.covering(*ends.min(axis=0), *ends.max(axis=0), resolution,
                                  margin=1.0)
    for k in rows:
        grid.integrate(log.scan(int(k)), laser[k])
    return grid
