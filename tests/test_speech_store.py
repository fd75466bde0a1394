"""Synthesised speech kept on disk: each utterance is synthesised once, read back to the
bit, keyed by the engines' versions; nothing kept where the versions cannot be read or
the folder cannot be written. The engine is replaced by a stand-in that counts its calls
(so these run without Debian's synthesisers)."""

import io
import wave

import numpy as np
import pytest

from abcwc.perception.speech import synthesis
from abcwc.perception.speech.audio import SAMPLE_RATE
from abcwc.perception.speech.synthesis import Voice, speak

VERSIONS = ("espeak-ng=1.51", "flite=2.2", "festival=2.5")


def _tone_wav(text: str) -> bytes:
    """A WAV of int16 samples that depend on ``text``: a tone 0.2 s long."""
    t = np.arange(int(0.2 * SAMPLE_RATE)) / SAMPLE_RATE
    samples = (8000 * np.sin(2 * np.pi * (200 + len(text)) * t)).astype(np.int16)
    out = io.BytesIO()
    with wave.open(out, "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(SAMPLE_RATE)
        w.writeframes(samples.tobytes())
    return out.getvalue()


@pytest.fixture
def engine(monkeypatch, tmp_path):
    """The espeak-ng stand-in: the texts it was asked to say, in order."""
    said: list[str] = []

    def fake_espeak(text, voice):
        said.append(text)
        return _tone_wav(text)

    monkeypatch.setenv("ABCWC_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setattr(synthesis, "engine_available", lambda engine: True)
    monkeypatch.setattr(synthesis, "_espeak", fake_espeak)
    monkeypatch.setattr(synthesis, "engine_versions", lambda: VERSIONS)
    _forget_in_memory()
    yield said
    _forget_in_memory()


def _forget_in_memory():
    """Clear what the synthesis module keeps in memory, as a new process starts."""
    synthesis._spoken.cache_clear()
    synthesis._what_the_audio_depends_on.cache_clear()


def test_an_utterance_is_synthesised_once_and_read_back_to_the_bit(engine, tmp_path):
    first = speak("turn left", Voice("en-us"))
    _forget_in_memory()  # a new process: only the disk remembers
    again = speak("turn left", Voice("en-us"))
    assert engine == ["turn left"]
    assert again.dtype == first.dtype and np.array_equal(again, first)
    assert len(list((tmp_path / "cache" / "speech").glob("*.wav"))) == 1
    # another text or another voice is another utterance
    speak("turn right", Voice("en-us"))
    speak("turn left", Voice("en-us", rate=1.2))
    assert engine == ["turn left", "turn right", "turn left"]


def test_other_engine_versions_synthesise_again(engine, monkeypatch):
    speak("stop", Voice("en-us"))
    _forget_in_memory()
    monkeypatch.setattr(synthesis, "engine_versions", lambda: ("espeak-ng=1.52",))
    speak("stop", Voice("en-us"))
    assert engine == ["stop", "stop"]


def test_without_the_versions_nothing_is_kept_on_disk(engine, monkeypatch, tmp_path):
    monkeypatch.setattr(synthesis, "engine_versions", lambda: None)
    speak("stop", Voice("en-us"))
    _forget_in_memory()
    speak("stop", Voice("en-us"))
    assert engine == ["stop", "stop"]
    assert not (tmp_path / "cache").exists()


def test_where_nothing_can_be_written_it_still_speaks(engine, monkeypatch, tmp_path):
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setenv("ABCWC_CACHE_DIR", str(blocked / "cache"))
    spoken = speak("stop", Voice("en-us"))
    assert spoken.size == int(0.2 * SAMPLE_RATE)
    _forget_in_memory()
    assert np.array_equal(speak("stop", Voice("en-us")), spoken)
    assert engine == ["stop", "stop"]


def test_a_damaged_file_is_synthesised_again(engine, tmp_path):
    first = speak("stop", Voice("en-us"))
    (kept,) = (tmp_path / "cache" / "speech").glob("*.wav")
    whole = kept.read_bytes()
    kept.write_bytes(b"not a wav")
    _forget_in_memory()
    assert np.array_equal(speak("stop", Voice("en-us")), first)
    kept.write_bytes(whole[:-100])  # its header promises more samples than it holds
    _forget_in_memory()
    assert np.array_equal(speak("stop", Voice("en-us")), first)
    assert engine == ["stop", "stop", "stop"]
    assert kept.read_bytes() == whole
