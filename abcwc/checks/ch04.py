"""Checks for chapter 04, speech commands (thesis 4.1.7, A.4).

Exercises:

* ``word_ratio(scores, aligned)``: the per-frame log-likelihood ratio of a word against
  the best state in each frame, from ``scores`` (T, S), the log likelihood of each of
  the model's S states in each of the word's T frames, and ``aligned`` (T,), the state
  the word's alignment gives each frame;
* ``predicted_false_activations()``: two percentages written down *before* the run
  that measures them: how many of the conversation sentences fire a command when the
  command may be anywhere in what was said, with the thesis's single words and with its
  two-word commands, each within ``PREDICTION_TOLERANCE`` points of the measurement;
* ``chosen_mean_threshold()``: the words' mean ratio a command must reach, read off the
  tuning speakers' plot, judged on speakers and sentences the notebook never used (kal
  and slt, each in flite and festival): in a quiet room at least 90 % of the commands
  recognised and at most 2 % of the sentence readings taken for commands, in room
  noise at 20 dB SNR at least 85 % and at most 3 % (``BARS``).

Each ``reference_*`` function is an answer the notebook falls back on; a check handed
the library's own function (or a ``reference_*``) says so instead of passing.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import cache, lru_cache

import numpy as np
from scipy.special import logsumexp

from abcwc.checks.report import (
    NotYet,
    checker,
    expect,
    expect_no_slip,
    expect_own,
    format_value,
    numbers,
)
from abcwc.experiments.disk_cache import cached_on_disk
from abcwc.perception.speech.recognizer import word_log_likelihood_ratio

__all__ = [
    "BARS",
    "HELD_OUT_SEED",
    "PREDICTION_TOLERANCE",
    "decoded_held_out",
    "held_out_condition",
    "held_out_trials",
    "prediction_check",
    "reference_word_ratio",
    "synthesise_held_out",
    "threshold_check",
    "word_ratio_check",
]

BARS = {None: (0.90, 0.02), 20.0: (0.85, 0.03)}
"""SNR (dB; None: a quiet room) -> (the least share of the held-out speakers' commands
recognised, the most share of their sentence readings taken for commands)."""
HELD_OUT_SEED = 400


def reference_word_ratio(scores: np.ndarray, aligned: np.ndarray) -> float:
    """The ratio (:func:`abcwc.perception.speech.recognizer.word_log_likelihood_ratio`)."""
    return word_log_likelihood_ratio(scores, aligned)


# --- exercise 1: the word's likelihood ratio ------------------------------------------------


def ratio_cases() -> list[tuple[np.ndarray, np.ndarray]]:
    """(scores, aligned): a hand-made word and seeded random ones."""
    hand = np.array([[-1.0, -3.0, -2.0, -9.0],
                     [-4.0, -2.0, -6.0, -5.0],
                     [-7.0, -8.0, -5.0, -1.0]])
    cases = [(hand, np.array([0, 0, 2])), (hand, np.array([1, 1, 3]))]
    rng = np.random.default_rng(4)
    for _ in range(6):
        frames, states = int(rng.integers(6, 40)), int(rng.integers(8, 60))
        scores = -rng.gamma(2.0, 4.0, (frames, states)) - rng.uniform(20, 60)
        word_states = rng.choice(states, 3, replace=False)
        cases.append((scores, np.sort(rng.choice(word_states, frames))))
    return cases


def _slips(scores: np.ndarray, aligned: np.ndarray) -> dict[str, float]:
    """What the usual slips give for one case."""
    frames = np.arange(len(aligned))
    own = scores[frames, aligned]
    exact = reference_word_ratio(scores, aligned)
    together = logsumexp(scores, axis=1)
    return {
        "each frame is compared with its own best state, not with the best score of the "
        "whole word (take the maximum along the states, axis 1)":
            float(np.mean(own - scores.max())),
        "compare with the best of all the model's states, not only the word's own":
            float(np.mean(own - scores[:, np.unique(aligned)].max(axis=1))),
        "compare with the best state, not with all states together (that log-sum is a "
        "posterior, another measure)": float(np.mean(own - together)),
        "the ratio is the word's score less the best state's, not the other way round":
            -exact,
        "that is the ratio for the whole word; take the mean over its frames for a "
        "ratio per frame": exact * len(aligned),
        "the best state has the largest log likelihood (the maximum, not the minimum)":
            float(np.mean(own - scores.min(axis=1))),
    }


def _same_ratio(got: float, wrong: float) -> bool:
    return abs(got - wrong) <= 1e-9 * max(1.0, abs(wrong))


@checker("word ratio")
def word_ratio_check(fn: Callable) -> str:
    """``fn(scores, aligned)`` against the ratio and the slips."""
    expect_own(fn, reference_word_ratio, word_log_likelihood_ratio)
    cases = ratio_cases()
    for scores, aligned in cases:
        expected = reference_word_ratio(scores, aligned)
        got = fn(scores.copy(), aligned.copy())
        expect(isinstance(got, (int, float, np.floating)) and math.isfinite(float(got)),
               f"word_ratio gave {format_value(got)}; return one finite number")
        if abs(float(got) - expected) <= 1e-9 * max(1.0, abs(expected)):
            continue
        where = f"a word of {len(aligned)} frames among {scores.shape[1]} states"
        expect_no_slip(float(got), _slips(scores, aligned), _same_ratio,
                       prefix=f"{where}: {float(got):.3f}, expected {expected:.3f}: ")
        raise NotYet(f"{where} gave {float(got):.3f}, expected {expected:.3f} per frame")
    return f"{len(cases)} words, each one's ratio per frame right"


# --- exercise 2: predict the false activations ----------------------------------------------


PREDICTION_TOLERANCE = 10.0
"""How far (percentage points) each predicted figure may lie from the measured one."""


@checker("prediction")
def prediction_check(predicted: Callable[[], tuple[float, float]], single: float,
                     two_word: float) -> str:
    """The two percentages written before the run against what it measured
    (``single`` and ``two_word``, %): each within ``PREDICTION_TOLERANCE`` points, and
    single words above two-word commands."""
    value = predicted()
    guess_single, guess_two = numbers(value, 2, "predicted_false_activations()",
                                      "return two percentages: (single words, two-word commands)")
    expect(all(math.isfinite(g) and 0 <= g <= 100 for g in (guess_single, guess_two)),
           f"predicted ({guess_single:g}, {guess_two:g}); each is a percentage, 0-100")
    measured = f"the run measured {single:.0f} % and {two_word:.0f} %"
    if guess_single <= guess_two:
        raise NotYet(f"you predicted {guess_single:.0f} % for single words and "
                     f"{guess_two:.0f} % for two-word commands; {measured}. Conversation "
                     "holds the single words far more often than the pairs: that is what "
                     "the thesis found (4.1.7)")
    for name, guess, truth in (("single words", guess_single, single),
                               ("two-word commands", guess_two, two_word)):
        if abs(guess - truth) > PREDICTION_TOLERANCE:
            raise NotYet(f"you predicted {guess:.0f} % for {name}; {measured}: "
                         f"{abs(guess - truth):.0f} points off, more than the "
                         f"{PREDICTION_TOLERANCE:.0f} a prediction may miss by. Count "
                         "the sentences that hold one of the words whole, and ask which "
                         "of them a keyword spotter would fire on")
    return (f"you predicted {guess_single:.0f} % and {guess_two:.0f} %; {measured}: "
            f"both within {PREDICTION_TOLERANCE:.0f} points")


# --- exercise 3: a threshold for voices never heard ------------------------------------------


def held_out_trials():  # noqa: ANN201 - speech_trials.Trial lists, imported lazily
    """The house commands and the held-out sentences said by the held-out speakers (kal
    and slt, each in flite and festival, at their own rate and pitch), in a quiet room
    and in room noise at 20 dB SNR, decoded once with no verification
    (``Verification.none()``): ({None: quiet trials, 20.0: noisy trials}, the
    recogniser that decoded them)."""
    return {snr: held_out_condition(snr) for snr in BARS}, _bare_recogniser()


@lru_cache(maxsize=1)
def _bare_recogniser():  # noqa: ANN202 - a CommandRecognizer, imported lazily
    from abcwc.experiments.speech_trials import floor_commands
    from abcwc.perception.speech.recognizer import CommandRecognizer, Verification

    return CommandRecognizer(floor_commands(), Verification.none())


@cache
def held_out_condition(snr: float | None) -> list:
    """``held_out_trials`` in one condition (``snr`` None: quiet; one of ``BARS``),
    decoded once and kept: a notebook can decode one condition per cell. Kept on disk
    too (:func:`decoded_held_out`), so the tests and both copies of the notebook decode
    it once; where the synthesisers' versions cannot be read, it is decoded each time."""
    from importlib.metadata import version

    from abcwc.perception.speech.synthesis import engine_versions

    if snr not in BARS:
        raise ValueError(f"snr must be one of {list(BARS)}, got {snr!r}")
    engines = engine_versions()
    if engines is None:
        return decoded_held_out.__wrapped__(snr, exercise_voices(), ())
    return decoded_held_out(snr, exercise_voices(),
                            (*engines, f"pocketsphinx={version('pocketsphinx')}"))


@cached_on_disk
def decoded_held_out(snr: float | None, voices: tuple, versions: tuple[str, ...]) -> list:
    """The house commands and the held-out sentences said in ``voices`` at ``snr`` (dB;
    None: quiet), decoded with no verification. ``versions`` (the synthesisers' Debian
    packages and pocketsphinx, ``package=version``) is not read: it is part of the disk
    cache's key, as the audio and its decoding depend on them."""
    from abcwc.experiments.speech_trials import HELD_OUT_DISTRACTORS, run_trials

    recogniser = _bare_recogniser()
    return run_trials(recogniser, recogniser.commands.phrases, list(HELD_OUT_DISTRACTORS),
                      voices, snr, seed=HELD_OUT_SEED)


def synthesise_held_out() -> int:
    """Synthesise every utterance of ``held_out_trials`` once (the synthesiser keeps
    them), so that decoding them later takes less time in one notebook cell; returns
    how many."""
    from abcwc.experiments.speech_trials import HELD_OUT_DISTRACTORS, floor_commands
    from abcwc.perception.speech.synthesis import speak

    texts = floor_commands().phrases + list(HELD_OUT_DISTRACTORS)
    for voice in exercise_voices():
        for text in texts:
            speak(text, voice)
    return len(texts) * len(exercise_voices())


def exercise_voices() -> tuple:
    """The held-out voices at their own rate and pitch."""
    from abcwc.perception.speech.synthesis import HELD_OUT_VOICES

    return tuple(v for v in HELD_OUT_VOICES if v.rate == 1.0 and v.pitch == 0.0)


def _condition(snr: float | None) -> str:
    return "in a quiet room" if snr is None else f"in room noise at {snr:.0f} dB SNR"


@checker("threshold")
def threshold_check(chosen: Callable[[], float]) -> str:
    """``chosen()``, the words' mean ratio a command needs (the library's other
    thresholds kept), on speakers and sentences the notebook never used, against
    ``BARS`` in each condition."""
    from dataclasses import replace

    from abcwc.experiments.speech_trials import judged_again, rates
    from abcwc.perception.speech.recognizer import Verification

    value = chosen()
    expect(isinstance(value, (int, float)) and math.isfinite(value),
           f"chosen_mean_threshold() gave {format_value(value)}; return one number")
    expect(value <= 0, f"{value:g} is above 0: a word's ratio per frame against the best "
           "state in each frame is at most 0, so nothing would pass")
    held, recogniser = held_out_trials()
    verification = replace(Verification(), min_mean_llr=float(value))
    said = []
    for snr, trials in held.items():
        least_recognised, most_false = BARS[snr]
        judged = judged_again(trials, recogniser, verification)
        found = rates(judged)
        fired = [t.text for t in judged if not t.is_command and t.heard.accepted]
        where = _condition(snr)
        if found.false_activations > most_false:
            raise NotYet(f"at {value:.2f}, {len(fired)} of {found.distractors} readings "
                         f"({100 * found.false_activations:.1f} %) of sentences the "
                         f"notebook never used passed as commands {where} "
                         f"({'; '.join(sorted(set(fired))[:3])}); at most "
                         f"{100 * most_false:.0f} % may: the edge of the tuning data is "
                         "not a safe place for new voices, leave a margin")
        if found.recognised < least_recognised:
            raise NotYet(f"at {value:.2f} only {100 * found.recognised:.0f} % of the "
                         f"commands of new speakers are recognised {where} (at least "
                         f"{100 * least_recognised:.0f} % needed): the threshold refuses "
                         "commands as well as the sentences; the sentences that score "
                         "highest are often refused by the other checks already")
        said.append(f"{where} {100 * found.recognised:.0f} % of {found.commands} commands "
                    f"recognised, {len(fired)} of {found.distractors} sentence readings "
                    "taken for commands")
    return f"{value:.2f} on {len(exercise_voices())} voices of two new speakers: " + \
        "; ".join(said)
