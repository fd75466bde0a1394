"""pytest plugin for running the course notebooks with nbval.

Loaded with ``-p abcwc.nbval_plugin`` (pyproject's addopts). With ``--nbval`` (set
there too), every notebook that pytest collects runs
in a fresh kernel, one test per code cell:

- ``solutions/*.ipynb`` are stored with their outputs, and every cell's new output must
  match the stored one (after the sanitizers in ``tests/nbval_sanitize.cfg``), so a
  re-run proves the same numbers still print and every check still passes;
- ``course/*.ipynb`` are stored clean and run in lax mode: they only have to run to the
  end without an error (their checks print "not yet" and later cells fall back to the
  library's own functions).

Kernels start with a fixed environment: this checkout of ``abcwc`` first on the path,
matplotlib's inline backend (non-interactive; figures still become image/png outputs),
``PYTHONHASHSEED=0``, OpenBLAS's Haswell kernels on x86-64 (:data:`BLAS_KERNELS`),
and, for ``solutions/``, ``ABCWC_PORT=simavr``: a test run never talks to a real chair,
and every real-chair cell (:func:`abcwc.hardware_chair`) of a solution runs against our
firmware on a simulated Arduino. Where the AVR toolchain and simavr are missing (outside
CI), ``ABCWC_PORT`` is removed instead and those cells say they are skipped; under CI
(``CI=true``) it stays set, those cells print which tools are missing (a missing device
never crashes a cell), and the firmware's own tests fail. The student copies run as on a
student's laptop with no chair attached (:data:`STUDENT_KERNEL_ENV`): their real-chair
cells, the solutions' own code, say they are skipped, and the firmware is driven once
per chapter, not twice.

Under pytest-xdist's ``--dist loadscope`` (pyproject's addopts), a chapter's two
notebooks, its checks' tests and the tests that compute what it keeps on disk
(:data:`READ_WITH_CHAPTER`) are one scope (:class:`ChapterScopeScheduling`): one
worker runs them in collection order (tests, solution, student copy), so the later ones
read the seeded results the first kept on disk (:mod:`abcwc.experiments.disk_cache`)
instead of waiting on their lock while the other worker idles beside it. The scopes
named by the ini option ``slow_scopes`` go out first, in its order (xdist's own order
is by number of tests, which leaves a module of a few long tests to the end, with the
other worker idle beside it); the rest follow in xdist's order.
"""

from __future__ import annotations

import contextlib
import os
import platform
import re
from collections.abc import Iterator
from pathlib import Path

# OpenBLAS picks its kernels by the CPU, and the kernels round matrix products in
# different orders (SkylakeX's on an AVX-512 Intel, Haswell's on an AMD): SLAM's loop
# closures turn those last bits into other decisions (chapter 14's MIT CSAIL crop: 9 loops
# with Haswell's kernels, 11 with SkylakeX's). The tests and the notebooks' kernels take
# Haswell's (AVX2, every x86-64 since 2013) on every x86-64 host, so a stored output is the
# same whichever machine checks it. Set before NumPy loads OpenBLAS, in pytest's own
# process too (its workers inherit it).
BLAS_KERNELS = ({"OPENBLAS_CORETYPE": "Haswell"}
                if platform.machine().lower() in ("x86_64", "amd64") else {})
for _name, _value in BLAS_KERNELS.items():
    os.environ.setdefault(_name, _value)

import pytest  # noqa: E402

from abcwc.connect import SIMAVR_PORT  # noqa: E402
from abcwc.paths import checkout_root  # noqa: E402


def firmware_in_loop_available() -> bool:
    """Whether hardware cells can run on the firmware in simavr (always so under CI)."""
    from abcwc.hw.fil_base import missing_tools

    return os.environ.get("CI", "").lower() == "true" or not missing_tools()


LAX_DIR = "course"  # under the pytest rootdir
SANITIZE_FILE = "tests/nbval_sanitize.cfg"  # under the pytest rootdir
KERNEL_ENV = {
    "MPLBACKEND": "module://matplotlib_inline.backend_inline",
    "PYTHONHASHSEED": "0",
    "PYTHONPATH": os.pathsep.join(
        str(p) for p in (checkout_root(), os.environ.get("PYTHONPATH")) if p),
    # None: removed from the kernel's environment
    "ABCWC_PORT": SIMAVR_PORT if firmware_in_loop_available() else None,
    **BLAS_KERNELS,
}
STUDENT_KERNEL_ENV = {**KERNEL_ENV, "ABCWC_PORT": None}
"""The kernels of ``course/``'s student copies: as :data:`KERNEL_ENV`, with no chair."""

try:
    from nbval.plugin import IPyNbFile, get_sanitize_patterns
except ImportError:  # nbval not installed: plain tests still run
    IPyNbFile = None
try:
    from xdist.scheduler import LoadScopeScheduling
except ImportError:  # pytest-xdist not installed: one process runs everything
    LoadScopeScheduling = None
SOLUTIONS_DIR = "solutions"  # under the pytest rootdir


@contextlib.contextmanager
def kernel_environment(environment: dict[str, str | None]) -> Iterator[None]:
    """Set ``environment`` (:data:`KERNEL_ENV` or :data:`STUDENT_KERNEL_ENV`) in
    ``os.environ`` while a kernel starts, then restore it."""
    saved = {key: os.environ.get(key) for key in environment}
    try:
        _set_environ(environment)
        yield
    finally:
        _set_environ(saved)


def _set_environ(values: dict[str, str | None]) -> None:
    """Set each variable in ``os.environ``; a ``None`` value removes it."""
    for key, value in values.items():
        if value is None:
            os.environ.pop(key, None)
        else:
            os.environ[key] = value


if IPyNbFile is not None:

    class CourseNotebook(IPyNbFile):
        """nbval's notebook collector, lax and with no chair under ``course/``, with our
        kernel env and sanitizers (a ``--nbval-sanitize-with`` file given on the command
        line adds to them)."""

        def __init__(self, *args, **kwargs) -> None:
            super().__init__(*args, **kwargs)
            lax_dir = (self.config.rootpath / LAX_DIR).resolve()
            self.student_copy = self.path.resolve().is_relative_to(lax_dir)
            if self.student_copy:
                self.compare_outputs = False

        def setup(self) -> None:
            with kernel_environment(STUDENT_KERNEL_ENV if self.student_copy else KERNEL_ENV):
                super().setup()

        def setup_sanitize_files(self) -> None:
            sanitize_file = self.config.rootpath / SANITIZE_FILE
            if sanitize_file.is_file():
                patterns = get_sanitize_patterns(sanitize_file.read_text(encoding="utf-8"))
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


def chapter_scope(scope: str) -> str:
    """``scope`` (a test's node id up to its last ``::``), or ``chapter NN`` for chapter
    NN's notebooks (``solutions/NN_x.ipynb``, ``course/NN_x.ipynb``), its checks' tests
    (``tests/test_checks_chNN.py``) and the tests that read what it keeps on disk
    (:data:`READ_WITH_CHAPTER`)."""
    if scope in READ_WITH_CHAPTER:
        return f"chapter {READ_WITH_CHAPTER[scope]}"
    chapter = _CHAPTER_FILE.fullmatch(scope)
    if chapter is None:
        return scope
    return f"chapter {chapter['notebook'] or chapter['checks']}"


READ_WITH_CHAPTER = {"tests/test_follow.py": "17", "tests/test_slam_sim.py": "14",
                     "tests/test_marker_fixes.py": "10"}
"""Test files that compute what a chapter keeps on disk, so they share its scope: the
follower's tests drive chapter 17's lab trials
(:func:`abcwc.experiments.follow_trial.run_trial_in`), the simulated SLAM tests
replay chapter 14's floor survey (:func:`abcwc.checks.ch14.floor_survey`), and the
marker fixes' tests filter four of chapter 10's camera drives
(:func:`abcwc.experiments.nees.record_marker_drive`)."""


_CHAPTER_FILE = re.compile(rf"(?:{SOLUTIONS_DIR}|{LAX_DIR})/(?P<notebook>\d\d)_[^/]*\.ipynb"
                           r"|tests/test_checks_ch(?P<checks>\d\d)\.py")


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addini("slow_scopes", type="linelist", default=[],
                  help="xdist scopes (chapter_scope's names) handed out first, in order")


def put_first(workqueue: dict[str, object], slow: list[str]) -> None:
    """Move the first of ``slow`` still in ``workqueue`` (an OrderedDict, scope -> its
    tests) to its front; with none left, leave it as it is."""
    for scope in slow:
        if scope in workqueue:
            workqueue.move_to_end(scope, last=False)  # type: ignore[attr-defined]
            return


if LoadScopeScheduling is not None:

    class ChapterScopeScheduling(LoadScopeScheduling):
        """xdist's ``loadscope``, with a chapter's notebooks and tests one scope
        (:func:`chapter_scope`); its items keep their collection order (``tests/``,
        ``solutions/``, ``course/``: pyproject's testpaths)."""

        def __init__(self, config: pytest.Config, log: object = None) -> None:
            super().__init__(config, log)
            self.slow = [chapter_scope(scope) for scope in config.getini("slow_scopes")]

        def _split_scope(self, nodeid: str) -> str:
            return chapter_scope(super()._split_scope(nodeid))

        def _assign_work_unit(self, node: object) -> None:
            put_first(self.workqueue, self.slow)
            super()._assign_work_unit(node)

    @pytest.hookimpl(optionalhook=True)
    def pytest_xdist_make_scheduler(config: pytest.Config, log: object) -> object:
        """:class:`ChapterScopeScheduling` for ``--dist loadscope``; xdist's own otherwise."""
        if config.getvalue("dist") != "loadscope":
            return None
        return ChapterScopeScheduling(config, log)
