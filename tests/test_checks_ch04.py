"""The exercise checks of chapter 04 (speech commands): each passes an answer written
independently of the library, and says "not yet" (never raises) for the plausible wrong
answers, the unwritten stub and abcwc's own function handed in."""

from __future__ import annotations

import numpy as np
import pytest

from abcwc.checks import ch04
from abcwc.perception.speech.recognizer import word_log_likelihood_ratio
from tests.check_helpers import assert_not_yet, assert_pass, not_written

SOLUTION_THRESHOLD = -6.5   # the notebook's answer to exercise 3
LENIENT = -8.0              # below the tuning speakers' sentences
STRICT = -5.0               # above most of their commands


def student_word_ratio(scores, aligned):
    """Written from the text, frame by frame: the word's state against the frame's best."""
    total = 0.0
    for frame, state in enumerate(aligned):
        total += scores[frame][state] - max(scores[frame])
    return total / len(aligned)


def against_the_words_own_states(scores, aligned):
    own = sorted(set(aligned))
    return float(np.mean([scores[f][s] - max(scores[f][k] for k in own)
                          for f, s in enumerate(aligned)]))


def against_the_whole_words_best(scores, aligned):
    return float(np.mean([scores[f][s] for f, s in enumerate(aligned)]) - np.max(scores))


def against_all_states_together(scores, aligned):
    from scipy.special import logsumexp

    return float(np.mean([scores[f][s] - logsumexp(scores[f]) for f, s in enumerate(aligned)]))


def test_the_hand_worked_ratio():
    """Three frames, four states; the word's states 0, 0, 2 score -1, -4, -5 where the
    frames' best are -1, -2, -1: (0 - 2 - 4) / 3 = -2 per frame."""
    scores = np.array([[-1.0, -3.0, -2.0, -9.0],
                       [-4.0, -2.0, -6.0, -5.0],
                       [-7.0, -8.0, -5.0, -1.0]])
    assert word_log_likelihood_ratio(scores, np.array([0, 0, 2])) == pytest.approx(-2.0)


def test_word_ratio_check_passes_an_independent_answer(capsys):
    assert_pass(ch04.word_ratio_check(student_word_ratio), capsys)


@pytest.mark.parametrize(("wrong", "fragment"), [
    (against_the_words_own_states, "not only the word's own"),
    (against_the_whole_words_best, "its own best state"),
    (against_all_states_together, "posterior"),
    (lambda s, a: -student_word_ratio(s, a), "other way round"),
    (lambda s, a: student_word_ratio(s, a) * len(a), "per frame"),
    (lambda s, a: float(np.mean(s[np.arange(len(a)), a] - s.min(axis=1))), "maximum"),
    (lambda s, a: float("nan"), "one finite number"),
    (not_written, "NotImplementedError"),
    (ch04.reference_word_ratio, "abcwc's own"),
    (word_log_likelihood_ratio, "abcwc's own"),
])
def test_word_ratio_check_refuses_plausible_slips(wrong, fragment, capsys):
    assert_not_yet(ch04.word_ratio_check(wrong), capsys, fragment)


def test_prediction_check(capsys):
    assert_pass(ch04.prediction_check(lambda: (25, 5), 20.0, 7.5), capsys)
    assert_pass(ch04.prediction_check(lambda: [29.0, 0.0], 20.0, 7.5), capsys)


@pytest.mark.parametrize(("predicted", "fragment"), [
    (lambda: (5.0, 25.0), "far more often"),          # the thesis's finding reversed
    (lambda: (10.0, 10.0), "far more often"),
    (lambda: (90.0, 5.0), "71 points off"),           # the order right, the size not
    (lambda: (59.0, 10.0), "40 points off"),
    (lambda: (25.0, 20.0), "12 points off"),
    (lambda: (150.0, 5.0), "percentage"),
    (lambda: 20.0, "two percentages"),
    (not_written, "NotImplementedError"),
    (ch04.reference_word_ratio, "abcwc's own"),
])
def test_prediction_check_refuses(predicted, fragment, capsys):
    assert_not_yet(ch04.prediction_check(predicted, 19.0, 7.5), capsys, fragment)


@pytest.fixture(scope="module")
def held_out():
    from tests.test_speech import _need_speech_tools

    _need_speech_tools()
    return ch04.held_out_trials()


def test_the_exercise_is_judged_on_held_out_speakers_in_quiet_and_noise(held_out):
    from abcwc.perception.speech.synthesis import HELD_OUT_SPEAKERS, TUNING_SPEAKERS

    trials, _ = held_out
    assert set(trials) == {None, 20.0}
    for condition in trials.values():
        speakers = {t.voice.speaker for t in condition}
        assert speakers == set(HELD_OUT_SPEAKERS) and not speakers & set(TUNING_SPEAKERS)
        assert {t.voice.engine for t in condition} == {"flite", "festival"}
        assert sum(not t.is_command for t in condition) >= 100


def test_threshold_check_passes_a_threshold_with_a_margin(held_out, capsys):
    assert_pass(ch04.threshold_check(lambda: SOLUTION_THRESHOLD), capsys)


def test_threshold_check_is_decided_by_more_than_one_sentence(held_out):
    """Between the solution's threshold and a lenient one that fails, several readings
    of several sentences change sides: the verdict does not hang on one sentence."""
    from dataclasses import replace

    from abcwc.experiments.speech_trials import judged_again
    from abcwc.perception.speech.recognizer import Verification

    trials, recogniser = held_out

    def fired(threshold):
        verification = replace(Verification(), min_mean_llr=threshold)
        return {(snr, t.voice, t.text) for snr, condition in trials.items()
                for t in judged_again(condition, recogniser, verification)
                if not t.is_command and t.heard.accepted}

    more = fired(LENIENT) - fired(SOLUTION_THRESHOLD)
    assert len(more) >= 3 and len({text for _, _, text in more}) >= 2


@pytest.mark.parametrize(("chosen", "fragment"), [
    (lambda: LENIENT, "passed as commands"),
    (lambda: STRICT, "refuses commands"),
    (lambda: 0.5, "above 0"),
    (lambda: float("nan"), "one number"),
    (not_written, "NotImplementedError"),
    (ch04.reference_word_ratio, "abcwc's own"),
])
def test_threshold_check_refuses(held_out, chosen, fragment, capsys):
    assert_not_yet(ch04.threshold_check(chosen), capsys, fragment)


def test_the_synthesisers_versions_are_read_from_their_debian_packages(monkeypatch, tmp_path):
    from abcwc.perception.speech.synthesis import DEBIAN_PACKAGES, engine_versions
    from tests.test_speech import _need_speech_tools

    _need_speech_tools()
    versions = engine_versions()
    assert versions is not None
    packages = sorted(" ".join(DEBIAN_PACKAGES.values()).split())
    assert [v.split("=")[0] for v in versions] == packages
    assert all(v.split("=")[1] for v in versions)
    monkeypatch.setenv("PATH", str(tmp_path))  # no dpkg-query: nothing to key a cache on
    assert engine_versions() is None


def test_the_held_out_decoding_is_kept_under_the_synthesisers_versions(monkeypatch):
    """held_out_condition hands the engines' package versions and pocketsphinx's to the
    disk-cached decoding (its key); without versions it decodes without keeping."""
    from importlib.metadata import version

    from abcwc.perception.speech import synthesis

    calls = []

    def decoded(snr, voices, versions):
        calls.append(("kept", snr, voices, versions))
        return []

    decoded.__wrapped__ = lambda snr, voices, versions: calls.append(
        ("not kept", snr, voices, versions)) or []
    monkeypatch.setattr(ch04, "decoded_held_out", decoded)
    monkeypatch.setattr(synthesis, "engine_versions", lambda: ("flite=9.9-1",))
    ch04.held_out_condition.__wrapped__(20.0)
    monkeypatch.setattr(synthesis, "engine_versions", lambda: None)
    ch04.held_out_condition.__wrapped__(None)
    voices = ch04.exercise_voices()
    assert calls == [("kept", 20.0, voices, ("flite=9.9-1",
                                              f"pocketsphinx={version('pocketsphinx')}")),
                     ("not kept", None, voices, ())]
    with pytest.raises(ValueError, match="snr must be one of"):
        ch04.held_out_condition.__wrapped__(10.0)
