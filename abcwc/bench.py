"""``abcwc bench``: how fast the parts run on this machine (medians of repeats).

Benchmarks measure; they assert nothing. Each benchmark returns named figures; the
command prints one table (or JSON) of their medians over ``repeats`` runs.
"""

from __future__ import annotations

import json
import statistics
import time
from collections.abc import Callable
from pathlib import Path

from abcwc.types import Twist

Benchmark = Callable[[], dict[str, float]]
BENCHMARKS: dict[str, tuple[str, Benchmark, bool, Callable[[], object] | None]] = {}
"""name -> (description, function, whether to repeat it: False for a deterministic one,
what it needs: a check that raises when it cannot run here, or None)."""


def benchmark(name: str, description: str, repeat: bool = True,
              needs: Callable[[], object] | None = None) -> Callable[[Benchmark], Benchmark]:
    """Register a benchmark under ``name``; ``repeat=False``: its figures do not vary
    from run to run, so it runs once whatever ``repeats`` says; ``needs``: called before
    any benchmark runs, it raises (one line for the user) when this one cannot run."""

    def register(fn: Benchmark) -> Benchmark:
        BENCHMARKS[name] = (description, fn, repeat, needs)
        return fn

    return register


def _real_time_factor(seconds: float = 60.0, **options: object) -> float:
    from abcwc.sim.base import SimBase

    chair = SimBase(errors="worn", **options)  # type: ignore[arg-type]
    # a gentle circle in the open middle of the lab: no collisions, all sensors live
    command = Twist(0.4, 0.35)
    start = time.perf_counter()
    chair.drive(command, seconds)
    return seconds / (time.perf_counter() - start)


@benchmark("sim", "simulator real-time factor (lab world, 60 simulated s)")
def bench_sim() -> dict[str, float]:
    return {
        "real-time factor, encoders+gyro+sonar+IR": _real_time_factor(
            world="lab", start="centre"),
        "real-time factor, + lidar 360 + depth scan": _real_time_factor(
            world="lab", start="centre", lidar=True, depth_scan=True),
        "real-time factor, floor world + lidar + depth": _real_time_factor(
            world="floor", start="corridor_east", lidar=True, depth_scan=True, people=False),
    }


@benchmark("ekf", "EKF predict+update cycles per second (NumPy and filterpy back ends)")
def bench_ekf() -> dict[str, float]:
    from abcwc.estimation.bench import bench_ekf as measure

    return measure()


@benchmark("nees", "EKF consistency: 50 seeded 5-minute floor drives (deterministic: run once)",
           repeat=False)
def bench_nees() -> dict[str, float]:
    import os

    from abcwc.experiments.nees import ekf_monte_carlo

    result = ekf_monte_carlo(50, 300.0, processes=min(os.cpu_count() or 1, 4))
    ekf = [run.ekf_final_error for run in result.runs]
    odometry = [run.odometry_final_error for run in result.runs]
    return {"average NEES, 50 runs x 300 s": result.average_nees,
            "95 % band low": result.band[0], "95 % band high": result.band[1],
            "EKF final error, mean (m)": statistics.fmean(ekf),
            "raw odometry final error, mean (m)": statistics.fmean(odometry)}


def _scans_per_second(world: str, start: str | None, seconds: float = 10.0) -> float:
    """Lidar scans (360 beams, 12 m) of a drive integrated into a 0.05 m grid per second."""
    import numpy as np

    from abcwc.geometry import compose
    from abcwc.mapping.grid import OccupancyGrid, scan_rows
    from abcwc.sim.base import SimBase
    from abcwc.sim.world import box_world

    body = box_world() if world == "box" else world  # an empty 40 x 40 m room
    chair = SimBase(world=body, start=start, lidar=True, people=False)
    log = chair.drive(Twist(0.4, 0.35), seconds)
    mount = np.asarray(chair.params.lidar.mount)
    poses = compose(log.pose[scan_rows(log)], np.broadcast_to(mount, (len(log.lidar.stamps), 3)))
    scans = [log.lidar.scan(k) for k in range(len(poses))]
    grid = OccupancyGrid.covering(*chair.world.bounds, 0.05, margin=1.0)
    start_time = time.perf_counter()
    for scan, pose in zip(scans, poses):
        grid.integrate(scan, pose)
    return len(scans) / (time.perf_counter() - start_time)


@benchmark("grid", "occupancy grid: 360-beam lidar scans integrated per second, 0.05 m cells")
def bench_grid() -> dict[str, float]:
    return {
        "scans/s, lab (10 x 8 m, most beams return)": _scans_per_second("lab", "centre"),
        "scans/s, 40 m box (no returns: every beam 12 m)": _scans_per_second("box", None),
    }


def _scattered_obstacles(count: int):  # noqa: ANN202 - a Costmap, imported lazily
    """A free 500 x 500 costmap at 0.05 m with ``count`` seeded lethal cells."""
    import numpy as np

    from abcwc.navigation.costmap import LETHAL, Costmap

    rng = np.random.default_rng(0)
    costmap = Costmap(0.05, 500, 500, default=0)
    costmap.cost[costmap.world_to_cell(rng.uniform(0, 25, (count, 2)))] = LETHAL
    return costmap


@benchmark("costmap", "costmaps: inflating a 500 x 500 global costmap, and a 5 x 5 m local "
           "window at 0.05 m updated from one 360-beam scan (ms)")
def bench_costmap() -> dict[str, float]:
    import math

    import numpy as np

    from abcwc.navigation.costmap import Costmap
    from abcwc.types import LaserScan

    global_map = _scattered_obstacles(3000)
    start = time.perf_counter()
    global_map.inflate(0.16, 0.6)
    inflate_ms = (time.perf_counter() - start) * 1000
    scan = LaserScan(-math.pi, 2 * math.pi / 360, 0.15, 12.0,
                     np.random.default_rng(1).uniform(0.5, 6.0, 360))
    start = time.perf_counter()
    local = Costmap.rolling_window((3.0, 4.0, 0.3), 5.0, 0.05)
    local.add_scan(scan, (3.1, 4.0, 0.3), obstacle_range=2.5, raytrace_range=3.0)
    local.inflate(0.16, 0.6)
    local_ms = (time.perf_counter() - start) * 1000
    return {"inflate 500 x 500 (ms)": inflate_ms, "local 5 x 5 m from one scan (ms)": local_ms}


@benchmark("planner", "global planner across a 500 x 500 costmap at 0.05 m, corner to corner "
           "(ms): the weights, the A* search, the whole plan, smoothing")
def bench_planner() -> dict[str, float]:
    from abcwc.navigation.planner import astar_search, cell_weights, plan, smooth

    costmap = _scattered_obstacles(600)
    costmap.inflate(0.16, 0.6)
    costmap.cost[5, 5] = costmap.cost[495, 495] = 0
    start, goal = costmap.cell_to_world(5, 5), costmap.cell_to_world(495, 495)
    plan(costmap, start, goal)  # numba compiles (or loads its cache) on the first call
    t0 = time.perf_counter()
    weights = cell_weights(costmap)
    t1 = time.perf_counter()
    astar_search(weights, 5 * 500 + 5, 495 * 500 + 495, 50.0)
    t2 = time.perf_counter()
    path = plan(costmap, start, goal)
    t3 = time.perf_counter()
    smooth(costmap, path)
    t4 = time.perf_counter()
    return {"weights (ms)": (t1 - t0) * 1000, "A* search (ms)": (t2 - t1) * 1000,
            "whole plan (ms)": (t3 - t2) * 1000, "smoothing (ms)": (t4 - t3) * 1000}


@benchmark("dwa", "one DWA cycle with A.17's 8 x 20 samples on a 5 x 5 m local costmap at "
           "0.05 m (ms)")
def bench_dwa() -> dict[str, float]:
    import numpy as np

    from abcwc.navigation.costmap import Costmap, chair_footprint
    from abcwc.navigation.dwa import DwaPlanner
    from abcwc.params import default_params

    footprint = chair_footprint(default_params())
    costmap = Costmap.rolling_window((0.0, 0.0, 0.0), 5.0, 0.05, default=0)
    rng = np.random.default_rng(0)
    costmap.cost[costmap.world_to_cell(rng.uniform(-2.5, 2.5, (40, 2)))] = 254
    costmap.inflate(footprint.inscribed_radius, 0.6)
    path = np.column_stack([np.linspace(0.0, 2.4, 60), np.zeros(60)])
    planner = DwaPlanner(footprint)
    times = []
    for _ in range(50):
        start = time.perf_counter()
        planner.plan(costmap, (0.0, 0.0, 0.0), (0.5, 0.0), path)
        times.append((time.perf_counter() - start) * 1000)
    return {"one cycle, median of 50 (ms)": statistics.median(times)}


@benchmark("navigator", "the navigator crossing the floor world to the cafeteria with its "
           "people walking: real-time factor, and ms per control period and per decision")
def bench_navigator() -> dict[str, float]:
    from abcwc.behaviours.navigator import Navigator
    from abcwc.sim.base import SimBase

    chair = SimBase("floor", seed=1, lidar=True)
    navigator = Navigator.for_world(chair.world)
    navigator.go_to("cafeteria")
    frame, periods, decisions = chair.read(), 0, []
    thinking = 0.0
    start = time.perf_counter()
    while navigator.running and periods < 5000:
        before = time.perf_counter()
        command = navigator(frame)
        spent = time.perf_counter() - before
        thinking += spent
        if navigator.decided_at == frame.t:  # a decision was taken
            decisions.append(spent * 1000)
        chair.send(command, navigator.decided_at)
        frame = chair.step()
        periods += 1
    wall = time.perf_counter() - start
    return {"real-time factor (sim + navigator)": periods * chair.period / wall,
            "navigator per 20 ms period, mean (ms)": thinking / periods * 1000,
            "one decision, median (ms)": statistics.median(decisions),
            "one decision, 95th percentile (ms)": sorted(decisions)[int(0.95 * len(decisions))]}


@benchmark("vision", "one 640 x 480 camera frame: rendering it (RGB and grey, the lab with a "
           "tag in view), reading the tag (ArUco with its pose; QR at 1x) and finding the "
           "lab's exit sign 4 m away, verification included (SIFT and ORB), ms each; and "
           "the sign detectors' found and false rates (%) on 288 views each, 1.5-4 m, up "
           "to 40 deg off the face, clean and under each imaging trouble, and on "
           "look-alike words made at run time (experiments.sign_sweep.rates)")
def bench_vision() -> dict[str, float]:
    import numpy as np

    from abcwc.experiments.follow_trial import follow_world
    from abcwc.experiments.sign_sweep import rates
    from abcwc.perception.known_objects import KnownObject, ObjectDetector
    from abcwc.perception.signs import WORD_BOX, house_sign
    from abcwc.perception.tags import detect_qr_codes, find_marker
    from abcwc.sim.base import SimBase
    from abcwc.types import Pose2D

    def median_ms(work: Callable[[], object], repeats: int = 30) -> float:
        times = []
        for _ in range(repeats):
            start = time.perf_counter()
            work()
            times.append((time.perf_counter() - start) * 1000)
        return statistics.median(times)

    figures = {}
    for mode in ("rgb", "gray"):
        chair = SimBase(follow_world(), camera=mode)
        figures[f"render {mode} (ms)"] = median_ms(chair.render_camera)
    gray = np.ascontiguousarray(chair.render_camera().pixels)
    figures["ArUco and its pose (ms)"] = median_ms(lambda: find_marker(gray, 7, 0.2,
                                                                        chair.camera))
    figures["QR code (ms)"] = median_ms(lambda: detect_qr_codes(gray))
    view = SimBase("lab", camera="gray", start=Pose2D(6.0, 4.6, 0.05)).render_camera()
    exit_sign = KnownObject("exit", house_sign("EXIT"), 0.6, WORD_BOX)
    for features in ("sift", "orb"):
        detector = ObjectDetector([exit_sign], features=features)
        if not detector.detect(view):
            raise RuntimeError(f"{features} did not find the exit sign in the benchmark's view")
        name = features.upper()
        figures[f"{name} exit sign (ms)"] = median_ms(
            lambda detector=detector: detector.detect(view), 20)
        measured = rates(features)  # deterministic: measured once, kept for repeats
        for condition, found in measured.found.items():
            figures[f"{name} found, {condition} (%)"] = 100 * found
        figures[f"{name} false, look-alikes (%)"] = 100 * measured.false
        for kind, false in measured.false_by_kind.items():
            figures[f"{name} false, {kind} (%)"] = 100 * false
    return figures


@benchmark("speech", "spoken commands of held-out speakers (kal and slt in flite and "
           "festival) and espeak-ng stress voices, per engine and overall: % recognised, % "
           "false activations on sentences sharing words with commands, x real time; quiet "
           "and in room noise at 20 and 10 dB SNR; enrolled speakers; the thesis's single "
           "words against two-word commands", repeat=False)
def bench_speech() -> dict[str, float]:
    from abcwc.experiments.speech_trials import speech_figures

    return speech_figures()


@benchmark("follow", "the tag follower behind Ana for 60 simulated s (camera, lidar, "
           "tracking, obstacle checks): real-time factor", repeat=False)
def bench_follow() -> dict[str, float]:
    from abcwc.experiments.follow_trial import run_follow_trial

    start = time.perf_counter()
    run_follow_trial(seconds=60.0)
    return {"real-time factor": 60.0 / (time.perf_counter() - start)}


@benchmark("slam", "graph SLAM on the benchmark logs in data/slam: seconds, scans per "
           "second, speed-up over the recording, relation errors (deterministic: run once)",
           repeat=False)
def bench_slam() -> dict[str, float]:
    from abcwc.mapping.carmen import read_carmen_log
    from abcwc.mapping.relations import read_relations, relation_errors
    from abcwc.mapping.slam import run_slam
    from abcwc.mapping.slam_data import LOG_FACTS, slam_file

    figures: dict[str, float] = {}
    for name, facts in LOG_FACTS.items():
        log = read_carmen_log(slam_file(f"{name}.clf.gz"), **facts)
        result = run_slam(log)
        errors = relation_errors(result.laser_poses,
                                 read_relations(slam_file(f"{name}.relations"), log.stamps))
        figures[f"{name}: seconds"] = result.seconds
        figures[f"{name}: scans per second"] = len(log) / result.seconds
        figures[f"{name}: x faster than recorded"] = (log.stamps[-1] - log.stamps[0]) / \
            result.seconds
        figures[f"{name}: translational error (m)"] = errors.translational_mean
        figures[f"{name}: rotational error (deg)"] = errors.rotational_mean_deg
    return figures


@benchmark("correlative", "correlative scan matching: one 180-beam scan against a room, "
           "window +-0.3 m, +-15 deg at 0.03 m (matches per second)")
def bench_correlative() -> dict[str, float]:
    import math

    import numpy as np

    from abcwc.geometry import inverse_transform_points
    from abcwc.mapping.correlative import LikelihoodField, correlative_match

    t = np.linspace(0.0, 1.0, 400, endpoint=False)[:, None]
    corners = np.array([(0, 0), (8, 0), (8, 4), (4, 4), (4, 6), (0, 6), (0, 0)], float)
    reference = np.vstack([a + t * (b - a) for a, b in zip(corners[:-1], corners[1:])])
    truth = np.array([3.0, 2.0, 0.4])
    local = inverse_transform_points(truth, reference)
    bearing = np.arctan2(local[:, 1], local[:, 0])
    scan = local[np.abs(bearing) < math.pi / 2][::2][:180]  # a 180-degree scanner's view
    field = LikelihoodField(reference, resolution=0.03)
    guess = truth + np.array([0.2, -0.15, 0.15])
    start = time.perf_counter()
    count = 20
    for _ in range(count):
        correlative_match(scan, field, guess, window_xy=0.3, window_theta=math.radians(15))
    return {"matches per second": count / (time.perf_counter() - start)}


@benchmark("posegraph", "pose-graph LM: the benchmark graphs in data/slam (chi2, s) and a "
           "10,000-pose simulated graph")
def bench_posegraph() -> dict[str, float]:
    from abcwc.mapping.g2o import read_g2o
    from abcwc.mapping.grid_graph import grid_world
    from abcwc.mapping.posegraph import optimise
    from abcwc.mapping.slam_data import REFERENCE_GRAPHS, slam_file

    figures: dict[str, float] = {}
    for name, reference in REFERENCE_GRAPHS.items():
        _, result = optimise(read_g2o(slam_file(reference.file)))
        figures[f"{name}: chi2 (GTSAM from the file's poses {reference.chi2_gtsam:g})"] = (
            result.chi2_final)
        figures[f"{name}: seconds (GTSAM {reference.seconds_gtsam:g})"] = result.seconds
    simulated = grid_world(10_000, seed=1, loops_per_pose=2)
    _, result = optimise(simulated.graph)
    figures["simulated 10,000 poses: edges"] = len(simulated.graph.edges)
    figures["simulated 10,000 poses: seconds"] = result.seconds
    return figures


@benchmark("carmen", "CARMEN log parse time (s) per benchmark log; ICP matches per second "
                     "on 500 consecutive ACES scans")
def bench_carmen() -> dict[str, float]:
    from abcwc.mapping.carmen import read_carmen_log
    from abcwc.mapping.icp import match_consecutive_scans
    from abcwc.mapping.slam_data import LOG_FACTS, slam_file

    figures: dict[str, float] = {}
    for name in ("aces", "mit-csail", "fr079"):
        start = time.perf_counter()
        log = read_carmen_log(slam_file(f"{name}.clf.gz"))
        figures[f"parse {name}.clf.gz ({len(log)} scans): s"] = time.perf_counter() - start
    aces = read_carmen_log(slam_file("aces.clf.gz"), **LOG_FACTS["aces"])
    start = time.perf_counter()
    matches = len(match_consecutive_scans(aces, 1000, 1500))
    figures["ICP matches per second, ACES consecutive scans"] = (
        matches / (time.perf_counter() - start))
    return figures


_NOTEBOOK_RUNNER = """
import resource, sys, time
from datetime import datetime
import nbformat
from nbclient import NotebookClient
nb = nbformat.read(sys.argv[1], as_version=4)
start = time.perf_counter()
NotebookClient(nb, timeout=600, kernel_name="python3", record_timing=True).execute()
seconds = time.perf_counter() - start
def stamp(cell, key):
    return datetime.fromisoformat(cell.metadata.execution[key].replace("Z", "+00:00"))
slowest = max((stamp(c, "shell.execute_reply") - stamp(c, "iopub.execute_input")).total_seconds()
              for c in nb.cells if c.cell_type == "code" and "execution" in c.metadata)
print(seconds, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, slowest)
"""


def _solutions_folder() -> Path:
    """The checkout's ``solutions/``; NotACheckoutError when abcwc is an installed copy."""
    from abcwc.paths import require_checkout

    return require_checkout("the notebooks benchmark (it runs solutions/)") / "solutions"


@benchmark("notebooks", "each solution notebook: execution time (s), its slowest cell (s, from "
           "the kernel's own timestamps) and kernel peak memory (MB)", needs=_solutions_folder)
def bench_notebooks() -> dict[str, float]:
    import subprocess
    import sys

    solutions = _solutions_folder()
    figures: dict[str, float] = {}
    for path in sorted(solutions.glob("*.ipynb")):
        done = subprocess.run([sys.executable, "-c", _NOTEBOOK_RUNNER, str(path)],
                              capture_output=True, text=True, check=True, cwd=path.parent)
        seconds, max_rss_kb, slowest = done.stdout.split()[-3:]
        figures[f"{path.stem}: seconds"] = float(seconds)
        figures[f"{path.stem}: slowest cell s"] = float(slowest)
        figures[f"{path.stem}: peak MB"] = int(max_rss_kb) / 1024
    return figures


def run_benchmarks(names: list[str] | None = None, repeats: int = 3,
                   progress: bool = False) -> dict[str, dict]:
    """Run the named benchmarks (all if None); medians of ``repeats`` runs. ``progress``
    shows a tqdm bar (on stderr) of the runs done, named by the benchmark running."""
    names = names or list(BENCHMARKS)
    unknown = [n for n in names if n not in BENCHMARKS]
    if unknown:
        raise ValueError(f"unknown benchmark(s) {', '.join(unknown)}; "
                         f"available: {', '.join(BENCHMARKS)}")
    if repeats < 1:
        raise ValueError(f"repeats {repeats} outside 1..")
    counts = {name: repeats if BENCHMARKS[name][2] else 1 for name in names}
    from tqdm.auto import tqdm

    results: dict[str, dict] = {}
    for name in names:  # a benchmark that cannot run here says so before any runs
        if BENCHMARKS[name][3] is not None:
            BENCHMARKS[name][3]()
    with tqdm(total=sum(counts.values()), desc="bench", unit="run", disable=not progress) as bar:
        for name in names:
            bar.set_description(f"bench {name}")
            runs = []
            for _ in range(counts[name]):
                runs.append(BENCHMARKS[name][1]())
                bar.update(1)
            results[name] = {key: statistics.median(r[key] for r in runs) for key in runs[0]}
    return results


def _figure(value: float) -> str:
    """Large figures with one decimal and thousands separators; small ones to 4 digits."""
    return f"{value:,.1f}" if abs(value) >= 100 else f"{value:.4g}"


def format_table(results: dict[str, dict]) -> str:
    """The results as an aligned text table."""
    rows = [(name, key, _figure(value)) for name, figures in results.items()
            for key, value in figures.items()]
    widths = [max(len(r[i]) for r in rows + [("benchmark", "figure", "median")])
              for i in range(3)]
    line = lambda r: f"{r[0]:<{widths[0]}}  {r[1]:<{widths[1]}}  {r[2]:>{widths[2]}}"  # noqa: E731
    out = [line(("benchmark", "figure", "median")), "-" * (sum(widths) + 4)]
    out += [line(r) for r in rows]
    return "\n".join(out)


def to_json(results: dict[str, dict]) -> str:
    """The results as JSON."""
    return json.dumps(results, indent=2, sort_keys=True)
