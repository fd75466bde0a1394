"""The quick benchmarks run and report named, finite figures (a merge that breaks one
shows here, not at the next measuring session); the slow ones are only registered."""

import math

import pytest

from abcwc.bench import BENCHMARKS

QUICK = ["costmap", "dwa", "planner", "grid", "correlative", "vision"]
SLOW = ["sim", "ekf", "nees", "posegraph", "carmen", "slam", "notebooks", "navigator",
        "follow", "speech"]


def test_every_benchmark_is_registered_with_a_description():
    assert set(QUICK + SLOW) == set(BENCHMARKS)
    assert all(description for description, _, _, _ in BENCHMARKS.values())


@pytest.mark.parametrize("name", QUICK)
def test_a_quick_benchmark_reports_finite_figures(name):
    figures = BENCHMARKS[name][1]()
    assert isinstance(figures, dict) and figures
    assert all(isinstance(key, str) and math.isfinite(value) and value > 0
               for key, value in figures.items())
