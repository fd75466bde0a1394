"""The command line: demo writes its files and summary; bench prints its table; a user's
mistake is one ``abcwc: error:`` line and exit status 2, never a traceback."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from abcwc import bench
from abcwc.cli import error_line, main
from abcwc.log import RunLog

ROOT = Path(__file__).resolve().parent.parent


def test_demo_writes_plot_animation_and_log(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path), "--seconds", "20", "--quiet"]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert "sonar-avoidance wander in lab" in line and "0 collisions" in line
    for name in ("demo_wander.png", "demo_wander.gif", "demo_wander.npz"):
        assert (tmp_path / name).stat().st_size > 1000
    log = RunLog.load(tmp_path / "demo_wander.npz")
    assert len(log) == 1000 and log.meta["world"] == "lab"


def test_demo_refuses_unknown_world(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path / "out"), "--world", "moon", "--quiet"]) == 2
    assert capsys.readouterr().err == (
        "abcwc: error: unknown world 'moon'; available: floor, lab "
        "(or give a path to a .json world file)\n")
    assert not (tmp_path / "out").exists()  # nothing written for a bad world


def test_bench_table_and_json(monkeypatch, capsys):
    calls = iter([{"x": 1.0}, {"x": 3.0}, {"x": 2.0}])
    monkeypatch.setitem(bench.BENCHMARKS, "fake", ("a fake", lambda: next(calls), True))
    assert main(["bench", "fake", "--json", "--repeats", "3"]) == 0
    assert json.loads(capsys.readouterr().out) == {"fake": {"x": 2.0}}  # the median
    with pytest.raises(ValueError, match="unknown benchmark"):
        bench.run_benchmarks(["nope"])


def test_course_build_runs_in_a_checkout(monkeypatch, capsys):
    monkeypatch.chdir(ROOT)
    assert main(["course", "build", "--check"]) == 0
    assert capsys.readouterr().out.startswith("course/ is up to date")


def test_error_line_is_one_line_and_names_the_file():
    assert error_line(ValueError("bad\n  value\n")) == "abcwc: error: bad value"
    assert error_line(IsADirectoryError(21, "Is a directory", "/tmp")) == (
        "abcwc: error: /tmp: Is a directory")
    assert error_line(FileNotFoundError("no data")) == "abcwc: error: no data"


# --- as a user runs it: a fresh process, outside the checkout -------------------------


def run_abcwc(*args: str, cwd: Path, **env: str) -> subprocess.CompletedProcess:
    """``python -m abcwc.cli ARGS`` on this checkout's abcwc, in ``cwd``."""
    environ = {k: v for k, v in os.environ.items() if k not in ("ABCWC_DATA", "ABCWC_PORT")}
    environ.update(env, PYTHONPATH=str(ROOT))
    return subprocess.run([sys.executable, "-m", "abcwc.cli", *args], cwd=cwd, env=environ,
                          capture_output=True, text=True, timeout=120)


USER_ERRORS = {
    "unknown world": (["demo", "--world", "moon"], {}, "unknown world 'moon'"),
    "negative seed": (["demo", "--seed", "-1"], {}, "seed must be a non-negative integer"),
    "negative seconds": (["demo", "--seconds", "-5"], {}, "seconds must be a finite number"),
    "world is a folder": (["demo", "--world", "."], {}, "Is a directory"),
    "missing data folder": (["demo"], {"ABCWC_DATA": "no-such-data"},
                            "ABCWC_DATA=no-such-data is not a folder"),
    "unknown benchmark": (["bench", "nope"], {}, "unknown benchmark(s) nope; available: sim"),
    "no repeats": (["bench", "--repeats", "0"], {}, "repeats 0 outside 1.."),
    "course build outside a checkout": (["course", "build"], {},
                                        "`abcwc course build` works on a checkout"),
    "no such solutions folder": (["course", "build", "--solutions", "nope"], {},
                                 "nope: no such directory"),
    "no goals": (["navtrial", "--goals", "0"], {}, "--goals must be at least 1"),
    "navtrial in an unknown world": (["navtrial", "--world", "moon"], {},
                                     "unknown world 'moon'"),
}


@pytest.mark.parametrize("args, env, message", USER_ERRORS.values(), ids=USER_ERRORS.keys())
def test_user_error_is_one_line_with_exit_status_2(tmp_path, args, env, message):
    done = run_abcwc(*args, cwd=tmp_path, **env)
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith("abcwc: error: "), done.stderr
    assert message in lines[0]


ARGPARSE_ERRORS = {
    "seed not a number": (["demo", "--seed", "x"], "abcwc demo: error: argument --seed"),
    "seconds not a number": (["demo", "--seconds", "long"], "abcwc demo: error: argument"),
    "unknown command": (["frob"], "abcwc: error: argument COMMAND: invalid choice: 'frob'"),
    "course without build": (["course"], "abcwc course: error: the following arguments"),
    "unknown option": (["bench", "--fast"], "abcwc: error: unrecognized arguments: --fast"),
}


@pytest.mark.parametrize("args, last_line", ARGPARSE_ERRORS.values(), ids=ARGPARSE_ERRORS.keys())
def test_argparse_errors_keep_argparse_conventions(tmp_path, args, last_line):
    done = run_abcwc(*args, cwd=tmp_path)
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert done.stderr.startswith("usage: abcwc")
    assert done.stderr.splitlines()[-1].startswith(last_line), done.stderr
