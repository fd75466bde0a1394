"""The one Base interface every chair body offers, and the control loop behind it.

Every body (the simulator :class:`abcwc.sim.SimBase`, the real chair
:class:`abcwc.hw.serial_base.SerialBase`, the firmware in the loop
:class:`abcwc.hw.fil_base.FirmwareInLoopBase`) offers the same surface: ``params``,
``period``, ``send(PotCommand | Twist)``, ``step() -> SensorFrame`` (one 20 ms
control period), ``read()``, ``stop()``, ``set_speed_cap()``, ``run(controller,
seconds) -> RunLog``, ``drive(command, seconds)``, ``close()``, ``last_command`` and
``log_meta()``. :func:`run_controller` is the one control loop behind every ``run``;
:class:`BodyMixin` gives a body ``frame``, ``read``, ``run``, ``drive`` and the
context manager once. This module imports no body: :mod:`abcwc.connect` picks one.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import ClassVar, Protocol, TypeVar, runtime_checkable

from abcwc.log import LogRecorder, RunLog
from abcwc.params import ChairParams
from abcwc.types import PotCommand, SensorFrame, Twist

Controller = Callable[[SensorFrame], "PotCommand | Twist | None"]
_Body = TypeVar("_Body", bound="BodyMixin")


@runtime_checkable
class Base(Protocol):
    """What every chair body offers."""

    params: ChairParams
    period: float

    def send(self, command: PotCommand | Twist) -> None: ...
    def step(self) -> SensorFrame: ...
    def read(self) -> SensorFrame: ...
    def stop(self) -> None: ...
    def set_speed_cap(self, offset: int) -> None: ...
    def run(self, controller: Controller, seconds: float, progress: bool = False) -> RunLog: ...
    def drive(self, command: PotCommand | Twist, seconds: float) -> RunLog: ...
    def close(self) -> None: ...
    def log_meta(self) -> dict: ...

    @property
    def last_command(self) -> PotCommand | None: ...


def run_controller(chair: Base, controller: Controller, seconds: float,
                   progress: bool = False, verb: str = "driving") -> RunLog:
    """The control loop every body's ``run`` uses.

    Every period: ``controller(latest frame)``; send what it returns (a PotCommand, a
    Twist, or None: send nothing, so after 250 ms the watchdog stops the chair); step;
    record the frame, the command and its pot bytes. ``progress`` shows a tqdm bar
    labelled "<verb> <seconds> s".
    """
    if not (isinstance(seconds, (int, float)) and math.isfinite(seconds) and seconds >= 0):
        raise ValueError(f"seconds must be a finite number >= 0, got {seconds!r}")
    steps = round(seconds / chair.period)
    recorder = LogRecorder(chair.log_meta())
    iterator = range(steps)
    if progress:
        from tqdm.auto import tqdm

        iterator = tqdm(iterator, desc=f"{verb} {seconds:g} s", unit="step")
    frame = chair.read()
    for _ in iterator:
        command = controller(frame)
        sent = None
        if command is not None:
            chair.send(command)
            sent = chair.last_command
        frame = chair.step()
        recorder.add(frame, command, sent)
    return recorder.build()


class BodyMixin:
    """What every body does the same way, on top of its own ``step``, ``send``,
    ``stop``, ``close`` and ``log_meta``.

    A body keeps its latest SensorFrame in ``_frame``; ``run_verb`` labels the
    progress bar of :meth:`run` ("simulating", "driving").
    """

    period: float
    _frame: SensorFrame
    run_verb: ClassVar[str] = "driving"

    @property
    def frame(self) -> SensorFrame:
        """The latest SensorFrame."""
        return self._frame

    def read(self) -> SensorFrame:
        """The latest SensorFrame (same as :attr:`frame`)."""
        return self._frame

    def run(self, controller: Controller, seconds: float, progress: bool = False) -> RunLog:
        """Call ``controller(frame)`` every period for ``seconds``; send what it returns.

        The controller returns a PotCommand, a Twist, or None (send nothing: after
        250 ms the watchdog stops the chair). Returns the whole run as a RunLog.
        """
        return run_controller(self, controller, seconds, progress,  # type: ignore[arg-type]
                              verb=self.run_verb)

    def drive(self, command: PotCommand | Twist, seconds: float) -> RunLog:
        """Send the same command every period for ``seconds``."""
        return self.run(lambda frame: command, seconds)

    def close(self) -> None:
        """Release what the body holds (nothing here); safe to call twice."""

    def __enter__(self: _Body) -> _Body:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
