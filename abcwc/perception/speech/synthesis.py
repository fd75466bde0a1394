"""Test speech made by espeak-ng (Debian's ``espeak-ng``), so that no recording of a
person is needed: the same sentence in several voices, at several speeds and pitches.

espeak-ng is a formant synthesiser: its voices are intelligible but unlike any one
speaker, which makes them a fair, repeatable test of a recogniser and a hard one (a
person is usually recognised better). Its output is deterministic for a given version.
"""

from __future__ import annotations

import io
import shutil
import subprocess
import wave
from dataclasses import dataclass

import numpy as np

from abcwc.perception.speech.audio import SAMPLE_RATE, to_float_audio

ESPEAK = "espeak-ng"


@dataclass(frozen=True)
class Voice:
    """An espeak-ng voice: its name (``espeak-ng --voices=en`` lists them; ``+f2`` and the
    like are variants), speed in words per minute and pitch (0-99, 50 is the default)."""

    name: str
    speed: int = 160
    pitch: int = 50


# The voices the recogniser's thresholds were set on, and the voices it is tested on,
# which it never saw: other speakers, accents, speeds and pitches.
TUNING_VOICES = (Voice("en-us"), Voice("en-us+f2", 150, 60), Voice("en-gb-x-rp", 170, 45),
                 Voice("en-us+m3", 140, 40))
TEST_VOICES = (Voice("en-us-nyc", 165, 50), Voice("en-us+f4", 155, 65),
               Voice("en-gb", 150, 50), Voice("en-us+m7", 175, 35),
               Voice("en-gb-x-rp+f3", 145, 55))


def espeak_available() -> bool:
    """True when the espeak-ng program is on the PATH."""
    return shutil.which(ESPEAK) is not None


def speak(text: str, voice: Voice = Voice("en-us")) -> np.ndarray:
    """``text`` spoken by espeak-ng in ``voice``: float audio in [-1, 1] at 16 kHz.

    Raises ``RuntimeError`` when espeak-ng is not installed (Debian: ``apt install
    espeak-ng``) and ``ValueError`` for an empty text."""
    if not text.strip():
        raise ValueError("nothing to say: the text is empty")
    if not espeak_available():
        raise RuntimeError("espeak-ng is not installed (Debian: apt install espeak-ng)")
    wav = subprocess.run([ESPEAK, "--stdout", "-v", voice.name, "-s", str(voice.speed),
                          "-p", str(voice.pitch), text],
                         capture_output=True, check=True).stdout
    with wave.open(io.BytesIO(wav)) as w:
        rate = w.getframerate()
        samples = np.frombuffer(w.readframes(w.getnframes()), np.int16)
    return to_float_audio(samples, rate)


def padded(x: np.ndarray, seconds: float = 0.3) -> np.ndarray:
    """``x`` with ``seconds`` of silence before and after, as a push-to-talk button or a
    voice-activity detector would cut an utterance."""
    pad = np.zeros(int(round(seconds * SAMPLE_RATE)))
    return np.concatenate([pad, x, pad])
