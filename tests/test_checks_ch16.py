"""The exercise checks of chapter 16 (planning and the navigator): each passes an answer
written independently of the library, and says "not yet" (never raises) for the
plausible wrong answers, the unwritten stub and abcwc's own function handed in."""

from __future__ import annotations

import heapq
import math

import numpy as np
import pytest

from abcwc.checks import ch16
from abcwc.navigation.planner import astar_search
from tests.check_helpers import assert_not_yet, assert_pass, not_written

# --- independent student answers ----------------------------------------------------------


def student_dijkstra(weights, start, goal, moves=None, step=None):
    """Dijkstra with a dictionary of costs, as a student writes it from the text."""
    height, width = weights.shape
    moves = moves or [(dr, dc) for dr in (-1, 0, 1) for dc in (-1, 0, 1) if dr or dc]
    step = step or (lambda length, a, b: length * (a + b) / 2)
    best = {tuple(start): 0.0}
    queue = [(0.0, tuple(start))]
    done = set()
    while queue:
        cost, cell = heapq.heappop(queue)
        if cell in done:
            continue
        done.add(cell)
        if cell == tuple(goal):
            return cost
        for dr, dc in moves:
            r, c = cell[0] + dr, cell[1] + dc
            if 0 <= r < height and 0 <= c < width and math.isfinite(weights[r, c]):
                new = cost + step(math.hypot(dr, dc), weights[cell], weights[r, c])
                if new < best.get((r, c), math.inf):
                    best[(r, c)] = new
                    heapq.heappush(queue, (new, (r, c)))
    return math.inf


FOUR = [(-1, 0), (1, 0), (0, -1), (0, 1)]


# --- exercise 1: the cheapest path --------------------------------------------------------


def test_path_cost_passes_an_independent_answer(capsys):
    assert_pass(ch16.path_cost_check(student_dijkstra), capsys)


@pytest.mark.parametrize(("wrong", "fragment"), [
    (lambda w, s, g: student_dijkstra(w, s, g, moves=FOUR), "only 4 moves"),
    (lambda w, s, g: student_dijkstra(w, s, g, step=lambda n, a, b: (a + b) / 2),
     "sqrt(2) cells long"),
    (lambda w, s, g: student_dijkstra(w, s, g, step=lambda n, a, b: n * b),
     "the cell it enters"),
    (lambda w, s, g: student_dijkstra(np.where(np.isfinite(w), w, 50.0), s, g),
     "impassable"),
    (lambda w, s, g: -1.0 if not math.isfinite(student_dijkstra(w, s, g))
     else student_dijkstra(w, s, g), "walled off"),
    (lambda w, s, g: f"{student_dijkstra(w, s, g)}", "one number"),
    (not_written, "not written yet"),
    (ch16.reference_cheapest_path_cost, "that is abcwc's own"),
    (astar_search, "that is abcwc's own"),
])
def test_path_cost_refuses_wrong_answers(wrong, fragment, capsys):
    assert_not_yet(ch16.path_cost_check(wrong), capsys, fragment)


def test_the_reference_agrees_with_the_checks_own_graph():
    for weights, start, goal in ch16.path_cost_grids():
        assert ch16.reference_cheapest_path_cost(weights, start, goal) == pytest.approx(
            student_dijkstra(weights, start, goal), rel=1e-12)


# --- exercise 2: predict, then run --------------------------------------------------------


def test_prediction_explains_both_ways(capsys):
    assert_pass(ch16.prediction_check(lambda: 0.3, 0.25), capsys)
    assert_not_yet(ch16.prediction_check(lambda: 0.05, 0.25), capsys, "touches more")
    assert_not_yet(ch16.prediction_check(lambda: 0.9, 0.25), capsys, "touches fewer")
    assert_not_yet(ch16.prediction_check(lambda: 25, 0.25), capsys, "fraction in 0..1")
    assert_not_yet(ch16.prediction_check(not_written, 0.25), capsys, "not written yet")


# --- exercise 3: diagnose and fix ---------------------------------------------------------


def test_a17s_scales_keep_the_chair_out_of_the_shown_door_and_the_fix_takes_it_in():
    walls, start, goal = ch16.shown_door()
    a17 = ch16.door_run(walls, start, goal, ch16.A17_SCALES)
    fixed = ch16.door_run(walls, start, goal, ch16.reference_door_scales())
    assert not a17.reached and a17.poses[:, 1].max() < 2.0  # it never went in
    assert fixed.reached and fixed.worst_cost < 254 and fixed.poses[-1, 1] > 3.5


def test_culprit(capsys):
    assert_pass(ch16.culprit_check(lambda: "occdist_scale"), capsys)
    assert_not_yet(ch16.culprit_check(lambda: "pdist_scale"), capsys, "argues for the door")
    assert_not_yet(ch16.culprit_check(lambda: "gdist_scale"), capsys, "argues for the door")
    assert_not_yet(ch16.culprit_check(lambda: "inflation"), capsys, "one of")
    assert_not_yet(ch16.culprit_check(not_written), capsys, "not written yet")


def test_door_scales_pass_a_different_fix(capsys):
    """Raising the goal scale instead of lowering the occupancy one also works."""
    assert_pass(ch16.door_scales_check(lambda: {**ch16.A17_SCALES, "gdist_scale": 4.0}),
                capsys)


@pytest.mark.parametrize(("wrong", "fragment"), [
    (lambda: dict(ch16.A17_SCALES), "A.17's scales"),
    (lambda: {"pdist_scale": 0.0, "gdist_scale": 0.0, "occdist_scale": 0.0},
     "did not get through"),
    (lambda: {**ch16.A17_SCALES, "occdist_scale": 1.0}, "did not get through"),
    (lambda: {**ch16.A17_SCALES, "occdist_scale": 0.05}, "unseen door"),
    (lambda: {"pdist": 0.8}, "exactly the keys"),
    (lambda: {**ch16.A17_SCALES, "occdist_scale": -1.0}, ">= 0"),
    (not_written, "not written yet"),
])
def test_door_scales_refuse_wrong_answers(wrong, fragment, capsys):
    assert_not_yet(ch16.door_scales_check(wrong), capsys, fragment)
