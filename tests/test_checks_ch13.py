"""The exercise checks of chapter 13 (occupancy grid mapping): each passes an answer
written independently of the library, and says "not yet" (never raises) for the
plausible wrong answers, the unwritten stub and abcwc's own function handed in."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.checks import ch13
from abcwc.mapping.grid import FREE, InverseSensorModel, OccupancyGrid
from abcwc.types import LaserScan
from tests.check_helpers import assert_not_yet, assert_pass, not_written


def student_update(log_odds, passed, returned, l_occ, l_free, l_min, l_max, *,
                   per_beam=False, both=False, clamp=True):
    """A cell at a time with Python sets, as a student writes it from the text."""
    out = [float(v) for v in log_odds]
    hits = list(returned) if per_beam else sorted(set(int(c) for c in returned))
    passes = list(passed) if per_beam else sorted(set(int(c) for c in passed))
    hit_set = set(int(c) for c in returned)
    for cell in passes:
        if both or int(cell) not in hit_set:
            out[cell] += l_free
    for cell in hits:
        out[cell] += l_occ
    if clamp:
        out = [min(max(v, l_min), l_max) for v in out]
    return np.array(out)


def test_update_passes_an_independent_answer(capsys):
    assert_pass(ch13.update_check(student_update), capsys)


@pytest.mark.parametrize(("wrong", "fragment"), [
    (lambda *a: student_update(*a, per_beam=True), "once per beam"),
    (lambda *a: student_update(*a, both=True), "a return wins"),
    (lambda *a: student_update(*a, clamp=False), "nothing is clamped"),
    (lambda *a: student_update(*a)[:-1], "whole array"),
    (lambda *a: student_update(*a) + 0.01, "cell 0"),
    (not_written, "NotImplementedError"),
    (ch13.reference_update_log_odds, "abcwc's own"),
])
def test_update_refuses_plausible_slips(wrong, fragment, capsys):
    assert_not_yet(ch13.update_check(wrong), capsys, fragment)


def test_clearing_takes_thirteen_scans_by_hand_and_in_a_grid():
    """From l_max = 3.5 down past log(0.196 / 0.804) = -1.411 at 0.4 a scan: 4.911 / 0.4 =
    12.3, so the 13th scan; and a real grid counts the same."""
    assert ch13.clearing_scans() == 13
    grid = OccupancyGrid(0.05, 40, 10)
    grid.log_odds[5, 20] = InverseSensorModel().l_max
    beam = LaserScan(0.0, 0.0, 0.1, 5.0, np.array([math.inf]))
    count = 0
    while grid.trinary()[5, 20] != FREE:
        grid.integrate(beam, (0.025, 0.275, 0.0))
        count += 1
    assert count == 13


def test_prediction_check(capsys):
    assert_pass(ch13.prediction_check(lambda: 13, 13), capsys)
    assert_not_yet(ch13.prediction_check(lambda: 217, 13), capsys, "without the clamp")
    assert_not_yet(ch13.prediction_check(lambda: 4, 13), capsys, "it took 13")
    assert_not_yet(ch13.prediction_check(lambda: "soon", 13), capsys, "number of scans")


def test_scores_check(capsys):
    precision, recall = ch13.ekf_map_scores()
    assert precision < 0.9 and recall < 0.9  # dead reckoning does not make a map
    assert_pass(ch13.scores_check(lambda: (precision, recall)), capsys)
    assert_not_yet(ch13.scores_check(lambda: (recall, precision)), capsys, "swapped")
    assert_not_yet(ch13.scores_check(lambda: (0.9, 0.9)), capsys, "not what the EKF's map")
    assert_not_yet(ch13.scores_check(lambda: ch13._scores("true poses")), capsys,
                   "map at the true poses")
    assert_not_yet(ch13.scores_check(lambda: ch13._scores("the EKF", tolerance=0)), capsys,
                   "one cell's tolerance")


def test_no_failure_message_holds_the_figures_to_copy(capsys):
    """A wrong pair is told what slip it is, never the right figures (handing in the
    figures of a failure message used to pass)."""
    precision, recall = ch13.ekf_map_scores()
    answer = {f"{precision:.2f}", f"{recall:.2f}", f"{precision:.3f}", f"{recall:.3f}"}
    for wrong in [(0, 0), (1.0, 1.0), (recall, precision), (precision, 0.2),
                  ch13._scores("true poses"), ch13._scores("the EKF", tolerance=0)]:
        result = ch13.scores_check(lambda wrong=wrong: wrong)
        capsys.readouterr()
        assert not result
        told = result.message.replace(f"you wrote ({wrong[0]:.2f}, {wrong[1]:.2f})", "")
        assert not any(figure in told for figure in answer), result.message
    assert_not_yet(ch13.scores_check(lambda: 0.5), capsys, "(precision, recall)")
