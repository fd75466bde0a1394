"""The capstone end to end, as a new user runs it: ``abcwc demo`` maps the floor it does
not know by a tour of its places, is told (spoken when flite is there) to go to the
cafeteria, drives there among the walking people, asks for the lift on the way and writes
its report; on a world file written here, with places no world of the project has, it
does the same. Judged by the simulator's truth (the report's figures are its)."""

from __future__ import annotations

import base64
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from abcwc.behaviours.mission import mission_timeline
from abcwc.cli import MISSION_FAILED, main
from abcwc.experiments.errand import tour_of
from abcwc.log import RunLog
from abcwc.mapping.grid import OccupancyGrid
from abcwc.mapping.map_io import load_map
from abcwc.perception.speech.synthesis import engine_available
from abcwc.sim.world import load_world, world_from_dict
from abcwc.types import Pose2D
from abcwc.viz.mission import plot_timeline
from abcwc.viz.report import (
    figure_png,
    plot_map_and_route,
    write_html_report,
)


@pytest.fixture(scope="module")
def floor_demo(tmp_path_factory):
    """README's first command's job, once: ``abcwc demo --out DIR --json``."""
    out = tmp_path_factory.mktemp("demo")
    import contextlib
    import io

    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        status = main(["demo", "--out", str(out), "--quiet", "--json"])
    return status, json.loads(printed.getvalue()), out


def test_the_demo_maps_the_floor_and_the_chair_gets_its_coffee(floor_demo):
    status, figures, _ = floor_demo
    assert status == 0, figures
    assert figures["arrived"] and figures["state"] == "arrived"
    assert figures["destination"] == "cafeteria" and figures["world"] == "floor"
    assert figures["heard"] == "go to the cafeteria"
    assert figures["heard_by"] == ("spoken" if engine_available("flite") else "typed")
    assert figures["collisions"] == 0 and figures["mapping_collisions"] == 0
    assert figures["final_error_m"] <= 0.25  # the navigator's tolerance, by the truth
    assert figures["max_localisation_error_m"] < 0.1
    assert figures["mapping_seconds"] > 60  # it mapped the floor: no map was given
    assert any(event.startswith("lift requested") for event in figures["events"])
    assert math.isfinite(figures["closest_person_m"])  # the floor's people were walking


def test_the_demo_writes_a_report_with_the_map_route_states_and_figures(floor_demo):
    _, figures, out = floor_demo
    assert sorted(Path(f).name for f in figures["files"]) == [
        "errand.gif", "errand.html", "errand.npz", "map.yaml"]
    page = (out / "errand.html").read_text()
    for heading in ("Figures", "The map and the route", "The mission's states", "The drive"):
        assert f"<h2>{heading}</h2>" in page
    pngs = re.findall(r"data:image/png;base64,([A-Za-z0-9+/=]+)", page)
    gifs = re.findall(r"data:image/gif;base64,([A-Za-z0-9+/=]+)", page)
    assert len(pngs) == 2 and len(gifs) == 1
    assert all(base64.b64decode(p)[:8] == b"\x89PNG\r\n\x1a\n" for p in pngs)
    assert base64.b64decode(gifs[0])[:6] == b"GIF89a"
    for name in ("distance m", "closest person m", "safety interventions", "collisions"):
        assert f"<th>{name}</th>" in page
    assert "navigating -&gt; arrived: arrived at the cafeteria" in page
    # the map the chair made: its walls lie on the floor's true walls
    grid = load_map(out / "map.yaml")
    walls = load_world("floor").walls.reshape(-1, 2, 2)
    rows, cols = np.nonzero(grid.trinary() == 100)
    points = grid.cell_to_world(rows, cols)
    a, b = walls[:, 0], walls[:, 1]
    t = np.clip(np.einsum("nmk,mk->nm", points[:, None] - a, b - a)
                / np.einsum("mk,mk->m", b - a, b - a), 0, 1)
    gap = np.hypot(*(points[:, None] - (a + t[..., None] * (b - a))).transpose(2, 0, 1))
    assert np.mean(gap.min(axis=1) <= 0.1) >= 0.9
    # the log: the mission's states end in arrived, and the truth agrees with the figures
    log = RunLog.load(out / "errand.npz")
    assert mission_timeline(log)[-1][2] == "arrived"
    cafe = load_world("floor").places["cafeteria"]
    assert math.hypot(*(log.pose[-1, :2] - (cafe.x, cafe.y))) == pytest.approx(
        figures["final_error_m"], abs=0.01)


def small_building(tmp_path: Path) -> Path:
    """A building no world of the project is: a corridor with a pantry to the south and
    a workshop and a studio to the north, each through a 1.2 m door."""
    world = {
        "name": "annex",
        "walls": [[[0, 0], [14, 0], [14, 8], [0, 8], [0, 0]],
                  [[0, 3], [9, 3]], [[10.2, 3], [14, 3]],
                  [[0, 5], [3, 5]], [[4.2, 5], [11, 5]], [[12.2, 5], [14, 5]],
                  [[7, 5], [7, 8]]],
        "places": {"start": [1.5, 4.0, 0.0], "pantry": [11.0, 1.5, -1.5708],
                   "workshop": [3.6, 6.8, 1.5708], "studio": [10.5, 6.6, 1.5708]},
    }
    path = tmp_path / "annex.json"
    path.write_text(json.dumps(world))
    return path


def test_the_demo_runs_an_errand_on_a_world_file_it_has_never_seen(tmp_path, capsys):
    world = small_building(tmp_path)
    out = tmp_path / "out"
    status = main(["demo", "--world", str(world), "--to", "pantry", "--out", str(out),
                   "--quiet", "--json"])
    figures = json.loads(capsys.readouterr().out)
    assert status == 0, figures
    assert figures["arrived"] and figures["world"] == "annex"
    assert figures["collisions"] == 0 and figures["mapping_collisions"] == 0
    pantry = world_from_dict(json.loads(world.read_text())).places["pantry"]
    log = RunLog.load(out / "errand.npz")
    assert math.hypot(log.pose[-1, 0] - pantry.x, log.pose[-1, 1] - pantry.y) <= 0.25


def test_an_errand_that_does_not_arrive_exits_with_its_own_status(tmp_path, capsys,
                                                                  monkeypatch):
    """Given 3 s for the errand, the chair cannot reach the studio: the demo says so,
    writes its report all the same, and exits with status 3."""
    import functools

    from abcwc.experiments import errand

    world = small_building(tmp_path)
    monkeypatch.setattr(errand, "capstone_errand",
                        functools.partial(errand.capstone_errand, timeout=3.0))
    status = main(["demo", "--world", str(world), "--to", "studio", "--out",
                   str(tmp_path / "out"), "--quiet", "--typed"])
    assert status == MISSION_FAILED
    line = capsys.readouterr().out.strip()
    assert "FAILED (out of time: 3 s without arriving)" in line
    assert (tmp_path / "out" / "errand.html").exists()


def test_tour_of_goes_nearest_first_and_ends_at_the_start():
    world = world_from_dict({"name": "t", "walls": [[[0, 0], [10, 0]]], "places": {
        "start": [0, 0, 0], "far": [9, 0, 0], "near": [1, 0, 0], "mid": [4, 0, 0]}})
    assert tour_of(world, world.start) == [(1, 0), (4, 0), (9, 0), (0, 0)]


def test_the_report_page_holds_what_it_was_given(tmp_path):
    cells = np.full((40, 60), 0, dtype=np.int8)
    cells[0, :] = cells[-1, :] = 100
    cells[10:20, 40:50] = -1
    grid = OccupancyGrid.from_trinary(cells, 0.1, (0.0, 0.0, 0.0))
    track = np.column_stack([np.linspace(0.5, 5, 30), np.full(30, 2.0), np.zeros(30)])
    map_png = figure_png(plot_map_and_route(grid, track, track + 0.02,
                                            {"desk": Pose2D(5, 2, 0)},
                                            [(3.0, "lift requested", 5.0, 2.0)]).figure)
    states_png = figure_png(plot_timeline(
        [(0.0, 2.0, "navigating"), (2.0, 2.5, "manual override"), (2.5, 4, "idle")],
        [(3.0, "lift requested", 5.0, 2.0)]).figure)
    page = write_html_report(tmp_path / "r.html", "An <errand>", "it went", [
        ("collisions", "0"), ("distance m", "4.5")], map_png, states_png, None, ["a -> b"])
    text = page.read_text()
    assert "<title>An &lt;errand&gt;</title>" in text  # escaped
    assert "<th>distance m</th><td>4.5</td>" in text and "a -&gt; b" in text
    assert "The drive" not in text  # no animation given, no section for it
    with pytest.raises(ValueError, match="ends in .html"):
        write_html_report(tmp_path / "r.txt", "t", "s", [], map_png, states_png)
