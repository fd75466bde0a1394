"""Plots of spoken commands: an utterance's waveform and spectrogram with the words the
grammar aligned, and the likelihood ratios that separate commands from conversation."""

from __future__ import annotations

from collections.abc import Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from abcwc.experiments.speech_trials import Trial
from abcwc.perception.speech.audio import SAMPLE_RATE


def plot_utterances(utterances: Sequence[tuple[str, np.ndarray]]) -> Figure:
    """Each (title, int16 audio at 16 kHz) as its waveform over its spectrogram (0-8
    kHz, dB), one column each."""
    fig, axes = plt.subplots(2, len(utterances), figsize=(4.2 * len(utterances), 4.2),
                             layout="constrained", squeeze=False,
                             gridspec_kw={"height_ratios": [1, 2]})
    for k, (title, audio) in enumerate(utterances):
        x = np.asarray(audio, dtype=float) / 32768.0
        t = np.arange(x.size) / SAMPLE_RATE
        wave, spec = axes[0, k], axes[1, k]
        wave.plot(t, x, linewidth=0.5, color="tab:blue")
        wave.set(title=title, xlim=(0, t[-1]), ylim=(-1, 1), ylabel="amplitude")
        spec.specgram(x, NFFT=400, Fs=SAMPLE_RATE, noverlap=240, cmap="magma",
                      vmin=-120, vmax=-20)
        spec.set(xlabel="time (s)", ylabel="frequency (Hz)", xlim=(0, t[-1]))
    return fig


def plot_ratio_separation(trials: Sequence[Trial], max_outside_speech: float = 0.3,
                          threshold: float | None = None) -> Figure:
    """The words' mean log-likelihood ratio per frame of each trial: commands the grammar
    heard right (green) against sentences it bent into a command that the outside-speech
    check let through (red), one row per voice; ``threshold`` drawn if given."""
    voices = list(dict.fromkeys(t.voice.name for t in trials))
    fig, ax = plt.subplots(figsize=(8.0, 0.45 * len(voices) + 1.4), layout="constrained")
    rng = np.random.default_rng(0)  # vertical jitter only, to see points that coincide
    for row, voice in enumerate(voices):
        mine = [t for t in trials if t.voice.name == voice and t.heard.word_llrs]
        right = [t.heard.mean_llr for t in mine if t.is_command and t.heard.phrase == t.text]
        fooled = [t.heard.mean_llr for t in mine if not t.is_command
                  and t.heard.outside_speech <= max_outside_speech]
        ax.scatter(right, row + 0.12 + rng.uniform(-0.08, 0.08, len(right)), s=14,
                   color="tab:green", label="a command, heard right" if row == 0 else None)
        ax.scatter(fooled, row - 0.12 + rng.uniform(-0.08, 0.08, len(fooled)), s=14,
                   color="tab:red", marker="x",
                   label="a sentence the grammar bent into a command" if row == 0 else None)
    if threshold is not None:
        ax.axvline(threshold, color="k", linestyle="--", linewidth=1,
                   label=f"threshold {threshold:.2f}")
    ax.set_yticks(range(len(voices)), voices)
    ax.set(xlabel="words' mean log-likelihood ratio per frame", ylim=(-0.6, len(voices) - 0.4))
    ax.legend(loc="lower left", fontsize=8)
    ax.grid(axis="x", alpha=0.3)
    return fig
