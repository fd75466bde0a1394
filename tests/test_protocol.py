"""The wire protocol's Python side: CRC, message layout, constants, version records.

The byte-for-byte agreement with the C firmware is in tests/firmware; these need no
toolchain.
"""

from __future__ import annotations

import os
import random
import re
import subprocess
import sys
from enum import IntEnum
from pathlib import Path

import numpy as np
import pytest

from abcwc.hw import protocol as P
from abcwc.params import default_params
from abcwc.sim.motor import ChairErrors
from abcwc.types import StatusFlags

ROOT = Path(__file__).resolve().parents[1]


def _crc16_bitwise(data: bytes) -> int:
    """CRC-16/CCITT-FALSE, one bit at a time, as the standard defines it."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc


def test_crc16_is_ccitt_false():
    assert P.crc16(b"123456789") == 0x29B1  # the catalogue's check value
    assert P.crc16(b"") == 0xFFFF  # the initial value, no final XOR
    # one zero byte by hand: 0xFFFF shifted out eight times through 0x1021
    assert P.crc16(b"\x00") == 0xE1F0 == _crc16_bitwise(b"\x00")
    rng = random.Random(8)
    for n in (1, 2, 7, 64, 300):
        data = bytes(rng.randrange(256) for _ in range(n))
        assert P.crc16(data) == _crc16_bitwise(data)
        assert P.crc16(data[n // 2:], P.crc16(data[:n // 2])) == P.crc16(data)  # running


def test_message_types_are_int_enums_with_the_documented_layout():
    assert issubclass(P.MsgType, IntEnum) and issubclass(P.HelloReason, IntEnum)
    layout = {  # firmware/PROTOCOL.md: type byte and payload fields
        P.Heartbeat: (0x01, "<"), P.SetPots: (0x02, "<BB"), P.SetTwist: (0x03, "<hh"),
        P.Stop: (0x04, "<"), P.Configure: (0x05, "<BBB"), P.HelloRequest: (0x06, "<"),
        P.Hello: (0x81, "<BBBBBB"), P.Telemetry: (0x82, "<IiihHHHBBBHBHBB"),
    }
    for cls, (mtype, fmt) in layout.items():
        assert cls.TYPE == mtype and isinstance(cls.TYPE, P.MsgType), cls
        assert cls.FORMAT == fmt, cls
    hello = P.FrameDecoder().feed(P.encode(P.Hello(seq=9, reason=P.HelloReason.PERIODIC)))
    assert hello == [P.Hello(seq=9, reason=2)]


def test_protocol_has_no_flag_class_of_its_own():
    """Telemetry flags are StatusFlags bits (PROTOCOL.md's table)."""
    assert not hasattr(P, "Flag")
    bits = {"JOYSTICK_OVERRIDE": 0x01, "WATCHDOG_TRIPPED": 0x02, "JOYSTICK_FAULT": 0x04,
            "IMU_FAULT": 0x08, "SPEED_CAPPED": 0x10, "HOST_ACTIVE": 0x20}
    assert {name: int(StatusFlags[name]) for name in bits} == bits


def test_constants_agree_with_the_firmware_and_the_chair_file():
    headers = "".join((ROOT / "firmware" / "core" / h).read_text()
                      for h in ("pots.h", "chair_core.h", "protocol.h"))

    def define(name: str) -> int:
        return int(re.search(rf"#define {name} (\d+)u", headers).group(1))

    assert P.POT_NEUTRAL == define("POT_NEUTRAL")
    assert P.JOY_CENTRE == define("JOY_CENTRE")
    assert P.POT_MAX_OFFSET == define("POT_MAX_OFFSET")
    assert P.TELEMETRY_PERIOD_MS == define("CORE_TELEMETRY_PERIOD_MS")
    assert P.PROTOCOL_VERSION == define("PROTO_VERSION")
    chair = default_params()
    assert (P.POT_NEUTRAL, P.JOY_CENTRE, P.POT_MAX_OFFSET) == (
        chair.pot_neutral, chair.joystick_centre, chair.pot_full_scale_offset)
    assert P.TELEMETRY_PERIOD_MS == round(chair.control_period * 1000)


def test_importing_the_protocol_reads_no_data_file():
    code = ("import abcwc.params as params, abcwc.hw.protocol\n"
            "print(params.default_params.cache_info().misses)")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True, cwd=ROOT)
    assert out.stdout.strip() == "0"


def _raw_frame(version: int, payload: bytes, crc_ok: bool = True) -> bytes:
    raw = bytes([version, P.MsgType.HELLO, 0]) + payload
    crc = P.crc16(raw) ^ (0 if crc_ok else 1)
    return P.cobs_encode(raw + crc.to_bytes(2, "little")) + b"\x00"


def test_decoder_records_other_protocol_versions():
    dec = P.FrameDecoder()
    hello = bytes([2, 0, 2, 0, 0, 1])
    messages = dec.feed(_raw_frame(2, hello) + _raw_frame(3, hello, crc_ok=False)
                        + P.encode(P.Heartbeat(seq=1)))
    assert messages == [P.Heartbeat(seq=1)]
    assert dec.bad_frames == 2
    assert dec.other_versions == {2}  # a frame with a bad CRC says nothing of its version
    with pytest.raises(P.VersionMismatch) as info:
        P.decode_frame(_raw_frame(7, hello)[:-1])
    assert info.value.version == 7 and isinstance(info.value, P.ProtocolError)


def test_chair_errors_take_numpy_scalars():
    errors = ChairErrors(wheel_base=np.uint8(1), slip_std=np.int64(0),
                         drive_wheel_left=np.float32(1.25))
    assert errors.wheel_base == 1.0 and type(errors.wheel_base) is float
    assert errors.slip_std == 0.0 and type(errors.slip_std) is float
    assert errors.drive_wheel_left == 1.25
    with pytest.raises(ValueError, match=r"ChairErrors.wheel_base \S*2\S* outside 0.5..1.5"):
        ChairErrors(wheel_base=np.uint8(2))
    with pytest.raises(ValueError, match=r"slip_std True outside 0..0.2"):
        ChairErrors(slip_std=True)
