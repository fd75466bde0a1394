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
   whose estimate lies within ``loop_radius`` m of the new one, more the further the
   robot has gone since (drift), are candidates; the new scan is matched against a
   submap around each (ICP, and where the drift is beyond ICP's reach the correlative
   matcher first), and kept as an edge when enough of its
   points pair up (``loop_fitness``) closely (``loop_rms``) and the match is pinned down
   in every direction (ICP's position covariance no more than ``loop_anisotropy`` times
   longer than wide: a corridor matches anywhere along itself). Loop edges go to the solver
   with a robust kernel (``robust``), so a wrong one that slips through cannot bend the
   map.
4. **Solving.** After a keyframe that closed a loop the graph is solved again from the
   current estimate; at the end once more.
5. **Every scan.** A scan between two keyframes starts from the pose interpolated in
   time between theirs, and is then matched (ICP) against the submap of the keyframes
   round it at their optimised poses. Wheel odometry is worst at the turns, where a
   robot's scans change fastest (MIT CSAIL's odometry reports some turns a third short,
   others twice too long), so neither it nor a pose that rode on it is a good enough
   start. Scans after the last keyframe ride on odometry.

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
from abcwc.mapping.correlative import LikelihoodField, correlative_match
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
    loop_drift: float = 0.05  # m of possible drift per m travelled (scan-matched odometry)
    loop_radius_max: float = 10.0
    loop_search_every: int = 3
    loop_search_xy: float = 2.0  # m, the correlative loop search's window, each way
    loop_search_theta: float = math.radians(20)
    loop_separation: int = 20
    loop_candidates: int = 3
    loop_fitness: float = 0.7
    loop_rms: float = 0.05
    loop_anisotropy: float = 25.0  # largest / smallest position variance a loop may show
    edge_sigma: tuple[float, float, float] = (0.05, 0.05, 0.01)
    loop_sigma: tuple[float, float, float] = (0.1, 0.1, 0.02)
    robust: str | None = "cauchy"
    max_correspondence_distance: float = 0.5
    sequential_fitness: float = 0.8  # below it, a sequential match is searched again
    search_xy: float = 0.4  # m, the correlative search's window, each way
    search_theta: float = math.radians(30)
    search_radius: float = 15.0  # m: points beyond are left out of the search
    search_spacing: float = 0.15  # m: the searched scan thinned to about one point per


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
    laser_offset: np.ndarray = field(default_factory=lambda: np.zeros(3))

    @property
    def laser_poses(self) -> np.ndarray:
        """Every scan's laser pose (N, 3): ``scan_poses`` (the robot's) composed with the
        laser's mount. The benchmark's relations relate these ("the pose of the scan");
        for FR079, whose laser sits 0.04 m ahead of the base, the two differ by up to
        0.08 m across a turn."""
        offset = np.broadcast_to(np.asarray(self.laser_offset, dtype=float),
                                 self.scan_poses.shape)
        return np.asarray(compose(self.scan_poses, offset)).reshape(-1, 3)

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
    along = np.zeros(len(keyframes))  # m along the estimated path
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
        matched = _match_sequential(points, submaps.around(
            poses, range(max(0, k - s.submap_size), k)), guess, s)
        poses[k] = guess if matched is None else matched.pose
        edges.append((k - 1, k))
        measurements.append(np.asarray(relative(poses[k - 1], poses[k])))
        informations.append(edge_info)
        along[k] = along[k - 1] + math.hypot(*(poses[k, :2] - poses[k - 1, :2]))
        closed = _close_loops(k, points, poses, submaps, s, along)
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
    every = _register_between(log, poses, keyframes, submaps,
                              _interpolated(poses, keyframes, odometry, log.stamps), s)
    return SlamResult(keyframes, poses, graph, every, time.perf_counter() - start_time,
                      loop_edges, np.asarray(log.laser_offset, dtype=float))


def _interpolated(poses: np.ndarray, keyframes: np.ndarray, odometry: np.ndarray,
                  stamps: np.ndarray) -> np.ndarray:
    """Each scan's pose interpolated in time between the keyframes either side (the
    relative motion scaled, a first-order approximation for motions this small); after
    the last keyframe, odometry's motion from it."""
    out = scan_poses(poses, keyframes, odometry)
    stamps = np.asarray(stamps, dtype=float)
    owner = np.searchsorted(keyframes, np.arange(len(out)), side="right") - 1
    inside = (owner < len(keyframes) - 1) & ~np.isin(np.arange(len(out)), keyframes)
    k = owner[inside]
    span = stamps[keyframes[k + 1]] - stamps[keyframes[k]]
    fraction = np.where(span > 0, (stamps[inside] - stamps[keyframes[k]]) / np.where(
        span > 0, span, 1.0), 0.0)
    step = np.asarray(relative(poses[k], poses[k + 1])).reshape(-1, 3)
    out[inside] = np.asarray(compose(poses[k], step * fraction[:, None])).reshape(-1, 3)
    return out


def _register_between(log: CarmenLog, poses: np.ndarray, keyframes: np.ndarray,
                      submaps: _Submaps, guesses: np.ndarray, s: SlamSettings) -> np.ndarray:
    """Every scan's pose: keyframes as optimised, the scans between them matched against
    the submap of the keyframes round them, from the odometry guess; a failed or poor
    match keeps the guess."""
    out = guesses.copy()
    owner = np.searchsorted(keyframes, np.arange(len(guesses)), side="right") - 1
    half = max(1, s.submap_size // 2)
    cached: tuple[int, np.ndarray] | None = None
    for scan in np.setdiff1d(np.arange(len(guesses)), keyframes):
        k = int(owner[scan])
        if cached is None or cached[0] != k:
            window = range(max(0, k - half + 1), min(len(keyframes), k + half + 1))
            cached = (k, submaps.around(poses, window))
        points = thin(log.points(int(scan), frame="base"), s.point_spacing)
        matched = _match(points, cached[1], guesses[scan], s)
        if matched is not None and matched.fitness >= s.loop_fitness:
            out[scan] = matched.pose
    return out


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


def _match_sequential(points: np.ndarray, submap: np.ndarray, guess: np.ndarray,
                      s: SlamSettings) -> IcpResult | None:
    """ICP from the odometry guess; where it pairs too few points (``sequential_fitness``)
    the guess was too far off for ICP's local search (odometry that misreads a fast
    turn), so the correlative matcher (Olson 2009) searches a window round the guess
    (``search_xy``, ``search_theta``) and ICP refines from its answer; the better fit of
    the two is kept."""
    first = _match(points, submap, guess, s)
    if first is not None and first.fitness >= s.sequential_fitness:
        return first
    second = _search(points, submap, guess, s, s.search_xy, s.search_theta,
                     resolution=0.05, reach=s.search_radius)
    candidates = [r for r in (first, second) if r is not None]
    return max(candidates, key=lambda r: (r.fitness, -r.rms)) if candidates else None


def _close_loops(k: int, points: np.ndarray, poses: np.ndarray, submaps: _Submaps,
                 s: SlamSettings, along: np.ndarray) -> list[tuple[int, np.ndarray]]:
    """Verified loop edges ``(candidate, measured relative pose)`` from keyframe ``k``.

    A candidate may lie as far from the estimate as the drift since it could carry it:
    ``loop_radius`` plus ``loop_drift`` per metre travelled between them (``along``:
    each keyframe's distance along the path), at most ``loop_radius_max``. Candidates
    come in runs of consecutive keyframes (each pass through a place); the nearest of
    each of the nearest ``loop_candidates`` runs is tried, so a big loop's return is
    tried beside the many small ones a robot turning round makes. ICP from the estimate
    tries first; every ``loop_search_every`` keyframes, a candidate ICP could not match
    is searched with the correlative matcher round the estimate (the drift may be beyond
    ICP's reach), and ICP refines what it finds."""
    older = k - s.loop_separation
    if older <= 0 or len(points) < 3 or s.loop_radius <= 0:  # loop_radius 0: no loops
        return []
    distances = np.hypot(*(poses[:older, :2] - poses[k, :2]).T)
    reach = np.minimum(s.loop_radius + s.loop_drift * (along[k] - along[:older]),
                       s.loop_radius_max)
    near = np.flatnonzero(distances < reach)
    if not len(near):
        return []
    runs = np.split(near, np.flatnonzero(np.diff(near) > 1) + 1)
    firsts = sorted((int(run[np.argmin(distances[run])]) for run in runs),
                    key=lambda c: distances[c])[: s.loop_candidates]
    closed = []
    search = k % s.loop_search_every == 0
    for candidate in firsts:
        window = range(max(0, candidate - s.submap_size // 2),
                       min(older, candidate + s.submap_size // 2 + 1))
        submap = submaps.around(poses, window)
        result = _match(points, submap, poses[k], s)
        if (result is None or not _trustworthy(result, s)) and search:
            search = False  # one search per keyframe at most
            window_xy = min(float(reach[candidate]), s.loop_search_xy)
            result = _search(points, submap, poses[k], s, window_xy, s.loop_search_theta,
                             resolution=0.1, reach=s.search_radius + window_xy)
        if result is not None and _trustworthy(result, s):
            closed.append((int(candidate), np.asarray(relative(poses[candidate], result.pose))))
    return closed


def _search(points: np.ndarray, submap: np.ndarray, guess: np.ndarray, s: SlamSettings,
            window_xy: float, window_theta: float, resolution: float,
            reach: float) -> IcpResult | None:
    """The correlative matcher over ``+- window_xy`` m and ``+- window_theta`` rad round
    ``guess``, on a table of ``resolution`` m cells of the submap's points within ``reach``
    m of the guess, refined by ICP (None if either finds nothing). The scan is searched
    thinned to ``search_spacing``, its points within ``search_radius``."""
    local = inverse_transform_points(guess, submap)
    keep = np.hypot(local[:, 0], local[:, 1]) < reach
    near = thin(points[np.hypot(points[:, 0], points[:, 1]) < s.search_radius],
                s.search_spacing)
    if keep.sum() < 3 or len(near) < 3:
        return None
    field = LikelihoodField(local[keep], resolution=resolution, sigma=resolution,
                            margin=window_xy + 0.5)
    found = correlative_match(near, field, (0.0, 0.0, 0.0), window_xy=window_xy,
                              window_theta=window_theta)
    return _match(points, submap, np.asarray(compose(guess, found.pose)), s)


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
