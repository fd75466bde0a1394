"""The instructor's microphone: one utterance recorded with sounddevice (the optional
extra ``pip install abcwc[mic]``; on Debian it needs ``libportaudio2``), ready for
``CommandRecognizer.recognise``."""

from __future__ import annotations

import math

import numpy as np

from abcwc.perception.speech.audio import MAX_SECONDS, SAMPLE_RATE


def record_utterance(seconds: float = 2.5, rate: int = SAMPLE_RATE,
                     device: int | str | None = None) -> np.ndarray:
    """``seconds`` of mono int16 audio from the default (or the given) input device.

    Raises ``RuntimeError`` with the install line when sounddevice or PortAudio is
    missing, and ``ValueError`` for a duration outside 0.5-30 s."""
    if not (math.isfinite(seconds) and 0.5 <= seconds <= MAX_SECONDS):
        raise ValueError(f"seconds must be 0.5-{MAX_SECONDS:.0f} s, got {seconds}")
    try:
        import sounddevice
    except (ImportError, OSError) as error:  # OSError: the PortAudio library is missing
        raise RuntimeError("the microphone needs sounddevice and PortAudio: "
                           "pip install 'abcwc[mic]' and, on Debian, "
                           "apt install libportaudio2") from error
    frames = int(round(seconds * rate))
    audio = sounddevice.rec(frames, samplerate=rate, channels=1, dtype="int16",
                            device=device)
    sounddevice.wait()
    return np.asarray(audio).reshape(-1)
