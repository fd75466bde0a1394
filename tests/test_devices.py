"""A missing device never crashes a real-chair cell: each hardware path raises a
DeviceUnavailableError naming what is missing and how to get it, and hardware_chair
prints it and goes on.

Each device is faked away: sounddevice without a library or without an input device
(PortAudio's "Error querying device -1"), a serial port that does not exist, will not
open or has another firmware on it, and a PATH without the AVR toolchain.
"""

from __future__ import annotations

import errno
import os
import shutil
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from abcwc.connect import hardware_chair
from abcwc.devices import DeviceUnavailableError
from abcwc.hw import fil_base
from abcwc.hw.link import (
    ChairLinkError,
    NoSuchPortError,
    NotOurFirmwareError,
    PortUnusableError,
    ProtocolVersionError,
)
from abcwc.hw.serial_base import SerialBase
from abcwc.params import default_params
from abcwc.perception.speech.microphone import record_utterance

CONNECT = sys.modules["abcwc.connect"]  # the package's ``connect`` is the function


def test_every_not_here_error_is_a_runtime_error_and_the_link_ones_are_link_errors():
    for error in (NoSuchPortError, PortUnusableError, NotOurFirmwareError,
                  ProtocolVersionError, fil_base.FirmwareToolchainError):
        assert issubclass(error, DeviceUnavailableError) and issubclass(error, RuntimeError)
    for error in (NoSuchPortError, PortUnusableError, NotOurFirmwareError,
                  ProtocolVersionError):
        assert issubclass(error, ChairLinkError)
    assert issubclass(NoSuchPortError, FileNotFoundError)
    # a link failing mid-run and a firmware that does not build are errors, not absences
    assert not issubclass(ChairLinkError, DeviceUnavailableError)
    assert not issubclass(fil_base.FirmwareBuildError, DeviceUnavailableError)


# ------------------------------------------------------------------ the microphone


class PortAudioError(Exception):
    """sounddevice's own error class (it derives from Exception only)."""


def fake_sounddevice(monkeypatch, *, check=None, rec=None) -> list:
    """Install a sounddevice whose check_input_settings and rec raise what is given (or
    record a ramp); returns the calls made."""
    calls = []

    def check_input_settings(**settings):
        calls.append(("check", settings))
        if check is not None:
            raise check

    def record(frames, **settings):
        calls.append(("rec", frames, settings))
        if rec is not None:
            raise rec
        return (np.arange(frames) % 100).astype(np.int16).reshape(-1, 1)

    module = types.SimpleNamespace(PortAudioError=PortAudioError, rec=record,
                                   check_input_settings=check_input_settings,
                                   wait=lambda: calls.append(("wait",)))
    monkeypatch.setitem(sys.modules, "sounddevice", module)
    return calls


def test_no_sounddevice_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "sounddevice", None)  # import raises ImportError
    with pytest.raises(DeviceUnavailableError, match=r"pip install 'abcwc\[mic\]'.*"
                                                     r"apt install libportaudio2"):
        record_utterance()


def test_portaudio_without_an_input_device_says_there_is_no_microphone(monkeypatch):
    calls = fake_sounddevice(monkeypatch, check=PortAudioError("Error querying device -1"))
    with pytest.raises(DeviceUnavailableError,
                       match=r"no microphone: PortAudio cannot open the default input device "
                             r"\(Error querying device -1\); plug one in"):
        record_utterance()
    assert [c[0] for c in calls] == ["check"]  # nothing recorded


def test_a_named_device_that_is_not_there_is_named(monkeypatch):
    fake_sounddevice(monkeypatch, check=ValueError("No input device matching 'usb'"))
    with pytest.raises(DeviceUnavailableError, match=r"input device 'usb' \(No input device"):
        record_utterance(device="usb")


def test_a_microphone_that_fails_while_recording_says_so(monkeypatch):
    fake_sounddevice(monkeypatch, rec=PortAudioError("Device unavailable [PaErrorCode -9985]"))
    with pytest.raises(DeviceUnavailableError, match=r"the microphone stopped: .*-9985"):
        record_utterance()


def test_a_working_microphone_records_the_asked_length(monkeypatch):
    calls = fake_sounddevice(monkeypatch)
    audio = record_utterance(seconds=0.5, rate=16000)
    assert audio.shape == (8000,) and audio.dtype == np.int16 and audio[101] == 1
    assert calls[0] == ("check", {"device": None, "channels": 1, "dtype": "int16",
                                  "samplerate": 16000})
    assert calls[1][1] == 8000 and calls[2] == ("wait",)
    with pytest.raises(ValueError, match="0.5-30 s"):
        record_utterance(seconds=0.1)


# ------------------------------------------------------------------ the cell


class FakeChair:
    """A body that opened: what hardware_chair reads and closes."""

    params = default_params()

    def __init__(self) -> None:
        self.closed = False

    def close(self) -> None:
        self.closed = True


@pytest.fixture()
def fake_chair(monkeypatch):
    chair = FakeChair()
    monkeypatch.setattr(CONNECT, "_hardware_body", lambda port, options: chair)
    return chair


def test_the_chapter_04_cell_without_a_microphone_stops_and_goes_on(fake_chair, monkeypatch,
                                                                    capsys):
    fake_sounddevice(monkeypatch, check=PortAudioError("Error querying device -1"))
    went_on = False
    with hardware_chair(port="/dev/ttyACM0") as real:
        assert real is fake_chair
        record_utterance()
        raise AssertionError("not reached: the block ends at the missing microphone")
    went_on = True
    out = capsys.readouterr().out
    assert went_on and fake_chair.closed
    assert "Stopped this real-chair cell: no microphone: PortAudio cannot open" in out


def test_a_link_that_fails_in_the_cell_is_not_swallowed(fake_chair):
    with pytest.raises(ChairLinkError, match="cable"), hardware_chair(port="/dev/ttyACM0"):
        raise ChairLinkError("chair link on /dev/ttyACM0: reading failed; is the cable "
                             "unplugged?")
    assert fake_chair.closed


# ------------------------------------------------------------------ the serial port


def test_a_port_that_does_not_exist_skips_the_cell(capsys):
    with hardware_chair(port="/dev/abcwc-no-such-port") as real:
        assert real is None
    out = capsys.readouterr().out
    assert out.startswith("Skipping this real-chair cell: serial port "
                          "'/dev/abcwc-no-such-port' does not exist; ")
    assert "ports on this machine" in out or "no serial ports found" in out


@pytest.mark.parametrize("code, says", [
    (errno.EACCES, "opened: permission denied: add yourself to the group that owns it, on "
                   "Debian 'sudo usermod -aG dialout $USER', then log out and in again"),
    (errno.EBUSY, "ttyACM0'; is another program (a serial monitor?) using it?"),
])
def test_a_port_that_will_not_open_says_why(monkeypatch, tmp_path, capsys, code, says):
    import serial

    port = tmp_path / "ttyACM0"
    port.touch()

    def refuse(name, *args, **kwargs):
        raise serial.SerialException(code, f"could not open port {name}: [Errno {code}] "
                                           f"{os.strerror(code)}: '{name}'")

    monkeypatch.setattr(serial, "Serial", refuse)
    with pytest.raises(PortUnusableError) as info:
        SerialBase(str(port))
    assert str(info.value).startswith(f"serial port '{port}' could not be opened: ")
    assert str(info.value).endswith(says)
    with hardware_chair(port=str(port)) as real:
        assert real is None
    assert capsys.readouterr().out.startswith("Skipping this real-chair cell: serial port")


@pytest.fixture()
def silent_device():
    """A pty that says nothing but noise: a device that is not our firmware."""
    master, slave = os.openpty()
    os.write(master, b"hello from another sketch\r\n" * 4)
    yield os.ttyname(slave)
    os.close(master)
    os.close(slave)


def test_a_device_that_is_not_our_firmware_says_so(silent_device, capsys):
    with pytest.raises(NotOurFirmwareError,
                       match=rf"the device on {silent_device} does not answer as "
                             r"abcwc_firmware: no HELLO within 0.4 s .*make -C firmware flash"):
        SerialBase(silent_device, ready_timeout=0.4)
    with hardware_chair(port=silent_device) as real:
        assert real is None
    assert "does not answer as abcwc_firmware" in capsys.readouterr().out


# ------------------------------------------------------------------ simavr and avr-gcc


def test_no_avr_toolchain_names_the_packages_and_skips_the_cell(monkeypatch, tmp_path,
                                                                 capsys):
    monkeypatch.setenv("PATH", str(tmp_path))  # no make, gcc, avr-gcc
    monkeypatch.setattr(fil_base, "SIMAVR_HEADER", tmp_path / "sim_avr.h")  # no simavr
    assert {"make", "gcc", "avr-gcc", "libsimavr-dev"} <= set(fil_base.missing_tools())
    with pytest.raises(fil_base.FirmwareToolchainError,
                       match=r"needs make, gcc, avr-gcc, .*libsimavr-dev: sudo apt-get "
                             r"install .*gcc-avr avr-libc .*simavr libsimavr-dev"):
        fil_base.build_harness()
    with hardware_chair(port="simavr", world="lab", people=False) as real:
        assert real is None
    out = capsys.readouterr().out
    assert out.startswith("Skipping this real-chair cell: the firmware in the loop needs make")


def test_no_firmware_sources_says_a_checkout_is_needed(tmp_path):
    with pytest.raises(fil_base.FirmwareToolchainError, match="needs a checkout"):
        fil_base.build_harness(tmp_path)


@pytest.mark.skipif(shutil.which("make") is None, reason="needs make")
def test_a_firmware_that_does_not_build_is_an_error_not_an_absence(monkeypatch, tmp_path):
    (tmp_path / "Makefile").write_text("harness:\n\t@echo broken on purpose; false\n")
    monkeypatch.setattr(fil_base, "missing_tools", lambda: [])
    with pytest.raises(fil_base.FirmwareBuildError, match="broken on purpose"):
        fil_base.build_harness(Path(tmp_path))
