"""The mission layer: errands for a person, on top of the navigator and the follower.

A rider picks a task ("get a coffee") by touch, by voice or by a click on the map; the
chair localises, plans, drives there among people, asks for the lift on the way, and
gives control back the moment the joystick moves (the thesis's concept, its figures
1-2). :class:`Mission` is that task layer, one behaviour over the others:

* **Destinations** are the navigator's named places (any world's, or those given with
  a built map), or any free point of the map.
* **Inputs**, all ending in the same calls: a typed or spoken command in the voice
  grammar (:class:`~abcwc.perception.speech.commands.CommandSet`: "go to the <place>",
  "follow me", "stop"; :meth:`Mission.command`), a button per place
  (``go_to("cafeteria")``) and a click on the map (``go_to((x, y))``).
* **States** (:class:`MissionState`): idle, localising, navigating, following, waiting,
  manual override, arrived, failed. Every change is a :class:`Transition` with its
  reason, kept in :attr:`Mission.transitions` and, through :meth:`Mission.log_fields`,
  in the RunLog of ``chair.run(mission, ...)``: channel ``mission_state`` (the state at
  every row), ``mission`` (the reasons, on the rows of transitions) and
  ``mission_event`` (the events fired).
* **Lost localisation** is a state, not a crash: when the navigator's localiser says the
  scans no longer fit the map, the mission is *localising* while the navigator stops,
  turns on the spot (:data:`RELOCALISE_TURN` between searches) and searches for the
  chair's place on the map; found, it goes on
  with the errand; not found within the navigator's patience, the mission has *failed*
  with the reason.
* **A way blocked** by something the map does not have (a cupboard in a corridor): when
  the navigator waits for the way to clear and its scan marks at least half a metre of
  it (:data:`MIN_BLOCKING_CELLS`; people it tracks left out), the navigator treats it as
  a wall for the rest of the errand (:meth:`Navigator.avoid
  <abcwc.behaviours.navigator.Navigator.avoid>`) and plans another way; with none, the
  navigator gives up with its reason ("no path to the goal ..."), and so does the mission.
* **Events near places** (:class:`PlaceEvent`): "lift requested" fires when the chair's
  estimate comes within 3 m of the place "lift", once per approach, to every
  subscriber (:meth:`Mission.subscribe`): the thesis's IoT hooks.
* **The joystick always wins** (ISO 7176-14; the interface board's rule): a frame that
  says the joystick drives (:func:`~abcwc.control.safety.joystick_overrides`, the board's
  ``JOYSTICK_OVERRIDE`` flag, the simulator's or the firmware's) puts the mission in
  *manual override* in that control period: the errand is cancelled, the mission sends
  a stop (the pots follow the joystick), and after the release it stays there, still,
  until a new command. It never resumes by itself.

**The decision and the actions are apart.** When the state changes is one pure function,
the *rule* :func:`next_state` ``(state, situation) -> (new state, reason) | None``, of
what the mission sees (:class:`Situation`: the joystick deflected, a new command, the
errand's status, the localiser lost, the navigator waiting, the way blocked). The
:class:`Mission` gathers the situation, asks the rule, logs the transition, and acts:
it runs the behaviour the state asks for and only it (the navigator while navigating,
localising or waiting, the follower while following, none otherwise; a stopped one is
started again), plans round the blocking cells when the rule says navigate on a blocked
way, sends the command the state allows, and fires the events. A different rule
(``Mission(..., rules=my_next_state)``) drives the same mission: the course's chapter 18
has students write it. :meth:`~Mission.cancel` and :meth:`~Mission.reset` end the
mission whatever the rule says.

A mission decides every control period (50 Hz), so the joystick is seen at once; it
never succeeds on its own and runs until :meth:`~Mission.cancel`. It does not apply the
safety filter: the body's control loop passes every command through it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np

from abcwc.behaviours.base import Behaviour, BehaviourBase, Status, positive_number
from abcwc.behaviours.navigator import Navigator, NavigatorSettings
from abcwc.behaviours.voice import understood
from abcwc.control.safety import joystick_overrides
from abcwc.params import ChairParams
from abcwc.perception.speech.commands import CommandSet, SpokenCommand, place_phrase
from abcwc.types import Pose2D, SensorFrame, Twist

if TYPE_CHECKING:
    from abcwc.base import Base
    from abcwc.estimation.ekf import ChairEkf
    from abcwc.log import RunLog
    from abcwc.mapping.grid import GridGeometry
    from abcwc.sim.world import World

REARM_MARGIN = 1.0
"""m beyond an event's radius the chair must go before the event can fire again: one
approach, one event, even when the estimate wavers on the circle."""
MIN_BLOCKING_CELLS = 10
"""Cells of the navigator's map (5 cm) the scan must newly mark off the map, while the
navigator waits for the way to clear, for the mission to plan round them for the rest of
the errand: half a metre of wall, not the odd noisy return."""
RELOCALISE_TURN = math.pi / 6
"""rad the chair turns on the spot between searches for its place when lost: the
navigator's ``relocalise_turn`` in :meth:`Mission.for_world` and :meth:`Mission.for_map`
(its own default stands still, as its chapter shows it)."""
RELOCALISING_PHASES = ("relocalising", "turning to re-localise")
"""The navigator's phases while it searches for the chair's place (it stands or turns)."""


class MissionState(str, Enum):
    """Where the mission stands; the values are what a person reads."""

    IDLE = "idle"
    LOCALISING = "localising"
    NAVIGATING = "navigating"
    FOLLOWING = "following"
    WAITING = "waiting"
    MANUAL_OVERRIDE = "manual override"
    ARRIVED = "arrived"
    FAILED = "failed"


@dataclass(frozen=True)
class Transition:
    """The mission went from ``before`` to ``after`` at frame time ``t`` (s) because of
    ``reason`` (a short sentence). A command given before the mission has seen a frame
    is stamped with the first frame's time."""

    t: float
    before: MissionState
    after: MissionState
    reason: str


@dataclass(frozen=True)
class PlaceEvent:
    """Fire ``name`` when the chair's estimate comes within ``radius`` m of ``place``."""

    name: str
    place: str
    radius: float = 3.0

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ValueError(f"an event's name is a non-empty text, got {self.name!r}")
        positive_number("radius", self.radius, "m")


@dataclass(frozen=True)
class MissionEvent:
    """An event that fired at frame time ``t`` (s), ``distance`` m (by the estimate)
    from ``place``."""

    t: float
    name: str
    place: str
    distance: float


LIFT_REQUESTED = PlaceEvent("lift requested", "lift")
"""The default event of a world with a place called "lift"."""

ERRAND_STATES = (MissionState.NAVIGATING, MissionState.LOCALISING, MissionState.WAITING)
"""The states in which the navigator drives the errand."""
COMMANDS = ("go to", "follow", "stop")
"""The commands a :class:`Situation` can carry."""


@dataclass(frozen=True)
class Situation:
    """What the mission sees when it decides: in a control period, or at a command.

    * ``joystick``: the frame says the joystick drives (the rider's hand);
    * ``command``: a new command at this moment, one of :data:`COMMANDS` ("go to",
      "follow", "stop"), or None;
    * ``asked``: who gave it and how, the start of a reason ('typed "stop"', "button");
    * ``goal``: the errand's goal as a person reads it ("the lift", "(8.00, 6.00) m");
    * ``status``: the errand's behaviour's :class:`~abcwc.behaviours.base.Status` (the
      navigator's or the follower's; after a "go to", whether the navigator could
      start), None with no errand;
    * ``failure``: why it failed, when its status is failed;
    * ``lost``: the localiser says the scans no longer fit the map;
    * ``waiting``: the navigator waits for the way to clear;
    * ``blocked``: while it waits, the scan marks at least :data:`MIN_BLOCKING_CELLS`
      of the way that the map does not have (people left out): planning round it
      may help.
    """

    joystick: bool = False
    command: str | None = None
    asked: str = ""
    goal: str = ""
    status: Status | None = None
    failure: str | None = None
    lost: bool = False
    waiting: bool = False
    blocked: bool = False

    def __post_init__(self) -> None:
        if self.command is not None and self.command not in COMMANDS:
            raise ValueError(f"a situation's command is one of {', '.join(COMMANDS)} or "
                             f"None, got {self.command!r}")


Rule = Callable[[MissionState, Situation], "tuple[MissionState, str] | None"]
"""A mission's rule: ``(state, situation) -> (new state, reason)``, or None to stay."""


def next_state(state: MissionState, situation: Situation) -> tuple[MissionState, str] | None:
    """The mission's transitions: the new state and the reason for it, or None (stay).

    In this order: the joystick wins (manual override, where the mission stays while the
    joystick is held and after, until a new command); a command is obeyed ("stop":
    idle; "follow": following; "go to": navigating, or failed if the navigator cannot
    start); a follower that ends has failed; on an errand, the navigator's end is
    arrived or failed, a lost localiser is localising until the chair's place is found,
    and a wait is waiting, left to navigate round what blocks the way when the scan
    shows it, or when the way clears.
    """
    s, st = situation, MissionState
    if s.joystick:
        if state is st.MANUAL_OVERRIDE:
            return None
        return (st.MANUAL_OVERRIDE, "the joystick moved: the rider drives; the errand is "
                                    "paused until a new command")
    if s.command == "stop":
        return st.IDLE, s.asked
    if s.command == "follow":
        return st.FOLLOWING, f"{s.asked}: following the person ahead"
    if s.command == "go to":
        if s.status is Status.FAILED:
            return st.FAILED, f"{s.asked}: cannot go to {s.goal}: {s.failure}"
        return st.NAVIGATING, f"{s.asked}: going to {s.goal}"
    if state is st.FOLLOWING:
        if s.status is Status.RUNNING:
            return None
        ended = s.failure or (s.status.value if s.status is not None else "no follower")
        return st.FAILED, f"stopped following: {ended}"
    if state not in ERRAND_STATES:
        return None
    if s.status is Status.SUCCEEDED:
        return st.ARRIVED, f"arrived at {s.goal}"
    if s.status is Status.FAILED:
        return st.FAILED, s.failure or "the navigator failed"
    if s.lost:
        if state is st.LOCALISING:
            return None
        return (st.LOCALISING, "lost: the scans no longer fit the map; stopping to turn "
                               "and find the chair's place on the map")
    if state is st.LOCALISING:
        return st.NAVIGATING, f"found the chair's place on the map: going on to {s.goal}"
    if s.waiting:
        if state is st.NAVIGATING:
            return st.WAITING, "waiting for the way to clear"
        if s.blocked:
            return (st.NAVIGATING, "the way is blocked by something the map does not "
                                   f"have: planning round it to {s.goal}")
        return None
    if state is st.WAITING:
        return st.NAVIGATING, f"the way is clear: going on to {s.goal}"
    return None


class Mission(BehaviourBase):
    """Errands on a :class:`~abcwc.behaviours.navigator.Navigator` (module notes).

    ``follower`` (a tag follower) makes "follow me" possible; ``commands`` is the voice
    grammar (default: the house set for the navigator's places); ``events`` the events
    near places (default: :data:`LIFT_REQUESTED` if there is a place "lift"; ``()`` for
    none); ``params`` the chair's (default: the navigator's); ``rules`` the transitions
    (default: :func:`next_state`). Most callers build it with :meth:`for_world` or
    :meth:`for_map`.
    """

    def __init__(self, navigator: Navigator, follower: Behaviour | None = None,
                 commands: CommandSet | None = None,
                 events: Sequence[PlaceEvent] | None = None,
                 params: ChairParams | None = None, rules: Rule = next_state) -> None:
        super().__init__()  # every period: the joystick must be seen at once
        if not isinstance(navigator, Navigator):
            raise ValueError(f"a mission needs a Navigator, got {type(navigator).__name__}")
        if not callable(rules):
            raise ValueError("rules is a function (state, situation) -> (state, reason) | "
                             f"None, got {rules!r}")
        self.rules = rules
        self.navigator = navigator
        self.follower = follower
        self.params = params or navigator.params
        self.destinations: dict[str, Pose2D] = dict(navigator.places)
        self.commands = commands if commands is not None else CommandSet(self.destinations)
        if events is None:
            events = (LIFT_REQUESTED,) if LIFT_REQUESTED.place in self.destinations else ()
        for event in events:
            if not isinstance(event, PlaceEvent):
                raise ValueError(f"events are PlaceEvents, got {event!r}")
            if event.place not in self.destinations:
                raise ValueError(f"event {event.name!r} is near {event.place!r}, which is "
                                 f"not a place; places: {', '.join(self.destinations)}")
        self.events = tuple(events)
        self.state = MissionState.IDLE
        self.reason = "waiting for a command"
        self.transitions: list[Transition] = []
        self.events_fired: list[MissionEvent] = []
        self.goal: str | Pose2D | None = None  # a place, or a point (a click's heading: 0)
        self._navigator_goal: str | Pose2D | tuple[float, float] | None = None  # as given
        self._goal_label = "nowhere"
        self._joystick = False  # the newest frame's
        self._blocking: np.ndarray | None = None  # the cells that block the way, waiting
        self._blocking_from: tuple[object, int] | None = None  # from: local costmap, avoided
        self._subscribers: list[Callable[[MissionEvent], None]] = []
        self._now = math.nan  # s, the newest frame's time (none seen yet)
        self._active: Behaviour | None = None  # the navigator or the follower, on an errand
        self._armed: dict[int, bool | None] = dict.fromkeys(range(len(self.events)))
        self._unlogged_reasons: list[str] = []
        self._unlogged_events: list[str] = []
        self.navigator.cancel()  # no goal yet: it drives only when the mission asks

    # ------------------------------------------------------------------ building
    @classmethod
    def for_world(cls, world: World | str, chair: Base | None = None,
                  start: Pose2D | str | None = None, follower: Behaviour | None = None,
                  events: Sequence[PlaceEvent] | None = None,
                  settings: NavigatorSettings | None = None,
                  rules: Rule = next_state) -> Mission:
        """A mission on a simulated world's walls and places (a :class:`World` or a
        world's name or file), for ``chair`` (its parameters; default the house chair),
        starting at ``start`` (a pose or a place; default the world's start); the
        navigator's ``settings`` default to its own with ``relocalise_turn`` set to
        :data:`RELOCALISE_TURN`; ``rules`` the transitions (:func:`next_state`)."""
        if isinstance(world, str):
            from abcwc.sim.world import load_world

            world = load_world(world)
        params = chair.params if chair is not None else None
        settings = settings or NavigatorSettings(relocalise_turn=RELOCALISE_TURN)
        navigator = Navigator.for_world(world, start, params, settings=settings)
        return cls(navigator, follower, events=events, params=params, rules=rules)

    @classmethod
    def for_map(cls, cells: np.ndarray, grid: GridGeometry, start: Pose2D,
                places: dict[str, Pose2D], params: ChairParams | None = None,
                follower: Behaviour | None = None, events: Sequence[PlaceEvent] | None = None,
                settings: NavigatorSettings | None = None, ekf: ChairEkf | None = None,
                rules: Rule = next_state) -> Mission:
        """A mission on a built map (trinary ``cells`` on ``grid``, as
        :meth:`Navigator.for_map`) with the named ``places`` (m, rad), from ``start``,
        its localiser's filter ``ekf`` (default: nominal odometry from ``start``; after
        mapping, the filter the mapping drove by, moved onto the map's frame);
        ``settings`` as :meth:`for_world`; ``rules`` the transitions (:func:`next_state`)."""
        settings = settings or NavigatorSettings(relocalise_turn=RELOCALISE_TURN)
        navigator = Navigator.for_map(cells, grid, start, params, ekf=ekf, settings=settings)
        navigator.places = dict(places)
        return cls(navigator, follower, events=events, params=params, rules=rules)

    # ------------------------------------------------------------------ inputs
    def command(self, text_or_spoken: str | SpokenCommand) -> SpokenCommand:
        """Obey a typed text or a recogniser's command, in the voice grammar: "go to the
        <place>", "follow me" or "stop". Raises ``ValueError`` listing the commands for
        anything else (a motion such as "drive forward" is voice control's, not an
        errand)."""
        how = "typed" if isinstance(text_or_spoken, str) else "heard"
        command = understood(self.commands, text_or_spoken, navigator=True,
                             follower=self.follower is not None, asker="Mission")
        said = f'{how} "{command.phrase}"'
        if command.place is not None:
            self.go_to(command.place, reason=said)
        elif command.follow:
            self.follow(reason=said)
        elif command.phrase == "stop":
            self.stop(reason=said)
        else:
            errands = [p for p in self.commands.phrases
                       if self.commands[p].twist is None or p == "stop"]
            raise ValueError(f'"{command.phrase}" is a motion, not an errand; a mission '
                             f"obeys: {', '.join(repr(p) for p in errands)}")
        return command

    def go_to(self, destination: str | tuple[float, float] | Pose2D,
              reason: str = "asked") -> None:
        """Start the errand to ``destination``: a place's name (a button), an ``(x, y)``
        in metres (a click on the map) or a Pose2D. ``reason`` says who asked (it
        prefixes the transition's reason). ``ValueError`` for an unknown place or a
        point that is not finite, saying what is allowed."""
        goal, label = self._destination(destination)
        self._revive()
        self._end_errand()
        # a click's (x, y) reaches the navigator as it is: any heading will do there
        self.goal = Pose2D(*goal) if isinstance(goal, tuple) else goal
        self._navigator_goal, self._goal_label = goal, label
        self.navigator.go_to(goal)  # off the map, in a wall, no path: it fails at once
        self._active = self.navigator
        self._decide(self._situation("go to", reason))

    def follow(self, reason: str = "asked") -> None:
        """Follow the person ahead (the follower's tag). ``ValueError`` without a
        follower."""
        if self.follower is None:
            raise ValueError("following needs a follower: Mission(navigator, follower=...)")
        self._revive()
        self._end_errand()
        self.goal = self._navigator_goal = None
        self.follower.reset()
        self._active = self.follower
        self._decide(self._situation("follow", reason))

    def stop(self, reason: str = "stop pressed") -> None:
        """End the errand and stand still (idle)."""
        self._revive()
        self._decide(self._situation("stop", reason))
        if self.state is MissionState.IDLE:
            self.goal = self._navigator_goal = None

    def subscribe(self, callback: Callable[[MissionEvent], None]) -> None:
        """Call ``callback(event)`` for every :class:`MissionEvent` from now on."""
        if not callable(callback):
            raise ValueError(f"subscribe takes a function of a MissionEvent, got {callback!r}")
        self._subscribers.append(callback)

    # ------------------------------------------------------------------ the loop
    @property
    def decided_at(self) -> float | None:
        """The decision time of the command sent: the navigator's or follower's while
        one drives (so the safety filter sees how old their decision is)."""
        if self._active is not None and self._active.running:
            return self._active.decided_at
        return super().decided_at

    def log_fields(self) -> dict[str, str]:
        """The control loop's hook (:func:`abcwc.base.run_controller`): the state, the
        reasons of the transitions and the events since the last call."""
        fields = {"mission_state": self.state.value,
                  "mission": " | ".join(self._unlogged_reasons),
                  "mission_event": " | ".join(self._unlogged_events)}
        self._unlogged_reasons, self._unlogged_events = [], []
        return fields

    def observe(self, frame: SensorFrame) -> None:
        if math.isnan(self._now):  # commands given before the first frame count from it
            self.transitions = [replace(tr, t=frame.t) if math.isnan(tr.t) else tr
                                for tr in self.transitions]
        self._now = frame.t
        if not self.running:  # cancelled: the localiser still keeps the chair's place
            self.navigator.observe(frame)

    def update(self, frame: SensorFrame) -> Twist:
        """One period: the errand decides its command (not while the joystick drives),
        the rule decides the state, the state says which command goes out; then the
        events."""
        self._joystick = joystick_overrides(frame)
        proposed: Twist = Twist(0.0, 0.0)
        errand = self._active if self._active is not None and self._active.running else None
        if errand is self.navigator and not self._joystick:
            proposed = self.navigator(frame)  # type: ignore[assignment]
        else:
            self.navigator.observe(frame)  # the localiser keeps the chair's place
            if errand is not None and not self._joystick:
                proposed = errand(frame)  # type: ignore[assignment]
        self._decide(self._situation())
        self._check_events(frame)
        return self._command(proposed)

    def cancel(self) -> None:
        """End the mission for good (it sends stop until :meth:`reset` or a command)."""
        self._end_errand()
        if self.state is not MissionState.IDLE:
            self._transition(MissionState.IDLE, "mission cancelled")
        super().cancel()

    def reset(self) -> None:
        """Start over: no errand, idle (the record of transitions and events is kept)."""
        super().reset()
        self._end_errand()
        self.goal = self._navigator_goal = None
        if self.state is not MissionState.IDLE:
            self._transition(MissionState.IDLE, "mission reset")

    # ------------------------------------------------------------------ the parts
    def _destination(self, destination: object) -> tuple[str | Pose2D | tuple[float, float],
                                                          str]:
        """The goal to hand the navigator and how a person reads it."""
        allowed = (f"a destination is a place ({', '.join(self.destinations) or 'none'}), "
                   f"a finite (x, y) in metres or a Pose2D")
        if isinstance(destination, str):
            if destination not in self.destinations:
                raise ValueError(f"unknown place {destination!r}; {allowed}")
            return destination, f"the {place_phrase(destination)}"
        if isinstance(destination, Pose2D):
            values = (destination.x, destination.y, destination.theta)
            if not all(math.isfinite(v) for v in values):
                raise ValueError(f"{allowed}, got {destination!r}")
            return destination, f"({destination.x:.2f}, {destination.y:.2f}) m"
        try:
            x, y = destination  # type: ignore[misc]
            x, y = float(x), float(y)
        except (TypeError, ValueError):
            raise ValueError(f"{allowed}, got {destination!r}") from None
        if isinstance(destination, (bytes, dict)) or not (math.isfinite(x)
                                                          and math.isfinite(y)):
            raise ValueError(f"{allowed}, got {destination!r}")
        return (x, y), f"({x:.2f}, {y:.2f}) m"

    def _revive(self) -> None:
        """A command after :meth:`cancel` starts the mission again."""
        if not self.running:
            BehaviourBase.reset(self)

    def _end_errand(self) -> None:
        if self._active is not None and self._active.running:
            self._active.cancel()
        self._active = None

    def _transition(self, after: MissionState, reason: str) -> None:
        self.transitions.append(Transition(self._now, self.state, after, reason))
        self.state, self.reason = after, reason
        self._unlogged_reasons.append(reason)

    def _situation(self, command: str | None = None, asked: str = "") -> Situation:
        """What the mission sees now (a new ``command`` and who ``asked``, if any)."""
        nav, active = self.navigator, self._active
        phase = nav.feedback.phase if nav.feedback is not None else ""
        waiting = active is nav and nav.running and phase.startswith("waiting")
        blocked = False
        if waiting:
            source = (nav.local_costmap, int(nav.avoided.sum()))
            if (self._blocking_from is None or source[0] is not self._blocking_from[0]
                    or source[1] != self._blocking_from[1]):  # a new scan, or a new wall
                self._blocking = nav.seen_off_map() & ~nav.avoided
                self._blocking_from = source
            blocked = bool(self._blocking.sum() >= MIN_BLOCKING_CELLS)  # type: ignore[union-attr]
        return Situation(joystick=self._joystick, command=command, asked=asked,
                         goal=self._goal_label,
                         status=active.status if active is not None else None,
                         failure=active.failure if active is not None else None,
                         lost=nav.localizer.lost, waiting=waiting, blocked=blocked)

    def _decide(self, situation: Situation) -> None:
        """Ask the rule; log its transition; act on the state it leaves."""
        decided = self.rules(self.state, situation)
        if decided is not None:
            after, reason = self._checked(decided)
            self._transition(after, reason)
            if after is MissionState.NAVIGATING and situation.blocked \
                    and situation.command is None and self._blocking is not None:
                self.navigator.avoid(self._blocking)  # a wall for the rest of the errand
        self._run_the_states_behaviour()

    def _checked(self, decided: object) -> tuple[MissionState, str]:
        """The rule's answer as (state, reason); ValueError saying what is allowed."""
        allowed = ("a mission's rule returns None (stay) or (state, reason): a MissionState "
                   f"({', '.join(state.value for state in MissionState)}) and a non-empty "
                   "text")
        try:
            after, reason = decided  # type: ignore[misc]
            after = MissionState(after)
        except (TypeError, ValueError):
            raise ValueError(f"{allowed}, got {decided!r}") from None
        if not isinstance(reason, str) or not reason.strip():
            raise ValueError(f"{allowed}, got the reason {reason!r}")
        return after, reason

    def _run_the_states_behaviour(self) -> None:
        """The navigator on an errand, the follower while following, none otherwise; a
        stopped one the state asks for is started again (to the same goal)."""
        wanted: Behaviour | None = None
        if self.state in ERRAND_STATES and self._navigator_goal is not None:
            wanted = self.navigator
        elif self.state is MissionState.FOLLOWING:
            wanted = self.follower
        if self._active is not wanted:
            self._end_errand()
        if wanted is None:
            return
        if self._active is not wanted or not wanted.running:
            if wanted is self.navigator:
                self.navigator.go_to(self._navigator_goal)  # type: ignore[arg-type]
            else:
                wanted.reset()
        self._active = wanted

    def _command(self, proposed: Twist) -> Twist:
        """What goes out: the errand's command while navigating, waiting or following,
        and while localising only when the navigator turns to search; else stop."""
        phase = self.navigator.feedback.phase if self.navigator.feedback is not None else ""
        if self.state in (MissionState.NAVIGATING, MissionState.WAITING,
                          MissionState.FOLLOWING) or (
                self.state is MissionState.LOCALISING and phase in RELOCALISING_PHASES):
            return proposed
        return Twist(0.0, 0.0)

    def _check_events(self, frame: SensorFrame) -> None:
        """Fire each event whose place the estimate has come within reach of, once per
        approach; not while the estimate is lost."""
        if self.navigator.localizer.lost or self.state is MissionState.LOCALISING:
            return
        pose = self.navigator.localizer.pose
        for k, event in enumerate(self.events):
            place = self.destinations[event.place]
            distance = math.hypot(place.x - pose.x, place.y - pose.y)
            armed = self._armed[k]
            if armed is None:  # the first frame: an event fires on coming near, not at start
                self._armed[k] = distance > event.radius
            elif armed and distance <= event.radius:
                self._armed[k] = False
                fired = MissionEvent(frame.t, event.name, event.place, distance)
                self.events_fired.append(fired)
                self._unlogged_events.append(event.name)
                for callback in self._subscribers:
                    callback(fired)
            elif not armed and distance > event.radius + REARM_MARGIN:
                self._armed[k] = True


def mission_timeline(log: RunLog) -> list[tuple[float, float, str]]:
    """The mission's states over a run: ``(start, end, state)`` (s, s, the state's
    value) for each stretch of equal ``mission_state`` rows; each ends where the next
    begins, the last a period after its last row. ValueError for a log without the
    channel (record one with ``chair.run(mission, seconds)``)."""
    states = log.channels.get("mission_state")
    if states is None:
        raise ValueError("the log has no 'mission_state' channel: record the run with "
                         "chair.run(mission, seconds) (a controller with log_fields)")
    if len(states) == 0:
        return []
    t = np.asarray(log.t, dtype=float)
    starts = [0] + [k for k in range(1, len(states)) if states[k] != states[k - 1]]
    ends = [float(t[k]) for k in starts[1:]] + [float(t[-1]) + log.period]
    return [(float(t[k]), end, str(states[k])) for k, end in zip(starts, ends)]
