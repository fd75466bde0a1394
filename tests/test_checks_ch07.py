"""The exercise checks of chapter 07 (going to a landmark).

Each check must pass a correct answer, and report "not yet" (never raise) for a wrong
one and for an exercise that is not written yet.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.behaviours import landmark
from abcwc.checks import ch07
from abcwc.types import Twist
from tests.check_helpers import assert_not_yet, assert_pass, not_written

# --- exercise 1: distance and bearing --------------------------------------------------


def numpy_bearing(pose, goal):
    """A correct answer written differently: NumPy, wrapping with the modulo."""
    d = np.array(goal) - np.array([pose.x, pose.y])
    alpha = (np.arctan2(d[1], d[0]) - pose.theta + np.pi) % (2 * np.pi) - np.pi
    return np.linalg.norm(d), alpha


def test_bearing_passes_eqns_11_12(capsys):
    assert_pass(ch07.distance_and_bearing_check(numpy_bearing), capsys)
    assert_not_yet(ch07.distance_and_bearing_check(landmark.distance_and_bearing), capsys,
                   "abcwc's own")


def test_bearing_hand_worked_values():
    from abcwc.types import Pose2D

    rho, alpha = ch07.reference_distance_and_bearing(Pose2D(1.0, 2.0, 0.0), (4.0, 6.0))
    assert (rho, alpha) == pytest.approx((5.0, math.atan2(4.0, 3.0)))
    rho, alpha = ch07.reference_distance_and_bearing(Pose2D(0.0, 0.0, 3.0), (-1.0, -0.1))
    assert alpha == pytest.approx(math.atan2(-0.1, -1.0) - 3.0 + 2 * math.pi)


def test_bearing_without_the_wrap_is_not_yet(capsys):
    def unwrapped(pose, goal):
        dx, dy = goal[0] - pose.x, goal[1] - pose.y
        return math.hypot(dx, dy), math.atan2(dy, dx) - pose.theta

    result = ch07.distance_and_bearing_check(unwrapped)
    assert_not_yet(result, capsys, "outside (-pi, pi]", "wrap it to 0.241261")


def test_bearing_with_eqn_11_as_printed_is_not_yet(capsys):
    def as_printed(pose, goal):
        rho, alpha = numpy_bearing(pose, goal)
        return math.sqrt((goal[0] - pose.x) ** 2 + (goal[1] - goal[1]) ** 2), alpha

    assert_not_yet(ch07.distance_and_bearing_check(as_printed), capsys, "y_d - y_d")


def test_bearing_with_atan2_arguments_swapped_is_not_yet(capsys):
    def swapped(pose, goal):
        dx, dy = goal[0] - pose.x, goal[1] - pose.y
        return math.hypot(dx, dy), landmark.wrap_angle(math.atan2(dx, dy) - pose.theta)

    assert_not_yet(ch07.distance_and_bearing_check(swapped), capsys, "alpha gave",
                   "3-4-5 triangle")


def test_bearing_in_degrees_is_not_yet(capsys):
    def degrees(pose, goal):
        rho, alpha = numpy_bearing(pose, goal)
        return rho, math.degrees(alpha)

    assert_not_yet(ch07.distance_and_bearing_check(degrees), capsys, "53.1301 rad")


def test_bearing_returning_one_number_is_not_yet(capsys):
    result = ch07.distance_and_bearing_check(lambda pose, goal: 5.0)
    assert_not_yet(result, capsys, "expected a pair (rho, alpha)")


def test_bearing_not_written(capsys):
    assert_not_yet(ch07.distance_and_bearing_check(not_written), capsys, "not written yet")


# --- exercise 2: turn then drive ---------------------------------------------------------


def student_machine(state, rho, alpha, tolerance=0.5, heading_tolerance=0.3,
                    align_tolerance=0.1, speed=0.5, turn_rate=0.5):
    """A correct answer written differently."""
    if state == "reached" or rho <= tolerance:
        return "reached", Twist(0.0, 0.0)
    off = align_tolerance if state == "turn" else heading_tolerance
    if abs(alpha) <= off:
        return "drive", Twist(speed, 0.0)
    return "turn", Twist(0.0, turn_rate if alpha > 0 else -turn_rate)


def test_machine_passes(capsys):
    assert_pass(ch07.turn_then_drive_check(student_machine), capsys)
    assert_not_yet(ch07.turn_then_drive_check(landmark.turn_then_drive), capsys,
                   "abcwc's own")


def test_machine_hand_worked_values():
    settings = ch07.THESIS_MACHINE
    state, twist = ch07.reference_turn_then_drive("turn", 2.0, 0.2, **settings)
    assert (state, twist) == ("turn", Twist(0.0, 0.5))
    state, twist = ch07.reference_turn_then_drive("drive", 2.0, 0.2, **settings)
    assert (state, twist) == ("drive", Twist(0.5, 0.0))
    state, twist = ch07.reference_turn_then_drive("drive", 2.0, -0.35, **settings)
    assert (state, twist) == ("turn", Twist(0.0, -0.5))
    assert ch07.reference_turn_then_drive("reached", 5.0, 1.0, **settings)[0] == "reached"


def test_machine_without_hysteresis_is_not_yet(capsys):
    def one_threshold(state, rho, alpha, **settings):
        settings["align_tolerance"] = settings["heading_tolerance"]
        return student_machine(state, rho, alpha, **settings)

    assert_not_yet(ch07.turn_then_drive_check(one_threshold), capsys,
                   "state gave 'drive', expected 'turn'", "align_tolerance")


def test_machine_with_a10s_turn_directions_is_not_yet(capsys):
    def away(state, rho, alpha, **settings):
        state, twist = student_machine(state, rho, alpha, **settings)
        return state, Twist(twist.v, -twist.w)

    assert_not_yet(ch07.turn_then_drive_check(away), capsys, "positive w turns left")


def test_machine_that_forgets_it_arrived_is_not_yet(capsys):
    def no_latch(state, rho, alpha, **settings):
        return student_machine("turn" if state == "reached" else state, rho, alpha,
                               **settings)

    assert_not_yet(ch07.turn_then_drive_check(no_latch), capsys, "for good")


def test_machine_returning_bare_numbers_is_not_yet(capsys):
    def numbers(state, rho, alpha, **settings):
        state, twist = student_machine(state, rho, alpha, **settings)
        return state, twist.v, twist.w

    assert_not_yet(ch07.turn_then_drive_check(numbers), capsys, "expected (state, Twist")


def test_machine_not_written(capsys):
    assert_not_yet(ch07.turn_then_drive_check(not_written), capsys, "not written yet")


# --- exercise 3: the proportional law ---------------------------------------------------


def student_law(rho, alpha, k_rho=0.8, k_alpha=1.5, max_speed=0.8, max_turn_rate=0.8,
                decel=0.5):
    """A correct answer written differently (NumPy clip)."""
    w = float(np.clip(k_alpha * alpha, -max_turn_rate, max_turn_rate))
    v = min(k_rho * rho, max_speed, (2 * decel * rho) ** 0.5)
    return Twist(v * np.cos(alpha) if np.cos(alpha) > 0 else 0.0, w)


def test_law_passes(capsys):
    assert_pass(ch07.proportional_command_check(student_law), capsys)
    assert_not_yet(ch07.proportional_command_check(landmark.proportional_command), capsys,
                   "abcwc's own")


def test_law_hand_worked_values():
    twist = ch07.reference_proportional_command(2.0, 0.2)
    assert twist.v == pytest.approx(0.8 * math.cos(0.2)) and twist.w == pytest.approx(0.3)
    assert ch07.reference_proportional_command(0.3, 0.0).v == pytest.approx(0.24)
    assert ch07.reference_proportional_command(0.5, 0.0, k_rho=2.0).v == pytest.approx(
        math.sqrt(0.5))
    assert ch07.reference_proportional_command(2.0, 2.0).v == 0.0


def test_law_that_reverses_towards_a_goal_behind_is_not_yet(capsys):
    def reverses(rho, alpha, **gains):
        twist = student_law(rho, 0.0, **gains)
        return Twist(twist.v * math.cos(alpha), student_law(rho, alpha, **gains).w)

    assert_not_yet(ch07.proportional_command_check(reverses), capsys, "goal behind")


def test_law_without_the_turn_limit_is_not_yet(capsys):
    def unclipped(rho, alpha, **gains):
        return Twist(student_law(rho, alpha, **gains).v, gains["k_alpha"] * alpha)

    assert_not_yet(ch07.proportional_command_check(unclipped), capsys, "max_turn_rate")


def test_law_without_the_braking_limit_is_not_yet(capsys):
    def no_brake(rho, alpha, **gains):
        gains["decel"] = 1e6
        return student_law(rho, alpha, **gains)

    assert_not_yet(ch07.proportional_command_check(no_brake), capsys, "braking limit")


def test_law_not_written(capsys):
    assert_not_yet(ch07.proportional_command_check(not_written), capsys, "not written yet")


# --- predict, then run: a 2 cm tolerance -------------------------------------------------------

TIGHT_RUN = dict(turn_then_drive=0.291, proportional=0.010)   # m, as the notebook measures


def tight_check(predicted):
    return ch07.tight_prediction_check(predicted, **TIGHT_RUN)


def test_tight_prediction_passes_a_stopping_distance_reading(capsys):
    # 0.5 m/s through the delay and the lag, then braked at the safety filter's 0.8 m/s^2
    roll_out = 0.5 * (0.06 + 0.25) + 0.5 ** 2 / (2 * 0.8)
    assert_pass(tight_check(lambda: (roll_out, 0.01)), capsys)


@pytest.mark.parametrize(("predicted", "fragment"), [
    (lambda: (0.02, 0.02), "cannot stop within 2 cm"),   # both keep their tolerance
    (lambda: (1.0, 0.01), "one roll-out"),
    (lambda: (0.3, 0.1), "slows down as it closes in"),
    (lambda: (0.1, -0.01), "distances in m"),
    (lambda: 0.1, "two distances"),
    (not_written, "NotImplementedError"),
    (ch07.reference_proportional_command, "abcwc's own"),
])
def test_tight_prediction_refuses(predicted, fragment, capsys):
    assert_not_yet(tight_check(predicted), capsys, fragment)


# --- measure: the heading error gained per corner --------------------------------------------

# the notebook's corners, reached before the safety filter stops the chair at the shelf
GAPS = [(gap, math.radians(turn)) for gap, turn in ((0.08, -0.2), (0.23, 1.4), (0.43, 2.6),
                                                    (0.45, 4.3), (0.39, 5.6), (0.55, 6.9))]


def corner_check(fn):
    return ch07.corner_gain_check(fn, GAPS)


def test_corner_gain_passes_an_independent_fit(capsys):
    def least_squares(gaps):
        y = [math.degrees(turn) for _, turn in gaps]
        x = list(range(len(gaps)))
        mx, my = sum(x) / len(x), sum(y) / len(y)
        return (sum((a - mx) * (b - my) for a, b in zip(x, y))
                / sum((a - mx) ** 2 for a in x))
    assert_pass(corner_check(least_squares), capsys)


def test_corner_gain_passes_the_mean_step_between_corners(capsys):
    def mean_step(gaps):
        return (math.degrees(gaps[-1][1]) - math.degrees(gaps[0][1])) / (len(gaps) - 1)
    assert_pass(corner_check(mean_step), capsys)


def _degrees(gaps):
    return np.degrees([turn for _, turn in gaps])


@pytest.mark.parametrize(("fn", "fragment"), [
    (lambda gaps: math.radians(1.42), "radians"),
    (lambda gaps: math.degrees(gaps[-1][1] - gaps[0][1]), "divide by the number"),
    (lambda gaps: float(np.polyfit(range(len(gaps)), _degrees(gaps), 1)[1]), "intercept"),
    (lambda gaps: float(np.polyfit(range(len(gaps)), [gap for gap, _ in gaps], 1)[0]),
     "position errors"),
    (lambda gaps: 3.0, "straight line"),
    (lambda gaps: "1.5", "one number"),
    (not_written, "NotImplementedError"),
    (ch07.reference_proportional_command, "abcwc's own"),
])
def test_corner_gain_refuses(fn, fragment, capsys):
    assert_not_yet(corner_check(fn), capsys, fragment)


def test_corner_gain_does_not_print_the_answer(capsys):
    corner_check(lambda gaps: 3.0)
    assert "1.42" not in capsys.readouterr().out
