"""Driving by voice (or by typed command): the thesis's A.4, with the chair's other
behaviours behind the commands that need them.

A heard command replaces the one before it, as in A.4:

* a motion ("drive forward", "turn left", ...) is held until the next command or for
  ``hold_seconds`` (10 s), whichever comes first: a person who cannot say "stop" in
  time is not driven into the far wall (and the body's safety filter, in the control
  loop, ramps it, stops it short of what the sonar and IR see and gives way to the
  joystick);
* "stop" stands still, and cancels a goal or a follow;
* "go to the <place>" hands the chair to the ``navigator``, "follow me" to the
  ``follower``; when either ends the chair stands still and ``last_outcome`` says how
  it ended.

The behaviour never succeeds on its own: it listens until it is cancelled.
"""

from __future__ import annotations

import math

from abcwc.behaviours.base import Behaviour, BehaviourBase, positive_number
from abcwc.perception.speech.commands import CommandSet, SpokenCommand
from abcwc.types import SensorFrame, Twist


def understood(commands: CommandSet, command: SpokenCommand | str, navigator: bool,
               follower: bool, asker: str = "VoiceControl") -> SpokenCommand:
    """``command`` (a recogniser's ``SpokenCommand``, or typed text parsed by the
    ``commands`` grammar) checked against what the chair can obey: ``navigator`` and
    ``follower`` say whether it has them (``asker`` names the class in the message).
    Raises ``ValueError`` for text that is not a command (the message lists them), or
    for a command whose behaviour is missing."""
    if isinstance(command, str):
        command = commands.parse(command)
    if not isinstance(command, SpokenCommand):
        raise ValueError(f"a command is text or a SpokenCommand, got "
                         f"{type(command).__name__}")
    if command.phrase not in commands:
        raise ValueError(f'"{command.phrase}" is not one of this chair\'s commands')
    if command.place is not None and not navigator:
        raise ValueError(f'"{command.phrase}" needs a navigator: '
                         f"{asker}(..., navigator=...)")
    if command.follow and not follower:
        raise ValueError(f'"follow me" needs a follower: {asker}(..., follower=...)')
    return command


class VoiceControl(BehaviourBase):
    """Obey ``commands`` as they are heard (module notes). ``navigator`` and
    ``follower`` are optional; a command that needs one that is missing is refused."""

    def __init__(self, commands: CommandSet, navigator: Behaviour | None = None,
                 follower: Behaviour | None = None, hold_seconds: float = 10.0) -> None:
        super().__init__()
        self.commands = commands
        self.navigator = navigator
        self.follower = follower
        self.hold_seconds = positive_number("hold_seconds", hold_seconds, "s")
        self.heard: list[tuple[float, str]] = []  # (t, phrase) of every command obeyed
        self.last_outcome: str | None = None
        self._reset_state()

    def _reset_state(self) -> None:
        self._wanted = Twist(0.0, 0.0)
        self._since = -math.inf
        self._delegate: Behaviour | None = None
        self._pending: SpokenCommand | None = None

    def reset(self) -> None:
        super().reset()
        self._reset_state()

    @property
    def decided_at(self) -> float | None:
        """The decision time of the command sent: the navigator's or follower's while
        one drives (so the safety filter sees how old their decision is), else this
        behaviour's own."""
        if self._delegate is not None and self._delegate.running:
            return self._delegate.decided_at
        return super().decided_at

    def hear(self, command: SpokenCommand | str) -> SpokenCommand:
        """Obey ``command`` (a recogniser's ``SpokenCommand``, or typed text, parsed by
        the same grammar) from the next frame on. Raises ``ValueError`` for text that is
        not a command (the message lists them) or for a command whose behaviour this
        chair lacks."""
        command = understood(self.commands, command, navigator=self.navigator is not None,
                             follower=self.follower is not None, asker="VoiceControl")
        self._pending = command
        return command

    def update(self, frame: SensorFrame) -> Twist:
        if self._pending is not None:
            self._start(self._pending, frame.t)
            self._pending = None
        if self._delegate is not None:
            command = self._delegate(frame)
            if self._delegate.running:
                return command
            self.last_outcome = (self._delegate.failure or
                                 self._delegate.status.value)
            self._delegate, self._wanted = None, Twist(0.0, 0.0)
        if frame.t - self._since > self.hold_seconds:
            self._wanted = Twist(0.0, 0.0)
        return self._wanted

    def _start(self, command: SpokenCommand, t: float) -> None:
        if self._delegate is not None and self._delegate.running:
            self._delegate.cancel()
            self.last_outcome = "cancelled"
        self._delegate = None
        self.heard.append((t, command.phrase))
        self._wanted, self._since = Twist(0.0, 0.0), t
        if command.twist is not None:
            self._wanted = command.twist
        elif command.place is not None:
            self.navigator.go_to(command.place)  # type: ignore[union-attr]
            self._delegate = self.navigator
        elif command.follow:
            self.follower.reset()  # type: ignore[union-attr]
            self._delegate = self.follower

    def cancel(self) -> None:
        if self._delegate is not None and self._delegate.running:
            self._delegate.cancel()
        super().cancel()
