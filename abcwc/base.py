"""One Base interface, two bodies: :func:`connect` picks the simulator or the chair.

Both bodies offer the same surface: ``send(PotCommand | Twist)``, ``step() ->
SensorFrame`` (one 20 ms control period), ``read()``, ``stop()``,
``set_speed_cap()``, ``run(controller, seconds) -> RunLog``, ``drive(command,
seconds)`` and ``close()``.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Protocol, runtime_checkable

from abcwc.log import RunLog
from abcwc.types import PotCommand, SensorFrame, Twist


@runtime_checkable
class Base(Protocol):
    """What every chair body offers."""

    period: float

    def send(self, command: PotCommand | Twist) -> None: ...
    def step(self) -> SensorFrame: ...
    def read(self) -> SensorFrame: ...
    def stop(self) -> None: ...
    def set_speed_cap(self, offset: int) -> None: ...
    def run(self, controller: Callable[[SensorFrame], PotCommand | Twist | None],
            seconds: float, progress: bool = False) -> RunLog: ...
    def drive(self, command: PotCommand | Twist, seconds: float) -> RunLog: ...
    def close(self) -> None: ...


def connect(port: str | None = None, **options: object) -> Base:
    """The chair to drive.

    ``connect()`` -> the simulator (``world="lab"``, ``seed=0``, ``errors="worn"``;
    see :class:`abcwc.sim.SimBase` for all options). ``connect("/dev/ttyACM0")``, or
    ``connect()`` with the environment variable ``ABCWC_PORT`` set, -> the real chair
    over USB serial.
    """
    port = port if port is not None else os.environ.get("ABCWC_PORT") or None
    if port is None:
        from abcwc.sim.base import SimBase

        return SimBase(**options)  # type: ignore[arg-type]
    try:
        from abcwc.hw.serial_base import SerialBase
    except ImportError as exc:  # pragma: no cover - until the hardware path lands
        raise RuntimeError(f"the real-chair link is not available in this abcwc: {exc}") from exc
    return SerialBase(port, **options)  # type: ignore[arg-type]
