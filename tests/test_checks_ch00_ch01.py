"""The exercise checks of chapters 00 (tour) and 01 (joystick to wheels).

Each check must pass a correct answer written here, independently of the library, and
report "not yet", without raising, for wrong answers, for an unwritten exercise and for
the library's own function handed in.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from abcwc.checks import NOT_YET, PASS, ch00, ch01
from abcwc.control import direction_pot_command, joystick_to_pot_byte
from abcwc.types import PotCommand


def not_written(*args, **kwargs):
    # YOUR CODE HERE
    raise NotImplementedError("not_written: replace these lines with your code")


def run(check, fn, capsys):
    """Run a check; return its result and the one line it printed."""
    result = check(fn)
    out = capsys.readouterr().out
    assert out.count("\n") == 1, out
    return result, out.strip()


def assert_pass(check, fn, capsys) -> str:
    result, line = run(check, fn, capsys)
    assert result.passed, line
    assert line.startswith(PASS)
    return line


def assert_not_yet(check, fn, capsys, *fragments: str) -> str:
    result, line = run(check, fn, capsys)
    assert not result.passed, line
    assert line.startswith(NOT_YET)
    for fragment in fragments:
        assert fragment in line, line
    return line


# --- chapter 00 -----------------------------------------------------------------------


def test_counts_per_wheel_turn(capsys):
    line = assert_pass(ch00.counts_per_wheel_turn, lambda dw, de, n: n * dw / de, capsys)
    assert "1258.06" in line
    assert_not_yet(ch00.counts_per_wheel_turn, ch00.reference_counts_per_wheel_turn, capsys,
                   "abcwc's own")
    assert_not_yet(ch00.counts_per_wheel_turn, lambda dw, de, n: n * de / dw, capsys,
                   "upside down")
    assert_not_yet(ch00.counts_per_wheel_turn, lambda dw, de, n: 1258, capsys, "expected 1258.06")
    assert_not_yet(ch00.counts_per_wheel_turn, not_written, capsys, "not written yet")


def test_encoder_counts_to_distance(capsys):
    assert_not_yet(ch00.encoder_counts_to_distance, ch00.reference_encoder_counts_to_distance,
                   capsys, "abcwc's own")
    assert_pass(ch00.encoder_counts_to_distance,
                lambda n, per_turn, d: np.asarray(n) * math.pi * d / per_turn, capsys)
    assert_not_yet(ch00.encoder_counts_to_distance,
                   lambda n, per_turn, d: n / per_turn * d, capsys, "one wheel turn")
    assert_not_yet(ch00.encoder_counts_to_distance,
                   lambda n, per_turn, d: abs(n) / per_turn * math.pi * d, capsys, "-629")
    assert_not_yet(ch00.encoder_counts_to_distance, not_written, capsys, "not written yet")


def test_distance_ahead(capsys):
    def distance_ahead(frame, params):  # nothing seen reads as the sonar's maximum range
        seen = frame.sonar < params.sonar.max_range
        return frame.sonar + params.sonar.mount[0] if seen else float("inf")

    assert_pass(ch00.distance_ahead, distance_ahead, capsys)
    assert_not_yet(ch00.distance_ahead, ch00.reference_distance_ahead, capsys, "abcwc's own")
    assert_not_yet(ch00.distance_ahead, lambda frame, params: frame.sonar, capsys,
                   "2.605", "3.005")
    assert_not_yet(ch00.distance_ahead,
                   lambda frame, params: frame.sonar + params.sonar.mount[0], capsys,
                   "expected inf")
    assert_not_yet(ch00.distance_ahead, not_written, capsys, "not written yet")


# --- chapter 01 -----------------------------------------------------------------------


def test_pot_mapping(capsys):
    line = assert_pass(ch01.pot_mapping, lambda v: int((v - 100) * 0.85), capsys)
    assert "289" in line
    assert_not_yet(ch01.pot_mapping, joystick_to_pot_byte, capsys, "abcwc's own")
    assert_not_yet(ch01.pot_mapping, lambda v: round((v - 100) * 0.85), capsys,
                   "254 gave 131", "truncates")
    assert_not_yet(ch01.pot_mapping, lambda v: (v - 100) * 0.85, capsys, "int(")
    assert_not_yet(ch01.pot_mapping, lambda v: int((v - 100) * 0.85) if v < 300 else 0,
                   capsys, "joystick 398")
    assert_not_yet(ch01.pot_mapping, not_written, capsys, "not written yet")


def test_table_6(capsys):
    def table_6(direction):  # eqn 1 of the joystick's ends: 398 -> 253, 110 -> 8
        fb, lr = {"forward": (253, 128), "reverse": (8, 128), "left": (128, 8),
                  "right": (128, 253), "stop": (128, 128)}[direction]
        return PotCommand(fb, lr)

    assert_pass(ch01.table_6, table_6, capsys)
    assert_not_yet(ch01.table_6, direction_pot_command, capsys, "abcwc's own")

    def as_printed(direction):
        table = {"left": PotCommand(128, 253), "right": PotCommand(128, 8)}
        return table.get(direction) or table_6(direction)

    assert_not_yet(ch01.table_6, as_printed, capsys, "left/right as printed")
    assert_not_yet(ch01.table_6, lambda d: (253, 128), capsys, "PotCommand")
    assert_not_yet(ch01.table_6, lambda d: PotCommand(128, 128), capsys, "forward")
    assert_not_yet(ch01.table_6, not_written, capsys, "not written yet")


def test_square_sequence(capsys):
    def square(t):  # A.3: 5 s forward and 2 s left three times, then 2.5 s forward
        if not 0.0 <= t < 23.5:
            return PotCommand(128, 128)
        return PotCommand(168, 128) if t % 7.0 < 5.0 else PotCommand(128, 64)

    line = assert_pass(ch01.square_sequence, square, capsys)
    assert "fb 168" in line and "lr 64" in line
    assert_not_yet(ch01.square_sequence, ch01.reference_square_sequence, capsys, "abcwc's own")

    def other_bytes(t):  # a faster square is fine, within what a seated person can take
        phase = ch01.square_phase(t)
        return {"forward": PotCommand(200, 128), "left": PotCommand(128, 70)}.get(
            phase, PotCommand(128, 128))

    assert_pass(ch01.square_sequence, other_bytes, capsys)

    def full_deflection(t):  # table 6's full forward and full left: 6 km/h, 88 deg/s
        phase = ch01.square_phase(t)
        return {"forward": PotCommand(253, 128), "left": PotCommand(128, 8)}.get(
            phase, PotCommand(128, 128))

    assert_not_yet(ch01.square_sequence, full_deflection, capsys, "1.67 m/s", "fb 203")

    def full_turn(t):
        return PotCommand(128, 8) if ch01.square_phase(t) == "left" else square(t)

    assert_not_yet(ch01.square_sequence, full_turn, capsys, "rad/s", "lr 64")

    def turns_right(t):
        if ch01.square_phase(t) == "left":
            return PotCommand(128, 192)
        return square(t)

    assert_not_yet(ch01.square_sequence, turns_right, capsys, "lr below 126")
    assert_not_yet(ch01.square_sequence, lambda t: square(t - 0.5),
                   capsys, "t = 0.01 s")
    assert_not_yet(ch01.square_sequence, lambda t: square(t % 23.5),
                   capsys, "should stop")
    assert_not_yet(ch01.square_sequence, lambda t: (168, 128), capsys, "PotCommand")
    assert_not_yet(ch01.square_sequence, not_written, capsys, "not written yet")


@pytest.mark.parametrize(
    ("t", "phase"),
    [(0.0, "forward"), (4.99, "forward"), (5.0, "left"), (6.99, "left"), (7.0, "forward"),
     (21.0, "forward"), (23.49, "forward"), (23.5, "stop"), (-1.0, "stop"), (99.0, "stop")],
)
def test_square_phase(t, phase):
    assert ch01.square_phase(t) == phase


# --- chapter 01, exercise 4: predicting the clockwise square ---------------------------------

MEASURED_CW = 18.1  # deg: worn minus ideal at the end of the clockwise square, as measured
CLOCKWISE_CHECK = functools.partial(ch01.clockwise_prediction_check, measured=MEASURED_CW)


def test_the_clockwise_budget_worked_by_hand():
    """Side 0.515 m/s x 5 s = 2.57 m; 1 % tyre difference over a 453 mm wheel base: 3.25 deg
    a straight. A 90.7 deg corner on a 3 % wider wheel base with 0.5 % larger tyres on average:
    90.7 (1 - 1.005 / 1.03) = 2.20 deg short. Clockwise: 3.5 x 3.25 + 3 x 2.20 = 18.0 deg."""
    budget = ch01.clockwise_budget()
    assert budget["straight"] == pytest.approx(3.25, abs=0.01)
    assert budget["corner_short"] == pytest.approx(2.20, abs=0.01)
    assert budget["clockwise"] == pytest.approx(18.0, abs=0.05)


def test_clockwise_prediction_passes_an_independent_budget(capsys):
    straight = math.degrees(0.515 * 5 * 0.01 / (0.44 * 1.03))
    corner = 90.7 * (1 - 1.005 / 1.03)
    assert_pass(CLOCKWISE_CHECK, lambda: 3.5 * straight + 3 * corner, capsys)


@pytest.mark.parametrize(("predicted", "fragment"), [
    (lambda: 4.8, "counter-clockwise"),       # the worked example's number, sign kept
    (lambda: -18.0, "the sign"),
    (lambda: 11.4, "only the straights"),
    (lambda: 6.6, "only the corners"),
    (lambda: 45.0, "Budget it"),
    (lambda: float("nan"), "one number"),
    (not_written, "NotImplementedError"),
    (ch01.reference_square_sequence, "abcwc's own"),
])
def test_clockwise_prediction_refuses(predicted, fragment, capsys):
    assert_not_yet(CLOCKWISE_CHECK, predicted, capsys, fragment)


# --- chapter 01, exercise 4: measuring one corner --------------------------------------------


def student_corners():
    """Written independently: turn with lr 64 for 2 s on each chair, stop, and read the
    true heading change after 2 s of rest."""
    import abcwc

    turned = []
    for errors in ("worn", "ideal"):
        chair = abcwc.connect(world="lab", seed=3, errors=errors, start="centre")
        start = chair.pose.theta
        chair.drive(PotCommand(128, 64), 2.0)
        chair.drive(PotCommand(128, 128), 2.0)
        turned.append(math.degrees(math.remainder(chair.pose.theta - start, 2 * math.pi)))
    return tuple(turned)


def test_corners_check_passes_an_independent_measurement(capsys):
    assert_pass(ch01.corners_check, student_corners, capsys)


@pytest.mark.parametrize(("measured", "fragment"), [
    (lambda: (1.545, 1.583), "radians"),
    (lambda: (90.7, 90.7), "errors=\"worn\""),          # the ideal chair twice
    (lambda: (93.4, 90.7), "wider wheel base"),          # x E_b instead of / E_b
    (lambda: (44.0, 45.3), "lasts 2 s"),                  # a 1 s corner
    (lambda: (75.0, 76.6), "come to rest"),              # read before the lag had run out
    (lambda: (88.5, 86.0), "omega x 2 s"),
    (lambda: 88.5, "two angles"),
    (not_written, "NotImplementedError"),
    (ch01.reference_square_sequence, "abcwc's own"),
])
def test_corners_check_refuses(measured, fragment, capsys):
    assert_not_yet(ch01.corners_check, measured, capsys, fragment)


# --- chapter 00, exercise 4: measuring the counts per wheel turn --------------------------------


@pytest.fixture(scope="module")
def straight_log():
    import abcwc

    chair = abcwc.connect(world="lab", seed=4)
    return chair.drive(PotCommand(170, 128), seconds=5.0)


def test_counts_measurement_passes_an_independent_measurement(straight_log, capsys):
    """Counts per metre of true path, times one wheel turn's 0.6126 m."""
    def counts_per_turn(log):
        counts = (log.ticks[-1, 0] + log.ticks[-1, 1]) / 2
        return counts / log.distance_travelled() * math.pi * 0.195
    check = functools.partial(ch00.counts_measurement_check, log=straight_log)
    line = assert_pass(check, counts_per_turn, capsys)
    assert "1242" in line or "1243" in line       # the worn chair's encoder wheels, 1.2 % big


@pytest.mark.parametrize(("measured", "fragment"), [
    (lambda log: 400 * 0.195 / 0.062, "nominal"),
    (lambda log: float(np.mean(log.ticks[-1])) / log.distance_travelled(), "counts per metre"),
    (lambda log: log.distance_travelled() / (math.pi * 0.195) / float(np.mean(log.ticks[-1])),
     "upside down"),
    (lambda log: 1300.0, "wheel turns gives"),
    (lambda log: float("nan"), "one number"),
    (not_written, "NotImplementedError"),
    (ch00.reference_counts_per_wheel_turn, "abcwc's own"),
])
def test_counts_measurement_refuses(straight_log, measured, fragment, capsys):
    check = functools.partial(ch00.counts_measurement_check, log=straight_log)
    assert_not_yet(check, measured, capsys, fragment)


# --- chapter 00, exercise 5: predicting where the chair comes to rest ---------------------------

REST = functools.partial(ch00.rest_prediction_check, measured=0.96)


def test_rest_prediction_passes_a_reasoned_guess(capsys):
    assert_pass(REST, lambda: 1.2 - 0.066 - 0.2, capsys)


@pytest.mark.parametrize(("predicted", "fragment"), [
    (lambda: 1.2, "cannot stop on the 1.2 m line"),
    (lambda: 1.5, "cannot stop"),
    (lambda: 0.45, "past the line"),
    (lambda: -1.0, "one distance"),
    (not_written, "NotImplementedError"),
    (ch00.reference_distance_ahead, "abcwc's own"),
])
def test_rest_prediction_refuses(predicted, fragment, capsys):
    assert_not_yet(REST, predicted, capsys, fragment)
