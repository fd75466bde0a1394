"""The mission layer against the simulator's ground truth: commands typed, spoken,
pressed and clicked take the chair to its place; every transition is logged with its
reason; the lift is called once per approach; the joystick always wins (in the simulator
and through the firmware in the loop); a lost chair finds its place again or fails with
the reason; a blocked corridor is driven round or ends the errand with the navigator's
reason; bad input is refused with what is allowed."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from abcwc.behaviours import (
    Mission,
    MissionEvent,
    MissionState,
    PlaceEvent,
    mission_timeline,
)
from abcwc.control import joystick_adc_to_pot_byte
from abcwc.geometry import wrap_angle
from abcwc.log import LogRecorder, RunLog
from abcwc.sim import SimBase
from abcwc.sim.world import World, world_from_dict
from abcwc.types import Pose2D, StatusFlags, Twist

ENDED = (MissionState.ARRIVED, MissionState.FAILED)


def _run(chair, mission: Mission, seconds: float, until=ENDED) -> float:
    """Drive ``mission`` until its state is one of ``until`` (or ``seconds``); the
    largest localisation error on the way (m, the estimate against the truth)."""
    frame, worst = chair.read(), 0.0
    for _ in range(round(seconds / chair.period)):
        chair.send(mission(frame), mission.decided_at)
        frame = chair.step()
        estimate, truth = mission.navigator.localizer.pose, chair.pose
        if mission.state is not MissionState.LOCALISING:
            worst = max(worst, math.hypot(truth.x - estimate.x, truth.y - estimate.y))
        if mission.state in until:
            break
    return worst


def _assert_arrived(chair, mission: Mission, place: Pose2D | tuple) -> None:
    assert mission.state is MissionState.ARRIVED, mission.reason
    truth = chair.pose
    gx, gy = (place.x, place.y) if isinstance(place, Pose2D) else place
    tolerance = mission.navigator.settings.xy_goal_tolerance
    assert math.hypot(truth.x - gx, truth.y - gy) <= tolerance
    assert chair.read().truth.collisions == 0


# ------------------------------------------------------------------ inputs


def test_a_typed_command_arrives_and_every_transition_is_in_the_log(tmp_path):
    chair = SimBase("floor", seed=3, lidar=True, people=False)
    mission = Mission.for_world(chair.world)
    assert mission.command("Go to the office A.").place == "office_a"
    log = chair.run(mission, 25)
    _assert_arrived(chair, mission, chair.world.places["office_a"])
    states = [(tr.before, tr.after) for tr in mission.transitions]
    assert states == [(MissionState.IDLE, MissionState.NAVIGATING),
                      (MissionState.NAVIGATING, MissionState.ARRIVED)]
    assert mission.transitions[0].reason == 'typed "go to the office a": going to the office a'

    saved = RunLog.load(log.save(tmp_path / "errand.npz"))
    for each in (log, saved):
        logged = [reason for reason in each.mission if reason]
        assert logged == [tr.reason for tr in mission.transitions]
        assert each.mission_state[-1] == "arrived"
    # the state channel agrees with the transitions: each row has the state after the
    # transitions made while deciding its command (the row is stamped a period later)
    arrived_at = mission.transitions[1].t
    rows = np.flatnonzero(log.mission_state == "arrived")
    assert log.t[rows[0]] == pytest.approx(arrived_at + chair.period)
    assert set(log.mission_state[:rows[0]]) == {"navigating"}
    timeline = mission_timeline(saved)
    assert [state for _, _, state in timeline] == ["navigating", "arrived"]
    assert timeline[0][1] == timeline[1][0] == pytest.approx(arrived_at + chair.period)
    assert timeline[-1][1] == pytest.approx(log.t[-1] + chair.period)


def test_a_button_and_a_map_click_take_the_chair_there():
    chair = SimBase("lab", seed=4, lidar=True, people=False)
    mission = Mission.for_world(chair.world)
    mission.go_to("centre", reason="button")
    _run(chair, mission, 40)
    _assert_arrived(chair, mission, chair.world.places["centre"])
    click = (8.0, 6.0)
    mission.go_to(click, reason="map click")
    assert mission.goal == Pose2D(8.0, 6.0, 0.0)
    _run(chair, mission, 40)
    _assert_arrived(chair, mission, click)
    assert [tr.reason for tr in mission.transitions if tr.after is MissionState.NAVIGATING] \
        == ["button: going to the centre", "map click: going to (8.00, 6.00) m"]


def test_a_spoken_command_is_heard_and_takes_the_chair_there():
    from tests.test_speech import _need_speech_tools

    _need_speech_tools()
    from abcwc.experiments.speech_trials import utterance
    from abcwc.perception.speech.recognizer import CommandRecognizer
    from abcwc.perception.speech.synthesis import Voice

    chair = SimBase("lab", seed=5, lidar=True, people=False)
    mission = Mission.for_world(chair.world)
    heard = CommandRecognizer(mission.commands).recognise(
        utterance("go to the centre", Voice("slt", "flite")))
    assert heard.accepted, heard.reason
    mission.command(heard.command)
    _run(chair, mission, 40)
    _assert_arrived(chair, mission, chair.world.places["centre"])
    assert mission.transitions[0].reason == 'heard "go to the centre": going to the centre'


def test_stop_ends_the_errand_and_the_chair_stands():
    chair = SimBase("lab", seed=6, lidar=True, people=False)
    mission = Mission.for_world(chair.world)
    mission.go_to("centre")
    _run(chair, mission, 3)
    mission.command("stop")
    assert mission.state is MissionState.IDLE and mission.reason == 'typed "stop"'
    assert not mission.navigator.running
    _run(chair, mission, 3.0, until=())  # the comfort ramp brakes, the motors lag
    still = chair.pose
    _run(chair, mission, 3, until=())
    assert math.hypot(chair.pose.x - still.x, chair.pose.y - still.y) < 1e-3


def test_follow_me_hands_the_chair_to_the_follower_and_stop_ends_it():
    from abcwc.behaviours.follow import TagFollower
    from abcwc.estimation.gyro import GyroOdometry
    from abcwc.geometry import compose
    from tests.test_follow import standing_person_world

    chair = SimBase(standing_person_world(2.5), seed=12, lidar=True, camera="gray")
    follower = TagFollower(chair.walkers[0].spec.tag, GyroOdometry(params=chair.params),
                           chair.params)
    mission = Mission.for_world(chair.world, chair=chair, follower=follower)
    mission.command("follow me")
    assert mission.state is MissionState.FOLLOWING and mission.goal is None
    _run(chair, mission, 12.0)
    assert mission.state is MissionState.FOLLOWING, mission.reason
    tag = chair.walkers[0].tag_target()
    camera = compose(chair.pose, chair.params.depth_scan.mount)[:2]
    assert math.hypot(tag.centre[0] - camera[0], tag.centre[1] - camera[1]) == pytest.approx(
        1.0, abs=0.1)  # the follower's distance: it drove
    mission.command("stop")
    assert mission.state is MissionState.IDLE and not follower.running
    assert [tr.reason for tr in mission.transitions] == [
        'typed "follow me": following the person ahead', 'typed "stop"']


# ------------------------------------------------------------------ events


def test_the_lift_is_requested_once_per_approach_within_three_metres():
    """Up the corridor to the lift, away 6 m and back: two approaches, two requests,
    each to both subscribers, each with the chair truly within 3 m (plus the estimate's
    error) of the lift when it fired."""
    start = Pose2D(19.0, 9.0, 0.0)
    chair = SimBase("floor", seed=7, lidar=True, people=False, start=start)
    mission = Mission.for_world(chair.world, start=start)
    lift = chair.world.places["lift"]
    received: list[list[tuple[MissionEvent, float, float]]] = [[], []]

    def listener(k: int):
        def heard(event: MissionEvent) -> None:
            truth, estimate = chair.pose, mission.navigator.localizer.pose
            received[k].append((event, math.hypot(truth.x - lift.x, truth.y - lift.y),
                                math.hypot(truth.x - estimate.x, truth.y - estimate.y)))
        return heard

    mission.subscribe(listener(0))
    mission.subscribe(listener(1))
    worst = 0.0
    for goal in ("lift", (19.0, 9.0), "lift"):
        mission.go_to(goal)
        worst = max(worst, _run(chair, mission, 40))
        assert mission.state is MissionState.ARRIVED, mission.reason
    assert received[0] == received[1] and len(received[0]) == 2
    for event, true_distance, error in received[0]:
        assert (event.name, event.place) == ("lift requested", "lift")
        assert event.distance <= 3.0
        assert true_distance <= 3.0 + error
    assert mission.events_fired == [event for event, _, _ in received[0]]
    assert worst < 0.1
    assert chair.collisions == 0


# ------------------------------------------------------------------ the joystick wins


def _override_and_resume(chair, mission: Mission, place: str) -> None:
    """Mid-errand the joystick pulls back for 1 s: the mission stops its command in the
    period the frame says so and the pots follow the joystick; released, the chair
    stands still for 10 s in manual override; a new command completes the errand."""
    mission.go_to(place)
    _run(chair, mission, 3, until=())
    assert mission.state is MissionState.NAVIGATING
    pulled = chair.params.joystick_centre - 60
    chair.set_joystick(fb=pulled)
    frame, reversed_from = chair.step(), chair.pose
    assert frame.flags & StatusFlags.JOYSTICK_OVERRIDE
    assert frame.pot_fb == joystick_adc_to_pot_byte(pulled)  # the pots follow at once
    command = mission(frame)
    assert command == Twist(0.0, 0.0)  # in the first period whose frame says so
    assert mission.state is MissionState.MANUAL_OVERRIDE
    assert not mission.navigator.running
    for _ in range(round(1.0 / chair.period)):
        chair.send(command, mission.decided_at)
        frame = chair.step()
        assert frame.pot_fb == joystick_adc_to_pot_byte(pulled)  # the joystick drives
        command = mission(frame)
        assert command == Twist(0.0, 0.0)
    chair.send(command, mission.decided_at)
    before = chair.pose
    chair.step()
    released, p = chair.pose, chair.params
    speed = math.hypot(released.x - before.x, released.y - before.y) / chair.period
    moved_back = math.hypot(released.x - reversed_from.x, released.y - reversed_from.y)
    assert moved_back > 0.1
    chair.release_joystick()
    _run(chair, mission, 2.0, until=())  # the chair rolls to a stop
    still = chair.pose
    # no further than the lag lets it roll: the stop goes out within two periods, the
    # motor controller's input delay, then a first-order lag stops from v in v tau
    coast = speed * (2 * chair.period + p.command_delay + p.motor_time_constant)
    assert math.hypot(still.x - released.x, still.y - released.y) < coast + 0.01
    _run(chair, mission, 10.0, until=())
    assert math.hypot(chair.pose.x - still.x, chair.pose.y - still.y) < 1e-3
    assert abs(chair.pose.theta - still.theta) < 1e-3
    assert mission.state is MissionState.MANUAL_OVERRIDE
    mission.command(f"go to the {place}")
    _run(chair, mission, 40)
    _assert_arrived(chair, mission, chair.world.places[place])
    after = [tr.after for tr in mission.transitions]
    assert after == [MissionState.NAVIGATING, MissionState.MANUAL_OVERRIDE,
                     MissionState.NAVIGATING, MissionState.ARRIVED]


def test_the_joystick_wins_in_the_simulator():
    chair = SimBase("lab", seed=8, lidar=True, people=False)
    _override_and_resume(chair, Mission.for_world(chair.world), "centre")


def test_the_joystick_wins_through_the_firmware_in_the_loop(harness_files):
    """The same errand, with the firmware on a simulated Arduino between the host and
    the chair: its override flag, its pots."""
    from abcwc.hw.fil_base import FirmwareInLoopBase

    chair = FirmwareInLoopBase("lab", seed=8, lidar=True, people=False, build=False)
    try:
        _override_and_resume(chair, Mission.for_world(chair.world), "centre")
    finally:
        chair.close()


# ------------------------------------------------------------------ lost localisation


def _kidnap(chair: SimBase, dx: float, dy: float, dtheta: float) -> None:
    """Move the simulated chair as a carer lifting it would: its wheels turn no tick."""
    chair.carry(dx, dy, dtheta)


def test_a_lost_chair_stops_finds_its_place_and_completes_the_errand():
    chair = SimBase("floor", seed=9, lidar=True, people=False)
    mission = Mission.for_world(chair.world)
    goal = (16.0, 9.0)
    mission.go_to(goal)
    _run(chair, mission, 4, until=())
    _kidnap(chair, 1.0, 0.0, 0.5)
    _run(chair, mission, 60)
    _assert_arrived(chair, mission, goal)
    after = [tr.after for tr in mission.transitions]
    assert after[:3] == [MissionState.NAVIGATING, MissionState.LOCALISING,
                         MissionState.NAVIGATING]
    assert after.count(MissionState.LOCALISING) == 1 and after[-1] is MissionState.ARRIVED
    assert mission.transitions[1].reason.startswith("lost")
    assert mission.transitions[2].reason.startswith("found the chair's place")
    truth, estimate = chair.pose, mission.navigator.localizer.pose
    assert math.hypot(truth.x - estimate.x, truth.y - estimate.y) < 0.1


def test_a_chair_that_cannot_find_its_place_fails_with_the_reason():
    """Carried 5 m away into another room: it stops, turns on the spot between
    searches, and, the place beyond the search's reach, fails saying so; nothing is
    raised."""
    chair = SimBase("floor", seed=10, lidar=True, people=False)
    mission = Mission.for_world(chair.world)
    mission.go_to((16.0, 9.0))
    _run(chair, mission, 4, until=())
    _kidnap(chair, 3.0, 4.0, 1.0)
    frame, phases, stopped = chair.read(), set(), None
    for _ in range(round(40 / chair.period)):
        chair.send(mission(frame), mission.decided_at)
        frame = chair.step()
        phase = mission.navigator.feedback.phase
        phases.add(phase)
        if stopped is None and phase == "turning to re-localise":
            stopped = chair.pose  # where it stood when it first turned
        if mission.state in ENDED:
            break
    assert mission.state is MissionState.FAILED
    assert mission.reason.startswith("lost:") and "turning on the spot" in mission.reason
    assert MissionState.LOCALISING in [tr.after for tr in mission.transitions]
    assert {"relocalising", "turning to re-localise"} <= phases
    truth = chair.pose  # it stopped, then turned on the spot
    assert math.hypot(truth.x - stopped.x, truth.y - stopped.y) < 0.05
    assert abs(wrap_angle(truth.theta - stopped.theta)) > 0.5
    assert chair.collisions == 0


# ------------------------------------------------------------------ a blocked corridor


def _blocked_worlds(loop: bool, tmp_path: Path) -> tuple[World, Path]:
    """A corridor 12 m long and 2 m wide, from ``start`` to ``end``, blocked half-way by
    something the map does not have; with ``loop``, a second corridor joins its ends
    round a block 8 x 3 m. (The map the chair has, the world as it is.)"""
    height = 7.0 if loop else 2.0
    walls = [[[0, 0], [12, 0], [12, height], [0, height], [0, 0]]]
    if loop:
        walls.append([[2, 2], [10, 2], [10, 5], [2, 5], [2, 2]])
    places = {"start": [1.0, 1.0, 0.0], "end": [11.0, 1.0, 0.0]}
    known = {"name": "known", "walls": walls, "places": places}
    actual = {"name": "blocked", "walls": walls + [[[6, 0], [6, 2]]], "places": places}
    path = tmp_path / "blocked.json"
    path.write_text(json.dumps(actual))
    return world_from_dict(known), path


def test_a_corridor_blocked_with_no_other_way_ends_with_the_navigators_reason(tmp_path):
    known, actual = _blocked_worlds(False, tmp_path)
    chair = SimBase(str(actual), seed=11, lidar=True, people=False)
    mission = Mission.for_world(known)
    mission.go_to("end")
    _run(chair, mission, 60)
    assert mission.state is MissionState.FAILED
    assert mission.reason.startswith("no path to the goal")
    assert mission.transitions[-1].reason == mission.navigator.failure
    assert chair.pose.x < 6.0 and chair.collisions == 0


def test_a_corridor_blocked_with_another_way_is_driven_round(tmp_path):
    known, actual = _blocked_worlds(True, tmp_path)
    chair = SimBase(str(actual), seed=11, lidar=True, people=False)
    mission = Mission.for_world(known)
    mission.go_to("end")
    _run(chair, mission, 100)
    _assert_arrived(chair, mission, known.places["end"])
    assert any(tr.reason.startswith("the way is blocked") for tr in mission.transitions)


# ------------------------------------------------------------------ bad input


def test_bad_input_is_refused_with_what_is_allowed():
    chair = SimBase("lab", seed=0, people=False)
    mission = Mission.for_world(chair.world)
    with pytest.raises(ValueError, match=r"unknown place 'kitchen'.*centre, door"):
        mission.go_to("kitchen")
    for bad in ((math.nan, 1.0), (1.0, math.inf), "", (1.0,), None, (1.0, "x")):
        with pytest.raises(ValueError, match=r"finite \(x, y\) in metres"):
            mission.go_to(bad)
    with pytest.raises(ValueError, match=r'"fly to the moon" is not a command; say one of: '
                                         r'.*"go to the centre"'):
        mission.command("fly to the moon")
    with pytest.raises(ValueError, match=r'"drive forward" is a motion.*\'go to the door\''):
        mission.command("drive forward")
    with pytest.raises(ValueError, match="needs a follower"):
        mission.command("follow me")
    with pytest.raises(ValueError, match="not a place"):
        Mission(mission.navigator, events=[PlaceEvent("coffee ready", "cafeteria")])
    with pytest.raises(ValueError, match="radius"):
        PlaceEvent("lift requested", "lift", radius=-1.0)
    assert mission.state is MissionState.IDLE and mission.transitions == []
    assert mission.events == ()  # the lab has no lift


def test_an_impossible_destination_fails_at_once_with_the_reason():
    chair = SimBase("lab", seed=0, lidar=True, people=False)
    mission = Mission.for_world(chair.world)
    mission.go_to((100.0, 100.0), reason="map click")
    assert mission.state is MissionState.FAILED
    assert mission.reason == ("map click: cannot go to (100.00, 100.00) m: the goal "
                              "(100.00, 100.00) m is off the map")


# ------------------------------------------------------------------ the log's text channels


class _Counter:
    """A controller with the log hook: stands still and says how many periods it ran."""

    def __init__(self) -> None:
        self.calls = 0

    def __call__(self, frame) -> Twist:
        self.calls += 1
        return Twist(0.0, 0.0)

    def log_fields(self) -> dict[str, str]:
        return {"count": str(self.calls), "odd": "yes" if self.calls % 2 else ""}


def test_the_control_loop_records_a_controllers_text_fields(tmp_path):
    chair = SimBase("lab", seed=0, people=False)
    log = chair.run(_Counter(), 0.1)
    assert list(log.count) == ["1", "2", "3", "4", "5"]
    assert list(RunLog.load(log.save(tmp_path / "c.npz")).odd) == ["yes", "", "yes", "", "yes"]
    plain = chair.run(lambda frame: Twist(0.0, 0.0), 0.1)
    assert "count" not in plain.channels


def test_a_text_field_may_not_take_a_channels_name():
    chair = SimBase("lab", seed=0, people=False)
    with pytest.raises(ValueError, match="not one of the channels"):
        LogRecorder().add(chair.read(), None, None, text={"safety": "mine"})


def test_the_timeline_reads_the_state_channel():
    t = np.array([0.0, 0.02, 0.04, 0.06, 0.08])
    states = np.array(["idle", "navigating", "navigating", "manual override", "idle"])
    log = RunLog(t=t, mission_state=states, meta={"period": 0.02})
    assert mission_timeline(log) == [(0.0, 0.02, "idle"), (0.02, 0.06, "navigating"),
                                     (0.06, 0.08, "manual override"),
                                     (0.08, pytest.approx(0.1), "idle")]
    assert mission_timeline(RunLog(t=t[:0], mission_state=states[:0])) == []
    with pytest.raises(ValueError, match="no 'mission_state' channel"):
        mission_timeline(RunLog(t=t))


# ------------------------------------------------------------------ the rule


def test_the_rule_is_a_pure_function_of_the_state_and_the_situation():
    from abcwc.behaviours import Situation, Status, next_state

    st = MissionState
    running = Situation(status=Status.RUNNING, goal="the lift")
    held = Situation(joystick=True, command="go to", asked="button")
    assert next_state(st.NAVIGATING, held)[0] is st.MANUAL_OVERRIDE  # the hand first
    assert next_state(st.MANUAL_OVERRIDE, held) is None
    assert next_state(st.MANUAL_OVERRIDE, Situation()) is None  # released: it stays
    assert next_state(st.MANUAL_OVERRIDE, Situation(command="go to", asked="button",
                                                    goal="the lift", status=Status.RUNNING)) \
        == (st.NAVIGATING, "button: going to the lift")
    assert next_state(st.NAVIGATING, running) is None
    lost = Situation(status=Status.RUNNING, lost=True)
    assert next_state(st.NAVIGATING, lost)[0] is st.LOCALISING
    assert next_state(st.LOCALISING, lost) is None
    assert next_state(st.LOCALISING, running)[0] is st.NAVIGATING
    waiting = Situation(status=Status.RUNNING, waiting=True)
    assert next_state(st.NAVIGATING, waiting)[0] is st.WAITING
    assert next_state(st.WAITING, waiting) is None
    assert next_state(st.WAITING, Situation(status=Status.RUNNING, waiting=True,
                                            blocked=True))[1].startswith("the way is blocked")
    assert next_state(st.WAITING, running)[1].startswith("the way is clear")
    assert next_state(st.NAVIGATING, Situation(status=Status.FAILED, failure="stuck")) \
        == (st.FAILED, "stuck")
    assert next_state(st.IDLE, Situation(status=Status.RUNNING, lost=True)) is None
    with pytest.raises(ValueError, match="go to, follow, stop"):
        Situation(command="fly")


def test_a_different_rule_drives_the_same_mission():
    """A rule that takes the errand up again when the joystick is let go: the mission
    starts the navigator again to the same goal, and the chair drives there."""
    from abcwc.behaviours import next_state

    def resumes(state, situation):
        if state is MissionState.MANUAL_OVERRIDE and not situation.joystick:
            return MissionState.NAVIGATING, "released: going on"
        return next_state(state, situation)

    chair = SimBase("lab", seed=8, lidar=True, people=False)
    mission = Mission.for_world(chair.world, rules=resumes)
    mission.go_to("centre")
    _run(chair, mission, 2, until=())
    chair.set_joystick(fb=chair.params.joystick_centre - 60)
    _run(chair, mission, 0.5, until=())
    chair.release_joystick()
    _run(chair, mission, 40)
    _assert_arrived(chair, mission, chair.world.places["centre"])
    assert [tr.reason for tr in mission.transitions][1:3] == [
        "the joystick moved: the rider drives; the errand is paused until a new command",
        "released: going on"]


def test_a_rule_that_answers_something_else_is_refused_with_what_is_allowed():
    chair = SimBase("lab", seed=0, people=False)
    for answer in ("navigating", (MissionState.IDLE, ""), ("flying", "up"), 3):
        mission = Mission.for_world(chair.world,
                                    rules=lambda state, situation, answer=answer: answer)
        with pytest.raises(ValueError, match=r"returns None \(stay\) or \(state, reason\)"):
            mission.go_to("centre")
    with pytest.raises(ValueError, match="rules is a function"):
        Mission.for_world(chair.world, rules="next_state")


def test_a_mission_on_a_built_map_drives_by_the_filter_it_is_given():
    """The filter a mapping run hands back (here: one that believes the chair 0.3 m off
    its start) is the localiser's, so the mission starts from its belief; without one,
    from the start given."""
    from abcwc.estimation.ekf import ChairEkf
    from abcwc.mapping.grid import FREE, OCCUPIED, OccupancyGrid
    from abcwc.mapping.truth import rasterise_walls

    chair = SimBase("lab", seed=2, lidar=True, people=False)
    grid = OccupancyGrid.covering(-1.0, -1.0, 14.0, 9.0, 0.05)
    cells = np.where(rasterise_walls(chair.world.walls, grid), OCCUPIED, FREE).astype(np.int8)
    start = chair.world.places["start"]
    ekf = ChairEkf(Pose2D(start.x + 0.3, start.y, start.theta), chair.params)
    mission = Mission.for_map(cells, grid, start, places=chair.world.places, ekf=ekf)
    assert mission.navigator.localizer.ekf is ekf
    assert mission.navigator.localizer.pose.x == pytest.approx(start.x + 0.3)
    plain = Mission.for_map(cells, grid, start, places=chair.world.places)
    assert plain.navigator.localizer.pose.x == pytest.approx(start.x)


def test_a_command_before_the_first_frame_is_stamped_with_the_first_frames_time():
    chair = SimBase("lab", seed=0, lidar=True, people=False)
    chair.run(lambda frame: Twist(0.0, 0.0), 5.0)  # the chair's clock has run on
    mission = Mission.for_world(chair.world, chair=chair)
    mission.go_to("centre")
    assert math.isnan(mission.transitions[0].t)  # not seen a frame: no time yet
    log = chair.run(mission, 0.1)
    assert mission.transitions[0].t == pytest.approx(5.0) == log.t[0] - chair.period
