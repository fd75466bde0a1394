"""SerialBase against the real firmware (simavr harness) and the firmware in the loop.

The harness runs ``abcwc_firmware.elf`` on a simulated ATmega2560 with UART0 on a
pseudo-terminal, so SerialBase talks to the firmware exactly as to the chair. The
tests that need it skip when the AVR toolchain or simavr is missing, and fail
instead under CI=true.
"""

from __future__ import annotations

import math
import os
import subprocess
import threading
import time
from types import SimpleNamespace

import numpy as np
import pytest

from abcwc.base import Base
from abcwc.connect import connect
from abcwc.control.velocity import twist_to_pot_command
from abcwc.hw import protocol as P
from abcwc.hw import serial_base as sb
from abcwc.hw.serial_base import ChairLinkError, NoSuchPortError, ProtocolVersionError, SerialBase
from abcwc.sim.motor import ChairErrors
from abcwc.sim.world import world_from_dict
from abcwc.types import PotCommand, StatusFlags, Twist


@pytest.fixture()
def realtime_chair(harness_files):
    """The firmware on simavr, paced to the wall clock, like a chair on a cable."""
    harness, elf = harness_files
    proc = subprocess.Popen([str(harness), "--mode", "realtime", str(elf)],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, bufsize=1)
    pty = proc.stdout.readline().strip()
    assert pty.startswith("/dev/"), pty
    yield SimpleNamespace(proc=proc, pty=pty)
    if proc.poll() is None:
        try:
            proc.stdin.write("Q\n")
            proc.stdin.flush()
            proc.communicate(timeout=5)
        except Exception:  # noqa: BLE001
            proc.kill()
            proc.communicate()


# ------------------------------------------------------------------ the real firmware


def test_connect_step_and_twist_gives_controller_pots(realtime_chair):
    with connect(realtime_chair.pty, speed_cap=125) as chair:
        assert isinstance(chair, SerialBase) and isinstance(chair, Base)
        assert chair.hello.protocol_version == P.PROTOCOL_VERSION
        assert chair.pose is None and chair.frame.t == 0.0
        frames = [chair.step() for _ in range(5)]
        assert [round(f.t, 3) for f in frames] == [0.02, 0.04, 0.06, 0.08, 0.1]
        assert (frames[-1].pot_fb, frames[-1].pot_lr) == (128, 128)
        for twist in (Twist(0.6, -0.4), Twist(-0.3, 0.9), Twist(1.2, 0.0)):
            log = chair.drive(twist, 0.1, safety=None)  # the wire's encoding, unfiltered
            want = twist_to_pot_command(twist)
            assert (chair.frame.pot_fb, chair.frame.pot_lr) == (want.fb, want.lr), twist
            assert tuple(log.cmd_pots[-1]) == (want.fb, want.lr)
        chair.drive(PotCommand(255, 0), 0.06, safety=None)  # clamped into the safe range
        frame = chair.read()
        assert (frame.pot_fb, frame.pot_lr) == (253, 8)
        assert frame.extras["host_active"] and frame.flags & StatusFlags.SPEED_CAPPED
        assert frame.bad_frames == 0 and frame.extras["lost_frames"] == 0
        # Nothing sent: the firmware's watchdog stops the chair after 250 ms.
        log = chair.run(lambda f: None, 0.4)
        assert (log.pots[-1] == 128).all()
        assert log.flags[-1] & StatusFlags.WATCHDOG_TRIPPED


def test_speed_cap_defaults_to_env_or_40(realtime_chair, monkeypatch):
    monkeypatch.delenv(sb.SPEED_CAP_ENV, raising=False)
    assert sb.default_speed_cap() == sb.DEFAULT_SPEED_CAP == 40
    monkeypatch.setenv(sb.SPEED_CAP_ENV, "lots")
    with pytest.raises(ValueError, match="ABCWC_SPEED_CAP"):
        sb.default_speed_cap()
    monkeypatch.setenv(sb.SPEED_CAP_ENV, "30")
    with SerialBase(realtime_chair.pty) as chair:
        chair.safety = None  # the firmware's own cap, under any host
        chair.drive(Twist(1.5, 0.0), 0.1)
        assert chair.frame.pot_fb == 128 + 30
        assert chair.frame.extras["cap"] == (30, 30)
        assert chair.frame.flags & StatusFlags.SPEED_CAPPED
        chair.set_speed_cap(10)
        chair.drive(Twist(-1.5, 0.0), 0.1)
        assert chair.frame.pot_fb == 128 - 10
        with pytest.raises(ValueError):
            chair.set_speed_cap(126)


def test_the_real_chair_body_passes_every_command_through_its_safety_filter(realtime_chair):
    """Over serial as in the simulator: a Twist beyond the comfort limits goes out capped
    and ramped, and the RunLog says what the filter changed."""
    with connect(realtime_chair.pty, speed_cap=125) as chair:
        log = chair.drive(Twist(1.5, 0.0), 0.5)
        limits = chair.safety.limits
        sent = log.cmd_twist[:, 0]
        assert (sent <= limits.max_speed).all() and sent[0] < 0.01  # capped, from rest
        assert np.all(np.diff(sent) <= limits.max_accel * chair.period + 1e-9)
        assert (log.wanted_twist[:, 0] == 1.5).all()
        assert all(reason == "speed limit" for reason in log.safety)
        want = twist_to_pot_command(Twist(sent[-1], 0.0))
        assert tuple(log.cmd_pots[-1]) == (want.fb, want.lr)


def test_killed_harness_mid_run_raises_within_half_a_second(realtime_chair):
    chair = SerialBase(realtime_chair.pty, speed_cap=125)
    killed = {}

    def controller(frame):
        if len(killed) == 0 and frame.t >= 0.2:
            realtime_chair.proc.kill()  # the cable is pulled
            killed["at"] = time.monotonic()
        return Twist(0.5, 0.0)

    with pytest.raises(ChairLinkError, match="chair link"):
        chair.run(controller, 5.0)
    waited = time.monotonic() - killed["at"]
    chair.close()
    print(f"link loss noticed {waited * 1000:.0f} ms after the harness died")
    assert waited < 0.5


def test_frozen_chair_raises_within_half_a_second(realtime_chair):
    """A chair that stops talking without a port error (a hung board) is noticed too."""
    chair = SerialBase(realtime_chair.pty, speed_cap=125)
    frozen = {}

    def controller(frame):
        if not frozen and frame.t >= 0.2:
            realtime_chair.proc.stdin.write("M lockstep\n")  # simulated time stops
            realtime_chair.proc.stdin.flush()
            frozen["at"] = time.monotonic()
        return None

    with pytest.raises(ChairLinkError, match="no telemetry"):
        chair.run(controller, 5.0)
    waited = time.monotonic() - frozen["at"]
    chair.close()
    assert waited < 0.5


# ------------------------------------------------------------------ errors without a chair


def test_no_such_port_lists_the_ports(monkeypatch):
    with pytest.raises(NoSuchPortError, match="ttyNOPE9") as info:
        SerialBase("/dev/ttyNOPE9")
    assert "ports on this machine" in str(info.value) or "no serial ports" in str(info.value)
    from serial.tools import list_ports

    fake = [SimpleNamespace(device="/dev/ttyACM3", description="Arduino Mega 2560"),
            SimpleNamespace(device="/dev/ttyUSB0", description="n/a")]
    monkeypatch.setattr(list_ports, "comports", lambda: fake)
    with pytest.raises(FileNotFoundError) as info:
        SerialBase("/dev/ttyNOPE9")
    assert "/dev/ttyACM3 (Arduino Mega 2560), /dev/ttyUSB0" in str(info.value)


def _raw_frame(version: int, mtype: int, payload: bytes) -> bytes:
    raw = bytes([version, mtype, 0]) + payload
    raw += P.crc16(raw).to_bytes(2, "little")
    return P.cobs_encode(raw) + b"\x00"


@pytest.fixture()
def fake_chair():
    """A pty whose far end the test writes, as a stand-in for a chair."""
    master, slave = os.openpty()
    yield SimpleNamespace(path=os.ttyname(slave),
                          later=lambda data, s=0.1: threading.Timer(
                              s, os.write, (master, data)).start())
    time.sleep(0.15)
    os.close(master)
    os.close(slave)


def test_protocol_version_mismatch_names_both_versions(fake_chair):
    hello_v2 = _raw_frame(2, P.MsgType.HELLO, bytes([2, 0, 2, 0, 0, 1]))
    fake_chair.later(b"\x17\x42\x00" + hello_v2)  # a torn frame first, as after a reset
    with pytest.raises(ProtocolVersionError, match=r"version 2.*version 1"):
        SerialBase(fake_chair.path, ready_timeout=1.0)


def test_hello_but_no_telemetry_times_out(fake_chair):
    fake_chair.later(P.encode(P.Hello(seq=0)))
    t0 = time.monotonic()
    with pytest.raises(ChairLinkError, match="no telemetry"):
        SerialBase(fake_chair.path, timeout=0.3, ready_timeout=1.0)
    assert time.monotonic() - t0 < 1.0


# ------------------------------------------------------------------ firmware in the loop

BOX = world_from_dict({"name": "box", "walls": [[[0, 0], [8, 0], [8, 8], [0, 8], [0, 0]]],
                       "places": {"start": [2.0, 2.0, 0.0]}})


@pytest.fixture()
def fil(harness_files):
    from abcwc.hw.fil_base import FirmwareInLoopBase

    chair = FirmwareInLoopBase(BOX, seed=3, errors=ChairErrors.ideal(), people=False,
                               build=False)
    chair.safety = None  # these tests hold the firmware to its own rules, under any host
    yield chair
    chair.close()


def _coast(params, rate: float) -> float:
    """How far the chair rolls on after the stop decision: two periods (a frame's
    counts are those the firmware had at its mid-period telemetry, and the stop goes
    out with the next period), the motor controller's input delay, and the
    first-order motor lag (integral of rate * exp(-t / tau) = rate * tau)."""
    return rate * (2 * params.control_period + params.command_delay
                   + params.motor_time_constant)


def test_fil_straight_2m_encoders_match_wheel_travel(fil):
    """Drive 2 m on the firmware's odometry, braking ahead by the predicted coast.

    Tolerance 3 cm: the coast prediction uses the measured speed (quantised to one
    count, 0.5 mm, per 20 ms), and the stop lands within a period (1 cm at 0.5 m/s)."""
    p, dpc = fil.params, fil.params.distance_per_count
    start = fil.pose
    t0 = fil.frame.ticks_left, fil.frame.ticks_right
    hist: list[float] = []
    stopped = []  # latched once the stop is decided

    def controller(frame):
        d = ((frame.ticks_left - t0[0]) + (frame.ticks_right - t0[1])) / 2 * dpc
        hist.append(d)
        v = (hist[-1] - hist[-2]) / p.control_period if len(hist) > 1 else 0.0
        if stopped or d + _coast(p, v) >= 2.0:
            stopped.append(True)
            return PotCommand(128, 128)
        return Twist(0.5, 0.0)

    log = fil.run(controller, 6.0)
    end = fil.pose
    driven = math.hypot(end.x - start.x, end.y - start.y)
    print(f"FIL straight: {driven:.4f} m, heading {math.degrees(end.theta):+.3f} deg")
    assert driven == pytest.approx(2.0, abs=0.03)
    assert abs(end.y - start.y) < 0.002 and abs(math.degrees(end.theta)) < 0.2
    assert log.collisions[-1] == 0 and log.bad_frames[-1] == 0
    # The firmware counted every pulse the chair's wheels made.
    fil.run(lambda f: PotCommand(128, 128), 0.1)
    prev_sim = fil.frame.extras["sim_ticks"]
    frame = fil.step()
    assert (frame.ticks_left, frame.ticks_right) == prev_sim
    travel = fil.sim.encoders.travel_left, fil.sim.encoders.travel_right
    for ticks, metres in zip((frame.ticks_left, frame.ticks_right), travel, strict=True):
        assert abs(ticks * dpc - metres) <= 2 * dpc
        assert abs(ticks * dpc - driven) < 0.002
    # Command -> telemetry: the frame of the period a command goes out shows its pots.
    fil.send(Twist(0.3, 0.2))
    frame = fil.step()
    want = twist_to_pot_command(Twist(0.3, 0.2))
    assert (frame.pot_fb, frame.pot_lr) == (want.fb, want.lr)
    print(f"FIL: {fil.sim_speed:.2f}x real time, {fil.wall_time / fil.sim_steps * 1000:.1f} ms "
          f"wall per 20 ms step")


def test_fil_turn_90_degrees(fil):
    """Turn left 90 degrees on the firmware's encoder heading, braking ahead.

    Tolerance 2 degrees: the measured rate is quantised to one count per wheel per
    period (0.1 degrees) and the stop lands within one period (0.6 degrees at
    0.5 rad/s); the ideal chair's wheel base is the nominal one."""
    p, dpc = fil.params, fil.params.distance_per_count
    start = fil.pose
    t0 = fil.frame.ticks_left, fil.frame.ticks_right
    hist: list[float] = []
    stopped = []  # latched once the stop is decided

    def controller(frame):
        dl, dr = frame.ticks_left - t0[0], frame.ticks_right - t0[1]
        heading = (dr - dl) * dpc / p.wheel_base
        hist.append(heading)
        w = (hist[-1] - hist[-2]) / p.control_period if len(hist) > 1 else 0.0
        if stopped or heading + _coast(p, w) >= math.pi / 2:
            stopped.append(True)
            return PotCommand(128, 128)
        return Twist(0.0, 0.5)

    log = fil.run(controller, 6.0)
    turned = math.degrees(fil.pose.theta - start.theta)
    print(f"FIL turn: {turned:.2f} deg")
    assert turned == pytest.approx(90.0, abs=2.0)
    assert math.hypot(fil.pose.x - start.x, fil.pose.y - start.y) < 0.01
    # The firmware's gyro reading followed the chair's rotation.
    assert max(log.gyro_z) == pytest.approx(0.5, abs=0.1)
    assert log.meta["source"] == "firmware-in-the-loop"
    assert not (log.flags & StatusFlags.WATCHDOG_TRIPPED).any()


def test_fil_joystick_overrides_the_host_and_never_resumes_by_itself(fil):
    """The person on the chair wins: a joystick pull overrides a host that keeps
    commanding forward, in the firmware's own loop, and the chair drives as the
    joystick says; released, the pots go neutral until the host sends again."""
    from abcwc.control import joystick_adc_to_pot_byte

    fil.send(Twist(0.5, 0.0))
    fil.run(lambda f: Twist(0.5, 0.0), 2.0)
    assert fil.sim.chair.velocity.length > 0.4  # driving forward at the host's 0.5 m/s
    fil.set_joystick(fb=170)                    # pulled back (centre 254)
    reverse = joystick_adc_to_pot_byte(170)
    log = fil.run(lambda f: Twist(0.5, 0.0), 3.0)
    override = (log.flags & StatusFlags.JOYSTICK_OVERRIDE) != 0
    assert override.all(), "the override must show in every frame from the first period"
    centre = joystick_adc_to_pot_byte(254)  # eqn 1: 130, inside the dead band
    assert (log.pots[:, 0] == reverse).all() and (log.pots[:, 1] == centre).all()
    heading = fil.pose.theta
    forward = (math.cos(heading), math.sin(heading))
    speed = fil.sim.chair.velocity.dot(forward)
    assert reverse < 128 and speed < -0.3, speed  # the chair now backs up
    # Released: neutral at once; the host's next command is a new one and drives again.
    fil.release_joystick()
    frame = fil.step()
    assert not frame.flags & StatusFlags.JOYSTICK_OVERRIDE
    assert (frame.pot_fb, frame.pot_lr) == (128, 128)
    fil.send(Twist(0.3, 0.0))
    frame = fil.step()
    want = twist_to_pot_command(Twist(0.3, 0.0))
    assert (frame.pot_fb, frame.pot_lr) == (want.fb, want.lr)


# ------------------------------------------------------------------ hardware cells
def test_hardware_chair_unset_is_skipped_with_a_message(monkeypatch, capsys):
    from abcwc import hardware_chair

    monkeypatch.delenv("ABCWC_PORT", raising=False)
    with hardware_chair(speed_cap=20, world="lab") as real:
        assert real is None
    assert "ABCWC_PORT is not set: skipping" in capsys.readouterr().out
    with pytest.raises(ValueError, match="0..125"), hardware_chair(speed_cap=200):
        pass


def test_simulator_options_never_reach_a_real_port(monkeypatch):
    """With ABCWC_PORT set, a simulator cell (options given) stays in the simulator;
    connect() with no arguments goes to the port."""
    from abcwc.sim.base import SimBase

    monkeypatch.setenv("ABCWC_PORT", "/dev/abcwc-no-such-port")
    assert isinstance(connect(world="lab", seed=1), SimBase)
    with pytest.raises(NoSuchPortError, match="abcwc-no-such-port"):
        connect()


def test_hardware_chair_on_the_firmware_in_simavr(harness_files, monkeypatch, capsys):
    """ABCWC_PORT=simavr: the real firmware drives the simulated chair, capped; the
    chair is stopped and the harness ended when the block is left, even by an error."""
    from abcwc import Pose2D, hardware_chair
    from abcwc.hw.fil_base import FirmwareInLoopBase

    monkeypatch.setenv("ABCWC_PORT", "simavr")
    start = Pose2D(3.0, 4.0, 0.0)
    with pytest.raises(RuntimeError, match="cell failed"):
        with hardware_chair(speed_cap=20, world="lab", start=start, people=False) as real:
            assert isinstance(real, FirmwareInLoopBase)
            log = real.drive(PotCommand(253, 128), seconds=2.0)
            raise RuntimeError("cell failed")
    assert "simavr" in capsys.readouterr().out
    assert real._proc is None and real.link.closed  # harness gone, link closed
    assert (log.pots[:, 0] <= 148).all() and log.pots[-1, 0] == 148  # 128 + cap
    assert (log.flags[-1] & StatusFlags.SPEED_CAPPED)
    moved = log.pose[-1, 0] - start.x
    cap_speed = 20 / 125 * real.params.max_speed
    assert 0.5 * cap_speed * 2.0 < moved < cap_speed * 2.0, moved


def test_notebook_kernels_run_hardware_cells_on_the_firmware(harness_files):
    """With the toolchain present (always under CI), nbval's kernels get
    ABCWC_PORT=simavr, so every real-chair cell runs the real firmware in simavr."""
    from abcwc.nbval_plugin import KERNEL_ENV

    assert KERNEL_ENV["ABCWC_PORT"] == "simavr"


# ------------------------------------------------------------------ one interface
def test_every_body_is_a_base_with_params(realtime_chair, fil):
    """The simulator, the real chair's SerialBase and the firmware in the loop all
    satisfy the Base protocol and carry the chair's parameters."""
    from abcwc.hw.link import SerialLink
    from abcwc.params import ChairParams
    from abcwc.sim.base import SimBase

    with SerialBase(realtime_chair.pty, speed_cap=125) as serial:
        bodies = {"sim": SimBase(BOX, people=False), "serial": serial, "fil": fil}
        for name, body in bodies.items():
            assert isinstance(body, Base), name
            assert isinstance(body.params, ChairParams), name
            assert body.period == body.params.control_period == 0.02, name
            assert body.read() is body.frame, name
            log = body.drive(PotCommand(140, 128), 0.1)
            assert len(log.t) == 5 and tuple(log.cmd_pots[-1]) == (140, 128), name
            assert body.last_command == PotCommand(140, 128), name
    assert serial.link.closed  # the with block closed it
    # The firmware in the loop is made of a simulator and a link, not a SerialBase.
    assert isinstance(fil.sim, SimBase) and isinstance(fil.link, SerialLink)
    assert not isinstance(fil, SerialBase)
