"""The navigator against the simulator's ground truth: it reaches goals localised only by
its own estimate, ends bad goals with a reason, keeps out of people's way, and every
command it sends passes the safety filter."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.behaviours.base import Status
from abcwc.behaviours.navigator import Navigator
from abcwc.geometry import transform_points, wrap_angle
from abcwc.navigation.costmap import LETHAL
from abcwc.navigation.dwa import DwaResult
from abcwc.navigation.people import PeopleTracker, is_straight
from abcwc.sim import SimBase
from abcwc.sim.world import world_from_dict
from abcwc.types import Pose2D, Twist


def _drive(chair: SimBase, navigator: Navigator, seconds: float) -> tuple[float, object]:
    """Run until the navigator ends (or ``seconds``); the largest localisation error."""
    frame, worst = chair.read(), 0.0
    for _ in range(round(seconds / chair.period)):
        chair.send(navigator(frame))
        frame = chair.step()
        truth, estimate = chair.pose, navigator.localizer.pose
        worst = max(worst, math.hypot(truth.x - estimate.x, truth.y - estimate.y))
        if not navigator.running:
            break
    return worst, frame


def test_reaches_the_cafeteria_by_its_own_estimate():
    chair = SimBase("floor", seed=4, lidar=True, people=False)
    navigator = Navigator.for_world(chair.world)
    navigator.go_to("cafeteria")
    worst, frame = _drive(chair, navigator, 120)
    goal, truth = chair.world.places["cafeteria"], chair.pose
    assert navigator.status is Status.SUCCEEDED, navigator.failure
    assert frame.truth.collisions == 0
    tolerance = navigator.settings.xy_goal_tolerance
    assert math.hypot(goal.x - truth.x, goal.y - truth.y) <= tolerance
    assert abs(wrap_angle(goal.theta - truth.theta)) <= navigator.settings.yaw_goal_tolerance + 0.05
    assert worst < tolerance  # the estimate stays within the goal tolerance all the way
    assert navigator.localizer.accepted > 50  # the map fixes did the work


@pytest.mark.parametrize(("goal", "reason"), [
    ((9.0, 4.0), "inside a wall"),
    ((100.0, 100.0), "off the map"),
    ((29.0, 2.5), "no path to the goal"),  # inside a closed table's outline
    ((9.1, 4.0), "too close to a wall"),
])
def test_impossible_goals_end_at_once_with_the_reason(goal, reason):
    chair = SimBase("floor", seed=0, lidar=True, people=False)
    navigator = Navigator.for_world(chair.world)
    navigator.go_to(goal)
    assert navigator.status is Status.FAILED
    assert reason in navigator.failure
    assert navigator(chair.read()) == Twist(0.0, 0.0)


def test_bad_goal_values_are_refused():
    navigator = Navigator.for_world(SimBase("floor", people=False).world)
    with pytest.raises(ValueError, match="unknown place 'moon'; places: start"):
        navigator.go_to("moon")
    with pytest.raises(ValueError, match="finite"):
        navigator.go_to((math.nan, 1.0))
    with pytest.raises(ValueError, match="a goal is a place name"):
        navigator.go_to(object())


def test_cancel_stops_the_chair():
    chair = SimBase("floor", seed=1, lidar=True, people=False)
    navigator = Navigator.for_world(chair.world)
    navigator.go_to("cafeteria")
    _drive(chair, navigator, 6)
    navigator.cancel()
    assert navigator.status is Status.FAILED and navigator.failure == "cancelled"
    frame = chair.read()
    for _ in range(100):
        chair.send(navigator(frame))
        frame = chair.step()
    before = chair.pose
    for _ in range(25):
        chair.send(navigator(frame))
        frame = chair.step()
    assert math.hypot(chair.pose.x - before.x, chair.pose.y - before.y) < 0.005


def _one_sample_result(command: Twist, gap: float = math.inf) -> DwaResult:
    """A DWA cycle that chose ``command``, its only sample, with the footprint ``gap`` m
    from what it may not come nearer."""
    return DwaResult(command, np.zeros((1, 2)), np.zeros((1, 1, 3)), np.ones(1, bool),
                     np.zeros(1), 0, gap=gap)


def test_the_safety_filter_cannot_be_bypassed(monkeypatch):
    """A local planner gone wrong (always full ahead) still never reaches the wall."""
    chair = SimBase("floor", seed=2, lidar=True, people=False, errors="ideal")
    navigator = Navigator.for_world(chair.world)
    navigator.go_to("cafeteria")  # the reckless planner drives straight on, east

    def reckless(*args, **kwargs) -> DwaResult:
        return _one_sample_result(Twist(0.8, 0.0))

    monkeypatch.setattr(navigator.dwa, "plan", reckless)
    chair_start = chair.pose
    frame = chair.read()
    for _ in range(round(60 / chair.period)):
        chair.send(navigator(frame))
        frame = chair.step()
    assert frame.truth.collisions == 0
    assert chair.pose.x > chair_start.x + 20  # it did drive, and stopped at the end wall
    assert chair.safety.interventions["obstacle"] > 0  # the body's filter, in the loop


def test_joystick_takes_over_and_the_navigator_carries_on_after():
    chair = SimBase("floor", seed=5, lidar=True, people=False)
    navigator = Navigator.for_world(chair.world)
    navigator.go_to((14.0, 9.0, 0.0))
    _drive(chair, navigator, 5)
    chair.set_joystick(fb=chair.params.joystick_centre - 60)  # pull back: reverse
    frame = chair.read()
    x_before = chair.pose.x
    for _ in range(100):
        chair.send(navigator(frame), navigator.decided_at)
        frame = chair.step()
    assert chair.pose.x < x_before  # the person in the seat drove it back
    assert chair.safety.reason == "joystick override"
    chair.release_joystick()
    _drive(chair, navigator, 60)
    assert navigator.status is Status.SUCCEEDED, navigator.failure


def _corridor(people: list) -> object:
    return world_from_dict({
        "name": "corridor", "walls": [[[0, 0], [16, 0], [16, 3], [0, 3], [0, 0]]],
        "places": {"start": [1.0, 1.5, 0.0], "end": [14.5, 1.5, 0.0]}, "people": people,
    })


def test_a_person_stepping_in_front_is_never_touched():
    crossing = {"name": "crosser", "path": [[6.0, 2.8], [6.0, 0.2]], "speed": 0.7,
                "radius": 0.25, "loop": False}
    chair = SimBase(_corridor([crossing]), seed=6, lidar=True)
    navigator = Navigator.for_world(chair.world)
    navigator.go_to("end")
    _, frame = _drive(chair, navigator, 90)
    assert frame.truth.collisions == 0
    assert navigator.status is Status.SUCCEEDED, navigator.failure


def test_a_person_walking_head_on_down_a_corridor_is_never_touched():
    oncoming = {"name": "walker", "path": [[15.0, 1.5], [1.0, 1.5]], "speed": 0.9,
                "radius": 0.25, "loop": False}
    chair = SimBase(_corridor([oncoming]), seed=7, lidar=True)
    navigator = Navigator.for_world(chair.world)
    navigator.go_to("end")
    _, frame = _drive(chair, navigator, 90)
    assert frame.truth.collisions == 0
    assert navigator.status is Status.SUCCEEDED, navigator.failure


def test_a_walker_turning_back_towards_a_following_chair_is_never_touched():
    """The chair follows a walker down the corridor; the walker turns round where its
    path ends (taking the time a person takes to turn) and walks back towards the
    chair, which keeps clear of them: more than DWA's people_margin (0.1 m) from the
    chair's outline. (Evading, the chair now brakes and stands aside while the walker
    passes, 0.13 m away; it used to swerve on at speed, 0.29 m away.)"""
    ahead = {"name": "walker", "path": [[2.2, 1.5], [12.0, 1.5]], "speed": 0.9,
             "radius": 0.25, "loop": False}
    chair = SimBase(_corridor([ahead]), seed=2, lidar=True)
    navigator = Navigator.for_world(chair.world)
    navigator.go_to("end")
    frame, closest = chair.read(), math.inf
    for _ in range(round(60 / chair.period)):
        chair.send(navigator(frame))
        frame = chair.step()
        x, y, r = chair.walkers[0].circle
        closest = min(closest, chair._chair_shape.point_query((x, y)).distance - r)
        if not navigator.running:
            break
    assert frame.truth.collisions == 0
    assert closest > 0.1
    assert navigator.status is Status.SUCCEEDED, navigator.failure


@pytest.mark.parametrize("with_map", [True, False])
def test_people_tracker_finds_a_walker_and_its_velocity(with_map):
    """With the static map the walls are explained away; without one every return is
    unexplained, and only the walker's compact blob (not the room's long walls) becomes
    a track. Either way one track, on the walker, at its velocity."""
    walker = {"name": "w", "path": [[3.0, 1.0], [3.0, 9.0]], "speed": 0.8, "radius": 0.25,
              "loop": False}
    world = world_from_dict({"name": "room", "walls": [[[0, 0], [10, 0], [10, 10], [0, 10],
                                                        [0, 0]]],
                             "places": {"start": [7.0, 5.0, math.pi]}, "people": [walker]})
    chair = SimBase(world, seed=8, lidar=True)
    if with_map:
        static = Navigator.for_world(world).static_map
        tracker = PeopleTracker(static.cost == 254, static)
    else:
        tracker = PeopleTracker(None, None, max_extent=0.7)
    sensor = Pose2D(7.0 + math.cos(math.pi) * chair.params.lidar.mount[0], 5.0, math.pi)
    last = -1.0
    for _ in range(150):
        frame = chair.step()
        if frame.lidar.stamp > last:
            last = frame.lidar.stamp
            tracks = tracker.update(frame.lidar, sensor, frame.lidar.stamp)
    assert len(tracks) == 1
    x, y, _ = chair.walkers[0].circle
    assert np.hypot(*(tracks[0].position - (x, y))) < 0.1
    assert np.allclose(tracks[0].velocity, (0.0, 0.8), atol=0.1)


def test_a_tracker_takes_a_map_whole_or_none():
    with pytest.raises(ValueError, match="neither"):
        PeopleTracker(np.zeros((2, 2), bool), None)


def test_random_goal_trial_with_people_reaches_every_goal_without_a_touch():
    """A short run of the 50-goal trial (``abcwc navtrial``): seeded goals in the floor
    world with its people walking, judged by the simulator's ground truth."""
    from abcwc.experiments.navigation_trial import run_trial

    result = run_trial(goals=3, seed=11)
    assert result.success_rate == 1.0, result.summary()
    assert result.collisions == 0 and result.lethal_periods == 0
    assert all(o.max_localisation_error < o.tolerance for o in result.outcomes)
    assert all(1.0 <= o.driven / o.straight for o in result.outcomes)


def test_a_chair_moved_by_hand_finds_its_place_and_carries_on():
    """Lifted 1 m on and turned 29 degrees mid-way (its wheels turn no tick): the scans
    stop fitting, the navigator stands, searches round its estimate, finds the place and
    goes on to the goal."""
    from tests.test_localization import _kidnap

    chair = SimBase("floor", seed=7, lidar=True, people=False)
    navigator = Navigator.for_world(chair.world)
    navigator.go_to((16.0, 9.0, 0.0))
    _drive(chair, navigator, 4)
    _kidnap(chair, 1.0, 0.0, 0.5)
    phases = set()
    frame = chair.read()
    for _ in range(round(60 / chair.period)):
        chair.send(navigator(frame))
        frame = chair.step()
        phases.add(navigator.feedback.phase)
        if not navigator.running:
            break
    assert "relocalising" in phases
    assert navigator.status is Status.SUCCEEDED, navigator.failure
    assert frame.truth.collisions == 0
    truth, estimate = chair.pose, navigator.localizer.pose
    assert math.hypot(truth.x - estimate.x, truth.y - estimate.y) < 0.1


def test_drives_by_a_map_file_the_mapping_made(tmp_path):
    """Map the lab from one spot (a turn on the spot, the lidar's scans laid at the true
    poses), save it as map_server files, load them, and drive by them: the static layer
    and the localiser both come from the file."""
    from abcwc.mapping.grid import OccupancyGrid, integrate_log
    from abcwc.mapping.map_io import load_map, save_map

    surveyor = SimBase("lab", seed=8, lidar=True, start="centre", people=False)
    log = surveyor.run(lambda frame: Twist(0.0, 0.6), 12.0)
    grid = OccupancyGrid.covering(*surveyor.world.bounds, 0.05, margin=1.0)
    assert integrate_log(grid, log) >= 100
    save_map(grid, tmp_path / "lab.yaml")
    loaded = load_map(tmp_path / "lab.yaml")

    chair = SimBase("lab", seed=9, lidar=True, start="centre", people=False)
    navigator = Navigator.for_map(loaded.trinary(), loaded, chair.pose)
    navigator.go_to((8.0, 6.5, 0.0))
    _, frame = _drive(chair, navigator, 60)
    assert navigator.status is Status.SUCCEEDED, navigator.failure
    assert frame.truth.collisions == 0
    assert math.hypot(chair.pose.x - 8.0, chair.pose.y - 6.5) <= 0.3


@pytest.mark.parametrize("gap, cap", [(math.inf, 0.8), (0.3, 0.8), (0.15, 0.4), (0.06, 0.3),
                                      (-0.02, 0.3)])
def test_near_obstacles_the_speed_is_scaled_down_along_the_same_arc(gap, cap):
    """DWA's (0.8 m/s, 0.4 rad/s) with the footprint ``gap`` m from what it may not come
    nearer: at most max_vel_x * gap / slow_within (0.8 * gap / 0.3), never below
    narrow_speed (0.3 m/s), and the turn rate scaled with it, so the chair stays on the
    arc DWA checked (curvature 0.5 /m)."""
    navigator = Navigator.for_world(SimBase("floor", seed=0, people=False).world)
    s = navigator.settings
    assert (s.max_vel_x, s.slow_within, s.narrow_speed) == (0.8, 0.3, 0.3)
    result = _one_sample_result(Twist(0.8, 0.4), gap=gap)
    command = navigator._regulated(result, Pose2D(3.0, 9.0, 0.0))
    assert command.v == pytest.approx(cap)
    assert command.w / command.v == pytest.approx(0.5)


def test_near_a_person_the_speed_is_scaled_down_along_the_same_arc(monkeypatch):
    """A person standing ahead of the chair: the speed is at most people_speed +
    (max_vel_x - people_speed) * gap / people_slow_within, the gap from the covering
    circles to the person's body (people_gap of standing still), and the arc is kept;
    2 m and more away, nothing changes."""
    navigator = Navigator.for_world(SimBase("floor", seed=0, people=False).world)
    s = navigator.settings
    pose = Pose2D(3.0, 9.0, 0.0)
    result = _one_sample_result(Twist(0.8, 0.4))
    for x in (4.6, 5.2, 8.0):
        person = np.array([[x, 9.0, 0.0, 0.0, 0.25]])
        monkeypatch.setattr(navigator.people, "moving_discs",
                            lambda walked_only=False, person=person: person)
        gap = navigator.dwa.people_gap(pose, np.zeros((1, 2)), person, 0.0)[0]
        expected = min(0.8, s.people_speed + (0.8 - s.people_speed) * gap / s.people_slow_within)
        command = navigator._regulated(result, pose)
        assert command.v == pytest.approx(expected)
        assert command.w / command.v == pytest.approx(0.5)
    assert command.v == 0.8  # the last person, 8 m ahead, is far enough


def test_avoided_cells_are_walls_until_the_next_goal():
    """avoid() makes cells walls of the global costmap (inflated), counts only new ones,
    refuses a grid of another shape, and the next goal forgets them."""
    navigator = Navigator.for_world(SimBase("floor", seed=0, people=False).world)
    navigator.go_to((14.0, 9.0, 0.0))
    rows, cols = navigator.static_map.world_to_cell(np.array([[8.0, 9.0]]))
    marks = np.zeros(navigator.static_map.shape, dtype=bool)
    marks[rows[0] - 2:rows[0] + 3, cols[0] - 2:cols[0] + 3] = True
    before = navigator.global_costmap.cost.copy()
    assert navigator.avoid(marks) == 25 and navigator.avoid(marks) == 0
    after = navigator.global_costmap.cost
    assert after[rows[0], cols[0]] == LETHAL
    assert (after >= before).all() and (after > before).sum() > 25  # inflated round them
    with pytest.raises(ValueError, match="static map's shape"):
        navigator.avoid(np.zeros((3, 3), dtype=bool))
    navigator.go_to((14.0, 9.0, 0.0))
    assert (navigator.global_costmap.cost == before).all() and not navigator.avoided.any()


def test_on_a_finished_map_no_plan_crosses_unknown_cells():
    """A built map's unknown cells are a wall's shadow or the outside, never a way: a
    room whose only opening is unknown has no path in (the navigator fails at once,
    saying so), where a map that is still growing may plan through it."""
    from abcwc.mapping.grid import FREE, OCCUPIED, UNKNOWN, OccupancyGrid
    from abcwc.navigation.costmap import Costmap
    from abcwc.navigation.localization import MapLocalizer, occupied_points

    cells = np.full((80, 120), FREE, dtype=np.int8)
    cells[[0, -1], :] = OCCUPIED
    cells[:, [0, -1]] = OCCUPIED
    cells[:, 60] = OCCUPIED  # a wall across the room
    cells[30:50, 58:63] = UNKNOWN  # a stretch of it never seen
    grid = OccupancyGrid.from_trinary(cells, 0.05, (0.0, 0.0, 0.0))
    start, goal = Pose2D(1.0, 2.0, 0.0), (5.0, 2.0)
    finished = Navigator.for_map(cells, grid, start)
    assert not finished.allow_unknown
    finished.go_to(goal)
    assert finished.status is Status.FAILED and "no path" in finished.failure
    growing = Costmap.like(grid)
    growing.add_static(cells)
    still_mapping = Navigator(growing, MapLocalizer(occupied_points(cells, grid), start))
    still_mapping.go_to(goal)
    assert still_mapping.running and still_mapping.path is not None


def test_only_a_track_seen_walking_is_a_walker():
    """A post the map lacks is tracked as a person standing still; the navigator waits
    for people in its way (a way they shut is no proof it is too narrow) but not for a
    post, so PeopleTracker.walkers keeps only the tracks once faster than a walk."""
    room = [[[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]]
    post = [[[5.0, 7.0], [5.2, 7.0], [5.2, 7.2], [5.0, 7.2], [5.0, 7.0]]]
    walker = {"name": "w", "path": [[3.0, 1.0], [3.0, 9.0]], "speed": 0.8, "radius": 0.25,
              "loop": False}
    places = {"start": [7.0, 5.0, math.pi]}
    world = world_from_dict({"name": "room", "walls": room + post, "places": places,
                             "people": [walker]})
    static = Navigator.for_world(world_from_dict({"name": "map", "walls": room,
                                                  "places": places})).static_map
    tracker = PeopleTracker(static.cost == 254, static)
    chair = SimBase(world, seed=8, lidar=True)
    sensor = Pose2D(7.0 - chair.params.lidar.mount[0], 5.0, math.pi)
    last = -1.0
    for _ in range(150):
        frame = chair.step()
        if frame.lidar.stamp > last:
            last = frame.lidar.stamp
            tracker.update(frame.lidar, sensor, frame.lidar.stamp)
    positions = np.array([track.position for track in tracker.tracks])
    assert len(positions) == 2 and np.hypot(*(positions - (5.1, 7.1)).T).min() < 0.3
    walkers = tracker.walkers()
    x, y, _ = chair.walkers[0].circle
    assert walkers.shape == (1, 3) and np.hypot(walkers[0, 0] - x, walkers[0, 1] - y) < 0.1
    # DWA keeps a person's berth from the walker only; the post is the costmap's
    assert tracker.moving_discs().shape == (2, 5)
    assert np.allclose(tracker.moving_discs(walked_only=True)[:, :2], walkers[:, :2])


def test_a_speck_the_survey_never_saw_does_not_stop_the_chair():
    """A map the chair made itself can hold a few unknown cells in open floor (a walker
    stood in the lidar's way). A finished map's unknown cells are no way, but where the
    newest scan's beams cross them, the scan wins (costmap_2d's layers combine so): the
    chair drives down the corridor past the speck, where the plan went beside it."""
    from abcwc.mapping.grid import FREE, OCCUPIED, UNKNOWN, OccupancyGrid
    from abcwc.navigation.costmap import FREE_SPACE

    cells = np.full((60, 320), FREE, dtype=np.int8)  # the corridor, 16 x 3 m at 0.05 m
    cells[[0, -1], :] = OCCUPIED
    cells[:, [0, -1]] = OCCUPIED
    cells[26:28, 120:122] = UNKNOWN  # (6.0-6.1, 1.3-1.4): on the chair's way
    cells[33:35, 160:162] = UNKNOWN  # (8.0-8.1, 1.65-1.75)
    grid = OccupancyGrid.from_trinary(cells, 0.05, (0.0, 0.0, 0.0))
    chair = SimBase(_corridor([]), seed=9, lidar=True, people=False)
    navigator = Navigator.for_map(cells, grid, chair.pose)
    navigator.go_to(chair.world.places["end"])
    frame, seen_free = chair.read(), False
    for _ in range(round(40.0 / chair.params.control_period)):
        chair.send(navigator(frame), navigator.decided_at)
        frame = chair.step()
        local = navigator.local_costmap
        if local is not None and 4.0 < chair.pose.x < 5.5:
            rows, cols = local.world_to_cell(np.array([[6.025, 1.325]]))
            seen_free |= bool(local.contains(rows, cols)[0]
                              and local.cost[rows[0], cols[0]] == FREE_SPACE)
        if not navigator.running:
            break
    assert seen_free
    assert navigator.status is Status.SUCCEEDED, navigator.failure
    assert frame.truth.collisions == 0


def test_without_a_map_a_wall_piece_is_not_a_person():
    """Without a map, the piece of a wall left in view beside a door (0.4 m of it) is as
    compact as a person; the tracker tells them apart by shape: the wall's returns lie
    on a line, a person's arc bows away from it. One candidate, on the person."""
    person = {"name": "p", "path": [[3.0, 0.8], [3.0, 0.81]], "speed": 0.01, "radius": 0.25,
              "loop": False}
    world = world_from_dict({"name": "piece", "walls": [[[3.0, -1.0], [3.0, -0.6]]],
                             "places": {"start": [0.0, 0.0, 0.0]}, "people": [person]})
    chair = SimBase(world, seed=3, lidar=True)
    scan = chair.step().lidar
    sensor = Pose2D(*chair.params.lidar.mount)
    points = transform_points(sensor, scan.points())
    wall = points[(np.abs(points[:, 0] - 3.0) < 0.05) & (points[:, 1] < -0.5)]
    arc = points[np.hypot(points[:, 0] - 3.0, points[:, 1] - 0.8) < 0.35]
    assert len(wall) >= 4 and np.ptp(wall[:, 1]) > 0.3 and len(arc) >= 4
    assert is_straight(wall) and not is_straight(arc)
    candidates = PeopleTracker(None, None, max_extent=0.7).detect(scan, sensor)
    assert len(candidates) == 1
    assert np.hypot(*(candidates[0] - (3.0, 0.8))) < 0.15
