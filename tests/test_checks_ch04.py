"""The exercise checks of chapter 04 (speech commands): each passes an answer written
independently of the library, and says "not yet" (never raises) for the plausible wrong
answers, the unwritten stub and abcwc's own function handed in."""

from __future__ import annotations

import numpy as np
import pytest

from abcwc.checks import ch04
from abcwc.perception.speech.recognizer import word_log_likelihood_ratio
from tests.check_helpers import assert_not_yet, assert_pass, not_written


def student_word_ratio(score, first, last, phones):
    """Written from the text, vectorised: each phone's frames inside the word, as a share
    of its own frames."""
    phones = np.asarray(phones, dtype=float)
    lo = np.maximum(phones[:, 1], first)
    hi = np.minimum(phones[:, 2], last)
    share = np.clip(hi - lo + 1, 0, None) / (phones[:, 2] - phones[:, 1] + 1)
    return float((score - np.dot(share, phones[:, 0])) / (last - first + 1))


def whole_phones(score, first, last, phones):
    touching = [p for p in phones if min(p[2], last) >= max(p[1], first)]
    return (score - sum(p[0] for p in touching)) / (last - first + 1)


def only_inside(score, first, last, phones):
    inside = [p for p in phones if p[1] >= first and p[2] <= last]
    return (score - sum(p[0] for p in inside)) / (last - first + 1)


def test_the_hand_worked_ratio():
    """Phones -20 over frames 0-9, -40 over 10-19, -10 over 20-39; a word of -80 over
    frames 5-24 holds half the first phone, all the second and a quarter of the third:
    (-80 - (-10 - 40 - 2.5)) / 20 = -1.375 per frame."""
    phones = np.array([[-20.0, 0, 9], [-40.0, 10, 19], [-10.0, 20, 39]])
    assert word_log_likelihood_ratio(-80.0, 5, 24, phones) == pytest.approx(-1.375)


def test_word_ratio_check_passes_an_independent_answer(capsys):
    assert_pass(ch04.word_ratio_check(student_word_ratio), capsys)


@pytest.mark.parametrize(("wrong", "fragment"), [
    (whole_phones, "counted whole"),
    (only_inside, "wholly inside"),
    (lambda s, f, e, p: -student_word_ratio(s, f, e, p), "other way round"),
    (lambda s, f, e, p: student_word_ratio(s, f, e, p) * (e - f + 1), "per frame"),
    (lambda s, f, e, p: student_word_ratio(s, f, e, p) * (e - f + 1) / (e - f),
     "both ends count"),
    (lambda s, f, e, p: float("nan"), "one finite number"),
    (not_written, "NotImplementedError"),
    (ch04.reference_word_ratio, "abcwc's own"),
    (word_log_likelihood_ratio, "abcwc's own"),
])
def test_word_ratio_check_refuses_plausible_slips(wrong, fragment, capsys):
    assert_not_yet(ch04.word_ratio_check(wrong), capsys, fragment)


def test_prediction_check(capsys):
    assert_pass(ch04.prediction_check(lambda: (25, 5), 20.0, 7.5), capsys)
    assert_pass(ch04.prediction_check(lambda: [60.0, 10.0], 20.0, 7.5), capsys)


@pytest.mark.parametrize(("predicted", "fragment"), [
    (lambda: (5.0, 25.0), "far more often"),          # the thesis's finding reversed
    (lambda: (10.0, 10.0), "far more often"),
    (lambda: (150.0, 5.0), "percentage"),
    (lambda: 20.0, "two percentages"),
    (not_written, "NotImplementedError"),
    (ch04.reference_word_ratio, "abcwc's own"),
])
def test_prediction_check_refuses(predicted, fragment, capsys):
    assert_not_yet(ch04.prediction_check(predicted, 20.0, 7.5), capsys, fragment)


@pytest.fixture(scope="module")
def held_out():
    from tests.test_speech import _need_speech_tools

    _need_speech_tools()
    return ch04.held_out_trials()


def test_threshold_check_passes_a_threshold_with_a_margin(held_out, capsys):
    assert_pass(ch04.threshold_check(lambda: -3.5), capsys)


@pytest.mark.parametrize(("chosen", "fragment"), [
    (lambda: -4.5, "passed as commands"),      # at the tuning data's edge and beyond
    (lambda: -2.5, "refuses most commands"),   # so strict nothing gets through
    (lambda: 0.5, "above 0"),
    (lambda: float("nan"), "one number"),
    (not_written, "NotImplementedError"),
    (ch04.reference_word_ratio, "abcwc's own"),
])
def test_threshold_check_refuses(held_out, chosen, fragment, capsys):
    assert_not_yet(ch04.threshold_check(chosen), capsys, fragment)
