"""FirmwareInLoopBase: the real firmware image driving the simulated chair.

``firmware/build/abcwc_harness`` runs ``abcwc_firmware.elf`` on a simulated
ATmega2560 (simavr) with its UART0 on a pseudo-terminal. This body is made of a
:class:`~abcwc.hw.link.SerialLink` on that pty (the same frames, HELLO handshake,
version check and telemetry decoding as on the real chair) and a
:class:`abcwc.sim.SimBase`, the pymunk chair co-simulated in lock-step. Every 20 ms
control period:

1. the pending host command (if any) is written to the pty;
2. the harness advances the AVR 20 ms (``A 20 <bytes sent>``: the host's bytes are
   in before time moves) and the firmware's telemetry of that period is read;
3. the pot bytes the firmware wrote to its (simulated) MCP42010 go to the
   simulated motor controller, in place of the Python interface board;
4. physics advances one period, and the chair's wheel motion goes back to the
   firmware as encoder pulses (counts), with the gyro's raw reading, the sonar's
   range in mm and the joystick's ADC values.

So the joystick override, speed caps, clamps and the watchdog are the firmware's
own. Frames carry the firmware's telemetry plus the simulator's ground truth
(``pose``, IR ring, scans, collisions). The encoder counts in a frame are those
the firmware had counted at its telemetry instant, so they trail the simulated
wheels by up to one period; after the chair stops they agree exactly.
"""

from __future__ import annotations

import math
import shutil
import subprocess
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace
from pathlib import Path
from typing import Any

from abcwc.devices import DeviceUnavailableError
from abcwc.hw import protocol as P
from abcwc.hw.link import ChairLinkError, SerialLink
from abcwc.hw.serial_base import LinkedBody
from abcwc.sim.base import SimBase
from abcwc.sim.world import World
from abcwc.types import Pose2D, PotCommand, SensorFrame

__all__ = ["FirmwareBuildError", "FirmwareInLoopBase", "FirmwareToolchainError",
           "build_harness", "missing_tools", "FIRMWARE_DIR"]

FIRMWARE_DIR = Path(__file__).resolve().parents[2] / "firmware"
"""The firmware sources (present in a repository checkout)."""
TOOL_PACKAGES = {
    "make": "make",
    "gcc": "gcc",
    "avr-gcc": "gcc-avr avr-libc",
    "arduino-core-avr": "arduino-core-avr",
    "libsimavr-dev": "simavr libsimavr-dev",
}
SIMAVR_HEADER = Path("/usr/include/simavr/sim_avr.h")
ARDUINO_CORE = Path("/usr/share/arduino/hardware/arduino/avr/cores/arduino")
HARNESS_REPLY_TIMEOUT = 5.0  # s of wall time for one harness command


class FirmwareToolchainError(DeviceUnavailableError):
    """The firmware in the loop cannot run here: the AVR toolchain or simavr is missing
    (the message names the Debian packages), or abcwc is an installed copy without the
    firmware's sources."""


class FirmwareBuildError(RuntimeError):
    """The tools are there, but the harness did not build or would not start."""


def missing_tools() -> list[str]:
    """The tools the firmware in the loop needs that this machine lacks (empty: all there)."""
    missing = [t for t in ("make", "gcc", "avr-gcc") if shutil.which(t) is None]
    if not ARDUINO_CORE.is_dir():
        missing.append("arduino-core-avr")
    if not SIMAVR_HEADER.exists():
        missing.append("libsimavr-dev")
    return missing


@contextmanager
def firmware_build_lock(firmware_dir: Path = FIRMWARE_DIR) -> Iterator[None]:
    """Hold ``firmware/build/.make.lock`` while ``make`` runs: test workers and notebook
    kernels side by side must not build the same files at once (POSIX ``flock``; where
    there is none, as on Windows, builds are not serialised)."""
    build = Path(firmware_dir) / "build"
    build.mkdir(exist_ok=True)
    try:
        import fcntl
    except ImportError:
        yield
        return
    with open(build / ".make.lock", "w") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def build_harness(firmware_dir: Path = FIRMWARE_DIR) -> tuple[Path, Path]:
    """Build (if needed) and return ``(harness, elf)``.

    Raises:
        FirmwareToolchainError: no firmware sources, or missing tools (naming the
            Debian packages to install).
        FirmwareBuildError: make failed (with its output).
    """
    firmware_dir = Path(firmware_dir)
    if not (firmware_dir / "Makefile").is_file():
        raise FirmwareToolchainError(
            f"firmware sources not found at {firmware_dir}: the firmware in the loop "
            f"needs a checkout of the abcwc repository")
    missing = missing_tools()
    if missing:
        pkgs = " ".join(sorted({TOOL_PACKAGES[m] for m in missing}))
        raise FirmwareToolchainError(
            f"the firmware in the loop needs {', '.join(missing)}: "
            f"sudo apt-get install {pkgs}")
    with firmware_build_lock(firmware_dir):
        proc = subprocess.run(["make", "-C", str(firmware_dir), "harness"],
                              capture_output=True, text=True, timeout=900)
    if proc.returncode != 0:
        raise FirmwareBuildError(
            f"make -C {firmware_dir} harness failed ({proc.returncode}):\n"
            f"{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
    build = firmware_dir / "build"
    return build / "abcwc_harness", build / "abcwc_firmware.elf"


class FirmwareInLoopBase(LinkedBody):
    """The simulated chair driven by the real firmware. Same surface as SimBase.

    Args:
        world: the simulated world (a name or a :class:`~abcwc.sim.world.World`).
        speed_cap: firmware speed cap in pot bytes from 128 (0..125); ``None``
            leaves the firmware's default, 125 (no cap beyond the safe range), as
            the simulator. This is a simulation: ``ABCWC_SPEED_CAP`` is not read.
        timeout: wall seconds to wait for a harness answer or for the bytes it
            reports written to the pty.
        ready_timeout: simulated seconds to wait for the firmware's HELLO.
        build: run ``make -C firmware harness`` first (quick when up to date).
        sim_options: ``seed``, ``errors``, ``params``, ``lidar``, ``depth_scan``,
            ``start``, ``people``: as :class:`abcwc.sim.SimBase` (the chair, its
            errors and its world).

    Attributes:
        sim: the SimBase whose world, motors and sensors are co-simulated.
        link: the SerialLink to the firmware's UART on the harness's pty.
        wall_time: wall seconds spent in ``step`` so far; ``sim_speed`` the
            simulated seconds per wall second of those steps.
    """

    source = "firmware-in-the-loop"

    def __init__(
        self,
        world: str | World = "lab",
        *,
        speed_cap: int | None = None,
        timeout: float = HARNESS_REPLY_TIMEOUT,
        ready_timeout: float = 3.0,
        build: bool = True,
        **sim_options: Any,
    ):
        self.sim = SimBase(world, **sim_options)
        self.sim.safety = None  # commands reach the sim as the firmware's pot bytes
        self.params = self.sim.params
        self._init_safety()  # this body's filter, before the commands go on the wire
        self.timeout = float(timeout)
        self.ready_timeout = float(ready_timeout)
        self.period = P.TELEMETRY_PERIOD_MS / 1000.0
        if abs(self.sim.period - self.period) > 1e-9:
            raise ValueError(f"the simulator's control period {self.sim.period} s differs "
                             f"from the firmware's telemetry period {self.period} s")
        self._proc: subprocess.Popen | None = None
        self._enc_sent = [0, 0]
        self._inputs: dict[str, str] = {}
        self.wall_time = 0.0
        self.sim_steps = 0
        self.sim_us = 0
        harness, elf = build_harness() if build else (
            FIRMWARE_DIR / "build" / "abcwc_harness", FIRMWARE_DIR / "build" / "abcwc_firmware.elf")
        pty = self._start_harness(harness, elf)
        try:
            self._connect(pty, speed_cap)
        except BaseException:
            self._end_harness()
            raise

    # ----------------------------------------------------------------- harness
    def _start_harness(self, harness: Path, elf: Path) -> str:
        """Start the harness; the pty it gives for the firmware's UART."""
        try:
            self._proc = subprocess.Popen(
                [str(harness), "--mode", "lockstep", str(elf)],
                stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                text=True, bufsize=1)
        except OSError as exc:
            raise FirmwareBuildError(f"could not start {harness}: {exc}") from exc
        line = self._proc.stdout.readline().strip()
        if not line.startswith("/dev/"):
            self._proc.kill()
            err = self._proc.communicate()[1]
            self._proc = None
            raise ChairLinkError(f"the harness did not give a pty: {line!r} {err[-2000:]}")
        return line

    def _connect(self, pty: str, speed_cap: int | None) -> None:
        """Open the link on ``pty``, shake hands, set the cap, take the first frame."""
        self.link = SerialLink(pty, P.BAUD_RATE, self.timeout)
        try:
            self._wait_ready()
            if speed_cap is not None:
                self.set_speed_cap(speed_cap)
            self._push_inputs(self.sim.frame.gyro_z)
            self._frame = self._merge(self.link.frame_from(self._period_telemetry()))
        except BaseException:
            self.link.close_port()
            raise

    def _end_harness(self) -> None:
        """Ask the harness to quit (kill it if it will not) and reap it."""
        proc, self._proc = self._proc, None
        if proc is None:
            return
        try:
            if proc.poll() is None and proc.stdin:
                proc.stdin.write("Q\n")
                proc.stdin.flush()
            proc.communicate(timeout=5)
        except Exception:  # noqa: BLE001 - make sure it is gone
            proc.kill()
            proc.communicate()

    def _harness_error(self, line: str, answer: str = "") -> ChairLinkError:
        code = self._proc.poll() if self._proc else None
        state = f"the harness exited ({code})" if code is not None else f"answer {answer!r}"
        return ChairLinkError(f"firmware harness: {line!r} failed: {state}")

    def harness(self, line: str) -> str:
        """Send one control line to the harness and return its answer."""
        proc = self._proc
        if proc is None or proc.stdin is None or proc.stdout is None:
            raise ChairLinkError("firmware harness is not running")
        try:
            proc.stdin.write(line + "\n")
            proc.stdin.flush()
            answer = proc.stdout.readline().strip()
        except (OSError, ValueError) as exc:
            raise self._harness_error(line) from exc
        if not answer or answer.startswith("ERR"):
            raise self._harness_error(line, answer)
        return answer

    def _advance(self, ms: float) -> list:
        """Advance the AVR ``ms`` (after our bytes are in); decode what it sent."""
        _, sim_us, written = self.harness(f"A {ms:g} {self.link.bytes_sent}").split()
        self.sim_us = int(sim_us)
        return self.link.receive_until(int(written), self.timeout)

    def _wait_ready(self) -> P.Hello:
        """Ask for HELLO and advance simulated time 10 ms at a time until it comes."""
        self.link.ask_hello()
        for _ in range(max(1, round(self.ready_timeout * 100))):
            hello = self.link.hello_in(self._advance(10))
            if hello is not None:
                return hello
        raise ChairLinkError(f"no HELLO from the firmware within {self.ready_timeout:g} s "
                             f"of simulated time")

    def _period_telemetry(self) -> P.Telemetry:
        """Advance one period; the newest telemetry frame of it."""
        telemetry = self.link.telemetry
        self._advance(self.period * 1000)
        if not telemetry:
            self._advance(self.period * 1000)  # phase slip: take the next one
        if not telemetry:
            raise ChairLinkError("the firmware sent no telemetry for 40 ms of simulated time")
        tel = telemetry[-1]
        telemetry.clear()
        return tel

    def _set_input(self, key: str, line: str) -> None:
        if self._inputs.get(key) != line:
            self.harness(line)
            self._inputs[key] = line

    def _push_inputs(self, gyro_z: float) -> None:
        """Give the firmware the chair's encoder counts, gyro, sonar and joystick."""
        sim = self.sim
        left, right = sim.encoders.counts
        dl, dr = left - self._enc_sent[0], right - self._enc_sent[1]
        if dl or dr:
            self.harness(f"E {dl} {dr}")
            self._enc_sent = [left, right]
        raw = round(math.degrees(gyro_z) * P.GYRO_LSB_PER_DEG_S)
        self._set_input("G", f"G {max(-32768, min(32767, raw))}")
        sonar = sim.frame.sonar
        mm = round(sonar * 1000) if math.isfinite(sonar) and sonar > 0 else 0
        self._set_input("S", f"S {max(0, min(65535, mm))}")
        self._set_input("J", f"J {sim.joystick[0]} {sim.joystick[1]}")

    def firmware_pots(self) -> PotCommand:
        """The bytes on the firmware's digital pot now."""
        _, fb, lr, _ = self.harness("P?").split()
        return PotCommand(int(fb), int(lr))

    def _merge(self, frame: SensorFrame) -> SensorFrame:
        """Add the simulator's ground truth and extra sensors to a telemetry frame."""
        sim = self.sim
        s = sim.frame
        extras = dict(frame.extras, sim_ticks=(s.ticks_left, s.ticks_right),
                      sim_gyro_z=s.gyro_z, sim_sonar=s.sonar, avr_time_us=self.sim_us)
        return replace(frame, truth=s.truth, ir=s.ir, lidar=s.lidar, depth_scan=s.depth_scan,
                       extras=extras)

    # ----------------------------------------------------------------- state
    @property
    def pose(self) -> Pose2D:
        """Ground-truth pose of base_link in the world frame."""
        return self.sim.pose

    @property
    def world(self) -> World:
        return self.sim.world

    @property
    def joystick(self) -> tuple[int, int]:
        return self.sim.joystick

    @property
    def sim_speed(self) -> float:
        """Simulated seconds per wall second over the steps so far."""
        return self.sim_steps * self.period / self.wall_time if self.wall_time else 0.0

    def set_joystick(self, fb: int | None = None, lr: int | None = None) -> None:
        """Set the joystick's ADC readings (pot scale; 254 centred); the firmware
        sees them from the next step."""
        self.sim.set_joystick(fb, lr)

    def release_joystick(self) -> None:
        """Let the joystick spring back to the centre."""
        self.sim.release_joystick()

    # ----------------------------------------------------------------- stepping
    def step(self) -> SensorFrame:
        """One 20 ms period of firmware and chair in lock-step."""
        t0 = time.perf_counter()
        sim = self.sim
        self._set_input("J", f"J {sim.joystick[0]} {sim.joystick[1]}")
        self.link.flush_pending()
        tel = self._period_telemetry()
        pots = self.firmware_pots()
        # the simulated chair runs on the firmware's pots instead of the Python board's
        gyro_z = sim.step_with_pots(pots).gyro_z
        self._push_inputs(gyro_z)
        self._frame = self._merge(self.link.frame_from(tel))
        self.sim_steps += 1
        self.wall_time += time.perf_counter() - t0
        return self._frame

    def log_meta(self) -> dict:
        sim = self.sim.log_meta()
        return {**super().log_meta(), "world": sim["world"], "seed": sim["seed"],
                "errors": sim["errors"]}

    def close(self) -> None:
        """Stop, close the pty and end the harness (safe to call twice)."""
        self.link.close()
        self._end_harness()

    def __repr__(self) -> str:
        return (f"FirmwareInLoopBase(world={self.sim.world.name!r}, seed={self.sim.seed}, "
                f"port={self.port_name!r})")
