"""Auto-checks for the course's exercises.

The reporting core lives in :mod:`abcwc.checks.report` and is re-exported here; each
chapter's checks live in ``abcwc.checks.chNN`` (``from abcwc.checks import ch01``).
"""

from abcwc.checks.report import (
    NOT_YET,
    PASS,
    CheckResult,
    NotYet,
    check,
    checker,
    expect,
    expect_close,
    expect_equal,
    format_value,
    use_or_fallback,
)

__all__ = [
    "NOT_YET",
    "PASS",
    "CheckResult",
    "NotYet",
    "check",
    "checker",
    "expect",
    "expect_close",
    "expect_equal",
    "format_value",
    "use_or_fallback",
]
