"""The exercise checks of chapter 05 (seeing known objects): each passes an answer written
independently of the library, and says "not yet" (never raises) for the plausible wrong
answers, the unwritten stub and abcwc's own function handed in."""

from __future__ import annotations

import math

import pytest

from abcwc.checks import ch05
from abcwc.perception.known_objects import ratio_test
from tests.check_helpers import assert_not_yet, assert_pass, not_written


def student_good_matches(pairs, ratio):
    """Written from the text: skip short lists, keep the best of a clear pair."""
    kept = []
    for neighbours in pairs:
        if len(neighbours) < 2:
            continue
        best, runner_up = neighbours[:2]
        if best.distance < ratio * runner_up.distance:
            kept.append(best)
    return kept


def test_match_check_passes_an_independent_answer(capsys):
    assert_pass(ch05.match_check(student_good_matches), capsys)


@pytest.mark.parametrize(("wrong", "fragment"), [
    (lambda pairs, r: [m for m, n in pairs if m.distance < r * n.distance], "fewer than two"),
    (lambda pairs, r: [p[0] for p in pairs if len(p) == 2 and p[1].distance < r * p[0].distance],
     "wrong way round"),
    (lambda pairs, r: [p[1] for p in pairs if len(p) == 2 and p[0].distance < r * p[1].distance],
     "second neighbour"),
    (lambda pairs, r: [p[0] for p in pairs if len(p) == 2 and p[0].distance <= r * p[1].distance],
     "strictly nearer"),
    (lambda pairs, r: [p[0] for p in pairs if len(p) == 2 and p[0].distance < r], "fixed number"),
    (lambda pairs, r: [p[0].distance for p in pairs
                       if len(p) == 2 and p[0].distance < r * p[1].distance], "match objects"),
    (lambda pairs, r: 7, "return a list"),
    (not_written, "NotImplementedError"),
    (ch05.reference_good_matches, "abcwc's own"),
    (ratio_test, "abcwc's own"),
])
def test_match_check_refuses_plausible_slips(wrong, fragment, capsys):
    assert_not_yet(ch05.match_check(wrong), capsys, fragment)


def test_the_sign_range_is_the_pinhole_worked_by_hand():
    """fx = 320 / tan(28.5 deg) = 589.4 px; 0.6 m in 50 px: 589.4 * 0.6 / 50 = 7.07 m."""
    assert ch05.pinhole_range(50.0) == pytest.approx(7.073, abs=0.001)
    assert ch05.pinhole_range(60.0) == pytest.approx(5.894, abs=0.001)


def test_range_check(capsys):
    fx = 320 / math.tan(math.radians(28.5))
    measured = ch05.sweep_range()
    assert_pass(ch05.range_check(lambda: fx * 0.6 / 52, measured), capsys)
    assert_not_yet(ch05.range_check(lambda: fx * 0.3 / 52, measured), capsys, "height")
    whole = 320 / math.tan(math.radians(57))  # the whole field in the tangent
    assert_not_yet(ch05.range_check(lambda: whole * 0.6 / 52, measured), capsys,
                   "half the field")
    wide = 640 / math.tan(math.radians(28.5))  # the whole width over the half angle
    assert_not_yet(ch05.range_check(lambda: wide * 0.6 / 52, measured), capsys,
                   "twice too long")
    assert_not_yet(ch05.range_check(lambda: 1.5, measured), capsys, "45-60")
    assert_not_yet(ch05.range_check(lambda: "far", measured), capsys, "one distance")
    assert_not_yet(ch05.range_check(not_written, measured), capsys, "NotImplementedError")


def test_range_check_checks_the_measured_range_against_the_sweep(capsys):
    """A measured range typed in (or the wrong sweep's) is not the sweep's: the check runs
    the notebook's sweep itself and says so, whatever the prediction."""
    truth = ch05.sweep_range()
    assert 1.5 < truth < 9.0  # a view of the 1.5-9 m sweep
    assert_not_yet(ch05.range_check(lambda: 6.3, 0.0), capsys, "the sweep (SIFT")
    assert_not_yet(ch05.range_check(lambda: 6.3, truth + 0.5), capsys, f"{truth:.2f} m")
    assert_not_yet(ch05.range_check(lambda: 6.3, math.nan), capsys, "farthest")


def test_threshold_check_passes_a_threshold_read_off_the_plot(capsys):
    assert_pass(ch05.threshold_check(lambda: 0.45), capsys)


@pytest.mark.parametrize(("wrong", "fragment"), [
    (lambda: 0.05, "LIFT"),  # just above the STAIRS sign the notebook showed: LIFT passes
    (lambda: 0.0, "look-alikes"),
    (lambda: 0.99, "refused"),
    (lambda: 70, "between -1 and 1"),
    (lambda: math.nan, "one number"),
    (not_written, "NotImplementedError"),
])
def test_threshold_check_refuses_plausible_slips(wrong, fragment, capsys):
    assert_not_yet(ch05.threshold_check(wrong), capsys, fragment)
