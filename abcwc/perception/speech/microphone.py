"""The instructor's microphone: one utterance recorded with sounddevice (the optional
extra ``pip install abcwc[mic]``; on Debian it needs ``libportaudio2``), ready for
``CommandRecognizer.recognise``.

A machine without the library, without PortAudio or without an input device gets a
:class:`~abcwc.devices.DeviceUnavailableError` that says which, never sounddevice's own
``PortAudioError`` (``Error querying device -1`` is what PortAudio says when there is no
default input device).
"""

from __future__ import annotations

import math

import numpy as np

from abcwc.devices import DeviceUnavailableError
from abcwc.perception.speech.audio import MAX_SECONDS, SAMPLE_RATE

INSTALL = "pip install 'abcwc[mic]' and, on Debian, apt install libportaudio2"
"""How to get sounddevice and PortAudio."""


def record_utterance(seconds: float = 2.5, rate: int = SAMPLE_RATE,
                     device: int | str | None = None) -> np.ndarray:
    """``seconds`` of mono int16 audio from the default (or the given) input device.

    Raises:
        ValueError: a duration outside 0.5-30 s.
        DeviceUnavailableError: sounddevice or PortAudio is missing, there is no such
            input device (or no default one), or PortAudio could not record from it.
    """
    if not (math.isfinite(seconds) and 0.5 <= seconds <= MAX_SECONDS):
        raise ValueError(f"seconds must be 0.5-{MAX_SECONDS:.0f} s, got {seconds}")
    try:
        import sounddevice
    except (ImportError, OSError) as error:  # OSError: the PortAudio library is missing
        raise DeviceUnavailableError(
            f"the microphone needs sounddevice and PortAudio ({error}): {INSTALL}") from error
    which = "the default input device" if device is None else f"input device {device!r}"
    try:
        sounddevice.check_input_settings(device=device, channels=1, dtype="int16",
                                         samplerate=rate)
    except (sounddevice.PortAudioError, ValueError) as error:
        raise DeviceUnavailableError(
            f"no microphone: PortAudio cannot open {which} ({error}); plug one in, or "
            "pick one with device= (python -m sounddevice lists them)") from error
    try:
        audio = sounddevice.rec(int(round(seconds * rate)), samplerate=rate, channels=1,
                                dtype="int16", device=device)
        sounddevice.wait()
    except sounddevice.PortAudioError as error:
        raise DeviceUnavailableError(
            f"the microphone stopped: PortAudio could not record from {which} ({error}); "
            "is another program using it?") from error
    return np.asarray(audio).reshape(-1)
