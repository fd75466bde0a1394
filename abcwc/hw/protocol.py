"""The abcwc serial protocol between a host and the chair's Arduino.

The Python twin of ``firmware/core/protocol.c``; the byte layout is described in
``firmware/PROTOCOL.md`` and the two implementations are cross-checked by
``tests/firmware``.

A frame before stuffing is ``version, type, seq, payload..., crc16`` where the
CRC-16/CCITT-FALSE (polynomial 0x1021, initial value 0xFFFF) covers
version..payload and is sent little-endian. On the wire each frame is
COBS-encoded (Cheshire & Baker, 1999) and followed by one ``0x00`` delimiter.
All multi-byte fields are little-endian. The link runs at 115200 baud, 8N1.

The pot maps and the integer velocity controller that the firmware runs live in
:mod:`abcwc.control` (``twist_to_pot_bytes_int``, ``joystick_adc_to_pot_byte``,
``cap_pot_byte``), so the simulator and the chair turn a twist into exactly the
same pot bytes; ``tests/firmware`` checks them against the C core.

Example::

    >>> frame = encode(SetTwist(seq=7, v_mm_s=500, w_mrad_s=-300))
    >>> frame.hex(" ")
    '0a 01 03 07 f4 01 d4 fe 25 55 00'
    >>> FrameDecoder().feed(frame)
    [SetTwist(seq=7, v_mm_s=500, w_mrad_s=-300)]
"""

from __future__ import annotations

import binascii
import struct
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from enum import IntEnum
from typing import Any, ClassVar

from abcwc.geometry import wrap_tick_delta

__all__ = [
    "PROTOCOL_VERSION",
    "BAUD_RATE",
    "MsgType",
    "HelloReason",
    "POT_NEUTRAL",
    "JOY_CENTRE",
    "POT_MAX_OFFSET",
    "TELEMETRY_PERIOD_MS",
    "GYRO_LSB_PER_DEG_S",
    "Heartbeat",
    "SetPots",
    "SetTwist",
    "Stop",
    "Configure",
    "HelloRequest",
    "Hello",
    "Telemetry",
    "Message",
    "ProtocolError",
    "VersionMismatch",
    "crc16",
    "cobs_encode",
    "cobs_decode",
    "encode",
    "decode_frame",
    "FrameDecoder",
    "tick_delta",
]

PROTOCOL_VERSION = 1
BAUD_RATE = 115200

# --- the firmware's constants (firmware/core/pots.h, chair_core.h); they agree with
# data/chair.toml (tests/test_protocol.py checks both)
POT_NEUTRAL = 128
"""Pot byte for no motion on either channel."""
POT_MAX_OFFSET = 125
"""Largest |pot byte - 128|: a speed cap of this many bytes is no cap."""
JOY_CENTRE = 254
"""Joystick ADC reading at rest, on the thesis's "pot scale"."""
TELEMETRY_PERIOD_MS = 20
"""Default telemetry period, ms (50 Hz), the control period."""
GYRO_LSB_PER_DEG_S = 65.5
"""MPU9250 gyro scale at +-500 deg/s: raw counts per deg/s."""


class MsgType(IntEnum):
    """Message type bytes. Host -> chair are below 0x80, chair -> host above."""

    HEARTBEAT = 0x01
    SET_POTS = 0x02
    SET_TWIST = 0x03
    STOP = 0x04
    CONFIGURE = 0x05
    HELLO_REQUEST = 0x06
    HELLO = 0x81
    TELEMETRY = 0x82


class HelloReason(IntEnum):
    """Why the chair sent a HELLO."""

    BOOT = 0
    REQUEST = 1
    PERIODIC = 2


class ProtocolError(ValueError):
    """A frame or a field value that the protocol does not allow."""


class VersionMismatch(ProtocolError):
    """A well-formed frame of another protocol version (``version`` holds it)."""

    def __init__(self, version: int):
        super().__init__(f"protocol version {version}, expected {PROTOCOL_VERSION}")
        self.version = version


# --- messages -----------------------------------------------------------------------


def _wire(code: str, default: int = 0) -> Any:
    """A message field, with its struct code on the wire (``B`` uint8, ``h`` int16,
    ``H`` uint16, ``i`` int32, ``I`` uint32)."""
    return field(default=default, metadata={"wire": code})


@dataclass(frozen=True)
class _Frame:
    """What every message has: the sender's frame counter, wrapping at 256.

    ``TYPE`` is its type byte and ``FORMAT`` the struct format of its payload, made
    from its fields' wire codes by :func:`_message`.
    """

    seq: int = 0
    TYPE: ClassVar[MsgType]
    FORMAT: ClassVar[str]


def _message(mtype: MsgType) -> Callable[[type], type]:
    """Make a :class:`_Frame` subclass a frozen message of type ``mtype``."""

    def make(cls: type) -> type:
        cls = dataclass(frozen=True)(cls)
        cls.TYPE = mtype
        cls.FORMAT = "<" + "".join(f.metadata["wire"] for f in fields(cls) if f.name != "seq")
        return cls

    return make


@_message(MsgType.HEARTBEAT)
class Heartbeat(_Frame):
    """Host -> chair: keeps the chair's 250 ms watchdog fed, nothing else."""


@_message(MsgType.SET_POTS)
class SetPots(_Frame):
    """Host -> chair: drive the pots directly.

    ``fb`` and ``lr`` are pot bytes 0..255 (128 neutral; FB above 128 forward,
    LR below 128 turns left). The chair clamps them into 8..253 and the speed cap.
    """

    fb: int = _wire("B", POT_NEUTRAL)
    lr: int = _wire("B", POT_NEUTRAL)


@_message(MsgType.SET_TWIST)
class SetTwist(_Frame):
    """Host -> chair: drive at a linear speed ``v_mm_s`` (mm/s, + forward) and a
    turn rate ``w_mrad_s`` (mrad/s, + counter-clockwise), both int16.

    The chair turns it into pot bytes with ``twist_to_pot_bytes_int``.
    """

    v_mm_s: int = _wire("h")
    w_mrad_s: int = _wire("h")


@_message(MsgType.STOP)
class Stop(_Frame):
    """Host -> chair: pots to neutral now (the host stays in charge)."""


@_message(MsgType.CONFIGURE)
class Configure(_Frame):
    """Host -> chair: speed caps and telemetry rate.

    ``cap_fb`` / ``cap_lr``: the largest |pot byte - 128| allowed for host
    commands on each channel, 0..125 (more means 125; the joystick is never
    capped). ``telemetry_period_ms``: 10..255 ms (0 = the default 20 ms; below 10
    means 10).
    """

    cap_fb: int = _wire("B", POT_MAX_OFFSET)
    cap_lr: int = _wire("B", POT_MAX_OFFSET)
    telemetry_period_ms: int = _wire("B")


@_message(MsgType.HELLO_REQUEST)
class HelloRequest(_Frame):
    """Host -> chair: please send a HELLO now."""


@_message(MsgType.HELLO)
class Hello(_Frame):
    """Chair -> host: sent at boot, on request, and every 500 ms until the
    host's first valid frame. ``reason`` is a :class:`HelloReason`;
    ``reset_flags`` is the AVR's MCUSR at boot (1 power-on, 2 external/reset
    button, 4 brown-out, 8 watchdog)."""

    protocol_version: int = _wire("B", PROTOCOL_VERSION)
    fw_major: int = _wire("B")
    fw_minor: int = _wire("B")
    fw_patch: int = _wire("B")
    reason: int = _wire("B", HelloReason.BOOT)
    reset_flags: int = _wire("B")

    @property
    def fw_version(self) -> str:
        """Firmware version as ``"major.minor.patch"``."""
        return f"{self.fw_major}.{self.fw_minor}.{self.fw_patch}"


@_message(MsgType.TELEMETRY)
class Telemetry(_Frame):
    """Chair -> host, every 20 ms by default.

    Attributes:
        seq: the chair's frame counter (shared with HELLO), wraps at 256.
        time_ms: chair clock, ms since boot (uint32, wraps).
        enc_left, enc_right: encoder counts (int32, wrap), + when that wheel
            drives forward; use ``tick_delta`` for differences.
        gyro_z_raw: gyro z, 65.5 counts per deg/s, + counter-clockwise.
        sonar_mm: sonar range, mm; 0 = no reading in the last 300 ms.
        joy_fb, joy_lr: joystick ADC readings, pot scale (centre 254).
        pot_fb, pot_lr: the pot bytes the chair is driving.
        flags: :class:`abcwc.types.StatusFlags` bits.
        bad_frames: frames the chair dropped since boot (uint16, wraps).
        last_cmd_seq: seq of the last valid host frame.
        loops: main-loop passes since the previous telemetry.
        cap_fb, cap_lr: the speed caps in force.
    """

    time_ms: int = _wire("I")
    enc_left: int = _wire("i")
    enc_right: int = _wire("i")
    gyro_z_raw: int = _wire("h")
    sonar_mm: int = _wire("H")
    joy_fb: int = _wire("H", JOY_CENTRE)
    joy_lr: int = _wire("H", JOY_CENTRE)
    pot_fb: int = _wire("B", POT_NEUTRAL)
    pot_lr: int = _wire("B", POT_NEUTRAL)
    flags: int = _wire("B")
    bad_frames: int = _wire("H")
    last_cmd_seq: int = _wire("B")
    loops: int = _wire("H")
    cap_fb: int = _wire("B", POT_MAX_OFFSET)
    cap_lr: int = _wire("B", POT_MAX_OFFSET)

    @property
    def gyro_z_rad_s(self) -> float:
        """Gyro z in rad/s (+ counter-clockwise)."""
        return self.gyro_z_raw / GYRO_LSB_PER_DEG_S * 0.017453292519943295

    @property
    def sonar_m(self) -> float | None:
        """Sonar range in metres, or None without a recent reading."""
        return self.sonar_mm / 1000.0 if self.sonar_mm else None


Message = Heartbeat | SetPots | SetTwist | Stop | Configure | HelloRequest | Hello | Telemetry

_CLASSES: dict[int, type] = {
    cls.TYPE: cls
    for cls in (Heartbeat, SetPots, SetTwist, Stop, Configure, HelloRequest, Hello, Telemetry)
}
_HEADER = struct.Struct("<BBB")
_CRC = struct.Struct("<H")
MAX_PAYLOAD = max(struct.calcsize(c.FORMAT) for c in _CLASSES.values())
MAX_RAW = _HEADER.size + MAX_PAYLOAD + _CRC.size
MAX_ENCODED = MAX_RAW + MAX_RAW // 254 + 1
"""Longest valid frame on the wire, without its delimiter."""


# --- CRC and COBS -------------------------------------------------------------------


def crc16(data: bytes, crc: int = 0xFFFF) -> int:
    """CRC-16/CCITT-FALSE of ``data``: polynomial 0x1021, initial value 0xFFFF, no
    reflection, no final XOR (``crc16(b"123456789") == 0x29B1``). It is
    :func:`binascii.crc_hqx` started at 0xFFFF; ``crc`` carries a running CRC on."""
    return binascii.crc_hqx(data, crc)


def cobs_encode(data: bytes) -> bytes:
    """COBS-encode ``data`` (no delimiter added); the result has no zero byte."""
    out = bytearray(b"\x00")
    code_pos = 0
    code = 1
    n = len(data)
    for i, byte in enumerate(data):
        if byte != 0:
            out.append(byte)
            code += 1
        # a zero ends its group; so does a full group (254 data bytes), which carries
        # no implied zero: open a new group only if more data follows
        if byte == 0 or (code == 0xFF and i + 1 < n):
            out[code_pos] = code
            code_pos = len(out)
            out.append(0)
            code = 1
    out[code_pos] = code
    return bytes(out)


def cobs_decode(data: bytes) -> bytes:
    """Decode one COBS frame (delimiter removed).

    Raises:
        ProtocolError: if ``data`` holds a zero byte or a group runs past the end.
    """
    out = bytearray()
    i = 0
    n = len(data)
    while i < n:
        code = data[i]
        i += 1
        if code == 0:
            raise ProtocolError("COBS: zero byte inside a frame")
        end = i + code - 1
        if end > n:
            raise ProtocolError("COBS: group runs past the end of the frame")
        chunk = data[i:end]
        if 0 in chunk:
            raise ProtocolError("COBS: zero byte inside a frame")
        out += chunk
        i = end
        if code != 0xFF and i < n:
            out.append(0)
    return bytes(out)


# --- frames -------------------------------------------------------------------------


def _check_fields(msg: Message) -> tuple[int, ...]:
    cls = type(msg)
    values = tuple(getattr(msg, f.name) for f in fields(msg) if f.name != "seq")
    if not 0 <= msg.seq <= 255:
        raise ProtocolError(f"seq {msg.seq} outside 0..255")
    try:
        struct.pack(cls.FORMAT, *values)
    except struct.error as exc:
        raise ProtocolError(f"{cls.__name__}{values}: a field is out of range ({exc})") from exc
    return values


def encode(msg: Message) -> bytes:
    """The complete wire frame for ``msg``: COBS bytes plus the 0x00 delimiter.

    Raises:
        ProtocolError: if a field does not fit its wire type (for example
            ``SetTwist(v_mm_s=40000)``: int16 is -32768..32767).
    """
    values = _check_fields(msg)
    raw = _HEADER.pack(PROTOCOL_VERSION, msg.TYPE, msg.seq) + struct.pack(msg.FORMAT, *values)
    raw += _CRC.pack(crc16(raw))
    return cobs_encode(raw) + b"\x00"


def decode_frame(frame: bytes) -> Message:
    """Decode one frame's COBS bytes (without the 0x00 delimiter).

    Raises:
        ProtocolError: bad COBS, short frame, CRC mismatch, other protocol
            version, unknown type or wrong payload length.
    """
    raw = cobs_decode(frame)
    if len(raw) < _HEADER.size + _CRC.size:
        raise ProtocolError(f"frame of {len(raw)} bytes is shorter than a header and CRC")
    body, (crc,) = raw[:-2], _CRC.unpack(raw[-2:])
    if crc16(body) != crc:
        raise ProtocolError(f"CRC mismatch: frame says {crc:#06x}, bytes give {crc16(body):#06x}")
    version, mtype, seq = _HEADER.unpack(body[:3])
    if version != PROTOCOL_VERSION:
        raise VersionMismatch(version)
    cls = _CLASSES.get(mtype)
    if cls is None:
        raise ProtocolError(f"unknown message type {mtype:#04x}")
    payload = body[3:]
    if len(payload) != struct.calcsize(cls.FORMAT):
        raise ProtocolError(
            f"{cls.__name__} payload is {len(payload)} bytes, expected "
            f"{struct.calcsize(cls.FORMAT)}"
        )
    return cls(seq, *struct.unpack(cls.FORMAT, payload))


class FrameDecoder:
    """Streaming decoder: feed it bytes as they come, get whole messages back.

    Bad frames are dropped and counted in ``bad_frames``, with the reason of the
    last one in ``last_error``; the decoder resynchronises at the next 0x00. The
    protocol versions of well-formed frames of another version collect in
    ``other_versions`` (firmware that does not match this library).
    Empty frames (two delimiters in a row) are ignored and not counted, the same
    rules as the chair's parser.
    """

    def __init__(self) -> None:
        self._buf = bytearray()
        self._overflow = False
        self.bad_frames = 0
        """Frames dropped so far."""
        self.last_error: str | None = None
        """Why the last bad frame was dropped."""
        self.other_versions: set[int] = set()
        """Protocol versions seen in frames of another version."""

    def feed(self, data: bytes) -> list[Message]:
        """Consume ``data``; return the messages completed by it, in order."""
        out: list[Message] = []
        for byte in data:
            if byte != 0:
                if len(self._buf) < MAX_ENCODED:
                    self._buf.append(byte)
                else:
                    self._overflow = True
                continue
            if not self._buf and not self._overflow:
                continue
            try:
                if self._overflow:
                    raise ProtocolError(f"frame longer than {MAX_ENCODED} bytes")
                out.append(decode_frame(bytes(self._buf)))
            except ProtocolError as exc:
                self.bad_frames += 1
                self.last_error = str(exc)
                if isinstance(exc, VersionMismatch):
                    self.other_versions.add(exc.version)
            self._buf.clear()
            self._overflow = False
        return out


# --- counters ------------------------------------------------------------------------


def tick_delta(now: int, before: int) -> int:
    """Signed difference of two wrapping 32-bit encoder counts (or chair
    times), correct across a wrap: ``tick_delta(5, -2) == 7`` and
    ``tick_delta(0, 2**32 - 1) == 1``."""
    return wrap_tick_delta(int(now) - int(before), bits=32)
