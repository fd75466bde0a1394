"""Mapping a floor the chair does not know, judged against the simulator's truth: the tour
maps the floor world, the SLAM map agrees with the true walls and reloads identical from
its map_server files, a navigator on that map (never the world's walls) reaches places
localised within 0.1 m, and frontier exploration maps a small world of two rooms and
stops by itself. The floor is mapped once for the whole module."""

from __future__ import annotations

import json
import math
import time

import numpy as np
import pytest
from scipy import ndimage

from abcwc.behaviours.base import Status
from abcwc.behaviours.explore import (
    Explorer,
    ExploreSettings,
    floor_map,
    frontier_cells,
    run_exploration,
)
from abcwc.behaviours.navigator import Navigator
from abcwc.experiments.navigation_trial import calibrated_ekf
from abcwc.geometry import wrap_angle
from abcwc.mapping.build import build_map, load_built_map
from abcwc.mapping.grid import FREE, OCCUPIED
from abcwc.mapping.truth import rasterise_walls
from abcwc.sim import SimBase
from abcwc.sim.world import load_world
from abcwc.types import Pose2D

TOUR = ["office_a", "meeting", "lab", "library", "store", "lift", "cafeteria", "reading",
        "corridor_east"]
"""The floor world's places in the order the chair tours them (only their x, y are
handed to it)."""


@pytest.fixture(scope="module")
def floor(tmp_path_factory):
    """The floor world mapped once by a tour of its places, seed 24: the chair, the
    mapping run (:class:`MappedFloor`) and the saved map's path."""
    chair = SimBase("floor", seed=24, lidar=True, people=False)
    places = chair.world.places
    path = tmp_path_factory.mktemp("maps") / "floor.yaml"
    ekf = calibrated_ekf(chair)
    mapped = floor_map(chair, path, places["start"],
                       tour=[(places[n].x, places[n].y) for n in TOUR], ekf=ekf)
    own = mapped.explorer.estimates(mapped.log)
    drift = np.hypot(*(own[:, :2] - mapped.log.pose[:, :2]).T).max()
    print(f"\nmapping the floor: {mapped.wall_seconds:.1f} s wall, "
          f"{mapped.log.t[-1] - mapped.log.t[0]:.0f} s simulated, SLAM "
          f"{mapped.built.slam.seconds:.1f} s; the explorer's own estimate at most "
          f"{drift:.2f} m off")
    return chair, mapped, path


def test_the_tour_maps_the_floor_without_touching_anything(floor):
    chair, mapped, _ = floor
    explorer = mapped.explorer
    assert explorer.status is Status.SUCCEEDED, explorer.failure
    assert [v.status for v in explorer.visits] == ["succeeded"] * len(TOUR)
    assert int(mapped.log.collisions[-1]) == 0
    # where the chair stands on its map at the end (a navigator's start), against the truth
    truth = Pose2D(*mapped.log.pose[-1])
    assert math.hypot(mapped.pose.x - truth.x, mapped.pose.y - truth.y) < 0.1
    assert abs(wrap_angle(mapped.pose.theta - truth.theta)) < 0.02


def test_the_built_map_agrees_with_the_true_walls(floor):
    chair, mapped, _ = floor
    built = mapped.built
    truth = rasterise_walls(chair.world.walls, built.grid)
    metres_to_wall = ndimage.distance_transform_edt(~truth) * built.grid.resolution
    occupied = built.cells == OCCUPIED
    assert occupied.sum() > 3000  # 130 m of walls and more
    assert (metres_to_wall[occupied] <= 0.1).mean() >= 0.9
    # the free space covers the corridor (keeping 0.4 m off its walls) ...
    rows, cols = np.indices(built.cells.shape)
    centres = built.grid.cell_to_world(rows, cols)
    corridor = ((centres[..., 0] > 0.4) & (centres[..., 0] < 39.6)
                & (centres[..., 1] > 8.4) & (centres[..., 1] < 9.6))
    assert (built.cells[corridor] == FREE).mean() >= 0.95
    # ... and every place within 0.3 m
    for name, place in chair.world.places.items():
        near = np.hypot(centres[..., 0] - place.x, centres[..., 1] - place.y) <= 0.3
        assert (built.cells[near] == FREE).all(), name


def test_the_map_files_reload_identical_and_a_known_floor_is_loaded(floor):
    chair, mapped, path = floor
    assert path.exists() and path.with_suffix(".pgm").exists()
    loaded = load_built_map(path)
    assert np.array_equal(loaded.cells, mapped.built.cells)
    assert loaded.grid.resolution == mapped.built.grid.resolution
    assert loaded.grid.origin == mapped.built.grid.origin
    before = chair.frame.t
    known = floor_map(chair, path, chair.world.places["start"])  # the saved map: no drive
    assert chair.frame.t == before and known.log is None
    assert np.array_equal(known.built.cells, mapped.built.cells)


def _drive_to(chair, navigator, names):
    """Drive ``navigator`` on ``chair`` to each named place of its world in turn, checking
    each arrival against the truth; the largest localisation error (m) on the way."""
    worst = 0.0

    def driver(frame):
        nonlocal worst
        command = navigator(frame)
        estimate, truth = navigator.localizer.pose, frame.truth.pose
        worst = max(worst, math.hypot(estimate.x - truth.x, estimate.y - truth.y))
        return command

    for name in names:
        goal = chair.world.places[name]
        navigator.go_to(goal)
        for _ in range(24):  # 5 s at a time, at most 120 s
            log = chair.run(driver, 5.0)
            if not navigator.running:
                break
        assert navigator.status is Status.SUCCEEDED, (name, navigator.failure)
        truth = chair.pose
        assert math.hypot(goal.x - truth.x, goal.y - truth.y) <= \
            navigator.settings.xy_goal_tolerance, name
        assert int(log.collisions[-1]) == 0
        print(f"\n{name}: {math.hypot(goal.x - truth.x, goal.y - truth.y):.3f} m from the "
              f"place by the truth at {chair.frame.t:.0f} s")
    print(f"localisation on the built map: at most {worst:.3f} m off")
    return worst


def test_the_chair_navigates_by_its_own_map(floor):
    built = floor[1].built
    chair = SimBase("floor", seed=7, lidar=True, people=False)
    navigator = Navigator.for_map(built.cells, built.grid, chair.world.places["start"],
                                  ekf=calibrated_ekf(chair))
    assert _drive_to(chair, navigator, ["lab", "cafeteria", "library"]) < 0.1


def test_after_mapping_the_chair_drives_on_by_the_new_map(floor):
    chair, mapped, _ = floor
    navigator = Navigator.for_map(mapped.built.cells, mapped.built.grid, mapped.pose,
                                  ekf=mapped.ekf)
    assert _drive_to(chair, navigator, ["cafeteria"]) < 0.1


def _two_rooms(tmp_path):
    """A world file of two rooms joined by a 1.2 m door, an alcove in the second room
    behind a wall that the door does not show."""
    world = {"name": "two_rooms", "description": "two rooms, a door and an alcove",
             "walls": [[[0, 0], [12, 0], [12, 7], [0, 7], [0, 0]],
                       [[6, 0], [6, 2.5]], [[6, 3.7], [6, 7]],
                       [[7, 4.5], [12, 4.5]]],
             "places": {"start": [2.0, 2.0, 0.0]}, "people": []}
    path = tmp_path / "two_rooms.json"
    path.write_text(json.dumps(world))
    return load_world(path)


def test_frontier_exploration_maps_two_rooms_and_stops_by_itself(tmp_path):
    world = _two_rooms(tmp_path)
    chair = SimBase(world, seed=3, lidar=True, people=False)
    explorer = Explorer(chair.pose, ekf=calibrated_ekf(chair))
    clock = time.perf_counter()
    log = run_exploration(chair, explorer, 300.0)
    print(f"\ntwo rooms by frontiers: {time.perf_counter() - clock:.1f} s wall, "
          f"{log.t[-1] - log.t[0]:.0f} s simulated")
    assert explorer.status is Status.SUCCEEDED, explorer.failure
    assert explorer.ended_because == "no reachable frontier is left"
    assert log.t[-1] < 200.0  # it stopped, long before the run's end
    assert int(log.collisions[-1]) == 0
    assert any(v.goal[0] > 6.0 for v in explorer.visits)  # it went through the door
    # the floor of both rooms, 0.3 m off the walls, is mapped free, the alcove too
    grid = explorer.grid
    cells = grid.trinary()
    truth = rasterise_walls(world.walls, grid)
    rows, cols = np.indices(grid.shape)
    centres = grid.cell_to_world(rows, cols)
    inside = ((centres[..., 0] > 0) & (centres[..., 0] < 12) & (centres[..., 1] > 0)
              & (centres[..., 1] < 7)
              & (ndimage.distance_transform_edt(~truth) * grid.resolution > 0.3))
    assert (cells[inside] == FREE).mean() >= 0.95
    alcove = inside & (centres[..., 0] > 7.5) & (centres[..., 1] > 4.8)
    assert (cells[alcove] == FREE).mean() >= 0.95
    # and SLAM over the run draws walls where they are
    built = build_map(log, world.places["start"], poses=explorer.estimates(log))
    truth = rasterise_walls(world.walls, built.grid)
    metres = ndimage.distance_transform_edt(~truth) * built.grid.resolution
    assert (metres[built.cells == OCCUPIED] <= 0.1).mean() >= 0.9


def test_frontier_cells_are_open_cells_beside_a_large_unknown_region():
    log_odds = np.zeros((40, 40))
    log_odds[:, :20] = -1.0  # seen free: the left half
    log_odds[5:8, 5:8] = 0.0  # a 3 x 3 gap between beams inside it
    log_odds[30:, :20] = 1.0  # occupied along the bottom left
    frontier = frontier_cells(log_odds, min_unknown=20)
    expected = np.zeros_like(frontier)
    expected[:30, 19] = True  # beside the unknown right half, above the occupied cells
    assert np.array_equal(frontier, expected)
    # the gap counts when it is as large as asked
    assert frontier_cells(log_odds, min_unknown=9)[4, 6]


def test_bad_input_is_refused_with_what_is_allowed(tmp_path):
    with pytest.raises(ValueError, match="min_frontier"):
        ExploreSettings(min_frontier=0.0)
    with pytest.raises(ValueError, match="area"):
        ExploreSettings(area=(5.0, 0.0, 1.0, 4.0))
    with pytest.raises(ValueError, match="start must be a Pose2D"):
        Explorer((0.0, 0.0, 0.0))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="tour point"):
        Explorer(Pose2D(0.0, 0.0, 0.0), tour=[(1.0, math.nan)])
    chair = SimBase(_two_rooms(tmp_path), seed=0, lidar=True, people=False)
    log = chair.run(lambda frame: None, 1.0)
    with pytest.raises(ValueError, match="scan_every"):
        build_map(log, chair.world.places["start"], scan_every=0)
    with pytest.raises(ValueError, match="max_seconds"):
        run_exploration(chair, Explorer(chair.pose), 0.0)


def test_a_mapping_run_that_does_not_end_in_time_says_so(tmp_path):
    world = _two_rooms(tmp_path)
    chair = SimBase(world, seed=0, lidar=True, people=False)
    with pytest.raises(RuntimeError, match="did not end within 3 s"):
        floor_map(chair, tmp_path / "rooms.yaml", world.places["start"],
                  tour=[(10.0, 2.0)], max_seconds=3.0)
    assert not (tmp_path / "rooms.yaml").exists()  # no half map saved
