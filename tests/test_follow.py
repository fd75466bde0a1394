"""The tag follower in the simulator, judged by the ground truth."""

import json
import math

import numpy as np
import pytest

from abcwc.behaviours.base import Status
from abcwc.behaviours.follow import FollowSettings, TagFollower
from abcwc.behaviours.follow_handover import HandOver
from abcwc.behaviours.follow_identity import IdentityGate
from abcwc.estimation.gyro import GyroOdometry
from abcwc.experiments.follow_trial import (
    hand_over_demo,
    run_follow_trial,
    run_trial_in,
    two_rooms_world,
)
from abcwc.geometry import compose
from abcwc.params import default_params
from abcwc.paths import data_dir
from abcwc.perception.tags import FollowCard
from abcwc.sim import SimBase
from abcwc.sim.world import world_from_dict
from abcwc.types import LIDAR_FRAME, Pose2D


@pytest.fixture(scope="module")
def trials():
    """Three two-minute trials (seeds 0, 1, 2): one seed's luck with the passer-by at a
    corner moves its figure by 15 points, so the bar is judged on the typical run."""
    return [run_trial_in("lab", seed) for seed in (0, 1, 2)]


@pytest.fixture(scope="module")
def trial(trials):
    return trials[0]


def test_the_follower_keeps_a_metre_behind_ana_for_two_minutes(trials, trial):
    """The bar: 1.0 +- 0.3 m for at least 90 % of the time the tag is read in the
    typical run (the median of three seeds), at least 75 % in every run, the tag read in
    at least 80 % of the decisions, never touching anyone or anything, and reading the
    tag again after every loss."""
    held = [t.held() for t in trials]
    assert np.median(held) >= 0.90 and min(held) >= 0.75, held
    # the bar for the tag: read in at least 80 % of the decisions, every run
    # (the card's marker on its middle line stays in the picture after her turns)
    read = [float(t.seen.mean()) for t in trials]
    assert min(read) >= 0.80, read
    assert all(t.collisions == 0 and t.closest_person > 0.05 for t in trials)
    assert trial.collisions == 0
    assert trial.closest_person > 0.05
    assert trial.status == "running"
    assert trial.longest_blind() < 5.0  # Ben and the corners hide her, but not for long
    assert trial.seen[-50:].any()  # still reading her at the end
    blind = ~trial.seen
    assert blind.sum() > 100  # there were losses to recover from (corners, Ben)
    assert np.median(trial.distance) == pytest.approx(1.0, abs=0.1)


def test_the_follower_turns_smoothly(trial):
    """No figure 50: the turn rate changes sign seldom (corners, not chatter)."""
    turning = trial.w[np.abs(trial.w) > 0.05]
    flips = np.count_nonzero(np.diff(np.sign(turning)))
    assert flips / (trial.t[-1] - trial.t[0]) < 0.5  # per second


def test_a_s_thesis_follower_does_not_keep_up():
    """A.13's law, v = 1000 dz: the chair lags metres behind a walking person."""
    thesis = run_follow_trial(seconds=30.0, thesis=True)
    assert thesis.held() < 0.5
    assert np.median(thesis.distance) > 2.0


def standing_person_world(distance: float):
    raw = json.loads((data_dir() / "worlds" / "lab.json").read_text())
    x, y = 1.5 + 0.3 + distance + 0.26, 1.5  # the tag `distance` m ahead of the camera
    # walking away at 1 mm/s: standing, her back (and the tag) to the chair
    raw["people"] = [{"name": "ana", "speed": 0.001, "path": [[x, y], [x + 1.0, y]],
                      "loop": False, "tag": {"text": "ana", "marker_id": 7}}]
    return world_from_dict(raw)


def test_the_chair_closes_to_a_metre_from_a_standing_person_and_stops():
    chair = SimBase(standing_person_world(2.5), lidar=True, camera="gray")
    follower = TagFollower(chair.walkers[0].spec.tag, GyroOdometry(params=chair.params),
                           chair.params)
    chair.run(follower, 12.0)
    tag = chair.walkers[0].tag_target()
    origin = compose(chair.pose, chair.params.depth_scan.mount)[:2]
    assert math.hypot(tag.centre[0] - origin[0], tag.centre[1] - origin[1]) == pytest.approx(
        1.0, abs=0.1)
    assert follower.state == "following"
    assert follower.sightings[-1].t > 11.5  # reading the tag to the end
    assert abs(chair.read().truth.pose.theta) < 0.05
    assert np.abs(np.array([row[4] for row in follower.log[-30:]])).max() < 0.05  # still


def test_with_no_one_to_follow_the_chair_looks_round_once_and_says_so():
    chair = SimBase("lab", lidar=True, camera="gray")
    card = standing_person_world(2.0).people[0].tag
    follower = TagFollower(card, GyroOdometry(params=chair.params), chair.params)
    chair.run(follower, 20.0)
    assert follower.status is Status.FAILED
    assert "lost" in follower.failure and "full turn" in follower.failure
    assert chair.collisions == 0


def test_bad_settings_are_refused():
    card = standing_person_world(2.0).people[0].tag
    with pytest.raises(ValueError, match="distance"):
        TagFollower(card, GyroOdometry(), settings=FollowSettings(distance=0.0))
    with pytest.raises(ValueError, match="k_turn"):
        TagFollower(card, GyroOdometry(), settings=FollowSettings(k_turn=math.nan))


# ---------------------------------------------------------------- the trail, the gate, people
def corridor_world(people: list[dict]) -> object:
    """A corridor 2 m wide and 16 m long, a room to its north behind a 0.9 m door
    (x 6.55-7.45), the chair at its west end facing east."""
    return world_from_dict({
        "name": "corridor", "walls": [
            [[0, 2], [0, 0], [16, 0], [16, 2], [7.45, 2]], [[6.55, 2], [0, 2]],
            [[4, 2], [4, 6], [10, 6], [10, 2]]],
        "places": {"start": [1.0, 1.0, 0.0]}, "people": people})


def follow_in(world, seconds: float) -> tuple[SimBase, TagFollower, list]:
    chair = SimBase(world, lidar=True, camera="gray")
    follower = TagFollower(chair.walkers[0].spec.tag, GyroOdometry(params=chair.params),
                           chair.params)
    poses = []
    frame = chair.read()
    for _ in range(round(seconds / chair.period)):
        chair.send(follower(frame), follower.decided_at)
        frame = chair.step()
        poses.append((chair.pose.x, chair.pose.y))
    return chair, follower, np.array(poses)


ANA = {"name": "ana", "speed": 0.7, "loop": False,
       "tag": {"text": "ana", "marker_id": 7}}


def test_the_trail_takes_the_chair_through_a_side_door_not_across_its_frame():
    """Ana turns 90 degrees into a 0.9 m door; the chair goes where she went: through
    the door's middle, touching nothing (aiming at her would cross the frame)."""
    ana = {**ANA, "path": [[2.2, 1.0], [7.0, 1.0], [7.0, 4.5]]}
    chair, follower, poses = follow_in(corridor_world([ana]), 30.0)
    assert chair.collisions == 0
    assert poses[-1, 1] > 2.4  # in the room
    in_door = poses[np.abs(poses[:, 1] - 2.0) < 0.05]
    assert len(in_door) and np.abs(in_door[:, 0] - 7.0).max() < 0.15  # the door's middle
    assert follower.status is not Status.FAILED


def test_someone_walking_up_from_behind_does_not_stop_the_chair():
    """Carl overtakes at 1.3 m/s from behind, 0.6 m to the side: the chair keeps
    following, never standing more than 0.3 s once under way (judged where he stands,
    and by his motion once ahead, he is never a block)."""
    ana = {**ANA, "path": [[2.2, 1.1], [15.0, 1.1]]}
    carl = {"name": "carl", "speed": 1.3, "loop": False, "path": [[-2.0, 0.5], [15.0, 0.5]]}
    world = corridor_world([ana, carl])
    chair, follower, poses = follow_in(world, 12.0)
    assert chair.collisions == 0
    assert poses[-1, 0] > 7.5  # kept up with Ana (she is at 9.9 m by then)
    standing = np.array([row[3] for row in follower.log])[20:] < 0.05  # once under way
    longest = max((len(run) for run in "".join("s" if s else "." for s in standing).split(".")),
                  default=0)
    assert longest <= 3, longest  # decisions at 10 Hz


def test_the_identity_gate_refuses_a_jump_to_a_passer_by():
    """A track at 0.9 m/s does not take a blob 0.45 m ahead of its prediction 0.1 s on
    (its velocity would become 0.9 + 0.2 / 0.1 * 0.45 = 1.8 m/s), nor one of two blobs
    inside its gate; a step at walking pace is taken."""
    gate = IdentityGate(gate=0.5, max_speed=1.6)
    track, velocity = np.array([5.0, 1.0]), np.array([0.7, 0.0])
    step, why = gate.choose(np.array([[5.07, 1.0], [8.0, 1.0]]), track, velocity, 0.1, 0.2)
    assert why == "taken" and np.allclose(step, [5.07, 1.0])
    fast = np.array([0.9, 0.0])
    assert gate.choose(np.array([[5.45, 1.0]]), track, fast, 0.1, 0.2) == (None, "too fast")
    assert gate.choose(np.array([[5.3, 1.0]]), track, velocity, 0.1, 0.2)[1] == "taken"
    assert gate.choose(np.array([[5.05, 1.0], [5.0, 1.4]]), track, velocity, 0.1, 0.2
                       ) == (None, "two near")
    assert gate.choose(np.array([[6.0, 1.0]]), track, velocity, 0.1, 0.2) == (None,
                                                                              "none near")
    with pytest.raises(ValueError, match="max_speed"):
        IdentityGate(max_speed=0.0)


def _turns_back_while(velocities: list[tuple[float, float]]) -> list[bool]:
    """A follower fed lidar-only updates every 0.1 s of a blob moving at each of
    ``velocities`` (m/s) in turn, as :meth:`TagFollower.update` feeds them: whether it
    judged the track to have turned back, at each update."""
    params = default_params()
    follower = TagFollower(FollowCard("ana", 7), GyroOdometry(params=params), params)
    t, point = 0.0, np.array([5.0, 1.0])
    follower.track, follower.velocity = point.copy(), np.array(velocities[0], dtype=float)
    follower._predict(t)
    follower._measured(t, point)
    judged = []
    for velocity in velocities:
        t += 0.1
        point = point + 0.1 * np.asarray(velocity, dtype=float)
        follower._predict(t)
        follower._measured(t, point)
        judged.append(follower._turned_back(t))
        if judged[-1]:  # coasting from here: back where she would be, walking on
            assert follower.velocity[1] < -0.5 and follower.track[1] < point[1] - 0.3
            break
    return judged


def test_a_track_that_runs_back_the_way_it_came_is_on_someone_else():
    """Walking south at 0.7 m/s for 1 s, then a blob coming back north at 1 m/s (two
    people crossing in a doorway, the one coming back hiding her): within 0.5 s the
    track is turned back to its old prediction and coasts. A 90 degree turn (a corner,
    a door) is hers, and so is walking on."""
    assert any(_turns_back_while([(0.0, -0.7)] * 10 + [(0.0, 1.0)] * 5))
    assert not any(_turns_back_while([(0.0, -0.7)] * 10 + [(0.7, 0.0)] * 20))
    assert not any(_turns_back_while([(0.0, -0.7)] * 30))


def test_the_search_turns_to_where_she_walked_on_not_where_she_was_last_seen():
    """Lost 7.5 s ago just left of the camera's axis, walking east at 0.7 m/s across the
    chair's view: by now she is well to its right, and the search turns right."""
    params = default_params()
    follower = TagFollower(FollowCard("ana", 7), GyroOdometry(params=params), params)
    follower.pose = Pose2D(0.0, 0.0, math.pi / 2)  # facing north
    camera = follower._camera()
    follower.track = np.array([camera.x - 0.5, camera.y + 2.0])  # last seen left of it
    follower.velocity = np.array([0.7, 0.0])
    follower._updated = 10.0
    assert follower._side_of_her(10.0) == 1.0  # where she was: left
    assert follower._side_of_her(17.5) == -1.0  # where she has walked on to: right


def _follower_at_origin() -> TagFollower:
    params = default_params()
    follower = TagFollower(FollowCard("ana", 7), GyroOdometry(params=params), params)
    follower.pose = Pose2D(0.0, 0.0, 0.0)  # odom = base_link
    return follower


def test_someone_standing_by_the_chairs_front_is_given_way_and_she_is_not():
    """Someone standing 0.23 m beside the front half of the chair (coming out of a door
    the chair blocks) is in its way, so a blocked chair backs off ``give_way`` m, not
    ``back_off_distance``; someone 1.3 m ahead, someone behind, and she herself (her
    track's disc) are not."""
    follower = _follower_at_origin()
    standing: list[tuple[float, float]] = []
    follower._walked = lambda: np.array([[x, y, 0.0, 0.0, 0.25] for x, y in standing]
                                        ).reshape(-1, 5)
    standing[:] = [(0.35, -0.72)]  # outline to y = -0.24: 0.72 - 0.24 - 0.25 = 0.23 m
    assert follower._someone_in_the_way()
    standing[:] = [(2.0, 0.0)]  # front at x = 0.45: 2.0 - 0.45 - 0.25 = 1.3 m ahead
    assert not follower._someone_in_the_way()
    standing[:] = [(-0.8, 0.0)]  # behind the axle
    assert not follower._someone_in_the_way()
    follower.track = np.array([0.9, 0.0])  # her, standing right in front
    standing[:] = [(0.9, 0.0)]
    assert not follower._someone_in_the_way()
    standing[:] = [(0.9, 0.0), (0.35, -0.72)]
    assert follower._someone_in_the_way()


def test_a_coasting_track_is_not_taken_up_by_a_pillar():
    """A compact blob that never walks (a pillar, a door's frame) near her track: while
    the track is fresh (updated 0.1 s ago) the lidar may update it from the blob, but
    once it has coasted (1 s without a sighting) only a blob that walks can be her, so
    the track is not led off along the walls."""
    world = world_from_dict({
        "name": "pillar", "walls": [[[3.0, -0.15], [3.3, -0.15], [3.3, 0.15], [3.0, 0.15],
                                     [3.0, -0.15]]],
        "places": {"start": [0.0, 0.0, 0.0]}, "people": []})
    chair = SimBase(world, lidar=True)
    follower = _follower_at_origin()
    sensor = compose(follower.pose, Pose2D(*chair.params.lidar.mount))
    for _ in range(round(1.0 / chair.period)):  # a second of scans: a track, standing
        frame = chair.step()
        scan = frame.readings[LIDAR_FRAME]
        follower.others.update(scan, sensor, frame.t)
    pillar = follower.others.detect(scan, sensor)
    assert len(pillar) == 1 and 2.9 < pillar[0, 0] < 3.5
    assert not follower._walked_mask().any()
    follower.track, follower.velocity = pillar[0] + (0.0, 0.2), np.zeros(2)
    follower._tag_read = follower._t = frame.t
    follower._updated = frame.t - 0.1
    taken = follower._lidar_centre(scan, None, frame.t)
    assert taken is not None and np.allclose(taken, pillar[0])
    follower._updated = frame.t - 1.0
    assert follower._lidar_centre(scan, None, frame.t) is None


def test_a_door_on_her_trail_is_found_as_far_ahead_as_she_is():
    """Her trail runs 2 m east, then north through a 0.9 m door in a wall at y = 1.2: the
    door is 3.2 m along the trail from the chair, farther than the chair needs to slow
    from 1 m/s, and is found there, middle and axis, so the chair slows in time."""
    follower = _follower_at_origin()
    wall = [(x, 1.2) for x in np.arange(0.5, 1.56, 0.05)] + [
        (x, 1.2) for x in np.arange(2.45, 3.51, 0.05)]
    follower._scan_points = np.array(wall)
    trail = np.vstack([np.column_stack([np.arange(0.0, 2.0, 0.1), np.zeros(20)]),
                       np.column_stack([np.full(26, 2.0), np.arange(0.0, 2.6, 0.1)])])
    follower.track = trail[-1]
    door = follower._door_ahead(np.zeros(2), trail)
    assert door is not None
    middle, axis = door
    assert np.allclose(middle, (2.0, 1.2), atol=0.03)
    assert np.allclose(axis, (0.0, 1.0), atol=0.02)


def test_the_door_speed_cap_leaves_room_for_the_chairs_reaction_time():
    """Sent at the cap ``d`` m before the door's approach, the chair drives on at that
    speed for its reaction time, then slows at ``braking``: it is at ``door_speed``
    exactly at the approach (worked on the kinematics, not the formula), and never
    faster than the cap without the reaction time would allow."""
    follower = _follower_at_origin()
    s, lag = follower.settings, follower.stopping.reaction_time
    assert lag > 0.2
    assert follower.door_speed_cap(s.door_approach) == pytest.approx(s.door_speed)
    assert follower.door_speed_cap(0.1) == pytest.approx(s.door_speed)
    for room in (0.2, 0.5, 1.0, 2.0):
        v = follower.door_speed_cap(s.door_approach + room)
        coasting = v * lag  # m driven before the wheels slow
        at_approach = math.sqrt(max(v * v - 2 * s.braking * (room - coasting), 0.0))
        assert at_approach == pytest.approx(s.door_speed, abs=1e-9)
        assert v < math.sqrt(s.door_speed ** 2 + 2 * s.braking * room)


def test_with_a_door_on_her_trail_the_chair_keeps_to_the_trail_in_plain_view():
    """Ana has walked 2 m east and turned north towards a 0.9 m door 0.2 m ahead of her.
    The straight way to her is clear (it passes the door frame's end 0.43 m off), but
    aimed at her the chair would come to the door aslant: with the door on her trail it
    steers along the trail, for a point of its first leg, not at her."""
    follower = _follower_at_origin()
    wall = [(x, 1.2) for x in np.arange(0.5, 1.56, 0.05)] + [
        (x, 1.2) for x in np.arange(2.45, 3.51, 0.05)]
    follower._scan_points = np.array(wall)
    for x in np.arange(0.0, 2.0, 0.1):
        follower.trail.add((x, 0.0))
    for y in np.arange(0.0, 1.01, 0.1):
        follower.trail.add((2.0, y))
    target = np.array([2.0, 1.0])
    follower.track = target
    assert follower._clear_ways(np.zeros(2), target[None])[0]  # in plain view
    carrot, _ = follower._carrot(target)
    assert follower.door is not None
    assert carrot is not target
    assert abs(carrot[1]) < 0.05 and 0.3 < carrot[0] < 2.05  # on her trail's first leg


def test_blocked_for_seconds_on_the_spot_the_follower_hands_over_to_the_navigator():
    """Blocked decisions count towards ``hand_over_after`` only while the chair has not
    moved ``progress`` m: 2.9 s blocked is not yet enough, 3 s is; moving 0.3 m starts
    the count again."""
    follower = _follower_at_origin()
    follower.track = np.array([3.0, 0.0])
    follower.state = "blocked"
    t = 0.0
    for _ in range(29):
        t += 0.1
        assert not follower._stuck(t)
    assert follower._stuck(t + 0.1)
    follower.pose = Pose2D(0.3, 0.0, 0.0)
    assert not follower._stuck(t + 0.2)


def test_the_hand_over_drives_round_through_the_only_door_on_the_map_of_its_scans():
    """The hand-over's map holds only what the chair's scans saw from its start. Sent to
    a point behind the wall, 4.5 m ahead, the navigator on that map plans through the
    door at the wall's far end (the cells behind the wall are unknown, free to plan) and
    gets there, touching nothing."""
    demo = hand_over_demo(goal=(6.0, 1.5))
    assert demo.status == "succeeded"
    assert demo.collisions == 0
    assert math.hypot(demo.track[-1, 0] - 6.0, demo.track[-1, 1] - 1.5) < 0.3
    assert demo.plan[:, 1].max() > 4.5 and demo.track[:, 1].max() > 4.3  # the only door
    assert demo.grid.known().sum() > 1000  # the one scan


def test_the_hand_over_refuses_goals_it_cannot_stand_on():
    """Goals inside a wall, or off the map, are passed over for the next one; with none
    left nothing is handed over, and the reason says so."""
    chair = SimBase(two_rooms_world(), lidar=True)
    hand_over = HandOver(chair.params)
    assert hand_over.start(0.0, chair.pose, np.array([[6.0, 1.5]])) == "no map yet"
    frame = chair.step()
    sensor = compose(chair.pose, Pose2D(*chair.params.lidar.mount))
    hand_over.lay(frame.readings[LIDAR_FRAME], sensor)
    assert hand_over.start(0.0, chair.pose, np.array([[4.0, 2.0], [90.0, 2.0]])) == (
        "no goal the chair can stand on")
    assert not hand_over.active
    assert hand_over.start(0.0, chair.pose, np.array([[4.0, 2.0], [2.5, 3.0]])) is None
    assert hand_over.goal == (2.5, 3.0)
    hand_over.end(4.0, "reached")  # taking over again notes how it ended
    assert not hand_over.active and hand_over.goal is None
    assert hand_over.outcomes == [(0.0, 4.0, "reached")]
    with pytest.raises(ValueError, match="reach"):
        HandOver(chair.params, reach=math.inf)
