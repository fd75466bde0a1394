"""Offline recognition of the chair's spoken commands with pocketsphinx, restricted to
the command grammar and verified, so that conversation is not taken for a command.

A grammar alone always answers: every sound becomes the command it is least unlike.
So each answer is checked twice before the chair obeys it.

1. **The words are the command's.** In every 10 ms frame the acoustic model scores each
   of its states (5126 senones for the en-us model), and the best of them is the best
   that any sound could do there. Over each word of the grammar's answer, the per-frame
   log-likelihood ratio between the word's alignment and those best states,

       LLR_w = (log p(frames | word) - sum_t max_s log p(x_t | s)) / n_frames,

   is highest when the word was said and much lower when the grammar bent other sounds
   into it (a person's "go forward ten meters", from pocketsphinx's own test recordings,
   scores -3.1 per frame; flite's and festival's voices, made from people's
   recordings, -3 to -6; espeak-ng's formant voices -4 to -7, as the model knows them
   less well): the "on-line garbage" model of utterance verification
   (Bourlard, D'hoore and Boite, "Optimizing recognition and rejection performance in
   wordspotting systems", ICASSP 1994; Jiang, "Confidence measures for speech
   recognition: a survey", Speech Communication 45, 2005). ``word_log_likelihood_ratio``
   states it on a matrix of state scores. pocketsphinx computes it when told to score
   every state in every frame (``compallsen``): each frame's scores are then taken
   relative to the best state's, so a word segment's acoustic score is the numerator
   above. Without it they are relative to the best state the search happened to visit,
   which depends on the grammar: the same "go to the lab" scored 1.0 per frame higher
   with one place in the grammar than with the floor's nine. The answer stands only if
   the command's mean ratio per frame (over all its words' frames, so that a long word
   counts for more than "the") clears ``min_mean_llr`` and its *weakest* word clears
   ``min_word_llr`` (a short word such as "the" scores noisily, so the bound on one word
   is looser than on the mean); a one-word command, which has no second word to vouch
   for it, must clear ``min_single_word_llr``.
2. **Nothing else was said.** A frame is speech when its energy is 12 dB above the
   utterance's quietest frames; at most ``max_outside_speech`` of the speech frames may
   lie outside the command's words. "stop worrying about it" aligns "stop" to its first
   word and calls the rest silence; this check refuses it. A room's echo is not speech:
   after the command's last word, frames whose energy only falls (smoothed over 30 ms,
   never ``ONSET_RISE_DB`` above the quietest frame since the command ended) are its
   reverberant tail, and are not counted; a new word is an onset, a rise of more than
   that (measured with a synthetic room of RT60 0.4 s on the held-out speakers: 66 % of
   the commands were refused for their own echo, 92 % recognised without it, the same
   as in a dry room, with no more sentences let through). When the grammar draws a
   command out over a whole sentence ("I forgot to go to the store" heard as "drive
   reverse", "reverse" stretched over "go to the store"), no speech lies outside it,
   but its long words fit badly, and the command's mean ratio, taken over all its
   frames, is low.

The thresholds (``Verification``) were set on the tuning speakers and sentences of
``abcwc.experiments.speech_trials`` (``tuned_verification``), and are measured on its
held-out speakers and sentences.
"""

from __future__ import annotations

import math
import os
import tempfile
import time
from dataclasses import dataclass, replace

import numpy as np

from abcwc.perception.speech.adaptation import MeanTransform
from abcwc.perception.speech.audio import SAMPLE_RATE, for_decoding, frame_powers, to_int16
from abcwc.perception.speech.commands import CommandSet, SpokenCommand
from abcwc.perception.speech.model import decoded, model_paths

SPEECH_ABOVE_FLOOR_DB = 12.0
ONSET_RISE_DB = 3.0       # dB a frame's energy must rise over the tail's lowest: new speech


@dataclass(frozen=True)
class Recognition:
    """What was heard: the ``command`` obeyed (None when refused), the grammar's best
    ``phrase`` whether accepted or not, each of its words' log-likelihood ratio per frame
    (``word_llrs``; empty when no command fit), the fraction of the speech outside the
    command's words, each word's number of frames (``word_frames``), why it was
    refused (``reason``, "" when accepted) and the decoding time (s)."""

    command: SpokenCommand | None
    phrase: str
    word_llrs: tuple[tuple[str, float], ...]
    outside_speech: float
    word_frames: tuple[int, ...]
    reason: str
    seconds: float

    @property
    def accepted(self) -> bool:
        return self.command is not None

    @property
    def mean_llr(self) -> float:
        """The command's log-likelihood ratio per frame over all its words' frames: the
        words' ratios weighted by their frames (-inf when no command fit)."""
        if not self.word_llrs:
            return -math.inf
        return float(np.average([v for _, v in self.word_llrs], weights=self.word_frames))

    @property
    def weakest_llr(self) -> float:
        """The weakest word's log-likelihood ratio per frame (-inf when none fit)."""
        return min(v for _, v in self.word_llrs) if self.word_llrs else -math.inf


@dataclass(frozen=True)
class Verification:
    """The thresholds an answer of the grammar must clear (module notes): the command's
    mean log-likelihood ratio per frame (``min_mean_llr``), the weakest word's
    (``min_word_llr``), a one-word command's (``min_single_word_llr``), and the largest
    fraction of the speech outside the command's words (``max_outside_speech``; 1.0
    lets the command be anywhere in the utterance, as a keyword spotter listens).

    The defaults were set by ``speech_trials.tuned_verification`` on the tuning
    speakers made from people's recordings alone (flite's awb and rms and festival's
    ked, each at three rates and pitches) and their sentences: the most commands
    recognised (96 % of 135) with none of the 252 sentence readings taken for a
    command, the strictest such thresholds where several tie. The espeak-ng voices were
    left out of the choice: formant voices no rider has, whose commands score -5 to -7
    per frame, pull the thresholds down to where conversation passes (measured once
    both ways, the held-out speakers' commands were recognised 88 % of the time with
    them in the choice, 92 % without). Tuned again since the decoder hears no DC offset,
    a floor below quiet speech and no echo as speech (``audio.for_decoding``,
    ``speech_outside_fraction``), the choice moves only the single-word bound, to -6.75:
    one tuning command more (95.6 % against 94.8 %), and the same figures to the last
    utterance on the held-out speakers, quiet and at 20 dB SNR; the bound is kept.
    ``Verification.none()`` checks nothing: the grammar's answer as it comes."""

    min_mean_llr: float = -6.0
    min_word_llr: float = -8.5
    min_single_word_llr: float = -6.5
    max_outside_speech: float = 0.1

    def __post_init__(self) -> None:
        for name in ("min_mean_llr", "min_word_llr", "min_single_word_llr"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and not math.isnan(value)
                    and value <= 0 and value != math.inf):
                raise ValueError(f"{name} must be a log-likelihood ratio <= 0 (per frame; "
                                 f"-inf turns the check off), got {value!r}")
        if not 0.0 <= self.max_outside_speech <= 1.0:
            raise ValueError(f"max_outside_speech must be a fraction in [0, 1], "
                             f"got {self.max_outside_speech!r}")

    @classmethod
    def none(cls) -> Verification:
        """No check at all: every answer of the grammar stands."""
        return cls(-math.inf, -math.inf, -math.inf, 1.0)

    def refusal(self, heard: Recognition) -> str:
        """Why the grammar's answer in ``heard`` is refused, or "" when it stands."""
        phrase, word_llrs = heard.phrase, heard.word_llrs
        if not word_llrs:
            return "no command fits the sound from start to end"
        word, weakest = min(word_llrs, key=lambda pair: pair[1])
        mean = heard.mean_llr
        if len(word_llrs) == 1 and weakest < self.min_single_word_llr:
            return (f'"{phrase}" fits the sound badly (log-likelihood ratio {weakest:.2f} '
                    f'per frame; a one-word command needs {self.min_single_word_llr:.2f})')
        if len(word_llrs) > 1 and mean < self.min_mean_llr:
            return (f'"{phrase}" fits the sound badly (mean log-likelihood ratio '
                    f'{mean:.2f} per frame, needed {self.min_mean_llr:.2f})')
        if len(word_llrs) > 1 and weakest < self.min_word_llr:
            return (f'"{word}" fits the sound badly (log-likelihood ratio {weakest:.2f} '
                    f'per frame, needed {self.min_word_llr:.2f})')
        if heard.outside_speech > self.max_outside_speech:
            return (f"{100 * heard.outside_speech:.0f} % of the speech lies outside the "
                    f"command (at most {100 * self.max_outside_speech:.0f} %): more was said")
        return ""


class CommandRecognizer:
    """pocketsphinx with the ``commands`` grammar and the checks of ``verification``.

    ``adaptation``, a speaker's ``MeanTransform`` (``adaptation.enroll``), moves the
    acoustic model's means to that speaker's voice. ``recognise(samples, rate)`` takes
    one utterance (int16, or float in [-1, 1]; any rate from 8 to 96 kHz) and returns a
    ``Recognition``. Bad buffers raise ``AudioError`` with what is allowed."""

    def __init__(self, commands: CommandSet, verification: Verification = Verification(),
                 noise_floor_seed: int = 0, adaptation: MeanTransform | None = None
                 ) -> None:
        from pocketsphinx import Decoder

        if not isinstance(verification, Verification):
            raise ValueError(f"verification must be a Verification, got "
                             f"{type(verification).__name__}")
        if adaptation is not None and not isinstance(adaptation, MeanTransform):
            raise ValueError(f"adaptation must be a MeanTransform (from "
                             f"abcwc.perception.speech.adaptation.enroll), got "
                             f"{type(adaptation).__name__}")
        hmm, dictionary = model_paths()
        self.commands = commands
        self.verification = verification
        self.noise_floor_seed = noise_floor_seed
        self.adaptation = adaptation
        with tempfile.TemporaryDirectory() as work:
            extra = {}
            if adaptation is not None:  # pocketsphinx reads the file as it starts
                extra["mllr"] = os.path.join(work, "speaker.mllr")
                adaptation.write(extra["mllr"])
            self._grammar = Decoder(hmm=hmm, dict=dictionary, lm=None, samprate=SAMPLE_RATE,
                                    compallsen=True, loglevel="FATAL", **extra)
        unknown = sorted(w for w in commands.words() if self._grammar.lookup_word(w) is None)
        if unknown:
            raise ValueError(f"not in the pronunciation dictionary: {', '.join(unknown)}; "
                             f"use other words for these commands or places")
        self._grammar.add_jsgf_string("commands", commands.jsgf())
        self._grammar.activate_search("commands")

    def recognise(self, samples: np.ndarray, rate: int = SAMPLE_RATE) -> Recognition:
        """The command in one utterance, or None with the reason it was refused."""
        started = time.perf_counter()
        x = for_decoding(samples, rate, seed=self.noise_floor_seed)
        pcm = to_int16(x).tobytes()
        phrase, words = self._decode_words(pcm)
        llrs: tuple[tuple[str, float], ...] = ()
        outside = 1.0
        if phrase in self.commands and words:
            llrs = tuple((w, score / (last - first + 1)) for w, score, first, last in words)
            outside = speech_outside_fraction(x, words[0][2], words[-1][3])
        heard = Recognition(None, phrase, llrs, outside,
                            tuple(last - first + 1 for _, _, first, last in words) if llrs
                            else (), "", time.perf_counter() - started)
        return self.judged(heard, self.verification)

    def judged(self, heard: Recognition, verification: Verification) -> Recognition:
        """``heard`` judged with ``verification`` (no decoding): for choosing thresholds
        from recorded trials."""
        reason = verification.refusal(heard)
        return replace(heard, command=None if reason else self.commands[heard.phrase],
                       reason=reason)

    def _decode_words(self, pcm: bytes) -> tuple[str, list[tuple[str, float, int, int]]]:
        """The grammar's phrase and its words: (word, log acoustic score relative to each
        frame's best state, first and last frame)."""
        d = decoded(self._grammar, pcm)
        hyp = d.hyp()
        words = [(_base_word(s.word), _log(s.ascore), s.start_frame, s.end_frame)
                 for s in (d.seg() or []) if not _is_filler(s.word)]
        return (hyp.hypstr if hyp else ""), words


def _log(probability: float) -> float:
    return math.log(max(probability, 1e-300))


def _base_word(word: str) -> str:
    """A dictionary entry without its alternate-pronunciation suffix: to(3) is to."""
    return word.split("(")[0]


def _is_filler(word: str) -> bool:
    return word.startswith("<") or word.startswith("[") or word.startswith("+")


def word_log_likelihood_ratio(state_log_likelihoods: np.ndarray, aligned: np.ndarray
                              ) -> float:
    """Per-frame log-likelihood ratio of a word against the best state in each frame.

    ``state_log_likelihoods`` (T, S) are the log likelihoods of each of the model's S
    states for each of the word's T frames; ``aligned`` (T,) is the state the word's
    alignment gives each frame. The ratio is the mean over the frames of
    ``log p(x_t | aligned_t) - max_s log p(x_t | s)``: zero when the word's own states
    are the best in every frame, and never positive (module notes, check 1)."""
    scores = np.asarray(state_log_likelihoods, dtype=float)
    states = np.asarray(aligned)
    frames = np.arange(scores.shape[0])
    return float(np.mean(scores[frames, states] - scores.max(axis=1)))


def speech_outside_fraction(x: np.ndarray, first: int, last: int) -> float:
    """The fraction of the speech frames of ``x`` (float audio at 16 kHz) that lie
    outside frames ``first``..``last`` (inclusive, 10 ms each). A frame is speech when
    its energy (dB) is ``SPEECH_ABOVE_FLOOR_DB`` over the 10th percentile of the
    utterance's frames; the frames after ``last`` whose (30 ms smoothed) energy never
    rises ``ONSET_RISE_DB`` over the lowest since ``last`` are the command's echo, not
    speech outside it: module notes, check 2."""
    energy = 10 * np.log10(frame_powers(x) + 1e-12)
    n = energy.size
    speech = energy > np.percentile(energy, 10) + SPEECH_ABOVE_FLOOR_DB
    if not speech.any():
        return 0.0
    final = min(last, n - 1)  # the command's last frame
    smooth = np.convolve(energy, np.ones(3) / 3, mode="same")[final:]
    onset = np.flatnonzero(smooth > np.minimum.accumulate(smooth) + ONSET_RISE_DB)
    tail_end = final + int(onset[0]) if len(onset) else n  # the echo runs up to here
    frames = np.arange(n)
    outside = speech & ((frames < first) | (frames >= tail_end))
    return float(outside.sum() / speech.sum())
