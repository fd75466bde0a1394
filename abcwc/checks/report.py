"""How an exercise check reports: one plain line, pass or not yet.

Every exercise in the course ends with a check. A check runs the student's function on
known inputs, compares the answers with the expected ones, and prints exactly one line::

    ✔ pass — pot mapping: all 7 thesis values match
    … not yet — pot mapping: joystick 398 gave 250, expected 253 (eqn 1)

A check never raises: an unwritten exercise (the stub still raises
``NotImplementedError``) and an exception from the student's code are both reported as
"not yet", so an untouched student notebook runs to the end. Later cells then call
:func:`use_or_fallback` to carry on with the library's own implementation.

Under nbgrader a "not yet" must fail the cell, since nbgrader scores a test cell by
whether it raised. nbgrader sets ``NBGRADER_EXECUTION`` (``autograde`` or ``validate``)
while it runs a submission, and the nbgrader form of a chapter (``abcwc course build``,
:mod:`abcwc.course_nbgrader`) ends each check cell with ``result.raise_for_nbgrader()``,
which then raises :class:`NotYet` with the check's line; anywhere else it does nothing,
so the notebook still runs to the end. The check's own line is shown first either way.

The line is plain and deterministic, because the course's CI (nbval) compares the
outputs stored in ``solutions/`` with a fresh run. In a notebook it is shown as rich
output as well: a pass in green, a "not yet" in bold orange (:meth:`CheckResult.html`),
with the same plain line as the text fallback; elsewhere (a script, a test) it is printed.

Writing a chapter check (``abcwc/checks/chNN.py``)::

    from abcwc.checks import checker, expect_equal

    @checker("pot mapping")
    def pot_mapping(pot_from_joystick) -> str:
        for joystick, expected in TABLE:
            expect_equal(pot_from_joystick(joystick), expected,
                         what=f"joystick {joystick}", ref="eqn 1")
        return f"all {len(TABLE)} thesis values match"
"""

from __future__ import annotations

import functools
import html
import inspect
import linecache
import math
import os
import re
import sys
import sysconfig
import types
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ParamSpec, TypeVar

import numpy as np

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
    "expect_no_slip",
    "expect_own",
    "format_value",
    "numbers",
    "use_or_fallback",
]

PASS = "✔ pass"
NOT_YET = "… not yet"
NBGRADER_EXECUTION = "NBGRADER_EXECUTION"
"""The environment variable nbgrader sets while it runs a submission."""
NOT_WRITTEN = "not written yet (the cell above still raises NotImplementedError)"
_MAX_MESSAGE = 300

P = ParamSpec("P")
F = TypeVar("F", bound=Callable[..., Any])
A = TypeVar("A")
T = TypeVar("T")


class NotYet(Exception):
    """Raised inside a check when the student's answer is wrong.

    The message says what was wrong, e.g. ``joystick 398 gave 250, expected 253 (eqn 1)``;
    :func:`check` turns it into a "not yet" line.
    """


@dataclass(frozen=True)
class CheckResult:
    """The outcome of one exercise check.

    ``bool(result)`` is ``result.passed``; ``str(result)`` is the line the check printed.
    """

    name: str
    passed: bool
    message: str

    @property
    def line(self) -> str:
        """The one line a check prints, e.g. ``✔ pass — odometry: 4 poses match``."""
        status = PASS if self.passed else NOT_YET
        return f"{status} — {self.name}: {self.message}"

    def html(self) -> str:
        """The line as HTML: a pass in green, a "not yet" in bold orange."""
        colour, weight = ("#1a7f37", "normal") if self.passed else ("#b35900", "bold")
        status = PASS if self.passed else NOT_YET
        return (f'<pre style="margin:0"><span style="color:{colour};font-weight:{weight}">'
                f"{html.escape(status)}</span> — {html.escape(self.name)}: "
                f"{html.escape(self.message)}</pre>")

    def raise_for_nbgrader(self) -> None:
        """Raise :class:`NotYet` with :attr:`line` if the check did not pass and nbgrader
        is running the notebook (``NBGRADER_EXECUTION`` set: ``autograde`` or
        ``validate``); elsewhere do nothing. nbgrader gives a test cell its points only
        when the cell raises nothing."""
        if not self.passed and os.environ.get(NBGRADER_EXECUTION):
            raise NotYet(self.line)

    def _repr_html_(self) -> str:
        return self.html()

    def __bool__(self) -> bool:
        return self.passed

    def __str__(self) -> str:
        return self.line

    def __repr__(self) -> str:
        return f"CheckResult({self.line!r})"


def _one_line(text: str) -> str:
    """Squash a message onto one line and cap its length."""
    text = " ".join(text.split())
    if len(text) > _MAX_MESSAGE:
        text = text[: _MAX_MESSAGE - 1] + "…"
    return text


def check(
    name: str, fn: Callable[P, str | None], /, *args: P.args, **kwargs: P.kwargs
) -> CheckResult:
    """Run the comparison ``fn(*args, **kwargs)``, print one line and return the result.

    ``fn`` passes by returning (a short message such as ``"all 7 values match"``, or
    ``None`` for ``"ok"``) and fails by raising :class:`NotYet` with what was wrong.
    A function of abcwc's own handed in (the library's, or a check's ``reference_*``)
    is refused before ``fn`` runs: ``that is abcwc's own <name>: write yours``.
    ``NotImplementedError`` means the exercise is not written yet; any other exception
    is reported as raised by the student's code, without a traceback.
    ``KeyboardInterrupt`` and ``SystemExit`` are not caught.

    Example::

        def compare(fn):
            expect_close(fn(1000), 0.9425, what="1000 ticks", atol=1e-4)
            return "1 value matches"

        result = check("wheel distance", compare, wheel_distance)
    """
    try:
        for handed in (*args, *kwargs.values()):  # a check judges the student's own code
            if callable(handed):
                expect_own(handed)
        message = fn(*args, **kwargs)
    except NotYet as exc:
        result = CheckResult(name, False, _one_line(str(exc)) or "wrong answer")
    except NotImplementedError as exc:
        result = CheckResult(name, False, _not_written(exc, args))
    except Exception as exc:  # noqa: BLE001 - student code may raise anything
        result = CheckResult(name, False, _raised(exc))
    else:
        result = CheckResult(name, True, _one_line(message) if message else "ok")
    _show(result)
    return result


def _show(result: CheckResult) -> None:
    """Show the result's line: as HTML with a plain-text fallback in a notebook's kernel,
    printed anywhere else."""
    shell = sys.modules.get("IPython") and sys.modules["IPython"].get_ipython()
    if shell is None or not hasattr(shell, "kernel"):
        print(result.line)
        return
    from IPython.display import display

    sys.stdout.flush()  # what the check printed before stays above its line
    display({"text/plain": result.line, "text/html": result.html()}, raw=True)


_LIBRARY_DIRS = tuple(
    str(Path(path).resolve()) + os.sep
    for path in {sysconfig.get_paths()[key] for key in ("stdlib", "platstdlib", "purelib",
                                                        "platlib")}
) + (str(Path(__file__).resolve().parents[1]) + os.sep,)
_CELL_FILE = re.compile(r"(ipykernel_\d+[/\\]\d+\.py|<ipython-input-[\d-]+.*>)$")


def _raised(exc: BaseException) -> str:
    """``your code raised <Type>: <message> (line <n>: <source>)``: the line is the last one
    in the traceback that is the student's own (not abcwc's, Python's or a package's)."""
    detail = _one_line(str(exc))
    if len(detail) > 160:
        detail = detail[:159] + "…"
    raised = type(exc).__name__ + (f": {detail}" if detail else "")
    where = _student_line(exc)
    return f"your code raised {raised}" + (f" ({where})" if where else "")


def _student_line(exc: BaseException) -> str:
    """Where in the student's code ``exc`` was raised: ``line 3: return x + 1`` in a
    notebook cell, ``line 3 of name.py: return x + 1`` in a file; "" when no frame of the
    traceback is the student's."""
    found = ""
    tb = exc.__traceback__
    while tb is not None:
        filename = tb.tb_frame.f_code.co_filename
        if not filename.startswith("<frozen") and not _is_library(filename):
            lineno = tb.tb_lineno
            source = " ".join(linecache.getline(filename, lineno).split())
            if len(source) > 80:
                source = source[:79] + "…"
            place = (f"line {lineno}" if _CELL_FILE.search(filename)
                     else f"line {lineno} of {Path(filename).name}")
            found = f"{place}: {source}" if source else place
        tb = tb.tb_next
    return found


def _is_library(filename: str) -> bool:
    """Whether ``filename`` is abcwc's, Python's own or an installed package's."""
    try:
        resolved = str(Path(filename).resolve())
    except (OSError, ValueError):
        return False
    return resolved.startswith(_LIBRARY_DIRS)


def _not_written(exc: NotImplementedError, args: tuple) -> str:
    """What to say when a stub raised: :data:`NOT_WRITTEN` when it is the exercise being
    checked, else which other exercise's stub it called (``course build`` writes each
    stub's message as ``"<function>: replace these lines with your code"``; nbgrader's own
    stub, ``raise NotImplementedError()``, says nothing, and the student's function it
    was raised in names it)."""
    message = str(exc)
    if message:
        stub, marker, _ = message.partition(": replace these lines")
        if not marker:
            return NOT_WRITTEN
    else:
        stub = _raised_in(exc)
    if not stub:
        return NOT_WRITTEN
    checked = {getattr(a, "__name__", None) for a in args if callable(a)} - {None}
    if not checked or stub in checked:
        return NOT_WRITTEN
    return (f"not written yet: this exercise calls {stub}(), an earlier exercise that still "
            f"raises NotImplementedError; write {stub} first")


def _raised_in(exc: BaseException) -> str:
    """The name of the function ``exc`` was raised in, if that is the student's own."""
    tb = exc.__traceback__
    while tb is not None and tb.tb_next is not None:
        tb = tb.tb_next
    if tb is None or _is_library(tb.tb_frame.f_code.co_filename):
        return ""
    return tb.tb_frame.f_code.co_name


def checker(name: str) -> Callable[[Callable[P, str | None]], Callable[P, CheckResult]]:
    """Decorator form of :func:`check`: the decorated function returns a CheckResult.

    Example::

        @checker("wheel distance")
        def wheel_distance(fn) -> str:
            expect_close(fn(1000), 0.9425, what="1000 ticks", atol=1e-4)
            return "1 value matches"

        result = wheel_distance(student_wheel_distance)   # prints one line
    """

    def decorate(fn: Callable[P, str | None]) -> Callable[P, CheckResult]:
        @functools.wraps(fn)
        def run(*args: P.args, **kwargs: P.kwargs) -> CheckResult:
            return check(name, fn, *args, **kwargs)

        return run

    return decorate


def use_or_fallback(student_fn: F, library_fn: F, result: CheckResult | bool) -> F:
    """Return ``student_fn`` if its check passed, else ``library_fn``; say which in one line.

    Example::

        distance = use_or_fallback(wheel_distance, abcwc.estimation.wheel_distance, result)
    """
    if bool(result):
        print(f"→ the rest of this notebook uses your {_name(student_fn)}")
        return student_fn
    print(f"→ the rest of this notebook uses abcwc's own {_name(library_fn)} instead")
    return library_fn


def _name(fn: Callable[..., Any]) -> str:
    """``qualname`` of a function, with its module when that is part of abcwc."""
    qualname = getattr(fn, "__qualname__", None) or getattr(fn, "__name__", repr(fn))
    module = getattr(fn, "__module__", None) or ""
    if module == "abcwc" or module.startswith("abcwc."):
        return f"{qualname} (from {module})"
    return qualname


# --- comparisons ----------------------------------------------------------------------


def format_value(value: Any) -> str:
    """Format a value for a check message: ints as ints, floats to 6 significant digits."""
    if isinstance(value, bool | np.bool_):
        return str(bool(value))
    if isinstance(value, int | np.integer):
        return str(int(value))
    if isinstance(value, float | np.floating):
        return f"{float(value):.6g}"
    if isinstance(value, np.ndarray) and value.ndim == 0:
        return format_value(value.item())
    text = repr(value)
    return text if len(text) <= 60 else text[:59] + "…"


def _suffix(ref: str | None) -> str:
    return f" ({ref})" if ref else ""


def _shape(array: np.ndarray) -> str:
    return "a single number" if array.ndim == 0 else f"an array of shape {array.shape}"


def expect(condition: bool, message: str) -> None:
    """Raise :class:`NotYet` with ``message`` unless ``condition`` holds."""
    if not condition:
        raise NotYet(message)


def expect_own(fn: Callable[..., Any], *library_fns: Callable[..., Any]) -> None:
    """Refuse a function of abcwc's own handed to a check in place of the student's:
    ``that is abcwc's own <name>: write yours``.

    The library's own is any function defined in abcwc, and ``library_fns``: the
    exercise's own implementations (the library's function and the check's
    ``reference_*``). ``fn`` is refused when

    - it is one of them, also inside ``functools.partial``, a bound method or a
      ``functools.wraps`` wrapper;
    - it reaches one of ``library_fns``: a lambda, closure or function of the student's
      whose code names it (through its globals, its closure cells, its defaults or a
      module attribute such as ``abcwc.slam.biggest_correction``), directly or through
      another function of the student's.

    A student's function that calls *other* abcwc functions (helpers the exercise allows,
    such as ``wrap_angle``) is the student's own and passes.
    """
    bare = _unwrapped(fn)
    if _is_own(bare, library_fns):
        raise NotYet(f"that is abcwc's own {_name(bare)}: write yours")
    own = {id(_unwrapped(other)) for other in library_fns}
    if not own:
        return
    for reached in _reached(fn):
        if id(reached) in own:
            raise NotYet(f"that calls abcwc's own {_name(reached)}: write yours")


def _is_own(fn: Any, library_fns: tuple[Callable[..., Any], ...]) -> bool:
    module = getattr(fn, "__module__", None) or ""
    return (any(fn is _unwrapped(other) for other in library_fns)
            or module == "abcwc" or module.startswith("abcwc."))


def _unwrapped(fn: Any) -> Any:
    """``fn`` without ``functools.partial``, bound-method and ``functools.wraps`` layers."""
    seen: set[int] = set()
    while id(fn) not in seen:
        seen.add(id(fn))
        if isinstance(fn, functools.partial):
            fn = fn.func
        elif isinstance(fn, types.MethodType):
            fn = fn.__func__
        elif getattr(fn, "__wrapped__", None) is not None:
            fn = fn.__wrapped__
        else:
            break
    return fn


def _reached(fn: Any) -> Iterator[Any]:
    """Every object the student's ``fn`` can call into: the layers it is wrapped in, the
    arguments a partial holds, and for each function of the student's (not abcwc's, not
    Python's or an installed package's) the objects its code names (globals and module
    attributes), its closure cells and its defaults, followed through the student's own
    functions."""
    pending, seen = [fn], set()
    while pending:
        item = pending.pop()
        if id(item) in seen:
            continue
        seen.add(id(item))
        yield item
        if isinstance(item, functools.partial):
            pending += [item.func, *item.args, *item.keywords.values()]
        elif isinstance(item, types.MethodType):
            pending.append(item.__func__)
        elif isinstance(item, types.FunctionType) and not _is_own(item, ()) \
                and not _is_library(item.__code__.co_filename):
            pending += _named_by(item)
        elif getattr(item, "__wrapped__", None) is not None:
            pending.append(item.__wrapped__)


def _named_by(fn: types.FunctionType) -> list[Any]:
    """The objects ``fn``'s code (nested functions and lambdas included) refers to."""
    names: set[str] = set()
    codes = [fn.__code__]
    while codes:
        code = codes.pop()
        names.update(code.co_names)
        codes += [const for const in code.co_consts if isinstance(const, types.CodeType)]
    found = [fn.__globals__[name] for name in names if name in fn.__globals__]
    found += [cell.cell_contents for cell in fn.__closure__ or ()
              if _has_contents(cell)]
    found += list(fn.__defaults__ or ()) + list((fn.__kwdefaults__ or {}).values())
    owners = [item for item in found if _is_abcwc_owner(item)]
    seen_owners: set[int] = set()
    while owners:  # abcwc.mapping.slam.run_slam, OccupancyGrid.integrate: attributes the
        owner = owners.pop()  # code names, of abcwc's modules and classes
        if id(owner) in seen_owners:
            continue
        seen_owners.add(id(owner))
        for name in names:
            value = inspect.getattr_static(owner, name, None)
            value = value.__func__ if isinstance(value, (staticmethod, classmethod)) else value
            if _is_abcwc_owner(value):
                owners.append(value)
            elif value is not None and not isinstance(value, types.ModuleType):
                found.append(value)
    return found


def _is_abcwc_owner(item: Any) -> bool:
    """Whether ``item`` is one of abcwc's modules or classes (whose attributes a student's
    code may name, as in ``abcwc.mapping.slam.run_slam`` or ``OccupancyGrid.integrate``)."""
    if isinstance(item, types.ModuleType):
        name = item.__name__
    elif isinstance(item, type):
        name = item.__module__ or ""
    else:
        return False
    return name == "abcwc" or name.startswith("abcwc.")


def _has_contents(cell: types.CellType) -> bool:
    try:
        cell.cell_contents  # noqa: B018 - an empty cell raises
    except ValueError:
        return False
    return True


def expect_equal(got: Any, expected: Any, *, what: str, ref: str | None = None) -> None:
    """Require ``got == expected`` exactly (numbers, strings, tuples, ...).

    Message on failure: ``<what> gave <got>, expected <expected> (<ref>)``.
    """
    try:
        if isinstance(got, np.ndarray) or isinstance(expected, np.ndarray):
            same = bool(np.array_equal(got, expected))
        else:
            same = bool(got == expected)
    except (ValueError, TypeError):  # e.g. a type that cannot be compared
        same = False
    if not same:
        raise NotYet(
            f"{what} gave {format_value(got)}, expected {format_value(expected)}{_suffix(ref)}"
        )


def expect_close(
    got: Any,
    expected: Any,
    *,
    what: str,
    rtol: float = 1e-6,
    atol: float = 0.0,
    ref: str | None = None,
    unit: str = "",
) -> None:
    """Require ``got`` to match ``expected`` within ``atol + rtol * |expected|``.

    Works for numbers and for arrays (element by element, shapes must match). Messages:

    - ``1000 ticks gave 0.95 m, expected 0.942478 m ± 0.001 m (circumference)``
    - ``pose[3] gave 1.2, expected 1 ± 1e-06 (eqn 5; 2 of 50 values differ)``
    - ``wheel speeds gave None, expected a number like 0.5``
    """
    unit_s = f" {unit}" if unit else ""
    expected_arr = np.asarray(expected, dtype=float)
    try:
        got_arr = np.asarray(got)
        if got_arr.dtype.kind not in "biuf":
            raise TypeError("not a number")
        got_arr = got_arr.astype(float)
    except (TypeError, ValueError):
        kind = "a number" if expected_arr.ndim == 0 else _shape(expected_arr)
        raise NotYet(
            f"{what} gave {format_value(got)}, expected {kind} like "
            f"{format_value(expected)}{_suffix(ref)}"
        ) from None
    if got_arr.shape != expected_arr.shape:
        raise NotYet(
            f"{what} gave {_shape(got_arr)}, expected {_shape(expected_arr)}{_suffix(ref)}"
        )
    ok = np.isclose(got_arr, expected_arr, rtol=rtol, atol=atol, equal_nan=True)
    if np.all(ok):
        return
    bad = np.argwhere(~ok)
    first = tuple(int(i) for i in bad[0])
    g, e = got_arr[first], expected_arr[first]
    tol = atol + rtol * abs(float(e)) if math.isfinite(float(e)) else 0.0
    where = what if not first else f"{what}[{', '.join(map(str, first))}]"
    plus_minus = f" ± {tol:.2g}{unit_s}" if tol > 0 else ""
    notes = [ref] if ref else []
    if ok.size > 1:
        notes.append(f"{len(bad)} of {ok.size} values differ")
    raise NotYet(
        f"{where} gave {format_value(g)}{unit_s}, expected {format_value(e)}{unit_s}"
        f"{plus_minus}{_suffix('; '.join(notes))}"
    )


def expect_no_slip(got: A, slips: Mapping[str, T], same: Callable[[A, T], bool], *,
                   prefix: str = "", suffix: str = "") -> None:
    """Name the usual slip the answer ``got`` is: ``slips`` maps what each slip is (its
    hint) to the wrong answer it gives, and the first, in order, for which
    ``same(got, wrong)`` holds raises :class:`NotYet` with ``prefix + hint + suffix``.
    Nothing happens when none matches: the check goes on to its own message.

    Example::

        slips = {"that is the radius, not the diameter": expected / 2,
                 "that is in mm: the check wants metres": expected * 1000}
        expect_no_slip(got, slips, lambda got, wrong: abs(got - wrong) <= 1e-6,
                       prefix=f"you gave {got:g}: ")
    """
    for hint, wrong in slips.items():
        if same(got, wrong):
            raise NotYet(prefix + hint + suffix)


def numbers(value: Any, count: int, what: str, wanted: str) -> tuple[float, ...]:
    """``value`` (an answer of ``count`` numbers, such as a pair of predictions) as floats;
    "not yet" with ``"<what> gave <value>; <wanted>"`` when it is not ``count`` numbers."""
    try:
        got = tuple(float(v) for v in value)
    except (TypeError, ValueError):
        got = ()
    if len(got) != count:
        raise NotYet(f"{what} gave {format_value(value)}; {wanted}")
    return got
