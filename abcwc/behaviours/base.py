"""The one behaviour interface: frame in, command out, with a status, a rate and a cancel.

Modelled on Nav2's controllers and behaviour-tree actions: a behaviour is called with
the latest :class:`~abcwc.types.SensorFrame` every control period (50 Hz) and returns
the command to send. It reports a :class:`Status` (running, succeeded, or failed with a
reason), can be :meth:`~BehaviourBase.reset` to start over and
:meth:`~BehaviourBase.cancel`-led, and says at what rate it wants to decide
(``rate_hz``): a DWA planner or a mapper decides at 5-10 Hz inside the 50 Hz loop.

:class:`BehaviourBase` does the bookkeeping once. A behaviour writes two methods:

* ``observe(frame)``: called with *every* frame, for what must not miss one (pose
  estimators integrate every gyro sample and encoder count);
* ``update(frame) -> command``: called at ``rate_hz``; between decisions the last
  command is repeated (so the body's watchdog never sees silence).

Once the status is not running, the behaviour sends :meth:`~BehaviourBase.stop_command`
(stand still) every period. Any plain function ``frame -> command`` is still a
controller for ``Base.run``; a behaviour is a controller that also says when it is done.

A behaviour does not apply the safety filter itself: the body's control loop passes
every command through it (:mod:`abcwc.base`), stamped with the behaviour's
:attr:`~BehaviourBase.decided_at`, so a command repeated long after its decision (a
planner that stopped deciding) is stopped as stale.
"""

from __future__ import annotations

import math
from enum import Enum
from numbers import Real
from typing import Protocol, runtime_checkable

from abcwc.types import PotCommand, SensorFrame, Twist

LOOP_RATE_HZ = 50.0
"""Hz, the control loop's rate (one 20 ms period per frame)."""

_CLOCK_SLACK = 1e-6  # s: frame stamps are sums of 0.02 s, so compare with a little slack


class Status(Enum):
    """Where a behaviour stands (Nav2's RUNNING / SUCCEEDED / FAILED)."""

    RUNNING = "running"
    SUCCEEDED = "succeeded"
    FAILED = "failed"


@runtime_checkable
class Behaviour(Protocol):
    """What every behaviour offers (see :class:`BehaviourBase`)."""

    rate_hz: float

    def __call__(self, frame: SensorFrame) -> PotCommand | Twist: ...
    def reset(self) -> None: ...
    def cancel(self) -> None: ...

    @property
    def decided_at(self) -> float | None: ...

    @property
    def status(self) -> Status: ...

    @property
    def failure(self) -> str | None: ...


def positive_number(name: str, value: object, unit: str) -> float:
    """``value`` as a float if it is a finite real number > 0; ValueError saying so if not."""
    if isinstance(value, bool) or not isinstance(value, Real) or not (
            math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a finite number > 0 {unit}, got {value!r}")
    return float(value)


def finite_point(value: object, name: str = "goal") -> tuple[float, float]:
    """``value`` as an ``(x, y)`` pair of finite floats (m); ValueError saying so if not."""
    message = f"{name} must be a finite (x, y) in metres, got {value!r}"
    if isinstance(value, (str, bytes)):
        raise ValueError(message)
    try:
        x, y = value  # type: ignore[misc]
    except (TypeError, ValueError):
        raise ValueError(message) from None
    if not all(isinstance(v, Real) and not isinstance(v, bool) and math.isfinite(v)
               for v in (x, y)):
        raise ValueError(message)
    return float(x), float(y)


class BehaviourBase:
    """Status, rate, reset and cancel for a behaviour; subclasses write ``update``.

    ``rate_hz`` (Hz, > 0) is how often :meth:`update` decides, by the frames' clock; at
    the loop's rate or above it decides at every call. Subclasses call :meth:`succeed`
    or :meth:`fail` when they are done, override :meth:`observe` for what needs every frame, and
    extend :meth:`reset` (calling ``super().reset()``) to clear their own state.
    """

    def __init__(self, rate_hz: float = LOOP_RATE_HZ):
        self.rate_hz = positive_number("rate_hz", rate_hz, "Hz")
        self._status = Status.RUNNING
        self._failure: str | None = None
        self._next_decision = -math.inf
        self._last_command: PotCommand | Twist | None = None
        self._decided_at: float | None = None

    # --- what a behaviour reports
    @property
    def status(self) -> Status:
        """:class:`Status`: running, succeeded or failed."""
        return self._status

    @property
    def failure(self) -> str | None:
        """Why it failed (``"cancelled"`` after :meth:`cancel`), or None."""
        return self._failure

    @property
    def decided_at(self) -> float | None:
        """s, the frame time of the decision the latest command came from (None before
        the first): the safety filter stops a command decided too long ago."""
        return self._decided_at

    @property
    def running(self) -> bool:
        """True while the status is running."""
        return self._status is Status.RUNNING

    # --- what a subclass writes
    def observe(self, frame: SensorFrame) -> None:
        """Called with every frame before any decision; nothing by default."""

    def update(self, frame: SensorFrame) -> PotCommand | Twist:
        """The command for this frame, at ``rate_hz``; subclasses write it."""
        raise NotImplementedError(f"{type(self).__name__} must define update(frame)")

    def stop_command(self) -> PotCommand | Twist:
        """What is sent once the behaviour is not running: stand still."""
        return Twist(0.0, 0.0)

    # --- what a subclass calls
    def succeed(self) -> None:
        """Mark the behaviour succeeded; from now on it sends :meth:`stop_command`."""
        if self.running:
            self._status = Status.SUCCEEDED

    def fail(self, reason: str) -> None:
        """Mark the behaviour failed because of ``reason``; it stops the chair."""
        if not reason:
            raise ValueError("a failure needs a reason (a short sentence)")
        if self.running:
            self._status, self._failure = Status.FAILED, str(reason)

    # --- what a caller uses
    def cancel(self) -> None:
        """Stop for good (status failed, reason ``"cancelled"``); :meth:`reset` restarts."""
        self.fail("cancelled")

    def reset(self) -> None:
        """Start over: running again, the next frame decides at once."""
        self._status, self._failure = Status.RUNNING, None
        self._next_decision = -math.inf
        self._last_command = None
        self._decided_at = None

    def __call__(self, frame: SensorFrame) -> PotCommand | Twist:
        self.observe(frame)
        if not self.running:
            self._decided_at = frame.t
            return self.stop_command()
        if (self.rate_hz < LOOP_RATE_HZ and self._last_command is not None
                and frame.t + _CLOCK_SLACK < self._next_decision):
            return self._last_command
        self._decided_at = frame.t
        command = self.update(frame)
        if not self.running:  # update finished it: stop now, not a period later
            return self.stop_command()
        interval = 1.0 / self.rate_hz
        scheduled = self._next_decision + interval  # on schedule, unless the loop fell behind
        self._next_decision = (scheduled if scheduled > frame.t + _CLOCK_SLACK
                               else frame.t + interval)
        self._last_command = command
        return command
