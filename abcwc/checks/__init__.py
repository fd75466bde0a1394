"""Auto-checks for the course's exercises.

The reporting core lives in :mod:`abcwc.checks.report` and is re-exported here; each
chapter's checks live in ``abcwc.checks.chNN`` (``from abcwc.checks import ch01``).
"""

# the public names are report's own __all__, listed once, there
from abcwc.checks.report import *  # noqa: F403
from abcwc.checks.report import __all__  # noqa: F401
