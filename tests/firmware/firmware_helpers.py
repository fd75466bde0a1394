"""Shared helpers for the firmware tests: building with make, the simavr
harness as a Python object, and the tool checks (fail under CI, skip locally)."""

from __future__ import annotations

import os
import random
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from abcwc.hw.fil_base import firmware_build_lock

REPO = Path(__file__).resolve().parents[2]
FIRMWARE = REPO / "firmware"
BUILD = FIRMWARE / "build"
ELF = BUILD / "abcwc_firmware.elf"
HARNESS = BUILD / "abcwc_harness"
PROTO_TOOL = BUILD / "proto_tool"

if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

UNDER_CI = os.environ.get("CI", "").lower() == "true"

# Debian packages that provide each tool (see firmware/README.md).
TOOL_PACKAGES = {
    "make": "make",
    "gcc": "gcc",
    "avr-gcc": "gcc-avr avr-libc arduino-core-avr",
    "simavr": "simavr",
    "clang": "clang",
}


def require_tools(*tools: str, headers: tuple[str, ...] = ()) -> None:
    """Skip (locally) or fail (CI=true) when a tool or header is missing."""
    missing = [t for t in tools if shutil.which(t) is None]
    missing += [h for h in headers if not Path(h).exists()]
    if (
        "avr-gcc" in tools
        and not Path("/usr/share/arduino/hardware/arduino/avr/cores/arduino").is_dir()
    ):
        missing.append("arduino-core-avr")
    if not missing:
        return
    pkgs = sorted({TOOL_PACKAGES.get(m, m) for m in missing})
    msg = f"missing {', '.join(missing)} (Debian: apt-get install {' '.join(pkgs)})"
    if UNDER_CI:
        pytest.fail(msg)
    pytest.skip(msg)


def make(*targets: str, timeout: float = 600, **variables: str) -> subprocess.CompletedProcess:
    """Run make in firmware/; fail the test with make's output on error."""
    cmd = ["make", "-C", str(FIRMWARE), *targets, *(f"{k}={v}" for k, v in variables.items())]
    with firmware_build_lock(FIRMWARE):  # other test workers may be building too
        proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    if proc.returncode != 0:
        pytest.fail(
            f"{' '.join(cmd)} failed ({proc.returncode}):\n"
            f"{proc.stdout[-4000:]}\n{proc.stderr[-4000:]}"
        )
    return proc


class Harness:
    """The firmware running in abcwc_harness, in lock-step mode, with its UART
    on a pseudo-terminal opened with pyserial."""

    def __init__(self, mode: str = "lockstep") -> None:
        import serial

        self.proc = subprocess.Popen(
            [str(HARNESS), "--mode", mode, str(ELF)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            bufsize=1,
        )
        assert self.proc.stdout is not None
        self.pty = self.proc.stdout.readline().strip()
        if not self.pty.startswith("/dev/"):
            err = self.proc.stderr.read() if self.proc.stderr else ""
            raise RuntimeError(f"harness did not print a pty path: {self.pty!r} {err}")
        self.port = serial.Serial(self.pty, 115200, timeout=0)
        self.sent = 0
        self.received = 0
        self.seq = 0
        from abcwc.hw.protocol import FrameDecoder

        self.decoder = FrameDecoder()
        self.messages: list = []

    # -- control channel -------------------------------------------------------
    def cmd(self, line: str) -> str:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        answer = self.proc.stdout.readline().strip()
        if not answer or answer.startswith("ERR"):
            raise RuntimeError(f"harness: {line!r} -> {answer!r}")
        return answer

    def advance(self, ms: float) -> int:
        """Advance simulated time; returns the new simulated time in us."""
        _, now_us, written = self.cmd(f"A {ms} {self.sent}").split()
        self.poll(int(written))
        return int(now_us)

    def now_us(self) -> int:
        return int(self.cmd("T?").split()[1])

    def pots(self) -> tuple[int, int]:
        _, fb, lr, _ = self.cmd("P?").split()
        return int(fb), int(lr)

    def pot_log(self) -> list[tuple[int, str, int]]:
        """Pot changes since the last call: (sim time us, 'F' or 'L', byte)."""
        parts = self.cmd("L?").split()
        out = []
        for item in parts[2:]:
            if item.startswith("dropped"):
                continue
            t, ch, v = item.split(":")
            out.append((int(t), ch, int(v)))
        return out

    # -- serial ------------------------------------------------------------------
    def write(self, data: bytes) -> None:
        self.port.write(data)
        self.port.flush()
        self.sent += len(data)

    def send(self, msg_cls, **fields) -> None:
        from abcwc.hw.protocol import encode

        self.write(encode(msg_cls(seq=self.seq & 0xFF, **fields)))
        self.seq += 1

    def poll(self, until_total: int | None = None) -> list:
        """Read and decode what the firmware has sent: everything up to byte
        number ``until_total`` of the session if given (the harness says how
        many it wrote), else whatever arrives within 50 ms."""
        deadline = time.monotonic() + (2.0 if until_total is not None else 0.05)
        data = b""
        while True:
            chunk = self.port.read(65536)
            data += chunk
            self.received += len(chunk)
            if until_total is not None and self.received >= until_total:
                break
            if not chunk:
                if time.monotonic() > deadline:
                    break
                time.sleep(0.0005)
        new = self.decoder.feed(data)
        self.messages.extend(new)
        return new

    def telemetry(self) -> list:
        from abcwc.hw.protocol import Telemetry

        return [m for m in self.messages if isinstance(m, Telemetry)]

    def wait_hello(self, max_ms: int = 2000):
        """As a host does after opening the port: ask for HELLO and wait."""
        from abcwc.hw.protocol import Hello, HelloRequest

        self.send(HelloRequest)
        for _ in range(max_ms // 10):
            self.advance(10)
            hellos = [m for m in self.messages if isinstance(m, Hello)]
            if hellos:
                return hellos[-1]
        raise AssertionError("no HELLO from the firmware")

    def close(self) -> str:
        try:
            self.port.close()
        finally:
            try:
                self.cmd("Q")
            except Exception:  # noqa: BLE001 - already gone
                pass
            try:
                _, err = self.proc.communicate(timeout=10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                _, err = self.proc.communicate()
        return err or ""


def random_bytes(rng: random.Random, n: int) -> bytes:
    return bytes(rng.randrange(256) for _ in range(n))
