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

A mission decides every control period (50 Hz), so the joystick is seen at once; it
never succeeds on its own and runs until :meth:`~Mission.cancel`. It does not apply the
safety filter: the body's control loop passes every command through it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np

from abcwc.behaviours.base import Behaviour, BehaviourBase, positive_number
from abcwc.behaviours.navigator import Navigator, NavigatorSettings
from abcwc.behaviours.voice import understood
from abcwc.control.safety import joystick_overrides
from abcwc.params import ChairParams
from abcwc.perception.speech.commands import CommandSet, SpokenCommand, place_phrase
from abcwc.types import Pose2D, SensorFrame, Twist

if TYPE_CHECKING:
    from abcwc.base import Base
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
    ``reason`` (a short sentence)."""

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


class Mission(BehaviourBase):
    """Errands on a :class:`~abcwc.behaviours.navigator.Navigator` (module notes).

    ``follower`` (a tag follower) makes "follow me" possible; ``commands`` is the voice
    grammar (default: the house set for the navigator's places); ``events`` the events
    near places (default: :data:`LIFT_REQUESTED` if there is a place "lift"; ``()`` for
    none); ``params`` the chair's (default: the navigator's). Most callers build it with
    :meth:`for_world` or :meth:`for_map`.
    """

    def __init__(self, navigator: Navigator, follower: Behaviour | None = None,
                 commands: CommandSet | None = None,
                 events: Sequence[PlaceEvent] | None = None,
                 params: ChairParams | None = None) -> None:
        super().__init__()  # every period: the joystick must be seen at once
        if not isinstance(navigator, Navigator):
            raise ValueError(f"a mission needs a Navigator, got {type(navigator).__name__}")
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
        self._goal_label = "nowhere"
        self._subscribers: list[Callable[[MissionEvent], None]] = []
        self._now = 0.0
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
                  settings: NavigatorSettings | None = None) -> Mission:
        """A mission on a simulated world's walls and places (a :class:`World` or a
        world's name or file), for ``chair`` (its parameters; default the house chair),
        starting at ``start`` (a pose or a place; default the world's start); the
        navigator's ``settings`` default to its own with ``relocalise_turn`` set to
        :data:`RELOCALISE_TURN`."""
        if isinstance(world, str):
            from abcwc.sim.world import load_world

            world = load_world(world)
        params = chair.params if chair is not None else None
        settings = settings or NavigatorSettings(relocalise_turn=RELOCALISE_TURN)
        navigator = Navigator.for_world(world, start, params, settings=settings)
        return cls(navigator, follower, events=events, params=params)

    @classmethod
    def for_map(cls, cells: np.ndarray, grid: GridGeometry, start: Pose2D,
                places: dict[str, Pose2D], params: ChairParams | None = None,
                follower: Behaviour | None = None, events: Sequence[PlaceEvent] | None = None,
                settings: NavigatorSettings | None = None) -> Mission:
        """A mission on a built map (trinary ``cells`` on ``grid``, as
        :meth:`Navigator.for_map`) with the named ``places`` (m, rad), from ``start``;
        ``settings`` as :meth:`for_world`."""
        settings = settings or NavigatorSettings(relocalise_turn=RELOCALISE_TURN)
        navigator = Navigator.for_map(cells, grid, start, params, settings=settings)
        navigator.places = dict(places)
        return cls(navigator, follower, events=events, params=params)

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
        self._goal_label = label
        self.navigator.go_to(goal)
        self._active = self.navigator
        if not self.navigator.running:  # off the map, in a wall, no path: at once
            self._active = None
            self._transition(MissionState.FAILED,
                             f"{reason}: cannot go to {label}: {self.navigator.failure}")
            return
        self._transition(MissionState.NAVIGATING, f"{reason}: going to {label}")

    def follow(self, reason: str = "asked") -> None:
        """Follow the person ahead (the follower's tag). ``ValueError`` without a
        follower."""
        if self.follower is None:
            raise ValueError("following needs a follower: Mission(navigator, follower=...)")
        self._revive()
        self._end_errand()
        self.goal = None
        self.follower.reset()
        self._active = self.follower
        self._transition(MissionState.FOLLOWING, f"{reason}: following the person ahead")

    def stop(self, reason: str = "stop pressed") -> None:
        """End the errand and stand still (idle)."""
        self._revive()
        self._end_errand()
        self.goal = None
        self._transition(MissionState.IDLE, reason)

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
        self._now = frame.t
        if not self.running:  # cancelled: the localiser still keeps the chair's place
            self.navigator.observe(frame)

    def update(self, frame: SensorFrame) -> Twist:
        """One period: the joystick first, then the errand, then the events."""
        if joystick_overrides(frame):
            if self.state is not MissionState.MANUAL_OVERRIDE:
                self._end_errand()
                self._transition(MissionState.MANUAL_OVERRIDE,
                                 "the joystick moved: the rider drives; the errand is "
                                 "paused until a new command")
            self.navigator.observe(frame)
            command = Twist(0.0, 0.0)
        elif self._active is self.navigator:
            command = self.navigator(frame)
            command = self._after_navigator(command)
        elif self._active is not None:
            self.navigator.observe(frame)
            command = self._active(frame)
            if not self._active.running:
                ended = self._active.failure or self._active.status.value
                self._active = None
                self._transition(MissionState.FAILED, f"stopped following: {ended}")
        else:
            self.navigator.observe(frame)
            command = Twist(0.0, 0.0)
        self._check_events(frame)
        return command  # type: ignore[return-value]

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
        self.goal = None
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

    def _after_navigator(self, command: Twist) -> Twist:
        """The mission's state from the navigator's: arrived, failed, lost, waiting."""
        nav, label = self.navigator, self._goal_label
        if not nav.running:
            self._active = None
            if nav.failure is None:
                self._transition(MissionState.ARRIVED, f"arrived at {label}")
            else:
                self._transition(MissionState.FAILED, nav.failure)
            return Twist(0.0, 0.0)
        phase = nav.feedback.phase if nav.feedback is not None else ""
        if nav.localizer.lost:
            if self.state is not MissionState.LOCALISING:
                self._transition(MissionState.LOCALISING,
                                 "lost: the scans no longer fit the map; stopping to turn "
                                 "and find the chair's place on the map")
            if phase not in RELOCALISING_PHASES:  # the navigator's next decision searches
                return Twist(0.0, 0.0)
        elif self.state is MissionState.LOCALISING:
            self._transition(MissionState.NAVIGATING,
                             f"found the chair's place on the map: going on to {label}")
        elif phase.startswith("waiting"):
            if self.state is not MissionState.WAITING:
                self._transition(MissionState.WAITING, phase)
                blocking = nav.seen_off_map() & ~nav.avoided
                if blocking.sum() >= MIN_BLOCKING_CELLS:  # kept for this errand
                    nav.avoid(blocking)
                    self._transition(MissionState.NAVIGATING,
                                     "the way is blocked by something the map does not "
                                     f"have: planning round it to {label}")
        elif self.state is MissionState.WAITING:
            self._transition(MissionState.NAVIGATING, f"the way is clear: going on to {label}")
        return command

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
