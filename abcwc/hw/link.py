"""SerialLink: the host's end of the serial line to ``abcwc_firmware``.

One link is one open port plus what the host keeps about it: the frame decoder, the
sequence numbers of the frames it writes, the queue of telemetry that arrived, the
command waiting for the next period, and the running sums that turn the firmware's
wrapping counters into a :class:`~abcwc.types.SensorFrame` (time since the first
frame, unwrapped encoder counts, bad and lost frames). The wire format is in
``firmware/PROTOCOL.md``; the codec is :mod:`abcwc.hw.protocol`.

Both hardware bodies talk through a link: :class:`abcwc.hw.serial_base.SerialBase`
(a real chair, time on the wall clock) and
:class:`abcwc.hw.fil_base.FirmwareInLoopBase` (the firmware on simavr, time advanced
by the host).
"""

from __future__ import annotations

import errno
import functools
import math
import operator
import os
import re
import time
from collections import deque

import numpy as np

from abcwc.control.interface_board import check_speed_cap
from abcwc.control.velocity import twist_to_pot_command, twist_to_wire_units
from abcwc.devices import DeviceUnavailableError
from abcwc.hw import protocol as P
from abcwc.types import PotCommand, SensorFrame, StatusFlags, Twist

__all__ = [
    "ChairLinkError",
    "NoSuchPortError",
    "NotOurFirmwareError",
    "PortUnusableError",
    "ProtocolVersionError",
    "SerialLink",
    "STALL_LIMIT",
    "list_ports",
]

STALL_LIMIT = 0.3
"""Once telemetry flows, this long (s) without a frame means the link is gone."""
BOOT_WAIT = 1.6
"""The Mega's bootloader runs ~1.5 s after the port opens; ask for HELLO after it."""
MAX_BACKLOG = 3
"""If more telemetry frames than this are waiting, skip to the newest."""
KNOWN_FLAGS = functools.reduce(operator.or_, StatusFlags, StatusFlags.NONE)
"""Every status bit this library knows; a frame's other bits stay in ``raw_flags``."""


class ChairLinkError(ConnectionError):
    """The serial link to the chair failed: no port, no answer, or it went away.

    The subclasses that are also a :class:`~abcwc.devices.DeviceUnavailableError` say
    the chair is not there to talk to; a plain ChairLinkError is a link that failed
    while in use."""


class NoSuchPortError(ChairLinkError, FileNotFoundError, DeviceUnavailableError):
    """The serial port does not exist (the message lists the ones that do)."""


class PortUnusableError(ChairLinkError, DeviceUnavailableError):
    """The serial port exists but would not open: permission denied (the message says
    how to join the ``dialout`` group), or another program holds it."""


class NotOurFirmwareError(ChairLinkError, DeviceUnavailableError):
    """Something is on the port, but it does not answer as ``abcwc_firmware`` (no HELLO
    in time): another board, another sketch, or the wrong baud rate."""


class ProtocolVersionError(ChairLinkError, DeviceUnavailableError):
    """The firmware speaks another protocol version than this library."""


def list_ports() -> list[str]:
    """Serial ports present on this machine, with their descriptions."""
    try:
        from serial.tools import list_ports as lp

        return [f"{p.device} ({p.description})" if p.description and p.description != "n/a"
                else p.device for p in sorted(lp.comports(), key=lambda p: p.device)]
    except Exception:  # noqa: BLE001 - listing is best effort
        return []


def _no_port_message(port: str, why: str) -> str:
    ports = list_ports()
    found = ("ports on this machine: " + ", ".join(ports)) if ports \
        else "no serial ports found on this machine (is the chair's USB cable plugged in?)"
    return f"serial port {port!r} {why}; {found}"


def _open_port(port: str, baudrate: int):
    """The pyserial port; NoSuchPortError listing the ports there are, or
    PortUnusableError saying why an existing port would not open."""
    import serial

    is_url = "://" in port
    if not is_url and not os.path.exists(port) and not re.match(r"(?i)^COM\d+$", port):
        raise NoSuchPortError(_no_port_message(port, "does not exist"))
    try:
        return serial.Serial(port, baudrate, timeout=0.005, write_timeout=0.5)
    except serial.SerialException as exc:
        if exc.errno in (errno.ENOENT, errno.ENODEV, errno.ENXIO):  # gone since the check
            message = _no_port_message(port, f"could not be opened: {exc}")
            raise NoSuchPortError(message) from exc
        if exc.errno in (errno.EACCES, errno.EPERM):
            why = ("permission denied: add yourself to the group that owns it, on Debian "
                   "'sudo usermod -aG dialout $USER', then log out and in again")
        else:
            why = f"{exc}; is another program (a serial monitor?) using it?"
        raise PortUnusableError(f"serial port {port!r} could not be opened: {why}") from exc


def _command_message(command: PotCommand | Twist) -> tuple[type, dict, PotCommand]:
    """The wire message for a command and the pot bytes it asks for."""
    if isinstance(command, Twist):
        v, w = twist_to_wire_units(command)
        return P.SetTwist, {"v_mm_s": v, "w_mrad_s": w}, twist_to_pot_command(command)
    if isinstance(command, PotCommand):
        return P.SetPots, {"fb": command.fb, "lr": command.lr}, command
    raise TypeError(f"command must be a PotCommand or Twist, got {type(command).__name__}")


class SerialLink:
    """An open serial port to ``abcwc_firmware`` and the host's state about it.

    Args:
        port: serial device, e.g. ``/dev/ttyACM0`` (any pyserial URL works too).
        baudrate: 115200, as the firmware.
        timeout: seconds to wait for a telemetry frame before the stream has
            started; once frames flow, a silence of :data:`STALL_LIMIT` raises.

    Attributes:
        hello: the firmware's HELLO once :meth:`wait_ready` (or :meth:`hello_in`)
            saw it.
        last_command: the last command queued, as pot bytes (before the chair's
            clamps and cap).
        speed_cap: the cap last configured (pot bytes from 128).
        bytes_sent, bytes_received: bytes written to and read from the port.
        telemetry: telemetry frames received and not yet taken.
    """

    def __init__(self, port: str, baudrate: int = P.BAUD_RATE, timeout: float = 1.0):
        self.port_name = str(port)
        self.baudrate = baudrate
        self.timeout = float(timeout)
        self.hello: P.Hello | None = None
        self.last_command: PotCommand | None = None
        self.speed_cap = P.POT_MAX_OFFSET
        self.bytes_sent = 0
        self.bytes_received = 0
        self.telemetry: deque[P.Telemetry] = deque()
        self.closed = False
        self._decoder = P.FrameDecoder()
        self._seq = 0
        self._pending: tuple[type, dict] | None = None
        self._streaming = False
        # running sums for unwrapping the firmware's counters (frame_from)
        self._first: P.Telemetry | None = None
        self._prev: P.Telemetry | None = None
        self._t_ms = 0
        self._ticks = [0, 0]
        self._chair_bad = 0
        self._lost = 0
        self._serial = _open_port(self.port_name, baudrate)

    # ----------------------------------------------------------------- bytes
    def link_error(self, what: str, exc: BaseException | None = None) -> ChairLinkError:
        """A ChairLinkError naming this port."""
        return ChairLinkError(f"chair link on {self.port_name}: {what}"
                              + (f" ({exc})" if exc else ""))

    def write(self, data: bytes) -> None:
        """Write raw bytes to the port."""
        if self._serial is None:
            raise self.link_error("the port is closed")
        try:
            self._serial.write(data)
        except Exception as exc:  # noqa: BLE001 - SerialException, OSError, timeouts
            raise self.link_error("writing failed; is the cable unplugged?", exc) from exc
        self.bytes_sent += len(data)

    def write_msg(self, cls: type, **fields: int) -> None:
        """Encode and write one message with the next sequence number."""
        data = P.encode(cls(seq=self._seq & 0xFF, **fields))
        self._seq += 1
        self.write(data)

    def read_bytes(self) -> bytes:
        """Whatever has arrived (waits up to the port's 5 ms read timeout)."""
        if self._serial is None:
            raise self.link_error("the port is closed")
        try:
            data = self._serial.read(max(1, self._serial.in_waiting))
        except Exception as exc:  # noqa: BLE001
            raise self.link_error("reading failed; is the cable unplugged?", exc) from exc
        self.bytes_received += len(data)
        return data

    def feed(self, data: bytes) -> list[P.Message]:
        """Decode bytes; queue the telemetry among them; return every message."""
        if not data:
            return []
        messages = self._decoder.feed(data)
        self.telemetry.extend(m for m in messages if isinstance(m, P.Telemetry))
        return messages

    def receive_until(self, total: int, timeout: float) -> list[P.Message]:
        """Read until :attr:`bytes_received` reaches ``total``; decode what came.

        Raises:
            ChairLinkError: fewer bytes arrived within ``timeout`` wall seconds.
        """
        deadline = time.monotonic() + timeout
        data = bytearray()
        while self.bytes_received < total:
            chunk = self.read_bytes()
            data += chunk
            if not chunk and time.monotonic() > deadline:
                raise ChairLinkError(f"{total} bytes were written to {self.port_name}, "
                                     f"only {self.bytes_received} arrived")
        return self.feed(bytes(data))

    # ----------------------------------------------------------------- handshake
    def version_error(self, version: int) -> ProtocolVersionError:
        """The error for firmware that speaks protocol ``version``."""
        return ProtocolVersionError(
            f"the chair on {self.port_name} speaks protocol version {version}, this abcwc "
            f"speaks version {P.PROTOCOL_VERSION}: flash the firmware that matches this "
            f"library (make -C firmware flash) or install the matching abcwc")

    def ask_hello(self) -> None:
        """Ask for a HELLO (after a zero that ends half a frame in the chair's buffer)."""
        self.write(b"\x00")
        self.write_msg(P.HelloRequest)

    def hello_in(self, messages: list[P.Message]) -> P.Hello | None:
        """The first HELLO among ``messages`` (kept in :attr:`hello`), or None.

        What came before it is dropped: stale telemetry, and the bad frames of
        joining the stream mid-frame.

        Raises:
            ProtocolVersionError: the HELLO, or any frame the decoder rejected,
                carries another protocol version.
        """
        for msg in messages:
            if isinstance(msg, P.Hello):
                if msg.protocol_version != P.PROTOCOL_VERSION:
                    raise self.version_error(msg.protocol_version)
                self.telemetry.clear()
                self._decoder.bad_frames = 0  # joining mid-frame is not an error
                self.hello = msg
                return msg
        if self._decoder.other_versions:
            raise self.version_error(min(self._decoder.other_versions))
        return None

    def wait_ready(self, ready_timeout: float) -> P.Hello:
        """Wait (wall clock) for HELLO, asking for it after the bootloader's time."""
        start = time.monotonic()
        asked_at = None
        while True:
            now = time.monotonic()
            hello = self.hello_in(self.feed(self.read_bytes()))
            if hello is not None:
                return hello
            if now - start > ready_timeout:
                raise NotOurFirmwareError(
                    f"the device on {self.port_name} does not answer as abcwc_firmware: no "
                    f"HELLO within {ready_timeout:g} s ({self._decoder.bad_frames} bad frames "
                    f"received); flash it (make -C firmware flash) or pick the chair's port, "
                    f"and check the baud rate is {self.baudrate}")
            if now - start > min(BOOT_WAIT, ready_timeout / 2) and (
                    asked_at is None or now - asked_at > 0.5):
                self.ask_hello()
                asked_at = now

    # ----------------------------------------------------------------- telemetry
    def next_telemetry(self, first: bool = False) -> P.Telemetry:
        """Block (wall clock) until a telemetry frame is there, skipping a long backlog."""
        limit = self.timeout if (first or not self._streaming) else min(self.timeout,
                                                                       STALL_LIMIT)
        since = time.monotonic()
        while not self.telemetry:
            data = self.read_bytes()
            now = time.monotonic()
            if data and self.feed(data):
                since = now
            if not self.telemetry and now - since > limit:
                raise self.link_error(
                    f"no telemetry for {now - since:.2f} s"
                    + ("; the cable was pulled or the chair lost power?" if self._streaming
                       else "; is abcwc_firmware running?"))
        while len(self.telemetry) > MAX_BACKLOG:
            self.telemetry.popleft()
        self._streaming = True
        return self.telemetry.popleft()

    def frame_from(self, tel: P.Telemetry) -> SensorFrame:
        """Turn a telemetry message into a SensorFrame, unwrapping its counters.

        ``t`` is chair time since the first frame; ticks are the firmware's counts,
        unwrapped; ``pose`` is None (no ground truth), IR ranges NaN (not wired to
        the firmware) and ``sonar`` NaN while the sonar gives no echo.
        """
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
        sonar = tel.sonar_m
        extras = {
            "time_ms": tel.time_ms, "seq": tel.seq, "last_cmd_seq": tel.last_cmd_seq,
            "loops": tel.loops, "cap": (tel.cap_fb, tel.cap_lr),
            "host_active": bool(tel.flags & StatusFlags.HOST_ACTIVE), "raw_flags": tel.flags,
            "chair_bad_frames": self._chair_bad, "host_bad_frames": self._decoder.bad_frames,
            "lost_frames": self._lost,
        }
        return SensorFrame(
            t=self._t_ms / 1000.0, ticks_left=self._ticks[0], ticks_right=self._ticks[1],
            gyro_z=tel.gyro_z_rad_s, sonar=math.nan if sonar is None else sonar,
            ir=np.full(6, np.nan), joystick_fb=tel.joy_fb, joystick_lr=tel.joy_lr,
            pot_fb=tel.pot_fb, pot_lr=tel.pot_lr, flags=StatusFlags(tel.flags & KNOWN_FLAGS),
            bad_frames=self._chair_bad + self._decoder.bad_frames, extras=extras,
        )

    # ----------------------------------------------------------------- commands
    def queue(self, command: PotCommand | Twist) -> None:
        """Hold a command for :meth:`flush_pending` (the next period)."""
        cls, fields, pots = _command_message(command)
        self._pending = (cls, fields)
        self.last_command = pots

    def flush_pending(self) -> None:
        """Write the queued command, if there is one."""
        if self._pending is not None:
            cls, fields = self._pending
            self._pending = None
            self.write_msg(cls, **fields)

    def stop(self) -> None:
        """Pots to neutral now (STOP frame, written at once)."""
        self._pending = None
        self.last_command = PotCommand(P.POT_NEUTRAL, P.POT_NEUTRAL)
        self.write_msg(P.Stop)

    def set_speed_cap(self, offset: int) -> None:
        """Limit host commands to 128 +- ``offset`` pot bytes (CONFIGURE, at once)."""
        offset = check_speed_cap(offset)
        self.write_msg(P.Configure, cap_fb=offset, cap_lr=offset, telemetry_period_ms=0)
        self.speed_cap = offset

    # ----------------------------------------------------------------- closing
    def close_port(self) -> None:
        """Close the port without a word to the chair (safe to call twice)."""
        if self._serial is not None:
            try:
                self._serial.close()
            except Exception:  # noqa: BLE001 - closing a dead port
                pass
            self._serial = None

    def close(self) -> None:
        """Stop the chair and close the port (safe to call twice)."""
        if self.closed:
            return
        self.closed = True
        if self._serial is not None:
            try:
                self.stop()
                self._serial.flush()
            except Exception:  # noqa: BLE001 - the link may be gone
                pass
        self.close_port()
