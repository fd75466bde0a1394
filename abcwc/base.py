"""The one Base interface every chair body offers, and the control loop behind it.

Every body (the simulator :class:`abcwc.sim.SimBase`, the real chair
:class:`abcwc.hw.serial_base.SerialBase`, the firmware in the loop
:class:`abcwc.hw.fil_base.FirmwareInLoopBase`) offers the same surface: ``params``,
``period``, ``safety``, ``send(PotCommand | Twist)``, ``step() -> SensorFrame`` (one
20 ms control period), ``read()``, ``stop()``, ``set_speed_cap()``, ``run(controller,
seconds) -> RunLog``, ``drive(command, seconds)``, ``close()``, ``last_command`` and
``log_meta()``. :func:`run_controller` is the one control loop behind every ``run``;
:class:`BodyMixin` gives a body ``frame``, ``read``, ``send``, ``run``, ``drive`` and
the context manager once. This module imports no body: :mod:`abcwc.connect` picks one.

**Every command from software passes the safety filter.** A body's :attr:`~BodyMixin.
safety` is a :class:`~abcwc.control.safety.SafetyFilter` of its own parameters, and
:meth:`~BodyMixin.send` passes each Twist or PotCommand through it against the latest
frame before the body writes it, so no controller, behaviour or notebook cell can go
round it (as Nav2's collision monitor sits between every controller and the base). A
teaching experiment that needs the bare chair says so for one run,
``chair.run(controller, seconds, safety=None)``, or for the whole session,
``chair.safety = None``. ``stop()`` is never filtered.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import ClassVar, Protocol, TypeVar, runtime_checkable

from abcwc.control.safety import SafetyFilter
from abcwc.log import LogRecorder, RunLog
from abcwc.params import ChairParams
from abcwc.types import PotCommand, SensorFrame, Twist

Controller = Callable[[SensorFrame], "PotCommand | Twist | None"]
_Body = TypeVar("_Body", bound="BodyMixin")


class _BodyFilter:
    """The default of ``run``'s ``safety``: the body's own filter."""

    def __repr__(self) -> str:
        return "BODY_FILTER"


BODY_FILTER = _BodyFilter()
"""``run(..., safety=BODY_FILTER)`` (the default): commands pass the body's own
:attr:`~BodyMixin.safety`."""
SafetyChoice = SafetyFilter | _BodyFilter | None
"""What ``run`` and ``drive`` take as ``safety``: a filter, the body's own
(:data:`BODY_FILTER`), or None for the bare chair."""


@runtime_checkable
class Base(Protocol):
    """What every chair body offers."""

    params: ChairParams
    period: float
    safety: SafetyFilter | None

    def send(self, command: PotCommand | Twist,
             decided_at: float | None = None) -> PotCommand | Twist: ...
    def step(self) -> SensorFrame: ...
    def read(self) -> SensorFrame: ...
    def stop(self) -> None: ...
    def set_speed_cap(self, offset: int) -> None: ...
    def run(self, controller: Controller, seconds: float, progress: bool = False,
            safety: SafetyChoice = BODY_FILTER) -> RunLog: ...
    def drive(self, command: PotCommand | Twist, seconds: float,
              safety: SafetyChoice = BODY_FILTER) -> RunLog: ...
    def close(self) -> None: ...
    def log_meta(self) -> dict: ...

    @property
    def last_command(self) -> PotCommand | None: ...


def run_controller(chair: Base, controller: Controller, seconds: float,
                   progress: bool = False, verb: str = "driving") -> RunLog:
    """The control loop every body's ``run`` uses.

    Every period: ``controller(latest frame)``; send what it returns (a PotCommand, a
    Twist, or None: send nothing, so after 250 ms the watchdog stops the chair) through
    the body's safety filter, stamped with the controller's ``decided_at`` when it has
    one (a behaviour deciding at 10 Hz repeats an older decision between); step; record
    the frame, the command wanted, the command sent, its pot bytes and what the filter
    changed (the RunLog's ``safety`` channel). A controller with a ``log_fields()``
    method (the mission layer's state and reasons) is asked for its short text fields
    after each call, and each becomes a text channel of the RunLog (``""`` in rows
    without it). ``progress`` shows a tqdm bar labelled "<verb> <seconds> s".
    """
    if not (isinstance(seconds, (int, float)) and math.isfinite(seconds) and seconds >= 0):
        raise ValueError(f"seconds must be a finite number >= 0, got {seconds!r}")
    steps = round(seconds / chair.period)
    recorder = LogRecorder(chair.log_meta())
    iterator = range(steps)
    if progress:
        from tqdm.auto import tqdm

        iterator = tqdm(iterator, desc=f"{verb} {seconds:g} s", unit="step")
    log_fields = getattr(controller, "log_fields", None)
    frame = chair.read()
    for _ in iterator:
        wanted = controller(frame)
        text = log_fields() if log_fields is not None else None
        sent = pots = reason = None
        if wanted is not None:
            sent = chair.send(wanted, getattr(controller, "decided_at", None))
            pots = chair.last_command
            reason = chair.safety.reason if chair.safety is not None else None
        frame = chair.step()
        recorder.add(frame, sent, pots, wanted=wanted, safety=reason, text=text)
    return recorder.build()


class BodyMixin:
    """What every body does the same way, on top of its own ``_write`` (hand a command
    to the chair), ``step``, ``stop``, ``close`` and ``log_meta``.

    A body keeps its latest SensorFrame in ``_frame`` and calls :meth:`_init_safety`
    once its ``params`` are set; ``run_verb`` labels the progress bar of :meth:`run`
    ("simulating", "driving").
    """

    params: ChairParams
    period: float
    _frame: SensorFrame
    safety: SafetyFilter | None
    run_verb: ClassVar[str] = "driving"

    def _init_safety(self) -> None:
        """Give the body its own safety filter, of its parameters."""
        self.safety = SafetyFilter(self.params)

    @property
    def frame(self) -> SensorFrame:
        """The latest SensorFrame."""
        return self._frame

    def read(self) -> SensorFrame:
        """The latest SensorFrame (same as :attr:`frame`)."""
        return self._frame

    def send(self, command: PotCommand | Twist,
             decided_at: float | None = None) -> PotCommand | Twist:
        """Pass ``command`` (decided at ``decided_at`` s, default the latest frame's
        time) through :attr:`safety` against the latest frame, and hand what it lets
        through to the chair; it holds until replaced or until the 250 ms watchdog.
        Returns the command sent."""
        if not isinstance(command, (PotCommand, Twist)):
            raise TypeError(f"command must be a PotCommand or Twist, got "
                            f"{type(command).__name__}")
        if self.safety is not None:
            command = self.safety.apply(self._frame, command, decided_at)
        self._write(command)
        return command

    def _write(self, command: PotCommand | Twist) -> None:
        """Hand a command to the chair (each body writes its own)."""
        raise NotImplementedError(f"{type(self).__name__} must define _write(command)")

    def _stopped(self) -> None:
        """After a ``stop``: the filter's ramp starts again from standing."""
        if self.safety is not None:
            self.safety.stopped()

    def run(self, controller: Controller, seconds: float, progress: bool = False,
            safety: SafetyChoice = BODY_FILTER) -> RunLog:
        """Call ``controller(frame)`` every period for ``seconds``; send what it returns.

        The controller returns a PotCommand, a Twist, or None (send nothing: after
        250 ms the watchdog stops the chair). Every command passes the safety filter:
        the body's own (:attr:`safety`) by default, ``safety`` if given, none with
        ``safety=None`` (the bare chair, for teaching what the filter prevents).
        Returns the whole run as a RunLog.
        """
        if not (safety is BODY_FILTER or safety is None or isinstance(safety, SafetyFilter)):
            raise ValueError(f"safety must be a SafetyFilter, or None for the bare chair, "
                             f"got {safety!r}")
        own = self.safety
        if safety is not BODY_FILTER:
            self.safety = safety  # type: ignore[assignment]
        try:
            return run_controller(self, controller, seconds, progress,  # type: ignore[arg-type]
                                  verb=self.run_verb)
        finally:
            self.safety = own

    def drive(self, command: PotCommand | Twist, seconds: float,
              safety: SafetyChoice = BODY_FILTER) -> RunLog:
        """Send the same command every period for ``seconds`` (through the safety filter
        as :meth:`run` does)."""
        return self.run(lambda frame: command, seconds, safety=safety)

    def close(self) -> None:
        """Release what the body holds (nothing here); safe to call twice."""

    def __enter__(self: _Body) -> _Body:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
