"""Pick a chair body: :func:`connect` and a course cell's :func:`hardware_chair`.

``connect()`` gives the simulator (:class:`abcwc.sim.SimBase`), ``connect(port)`` the
real chair over USB serial (:class:`abcwc.hw.serial_base.SerialBase`) and
``connect("simavr")`` our firmware on a simulated Arduino driving the simulated chair
(:class:`abcwc.hw.fil_base.FirmwareInLoopBase`); all three are a
:class:`abcwc.base.Base`. The bodies are imported only when asked for.

The package exports these names, so ``abcwc.connect`` is the function: import from
this module with ``from abcwc.connect import ...`` (not ``import abcwc.connect as m``).
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator

from abcwc.base import Base
from abcwc.devices import DeviceUnavailableError

__all__ = ["HARDWARE_CELL_CAP", "PORT_ENV", "SIMAVR_PORT", "connect", "hardware_chair"]


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
      chair built from ``sim_options`` (the test suite runs every solution's hardware
      cell this way), with the same cap.

    A device that is not there never crashes the cell: when the body cannot be opened
    for want of one (no such port, permission denied, not our firmware, no AVR
    toolchain or simavr), the message of its
    :class:`~abcwc.devices.DeviceUnavailableError` is printed and ``None`` yielded; when
    the block itself raises one (the microphone of chapter 04, say), the chair stops,
    the message is printed and the cell goes on after the block. Any other error
    propagates. On leaving the ``with`` block, normally or by an error, the chair stops
    and the link closes. Use::

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
    try:
        chair = _hardware_body(port, {**options, "speed_cap": cap})
    except DeviceUnavailableError as missing:
        print(f"Skipping this real-chair cell: {missing}")
        yield None
        return
    try:
        params = chair.params
        about = f", about {cap / params.pot_full_scale_offset * params.max_speed:.2f} m/s"
        if port == SIMAVR_PORT:
            print(f"{PORT_ENV}={SIMAVR_PORT}: our firmware on a simulated Arduino (simavr) "
                  f"drives the simulated chair; speed cap 128 +- {cap} pot bytes{about}.")
        else:
            print(f"real chair on {port}: speed cap 128 +- {cap} pot bytes{about}. Keep a "
                  "hand near the joystick: it overrides every command.")
        yield chair
    except DeviceUnavailableError as missing:
        print(f"Stopped this real-chair cell: {missing}")
    finally:
        chair.close()
