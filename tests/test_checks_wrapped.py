"""Every implement exercise's check refuses abcwc's own answer however it is wrapped: a
lambda that calls it, a ``functools.partial`` of it, or a student's function that calls
it through a helper (a wrapped library function used to pass every chapter's check)."""

from __future__ import annotations

import functools

import pytest

from abcwc.checks import (
    ch00,
    ch01,
    ch02,
    ch03,
    ch06,
    ch07,
    ch08,
    ch09,
    ch10,
    ch11,
    ch12,
    ch13,
    ch14,
    ch15,
)

# (check, the library's answer it must refuse)
IMPLEMENT_CHECKS = [
    (ch00.counts_per_wheel_turn, ch00.reference_counts_per_wheel_turn),
    (ch00.encoder_counts_to_distance, ch00.reference_encoder_counts_to_distance),
    (ch00.distance_ahead, ch00.reference_distance_ahead),
    (ch01.pot_mapping, ch01.joystick_to_pot_byte),
    (ch01.table_6, ch01.direction_pot_command),
    (ch01.square_sequence, ch01.reference_square_sequence),
    (ch02.turn_value_check, ch02.turn_value),
    (ch02.twist_to_pots_check, ch02.twist_to_pot_command),
    (ch03.turn_angle_check, ch03.sonar_turn_angle),
    (ch06.wheel_travel_check, ch06.reference_wheel_travel),
    (ch06.odometry_step_check, ch06.reference_odometry_step),
    (ch06.integrate_arcs_check, ch06.odometry.integrate_odometry),
    (ch07.distance_and_bearing_check, ch07.reference_distance_and_bearing),
    (ch07.turn_then_drive_check, ch07.reference_turn_then_drive),
    (ch07.proportional_command_check, ch07.reference_proportional_command),
    (ch08.centres_check, ch08.reference_centres_of_gravity_and_emax),
    (ch08.alpha_beta_radius_check, ch08.umbmark.alpha_beta),
    (ch08.correction_factors_check, ch08.reference_correction_factors),
    (ch09.bias_check, ch09.reference_estimate_bias),
    (ch09.heading_check, ch09.reference_integrate_heading),
    (ch09.fused_step_check, ch09.reference_fused_step),
    (ch10.kalman_update_check, ch10.kalman_update),
    (ch10.nees_check, ch10.nees),
    (ch11.origin_check, ch11.homogeneous),
    (ch11.correction_check, ch11.reference_biggest_correction),
    (ch12.ranges_check, ch12.depth_image_to_scan),
    (ch13.update_check, ch13.reference_update_log_odds),
    (ch14.error_check, ch14.edge_errors),
    (ch14.false_loop_check, ch14.reference_false_loop),
    (ch15.inflation_check, ch15.inflation_cost),
]


def through_a_helper(library):
    def helper(*args, **kwargs):
        return library(*args, **kwargs)

    def mine(*args, **kwargs):  # the student's own name, the library's work
        return helper(*args, **kwargs)

    return mine


@pytest.mark.parametrize("wrap", [
    lambda library: (lambda *args, **kwargs: library(*args, **kwargs)),
    functools.partial,
    through_a_helper,
], ids=["lambda", "partial", "helper"])
@pytest.mark.parametrize(("check", "library"), IMPLEMENT_CHECKS,
                         ids=[check.__module__[-4:] + "." + check.__name__
                              for check, _ in IMPLEMENT_CHECKS])
def test_the_librarys_answer_wrapped_is_refused(check, library, wrap, capsys):
    result = check(wrap(library))
    capsys.readouterr()
    assert not result and "abcwc's own" in result.message, result.message


def test_the_motion_models_wrapped_are_refused(capsys):
    result = ch10.motion_check(lambda s, dt: ch10.reference_motion(s, dt),
                               functools.partial(ch10.reference_motion_jacobian))
    capsys.readouterr()
    assert not result and "abcwc's own" in result.message, result.message
