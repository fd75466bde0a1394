"""Checks for chapter 04, speech commands (thesis 4.1.7, A.4).

Exercises:

* ``word_ratio(score, first, last, phones)``: the per-frame log-likelihood ratio of a
  word aligned to frames ``first``..``last`` (inclusive) with log likelihood ``score``,
  against the free phone sequence ``phones`` ((N, 3) rows: log likelihood, first frame,
  last frame) over the same frames, a phone partly inside counting pro rata;
* ``predicted_false_activations()``: two percentages written down *before* the run
  that measures them: how many of the conversation sentences fire a command when the
  command may be anywhere in what was said, with the thesis's single words and with its
  two-word commands;
* ``chosen_mean_threshold()``: the words' mean ratio a command must reach, read off the
  tuning voices' plot, judged on voices and sentences the notebook never used: at most
  2 % of the sentences may pass as commands, and at least 45 % of the commands must be
  recognised.

Each ``reference_*`` function is an answer the notebook falls back on; a check handed
the library's own function (or a ``reference_*``) says so instead of passing.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import lru_cache

import numpy as np

from abcwc.checks.report import NotYet, checker, expect, expect_own, format_value, numbers
from abcwc.perception.speech.recognizer import word_log_likelihood_ratio

__all__ = [
    "HELD_OUT_SEED",
    "MAX_FALSE_ACTIVATIONS",
    "MIN_RECOGNISED",
    "held_out_trials",
    "prediction_check",
    "reference_word_ratio",
    "threshold_check",
    "word_ratio_check",
]

MAX_FALSE_ACTIVATIONS = 0.02
"""Of the unseen sentences, the share that may pass as commands."""
MIN_RECOGNISED = 0.45
"""Of the unseen commands, the share that must be recognised."""
HELD_OUT_SEED = 400


def reference_word_ratio(score: float, first: int, last: int, phones: np.ndarray) -> float:
    """The ratio (:func:`abcwc.perception.speech.recognizer.word_log_likelihood_ratio`)."""
    return word_log_likelihood_ratio(score, first, last, np.asarray(phones, dtype=float))


# --- exercise 1: the word's likelihood ratio ------------------------------------------------


def ratio_cases() -> list[tuple[float, int, int, np.ndarray]]:
    """(score, first, last, phones): hand-made and seeded random alignments."""
    hand = np.array([[-20.0, 0, 9], [-40.0, 10, 19], [-10.0, 20, 39]])
    cases = [(-80.0, 5, 24, hand), (-60.0, 10, 19, hand), (-15.0, 0, 4, hand)]
    rng = np.random.default_rng(4)
    for _ in range(6):
        edges = np.cumsum(rng.integers(3, 12, 12))
        starts = np.concatenate([[0], edges[:-1] + 1])
        phones = np.column_stack([-rng.uniform(2, 8, 12) * (edges - starts + 1), starts,
                                  edges])
        first = int(rng.integers(2, 30))
        last = first + int(rng.integers(8, 40))
        score = float(-rng.uniform(3, 9) * (last - first + 1))
        cases.append((score, first, last, phones))
    return cases


def _slips(score: float, first: int, last: int, phones: np.ndarray) -> dict[str, float]:
    """What the usual slips give for one case."""
    frames = last - first + 1
    start, end = phones[:, 1], phones[:, 2]
    touching = (np.minimum(end, last) - np.maximum(start, first) + 1) > 0
    within = (start >= first) & (end <= last)
    exact = reference_word_ratio(score, first, last, phones)
    return {
        "every phone that touches the word counted whole; a phone partly inside counts "
        "pro rata (its score times the share of its frames inside)":
            (score - phones[touching, 0].sum()) / frames,
        "only the phones wholly inside the word were counted; the ones partly inside "
        "count too, pro rata": (score - phones[within, 0].sum()) / frames,
        "the ratio is the word's score less the phones', not the other way round":
            -exact,
        "that is the ratio for the whole word; divide by its number of frames for a "
        "ratio per frame": exact * frames,
        "the word spans last - first + 1 frames (both ends count)":
            exact * frames / (frames - 1),
    }


@checker("word ratio")
def word_ratio_check(fn: Callable) -> str:
    """``fn(score, first, last, phones)`` against the pro-rata ratio and the slips."""
    expect_own(fn, reference_word_ratio, word_log_likelihood_ratio)
    cases = ratio_cases()
    for score, first, last, phones in cases:
        expected = reference_word_ratio(score, first, last, phones)
        got = fn(score, first, last, phones.copy())
        expect(isinstance(got, (int, float, np.floating)) and math.isfinite(float(got)),
               f"word_ratio gave {format_value(got)}; return one finite number")
        if abs(float(got) - expected) <= 1e-9 * max(1.0, abs(expected)):
            continue
        for slip, wrong in _slips(score, first, last, phones).items():
            if abs(float(got) - wrong) <= 1e-9 * max(1.0, abs(wrong)):
                raise NotYet(f"frames {first}-{last}: {float(got):.3f}, expected "
                             f"{expected:.3f}: {slip}")
        raise NotYet(f"a word over frames {first}-{last} with score {score:.1f} gave "
                     f"{float(got):.3f}, expected {expected:.3f} per frame")
    return f"{len(cases)} alignments, each word's ratio per frame right"


# --- exercise 2: predict the false activations ----------------------------------------------


@checker("prediction")
def prediction_check(predicted: Callable[[], tuple[float, float]], single: float,
                     two_word: float) -> str:
    """The two percentages written before the run against what it measured
    (``single`` and ``two_word``, %)."""
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
    off = abs(guess_single - single)
    closeness = ("close" if off <= 5 else "the order right, the size off by "
                 f"{off:.0f} points: conversation shares the words the chapter's "
                 "sentences were written with")
    return (f"you predicted {guess_single:.0f} % and {guess_two:.0f} %; {measured}: "
            f"{closeness}")


# --- exercise 3: a threshold for voices never heard ------------------------------------------


@lru_cache(maxsize=1)
def held_out_trials():  # noqa: ANN201 - a list of speech_trials.Trial, imported lazily
    """The house commands and the held-out sentences, said by three of the held-out
    voices, decoded once with no verification (``Verification.none()``), and the
    recogniser that decoded them."""
    from abcwc.experiments.speech_trials import TEST_DISTRACTORS, floor_commands, run_trials
    from abcwc.perception.speech.recognizer import CommandRecognizer, Verification
    from abcwc.perception.speech.synthesis import TEST_VOICES

    commands = floor_commands()
    recogniser = CommandRecognizer(commands, Verification.none())
    trials = run_trials(recogniser, commands.phrases, list(TEST_DISTRACTORS),
                        TEST_VOICES[:3], seed=HELD_OUT_SEED)
    return trials, recogniser


@checker("threshold")
def threshold_check(chosen: Callable[[], float]) -> str:
    """``chosen()``, the words' mean ratio a command needs, on voices and sentences the
    notebook never used."""
    from abcwc.experiments.speech_trials import judged_again, rates
    from abcwc.perception.speech.recognizer import Verification

    value = chosen()
    expect(isinstance(value, (int, float)) and math.isfinite(value),
           f"chosen_mean_threshold() gave {format_value(value)}; return one number")
    expect(value <= 0, f"{value:g} is above 0: a ratio per frame of a word against the free "
           "phones is at most about 0, so nothing would pass")
    trials, recogniser = held_out_trials()
    judged = judged_again(trials, recogniser, Verification(min_mean_llr=float(value)))
    found = rates(judged)
    fired = sorted({t.text for t in judged if not t.is_command and t.heard.accepted})
    if found.false_activations > MAX_FALSE_ACTIVATIONS:
        raise NotYet(f"at {value:.2f}, {100 * found.false_activations:.1f} % of sentences the "
                     f"notebook never used passed as commands ({'; '.join(fired[:3])}); at "
                     f"most {100 * MAX_FALSE_ACTIVATIONS:.0f} % may: the edge of the tuning "
                     "data is not a safe place for new voices, leave a margin")
    if found.recognised < MIN_RECOGNISED:
        raise NotYet(f"at {value:.2f} only {100 * found.recognised:.0f} % of the commands "
                     f"in new voices are recognised (at least {100 * MIN_RECOGNISED:.0f} % "
                     "needed): the threshold refuses most commands as well as the "
                     "sentences")
    return (f"{value:.2f} on three voices and {found.distractors // 3} sentences never "
            f"used: {100 * found.recognised:.0f} % of the commands recognised, "
            f"{100 * found.false_activations:.1f} % of the sentences taken for commands")
