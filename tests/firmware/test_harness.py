"""Firmware in the loop: the real firmware image on a simulated ATmega2560
(firmware/harness), talked to over a pseudo-terminal with pyserial, exactly as
a host talks to the chair. Time is lock-stepped, so every run is the same."""

from __future__ import annotations

import random
import time

import pytest
from firmware_helpers import Harness, make, random_bytes, require_tools

from abcwc.control import joystick_adc_to_pot_byte, twist_to_pot_bytes_int
from abcwc.hw import protocol as P
from abcwc.types import StatusFlags

LOOP_MS = 1.5
"""Longest main-loop pass seen in simulation (about 0.5 ms; SPI bytes take
100 us each under simavr 1.6), with margin."""


@pytest.fixture(scope="module")
def built():
    require_tools("make", "avr-gcc", "gcc", headers=("/usr/include/simavr/sim_avr.h",))
    make("firmware", "harness")


@pytest.fixture()
def chair(built):
    h = Harness()
    h.wait_hello()
    yield h
    h.close()


def test_boot_hello_and_telemetry(chair):
    hellos = [m for m in chair.messages if isinstance(m, P.Hello)]
    assert hellos[0].protocol_version == P.PROTOCOL_VERSION
    assert hellos[0].fw_version == "0.1.0"
    chair.advance(200)
    tel = chair.telemetry()
    assert len(tel) >= 10
    periods = [b.time_ms - a.time_ms for a, b in zip(tel[-10:], tel[-9:], strict=False)]
    assert all(19 <= p <= 21 for p in periods), periods  # 50 Hz
    last = tel[-1]
    assert (last.pot_fb, last.pot_lr) == (128, 128)
    assert last.flags == 0, StatusFlags(last.flags)
    assert chair.decoder.bad_frames == 0
    assert chair.pots() == (128, 128)


def test_twist_parity_sweep(chair):
    """(a) The pot bytes the firmware writes equal twist_to_pot_bytes_int."""
    cases = [(v, w) for v in range(-1800, 1801, 200) for w in (-1700, -785, -8, 0, 9, 400, 1571)]
    cases += [(7, 0), (-7, 0), (0, 7), (6, -6), (32767, -32768)]
    for v, w in cases:
        chair.send(P.SetTwist, v_mm_s=v, w_mrad_s=w)
        chair.advance(4)
        assert chair.pots() == twist_to_pot_bytes_int(v, w), (v, w)
    chair.advance(25)
    tel = chair.telemetry()[-1]
    assert tel.flags & StatusFlags.HOST_ACTIVE
    assert tel.last_cmd_seq == (chair.seq - 1) & 0xFF


def test_set_pots_clamped_and_capped(chair):
    chair.send(P.SetPots, fb=255, lr=0)
    chair.advance(4)
    assert chair.pots() == (253, 8)
    chair.send(P.Configure, cap_fb=40, cap_lr=20, telemetry_period_ms=0)
    chair.send(P.SetPots, fb=250, lr=10)
    chair.advance(25)
    assert chair.pots() == (168, 108)
    tel = chair.telemetry()[-1]
    assert tel.flags & StatusFlags.SPEED_CAPPED
    assert (tel.cap_fb, tel.cap_lr) == (40, 20)


def test_watchdog_neutral_after_250_ms(chair):
    """(b) Stop sending: both pots neutral 250 ms (+ one loop) later."""
    chair.send(P.SetTwist, v_mm_s=1000, w_mrad_s=-500)
    chair.advance(20)
    for _ in range(5):  # heartbeats keep it alive
        chair.send(P.Heartbeat)
        chair.advance(100)
    assert chair.pots() == twist_to_pot_bytes_int(1000, -500)
    chair.pot_log()
    chair.send(P.Heartbeat)
    t_last = chair.now_us()
    chair.advance(400)
    log = chair.pot_log()
    assert [v for _, _, v in log] == [128, 128], log
    # The frame takes ~0.5 ms on the wire, then up to a loop to be read.
    dt_ms = [(t - t_last) / 1000 for t, _, _ in log]
    assert all(250 <= d <= 250 + 1 + 2 * LOOP_MS for d in dt_ms), dt_ms
    assert chair.telemetry()[-1].flags & StatusFlags.WATCHDOG_TRIPPED
    # A heartbeat does not restart the chair; a new command does.
    chair.send(P.Heartbeat)
    chair.advance(30)
    assert chair.pots() == (128, 128)
    chair.send(P.SetTwist, v_mm_s=500, w_mrad_s=0)
    chair.advance(30)
    assert chair.pots() == twist_to_pot_bytes_int(500, 0)
    assert not chair.telemetry()[-1].flags & StatusFlags.WATCHDOG_TRIPPED


def test_joystick_wins_within_one_loop(chair):
    """(c) A deflected joystick overrides the host in the loop that sees it."""
    chair.send(P.SetTwist, v_mm_s=-1000, w_mrad_s=1000)
    chair.advance(10)
    chair.pot_log()
    chair.cmd("J 398 200")
    t0 = chair.now_us()
    chair.advance(5)
    log = chair.pot_log()
    want = (joystick_adc_to_pot_byte(398), joystick_adc_to_pot_byte(200))
    assert chair.pots() == want
    assert log and max(t for t, _, _ in log) - t0 <= LOOP_MS * 1000, log
    # Host commands are ignored while the joystick is held ...
    for _ in range(5):
        chair.send(P.SetTwist, v_mm_s=1600, w_mrad_s=0)
        chair.advance(20)
        assert chair.pots() == want
    tel = chair.telemetry()[-1]
    assert tel.flags & StatusFlags.JOYSTICK_OVERRIDE
    assert (tel.joy_fb, tel.joy_lr) == (398, 200)
    # ... and not resumed on release: neutral until a new command.
    chair.cmd("J 254 254")
    chair.advance(10)
    assert chair.pots() == (128, 128)
    chair.send(P.SetTwist, v_mm_s=300, w_mrad_s=0)
    chair.advance(10)
    assert chair.pots() == twist_to_pot_bytes_int(300, 0)
    # A disconnected joystick (reads near 0): neutral, flagged.
    chair.cmd("J 3 254")
    chair.advance(25)
    assert chair.pots() == (128, 128)
    assert chair.telemetry()[-1].flags & StatusFlags.JOYSTICK_FAULT


def test_garbage_is_counted_and_harmless(chair):
    """(d) Random bytes and broken frames: dropped, counted, still running."""
    rng = random.Random(42)
    chair.advance(30)
    before = chair.telemetry()[-1].bad_frames
    mirror = P.FrameDecoder()  # the same rules as the firmware's parser
    mirror.feed(b"\x00")
    for i in range(40):
        good = P.encode(P.SetPots(seq=i, fb=150, lr=100))
        kind = i % 4
        if kind == 0:
            chunk = random_bytes(rng, rng.randrange(1, 120))
        elif kind == 1:
            chunk = good[: rng.randrange(1, len(good) - 1)] + b"\x00"  # truncated
        elif kind == 2:
            b = bytearray(good)
            b[rng.randrange(len(b) - 1)] ^= 1 << rng.randrange(8)
            chunk = bytes(b).replace(b"\x00", b"\x01", len(b) - 1)  # corrupted
        else:
            chunk = b"\x00" + good
        mirror.feed(chunk)
        chair.write(chunk)
        chair.advance(3)
    chair.write(b"\x00")
    mirror.feed(b"\x00")
    chair.advance(40)
    tel = chair.telemetry()[-1]
    assert tel.bad_frames - before == mirror.bad_frames > 20
    # Still alive and obeying.
    chair.send(P.SetTwist, v_mm_s=800, w_mrad_s=100)
    chair.advance(10)
    assert chair.pots() == twist_to_pot_bytes_int(800, 100)
    assert 8 <= min(chair.pots()) and max(chair.pots()) <= 253


def test_encoders_gyro_sonar(chair):
    """(e) Telemetry counts equal the counts played; gyro and sonar pass through."""
    chair.cmd("E 1234 -567")
    chair.cmd("G -6550")
    chair.cmd("S 2000")
    chair.advance(300)
    chair.cmd("E -200 300")
    chair.advance(100)
    played = chair.cmd("E?").split()
    assert played[1:] == ["1034", "-267", "0", "0"]
    tel = chair.telemetry()[-1]
    assert (tel.enc_left, tel.enc_right) == (1034, -267)
    assert tel.gyro_z_raw == -6550
    assert tel.gyro_z_rad_s == pytest.approx(-1.745, abs=1e-3)
    assert abs(tel.sonar_mm - 2000) <= 25
    assert not tel.flags & StatusFlags.IMU_FAULT
    chair.cmd("I 0")  # unplug the IMU
    chair.advance(100)
    tel = chair.telemetry()[-1]
    assert tel.flags & StatusFlags.IMU_FAULT and tel.gyro_z_raw == 0
    chair.cmd("I 1")
    chair.advance(1100)  # re-initialised within a second
    assert not chair.telemetry()[-1].flags & StatusFlags.IMU_FAULT


def test_speed_and_realtime_modes(built):
    """The harness runs faster than real time, and paces itself in realtime mode."""
    h = Harness(mode="fast")
    try:
        time.sleep(1.5)
        _, sim_us, _, ratio = h.cmd("T?").split()
        print(f"simavr: ATmega2560 firmware at {float(ratio):.2f}x real time")
        assert float(ratio) > 0.5
        h.cmd("M realtime")
        t0_sim, t0 = int(h.cmd("T?").split()[1]), time.monotonic()
        time.sleep(1.0)
        t1_sim, t1 = int(h.cmd("T?").split()[1]), time.monotonic()
        if float(ratio) >= 1.2:  # only meaningful if the host is fast enough
            assert (t1_sim - t0_sim) / 1e6 == pytest.approx(t1 - t0, rel=0.2)
        h.poll()
        assert any(isinstance(m, P.Telemetry) for m in h.messages)
    finally:
        err = h.close()
    assert "real time" in err
