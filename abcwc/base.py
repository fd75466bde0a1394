"""One Base interface, two bodies: :func:`connect` picks the simulator or the chair.

Both bodies offer the same surface: ``send(PotCommand | Twist)``, ``step() ->
SensorFrame`` (one 20 ms control period), ``read()``, ``stop()``,
``set_speed_cap()``, ``run(controller, seconds) -> RunLog``, ``drive(command,
seconds)``, ``close()``, ``last_command`` and ``log_meta()``; :func:`run_controller`
is the one control loop behind every ``run``.
"""

from __future__ import annotations

import contextlib
import math
import os
from collections.abc import Callable, Iterator
from typing import Protocol, runtime_checkable

from abcwc.log import LogRecorder, RunLog
from abcwc.types import PotCommand, SensorFrame, Twist

Controller = Callable[[SensorFrame], "PotCommand | Twist | None"]


@runtime_checkable
class Base(Protocol):
    """What every chair body offers."""

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


PORT_ENV = "ABCWC_PORT"
"""Environment variable naming the real chair's serial port (or :data:`SIMAVR_PORT`)."""
SIMAVR_PORT = "simavr"
"""``ABCWC_PORT`` value for our firmware on a simulated Arduino driving the simulated chair."""
HARDWARE_CELL_CAP = 20
"""Default speed cap of a hardware cell: 128 +- 20 pot bytes, about 0.27 m/s."""


def _hardware_body(port: str, options: dict) -> Base:
    """The real chair on ``port``, or the firmware in the loop for :data:`SIMAVR_PORT`."""
    if port == SIMAVR_PORT:
        from abcwc.hw.fil_base import FirmwareInLoopBase

        return FirmwareInLoopBase(**options)  # type: ignore[arg-type]
    from abcwc.hw.serial_base import SerialBase

    return SerialBase(port, **options)  # type: ignore[arg-type]


def connect(port: str | None = None, **options: object) -> Base:
    """The chair to drive.

    * ``connect(**sim_options)`` -> the simulator (``world="lab"``, ``seed=0``,
      ``errors="worn"``; see :class:`abcwc.sim.SimBase` for all options). Simulator
      options always mean the simulator, even with ``ABCWC_PORT`` set, so a notebook's
      simulator cells never move a real chair.
    * ``connect("/dev/ttyACM0")`` -> the real chair over USB serial
      (:class:`abcwc.hw.SerialBase`; ``options`` go to it, e.g. ``speed_cap``).
    * ``connect("simavr", **sim_options)`` -> our firmware on a simulated ATmega2560
      driving the simulated chair (:class:`abcwc.hw.fil_base.FirmwareInLoopBase`).
    * ``connect()`` with no arguments -> the port in ``ABCWC_PORT`` if it is set,
      else the simulator.

    Course cells that drive the real chair use :func:`hardware_chair` instead.
    """
    if port is None and not options:
        port = os.environ.get(PORT_ENV) or None
    if port is None:
        from abcwc.sim.base import SimBase

        return SimBase(**options)  # type: ignore[arg-type]
    return _hardware_body(str(port), options)


@contextlib.contextmanager
def hardware_chair(speed_cap: int = HARDWARE_CELL_CAP, port: str | None = None,
                   **sim_options: object) -> Iterator[Base | None]:
    """The chair for a course's real-chair cell, or ``None`` (the cell is skipped).

    ``port`` (default: ``ABCWC_PORT``) picks the body:

    * unset -> prints that the cell is skipped and yields ``None``;
    * a serial port such as ``/dev/ttyACM0`` -> the real chair, with the firmware's
      speed cap set to ``speed_cap`` pot bytes from 128 (``sim_options`` ignored: a
      real room has no simulated world and no ground truth);
    * ``"simavr"`` -> our real firmware on a simulated Arduino driving the simulated
      chair built from ``sim_options`` (the test suite runs every hardware cell this
      way), with the same cap.

    On leaving the ``with`` block, normally or by an error, the chair stops and the
    link closes. Use::

        with abcwc.hardware_chair(speed_cap=20, world="lab") as real:
            if real is not None:
                log = real.drive(Twist(0.25, 0.0), seconds=4.0)
    """
    from abcwc.control.interface_board import check_speed_cap

    cap = check_speed_cap(speed_cap)
    port = port if port is not None else os.environ.get(PORT_ENV) or None
    if port is None:
        print(f"{PORT_ENV} is not set: skipping this real-chair cell. Set it to the chair's "
              f"serial port (e.g. /dev/ttyACM0), or to '{SIMAVR_PORT}' to run our firmware "
              "on a simulated Arduino.")
        yield None
        return
    options = dict(sim_options) if port == SIMAVR_PORT else {}
    chair = _hardware_body(port, {**options, "speed_cap": cap})
    try:
        from abcwc.params import default_params

        params = getattr(chair, "params", None) or default_params()
        about = f", about {cap / params.pot_full_scale_offset * params.max_speed:.2f} m/s"
        if port == SIMAVR_PORT:
            print(f"{PORT_ENV}={SIMAVR_PORT}: our firmware on a simulated Arduino (simavr) "
                  f"drives the simulated chair; speed cap 128 +- {cap} pot bytes{about}.")
        else:
            print(f"real chair on {port}: speed cap 128 +- {cap} pot bytes{about}. Keep a "
                  "hand near the joystick: it overrides every command.")
        yield chair
    finally:
        chair.close()
