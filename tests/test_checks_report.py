"""Tests for the exercise-check reporting core (abcwc.checks)."""

from __future__ import annotations

import functools
import linecache

import numpy as np
import pytest

import abcwc.geometry
from abcwc import checks
from abcwc.checks import (
    CheckResult,
    NotYet,
    check,
    checker,
    expect,
    expect_close,
    expect_equal,
    expect_no_slip,
    expect_own,
    format_value,
    use_or_fallback,
)

TABLE = {110: 110, 398: 253}


def pot_mapping(fn) -> str:
    for joystick, expected in TABLE.items():
        expect_equal(fn(joystick), expected, what=f"joystick {joystick}", ref="eqn 1")
    return f"all {len(TABLE)} thesis values match"


def right(joystick: int) -> int:
    return TABLE[joystick]


def not_written(joystick: int) -> int:
    # YOUR CODE HERE
    raise NotImplementedError("not_written: replace these lines with your code")


def library_pot(joystick: int) -> int:
    return TABLE[joystick]


library_pot.__module__ = "abcwc.control.pots"  # as if it were the library's own


def test_pass_prints_one_line_and_returns_a_truthy_result(capsys):
    result = check("pot mapping", pot_mapping, right)
    assert capsys.readouterr().out == "✔ pass — pot mapping: all 2 thesis values match\n"
    assert result == CheckResult("pot mapping", True, "all 2 thesis values match")
    assert result and result.passed
    assert str(result) == result.line == "✔ pass — pot mapping: all 2 thesis values match"
    assert repr(result) == "CheckResult('✔ pass — pot mapping: all 2 thesis values match')"


def test_pass_without_a_message_says_ok(capsys):
    check("trivial", lambda: None)
    assert capsys.readouterr().out == "✔ pass — trivial: ok\n"


def test_wrong_answer_says_got_and_expected(capsys):
    result = check("pot mapping", pot_mapping, lambda joystick: 250)
    assert capsys.readouterr().out == (
        "… not yet — pot mapping: joystick 110 gave 250, expected 110 (eqn 1)\n"
    )
    assert not result
    assert result.message == "joystick 110 gave 250, expected 110 (eqn 1)"


def test_unwritten_exercise_is_not_yet_not_an_error(capsys):
    result = check("pot mapping", pot_mapping, not_written)
    assert capsys.readouterr().out == (
        "… not yet — pot mapping: not written yet "
        "(the cell above still raises NotImplementedError)\n"
    )
    assert not result


def test_exception_from_student_code_is_named_without_traceback(capsys):
    def broken(joystick: int) -> int:
        raise ValueError(f"fb pot {joystick + 302} outside 110..398\n(second line)")

    result = check("pot mapping", pot_mapping, broken)
    out = capsys.readouterr().out
    line = broken.__code__.co_firstlineno + 1
    assert out == (
        "… not yet — pot mapping: your code raised ValueError: "
        f"fb pot 412 outside 110..398 (second line) (line {line} of test_checks_report.py: "
        'raise ValueError(f"fb pot {joystick + 302} outside 110..398\\n(second line)"))\n'
    )
    assert "Traceback" not in out
    assert not result


def test_exception_names_the_line_of_the_students_code_that_raised(capsys):
    def plus_one(joystick: int) -> int:
        doubled = joystick * 2
        return undefined_name + doubled  # noqa: F821 - the student's slip

    check("pot mapping", pot_mapping, plus_one)
    line = plus_one.__code__.co_firstlineno + 2
    assert capsys.readouterr().out == (
        "… not yet — pot mapping: your code raised NameError: name 'undefined_name' is not "
        f"defined (line {line} of test_checks_report.py: return undefined_name + doubled "
        "# noqa: F821 - the student's slip)\n")


def test_the_line_is_the_students_even_when_a_library_raised_below_it(capsys):
    def stacked(joystick: int) -> int:
        return int(np.stack([np.zeros(2), np.zeros(3)]).sum())

    check("pot mapping", pot_mapping, stacked)
    out = capsys.readouterr().out
    line = stacked.__code__.co_firstlineno + 1
    assert out.startswith("… not yet — pot mapping: your code raised ValueError: ")
    assert out.endswith(f"(line {line} of test_checks_report.py: return "
                        "int(np.stack([np.zeros(2), np.zeros(3)]).sum()))\n")


def test_a_notebook_cell_is_named_by_its_line_alone(capsys):
    """ipykernel compiles each cell as a file ipykernel_<pid>/<hash>.py."""
    cell = "/tmp/ipykernel_4242/1234567.py"
    source = "def f(joystick):\n    y = 1\n    return x + y\n"
    linecache.cache[cell] = (len(source), None, source.splitlines(True), cell)
    namespace: dict = {}
    exec(compile(source, cell, "exec"), namespace)
    try:
        check("pot mapping", pot_mapping, namespace["f"])
    finally:
        del linecache.cache[cell]
    assert capsys.readouterr().out == (
        "… not yet — pot mapping: your code raised NameError: name 'x' is not defined "
        "(line 3: return x + y)\n")


def test_an_error_inside_abcwc_alone_names_no_line(capsys):
    check("angle", abcwc.geometry.wrap_angle, "a")  # raised in abcwc and numpy
    out = capsys.readouterr().out
    assert out.startswith("… not yet — angle: your code raised ") and "line" not in out


def test_exception_without_message_and_long_messages(capsys):
    check("a", lambda: {}["missing"])
    check("b", lambda: (_ for _ in ()).throw(RuntimeError()))
    check("c", lambda: expect(False, "x" * 1000))
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("… not yet — a: your code raised KeyError: 'missing' (line ")
    assert lines[1].startswith("… not yet — b: your code raised RuntimeError (line ")
    assert lines[2].endswith("x…") and len(lines[2]) < 400


def test_interrupts_are_not_swallowed():
    def interrupted():
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        check("stop", interrupted)


def test_checker_decorator_keeps_name_and_returns_result(capsys):
    @checker("pot mapping")
    def check_pot_mapping(fn) -> str:
        """Compare with the thesis table."""
        return pot_mapping(fn)

    assert check_pot_mapping.__name__ == "check_pot_mapping"
    assert check_pot_mapping.__doc__ == "Compare with the thesis table."
    assert check_pot_mapping(right).passed
    assert not check_pot_mapping(fn=not_written).passed
    assert capsys.readouterr().out.splitlines() == [
        "✔ pass — pot mapping: all 2 thesis values match",
        "… not yet — pot mapping: not written yet "
        "(the cell above still raises NotImplementedError)",
    ]


def test_use_or_fallback_picks_and_says_which(capsys):
    passed = CheckResult("pot mapping", True, "ok")
    failed = CheckResult("pot mapping", False, "not written yet")
    assert use_or_fallback(right, library_pot, passed) is right
    assert use_or_fallback(not_written, library_pot, failed) is library_pot
    assert use_or_fallback(not_written, np.hypot, False) is np.hypot
    assert capsys.readouterr().out.splitlines() == [
        "→ the rest of this notebook uses your right",
        "→ the rest of this notebook uses abcwc's own library_pot "
        "(from abcwc.control.pots) instead",
        "→ the rest of this notebook uses abcwc's own hypot instead",
    ]


# --- comparisons ----------------------------------------------------------------------


def message_of(fn, *args, **kwargs) -> str:
    with pytest.raises(NotYet) as info:
        fn(*args, **kwargs)
    return str(info.value)


def test_expect_close_scalars_with_tolerance_and_units():
    expect_close(0.94248, 0.942478, what="1000 ticks", atol=1e-4)
    expect_close(np.float32(2.5), 2.5, what="x")
    assert (
        message_of(
            expect_close,
            0.95,
            0.942478,
            what="1000 ticks",
            atol=1e-3,
            rtol=0,
            unit="m",
            ref="circumference",
        )
        == "1000 ticks gave 0.95 m, expected 0.942478 m ± 0.001 m (circumference)"
    )
    assert message_of(expect_close, 250, 253, what="joystick 398", rtol=0, ref="eqn 1") == (
        "joystick 398 gave 250, expected 253 (eqn 1)"
    )


def test_expect_close_arrays_names_first_mismatch_and_count():
    expected = np.linspace(0.0, 1.0, 5)
    expect_close(expected + 1e-9, expected, what="x", atol=1e-6)
    got = expected.copy()
    got[[2, 4]] += 0.1
    assert message_of(expect_close, got, expected, what="pose x", atol=0.01, rtol=0) == (
        "pose x[2] gave 0.6, expected 0.5 ± 0.01 (2 of 5 values differ)"
    )
    grid = np.zeros((2, 3))
    bad = grid.copy()
    bad[1, 2] = 1
    assert message_of(expect_close, bad, grid, what="grid", ref="eqn 3", atol=0.5) == (
        "grid[1, 2] gave 1, expected 0 ± 0.5 (eqn 3; 1 of 6 values differ)"
    )


def test_expect_close_rejects_wrong_types_and_shapes():
    assert message_of(expect_close, None, 0.5, what="v") == (
        "v gave None, expected a number like 0.5"
    )
    assert message_of(expect_close, "fast", 0.5, what="v") == (
        "v gave 'fast', expected a number like 0.5"
    )
    assert message_of(expect_close, [1.0, 2.0], 0.5, what="v") == (
        "v gave an array of shape (2,), expected a single number"
    )
    assert message_of(expect_close, [1.0], [1.0, 2.0], what="v", ref="table 6") == (
        "v gave an array of shape (1,), expected an array of shape (2,) (table 6)"
    )


def test_expect_close_nan_equals_nan_only():
    expect_close(float("nan"), float("nan"), what="x")
    assert message_of(expect_close, float("nan"), 1.0, what="x") == (
        "x gave nan, expected 1 ± 1e-06"
    )


def test_expect_equal_handles_arrays_and_tuples():
    expect_equal((1, 2), (1, 2), what="pots")
    expect_equal(np.arange(3), np.arange(3), what="ticks")
    expect_equal([0, 1, 2], np.arange(3), what="ticks")
    assert message_of(expect_equal, (1, 3), (1, 2), what="pots") == (
        "pots gave (1, 3), expected (1, 2)"
    )
    assert message_of(expect_equal, np.zeros(2), np.zeros(3), what="a").startswith("a gave array(")


SLIPS = {"that is the radius: the diameter is twice it": 0.5,
         "that is in millimetres: the check wants metres": 1000.0,
         "that is the radius again": 0.5}


def near(got: float, wrong: float) -> bool:
    return abs(got - wrong) <= 1e-9


def test_expect_no_slip_names_the_first_slip_the_answer_is():
    with pytest.raises(NotYet) as caught:
        expect_no_slip(0.5, SLIPS, near, prefix="0.5 m: ", suffix=" (1 m expected)")
    assert str(caught.value) == ("0.5 m: that is the radius: the diameter is twice it "
                                 "(1 m expected)")
    with pytest.raises(NotYet, match="^that is in millimetres: the check wants metres$"):
        expect_no_slip(1000.0, SLIPS, near)


def test_expect_no_slip_is_silent_for_an_answer_that_is_no_known_slip():
    expect_no_slip(0.7, SLIPS, near)  # the check goes on to its own message
    expect_no_slip(1.0, {}, near)


def test_expect_no_slip_hands_the_answer_and_each_wrong_answer_in_order():
    seen = []
    expect_no_slip("answer", {"a": 1, "b": 2}, lambda got, wrong: seen.append((got, wrong)))
    assert seen == [("answer", 1), ("answer", 2)]


def test_format_value_is_short_and_deterministic():
    assert format_value(np.int64(3)) == "3"
    assert format_value(np.float64(1 / 3)) == "0.333333"
    assert format_value(True) == "True"
    assert format_value(np.array(2.5)) == "2.5"
    assert format_value("x" * 100).endswith("…") and len(format_value("x" * 100)) == 60


def test_package_reexports_the_api():
    assert set(checks.__all__) <= set(dir(checks))
    assert checks.check is check and checks.PASS == "✔ pass" and checks.NOT_YET == "… not yet"


def test_a_stub_of_an_earlier_exercise_is_named(capsys):
    """Exercise 2 calls exercise 1, still a stub: the check names exercise 1 instead of
    saying that the cell above (exercise 2, which is written) is not."""

    def pot_from_joystick(joystick: int) -> int:
        raise NotImplementedError("pot_from_joystick: replace these lines with your code")

    def speed_command(joystick: int) -> int:  # exercise 2, written, calling exercise 1
        return pot_from_joystick(joystick) + 1

    result = check("speed", pot_mapping, speed_command)
    assert not result
    assert capsys.readouterr().out == (
        "… not yet — speed: not written yet: this exercise calls pot_from_joystick(), an "
        "earlier exercise that still raises NotImplementedError; write pot_from_joystick "
        "first\n")
    check("pot mapping", pot_mapping, pot_from_joystick)  # its own check: the cell above
    assert "the cell above still raises" in capsys.readouterr().out


def test_nbgraders_stub_of_an_earlier_exercise_is_named_by_its_function(capsys):
    """nbgrader's stub raises NotImplementedError() with no message: the function it is
    in names the exercise."""

    def pot_from_joystick(joystick: int) -> int:
        # YOUR CODE HERE
        raise NotImplementedError()

    def speed_command(joystick: int) -> int:
        return pot_from_joystick(joystick) + 1

    check("speed", pot_mapping, speed_command)
    assert "this exercise calls pot_from_joystick(), an earlier exercise" in (
        capsys.readouterr().out)
    check("pot mapping", pot_mapping, pot_from_joystick)
    assert capsys.readouterr().out == (
        "… not yet — pot mapping: not written yet (the cell above still raises "
        "NotImplementedError)\n")


# --- the library's own, wrapped -------------------------------------------------------


def reference_pot(joystick: int) -> int:
    return TABLE[joystick]


reference_pot.__module__ = "abcwc.checks.ch01"


def refusal(fn, *library_fns) -> str:
    with pytest.raises(NotYet) as info:
        expect_own(fn, *library_fns)
    return str(info.value)


def calls_library(joystick: int) -> int:
    return library_pot(joystick)


def calls_through_a_helper(joystick: int) -> int:
    return calls_library(joystick) + 0


@pytest.mark.parametrize("wrapped", [
    library_pot,
    functools.partial(library_pot),
    lambda joystick: library_pot(joystick),
    lambda joystick: abcwc.geometry.wrap_angle(joystick),
    calls_library,
    calls_through_a_helper,
    functools.partial(lambda fn, joystick: fn(joystick), library_pot),
    (lambda fn: lambda joystick: fn(joystick))(library_pot),   # a closure
    functools.update_wrapper(lambda joystick: 0, library_pot),  # functools.wraps
], ids=["bare", "partial", "lambda", "module attribute", "def", "through a helper",
        "partial argument", "closure", "wraps"])
def test_the_librarys_function_is_refused_however_it_is_wrapped(wrapped):
    own = (library_pot, abcwc.geometry.wrap_angle)
    message = refusal(wrapped, *own)
    assert message.startswith("that ") and message.endswith("write yours")
    assert "library_pot" in message or "wrap_angle" in message


class LibraryGrid:
    """Stands in for a class of abcwc's, such as OccupancyGrid."""

    def integrate(self, joystick: int) -> int:
        return TABLE[joystick]


LibraryGrid.__module__ = "abcwc.mapping.grid"


def test_a_method_of_abcwcs_named_through_its_class_is_refused():
    def mine(joystick: int) -> int:
        return LibraryGrid.integrate(LibraryGrid(), joystick)

    assert refusal(mine, LibraryGrid.integrate) == (
        "that calls abcwc's own LibraryGrid.integrate: write yours")
    expect_own(mine, library_pot)  # another exercise's function: this one is the student's


def test_a_function_defined_in_abcwc_is_refused_by_its_module_even_in_a_partial(capsys):
    assert refusal(functools.partial(abcwc.geometry.wrap_angle)) == (
        "that is abcwc's own wrap_angle (from abcwc.geometry): write yours")
    result = check("pot mapping", pot_mapping, functools.partial(reference_pot))
    assert not result and "that is abcwc's own reference_pot" in result.message
    capsys.readouterr()


def test_the_students_own_function_passes_though_it_calls_allowed_helpers(capsys):
    def own(joystick: int) -> int:  # uses a helper of abcwc's that the exercise allows
        return int(round(abcwc.geometry.wrap_angle(0.0))) + TABLE[joystick]

    expect_own(own, library_pot)
    expect_own(lambda joystick: own(joystick), library_pot)
    expect_own(functools.partial(own), library_pot)
    assert check("pot mapping", pot_mapping, lambda joystick: own(joystick))
    assert capsys.readouterr().out.startswith("✔ pass")


# --- pass and not yet, as a notebook shows them -----------------------------------------


def test_pass_and_not_yet_look_different_in_html_with_the_same_text():
    passed = CheckResult("pot mapping", True, "all 2 values match")
    failed = CheckResult("pot mapping", False, "joystick 398 gave 250 < 253")
    assert passed._repr_html_() == passed.html() == (
        '<pre style="margin:0"><span style="color:#1a7f37;font-weight:normal">✔ pass</span>'
        " — pot mapping: all 2 values match</pre>")
    assert failed.html() == (
        '<pre style="margin:0"><span style="color:#b35900;font-weight:bold">… not yet</span>'
        " — pot mapping: joystick 398 gave 250 &lt; 253</pre>")


def test_in_a_kernel_the_line_is_displayed_as_html_with_the_text_as_fallback(monkeypatch,
                                                                               capsys):
    IPython = pytest.importorskip("IPython")
    shown = []

    class Kernel:
        kernel = object()

    monkeypatch.setattr(IPython, "get_ipython", lambda: Kernel())
    monkeypatch.setattr("IPython.display.display",
                        lambda data, raw: shown.append((data, raw)))
    result = check("pot mapping", pot_mapping, right)
    assert capsys.readouterr().out == ""
    assert shown == [({"text/plain": result.line, "text/html": result.html()}, True)]
