"""SerialBase: the real chair (an Arduino Mega running ``abcwc_firmware``) over pyserial.

The same surface as :class:`abcwc.sim.SimBase`: ``send`` a PotCommand or Twist,
``step`` one 20 ms telemetry period and get a :class:`~abcwc.types.SensorFrame`,
``run(controller, seconds)`` for a :class:`~abcwc.log.RunLog`, ``drive``, ``stop``,
``set_speed_cap``, ``close`` and the context manager. The wire format is in
``firmware/PROTOCOL.md``; the codec is :mod:`abcwc.hw.protocol`.

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
that do; firmware of another protocol version raises :class:`ProtocolVersionError`;
no telemetry within ``timeout`` or, once telemetry flows, a silence of more than
0.3 s or a failing port (a cable pulled mid-run) raises :class:`ChairLinkError`.
Bad frames from the chair are counted (``SensorFrame.bad_frames``), never raised.
"""

from __future__ import annotations

import math
import os
import re
import time
from collections import deque

import numpy as np

from abcwc.base import Controller, run_controller
from abcwc.control.interface_board import check_speed_cap
from abcwc.control.velocity import twist_to_pot_command, twist_to_wire_units
from abcwc.hw import protocol as P
from abcwc.log import RunLog
from abcwc.params import ChairParams, default_params
from abcwc.types import PotCommand, SensorFrame, StatusFlags, Twist

__all__ = [
    "ChairLinkError",
    "NoSuchPortError",
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
STALL_LIMIT = 0.3
"""Once telemetry flows, this long (s) without a frame means the link is gone."""
BOOT_WAIT = 1.6
"""The Mega's bootloader runs ~1.5 s after the port opens; ask for HELLO after it."""
PERIOD = P.TELEMETRY_PERIOD_MS / 1000.0
MAX_BACKLOG = 3
"""If more telemetry frames than this are waiting, ``step`` skips to the newest."""

# Firmware flag bits that mean the same as StatusFlags bits.
_SHARED_FLAGS = (
    (P.Flag.JOYSTICK_OVERRIDE, StatusFlags.JOYSTICK_OVERRIDE),
    (P.Flag.WATCHDOG_TRIPPED, StatusFlags.WATCHDOG_TRIPPED),
    (P.Flag.JOYSTICK_FAULT, StatusFlags.JOYSTICK_FAULT),
    (P.Flag.IMU_FAULT, StatusFlags.IMU_FAULT),
    (P.Flag.SPEED_CAPPED, StatusFlags.SPEED_CAPPED),
    (P.Flag.HOST_ACTIVE, StatusFlags.HOST_ACTIVE),
)


class ChairLinkError(ConnectionError):
    """The serial link to the chair failed: no port, no answer, or it went away."""


class NoSuchPortError(ChairLinkError, FileNotFoundError):
    """The serial port does not exist (the message lists the ones that do)."""


class ProtocolVersionError(ChairLinkError):
    """The firmware speaks another protocol version than this library."""


def list_ports() -> list[str]:
    """Serial ports present on this machine, with their descriptions."""
    try:
        from serial.tools import list_ports as lp

        return [f"{p.device} ({p.description})" if p.description and p.description != "n/a"
                else p.device for p in sorted(lp.comports(), key=lambda p: p.device)]
    except Exception:  # noqa: BLE001 - listing is best effort
        return []


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


def _command_message(command: PotCommand | Twist) -> tuple[type, dict, PotCommand]:
    """The wire message for a command and the pot bytes it asks for."""
    if isinstance(command, Twist):
        v, w = twist_to_wire_units(command)
        return P.SetTwist, {"v_mm_s": v, "w_mrad_s": w}, twist_to_pot_command(command)
    if isinstance(command, PotCommand):
        return P.SetPots, {"fb": command.fb, "lr": command.lr}, command
    raise TypeError(f"command must be a PotCommand or Twist, got {type(command).__name__}")


class SerialBase:
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

    Frames have ``pose=None`` (no ground truth), IR ranges NaN (not wired to the
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
        self.port_name = str(port)
        self.baudrate = baudrate
        self.timeout = float(timeout)
        self.ready_timeout = float(ready_timeout)
        self.period = PERIOD
        self._init_state()
        cap = default_speed_cap() if speed_cap is None else check_speed_cap(speed_cap)
        self._serial = self._open_port(self.port_name, baudrate)
        try:
            self.hello = self._wait_ready()
            self.set_speed_cap(cap)
            self._frame = self._frame_from(self._next_telemetry(first=True))
        except BaseException:
            self._close_port()
            raise

    # ----------------------------------------------------------------- plumbing
    def _init_state(self) -> None:
        self._decoder = P.FrameDecoder()
        self._seq = 0
        self._pending: tuple[type, dict] | None = None
        self._last_command: PotCommand | None = None
        self._telemetry: deque[P.Telemetry] = deque()
        self._seen_versions: set[int] = set()
        self._last_rx = time.monotonic()
        self._streaming = False
        self._closed = False
        self._first: P.Telemetry | None = None
        self._prev: P.Telemetry | None = None
        self._t_ms = 0
        self._ticks = [0, 0]
        self._chair_bad = 0
        self._lost = 0
        self.speed_cap = P.POT_MAX_OFFSET
        self.hello: P.Hello | None = None
        self._serial = None

    def _open_port(self, port: str, baudrate: int):
        import serial

        is_url = "://" in port
        if not is_url and not os.path.exists(port) and not re.match(r"(?i)^COM\d+$", port):
            raise NoSuchPortError(self._no_port_message(port, "does not exist"))
        try:
            return serial.Serial(port, baudrate, timeout=0.005, write_timeout=0.5)
        except serial.SerialException as exc:
            raise NoSuchPortError(self._no_port_message(port, f"could not be opened: {exc}")) \
                from exc

    @staticmethod
    def _no_port_message(port: str, why: str) -> str:
        ports = list_ports()
        found = ("ports on this machine: " + ", ".join(ports)) if ports \
            else "no serial ports found on this machine (is the chair's USB cable plugged in?)"
        return f"serial port {port!r} {why}; {found}"

    def _link_error(self, what: str, exc: BaseException | None = None) -> ChairLinkError:
        return ChairLinkError(f"chair link on {self.port_name}: {what}"
                              + (f" ({exc})" if exc else ""))

    def _write_msg(self, cls: type, **fields: int) -> None:
        data = P.encode(cls(seq=self._seq & 0xFF, **fields))
        self._seq += 1
        self._write(data)

    def _write(self, data: bytes) -> None:
        if self._serial is None:
            raise self._link_error("the port is closed")
        try:
            self._serial.write(data)
        except Exception as exc:  # noqa: BLE001 - SerialException, OSError, timeouts
            raise self._link_error("writing failed; is the cable unplugged?", exc) from exc

    def _read_bytes(self) -> bytes:
        """Whatever has arrived (waits up to the port's 5 ms read timeout)."""
        if self._serial is None:
            raise self._link_error("the port is closed")
        try:
            n = self._serial.in_waiting
            return self._serial.read(max(1, n))
        except Exception as exc:  # noqa: BLE001
            raise self._link_error("reading failed; is the cable unplugged?", exc) from exc

    def _feed(self, data: bytes) -> list:
        """Decode bytes; queue telemetry; note the versions of rejected frames."""
        if not data:
            return []
        before = self._decoder.bad_frames
        messages = self._decoder.feed(data)
        if self._decoder.bad_frames != before and self._decoder.last_error:
            m = re.match(r"protocol version (\d+)", self._decoder.last_error)
            if m:
                self._seen_versions.add(int(m.group(1)))
        for msg in messages:
            if isinstance(msg, P.Telemetry):
                self._telemetry.append(msg)
        return messages

    def _version_error(self, version: int) -> ProtocolVersionError:
        return ProtocolVersionError(
            f"the chair on {self.port_name} speaks protocol version {version}, this abcwc "
            f"speaks version {P.PROTOCOL_VERSION}: flash the firmware that matches this "
            f"library (make -C firmware flash) or install the matching abcwc")

    def _wait_ready(self) -> P.Hello:
        """Wait for HELLO (asking for it after the bootloader's time); check versions."""
        start = time.monotonic()
        asked_at = None
        while True:
            now = time.monotonic()
            for msg in self._feed(self._read_bytes()):
                if isinstance(msg, P.Hello):
                    if msg.protocol_version != P.PROTOCOL_VERSION:
                        raise self._version_error(msg.protocol_version)
                    self._telemetry.clear()
                    self._decoder.bad_frames = 0  # joining mid-frame is not an error
                    return msg
            if self._seen_versions:
                raise self._version_error(min(self._seen_versions))
            if now - start > self.ready_timeout:
                raise self._link_error(
                    f"no HELLO from the firmware within {self.ready_timeout:g} s "
                    f"({self._decoder.bad_frames} bad frames received); is abcwc_firmware "
                    f"flashed and the baud rate {self.baudrate}?")
            if now - start > min(BOOT_WAIT, self.ready_timeout / 2) and (
                    asked_at is None or now - asked_at > 0.5):
                self._write(b"\x00")  # flush half a frame in the chair's buffer
                self._write_msg(P.HelloRequest)
                asked_at = now

    def _next_telemetry(self, first: bool = False) -> P.Telemetry:
        """Block until a telemetry frame is there (skipping a long backlog)."""
        limit = self.timeout if (first or not self._streaming) else min(self.timeout,
                                                                       STALL_LIMIT)
        since = time.monotonic()
        while not self._telemetry:
            data = self._read_bytes()
            now = time.monotonic()
            if data and self._feed(data):
                since = now
            if not self._telemetry and now - since > limit:
                raise self._link_error(
                    f"no telemetry for {now - since:.2f} s"
                    + ("; the cable was pulled or the chair lost power?" if self._streaming
                       else "; is abcwc_firmware running?"))
        while len(self._telemetry) > MAX_BACKLOG:
            self._telemetry.popleft()
        self._streaming = True
        self._last_rx = time.monotonic()
        return self._telemetry.popleft()

    def _frame_from(self, tel: P.Telemetry, **extra: object) -> SensorFrame:
        """Turn a telemetry message into a SensorFrame (unwrapping counters)."""
        if self._first is None:
            self._first = self._prev = tel
            self._ticks = [tel.enc_left, tel.enc_right]
            self._chair_bad = tel.bad_frames
        else:
            prev = self._prev
            self._t_ms += (tel.time_ms - prev.time_ms) & 0xFFFFFFFF
            self._ticks[0] += P.tick_delta(tel.enc_left, prev.enc_left)
            self._ticks[1] += P.tick_delta(tel.enc_right, prev.enc_right)
            self._chair_bad += (tel.bad_frames - prev.bad_frames) & 0xFFFF
            self._lost += max(0, ((tel.seq - prev.seq) & 0xFF) - 1)
            self._prev = tel
        flags = StatusFlags.NONE
        for bit, flag in _SHARED_FLAGS:
            if tel.flags & bit:
                flags |= flag
        sonar = tel.sonar_m
        extras = {
            "time_ms": tel.time_ms, "seq": tel.seq, "last_cmd_seq": tel.last_cmd_seq,
            "loops": tel.loops, "cap": (tel.cap_fb, tel.cap_lr),
            "host_active": bool(tel.flags & P.Flag.HOST_ACTIVE), "raw_flags": tel.flags,
            "chair_bad_frames": self._chair_bad, "host_bad_frames": self._decoder.bad_frames,
            "lost_frames": self._lost,
        }
        extras.update(extra.pop("extras", {}))
        return SensorFrame(
            t=self._t_ms / 1000.0, ticks_left=self._ticks[0], ticks_right=self._ticks[1],
            gyro_z=tel.gyro_z_rad_s, sonar=math.nan if sonar is None else sonar,
            ir=np.full(6, np.nan), joystick_fb=tel.joy_fb, joystick_lr=tel.joy_lr,
            pot_fb=tel.pot_fb, pot_lr=tel.pot_lr, flags=flags,
            bad_frames=self._chair_bad + self._decoder.bad_frames, extras=extras, **extra,
        )

    def _close_port(self) -> None:
        if self._serial is not None:
            try:
                self._serial.close()
            except Exception:  # noqa: BLE001 - closing a dead port
                pass
            self._serial = None

    # ----------------------------------------------------------------- state
    @property
    def pose(self) -> None:
        """No ground truth on the real chair."""
        return None

    @property
    def frame(self) -> SensorFrame:
        """The latest SensorFrame."""
        return self._frame

    def read(self) -> SensorFrame:
        """The latest SensorFrame (same as :attr:`frame`)."""
        return self._frame

    @property
    def last_command(self) -> PotCommand | None:
        """The last host command as pot bytes (before the chair's clamps and cap)."""
        return self._last_command

    # ----------------------------------------------------------------- commands
    def send(self, command: PotCommand | Twist) -> None:
        """Queue a command for the next ``step``; it holds on the chair until
        replaced or until the 250 ms watchdog."""
        cls, fields, pots = _command_message(command)
        self._pending = (cls, fields)
        self._last_command = pots

    def stop(self) -> None:
        """Pots to neutral now (STOP frame, written at once)."""
        self._pending = None
        self._last_command = PotCommand(P.POT_NEUTRAL, P.POT_NEUTRAL)
        self._write_msg(P.Stop)

    def set_speed_cap(self, offset: int) -> None:
        """Limit host commands to 128 +- ``offset`` pot bytes (CONFIGURE, at once)."""
        offset = check_speed_cap(offset)
        self._write_msg(P.Configure, cap_fb=offset, cap_lr=offset, telemetry_period_ms=0)
        self.speed_cap = offset

    # ----------------------------------------------------------------- stepping
    def _flush_pending(self) -> None:
        if self._pending is not None:
            cls, fields = self._pending
            self._pending = None
            self._write_msg(cls, **fields)

    def step(self) -> SensorFrame:
        """Write the pending command (if any), then block until the next telemetry
        frame (one 20 ms period) and return it as a SensorFrame."""
        self._flush_pending()
        self._frame = self._frame_from(self._next_telemetry())
        return self._frame

    def run(self, controller: Controller, seconds: float, progress: bool = False) -> RunLog:
        """Call ``controller(frame)`` every period for ``seconds``; send what it returns.

        The controller returns a PotCommand, a Twist, or None (send nothing: after
        250 ms the chair's watchdog stops it). A link failure stops the chair (if it
        can still hear) and raises ChairLinkError.
        """
        try:
            return run_controller(self, controller, seconds, progress, verb="driving")
        except BaseException:
            try:
                self.stop()
            except Exception:  # noqa: BLE001 - the link may be gone
                pass
            raise

    def drive(self, command: PotCommand | Twist, seconds: float) -> RunLog:
        """Send the same command every period for ``seconds``."""
        return self.run(lambda frame: command, seconds)

    def log_meta(self) -> dict:
        """What a log needs to say where it came from."""
        h = self.hello
        return {
            "source": self.source, "port": self.port_name, "period": self.period,
            "start_time": self._frame.t if hasattr(self, "_frame") else 0.0,
            "firmware": h.fw_version if h else None,
            "protocol_version": P.PROTOCOL_VERSION, "speed_cap": self.speed_cap,
        }

    def close(self) -> None:
        """Stop the chair and close the port (safe to call twice)."""
        if self._closed:
            return
        self._closed = True
        if self._serial is not None:
            try:
                self.stop()
                self._serial.flush()
            except Exception:  # noqa: BLE001 - the link may be gone
                pass
        self._close_port()

    def __enter__(self) -> SerialBase:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        fw = self.hello.fw_version if self.hello else "?"
        return f"SerialBase({self.port_name!r}, firmware {fw}, speed cap {self.speed_cap})"
