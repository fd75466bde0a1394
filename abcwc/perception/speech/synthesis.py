"""Test speech from Debian's offline synthesisers, so that no recording of a person is
needed: the same sentence by several speakers, at several rates and pitches.

Three engines (each a Debian main package):

* **espeak-ng** (``espeak-ng``), a formant synthesiser: it builds each sound from a few
  resonances, so its voices are intelligible but unlike any one speaker, and the
  acoustic model knows them badly (their commands' words score -5 to -7 per frame
  where a person's score about -3: ``recognizer`` module notes). A hard, repeatable
  stress test.
* **flite** (``flite``): voices made from recordings of people, kal (diphones) and
  awb, rms and slt (statistical parametric voices from CMU ARCTIC recordings).
* **festival** (``festival`` with ``festvox-kallpc16k``, ``festvox-kdlpc16k`` and
  ``festvox-us-slt-hts``): kal and ked (diphones) and slt (HTS).

A ``Voice`` names its engine, the engine's voice and the *speaker* whose recordings it
was made from: kal and slt each speak through both flite and festival, so a split of
voices into tuning and held-out sets is made by speaker (``TUNING_SPEAKERS``,
``HELD_OUT_SPEAKERS``), never by engine. Each engine's output is deterministic for a
given version, so each utterance is synthesised once: it is kept in memory, and the
engine's WAV on disk under the cache folder (:func:`abcwc.paths.cache_folder`,
``speech/``; chapter 04 and its tests keep 370 utterances, 22 MB), keyed by the engines' Debian
package versions (:func:`engine_versions`), this module's code, the voice and the text;
a notebook run again, its student copy and the tests read it there.
Where the versions cannot be read, or the folder cannot be written, it is only kept in
memory.

Rate and pitch are asked of the engine itself: ``rate`` scales the speaking rate
(1.2 is 20 % faster than the voice's own) and ``pitch`` moves the mean fundamental
frequency by semitones. How each engine takes them:

* espeak-ng: ``-s 160 * rate`` words per minute; ``-p 50 + 6 * pitch`` (its 0-99
  scale: 20 steps moved en-us's mean F0 by 3.3 semitones, 105 to 127 Hz, measured by
  autocorrelation here);
* flite: ``duration_stretch = 1 / rate``; ``int_f0_target_mean`` set to the voice's
  own mean F0 (``FLITE_OWN_F0_HZ``, measured the same way) moved by ``pitch``
  semitones (rms keeps its own pitch whatever it is asked);
* festival diphones: ``Duration_Stretch = 1 / rate``; ``target_f0_mean`` of
  ``int_lr_params`` from the voices' own 105 Hz; festival HTS (slt): hts_engine's
  ``-r rate``, and no pitch shift (festival's hts_engine ignores ``-fm``: its output
  was the same to the byte), so its voices differ in rate only.
"""

from __future__ import annotations

import hashlib
import io
import shutil
import subprocess
import tempfile
import wave
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from abcwc.paths import cache_folder, write_whole
from abcwc.perception.speech.audio import SAMPLE_RATE, to_float_audio

ENGINES = {"espeak-ng": "espeak-ng", "flite": "flite", "festival": "text2wave"}
"""Engine name -> the program that runs it."""
DEBIAN_PACKAGES = {"espeak-ng": "espeak-ng", "flite": "flite",
                   "festival": "festival festvox-kallpc16k festvox-kdlpc16k "
                               "festvox-us-slt-hts"}
FLITE_OWN_F0_HZ = {"kal16": 86.0, "awb": 128.0, "rms": 102.0, "slt": 172.0}
"""Mean F0 of each flite voice as it speaks by default (Hz), by autocorrelation."""
FESTIVAL_VOICES = {"kal": "kal_diphone", "ked": "ked_diphone",
                   "slt": "cmu_us_slt_arctic_hts"}
"""festival voice name -> its ``(voice_...)`` function."""
FESTIVAL_DIPHONE_F0_HZ = 105.0          # target_f0_mean in kal's and ked's definitions


@dataclass(frozen=True)
class Voice:
    """A voice: the engine's voice ``name`` (``espeak-ng --voices=en``, ``flite -lv``, or
    one of ``FESTIVAL_VOICES``), its ``engine``, the ``speaker`` it was made from (for
    espeak-ng, the voice name itself), the speaking ``rate`` (1 is the voice's own) and
    the ``pitch`` shift (semitones)."""

    name: str
    engine: str = "espeak-ng"
    speaker: str = ""
    rate: float = 1.0
    pitch: float = 0.0

    def __post_init__(self) -> None:
        if self.engine not in ENGINES:
            raise ValueError(f"engine {self.engine!r} is not one of {', '.join(ENGINES)}")
        if self.engine == "flite" and self.name not in FLITE_OWN_F0_HZ:
            raise ValueError(f"flite voice {self.name!r} is not one of "
                             f"{', '.join(FLITE_OWN_F0_HZ)}")
        if self.engine == "festival" and self.name not in FESTIVAL_VOICES:
            raise ValueError(f"festival voice {self.name!r} is not one of "
                             f"{', '.join(FESTIVAL_VOICES)}")
        if not 0.5 <= self.rate <= 2.0:
            raise ValueError(f"rate must be 0.5-2.0 times the voice's own, got {self.rate}")
        if not -8.0 <= self.pitch <= 8.0:
            raise ValueError(f"pitch must be -8 to 8 semitones, got {self.pitch}")
        if self.engine == "festival" and self.name == "slt" and self.pitch != 0.0:
            raise ValueError("festival's HTS voice slt takes no pitch shift (pitch=0): "
                             "its engine ignores one")
        if not self.speaker:
            object.__setattr__(self, "speaker", self.name)

    @property
    def label(self) -> str:
        """``engine:name`` with its rate and pitch when they are not the voice's own."""
        extra = "" if self.rate == 1.0 else f" x{self.rate:g}"
        extra += "" if self.pitch == 0.0 else f" {self.pitch:+g} st"
        return f"{self.engine}:{self.name}{extra}"


def _varied(engine: str, name: str, speaker: str) -> tuple[Voice, ...]:
    """One voice at its own rate and pitch, faster and higher, slower and lower (the
    rate alone for festival's slt)."""
    shift = 0.0 if (engine, name) == ("festival", "slt") else 2.0
    return tuple(Voice(name, engine, speaker, rate, pitch)
                 for rate, pitch in ((1.0, 0.0), (1.15, shift), (0.88, -shift)))


TUNING_SPEAKERS = ("awb", "rms", "ked")
"""Speakers (flite's awb and rms, festival's ked) whose voices the thresholds were set on,
beside the espeak-ng ``ESPEAK_TUNING_VOICES``."""
HELD_OUT_SPEAKERS = ("kal", "slt")
"""Speakers no threshold was set on, each in both flite and festival."""

TUNING_VOICES = (_varied("flite", "awb", "awb") + _varied("flite", "rms", "rms")
                 + _varied("festival", "ked", "ked"))
HELD_OUT_VOICES = (_varied("flite", "kal16", "kal") + _varied("festival", "kal", "kal")
                   + _varied("flite", "slt", "slt") + _varied("festival", "slt", "slt"))
ESPEAK_TUNING_VOICES = (Voice("en-us"), Voice("en-us+f2", rate=0.94, pitch=1.7),
                        Voice("en-gb-x-rp", rate=1.06, pitch=-0.8),
                        Voice("en-us+m3", rate=0.88, pitch=-1.7))
ESPEAK_STRESS_VOICES = (Voice("en-us-nyc", rate=1.03), Voice("en-us+f4", rate=0.97, pitch=2.5),
                        Voice("en-gb", rate=0.94), Voice("en-us+m7", rate=1.09, pitch=-2.5),
                        Voice("en-gb-x-rp+f3", rate=0.91, pitch=0.8))
"""espeak-ng voices no threshold was set on: the formant voices' figures, printed beside
the held-out speakers'."""


def engine_available(engine: str) -> bool:
    """True when ``engine``'s program is on the PATH."""
    return shutil.which(ENGINES[engine]) is not None


def missing_engines() -> list[str]:
    """The engines whose programs are not installed."""
    return [engine for engine in ENGINES if not engine_available(engine)]


def espeak_available() -> bool:
    """True when the espeak-ng program is on the PATH."""
    return engine_available("espeak-ng")


def engine_versions() -> tuple[str, ...] | None:
    """The engines' Debian packages (``DEBIAN_PACKAGES``) as ``package=version``, read
    with ``dpkg-query``: what a voice's audio depends on besides its text and settings.
    None where they cannot be read (no ``dpkg-query``, or a package not installed)."""
    packages = " ".join(DEBIAN_PACKAGES.values()).split()
    try:
        listed = subprocess.run(["dpkg-query", "-W", "-f=${Package}=${Version}\\n", *packages],
                                capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return None
    return tuple(sorted(listed.split()))


def speak(text: str, voice: Voice = Voice("en-us")) -> np.ndarray:
    """``text`` spoken in ``voice``: float audio in [-1, 1] at 16 kHz. Deterministic,
    so the last 1024 are kept in memory (as float32), and every engine's WAV on disk
    (module notes): synthesis takes 10-600 ms each.

    Raises ``RuntimeError`` when the voice's engine is not installed (the message
    names the Debian packages) and ``ValueError`` for an empty text."""
    if not text.strip():
        raise ValueError("nothing to say: the text is empty")
    if not engine_available(voice.engine):
        raise RuntimeError(f"{voice.engine} is not installed (Debian: apt install "
                           f"{DEBIAN_PACKAGES[voice.engine]})")
    return _spoken(" ".join(text.split()), voice).astype(np.float64)


@lru_cache(maxsize=1024)
def _spoken(text: str, voice: Voice) -> np.ndarray:
    kept = _kept_at(text, voice)
    heard = _read_kept(kept) if kept is not None else None
    if heard is None:
        wav = {"espeak-ng": _espeak, "flite": _flite, "festival": _festival}[voice.engine](
            text, voice)
        if kept is not None:
            _keep(kept, wav)
        heard = _samples_of(wav)
    rate, samples = heard
    return to_float_audio(samples, rate).astype(np.float32)


def _samples_of(wav: bytes) -> tuple[int, np.ndarray]:
    """A WAV's sample rate (Hz) and its int16 samples, as many as it holds."""
    with wave.open(io.BytesIO(wav)) as w:
        return w.getframerate(), np.frombuffer(w.readframes(w.getnframes()), np.int16)


@lru_cache(maxsize=1)
def _what_the_audio_depends_on() -> str | None:
    """A hash of the engines' package versions and of this module (how each engine is
    asked); None where the versions cannot be read."""
    versions = engine_versions()
    if versions is None:
        return None
    digest = hashlib.sha256("\n".join(versions).encode())
    digest.update(Path(__file__).read_bytes())
    return digest.hexdigest()


def _kept_at(text: str, voice: Voice) -> Path | None:
    """Where the engine's WAV of ``text`` in ``voice`` is kept on disk (module notes);
    None where the engines' versions cannot be read."""
    depends_on = _what_the_audio_depends_on()
    if depends_on is None:
        return None
    key = hashlib.sha256(f"{depends_on}\n{voice!r}\n{text}".encode()).hexdigest()
    return cache_folder() / "speech" / f"{key}.wav"


def _read_kept(path: Path) -> tuple[int, np.ndarray] | None:
    """The sample rate and samples of the WAV kept at ``path``; None if there is none,
    or it holds fewer samples than its header says (not a whole WAV)."""
    try:
        wav = path.read_bytes()
        with wave.open(io.BytesIO(wav)) as w:
            promised = w.getnframes() * w.getnchannels()
        rate, samples = _samples_of(wav)
    except (OSError, EOFError, wave.Error):
        return None
    return (rate, samples) if len(samples) == promised else None


def _keep(path: Path, wav: bytes) -> None:
    """Write ``wav`` to ``path`` whole (:func:`abcwc.paths.write_whole`); where it cannot
    be written, nothing is kept."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        write_whole(path, wav)
    except OSError:
        pass


def _espeak(text: str, voice: Voice) -> bytes:
    pitch = int(round(min(99.0, max(0.0, 50 + 6 * voice.pitch))))
    return subprocess.run(["espeak-ng", "--stdout", "-v", voice.name, "-s",
                           str(int(round(160 * voice.rate))), "-p", str(pitch), text],
                          capture_output=True, check=True).stdout


def _flite(text: str, voice: Voice) -> bytes:
    f0 = FLITE_OWN_F0_HZ[voice.name] * 2 ** (voice.pitch / 12)
    with tempfile.NamedTemporaryFile(suffix=".wav") as out:
        subprocess.run(["flite", "-voice", voice.name, "--setf",
                        f"duration_stretch={1 / voice.rate:.4f}", "--setf",
                        f"int_f0_target_mean={f0:.1f}", "-t", text, "-o", out.name],
                       capture_output=True, check=True)
        return out.read()


def _festival(text: str, voice: Voice) -> bytes:
    setup = [f"(voice_{FESTIVAL_VOICES[voice.name]})"]
    if voice.name == "slt":       # HTS: hts_engine's own speed
        setup.append(f"(set! hts_engine_params (append hts_engine_params "
                     f"'((\"-r\" {voice.rate:.4f}))))")
    else:
        f0 = FESTIVAL_DIPHONE_F0_HZ * 2 ** (voice.pitch / 12)
        setup += [f"(Parameter.set 'Duration_Stretch {1 / voice.rate:.4f})",
                  f"(set! int_lr_params (cons (list 'target_f0_mean {f0:.1f}) "
                  f"int_lr_params))"]
    with tempfile.NamedTemporaryFile(suffix=".wav") as out:
        command = ["text2wave", "-o", out.name]
        for expression in setup:
            command += ["-eval", expression]
        subprocess.run(command, input=text.encode(), capture_output=True, check=True)
        return out.read()


def padded(x: np.ndarray, seconds: float = 0.3) -> np.ndarray:
    """``x`` with ``seconds`` of silence before and after, as a push-to-talk button or a
    voice-activity detector would cut an utterance."""
    pad = np.zeros(int(round(seconds * SAMPLE_RATE)))
    return np.concatenate([pad, x, pad])
