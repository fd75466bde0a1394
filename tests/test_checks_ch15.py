"""The exercise checks of chapter 15 (costmaps): each passes an answer written
independently of the library, and says "not yet" (never raises) for the plausible wrong
answers, the unwritten stub and abcwc's own function handed in."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.checks import ch15
from abcwc.navigation.costmap import Costmap, inflation_cost
from tests.check_helpers import assert_not_yet, assert_pass, not_written

# --- independent student answers ----------------------------------------------------------


def student_inflation(distance, inscribed_radius, k):
    """Written from the text with a loop, one distance at a time."""
    out = []
    for d in np.asarray(distance, dtype=float):
        if d == 0:
            out.append(254)
        elif d <= inscribed_radius:
            out.append(253)
        else:
            out.append(int(252 * math.exp(-k * (d - inscribed_radius))))
    return np.array(out)


def student_costmap(walls, resolution):
    costmap = Costmap.from_walls(walls, resolution)
    costmap.inflate(0.16, 0.9, 5.0)
    return costmap


# --- exercise 1: inflation ----------------------------------------------------------------


def test_inflation_passes_an_independent_answer(capsys):
    assert_pass(ch15.inflation_check(student_inflation), capsys)


@pytest.mark.parametrize(("wrong", "fragment"), [
    (lambda d, r, k: np.round(252 * np.exp(-k * (np.asarray(d) - r))).clip(0, 253)
     * (np.asarray(d) > r) + 253 * (np.asarray(d) <= r) + (np.asarray(d) == 0),
     "rounded"),
    (lambda d, r, k: np.where(np.asarray(d) <= r, 253,
                              np.floor(252 * np.exp(-k * np.asarray(d)))), "distance 0 gave 253"),
    (lambda d, r, k: np.where(np.asarray(d) == 0, 254, np.where(
        np.asarray(d) <= r, 253, np.floor(252 * np.exp(-k * np.asarray(d))))),
     "the decay starts at the inscribed radius"),
    (not_written, "not written yet"),
    (ch15.reference_inflation_cost, "that is abcwc's own"),
    (inflation_cost, "that is abcwc's own"),
])
def test_inflation_refuses_wrong_answers(wrong, fragment, capsys):
    assert_not_yet(ch15.inflation_check(wrong), capsys, fragment)


# --- exercise 2: predict, then run --------------------------------------------------------


def test_prediction_explains_both_ways(capsys):
    assert_pass(ch15.prediction_check(lambda: 0.12, 0.08), capsys)
    assert_not_yet(ch15.prediction_check(lambda: 0.5, 0.08), capsys, "passes nearer")
    assert_not_yet(ch15.prediction_check(lambda: 0.0, 0.3), capsys, "farther off")
    assert_not_yet(ch15.prediction_check(lambda: "close", 0.08), capsys, "one number")
    assert_not_yet(ch15.prediction_check(not_written, 0.08), capsys, "not written yet")


def test_path_clearance_by_hand():
    walls = np.array([[0.0, 0.0, 10.0, 0.0], [10.0, 0.0, 10.0, 4.0], [10.0, 4.0, 0.0, 4.0],
                      [0.0, 4.0, 0.0, 0.0]])
    assert ch15.path_clearance(np.array([[5.0, 1.0], [5.0, 0.5]]), walls) == \
        pytest.approx(0.5, abs=0.03)
    assert ch15.path_clearance(np.array([[5.0, 2.0]]), walls) == pytest.approx(2.0, abs=0.03)


# --- exercise 3: diagnose -----------------------------------------------------------------


def fitted_yaw(marks, walls_here, lidar) -> float:
    """An independent search: the yaw whose turn of the marks lays most on the walls."""
    points = marks.cell_to_world(*np.nonzero(marks.cost == 254)) - lidar
    wall_cells = set(zip(*np.nonzero(walls_here.cost == 254)))

    def on_walls(degrees):
        c, s = math.cos(math.radians(-degrees)), math.sin(math.radians(-degrees))
        turned = points @ np.array([[c, s], [-s, c]]) + lidar
        rows, cols = walls_here.world_to_cell(turned)
        near = 0
        for r, q in zip(rows, cols):
            near += any((r + dr, q + dc) in wall_cells for dr in (-1, 0, 1) for dc in (-1, 0, 1))
        return near

    return float(max(np.arange(-15, 15.5, 0.5), key=on_walls))


def test_scan_yaw_found_by_fitting_the_marks_to_the_walls(capsys):
    assert_pass(ch15.scan_yaw_check(fitted_yaw), capsys)


def test_scan_yaw_cases_differ_so_no_single_angle_passes(capsys):
    errors = [yaw for _, yaw in ch15.MYSTERY_CASES]
    assert min(abs(a - b) for a in errors for b in errors if a is not b) > 4.0
    assert {math.copysign(1, yaw) for yaw in errors} == {-1.0, 1.0}
    for yaw in errors:  # the notebook's answer, or any other case's, written down
        assert_not_yet(ch15.scan_yaw_check(lambda *evidence, yaw=yaw: yaw), capsys, "not")


@pytest.mark.parametrize(("answer", "fragment"), [
    (lambda *evidence: -fitted_yaw(*evidence), "wrong sign"),
    (lambda *evidence: 0.0, "is not it"),
    (lambda *evidence: math.radians(fitted_yaw(*evidence)), "radians"),
    (not_written, "not written yet"),
])
def test_scan_yaw_refuses_wrong_answers(answer, fragment, capsys):
    assert_not_yet(ch15.scan_yaw_check(answer), capsys, fragment)


# --- exercise 4: design -------------------------------------------------------------------


def test_design_passes_a_chair_costmap(capsys):
    assert_pass(ch15.chair_costmap_check(student_costmap), capsys)


def _costmap(inscribed, inflation, k):
    def build(walls, resolution):
        costmap = Costmap.from_walls(walls, resolution)
        costmap.inflate(inscribed, inflation, k)
        return costmap
    return build


@pytest.mark.parametrize(("answer", "fragment"), [
    (_costmap(0.5, 0.55, 10.0), "no path through its doors"),  # A.17's robot_radius
    (_costmap(0.51, 0.8, 10.0), "no path through its doors"),  # the circumscribed radius
    (_costmap(0.16, 0.16, 10.0), "came 0."),  # no margin: the path hugs a wall
    (_costmap(0.16, 0.7, 30.0), "came 0."),  # too steep: a free middle but cheap edges
    (lambda walls, resolution: np.zeros((3, 3)), "expected a Costmap"),
    (not_written, "not written yet"),
    (ch15.reference_chair_costmap, "that is abcwc's own"),
])
def test_design_refuses_wrong_answers(answer, fragment, capsys):
    assert_not_yet(ch15.chair_costmap_check(answer), capsys, fragment)


def test_design_worlds_have_the_narrow_door_and_reachable_goals():
    for walls, start, goal, spans in ch15.design_worlds():
        gaps = []
        ys = walls[:, 1] == 4.0
        xs = np.sort(walls[ys][:, [0, 2]].ravel())
        gaps = np.diff(xs)[1::2]
        assert gaps.min() == pytest.approx(ch15.DESIGN_DOOR)
        assert spans and all(x1 - x0 > 1.0 for x0, x1, _ in spans)
        assert start[1] < 4.0 and goal[1] < 4.0
