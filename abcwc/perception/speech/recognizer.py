"""Offline recognition of the chair's spoken commands with pocketsphinx, restricted to
the command grammar and verified, so that conversation is not taken for a command.

A grammar alone always answers: every sound becomes the command it is least unlike.
So each answer is checked twice before the chair obeys it.

1. **The words are the command's.** A second decoder recognises the same audio as a
   free sequence of phones (pocketsphinx's allphone search with its phone bigram). Over
   each word of the grammar's answer, the per-frame log-likelihood ratio between the
   word's forced alignment and the free phone sequence,

       LLR_w = (log p(frames | word) - log p(frames | best phones)) / n_frames,

   is near zero when the word was said and strongly negative when the grammar bent
   other sounds into it: the standard confidence measure of utterance verification
   (Rahim, Lee and Juang, "Discriminative utterance verification for connected digits
   recognition", IEEE Trans. Speech Audio Proc. 5(3), 1997; Jiang, "Confidence measures
   for speech recognition: a survey", Speech Communication 45, 2005). The answer stands
   only if the words' mean ratio clears ``min_mean_llr`` and its *weakest* word clears
   ``min_word_llr`` (a short word such as "the" scores noisily, so the bound on one word
   is looser than on the mean); a one-word command, which has no second word to vouch
   for it, must clear ``min_single_word_llr``.
2. **Nothing else was said.** A frame is speech when its energy is 12 dB above the
   utterance's quietest frames; at most ``max_outside_speech`` of the speech frames may
   lie outside the command's words. "stop worrying about it" aligns "stop" to its first
   word and calls the rest silence; this check refuses it.

The thresholds were set on espeak-ng voices and sentences of
``abcwc.experiments.speech_trials``' tuning set, and are measured on its test set of
other voices and sentences.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from abcwc.perception.speech.audio import SAMPLE_RATE, to_float_audio, to_int16, with_noise_floor
from abcwc.perception.speech.commands import CommandSet, SpokenCommand

FRAME_RATE = 100          # pocketsphinx's feature frames per second
SPEECH_ABOVE_FLOOR_DB = 12.0


def _model_paths() -> tuple[str, str, str]:
    from pocketsphinx import get_model_path

    model = get_model_path()
    return (f"{model}/en-us/en-us", f"{model}/en-us/cmudict-en-us.dict",
            f"{model}/en-us/en-us-phone.lm.bin")


@dataclass(frozen=True)
class Recognition:
    """What was heard: the ``command`` obeyed (None when rejected), the grammar's best
    ``phrase`` whether accepted or not, its words' mean and weakest log-likelihood
    ratios (per frame; ``word_llrs`` has each word's), the fraction of speech outside
    the command's words, why it was rejected (``reason``, "" when accepted) and the
    decoding time (s)."""

    command: SpokenCommand | None
    phrase: str
    mean_llr: float
    weakest_llr: float
    outside_speech: float
    reason: str
    seconds: float
    word_llrs: tuple[tuple[str, float], ...] = ()

    @property
    def accepted(self) -> bool:
        return self.command is not None


class CommandRecognizer:
    """pocketsphinx with the ``commands`` grammar and the two checks above.

    ``recognise(samples, rate)`` takes one utterance (int16, or float in [-1, 1]; any
    rate from 8 to 96 kHz) and returns a ``Recognition``. Bad buffers raise
    ``AudioError`` with what is allowed."""

    def __init__(self, commands: CommandSet, min_mean_llr: float = -4.0,
                 min_word_llr: float = -5.5, min_single_word_llr: float = -3.5,
                 max_outside_speech: float = 0.3,
                 noise_floor_seed: int = 0) -> None:
        from pocketsphinx import Decoder

        for name, value in (("min_mean_llr", min_mean_llr), ("min_word_llr", min_word_llr),
                            ("min_single_word_llr", min_single_word_llr)):
            if not math.isfinite(value) or value > 0:
                raise ValueError(f"{name} must be a finite log-likelihood ratio <= 0, "
                                 f"got {value}")
        if not 0.0 <= max_outside_speech <= 1.0:
            raise ValueError(f"max_outside_speech must be a fraction in [0, 1], "
                             f"got {max_outside_speech}")
        hmm, dictionary, phone_lm = _model_paths()
        self.commands = commands
        self.min_mean_llr = min_mean_llr
        self.min_word_llr = min_word_llr
        self.min_single_word_llr = min_single_word_llr
        self.max_outside_speech = max_outside_speech
        self.noise_floor_seed = noise_floor_seed
        self._grammar = Decoder(hmm=hmm, dict=dictionary, lm=None, samprate=SAMPLE_RATE,
                                loglevel="FATAL")
        unknown = sorted(w for w in commands.words() if self._grammar.lookup_word(w) is None)
        if unknown:
            raise ValueError(f"not in the pronunciation dictionary: {', '.join(unknown)}; "
                             f"use other words for these commands or places")
        self._grammar.add_jsgf_string("commands", commands.jsgf())
        self._grammar.activate_search("commands")
        self._phones = Decoder(hmm=hmm, allphone=phone_lm, lm=None, samprate=SAMPLE_RATE,
                               loglevel="FATAL")

    def recognise(self, samples: np.ndarray, rate: int = SAMPLE_RATE) -> Recognition:
        """The command in one utterance, or None with the reason it was refused."""
        started = time.perf_counter()
        x = with_noise_floor(to_float_audio(samples, rate), seed=self.noise_floor_seed)
        pcm = to_int16(x).tobytes()
        phrase, words = self._decode_words(pcm)
        phones = self._decode_phones(pcm)
        if phrase not in self.commands:
            return Recognition(None, phrase, -math.inf, -math.inf, 1.0,
                               "no command fits the sound from start to end",
                               time.perf_counter() - started)
        llrs = tuple((w, _word_llr(score, first, last, phones))
                     for w, score, first, last in words)
        word, weakest = min(llrs, key=lambda pair: pair[1])
        mean = float(np.mean([llr for _, llr in llrs]))
        outside = _speech_outside(x, words[0][2], words[-1][3])
        reason = ""
        if len(words) == 1 and weakest < self.min_single_word_llr:
            reason = (f'"{phrase}" fits the sound badly (log-likelihood ratio {weakest:.2f} '
                      f'per frame; a one-word command needs {self.min_single_word_llr:.2f})')
        elif len(words) > 1 and mean < self.min_mean_llr:
            reason = (f'"{phrase}" fits the sound badly (mean log-likelihood ratio '
                      f'{mean:.2f} per frame, needed {self.min_mean_llr:.2f})')
        elif len(words) > 1 and weakest < self.min_word_llr:
            reason = (f'"{word}" fits the sound badly (log-likelihood ratio {weakest:.2f} '
                      f'per frame, needed {self.min_word_llr:.2f})')
        elif outside > self.max_outside_speech:
            reason = (f"{100 * outside:.0f} % of the speech lies outside the command "
                      f"(at most {100 * self.max_outside_speech:.0f} %): more was said")
        command = None if reason else self.commands[phrase]
        return Recognition(command, phrase, mean, weakest, outside, reason,
                           time.perf_counter() - started, llrs)

    def _decode_words(self, pcm: bytes) -> tuple[str, list[tuple[str, float, int, int]]]:
        """The grammar's phrase and its words: (word, log acoustic score, first and last
        frame)."""
        d = self._grammar
        d.start_utt()
        d.process_raw(pcm, full_utt=True)
        d.end_utt()
        hyp = d.hyp()
        words = [(_base_word(s.word), _log(s.ascore), s.start_frame, s.end_frame)
                 for s in (d.seg() or []) if not _is_filler(s.word)]
        return (hyp.hypstr if hyp else ""), words

    def _decode_phones(self, pcm: bytes) -> np.ndarray:
        """The free phone sequence as rows (log acoustic score, first, last frame)."""
        d = self._phones
        d.start_utt()
        d.process_raw(pcm, full_utt=True)
        d.end_utt()
        rows = [(_log(s.ascore), s.start_frame, s.end_frame) for s in (d.seg() or [])]
        return np.array(rows, dtype=float).reshape(-1, 3)


def _log(probability: float) -> float:
    return math.log(max(probability, 1e-300))


def _base_word(word: str) -> str:
    """A dictionary entry without its alternate-pronunciation suffix: to(3) is to."""
    return word.split("(")[0]


def _is_filler(word: str) -> bool:
    return word.startswith("<") or word.startswith("[") or word.startswith("+")


def _word_llr(score: float, first: int, last: int, phones: np.ndarray) -> float:
    """Per-frame log-likelihood ratio of a word aligned to frames first..last against
    the free phone sequence over the same frames (phones partly inside count pro rata)."""
    overlap = np.minimum(phones[:, 2], last) - np.maximum(phones[:, 1], first) + 1
    inside = overlap > 0
    frames = phones[inside, 2] - phones[inside, 1] + 1
    free = float(np.sum(phones[inside, 0] * overlap[inside] / frames))
    return (score - free) / (last - first + 1)


def _speech_outside(x: np.ndarray, first: int, last: int) -> float:
    """The fraction of speech frames (10 ms, energy ``SPEECH_ABOVE_FLOOR_DB`` over the
    quietest tenth) that lie outside frames first..last."""
    hop = SAMPLE_RATE // FRAME_RATE
    n = x.size // hop
    energy = 10 * np.log10(np.mean(x[: n * hop].reshape(n, hop) ** 2, axis=1) + 1e-12)
    speech = energy > np.percentile(energy, 10) + SPEECH_ABOVE_FLOOR_DB
    if not speech.any():
        return 0.0
    frames = np.arange(n)
    outside = speech & ((frames < first) | (frames > last))
    return float(outside.sum() / speech.sum())
