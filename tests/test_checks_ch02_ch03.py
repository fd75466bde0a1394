"""The exercise checks of chapters 02 (speed and turn control) and 03 (sonar avoidance).

Each check must pass a correct answer, and report "not yet" (never raise) for a wrong
one and for an exercise that is not written yet.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.behaviours import SonarAvoider
from abcwc.checks import ch02, ch03
from abcwc.control import turn_value, twist_to_pot_command
from abcwc.params import default_params
from abcwc.types import PotCommand, Twist
from tests.check_helpers import assert_not_yet, assert_pass, not_written

# --- chapter 02: eqn 2 ----------------------------------------------------------------


def test_turn_value_passes_eqn_2(capsys):
    assert_pass(ch02.turn_value_check(lambda angle: 254 - 1.6 * angle), capsys)
    assert_not_yet(ch02.turn_value_check(turn_value), capsys, "abcwc's own")


def test_turn_value_with_the_sign_flipped_is_not_yet(capsys):
    result = ch02.turn_value_check(lambda angle: 254 + 1.6 * angle)
    assert_not_yet(result, capsys, "angle -45 deg gave 182, expected 326", "worked example")


def test_turn_value_truncated_is_not_yet(capsys):
    result = ch02.turn_value_check(lambda angle: int(254 - 1.6 * angle))
    assert_not_yet(result, capsys, "eqn 2")


def test_turn_value_not_written(capsys):
    assert_not_yet(ch02.turn_value_check(not_written), capsys, "not written yet")


# --- chapter 02: the calibrated velocity controller -----------------------------------


def library_pots(v: float, w: float) -> PotCommand:
    """abcwc's own controller behind the exercise's signature: refused, not passed."""
    return twist_to_pot_command(Twist(v, w))


def float_pots(v: float, w: float) -> PotCommand:
    """The inverse of the motor model in floating point (a correct student answer)."""
    p = default_params()
    span = p.pot_full_scale_offset - p.pot_dead_band

    def offset(value: float, full: float) -> int:
        steps = round(min(abs(value) / full, 1.0) * span)
        return 0 if steps == 0 else int(math.copysign(p.pot_dead_band + steps, value))

    def safe(byte: int) -> int:
        return min(max(byte, p.pot_safe_min), p.pot_safe_max)

    return PotCommand(safe(128 + offset(v, p.max_speed)), safe(128 - offset(w, p.max_turn_rate)))


def test_twist_to_pots_passes_the_inverse_motor_model(capsys):
    assert_pass(ch02.twist_to_pots_check(float_pots), capsys)
    assert_not_yet(ch02.twist_to_pots_check(library_pots), capsys, "abcwc's own")


def test_twist_to_pots_off_by_two_is_not_yet(capsys):
    def off(v, w):
        command = float_pots(v, w)
        fb = command.fb + 2 if command.fb > 140 else command.fb
        return PotCommand(min(fb, 253), command.lr)

    assert_not_yet(ch02.twist_to_pots_check(off), capsys, "± 1")


def test_twist_to_pots_without_the_safe_range_is_not_yet(capsys):
    def unclamped(v, w):
        command = float_pots(v, w)
        return PotCommand(3 if command.fb == 8 else command.fb, command.lr)

    assert_not_yet(ch02.twist_to_pots_check(unclamped), capsys, "gave 3, expected 8")


def test_twist_to_pots_with_left_and_right_swapped_is_not_yet(capsys):
    def swapped(v, w):
        return float_pots(v, -w)

    assert_not_yet(ch02.twist_to_pots_check(swapped), capsys, "left turn is LR below 128")


def test_twist_to_pots_the_thesis_controller_is_not_yet(capsys):
    from abcwc.control import thesis_twist_to_pots

    result = ch02.twist_to_pots_check(lambda v, w: thesis_twist_to_pots(Twist(v, w)))
    assert_not_yet(result, capsys, "standing still")


def test_twist_to_pots_must_return_whole_bytes(capsys):
    result = ch02.twist_to_pots_check(lambda v, w: PotCommand(128, 128) if v == w == 0
                                      else type("P", (), {"fb": 128.5, "lr": 128})())
    assert_not_yet(result, capsys, "whole numbers")


def test_twist_to_pots_not_written(capsys):
    assert_not_yet(ch02.twist_to_pots_check(not_written), capsys, "not written yet")


# --- chapter 03: table 7 ---------------------------------------------------------------


def student_table7(distance_m):
    mm = distance_m * 1000
    if mm > 1000:
        return 0.0
    if mm < 200:
        return None
    return 45 + (10 - mm / 100) * 5.625


def test_turn_angle_passes_table_7(capsys):
    assert_pass(ch03.turn_angle_check(student_table7), capsys)
    assert_not_yet(ch03.turn_angle_check(ch03.table7_turn_angle), capsys, "abcwc's own")


def test_table7_turn_angle_values():
    assert ch03.table7_turn_angle(0.55) == pytest.approx(70.3125)
    assert ch03.table7_turn_angle(1.2) == 0.0
    assert ch03.table7_turn_angle(0.1) is None


def test_turn_angle_in_millimetres_is_not_yet(capsys):
    result = ch03.turn_angle_check(lambda d: student_table7(d / 1000))
    assert_not_yet(result, capsys, "expected 0 deg")


def test_turn_angle_without_the_45_degree_base_is_not_yet(capsys):
    def no_base(d):
        angle = student_table7(d)
        return angle - 45 if angle else angle

    assert_not_yet(ch03.turn_angle_check(no_base), capsys, "1 m gave 0", "expected 45")


def test_turn_angle_that_never_reverses_is_not_yet(capsys):
    result = ch03.turn_angle_check(lambda d: student_table7(max(d, 0.2)))
    assert_not_yet(result, capsys, "expected None")


def test_turn_angle_not_written(capsys):
    assert_not_yet(ch03.turn_angle_check(not_written), capsys, "not written yet")


# --- chapter 03: wandering the lab -------------------------------------------------------


class BounceWanderer:
    """Written here, not the chapter's recipe: drive on; near something in front, turn on
    the spot to the side the IR ring says is emptier until the front is clear; very
    near, back away first."""

    def __init__(self):
        self.turn = 0.0
        self.back_until = -1.0

    def __call__(self, frame):
        ir = np.nan_to_num(np.asarray(frame.ir, float), nan=1.5, posinf=1.5, neginf=0.0)
        front = min(frame.sonar, ir[0], ir[1] + 0.1, ir[5] + 0.1)
        if front < 0.35 and frame.t > self.back_until:
            self.back_until = frame.t + 0.8
        if frame.t < self.back_until:
            return Twist(-0.2, 0.0)
        if front < 0.9:
            if not self.turn:
                self.turn = 0.7 if ir[1] + ir[2] > ir[4] + ir[5] else -0.7
            return Twist(0.0, self.turn)
        self.turn = 0.0
        return Twist(0.45, 0.0)


def test_wander_passes_a_design_of_its_own(capsys):
    assert_pass(ch03.wander_check(BounceWanderer), capsys)


def test_wander_refuses_the_library_avoider_handed_in(capsys):
    assert_not_yet(ch03.wander_check(SonarAvoider), capsys, "abcwc's own")


def test_wander_accepts_a_factory_or_a_controller(capsys):
    assert_pass(ch03.wander_check(lambda: BounceWanderer()), capsys)
    # a controller object itself (a callable taking a frame) is used as it is
    assert ch03._make_controller(lambda frame: None) is not None


def test_wander_refuses_a_sensor_blind_circle(capsys):
    """Issue reproduction: Twist(0.35, 1.0) used to pass (42 m, no contact in the lab)."""
    result = ch03.wander_check(lambda frame: Twist(0.35, 1.0))
    assert_not_yet(result, capsys, "round in circles", "only 3 different square metres")


def test_wander_straight_ahead_collides(capsys):
    result = ch03.wander_check(lambda frame: Twist(0.8, 0.0))
    assert_not_yet(result, capsys, "touched something")


def plain_rule(frame):
    """Table 7 on the sonar, always turning right, at walking pace (0.6 / 0.3 m/s)."""
    angle = ch03.table7_turn_angle(frame.sonar)
    if not angle:
        return Twist(0.6, 0.0)
    return Twist(0.3, -math.radians(angle))


def test_wander_refuses_the_thesis_rule_turning_always_right(capsys):
    assert_not_yet(ch03.wander_check(lambda: plain_rule), capsys, "touched something")


def test_wander_standing_still_is_not_yet(capsys):
    result = ch03.wander_check(lambda frame: PotCommand(128, 128))
    assert_not_yet(result, capsys, "drove only 0.0 m")


def test_wander_hides_the_ground_truth(capsys):
    result = ch03.wander_check(lambda frame: Twist(0.5 if frame.truth.pose.x < 5 else 0.0, 0.0))
    assert_not_yet(result, capsys, "AttributeError")


def test_wander_not_written(capsys):
    class Stub:
        def __call__(self, frame):
            return not_written(frame)

    assert_not_yet(ch03.wander_check(Stub), capsys, "not written yet")


# --- chapter 02, exercise 3: predicting the coast after a stop ---------------------------------

MEASURED_COAST = 0.301  # m: the ideal chair after a stop at 1.0 m/s, as the notebook measures


def test_coast_prediction_passes_the_step_responses_reading(capsys):
    dead_time, tau = 0.040 + 0.020, 0.25   # the motor controller's delay and one period; the lag
    assert_pass(ch02.coast_prediction_check(lambda: 1.0 * (dead_time + tau), MEASURED_COAST),
                capsys)


@pytest.mark.parametrize(("predicted", "fragment"), [
    (lambda: 0.25, "only the lag"),
    (lambda: 0.06, "only the dead time"),
    (lambda: 1.31, "settling time"),
    (lambda: 0.185, "half of it"),
    (lambda: 0.9, "add up the distance"),
    (lambda: -0.3, "one distance"),
    (not_written, "NotImplementedError"),
    (ch02.turn_value_check, "abcwc's own"),
])
def test_coast_prediction_refuses(predicted, fragment, capsys):
    assert_not_yet(ch02.coast_prediction_check(predicted, MEASURED_COAST), capsys, fragment)


# --- chapter 03: predicting the sonar at a wall ----------------------------------------------

AT_THE_WALL = dict(reading=0.300, true_distance=0.05)   # as the notebook's run measures


def wall_check(predicted):
    return ch03.sonar_prediction_check(predicted, **AT_THE_WALL)


def test_sonar_prediction_passes_the_geometry_and_the_datasheet(capsys):
    p = default_params()
    front = p.length - p.axle_to_rear
    assert_pass(wall_check(lambda: (p.sonar.min_range, front - p.sonar.mount[0], False)), capsys)


@pytest.mark.parametrize(("predicted", "fragment"), [
    (lambda: (0.05, 0.05, False), "minimum range"),      # the truth, not what it reports
    (lambda: (0.30, 0.45, False), "their difference"),   # the front edge's offset
    (lambda: (0.30, 0.05, True), "never gives"),
    (lambda: (0.30, 0.20, False), "from the wall"),
    (lambda: (0.30, 0.05, "no"), "the third answer"),
    (lambda: 0.30, "return (reading"),
    (not_written, "NotImplementedError"),
    (ch03.table7_turn_angle, "abcwc's own"),
])
def test_sonar_prediction_refuses(predicted, fragment, capsys):
    assert_not_yet(wall_check(predicted), capsys, fragment)


# --- chapter 02, exercise 3: measuring the 63 % time -----------------------------------------


def model_step(dead=0.06, tau=0.25, dt=0.02):
    t = np.arange(-0.5, 2.0, dt)
    v = np.where(t > dead, 1.0 - np.exp(-(t - dead) / tau), 0.0)
    return t, v


def test_t63_check_passes_an_independent_reading(capsys):
    t, v = model_step()

    def crossing(t, v):
        final = v[-25:].mean()
        fine = np.linspace(0.0, t[-1], 20001)
        return float(fine[np.argmax(np.interp(fine, t, v) >= 0.632 * final)])
    assert_pass(ch02.t63_check(crossing, t, v), capsys)


@pytest.mark.parametrize(("measured", "fragment"), [
    (lambda t, v: 0.25, "tau alone"),
    (lambda t, v: 0.06, "dead time"),
    (lambda t, v: 1.31, "settling time"),
    (lambda t, v: 0.81, "log's own clock"),
    (lambda t, v: 0.5, "reaches 63.2 %"),
    (lambda t, v: float("nan"), "one time"),
    (not_written, "NotImplementedError"),
    (ch02.turn_value_check, "abcwc's own"),
])
def test_t63_check_refuses(measured, fragment, capsys):
    t, v = model_step()
    assert_not_yet(ch02.t63_check(measured, t, v), capsys, fragment)
