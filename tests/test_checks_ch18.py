"""The exercise checks of chapter 18 (the capstone): each passes an answer written
independently of the library, and says "not yet" (never raises) for the plausible wrong
answers, the unwritten stub and abcwc's own function handed in, wrapped or called."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from abcwc.behaviours import MissionState, Situation, Status, next_state
from abcwc.behaviours import mission as mission_module
from abcwc.checks import ch18
from abcwc.checks.report import NotYet, expect_own
from abcwc.experiments.selection import scanning_trials
from tests.check_helpers import assert_not_yet, assert_pass, not_written

S = MissionState
ON_AN_ERRAND = {S.NAVIGATING, S.LOCALISING, S.WAITING}


def student_rule(state: MissionState, s: Situation, *, resume=False, no_joystick=False,
                 stuck_localising=False, wait_fails=False, idle_on_release=False):
    """A table of what wins, top down, as a student writes it from the text; the
    keywords make the slips."""
    if s.joystick and not no_joystick:
        return None if state == S.MANUAL_OVERRIDE else (S.MANUAL_OVERRIDE, "the rider drives")
    if s.command == "stop":
        return S.IDLE, s.asked
    if s.command == "follow":
        return S.FOLLOWING, f"{s.asked}: follow"
    if s.command == "go to":
        ok = s.status != Status.FAILED
        return (S.NAVIGATING, f"{s.asked}: off to {s.goal}") if ok else (S.FAILED, str(s.failure))
    if state == S.MANUAL_OVERRIDE:
        if resume:
            return S.NAVIGATING, "released: back to the errand"
        if idle_on_release:
            return S.IDLE, "released"
        return None
    if state == S.FOLLOWING:
        return None if s.status == Status.RUNNING else (S.FAILED, "the follower stopped")
    if state not in ON_AN_ERRAND:
        return None
    if s.status == Status.SUCCEEDED:
        return S.ARRIVED, "there"
    if s.status == Status.FAILED:
        return S.FAILED, str(s.failure)
    wanted = state
    if s.lost:
        wanted = S.LOCALISING
    elif state == S.LOCALISING:
        wanted = S.LOCALISING if stuck_localising else S.NAVIGATING
    elif s.waiting:
        if wait_fails:
            return S.FAILED, "blocked"
        wanted = S.NAVIGATING if (state == S.WAITING and s.blocked) else S.WAITING
    elif state == S.WAITING:
        wanted = S.NAVIGATING
    return None if wanted == state else (wanted, f"{state.value} -> {wanted.value}")


def test_rule_check_passes_an_independent_rule(capsys):
    assert_pass(ch18.rule_check(student_rule), capsys)


def ignores_the_joystick(state, s):
    return student_rule(state, s, no_joystick=True)


def test_a_rule_that_ignores_the_joystick_is_refused(capsys):
    assert_not_yet(ch18.rule_check(ignores_the_joystick), capsys,
                   "joystick moved", "navigating")


@pytest.mark.parametrize(("slip", "fragments"), [
    ({"resume": True}, ("drove", "by itself", "until a new command")),
    ({"idle_on_release": True}, ("the chair stood", "idle", "stays in manual override")),
    ({"stuck_localising": True}, ("stayed localising",)),
    ({"wait_fails": True}, ("did not arrive", "failed", "a wait is not a failure")),
])
def test_rule_check_refuses_the_plausible_wrong_rules(slip, fragments, capsys):
    assert_not_yet(ch18.rule_check(functools.partial(student_rule, **slip)), capsys,
                   *fragments)


def test_a_rule_that_never_says_localising_is_refused(capsys):
    def never_lost(state, s):
        return student_rule(state, Situation(**{**vars(s), "lost": False}))

    assert_not_yet(ch18.rule_check(never_lost), capsys, "never said localising")


def test_a_rule_that_stays_navigating_when_the_way_is_shut_is_refused(capsys):
    def hopeful(state, s):
        if state in ON_AN_ERRAND and s.status == Status.FAILED:
            return None
        return student_rule(state, s)

    assert_not_yet(ch18.rule_check(hopeful), capsys, "no way round", "has failed")


def test_a_rule_that_raises_names_its_line(capsys):
    def broken(state, s):
        if s.command == "go to":
            return S.NAVIGATING, s.asked + 1
        return None

    assert_not_yet(ch18.rule_check(broken), capsys, "broken raised TypeError",
                   "return S.NAVIGATING, s.asked + 1")


@pytest.mark.parametrize(("own", "fragment"), [
    (not_written, "not written yet"),
    (next_state, "abcwc's own"),
    (lambda state, situation: next_state(state, situation), "abcwc's own next_state"),
    (lambda state, situation: ch18.next_state(state, situation), "abcwc's own"),
    (functools.partial(next_state), "abcwc's own"),
    (lambda state, situation: mission_module.next_state(state, situation), "abcwc's own"),
])
def test_rule_check_refuses_the_stub_and_abcwcs_own_rule(own, fragment, capsys):
    assert_not_yet(ch18.rule_check(own), capsys, fragment)


def test_a_helper_that_calls_abcwcs_rule_is_found():
    def helper(state, situation):
        return next_state(state, situation)

    def mine(state, situation):
        return helper(state, situation)

    with pytest.raises(NotYet, match="abcwc's own next_state"):
        expect_own(mine, next_state)
    expect_own(student_rule, next_state)  # the student's own rule is theirs


# --- exercise 2 -----------------------------------------------------------------------


@pytest.fixture(scope="module")
def lift_run():
    return ch18.run_lift_route()


def test_the_lift_route_fires_twice_by_the_true_track(lift_run):
    """Worked by hand: the first leg comes within 3 m (1); (21.3, 9.4) is 3.36 m from
    the lift (24.25, 11.0), not beyond 4 m, so the way back does not fire; (19, 9) is
    5.62 m away, so the last leg fires again (2)."""
    log, mission = lift_run
    lift = mission.destinations["lift"]
    assert (lift.x, lift.y) == (24.25, 11.0)
    assert math.hypot(21.3 - lift.x, 9.4 - lift.y) == pytest.approx(3.36, abs=0.01)
    assert math.hypot(19.0 - lift.x, 9.0 - lift.y) == pytest.approx(5.62, abs=0.01)
    assert len(mission.events_fired) == 2
    assert mission.state is S.ARRIVED


def test_lift_requests_check(lift_run, capsys):
    log, mission = lift_run
    lift = mission.destinations["lift"]
    assert_pass(ch18.lift_requests_check(lambda: 2, log, lift), capsys)
    assert_not_yet(ch18.lift_requests_check(lambda: 3, log, lift), capsys, "one a visit")
    assert_not_yet(ch18.lift_requests_check(lambda: 1, log, lift), capsys, "how far")
    assert_not_yet(ch18.lift_requests_check(lambda: 2.0, log, lift), capsys, "whole number")
    assert_not_yet(ch18.lift_requests_check(lambda: True, log, lift), capsys, "whole number")
    assert_not_yet(ch18.lift_requests_check(not_written, log, lift), capsys, "not written")
    ran = lambda: len(ch18.run_lift_route(seconds=1.0)[1].events_fired)  # noqa: E731
    assert_not_yet(ch18.lift_requests_check(ran, log, lift), capsys, "abcwc's own run_lift_route")
    # the measured count is checked too: part of the run, or a log whose events were
    # edited, is not the route's run
    half = log.select(slice(0, len(log) // 2))
    assert_not_yet(ch18.lift_requests_check(lambda: 1, half, lift), capsys, "whole run")
    edited = log.select(slice(None))
    edited.mission_event = np.full(len(log), "", dtype=log.mission_event.dtype)
    assert_not_yet(ch18.lift_requests_check(lambda: 0, edited, lift), capsys,
                   "true track comes near it 2 time(s)")


# --- exercise 3 -----------------------------------------------------------------------


def test_the_scan_choice_is_the_reaction_times_95th_percentile():
    """0.6 exp(1.645 x 0.3) = 0.983 s; 4 x 0.983 + 0.6 exp(0.045) = 4.56 s; and the
    seeded trials agree."""
    interval, seconds = ch18.true_scan_choice()
    assert interval == pytest.approx(0.983, abs=0.001)
    assert seconds == pytest.approx(4.56, abs=0.01)
    trials = scanning_trials(interval, trials=20000, seed=5)
    assert trials.false_rate == pytest.approx(0.05, abs=0.005)
    assert trials.mean_time == pytest.approx(seconds, abs=0.03)


def test_scan_choice_check(capsys):
    assert_pass(ch18.scan_choice_check(lambda: (1.0, 4.63)), capsys)
    assert_not_yet(ch18.scan_choice_check(lambda: (0.6, 3.0)), capsys, "median reaction")
    assert_not_yet(ch18.scan_choice_check(lambda: (1.3, 5.8)), capsys, "safer than asked")
    assert_not_yet(ch18.scan_choice_check(lambda: (1.0, 9.0)), capsys, "times the buttons")
    assert_not_yet(ch18.scan_choice_check(lambda: (1000, 4630)), capsys, "milliseconds")
    assert_not_yet(ch18.scan_choice_check(lambda: 1.0), capsys, "two numbers")
    assert_not_yet(ch18.scan_choice_check(not_written), capsys, "not written")
    assert_not_yet(ch18.scan_choice_check(ch18.true_scan_choice), capsys, "abcwc's own")
    assert_not_yet(ch18.scan_choice_check(lambda: ch18.true_scan_choice()), capsys,
                   "abcwc's own true_scan_choice")
    assert_not_yet(ch18.scan_choice_check(functools.partial(ch18.true_scan_choice, 9)),
                   capsys, "abcwc's own")


def test_the_scan_checks_messages_do_not_give_the_answer_away(capsys):
    """A wrong reading is told how it is wrong, never the 0.98 s or the 4.56 s."""
    for wrong in ((0.6, 3.0), (1.3, 5.8), (1.0, 9.0), (0.85, 4.0), (1.0, 3.0)):
        result = ch18.scan_choice_check(lambda wrong=wrong: wrong)
        out = capsys.readouterr().out
        assert not result.passed
        assert "0.98" not in out and "4.56" not in out and "4.6" not in out, out
