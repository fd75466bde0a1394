"""The command line: demo writes its files and summary; bench prints its table; every
command that prints figures prints them as JSON with --json, --out is a folder everywhere,
progress bars are on unless --quiet; a user's mistake is one ``abcwc: error:`` line and
exit status 2, never a traceback, and anything else one line calling it a bug (exit 1),
with the traceback under --debug."""

from __future__ import annotations

import gzip
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from abcwc import bench
from abcwc.cli import build_parser, error_line, main
from abcwc.log import RunLog
from abcwc.mapping.slam_data import slam_file

ROOT = Path(__file__).resolve().parent.parent


def test_demo_writes_plot_animation_and_log(tmp_path, capsys):
    assert main(["demo", "--mission", "wander", "--out", str(tmp_path), "--seconds", "20",
                 "--quiet"]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1]
    assert "sonar-avoidance wander in lab" in line and "0 collisions" in line
    for name in ("demo_wander.png", "demo_wander.gif", "demo_wander.npz"):
        assert (tmp_path / name).stat().st_size > 1000
    log = RunLog.load(tmp_path / "demo_wander.npz")
    assert len(log) == 1000 and log.meta["world"] == "lab"


def test_demo_json_gives_the_runs_figures_and_files(tmp_path, capsys):
    assert main(["demo", "--mission", "wander", "--out", str(tmp_path), "--seconds", "2",
                 "--quiet", "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    log = RunLog.load(tmp_path / "demo_wander.npz")
    assert figures["seconds"] == pytest.approx(2.0) and figures["world"] == "lab"
    assert figures["distance_m"] == pytest.approx(log.distance_travelled())
    assert figures["collisions"] == int(log.collisions[-1])
    assert sorted(Path(f).name for f in figures["files"]) == [
        "demo_wander.gif", "demo_wander.npz", "demo_wander.png"]


def test_demo_shows_a_progress_bar_unless_quiet(tmp_path, capsys):
    assert main(["demo", "--mission", "wander", "--out", str(tmp_path / "a"),
                 "--seconds", "1"]) == 0
    assert "50/50" in capsys.readouterr().err  # 50 steps of 20 ms
    assert main(["demo", "--mission", "wander", "--out", str(tmp_path / "b"),
                 "--seconds", "1", "--quiet"]) == 0
    assert capsys.readouterr().err == ""


def test_demo_refuses_unknown_world(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path / "out"), "--world", "moon", "--quiet"]) == 2
    assert capsys.readouterr().err == (
        "abcwc: error: unknown world 'moon'; available: building, floor, lab "
        "(or give a path to a .json world file)\n")
    assert not (tmp_path / "out").exists()  # nothing written for a bad world


def test_bench_table_and_json(monkeypatch, capsys):
    calls = iter([{"x": 1.0}, {"x": 3.0}, {"x": 2.0}])
    monkeypatch.setitem(bench.BENCHMARKS, "fake", ("a fake", lambda: next(calls), True, None))
    assert main(["bench", "fake", "--json", "--repeats", "3"]) == 0
    assert json.loads(capsys.readouterr().out) == {"fake": {"x": 2.0}}  # the median
    with pytest.raises(ValueError, match="unknown benchmark"):
        bench.run_benchmarks(["nope"])


def test_bench_shows_its_runs_unless_quiet(monkeypatch, capsys):
    monkeypatch.setitem(bench.BENCHMARKS, "fake", ("a fake", lambda: {"x": 1.0}, True, None))
    assert main(["bench", "fake", "--repeats", "2"]) == 0
    err = capsys.readouterr().err
    assert "bench fake" in err and "2/2" in err
    assert main(["bench", "fake", "--repeats", "2", "--quiet"]) == 0
    assert capsys.readouterr().err == ""


def test_version_is_the_packages():
    version = re.search(r'^version = "(.+)"$', (ROOT / "pyproject.toml").read_text(), re.M)
    done = run_abcwc("--version", cwd=ROOT)
    assert done.returncode == 0 and done.stdout == f"abcwc {version[1]}\n"


def test_every_command_takes_quiet_and_debug_and_the_figures_ones_json():
    minimal = {"demo": [], "bench": [], "course build": [], "posegraph": ["g.g2o"],
               "slam": ["log.clf"], "navtrial": [], "followtrial": [], "errands": [],
               "hubtrial": [], "dashboard": []}
    parser = build_parser()
    for command, needed in minimal.items():
        args = parser.parse_args([*command.split(), *needed, "--quiet", "--debug"])
        assert args.quiet and args.debug, command
        assert not parser.parse_args([*command.split(), *needed]).quiet, command
        if command not in ("course build", "dashboard"):  # they print no figures
            assert parser.parse_args([*command.split(), *needed, "--json"]).json, command
    # before the command too
    assert parser.parse_args(["--quiet", "--debug", "demo"]).debug


def test_posegraph_out_is_a_folder_with_the_optimised_graph(tmp_path, capsys):
    from abcwc.mapping.g2o import read_g2o, write_g2o
    from abcwc.mapping.grid_graph import grid_world
    from abcwc.mapping.posegraph import optimise

    graph = grid_world(200, seed=3, loops_per_pose=1).graph
    source = write_g2o(graph, tmp_path / "city.g2o")
    assert main(["posegraph", str(source), "--out", str(tmp_path / "out"), "--json",
                 "--quiet"]) == 0
    figures = json.loads(capsys.readouterr().out)
    poses, result = optimise(read_g2o(source))  # the same solve, run here
    written = tmp_path / "out" / "optimised.g2o"
    assert figures["files"] == [str(written)]
    np.testing.assert_allclose(read_g2o(written).poses, poses, atol=1e-9)
    assert figures["chi2_final"] == pytest.approx(result.chi2_final)
    assert figures["iterations"] == result.iterations and figures["poses"] == 200
    assert main(["posegraph", str(source), "--out", str(source)]) == 2  # a file, not a folder
    assert "names a folder" in capsys.readouterr().err


def test_slam_json_gives_the_runs_figures_and_its_relation_errors(tmp_path, capsys):
    from abcwc.mapping.carmen import read_carmen_log
    from abcwc.mapping.relations import read_relations, relation_errors
    from abcwc.mapping.slam import run_slam

    lines = gzip.open(slam_file("aces.clf.gz"), "rt").read().splitlines()
    scans = [k for k, line in enumerate(lines) if line.startswith("FLASER")]
    log_path = tmp_path / "aces_start.clf"
    log_path.write_text("\n".join(lines[:scans[200]]) + "\n")  # the first 200 scans
    log = read_carmen_log(log_path)
    last = log.stamps[-1]
    relations_path = tmp_path / "aces_start.relations"
    relations_path.write_text("".join(
        line + "\n" for line in slam_file("aces.relations").read_text().splitlines()
        if float(line.split()[1]) <= last))
    assert main(["slam", str(log_path), "--relations", str(relations_path), "--out",
                 str(tmp_path / "out"), "--json", "--quiet"]) == 0
    figures = json.loads(capsys.readouterr().out)
    result = run_slam(log)  # the same run, here
    errors = relation_errors(result.laser_poses, read_relations(relations_path, log.stamps))
    assert figures["scans"] == 200 and figures["keyframes"] == len(result.keyframes)
    assert figures["relation_errors"]["relations"] == len(errors.translational) > 0
    assert figures["relation_errors"]["translational_mean_m"] == pytest.approx(
        errors.translational_mean)
    assert figures["relation_errors"]["rotational_mean_deg"] == pytest.approx(
        errors.rotational_mean_deg)
    for name in ("map.yaml", "map.pgm", "trajectory.txt"):
        assert str(tmp_path / "out" / name) in figures["files"]
        assert (tmp_path / "out" / name).is_file()


def test_navtrial_json_has_the_trials_figures(monkeypatch, capsys):
    from abcwc.experiments import navigation_trial
    from abcwc.types import Pose2D

    outcome = navigation_trial.GoalOutcome(
        Pose2D(1.0, 2.0, 0.5), "failed", "blocked", 12.5, 3.0, 2.5, 2.75, 0.4, 0.1, 1, 2,
        math.inf, 0.05, 0.25, {"driving": 12.5},
        recoveries={"backing off": 2, "closing the gap ahead": 1})
    trial = navigation_trial.TrialResult([outcome], tolerance=0.25)
    monkeypatch.setattr(navigation_trial, "run_trial", lambda **options: trial)
    assert main(["navtrial", "--goals", "1", "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "recoveries: backing off 2 (1 goals), closing the gap ahead 1 (1 goals)" in text
    assert "goal 0 (1.0, 2.0) not reached: blocked" in text
    assert main(["navtrial", "--goals", "1", "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert figures["goals"] == 1 and figures["success_rate"] == 0.0
    assert figures["collisions"] == 1 and figures["lethal_periods"] == 2
    assert figures["closest_person"] is None  # no one met: infinity, which JSON lacks
    goal = figures["outcomes"][0]
    assert goal["goal"] == [1.0, 2.0, 0.5] and goal["reason"] == "blocked"
    assert goal["reached"] is False and goal["driven"] == 3.0
    assert goal["phases"] == {"driving": 12.5}
    assert goal["recoveries"] == {"backing off": 2, "closing the gap ahead": 1}


def test_dashboard_serves_the_packages_notebook_with_voila(monkeypatch, tmp_path, capsys):
    """The command Voila is run with, captured instead of run: the notebook inside the
    package, this machine only, the culling that releases a closed page's kernel, and the
    world for the notebook's kernel in its environment (a world file by its full path)."""
    import nbformat

    from abcwc import cli

    served = []
    monkeypatch.setattr(cli, "_serve", lambda command, env: served.append((command, env))
                        or 0)
    notebook = ROOT / "abcwc" / "ui" / "dashboard.ipynb"
    assert main(["dashboard", "--world", "floor", "--port", "8123", "--no-browser"]) == 0
    command, env = served[-1]
    assert command == [sys.executable, "-m", "voila", str(notebook), "--port=8123",
                       "--Voila.ip=127.0.0.1", "--MappingKernelManager.cull_interval=5",
                       "--MappingKernelManager.cull_idle_timeout=10", "--no-browser"]
    assert env["ABCWC_DASHBOARD_WORLD"] == "floor" and env["PATH"] == os.environ["PATH"]
    assert "http://127.0.0.1:8123/" in capsys.readouterr().out
    # the notebook builds its dashboard in the world the environment names
    code = nbformat.read(notebook, as_version=4).cells[-1].source
    assert "os.environ.get(WORLD_VARIABLE" in code and code.splitlines()[-1].startswith(
        "Dashboard(")
    # by default the page opens in a browser, on Voila's usual port
    monkeypatch.chdir(tmp_path)
    world = tmp_path / "mine.json"
    world.write_text((ROOT / "data" / "worlds" / "lab.json").read_text())
    assert main(["dashboard", "--world", "mine.json"]) == 0
    command, env = served[-1]
    assert "--port=8866" in command and "--no-browser" not in command
    assert env["ABCWC_DASHBOARD_WORLD"] == str(world)


def test_dashboard_refuses_a_bad_port_or_world_before_serving(monkeypatch, capsys):
    from abcwc import cli

    served = []
    monkeypatch.setattr(cli, "_serve", lambda command, env: served.append(command) or 0)
    assert main(["dashboard", "--port", "70000"]) == 2
    assert capsys.readouterr().err == ("abcwc: error: the port must be a whole number "
                                       "1..65535, got 70000\n")
    assert main(["dashboard", "--world", "moon"]) == 2
    assert "unknown world 'moon'" in capsys.readouterr().err
    assert served == []


def test_an_unexpected_error_is_one_line_calling_it_a_bug(monkeypatch, capsys):
    def broken(*_, **__):
        raise ZeroDivisionError("float division by zero")

    monkeypatch.setattr(bench, "run_benchmarks", broken)
    assert main(["bench"]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith(
        "abcwc: internal error: ZeroDivisionError: float division by zero")
    assert "a bug in abcwc" in err and "--debug" in err
    with pytest.raises(ZeroDivisionError):  # --debug: the traceback, after or before
        main(["bench", "--debug"])
    with pytest.raises(ZeroDivisionError):
        main(["--debug", "bench"])


def test_debug_shows_a_user_errors_traceback_too():
    with pytest.raises(ValueError, match="unknown benchmark"):
        main(["bench", "nope", "--debug"])


def test_an_out_that_is_a_file_is_refused_before_the_run(tmp_path):
    (tmp_path / "taken").write_text("a file")
    done = run_abcwc("demo", "--out", "taken", cwd=tmp_path)
    assert done.returncode == 2
    assert done.stderr == ("abcwc: error: --out taken: a file is there; --out names a "
                           "folder\n")


def test_a_refused_demo_leaves_no_folder_behind(tmp_path):
    for refused in (["--mission", "wander", "--seconds", "-5"],
                    ["--mission", "wander", "--seconds", "nan"], ["--world", "moon"],
                    ["--seed", "-1"], ["--to", "moon"]):
        done = run_abcwc("demo", *refused, cwd=tmp_path)
        assert done.returncode == 2, done.stderr
        assert list(tmp_path.iterdir()) == [], refused  # not even abcwc-demo/


def test_course_build_runs_in_a_checkout(monkeypatch, capsys):
    monkeypatch.chdir(ROOT)
    assert main(["course", "build", "--check"]) == 0
    assert capsys.readouterr().out.startswith("course/ is up to date")
    assert main(["course", "build", "--check", "--quiet"]) == 0
    assert capsys.readouterr().out == ""


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
    "negative seconds": (["demo", "--mission", "wander", "--seconds", "-5"], {},
                         "seconds must be a finite number"),
    "seconds for the errand": (["demo", "--seconds", "5"], {}, "--seconds is the wander's"),
    "unknown place": (["demo", "--to", "moon"], {}, "no place 'moon' in floor; its places: "
                      "cafeteria, corridor_east, lab, library, lift, meeting, office_a, "
                      "reading, store"),
    "no cafeteria": (["demo", "--world", "lab"], {}, "lab has no cafeteria: choose"),
    "a destination for the wander": (["demo", "--mission", "wander", "--to", "lab"], {},
                                     "--to is the errand's"),
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
    "no errands": (["errands", "--count", "0"], {}, "--count must be at least 1"),
    "errands in an unknown world": (["errands", "--world", "moon"], {},
                                    "unknown world 'moon'"),
    "navtrial in an unknown world": (["navtrial", "--world", "moon"], {},
                                     "unknown world 'moon'"),
    "a class of none": (["hubtrial", "--students", "0,2"], {},
                        "--students: every class size must be 1 or more"),
    "class sizes not numbers": (["hubtrial", "--students", "a,b"], {},
                                "--students takes class sizes separated by commas"),
    "a chapter not in the course": (["hubtrial", "--chapter", "solutions/00_tour.ipynb"], {},
                                    "no chapter 'solutions/00_tour.ipynb' in the students' "
                                    "course folder; one of: course/00_tour.ipynb"),
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
