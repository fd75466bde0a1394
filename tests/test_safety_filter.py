"""The safety filter: limits a seated person can take, stops that come in time, the
joystick's priority and stale commands; in the simulator, a blind controller driven at a
wall and a person through the filter never touches either."""

from __future__ import annotations

import math

import numpy as np
import pytest

from abcwc.control.safety import ComfortLimits, SafetyFilter
from abcwc.params import default_params
from abcwc.sim import SimBase
from abcwc.sim.world import world_from_dict
from abcwc.types import StatusFlags, Twist, make_frame

P = default_params()
DT = P.control_period


def _ramp(safety: SafetyFilter, command: Twist, seconds: float, **frame_fields) -> np.ndarray:
    out = []
    for k in range(round(seconds / DT)):
        t = k * DT
        twist = safety.apply(make_frame(t, **frame_fields), command, t)
        out.append((twist.v, twist.w))
    return np.array(out)


def test_speed_ramp_respects_speed_acceleration_and_jerk_limits_and_lands_on_target():
    limits = ComfortLimits()
    out = _ramp(SafetyFilter(limits=limits), Twist(3.0, 0.0), 5.0)
    v = out[:, 0]
    accel = np.diff(v) / DT
    jerk = np.diff(accel) / DT
    assert v.max() == pytest.approx(limits.max_speed)  # reached, never exceeded
    assert v.max() <= limits.max_speed + 1e-12
    assert np.abs(accel).max() <= limits.max_accel + 1e-9
    # the jerk limit holds but where the ramp lands on its target: there, one period's
    # rounding lets the acceleration's change exceed it, by at most a quarter
    over = np.flatnonzero(np.abs(jerk) > limits.max_jerk + 1e-9)
    landed = np.argmax(v >= limits.max_speed - 1e-12)
    assert set(over) <= {landed - 2, landed - 1}
    assert np.abs(jerk).max() <= 1.25 * limits.max_jerk
    # the jerk limit makes the ramp slower than a pure acceleration limit would:
    # at least v/a + a/j seconds (the trapezoid's two jerk phases)
    reached = np.argmax(v >= limits.max_speed - 1e-9) * DT
    least = limits.max_speed / limits.max_accel + limits.max_accel / limits.max_jerk
    assert reached >= least - 2 * DT


def test_turn_rate_and_lateral_acceleration_limits():
    limits = ComfortLimits()
    out = _ramp(SafetyFilter(limits=limits), Twist(1.0, 5.0), 6.0)
    assert np.abs(out[:, 1]).max() <= limits.max_turn_rate + 1e-12
    assert np.abs(out[:, 0] * out[:, 1]).max() <= limits.max_lateral_accel + 1e-9
    assert np.abs(np.diff(out[:, 1]) / DT).max() <= limits.max_angular_accel + 1e-9
    backwards = _ramp(SafetyFilter(limits=limits), Twist(-2.0, 0.0), 4.0)
    assert backwards[-1, 0] == pytest.approx(-limits.max_reverse_speed)


def test_braking_distance_follows_the_chair_model():
    check = SafetyFilter().check
    reaction = 1 / P.sonar.rate_hz + P.command_delay + P.motor_time_constant
    assert check.braking_distance(0.8) == pytest.approx(0.8 * reaction + 0.15)
    assert check.braking_distance(-0.8) == check.braking_distance(0.8)


def _moving_filter(speed: float) -> SafetyFilter:
    safety = SafetyFilter()
    _ramp(safety, Twist(speed, 0.0), 6.0)
    assert safety.v == pytest.approx(speed)
    return safety


def test_sonar_echo_inside_braking_distance_stops_forward_motion_at_once():
    front = P.length - P.axle_to_rear
    sonar_x = P.sonar.mount[0]
    safety = _moving_filter(0.8)
    limit = safety.check.braking_distance(0.8)
    near = limit - 0.05 + front - sonar_x  # sonar reading that puts the echo inside it
    far = limit + 0.05 + front - sonar_x
    t = 10.0
    assert safety.apply(make_frame(t, sonar=far), Twist(0.8, 0.0), t).v > 0.7
    stopped = safety.apply(make_frame(t, sonar=near), Twist(0.8, 0.0), t)
    assert stopped.v == 0.0
    assert safety.reason.startswith("obstacle") and "sonar_link" in safety.reason
    # turning on the spot is still allowed: it sweeps no strip ahead
    assert safety.apply(make_frame(t, sonar=near), Twist(0.0, 0.5), t).w > 0


def test_readings_beside_the_strip_or_missing_do_not_stop_and_too_close_does():
    safety = _moving_filter(0.5)
    t = 10.0
    beside = np.full(6, np.inf)
    beside[1] = 0.3  # IR at +60 degrees: the point lies 0.43 m to the left, outside the strip
    assert safety.apply(make_frame(t, ir=beside), Twist(0.5, 0.0), t).v > 0.4
    nothing = make_frame(t, sonar=math.nan, ir=np.full(6, np.nan))  # the real chair's IR
    assert safety.apply(nothing, Twist(0.5, 0.0), t).v > 0.4
    blind = make_frame(t, sonar=-math.inf)  # closer than the sonar can measure
    assert safety.apply(blind, Twist(0.5, 0.0), t).v == 0.0


def test_a_sonar_at_its_minimum_stops_even_a_creeping_chair():
    """The MaxSonar reads 0.30 m for anything nearer: the thing may be touching the
    chair's front. Taking the reading at face value (0.25 m ahead of the front) let a
    chair creeping at 0.1 m/s (braking distance under 0.25 m) drive its tray into a
    table top."""
    t = 10.0
    assert _moving_filter(0.1).check.braking_distance(0.1) < 0.25
    minimum = P.sonar.min_range
    assert _moving_filter(0.1).apply(make_frame(t, sonar=minimum), Twist(0.1, 0.0), t).v == 0.0
    # backing away is still allowed, and a reading beyond the minimum lets it creep on
    backing = SafetyFilter()
    for k in range(100):
        now = k * DT
        out = backing.apply(make_frame(now, sonar=minimum), Twist(-0.1, 0.0), now)
    assert out.v == pytest.approx(-0.1)
    assert _moving_filter(0.1).apply(make_frame(t, sonar=minimum + 0.5), Twist(0.1, 0.0),
                                     t).v > 0.0


def test_reversing_is_stopped_by_the_rear_ir_and_forward_is_not():
    safety = SafetyFilter()
    t = 0.0
    behind = np.full(6, np.inf)
    behind[3] = 0.25  # the ranger facing backwards
    assert safety.apply(make_frame(t, ir=behind), Twist(-0.3, 0.0), t).v == 0.0
    assert "ir_3_link" in safety.reason
    assert safety.apply(make_frame(t, ir=behind), Twist(0.3, 0.0), t).v > 0.0


def test_joystick_override_stops_and_holds_after_release():
    limits = ComfortLimits()
    safety = _moving_filter(0.5)
    t = 10.0
    held = safety.apply(make_frame(t, flags=StatusFlags.JOYSTICK_OVERRIDE), Twist(0.5, 0), t)
    assert held == Twist(0.0, 0.0) and safety.reason == "joystick override"
    released = t + DT
    assert safety.apply(make_frame(released), Twist(0.5, 0), released).v == 0.0
    later = released + limits.resume_delay - DT
    assert safety.apply(make_frame(later), Twist(0.5, 0), later).v == 0.0
    after = released + limits.resume_delay + DT
    resumed = safety.apply(make_frame(after), Twist(0.5, 0), after)
    assert 0.0 < resumed.v <= limits.max_jerk * DT * DT + 1e-12  # from rest, jerk-limited


def test_stale_command_stops():
    safety = _moving_filter(0.5)
    t = 10.0
    assert safety.apply(make_frame(t), Twist(0.5, 0), t - 0.4).v > 0
    assert safety.apply(make_frame(t), Twist(0.5, 0), t - 0.6) == Twist(0.0, 0.0)
    assert safety.reason.startswith("stale command")


def test_bad_input_is_refused_with_what_is_allowed():
    with pytest.raises(ValueError, match=r"takes a Twist \(m/s, rad/s\) or a PotCommand"):
        SafetyFilter().apply(make_frame(0.0), (200, 128))
    with pytest.raises(ValueError, match="max_speed must be a finite number >= 0"):
        ComfortLimits(max_speed=math.nan)
    with pytest.raises(ValueError, match="max_accel must be > 0"):
        ComfortLimits(max_accel=0.0)
    with pytest.raises(ValueError, match="finite"):
        Twist(math.inf, 0.0)


def _corridor(people: list | None = None, width: float = 3.0) -> object:
    """12 m long; the worn chair driven open-loop curves about 1 m to the left in it."""
    return world_from_dict({
        "name": "corridor",
        "walls": [[[0, 0], [12, 0], [12, width], [0, width], [0, 0]]],
        "places": {"start": [1.0, width / 2, 0.0]},
        "people": people or [],
    })


def test_blind_controller_through_the_filter_stops_short_of_a_wall():
    chair = SimBase(_corridor(width=6.0), seed=2, people=False)
    log = chair.run(lambda frame: Twist(1.0, 0.0), 25.0)  # the body's own filter
    front = chair.pose.x + P.length - P.axle_to_rear
    assert log.collisions[-1] == 0
    assert 0.0 < 12.0 - front < 0.6  # stopped, close to the wall and short of it
    assert chair.safety.interventions["obstacle"] > 0
    assert any(reason.startswith("obstacle") for reason in log.safety)


def test_person_stepping_in_front_of_a_blind_controller_is_not_touched():
    """A person crosses slowly 4 m ahead (stepping out beyond the braking distance: one
    stepping out nearer than that cannot be avoided by any filter, only by a planner
    that sees them coming)."""
    person = {"name": "crossing", "path": [[6.5, 2.9], [6.5, 0.1]], "speed": 0.3,
              "radius": 0.25, "loop": False}
    chair = SimBase(_corridor([person]), seed=3, errors="ideal")  # drives straight
    frame = chair.read()
    for _ in range(round(15 / DT)):
        chair.send(Twist(0.8, 0.0))  # a hand-written loop: send passes the filter too
        frame = chair.step()
    assert frame.truth.collisions == 0
    assert chair.safety.interventions["obstacle"] > 0
    assert chair.pose.x > 8.0  # and went on once the way was clear


def test_a_stop_brakes_along_the_arc_the_chair_is_on():
    """Stopping from (0.6 m/s, -0.3 rad/s): the turn rate falls with the speed, so the
    curvature stays -0.5 1/m and the chair sweeps the arc its planner checked. The turn
    ramp alone would have let w reach 0 in 0.2 s while v took 1 s, straightening the
    path towards whatever the arc was turning away from."""
    safety = SafetyFilter()
    cruise = _ramp(safety, Twist(0.6, -0.3), 4.0)
    assert cruise[-1] == pytest.approx([0.6, -0.3])
    out = []
    for k in range(round(3.0 / DT)):
        t = 4.0 + k * DT
        twist = safety.apply(make_frame(t), Twist(0.0, 0.0), t)
        out.append((twist.v, twist.w))
    out = np.array(out)
    moving = out[:, 0] > 0.02
    assert moving.sum() > 20                                   # braking takes time
    assert np.allclose(out[moving, 1] / out[moving, 0], -0.5)
    assert out[-1] == pytest.approx([0.0, 0.0])
    # turning on the spot still stops on the turn ramp
    spin = SafetyFilter()
    _ramp(spin, Twist(0.0, 0.6), 2.0)
    first = spin.apply(make_frame(2.0), Twist(0.0, 0.0), 2.0)
    assert first.w == pytest.approx(0.6 - spin.limits.max_angular_accel * DT)
