"""The exercise checks of chapter 16 (planning and the navigator): each passes an answer
written independently of the library, and says "not yet" (never raises) for the
plausible wrong answers, the unwritten stub and abcwc's own function handed in."""

from __future__ import annotations

import functools
import heapq
import math

import numpy as np
import pytest

from abcwc.checks import ch16
from abcwc.navigation.dwa import DwaPlanner
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


# --- exercise 4: the chair's minimum clear width ------------------------------------------


def student_clear_width(length, width, padding, resolution):
    """Written from the text: three circles along the chair, each over a third of its
    length; the padding; half a cell's diagonal for the wall's cell and for the chair's."""
    third = length / 3
    circle = math.sqrt((third / 2) ** 2 + (width / 2) ** 2)
    return 2 * circle + 2 * padding + 2 * resolution * math.sqrt(2)


def test_clear_width_passes_an_independent_answer(capsys):
    assert_pass(ch16.clear_width_check(student_clear_width), capsys)


def test_table_2s_chair_needs_about_0_76_m():
    assert ch16.reference_clear_width(0.61, 0.482, 0.05, 0.05) == pytest.approx(
        student_clear_width(0.61, 0.482, 0.05, 0.05), abs=1e-12)
    assert 0.76 < student_clear_width(0.61, 0.482, 0.05, 0.05) < 0.77


@pytest.mark.parametrize(("wrong", "fragment"), [
    (lambda length, width, padding, res: width + 2 * padding, "the chair's own width"),
    (lambda length, width, padding, res: 2 * (math.hypot(length / 2, width / 2) + padding),
     "turning on the spot"),
    (lambda length, width, padding, res: 2 * (math.hypot(length / 6, width / 2) + padding),
     "the grid is missing"),
    (lambda length, width, padding, res: 2 * (math.hypot(length / 6, width / 2) + padding
                                              + res / math.sqrt(2)), "only one half-diagonal"),
    (lambda length, width, padding, res: student_clear_width(length, width, padding, res) / 2,
     "that is a radius"),
    (lambda length, width, padding, res: 2 * (math.hypot(length / 2, width / 2) + padding
                                              + res * math.sqrt(2)), "one circle"),
    (lambda length, width, padding, res: 0.7646, "not the width the local planner needs"),
    (lambda length, width, padding, res: "0.76", "one number"),
    (not_written, "not written yet"),
    (ch16.reference_clear_width, "that is abcwc's own"),
    (lambda length, width, padding, res: ch16.reference_clear_width(length, width, padding, res),
     "abcwc's own"),
    (functools.partial(ch16.reference_clear_width), "abcwc's own"),
    (lambda length, width, padding, res: 2 * DwaPlanner(ch16.FOOTPRINT).passing_radius(res),
     "abcwc's own"),
])
def test_clear_width_refuses_wrong_answers(wrong, fragment, capsys):
    assert_not_yet(ch16.clear_width_check(wrong), capsys, fragment)


def test_clear_width_messages_do_not_give_the_answer(capsys):
    ch16.clear_width_check(lambda length, width, padding, res: 0.5)
    out = capsys.readouterr().out
    assert "0.765" not in out and "0.764" not in out


# --- exercise 5: predict, then run: the doors the chair takes -----------------------------

MEASURED_DOORS = {0.75: False, 0.80: True, 0.85: True, 0.90: True}  # the notebook's runs


def test_the_door_family_is_planned_as_the_chair_needs():
    """The check's own confirmation: the navigator plans through the doors at least the
    independently worked-out width and round the others."""
    needs = student_clear_width(0.61, 0.482, 0.05, 0.05)
    for width in ch16.DOOR_FAMILY:
        assert ch16._planned_through(width) == (width >= needs)


def test_doors_prediction_passes_the_right_doors(capsys):
    assert_pass(ch16.doors_prediction_check(lambda: [0.9, 0.85, 0.8], MEASURED_DOORS), capsys)
    assert_pass(ch16.doors_prediction_check(lambda: (0.80, 0.85, 0.90), MEASURED_DOORS), capsys)


@pytest.mark.parametrize(("wrong", "fragments"), [
    (lambda: [0.75, 0.80, 0.85, 0.90], ["[0.75] it went round"]),  # by the chair's own width
    (lambda: [0.90], ["[0.8, 0.85] it drove through"]),  # by the turning width, or caution
    (lambda: [0.85, 0.90], ["[0.8] it drove through"]),
    (lambda: [0.75], ["[0.75] it went round", "[0.8, 0.85, 0.9] it drove through"]),
    (lambda: 0.8, ["return the widths"]),
    (lambda: [1.0], ["return the widths"]),
    (not_written, ["not written yet"]),
])
def test_doors_prediction_refuses_wrong_answers(wrong, fragments, capsys):
    assert_not_yet(ch16.doors_prediction_check(wrong, MEASURED_DOORS), capsys, *fragments)


def test_doors_prediction_refuses_a_measurement_that_is_not_the_navigators(capsys):
    tampered = {**MEASURED_DOORS, 0.75: True}
    assert_not_yet(ch16.doors_prediction_check(lambda: [0.75, 0.80, 0.85, 0.90], tampered),
                   capsys, "do not match", "0.75 m door")
