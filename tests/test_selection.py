"""The model of choosing without a hand: switch scanning's false selections agree with
the closed form, dwell trades the same way, and bad settings are refused."""

import math

import pytest

from abcwc.experiments.selection import (
    REACTION_MEDIAN,
    dwell_trials,
    scan_false_rate,
    scanning_trials,
)


def test_scanning_is_false_when_the_reaction_outlasts_the_interval():
    for interval in (0.5, 0.8, 1.2):
        trials = scanning_trials(interval, trials=20000, seed=1)
        assert trials.false_rate == pytest.approx(scan_false_rate(interval), abs=0.01)
    assert scan_false_rate(REACTION_MEDIAN) == pytest.approx(0.5)  # the median: half
    slow, fast = scanning_trials(1.5), scanning_trials(0.7)
    assert slow.mean_time > fast.mean_time and slow.false_rate < fast.false_rate
    # the mean target is lit after (9 - 1) / 2 intervals, then the reaction
    mean_reaction = REACTION_MEDIAN * math.exp(0.3 ** 2 / 2)
    assert scanning_trials(1.0, trials=20000).mean_time == pytest.approx(
        4 * 1.0 + mean_reaction, abs=0.05)


def test_a_longer_dwell_is_slower_and_picks_the_wrong_button_less():
    short, long = dwell_trials(0.4), dwell_trials(1.0)
    assert long.mean_time > short.mean_time and long.false_rate < short.false_rate
    assert dwell_trials(0.4, seed=3).false_rate == dwell_trials(0.4, seed=3).false_rate
    one = dwell_trials(0.5, options=1)  # nothing else to look at: never wrong
    assert one.false_rate == 0.0 and one.mean_time == pytest.approx(0.5)


def test_bad_settings_are_refused_with_what_is_allowed():
    for bad in (0.0, -1.0, math.nan, "1", True):
        with pytest.raises(ValueError, match="seconds > 0"):
            scanning_trials(bad)
    with pytest.raises(ValueError, match="whole number >= 1"):
        dwell_trials(0.5, options=0)
    with pytest.raises(ValueError, match="whole number >= 1"):
        scanning_trials(0.5, trials=2.5)
