"""The quick benchmarks run and report named, finite figures (a merge that breaks one
shows here, not at the next measuring session); the slow ones are only registered."""

import math

import pytest

from abcwc.bench import BENCHMARKS

QUICK = ["costmap", "dwa", "planner", "grid", "correlative"]
SLOW = ["sim", "ekf", "nees", "posegraph", "carmen", "slam", "notebooks", "navigator",
        "follow", "speech", "vision"]


def test_every_benchmark_is_registered_with_a_description():
    assert set(QUICK + SLOW) == set(BENCHMARKS)
    assert all(description for description, _, _, _ in BENCHMARKS.values())


@pytest.mark.parametrize("name", QUICK)
def test_a_quick_benchmark_reports_finite_figures(name):
    figures = BENCHMARKS[name][1]()
    assert isinstance(figures, dict) and figures
    assert all(isinstance(key, str) and math.isfinite(value) and value > 0
               for key, value in figures.items())


def test_the_notebook_runner_reports_the_time_peak_memory_and_slowest_cell(tmp_path):
    import subprocess
    import sys

    import nbformat
    from nbformat.v4 import new_code_cell, new_notebook

    from abcwc.bench import _NOTEBOOK_RUNNER

    path = tmp_path / "slow_cell.ipynb"
    nbformat.write(new_notebook(cells=[new_code_cell("import time"),
                                       new_code_cell("time.sleep(1.5)"),
                                       new_code_cell("x = 1")]), path)
    done = subprocess.run([sys.executable, "-c", _NOTEBOOK_RUNNER, str(path)],
                          capture_output=True, text=True, check=True, cwd=tmp_path)
    seconds, max_rss_kb, slowest = (float(v) for v in done.stdout.split()[-3:])
    assert 1.5 <= slowest < 3.0 and seconds > slowest
    assert max_rss_kb > 10_000  # a Python kernel needs more than 10 MB
