"""The command line: demo writes its files and summary; bench prints its table."""

from __future__ import annotations

import json

import pytest

from abcwc import bench
from abcwc.cli import main
from abcwc.log import RunLog


def test_demo_writes_plot_animation_and_log(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path), "--seconds", "20", "--quiet"]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert "sonar-avoidance wander in lab" in line and "0 collisions" in line
    for name in ("demo_wander.png", "demo_wander.gif", "demo_wander.npz"):
        assert (tmp_path / name).stat().st_size > 1000
    log = RunLog.load(tmp_path / "demo_wander.npz")
    assert len(log) == 1000 and log.meta["world"] == "lab"


def test_demo_refuses_unknown_world(tmp_path):
    with pytest.raises(SystemExit) as stop:
        main(["demo", "--out", str(tmp_path), "--world", "moon", "--quiet"])
    assert stop.value.code == 2


def test_bench_table_and_json(monkeypatch, capsys):
    calls = iter([{"x": 1.0}, {"x": 3.0}, {"x": 2.0}])
    monkeypatch.setitem(bench.BENCHMARKS, "fake", ("a fake", lambda: next(calls), True))
    assert main(["bench", "fake", "--json", "--repeats", "3"]) == 0
    assert json.loads(capsys.readouterr().out) == {"fake": {"x": 2.0}}  # the median
    with pytest.raises(ValueError, match="unknown benchmark"):
        bench.run_benchmarks(["nope"])


def test_course_subcommand_needs_build(capsys):
    assert main(["course"]) == 2
    assert "abcwc course build" in capsys.readouterr().err
