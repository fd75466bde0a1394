"""abcwc.hw.protocol against the firmware's C core: the same bytes both ways,
and the same pot bytes from the velocity controller."""

from __future__ import annotations

import random
import subprocess
from dataclasses import fields

import pytest
from firmware_helpers import PROTO_TOOL, make, random_bytes, require_tools

from abcwc.control import cap_pot_byte, joystick_adc_to_pot_byte, twist_to_pot_bytes_int
from abcwc.hw import protocol as P

# ---------------------------------------------------------------- pure Python


def test_crc_and_cobs_known_answers():
    assert P.crc16(b"123456789") == 0x29B1
    assert P.cobs_encode(b"") == b"\x01"
    assert P.cobs_encode(b"\x00") == b"\x01\x01"
    assert P.cobs_encode(b"\x11\x22\x00\x33") == b"\x03\x11\x22\x02\x33"
    assert P.cobs_encode(bytes(range(1, 255))) == b"\xff" + bytes(range(1, 255))
    assert P.cobs_encode(bytes(range(1, 256))) == (
        b"\xff" + bytes(range(1, 255)) + b"\x02\xff"
    )
    rng = random.Random(1)
    for n in range(0, 600, 7):
        data = bytes(rng.choice([0, rng.randrange(1, 256)]) for _ in range(n))
        enc = P.cobs_encode(data)
        assert 0 not in enc
        assert P.cobs_decode(enc) == data


def test_known_frames():
    assert P.encode(P.Heartbeat(seq=0)) == bytes.fromhex("03010103 9dc8 00".replace(" ", ""))
    assert P.encode(P.SetTwist(seq=7, v_mm_s=500, w_mrad_s=-300)) == bytes.fromhex(
        "0a010307f401d4fe255500"
    )


def test_decoder_counts_bad_frames_and_resyncs():
    good = P.encode(P.SetPots(seq=3, fb=200, lr=60))
    bad_crc = bytearray(good)
    bad_crc[4] ^= 0x01
    stream = b"\x00\x00" + good[:-4] + b"\x00" + bytes(bad_crc) + b"\x55" * 100 + b"\x00" + good
    dec = P.FrameDecoder()
    msgs = dec.feed(stream)
    assert msgs == [P.SetPots(seq=3, fb=200, lr=60)]
    assert dec.bad_frames == 3


def test_field_range_errors():
    with pytest.raises(P.ProtocolError, match="out of range"):
        P.encode(P.SetTwist(v_mm_s=40000))
    with pytest.raises(P.ProtocolError, match="seq"):
        P.encode(P.Heartbeat(seq=256))


def test_velocity_controller_reference_points():
    f = twist_to_pot_bytes_int
    assert f(0, 0) == (128, 128)
    assert f(1667, 0) == (253, 128)
    assert f(-1667, 0) == (8, 128)
    assert f(0, 1571) == (128, 8)  # left turn lowers LR
    assert f(0, -1571) == (128, 253)
    assert f(6, 0) == (128, 128)
    assert f(7, 0) == (131, 128)
    assert joystick_adc_to_pot_byte(110) == 8
    assert joystick_adc_to_pot_byte(254) == 130
    assert joystick_adc_to_pot_byte(398) == 253
    assert P.tick_delta(5, 2**32 - 2) == 7
    assert P.tick_delta(2**32 - 2, 5) == -7


# ------------------------------------------------------- against the C core


class CoreTool:
    """firmware/build/proto_tool: the C core behind a line protocol."""

    def __init__(self) -> None:
        self.proc = subprocess.Popen(
            [str(PROTO_TOOL)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
            bufsize=1,
        )

    def ask(self, lines: list[str]) -> list[str]:
        """One answer line per command line."""
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write("".join(line + "\n" for line in lines))
        self.proc.stdin.flush()
        return [self.proc.stdout.readline().strip() for _ in lines]

    def decode(self, data: bytes) -> tuple[list[str], int]:
        """Feed data to a fresh C parser: (one line per message, bad frames)."""
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(f"dec {data.hex()}\n")
        self.proc.stdin.flush()
        msgs = []
        while True:
            line = self.proc.stdout.readline().strip()
            if line.startswith("bad "):
                return msgs, int(line.split()[1])
            msgs.append(line)

    def close(self) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        self.proc.wait(timeout=10)


@pytest.fixture(scope="module")
def tool():
    require_tools("make", "gcc")
    make("tools")
    t = CoreTool()
    yield t
    t.close()


def test_velocity_controller_matches_c(tool):
    cases = [(v, w) for v in range(-2000, 2001, 23) for w in range(-1800, 1801, 97)]
    cases += [(v, 0) for v in range(-40, 41)] + [(0, w) for w in range(-40, 41)]
    cases += [(-32768, 32767), (32767, -32768), (1667, 1571), (-1667, -1571)]
    answers = tool.ask([f"twist {v} {w}" for v, w in cases])
    for (v, w), ans in zip(cases, answers, strict=True):
        assert tuple(map(int, ans.split())) == twist_to_pot_bytes_int(v, w), (v, w)


def test_eqn1_and_cap_match_c(tool):
    answers = tool.ask([f"joy {a}" for a in range(0, 1024)])
    assert [int(a) for a in answers] == [joystick_adc_to_pot_byte(a) for a in range(0, 1024)]
    cases = [(b, c) for b in range(0, 256, 3) for c in (0, 1, 10, 60, 125, 126, 255)]
    answers = tool.ask([f"cap {b} {c}" for b, c in cases])
    assert [int(a) for a in answers] == [cap_pot_byte(b, c) for b, c in cases]


def _random_message(rng: random.Random):
    cls = rng.choice(
        [P.Heartbeat, P.SetPots, P.SetTwist, P.Stop, P.Configure, P.HelloRequest, P.Hello,
         P.Telemetry]
    )
    ranges = {
        "B": (0, 255), "b": (-128, 127), "H": (0, 65535), "h": (-32768, 32767),
        "I": (0, 2**32 - 1), "i": (-(2**31), 2**31 - 1),
    }
    codes = cls.FORMAT[1:]
    values = [rng.randint(*ranges[c]) for c in codes]
    names = [f.name for f in fields(cls) if f.name != "seq"]
    return cls(seq=rng.randrange(256), **dict(zip(names, values, strict=True)))


def _fields_line(msg) -> str:
    return " ".join(str(getattr(msg, f.name)) for f in fields(msg))


def test_encodings_match_c_both_ways(tool):
    rng = random.Random(2024)
    msgs = [_random_message(rng) for _ in range(400)]
    # C encodes -> Python decodes, and the bytes equal Python's encoding.
    hexes = tool.ask([f"enc {m.TYPE} {_fields_line(m)}" for m in msgs])
    for m, h in zip(msgs, hexes, strict=True):
        assert bytes.fromhex(h) == P.encode(m), m
        assert P.FrameDecoder().feed(bytes.fromhex(h)) == [m]
    # Python encodes -> C decodes.
    for m in msgs[:100]:
        assert tool.decode(P.encode(m)) == ([f"msg {m.TYPE} {_fields_line(m)}"], 0), m


def test_bad_frame_counts_match_c(tool):
    """Garbage, truncated and corrupted frames: both parsers count the same."""
    rng = random.Random(7)
    for _ in range(60):
        parts = []
        for _ in range(rng.randrange(1, 8)):
            frame = P.encode(_random_message(rng))
            kind = rng.randrange(4)
            if kind == 0:
                frame = frame[: rng.randrange(1, len(frame))] + b"\x00"
            elif kind == 1:
                b = bytearray(frame)
                i = rng.randrange(len(b) - 1)
                b[i] = rng.randrange(1, 256)
                frame = bytes(b)
            elif kind == 2:
                frame = random_bytes(rng, rng.randrange(1, 80))
            parts.append(frame)
        stream = b"".join(parts) + b"\x00"
        dec = P.FrameDecoder()
        py = dec.feed(stream)
        c_msgs, c_bad = tool.decode(stream)
        assert c_bad == dec.bad_frames
        assert c_msgs == [f"msg {m.TYPE} {_fields_line(m)}" for m in py]
