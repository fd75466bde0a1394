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
BENCHMARKS: dict[str, tuple[str, Benchmark, bool]] = {}
"""name -> (description, function, whether to repeat it: False for a deterministic one)."""


def benchmark(name: str, description: str,
              repeat: bool = True) -> Callable[[Benchmark], Benchmark]:
    """Register a benchmark under ``name``; ``repeat=False``: its figures do not vary
    from run to run, so it runs once whatever ``repeats`` says."""

    def register(fn: Benchmark) -> Benchmark:
        BENCHMARKS[name] = (description, fn, repeat)
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


def _slam_data() -> Path:
    """The SLAM benchmark logs: ``ABCWC_SLAM_DATA``, else ``../shared/data/slam`` beside
    the repository."""
    import os

    from abcwc.paths import REPO_ROOT

    path = Path(os.environ.get("ABCWC_SLAM_DATA", REPO_ROOT.parent / "shared/data/slam"))
    if not path.is_dir():
        raise ValueError(f"SLAM benchmark data not found at {path} (set ABCWC_SLAM_DATA)")
    return path


@benchmark("carmen", "CARMEN log parse time (s) per benchmark log; ICP matches per second "
                     "on 500 consecutive ACES scans")
def bench_carmen() -> dict[str, float]:
    from abcwc.mapping.carmen import read_carmen_log
    from abcwc.mapping.icp import match_consecutive_scans

    data = _slam_data()
    figures: dict[str, float] = {}
    for name in ("aces", "mit-csail", "fr079"):
        start = time.perf_counter()
        log = read_carmen_log(data / f"{name}.clf.gz")
        figures[f"parse {name}.clf.gz ({len(log)} scans): s"] = time.perf_counter() - start
    aces = read_carmen_log(data / "aces.clf.gz", max_range=50.0)
    start = time.perf_counter()
    matches = len(match_consecutive_scans(aces, 1000, 1500))
    figures["ICP matches per second, ACES consecutive scans"] = (
        matches / (time.perf_counter() - start))
    return figures


_NOTEBOOK_RUNNER = """
import resource, sys, time
import nbformat
from nbclient import NotebookClient
nb = nbformat.read(sys.argv[1], as_version=4)
start = time.perf_counter()
NotebookClient(nb, timeout=600, kernel_name="python3").execute()
seconds = time.perf_counter() - start
print(seconds, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)
"""


@benchmark("notebooks", "each solution notebook: execution time (s) and kernel peak memory (MB)")
def bench_notebooks() -> dict[str, float]:
    import subprocess
    import sys

    from abcwc.paths import REPO_ROOT

    figures: dict[str, float] = {}
    for path in sorted((REPO_ROOT / "solutions").glob("*.ipynb")):
        done = subprocess.run([sys.executable, "-c", _NOTEBOOK_RUNNER, str(path)],
                              capture_output=True, text=True, check=True, cwd=path.parent)
        seconds, max_rss_kb = done.stdout.split()[-2:]
        figures[f"{path.stem}: seconds"] = float(seconds)
        figures[f"{path.stem}: peak MB"] = int(max_rss_kb) / 1024
    return figures


def run_benchmarks(names: list[str] | None = None, repeats: int = 3) -> dict[str, dict]:
    """Run the named benchmarks (all if None); medians of ``repeats`` runs."""
    names = names or list(BENCHMARKS)
    unknown = [n for n in names if n not in BENCHMARKS]
    if unknown:
        raise ValueError(f"unknown benchmark(s) {', '.join(unknown)}; "
                         f"available: {', '.join(BENCHMARKS)}")
    if repeats < 1:
        raise ValueError(f"repeats {repeats} outside 1..")
    results: dict[str, dict] = {}
    for name in names:
        _, fn, repeat = BENCHMARKS[name]
        runs = [fn() for _ in range(repeats if repeat else 1)]
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
