"""A minimal mission for the dashboard's tests until ``abcwc.behaviours.mission.Mission``
is on this branch: the same surface (``destinations``, ``state``, ``reason``,
``transitions``, ``goal``, ``navigator``, ``command``, ``go_to``, ``stop``, ``__call__``,
``decided_at``) over a Navigator, with only the states the dashboard's tests reach
(idle, navigating, arrived, failed). Tests only: the package never imports it."""

from __future__ import annotations

from dataclasses import dataclass

from abcwc.behaviours.base import Status
from abcwc.behaviours.navigator import Navigator
from abcwc.perception.speech.commands import CommandSet, SpokenCommand
from abcwc.types import Pose2D, SensorFrame, Twist


@dataclass(frozen=True)
class Transition:
    t: float
    before: str
    after: str
    reason: str


class StandInMission:
    def __init__(self, navigator: Navigator):
        self.navigator = navigator
        self.destinations: dict[str, Pose2D] = dict(navigator.places)
        self.commands = CommandSet(self.destinations)
        self.state, self.reason = "idle", "ready"
        self.transitions: list[Transition] = []
        self.goal: str | Pose2D | None = None
        self._t = 0.0

    @classmethod
    def for_world(cls, world: object) -> StandInMission:
        return cls(Navigator.for_world(world))

    @property
    def decided_at(self) -> float | None:
        return self.navigator.decided_at if self.state == "navigating" else self._t

    def _to(self, state: str, reason: str) -> None:
        self.transitions.append(Transition(self._t, self.state, state, reason))
        self.state, self.reason = state, reason

    def command(self, text: str | SpokenCommand) -> SpokenCommand:
        spoken = text if isinstance(text, SpokenCommand) else self.commands.parse(text)
        if spoken.place is not None:
            self.go_to(spoken.place, reason=f'"{spoken.phrase}"')
        elif spoken.phrase == "stop":
            self.stop('"stop" said')
        else:
            raise ValueError(f"the stand-in mission only goes to places and stops, not "
                             f"{spoken.phrase!r}")
        return spoken

    def go_to(self, destination: str | tuple[float, float] | Pose2D,
              reason: str = "go to") -> None:
        self.navigator.go_to(destination)
        self.goal = destination if isinstance(destination, (str, Pose2D)) else \
            Pose2D(*destination, 0.0)
        if self.navigator.status is Status.FAILED:
            self._to("failed", self.navigator.failure or "failed")
        else:
            self._to("navigating", reason)

    def stop(self, reason: str = "stop pressed") -> None:
        self.navigator.cancel()
        self.goal = None
        self._to("idle", reason)

    def __call__(self, frame: SensorFrame) -> Twist:
        self._t = frame.t
        if self.state != "navigating":
            self.navigator.observe(frame)
            return Twist(0.0, 0.0)
        command = self.navigator(frame)
        if self.navigator.status is Status.SUCCEEDED:
            self._to("arrived", f"at the {self.goal}")
        elif self.navigator.status is Status.FAILED:
            self._to("failed", self.navigator.failure or "failed")
        return command
