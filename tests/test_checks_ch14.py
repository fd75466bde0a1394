"""The exercise checks of chapter 14 (SLAM with loop closure): each passes an answer
written independently of the library, and says "not yet" (never raises) for the
plausible wrong answers, the unwritten stub and abcwc's own function handed in."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.checks import ch14
from abcwc.mapping.posegraph import edge_errors
from tests.check_helpers import assert_not_yet, assert_pass, not_written


def _matrix(x, y, theta):
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s, x], [s, c, y], [0, 0, 1]])


def student_error(x_i, x_j, z, *, wrap=True, swap=False):
    """With 3 x 3 homogeneous matrices, as a student writes it from the text."""
    a, b = (x_j, x_i) if swap else (x_i, x_j)
    delta = np.linalg.inv(_matrix(*z)) @ np.linalg.inv(_matrix(*a)) @ _matrix(*b)
    theta = math.atan2(delta[1, 0], delta[0, 0])
    if not wrap:
        theta = (b[2] - a[2]) - z[2]
    return np.array([delta[0, 2], delta[1, 2], theta])


def test_error_passes_an_independent_answer(capsys):
    assert_pass(ch14.error_check(student_error), capsys)


@pytest.mark.parametrize(("wrong", "fragment"), [
    (lambda xi, xj, z: xj - xi - z, "x_j - x_i - z"),
    (lambda xi, xj, z: student_error(xi, xj, z, swap=True), "relative(x_j, x_i)"),
    (lambda xi, xj, z: student_error(xi, xj, z, wrap=False), "not wrapped"),
    (lambda xi, xj, z: student_error(xi, xj, z)[:2], "(x, y, theta)"),
    (lambda xi, xj, z: student_error(xi, xj, z) * 1.1, "expected"),
    (not_written, "NotImplementedError"),
    (ch14.reference_edge_error, "abcwc's own"),
    (edge_errors, "abcwc's own"),
])
def test_error_refuses_plausible_slips(wrong, fragment, capsys):
    assert_not_yet(ch14.error_check(wrong), capsys, fragment)


def test_prediction_check(capsys):
    assert_pass(ch14.prediction_check(lambda: 0.04, 0.03, 0.02), capsys)
    assert_not_yet(ch14.prediction_check(lambda: 1.0, 0.03, 0.02), capsys, "drifts far more")
    assert_not_yet(ch14.prediction_check(lambda: 0.001, 0.03, 0.02), capsys, "takes it back")
    assert_not_yet(ch14.prediction_check(lambda: "far", 0.03, 0.02), capsys, "one distance")


def student_false_loop(graph, metres=False):
    """Each edge's error at the solved poses, weighed by its information, the largest."""
    worst, index = -1.0, -1
    for k, (i, j) in enumerate(graph.edges):
        e = student_error(graph.poses[i], graph.poses[j], graph.measurements[k])
        size = math.hypot(e[0], e[1]) if metres else float(e @ graph.information[k] @ e)
        if size > worst:
            worst, index = size, k
    return index


def test_the_floor_survey_closes_loops_and_a_planted_false_loop_is_found(capsys):
    world, log, laser, with_loops, without = ch14.floor_survey()
    assert with_loops.loops > 50 and without.loops == 0
    assert ch14.worst_keyframe_error(with_loops, log, laser) < \
        ch14.worst_keyframe_error(without, log, laser)
    graph, planted, weak = ch14._planted()
    assert graph is ch14.planted_graph()
    assert 0 < planted < len(graph.edges) - 1 and 0 < weak < len(graph.edges) - 1
    assert_pass(ch14.false_loop_check(student_false_loop), capsys)
    # the false edge is not the last one, and the largest error in metres is another edge
    assert_not_yet(ch14.false_loop_check(lambda g: len(g.edges) - 1), capsys,
                   "fits the solved poses")
    assert_not_yet(ch14.false_loop_check(lambda g: student_false_loop(g, metres=True)),
                   capsys, "information matrix, not in metres")
    assert_not_yet(ch14.false_loop_check(lambda g: ch14.reference_false_loop(g)), capsys,
                   "abcwc's own")
    assert_not_yet(ch14.false_loop_check(lambda g: 0), capsys, "fits the solved poses")
    assert_not_yet(ch14.false_loop_check(lambda g: "the last"), capsys, "edge's index")
    assert_not_yet(ch14.false_loop_check(ch14.reference_false_loop), capsys, "abcwc's own")
    assert_not_yet(ch14.false_loop_check(not_written), capsys, "NotImplementedError")

