"""Pot control against the thesis's worked numbers (4.1.3-4.1.6, table 6, table 7, A.14)."""

from __future__ import annotations

import math

import pytest

from abcwc.control import (
    TABLE_6_AS_PRINTED,
    AvoidAction,
    angle_to_lr_byte,
    direction_pot_command,
    joystick_to_pot_byte,
    pot_byte_to_deflection,
    sonar_turn_angle,
    thesis_twist_to_pots,
    turn_value,
    twist_to_pot_bytes_int,
    twist_to_pot_command,
)
from abcwc.types import PotCommand, Twist


@pytest.mark.parametrize("joystick, byte", [(398, 253), (254, 130), (110, 8), (300, 170)])
def test_eqn1_worked_values(joystick, byte):
    # (v - 100) * 0.85, truncated: 298 * 0.85 = 253.3; 154 * 0.85 = 130.9; 10 * 0.85 = 8.5
    assert joystick_to_pot_byte(joystick) == byte


def test_eqn1_matches_float_formula_on_whole_range():
    for v in range(110, 399):
        assert joystick_to_pot_byte(v) == math.floor((v - 100) * 0.85 + 1e-9)


@pytest.mark.parametrize("bad", [109, 412, float("nan"), float("inf"), "254"])
def test_eqn1_refuses_out_of_range(bad):
    with pytest.raises(ValueError, match=r"110\.\.398|finite number"):
        joystick_to_pot_byte(bad)


def test_table_6_corrected_and_as_printed():
    # printed forward 256 is not a byte; eqn 1 of the joystick's end gives 253
    assert direction_pot_command("forward") == PotCommand(253, 128)
    assert direction_pot_command("reverse") == PotCommand(8, 128)
    assert TABLE_6_AS_PRINTED["reverse"][0] == 9  # 8.5 rounded in print, truncated in code
    assert direction_pot_command("stop") == PotCommand(128, 128)
    # eqn 2 / A.4 / A.14: a low LR byte turns left (table 6 prints it the other way)
    assert direction_pot_command("left").lr < 128 < direction_pot_command("right").lr
    with pytest.raises(ValueError, match="forward, reverse, left, right, stop"):
        direction_pot_command("up")


def test_eqn2_worked_example_and_ends():
    # the thesis's worked example: 254 + 1.6 * 45 = 326 (a 45-degree right turn here)
    assert turn_value(-45) == pytest.approx(326.0)
    assert turn_value(45) == pytest.approx(182.0)
    assert turn_value(90) == pytest.approx(110.0)
    assert turn_value(-90) == pytest.approx(398.0)
    assert turn_value(0) == 254
    assert angle_to_lr_byte(-45) == (326 - 100) * 85 // 100
    with pytest.raises(ValueError, match=r"-90\.\.90"):
        turn_value(91)


@pytest.mark.parametrize(
    "distance_mm, angle",
    [(1000, 45.0), (900, 50.625), (800, 56.25), (700, 61.875), (600, 67.5), (500, 73.125),
     (400, 78.75), (300, 84.375), (200, 90.0), (550, 70.3125)],
)
def test_table_7_and_eqn_3(distance_mm, angle):
    decision = sonar_turn_angle(distance_mm / 1000)
    assert decision.action is AvoidAction.TURN
    assert decision.angle_deg == pytest.approx(angle)


def test_table_7_ends():
    assert sonar_turn_angle(1.001).action is AvoidAction.FORWARD
    assert sonar_turn_angle(0.199).action is AvoidAction.REVERSE
    with pytest.raises(ValueError):
        sonar_turn_angle(float("nan"))
    with pytest.raises(ValueError, match="0..inf"):
        sonar_turn_angle(-0.1)


def test_a14_thesis_velocity_controller_hand_worked():
    # w = 0.3 rad/s -> 17.18874 deg/s -> int(254 - 27.502) = 226 -> int(126 * 0.85) = 107
    # v = 0.5 m/s -> 50 cm/s -> 254 + 80 = 334 -> int(234 * 0.85) = 198
    assert thesis_twist_to_pots(Twist(0.5, 0.3)) == PotCommand(198, 107)
    # 1 m/s would be 414 on the pot scale: clamped to 398 -> 253. 0.9 m/s is already full.
    assert thesis_twist_to_pots(Twist(1.0, 0.0)) == PotCommand(253, 130)
    assert thesis_twist_to_pots(Twist(0.9, 0.0)).fb == 253
    assert thesis_twist_to_pots(Twist(-2.0, -5.0)) == PotCommand(8, 253)


def test_calibrated_controller_is_inverse_of_motor_model(params):
    for v in (-1.5, -0.4, -0.05, 0.02, 0.3, 0.83, 1.2, 1.6667):
        fb = twist_to_pot_command(Twist(v, 0.0)).fb
        assert pot_byte_to_deflection(fb) * params.max_speed == pytest.approx(v, abs=0.008)
    # left (w > 0) and reverse reach 118/123 of full scale: the safe range stops at 8
    for w in (-1.5708, -0.5, 0.1, 0.7, 1.45):
        lr = twist_to_pot_command(Twist(0.0, w)).lr
        assert -pot_byte_to_deflection(lr) * params.max_turn_rate == pytest.approx(w, abs=0.007)


def test_calibrated_controller_saturates_into_safe_range():
    assert twist_to_pot_command(Twist(10.0, 10.0)) == PotCommand(253, 8)
    assert twist_to_pot_command(Twist(-10.0, -10.0)) == PotCommand(8, 253)
    assert twist_to_pot_bytes_int(0, 0) == (128, 128)
    assert twist_to_pot_bytes_int(1, 0) == (128, 128)  # below one step of the pot


def test_motor_model_dead_band_hides_eqn1_centre():
    assert pot_byte_to_deflection(130) == 0.0  # eqn 1 of the joystick centre
    assert pot_byte_to_deflection(253) == 1.0
    assert pot_byte_to_deflection(8) == pytest.approx(-118 / 123)
