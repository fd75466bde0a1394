"""Build the firmware with avr-gcc, run the core's unit tests on the host
(ASan + UBSan) and on a simulated ATmega2560, and fuzz the frame parser."""

from __future__ import annotations

import re

from firmware_helpers import ELF, make, require_tools


def test_firmware_builds_and_fits():
    require_tools("make", "avr-gcc")
    out = make("firmware").stdout
    assert ELF.exists() and ELF.with_suffix(".hex").exists()
    m = re.search(r"flash (\d+) of 253952 bytes .*static RAM (\d+) of 8192 bytes", out)
    assert m, out
    flash, ram = int(m.group(1)), int(m.group(2))
    print(f"abcwc_firmware: flash {flash} B, static RAM {ram} B")
    assert flash < 64 * 1024
    assert ram < 2048, "leave most of the 8 KB for the stack"


def test_core_unit_tests_on_host():
    require_tools("make", "gcc")
    out = make("test").stdout
    assert "RESULT PASS" in out, out


def test_core_unit_tests_on_avr():
    """The same tests on the ATmega2560 under simavr, where int is 16 bits."""
    require_tools("make", "avr-gcc", "simavr")
    out = make("avr-test").stdout
    assert "RESULT PASS" in out, out
    assert "0 failures" in out, out


def test_fuzz_frame_parser():
    require_tools("make", "clang")
    proc = make("fuzz", FUZZ_TIME="20", timeout=300)
    text = proc.stdout + proc.stderr
    assert "Done" in text and "runs in" in text, text[-2000:]
