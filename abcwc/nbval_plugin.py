"""pytest configuration for running the course notebooks with nbval.

With ``--nbval`` (set in pyproject's addopts), every notebook that pytest collects runs
in a fresh kernel, one test per code cell:

- ``solutions/*.ipynb`` are stored with their outputs, and every cell's new output must
  match the stored one (after the sanitizers in ``tests/nbval_sanitize.cfg``), so a
  re-run proves the same numbers still print and every check still passes;
- ``course/*.ipynb`` are stored clean and run in lax mode: they only have to run to the
  end without an error (their checks print "not yet" and later cells fall back to the
  library's own functions).

Kernels start with a fixed environment: this checkout of ``abcwc`` first on the path,
matplotlib's inline backend (non-interactive; figures still become image/png outputs),
``PYTHONHASHSEED=0``, and no ``ABCWC_PORT``, so a test run never talks to a real chair.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent
LAX_DIRS = (ROOT / "course",)
SANITIZE_FILE = ROOT / "tests" / "nbval_sanitize.cfg"
KERNEL_ENV = {
    "MPLBACKEND": "module://matplotlib_inline.backend_inline",
    "PYTHONHASHSEED": "0",
    "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")])),
    "ABCWC_PORT": None,  # None: removed from the kernel's environment
}

# The example notebooks under tests/data are run by tests/test_course_build.py itself.
collect_ignore_glob = ["tests/data/*"]

try:
    from nbval.plugin import IPyNbFile, get_sanitize_patterns
except ImportError:  # nbval not installed: plain tests still run
    IPyNbFile = None


@contextlib.contextmanager
def kernel_environment() -> Iterator[None]:
    """Set :data:`KERNEL_ENV` in ``os.environ`` while a kernel starts, then restore it."""
    saved = {key: os.environ.get(key) for key in KERNEL_ENV}
    try:
        for key, value in KERNEL_ENV.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
        yield
    finally:
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


if IPyNbFile is not None:

    class CourseNotebook(IPyNbFile):
        """nbval's notebook collector, lax under ``course/``, with our kernel env and
        sanitizers (a ``--nbval-sanitize-with`` file given on the command line adds to
        them)."""

        def __init__(self, *args, **kwargs) -> None:
            super().__init__(*args, **kwargs)
            if any(self.path.resolve().is_relative_to(lax) for lax in LAX_DIRS):
                self.compare_outputs = False

        def setup(self) -> None:
            with kernel_environment():
                super().setup()

        def setup_sanitize_files(self) -> None:
            if SANITIZE_FILE.is_file():
                patterns = get_sanitize_patterns(SANITIZE_FILE.read_text(encoding="utf-8"))
                self.sanitize_patterns.update(patterns)
            super().setup_sanitize_files()

    @pytest.hookimpl(wrapper=True)
    def pytest_collect_file(file_path: Path, parent: pytest.Collector):
        """Swap nbval's own notebook collector for :class:`CourseNotebook`."""
        collected = yield
        return [
            CourseNotebook.from_parent(parent, path=file_path) if type(node) is IPyNbFile else node
            for node in collected or []
        ]
