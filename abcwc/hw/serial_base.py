"""SerialBase: the real chair (an Arduino Mega running ``abcwc_firmware``) over pyserial.

The same surface as :class:`abcwc.sim.SimBase`: ``send`` a PotCommand or Twist,
``step`` one 20 ms telemetry period and get a :class:`~abcwc.types.SensorFrame`,
``run(controller, seconds)`` for a :class:`~abcwc.log.RunLog`, ``drive``, ``stop``,
``set_speed_cap``, ``close`` and the context manager. It talks through a
:class:`~abcwc.hw.link.SerialLink` (the port, the codec of :mod:`abcwc.hw.protocol`
and the counters); :class:`LinkedBody` is what it shares with the firmware in the
loop (:class:`abcwc.hw.fil_base.FirmwareInLoopBase`).

Opening the port resets a real Mega (DTR) and flushes its input, so the constructor
waits for the firmware's HELLO (sent at boot and every 500 ms until the first host
frame; after ~1.6 s it also asks with HELLO_REQUEST) and checks that the firmware
speaks this library's protocol version.

Commands follow the simulator's rules: a command given to ``send`` goes out on the
next ``step`` and holds on the chair until replaced or until the chair's 250 ms
watchdog. ``step`` writes nothing when nothing new was sent, so a host that stops
commanding (a controller returning None, a crashed notebook) stops the chair.
``run`` and ``drive`` send every period.

Errors: a port that does not exist raises :class:`NoSuchPortError` listing the ports
that do; a port that will not open (permission denied, busy) :class:`PortUnusableError`;
a device that sends no HELLO :class:`NotOurFirmwareError`; firmware of another protocol
version :class:`ProtocolVersionError`. Those four are
:class:`~abcwc.devices.DeviceUnavailableError`: the chair is not there to drive, and a
real-chair cell says so and goes on. No telemetry within ``timeout`` or, once telemetry
flows, a silence of more than 0.3 s or a failing port (a cable pulled mid-run) raises a
plain :class:`ChairLinkError`.
Bad frames from the chair are counted (``SensorFrame.bad_frames``), never raised.
"""

from __future__ import annotations

import os
from collections.abc import Callable

from abcwc.base import BODY_FILTER, BodyMixin, Controller, SafetyChoice
from abcwc.control.interface_board import check_speed_cap
from abcwc.hw import protocol as P
from abcwc.hw.link import (
    STALL_LIMIT,
    ChairLinkError,
    NoSuchPortError,
    NotOurFirmwareError,
    PortUnusableError,
    ProtocolVersionError,
    SerialLink,
    list_ports,
)
from abcwc.log import RunLog
from abcwc.params import ChairParams, default_params
from abcwc.types import PotCommand, SensorFrame, Twist

__all__ = [
    "ChairLinkError",
    "LinkedBody",
    "NoSuchPortError",
    "NotOurFirmwareError",
    "PortUnusableError",
    "ProtocolVersionError",
    "SerialBase",
    "DEFAULT_SPEED_CAP",
    "SPEED_CAP_ENV",
    "STALL_LIMIT",
    "default_speed_cap",
    "list_ports",
]


SPEED_CAP_ENV = "ABCWC_SPEED_CAP"
"""Environment variable holding the hardware speed cap (pot bytes from 128)."""
DEFAULT_SPEED_CAP = 40
"""Safe default cap for course cells on the real chair: |pot - 128| <= 40, about a
third of full deflection (~0.5 m/s, ~28 deg/s)."""
PERIOD = P.TELEMETRY_PERIOD_MS / 1000.0
"""The firmware's telemetry period, s: one step."""


def default_speed_cap() -> int:
    """The cap from ``ABCWC_SPEED_CAP`` if set, else :data:`DEFAULT_SPEED_CAP`."""
    raw = os.environ.get(SPEED_CAP_ENV, "").strip()
    if not raw:
        return DEFAULT_SPEED_CAP
    try:
        value = int(raw)
    except ValueError:
        raise ValueError(f"{SPEED_CAP_ENV}={raw!r}: expected an integer 0..125 "
                         f"(pot bytes from 128)") from None
    return check_speed_cap(value)


class LinkedBody(BodyMixin):
    """A body whose commands go to the firmware through ``self.link``.

    ``send`` queues a command for the next ``step`` (it holds on the chair until
    replaced or until the chair's 250 ms watchdog); ``stop`` and ``set_speed_cap``
    are written at once; ``run`` stops the chair when it fails.
    """

    link: SerialLink
    params: ChairParams
    source: str

    @property
    def last_command(self) -> PotCommand | None:
        """The last host command as pot bytes (before the chair's clamps and cap)."""
        return self.link.last_command

    @property
    def hello(self) -> P.Hello | None:
        """The firmware's HELLO (its version and why it said hello)."""
        return self.link.hello

    @property
    def port_name(self) -> str:
        return self.link.port_name

    @property
    def speed_cap(self) -> int:
        """The firmware's speed cap in force, pot bytes from 128."""
        return self.link.speed_cap

    def _write(self, command: PotCommand | Twist) -> None:
        """Queue a command (after the safety filter) for the next ``step``; it holds on
        the chair until replaced or until the 250 ms watchdog."""
        self.link.queue(command)

    def stop(self) -> None:
        """Pots to neutral now (STOP frame, written at once)."""
        self.link.stop()
        self._stopped()

    def set_speed_cap(self, offset: int) -> None:
        """Limit host commands to 128 +- ``offset`` pot bytes (CONFIGURE, at once)."""
        self.link.set_speed_cap(offset)

    def run(self, controller: Controller, seconds: float, progress: bool = False,
            safety: SafetyChoice = BODY_FILTER,
            until: Callable[[], bool] | None = None) -> RunLog:
        """Call ``controller(frame)`` every period for ``seconds`` (or until ``until()``
        says True); send what it returns
        through the safety filter (:meth:`abcwc.base.BodyMixin.run`).

        The controller returns a PotCommand, a Twist, or None (send nothing: after
        250 ms the chair's watchdog stops it). A link failure stops the chair (if it
        can still hear) and raises ChairLinkError.
        """
        try:
            return super().run(controller, seconds, progress, safety, until)
        except BaseException:
            try:
                self.stop()
            except Exception:  # noqa: BLE001 - the link may be gone
                pass
            raise

    def log_meta(self) -> dict:
        """What a log needs to say where it came from."""
        h = self.link.hello
        return {
            "source": self.source, "port": self.link.port_name, "period": self.period,
            "start_time": self._frame.t if hasattr(self, "_frame") else 0.0,
            "firmware": h.fw_version if h else None,
            "protocol_version": P.PROTOCOL_VERSION, "speed_cap": self.link.speed_cap,
        }


class SerialBase(LinkedBody):
    """The real chair over a serial port. Same surface as :class:`abcwc.sim.SimBase`.

    Args:
        port: serial device, e.g. ``/dev/ttyACM0`` (any pyserial URL works too).
        baudrate: 115200, as the firmware.
        timeout: seconds to wait for the first telemetry frame. Once frames flow,
            a silence of 0.3 s (:data:`STALL_LIMIT`) raises ChairLinkError.
        speed_cap: largest |pot byte - 128| the chair accepts from this host
            (0..125; the joystick is never capped). ``None`` takes
            ``ABCWC_SPEED_CAP`` from the environment, or 40 pot bytes
            (:data:`DEFAULT_SPEED_CAP`, ~0.5 m/s), the safe default for course
            cells that drive the real chair.
        ready_timeout: seconds to wait for the firmware's HELLO after opening.
        params: the chair's parameters (default: ``data/chair.toml``'s, the
            thesis chair's), for code that turns counts into metres and the like.

    Frames have ``truth=None`` (no ground truth), IR ranges NaN (not wired to the
    firmware) and ``sonar`` NaN while the sonar gives no echo. ``t`` is chair time
    since the first frame; ticks are the firmware's counts, unwrapped.
    ``frame.extras`` holds the raw telemetry fields (``time_ms``, ``seq``,
    ``last_cmd_seq``, ``loops``, ``cap``, ``host_active``, ``chair_bad_frames``,
    ``host_bad_frames``, ``lost_frames``).
    """

    source = "serial"

    def __init__(
        self,
        port: str,
        baudrate: int = P.BAUD_RATE,
        timeout: float = 1.0,
        speed_cap: int | None = None,
        ready_timeout: float = 3.0,
        params: ChairParams | None = None,
    ):
        self.params = params or default_params()
        self.period = PERIOD
        self.ready_timeout = float(ready_timeout)
        cap = default_speed_cap() if speed_cap is None else check_speed_cap(speed_cap)
        self.link = SerialLink(port, baudrate, timeout)
        try:
            self.link.wait_ready(self.ready_timeout)
            self._init_safety()
            self.set_speed_cap(cap)
            self._frame = self.link.frame_from(self.link.next_telemetry(first=True))
        except BaseException:
            self.link.close_port()
            raise

    @property
    def pose(self) -> None:
        """No ground truth on the real chair."""
        return None

    def step(self) -> SensorFrame:
        """Write the pending command (if any), then block until the next telemetry
        frame (one 20 ms period) and return it as a SensorFrame."""
        self.link.flush_pending()
        self._frame = self.link.frame_from(self.link.next_telemetry())
        return self._frame

    def close(self) -> None:
        """Stop the chair and close the port (safe to call twice)."""
        self.link.close()

    def __repr__(self) -> str:
        fw = self.hello.fw_version if self.hello else "?"
        return f"SerialBase({self.port_name!r}, firmware {fw}, speed cap {self.speed_cap})"
