"""Checks for chapter 18, the capstone (thesis 1 and its figures 1-2, 5.1, 5.3.4).

Exercises:

* ``mission_rule(state, situation)``: a design: the mission's transitions, the new
  state and its reason or None (stay). The check drives it inside the real
  :class:`~abcwc.behaviours.mission.Mission`, on worlds the notebook never shows, through
  the joystick taking over mid-errand, a chair carried off its place, and a corridor
  blocked with and without another way; a rule that resumes by itself after the
  joystick is let go, ignores the joystick, never leaves localising or fails on the
  first wait does not pass;
* ``predicted_lift_requests()``: a number written down *before* the run that shows it:
  how many times "lift requested" fires on :data:`LIFT_ROUTE`;
* ``scan_choice()``: a measurement: the shortest scan interval at which at most one
  selection in 20 is false, and the mean time to select there, read off a sweep of
  :func:`abcwc.experiments.selection.scanning_trials`.

A check handed the library's own function (or one that calls it) says so instead of
passing.
"""

from __future__ import annotations

import math
import traceback
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from abcwc.behaviours.mission import (
    LIFT_REQUESTED,
    REARM_MARGIN,
    Mission,
    MissionState,
    next_state,
)
from abcwc.checks.report import NotYet, checker, expect, expect_own, format_value, numbers
from abcwc.experiments.selection import (
    REACTION_MEDIAN,
    REACTION_SPREAD,
    scan_false_rate,
)
from abcwc.log import LogRecorder, RunLog
from abcwc.sim import SimBase
from abcwc.sim.world import World, world_from_dict
from abcwc.types import Pose2D, Twist

__all__ = [
    "FALSE_SELECTIONS",
    "LIFT_ROUTE",
    "lift_requests_check",
    "rule_check",
    "rule_worlds",
    "run_lift_route",
    "scan_choice_check",
    "true_scan_choice",
]

ENDED = (MissionState.ARRIVED, MissionState.FAILED)
LIFT_ROUTE = ("lift", (21.3, 9.4), "lift", (19.0, 9.0), "lift")
"""The errands of exercise 2, one after the other, from (19, 9) on the floor world: to
the lift (24.25, 11.0), to a point 3.36 m from it, back, to a point 5.62 m from it, and
back."""
LIFT_START = Pose2D(19.0, 9.0, 0.0)
FALSE_SELECTIONS = 0.05
"""Exercise 3: at most one selection in 20 false."""


# --- the student's rule, guarded ------------------------------------------------------------


def _guarded(rule: Callable) -> Callable:
    """The student's rule, its exceptions turned into "not yet" with the line that
    raised (NotImplementedError passes: the exercise is not written)."""
    name = getattr(rule, "__name__", "your rule")

    def guarded(state, situation):
        try:
            return rule(state, situation)
        except (NotImplementedError, NotYet):
            raise
        except Exception as exc:  # noqa: BLE001 - student code may raise anything
            lines = [entry for entry in traceback.extract_tb(exc.__traceback__)
                     if entry.name == name] or traceback.extract_tb(exc.__traceback__)[-1:]
            where = lines[-1]
            raise NotYet(f"{name} raised {type(exc).__name__}: {exc} (line {where.lineno}: "
                         f"{(where.line or '').strip()}) in state {state.value!r} with "
                         f"{situation}") from None
    return guarded


# --- exercise 1: the mission's rule ------------------------------------------------------


def rule_worlds() -> dict[str, World]:
    """The worlds the check drives in, none of them in the notebook: a day room with a
    table, a ward with alcoves, and a corridor blocked half-way by a cupboard the map
    does not have: round a block (``known``, the map the chair has; ``blocked``, the
    world as it is), and with no way round (``corridor``; ``dead end``)."""
    day_room = {"name": "a day room",
                "walls": [[[0, 0], [11, 0], [11, 8], [0, 8], [0, 0]],
                          [[4.5, 3.2], [6.5, 3.2], [6.5, 4.6], [4.5, 4.6], [4.5, 3.2]]],
                "places": {"start": [1.5, 1.5, 0.0], "window": [9.5, 6.5, 1.5708]}}
    ward = {"name": "a ward",
            "walls": [[[0, 0], [15, 0], [15, 7], [0, 7], [0, 0]],
                      [[3, 7], [3, 5.5], [4, 5.5], [4, 7]],
                      [[8, 0], [8, 1.8], [9.5, 1.8], [9.5, 0]],
                      [[11.5, 7], [11.5, 4.8]],
                      [[5.5, 3.0], [6.3, 3.0], [6.3, 3.8], [5.5, 3.8], [5.5, 3.0]]],
            "places": {"start": [1.5, 2.0, 0.0], "bed": [13.5, 2.5, 0.0]}}
    walls = [[[0, 0], [14, 0], [14, 7.5], [0, 7.5], [0, 0]],
             [[2, 2], [12, 2], [12, 5.5], [2, 5.5], [2, 2]]]
    places = {"start": [1.0, 1.0, 0.0], "end": [13.0, 1.0, 0.0]}
    cupboard = [[7.0, 0.0], [7.0, 2.0]]
    corridor = [[[0, 0], [14, 0], [14, 2], [0, 2], [0, 0]]]
    return {"day room": world_from_dict(day_room), "ward": world_from_dict(ward),
            "known": world_from_dict({"name": "a corridor round a block", "walls": walls,
                                      "places": places}),
            "blocked": world_from_dict({"name": "a corridor with a cupboard in it",
                                        "walls": walls + [cupboard], "places": places}),
            "corridor": world_from_dict({"name": "a corridor", "walls": corridor,
                                         "places": places}),
            "dead end": world_from_dict({"name": "a corridor with no way round",
                                         "walls": corridor + [cupboard], "places": places})}


@dataclass
class _Drive:
    """A mission driven on a chair, period by period, with what the check watches."""

    chair: SimBase
    mission: Mission
    lost_for: float = 0.0  # s the localiser said lost
    found_at: float | None = None  # when it stopped saying so, after it had

    def run(self, seconds: float, until: tuple = ENDED) -> Twist:
        frame, command = self.chair.read(), Twist(0.0, 0.0)
        for _ in range(round(seconds / self.chair.period)):
            command = self.mission(frame)
            self.chair.send(command, self.mission.decided_at)
            frame = self.chair.step()
            lost = self.mission.navigator.localizer.lost
            self.lost_for += self.chair.period if lost else 0.0
            if not lost and self.lost_for and self.found_at is None:
                self.found_at = frame.t
            if self.mission.state in until:
                break
        return command

    def arrived(self, goal: Pose2D) -> bool:
        truth, mission = self.chair.pose, self.mission
        return (mission.state is MissionState.ARRIVED and self.chair.collisions == 0
                and math.hypot(truth.x - goal.x, truth.y - goal.y)
                <= mission.navigator.settings.xy_goal_tolerance)

    def ended(self) -> str:
        return f'{self.mission.state.value} ("{self.mission.reason}")'


def _drive(world: World, rule: Callable, seed: int, real: World | None = None) -> _Drive:
    chair = SimBase(real or world, seed=seed, lidar=True, people=False)
    return _Drive(chair, Mission.for_world(world, chair=chair, rules=rule))


def _override(rule: Callable, world: World) -> None:
    """Mid-errand the joystick pulls back for 1 s; released, the chair must stand in
    manual override for 8 s; a new command must complete the errand."""
    drive = _drive(world, rule, seed=81)
    goal = world.places["window"]
    drive.mission.go_to("window", reason="button")
    expect(drive.mission.state is MissionState.NAVIGATING,
           f"a \"go to\" command left the mission {drive.ended()}: a command to a place the "
           "navigator can reach starts the errand (navigating)")
    start = drive.chair.pose
    drive.run(3.0, until=())
    moved = math.hypot(drive.chair.pose.x - start.x, drive.chair.pose.y - start.y)
    expect(moved > 0.5 and drive.mission.state is MissionState.NAVIGATING,
           f"3 s after \"go to the window\" in {world.name} the chair had moved "
           f"{moved:.2f} m and the mission was {drive.ended()}: it should be navigating")
    chair = drive.chair
    chair.set_joystick(fb=chair.params.joystick_centre - 60)
    frame = chair.step()
    command = drive.mission(frame)
    expect(drive.mission.state is MissionState.MANUAL_OVERRIDE,
           f"in the first control period whose frame said the joystick moved, your rule "
           f"left the mission {drive.ended()}: the joystick wins at once (manual override)")
    expect(command == Twist(0.0, 0.0), "in manual override the mission must send stop")
    for _ in range(round(1.0 / chair.period)):
        chair.send(command, drive.mission.decided_at)
        frame = chair.step()
        command = drive.mission(frame)
        expect(drive.mission.state is MissionState.MANUAL_OVERRIDE,
               f"while the joystick was held your rule went to {drive.ended()}: the rider "
               "drives until the joystick is let go")
    chair.send(command, drive.mission.decided_at)
    chair.step()
    chair.release_joystick()
    drive.run(2.0, until=())  # it rolls to a stop
    still = chair.pose
    drive.run(8.0, until=())
    drifted = math.hypot(chair.pose.x - still.x, chair.pose.y - still.y)
    if drifted > 0.01 or drive.mission.state is not MissionState.MANUAL_OVERRIDE:
        how = (f"the chair drove {drifted:.2f} m by itself" if drifted > 0.01 else
               "the chair stood")
        raise NotYet(f"after the joystick was let go {how} and your rule went to "
                     f"{drive.ended()}: the mission stays in manual override, still, until "
                     "a new command (ISO 7176-14: it never resumes by itself)")
    drive.mission.command("go to the window")
    drive.run(40.0)
    expect(drive.arrived(goal), f"after the override, a new command \"go to the window\" "
                                f"did not complete the errand: the mission ended "
                                f"{drive.ended()}")


def _lost(rule: Callable, world: World) -> None:
    """A chair carried 1 m aside and turned mid-errand must say localising, find its
    place and go on to arrive."""
    drive = _drive(world, rule, seed=82)
    goal = world.places["bed"]
    drive.mission.go_to("bed", reason="button")
    drive.run(4.0, until=())
    drive.chair.carry(0.0, 1.0, 0.5)
    drive.run(60.0)
    states = [tr.after for tr in drive.mission.transitions]
    expect(drive.lost_for > 0, "the chair carried off its place was never lost: tell your "
                               "teacher (the check's scene is broken)")
    expect(MissionState.LOCALISING in states,
           f"the chair was carried off its place in {world.name}; the localiser said lost "
           f"for {drive.lost_for:.1f} s, but your rule never said localising (the mission "
           f"ended {drive.ended()})")
    if drive.mission.state is MissionState.LOCALISING:
        found = (f"the chair found its place at {drive.found_at:.1f} s"
                 if drive.found_at is not None else "the chair never found its place")
        raise NotYet(f"{found} but your rule stayed localising: once the localiser is no "
                     "longer lost, the errand goes on (navigating)")
    expect(drive.arrived(goal), f"after it was carried off its place in {world.name} the "
                                f"errand did not complete: the mission ended "
                                f"{drive.ended()}")


def _blocked(rule: Callable, worlds: dict[str, World]) -> None:
    """A cupboard in the corridor: round the block to the end; with no way round, the
    errand fails with the navigator's reason."""
    drive = _drive(worlds["known"], rule, seed=83, real=worlds["blocked"])
    drive.mission.go_to("end", reason="button")
    drive.run(100.0)
    states = [tr.after for tr in drive.mission.transitions]
    if not drive.arrived(worlds["known"].places["end"]):
        waited = (" after the navigator waited for the way to clear"
                  if MissionState.WAITING in states else "")
        hint = ("a wait is not a failure: wait, and navigate on when the scan shows the "
                "way blocked (the mission then plans round it) or the way clears"
                if drive.mission.state in (MissionState.FAILED, MissionState.WAITING) else
                "does your rule leave waiting?")
        raise NotYet(f"in a corridor with a cupboard in it and a way round the block the "
                     f"chair did not arrive: the mission ended {drive.ended()}{waited}: {hint}")
    drive = _drive(worlds["corridor"], rule, seed=84, real=worlds["dead end"])
    known_end = worlds["corridor"].places["end"]
    drive.mission.go_to("end", reason="button")
    drive.run(60.0)
    expect(drive.mission.state is MissionState.FAILED and drive.chair.pose.x < known_end.x,
           f"in a corridor with no way round the cupboard the navigator gave up "
           f"({drive.mission.navigator.failure!r}), but your rule left the mission "
           f"{drive.ended()}: when the errand's behaviour fails, the mission has failed")


@checker("design")
def rule_check(rule: Callable) -> str:
    """``rule(state, situation)`` drives a :class:`Mission` through the joystick, a lost
    chair and a blocked corridor on :func:`rule_worlds` (module notes)."""
    expect_own(rule, next_state)
    guarded = _guarded(rule)
    worlds = rule_worlds()
    _override(guarded, worlds["day room"])
    _lost(guarded, worlds["ward"])
    _blocked(guarded, worlds)
    return ("the joystick won at once and the chair stood until a new command; the lost "
            "chair found its place and arrived; the blocked corridor was driven round, "
            "and with no way round the errand failed with the navigator's reason")


# --- exercise 2: how often is the lift called? ---------------------------------------------


def _requests_along(track: np.ndarray, lift: Pose2D) -> int:
    """How many times an event of :data:`LIFT_REQUESTED`'s radius fires along ``track``
    ((n, 2) m): on coming within the radius, re-armed beyond it plus REARM_MARGIN."""
    radius = LIFT_REQUESTED.radius
    distance = np.hypot(track[:, 0] - lift.x, track[:, 1] - lift.y)
    armed, fired = bool(distance[0] > radius), 0
    for d in distance[1:]:
        if armed and d <= radius:
            armed, fired = False, fired + 1
        elif not armed and d > radius + REARM_MARGIN:
            armed = True
    return fired


def run_lift_route(seed: int = 18, seconds: float = 150.0) -> tuple[RunLog, Mission]:
    """The errands of :data:`LIFT_ROUTE` on the floor world without people, one after
    another from :data:`LIFT_START`, as one RunLog (with the mission's channels), and
    the mission; it stops when the last errand ends (or after ``seconds``)."""
    chair = SimBase("floor", seed=seed, lidar=True, people=False, start=LIFT_START)
    mission = Mission.for_world(chair.world, chair=chair, start=LIFT_START)
    legs = list(LIFT_ROUTE)
    mission.go_to(legs.pop(0), reason="button")
    recorder = LogRecorder(chair.log_meta())
    frame = chair.read()
    for _ in range(round(seconds / chair.period)):
        if mission.state in ENDED:
            if not legs or mission.state is MissionState.FAILED:
                break
            mission.go_to(legs.pop(0), reason="button")
        wanted = mission(frame)
        text = mission.log_fields()
        sent = chair.send(wanted, mission.decided_at)
        frame = chair.step()
        recorder.add(frame, sent, chair.last_command, wanted=wanted,
                     safety=chair.safety.reason if chair.safety is not None else None,
                     text=text)
    return recorder.build(), mission


@checker("prediction")
def lift_requests_check(predicted: Callable[[], int], log, lift: Pose2D) -> str:
    """The count written before the run against the run's log (its ``mission_event``
    channel), itself checked against the chair's true track."""
    expect_own(predicted, run_lift_route, _requests_along)
    value = predicted()
    expect(isinstance(value, (int, np.integer)) and not isinstance(value, bool)
           and value >= 0, f"predicted_lift_requests() gave {format_value(value)}; write "
                           "one whole number (how many times it fires)")
    arrivals = sum(str(r).count("arrived at") for r in log.mission)
    expect(arrivals == len(LIFT_ROUTE), f"the log handed in has {arrivals} of the route's "
                                        f"{len(LIFT_ROUTE)} errands arrived: hand the check "
                                        "the log of the whole run of LIFT_ROUTE")
    fired = sum(str(e).split(" | ").count(LIFT_REQUESTED.name) for e in log.mission_event)
    along = _requests_along(np.asarray(log.pose)[:, :2], lift)
    expect(fired == along, f"the log says the lift was requested {fired} time(s), but the "
                           f"chair's true track comes near it {along} time(s): hand the check "
                           "the log of the run of LIFT_ROUTE")
    visits = sum(1 for leg in LIFT_ROUTE if leg == "lift")
    if value == fired:
        return (f"you predicted {value}; it fired {fired} times in {visits} visits to the "
                "lift: once per approach, and an approach ends only beyond "
                f"{LIFT_REQUESTED.radius + REARM_MARGIN:.0f} m")
    if value == visits:
        raise NotYet(f"you predicted {value}, one a visit; it fired {fired} times: the event "
                     f"re-arms only once the chair is more than {REARM_MARGIN:.0f} m beyond "
                     f"its {LIFT_REQUESTED.radius:.0f} m radius, and the first point of the "
                     "route is not that far from the lift")
    raise NotYet(f"you predicted {value}; it fired {fired} times in {visits} visits to the "
                 f"lift: it fires on coming within {LIFT_REQUESTED.radius:.0f} m and can fire "
                 f"again only after the chair has been beyond "
                 f"{LIFT_REQUESTED.radius + REARM_MARGIN:.0f} m: how far from the lift is "
                 "each point of the route?")


# --- exercise 3: the scan interval -------------------------------------------------------


def true_scan_choice(options: int = 9) -> tuple[float, float]:
    """(s, s): the scan interval at which exactly :data:`FALSE_SELECTIONS` of the
    selections are false, ``median exp(1.645 spread)`` (the reaction time's 95th
    percentile), and the mean time to select there, ``(options - 1) / 2 interval +
    median exp(spread^2 / 2)``."""
    z = 1.6448536269514722  # the standard normal's 95th percentile
    interval = REACTION_MEDIAN * math.exp(z * REACTION_SPREAD)
    mean_reaction = REACTION_MEDIAN * math.exp(REACTION_SPREAD ** 2 / 2)
    return interval, (options - 1) / 2 * interval + mean_reaction


@checker("measurement")
def scan_choice_check(choice: Callable[[], tuple[float, float]]) -> str:
    """``(interval, mean time)`` read off the sweep against the model's closed form."""
    expect_own(choice, true_scan_choice, scan_false_rate)
    interval, seconds = numbers(choice(), 2, "scan_choice()",
                                "return two numbers: the interval (s) and the mean time "
                                "to select there (s)")
    best, best_time = true_scan_choice()
    expect(interval > 0 and seconds > 0, f"scan_choice() gave ({interval:g}, {seconds:g}); "
                                         "both are times in seconds, > 0")
    if interval > 20 or seconds > 100:
        raise NotYet(f"scan_choice() gave ({interval:g}, {seconds:g}): milliseconds? the "
                     "check wants seconds")
    rate = scan_false_rate(interval)
    if abs(interval - best) > 0.1:
        if interval < best and rate > 0.25:
            hint = ("that is near the median reaction time: half the presses come after "
                    "the light has moved on")
        elif interval > best and rate < 0.02:
            hint = "that is safer than asked: the time to select grows by 4 intervals"
        else:
            hint = "read the interval where the false selections cross 5 %"
        raise NotYet(f"at {interval:.2f} s a button, {100 * rate:.1f} % of the selections "
                     f"are false (the model's closed form), where at most 5 % were asked "
                     f"for, with the least time to select: {hint}")
    expected_time = (9 - 1) / 2 * interval + REACTION_MEDIAN * math.exp(
        REACTION_SPREAD ** 2 / 2)
    if abs(seconds - expected_time) > 0.25:
        hint = (" that is the interval times the buttons: the mean target is the 5th, "
                "lit after 4 intervals, then the reaction" if abs(seconds - 9 * interval) < 0.3
                else "")
        raise NotYet(f"at {interval:.2f} s a button the mean time to select is not "
                     f"{seconds:.2f} s (off by more than 0.25 s):"
                     f"{hint or ' read it off the sweep, at the interval you chose'}")
    return (f"{interval:.2f} s a button ({100 * rate:.1f} % false by the closed form; the "
            f"5 % point is {best:.2f} s) and {seconds:.2f} s to select: the mean target is "
            "lit after 4 intervals, then the reaction")

