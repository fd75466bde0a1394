"""Shared helpers for the tests of the exercise checks (``tests/test_checks_*.py``)."""

from __future__ import annotations

from abcwc.checks import NOT_YET, PASS


def not_written(*args, **kwargs):
    """An exercise as the student notebook hands it out."""
    # YOUR CODE HERE
    raise NotImplementedError("not_written: replace these lines with your code")


def assert_pass(result, capsys) -> None:
    """The check passed and printed exactly one pass line."""
    out = capsys.readouterr().out
    assert result.passed, result.line
    assert out.startswith(PASS) and out.count("\n") == 1


def assert_not_yet(result, capsys, *fragments: str) -> None:
    """The check printed exactly one "not yet" line, containing every fragment."""
    out = capsys.readouterr().out
    assert not result.passed
    assert out.startswith(NOT_YET) and out.count("\n") == 1
    for fragment in fragments:
        assert fragment in out, out
