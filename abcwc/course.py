"""Build the student notebooks in ``course/`` from the solutions in ``solutions/``.

``solutions/NN_topic.ipynb`` is the source of truth for chapter NN. ``abcwc course build``
writes ``course/NN_topic.ipynb`` from it, using nbgrader's markers:

- In a code cell, each ``### BEGIN SOLUTION`` ... ``### END SOLUTION`` block becomes a
  stub at the marker's indentation::

      # YOUR CODE HERE
      raise NotImplementedError("pot_from_joystick: replace these lines with your code")

  The block must sit inside a function (``def``): student notebooks run to the end, so an
  exercise is a function that a later check calls. A block at column 0 is an error.
- In a markdown cell, the block becomes ``YOUR ANSWER HERE``.
- ``### BEGIN HIDDEN TESTS`` ... ``### END HIDDEN TESTS`` blocks are dropped, and so are
  cells tagged ``hidden`` (and code cells that held nothing but hidden tests).
- Outputs and execution counts are cleared; cell metadata keeps only tags and the
  editable/deletable/jupyter flags; notebook metadata is just the python3 kernelspec.
  The JSON is written the way nbformat writes it, so a rebuild is byte-identical.

``course/README.md`` is the front page (:mod:`abcwc.course_front_page`).
``course/nbgrader/`` is the same chapters as an nbgrader course folder, for grading a
class (:mod:`abcwc.course_nbgrader`): each chapter's source notebook there keeps the
solution's blocks, for nbgrader to stub, and marks exercises, checks and read-only
cells in nbgrader's cell metadata. Other files in ``course/`` and chapters in
``course/nbgrader/source/`` with no solution counterpart are removed. ``--check``
writes nothing and fails (exit code 1) when ``course/`` differs from what a build
would write.
"""

from __future__ import annotations

import ast
import hashlib
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import nbformat
from nbformat import NotebookNode

from abcwc import course_nbgrader
from abcwc.course_front_page import front_page
from abcwc.paths import NotACheckoutError

__all__ = [
    "Change",
    "CourseBuildError",
    "apply",
    "build",
    "nbgrader_source",
    "plan",
    "run",
    "student_notebook",
    "student_source",
]

SOLUTION = "SOLUTION"
HIDDEN_TESTS = "HIDDEN TESTS"
HIDDEN_TAG = "hidden"
NOTEBOOK_NAME = re.compile(r"^\d\d_[A-Za-z0-9_-]+\.ipynb$")
FRONT_PAGE = "README.md"
"""The course's front page in ``course/``: every chapter, its goals and thesis sections."""
KERNELSPEC = {"display_name": "Python 3 (ipykernel)", "language": "python", "name": "python3"}
KEPT_CELL_METADATA = ("tags", "editable", "deletable", "jupyter")

_MARKER = re.compile(
    r"^(?P<indent>[ \t]*)### (?P<edge>BEGIN|END) (?P<kind>SOLUTION|HIDDEN TESTS)[ \t]*$"
)
_LOOSE_MARKER = re.compile(r"\b(BEGIN|END)[ _]*(SOLUTION|HIDDEN[ _]*TESTS?)\b", re.IGNORECASE)
_DEF = re.compile(r"^[ \t]*(?:async[ \t]+)?def[ \t]+(?P<name>\w+)")


class CourseBuildError(ValueError):
    """A solution notebook cannot be turned into a student notebook.

    The message names the notebook, the cell (its 0-based index in the notebook) and the
    line in that cell (1-based), and says what to change.
    """

    def __init__(
        self, notebook: str, message: str, cell: int | None = None, line: int | None = None
    ) -> None:
        where = notebook
        if cell is not None:
            where += f", cell index {cell}"
        if line is not None:
            where += f", line {line}"
        super().__init__(f"{where}: {message}")
        self.notebook = notebook
        self.detail = message
        self.cell = cell
        self.line = line


@dataclass(frozen=True)
class Change:
    """One file in ``course/`` that a build would write or remove.

    ``reason`` is ``"missing"``, ``"out of date"`` or ``"no solution"``; ``text`` is the
    new content, or ``None`` when the file is to be removed.
    """

    path: Path
    reason: str
    text: str | None


# --- cell sources ---------------------------------------------------------------------


def student_source(source: str, cell_type: str, *, notebook: str = "", cell: int = 0) -> str:
    """Return a cell's student version: solution blocks stubbed, hidden tests dropped.

    ``notebook`` (e.g. ``"01_joystick"``) and ``cell`` (0-based index) are used in error
    messages and to name exercises that are not inside a function.
    """
    lines = source.split("\n")
    out: list[str] = []
    open_kind: str | None = None
    open_line = 0
    for number, line in enumerate(lines, start=1):
        match = _MARKER.match(line)
        if match is None:
            loose = _LOOSE_MARKER.search(line)
            if loose and line.lstrip().startswith("#"):
                raise CourseBuildError(
                    notebook,
                    f"malformed marker {line.strip()!r}; write it exactly as "
                    f"'### {loose.group(1).upper()} SOLUTION' or "
                    f"'### {loose.group(1).upper()} HIDDEN TESTS' on a line of its own",
                    cell,
                    number,
                )
            if open_kind is None:
                out.append(line)
            continue
        edge, kind, indent = match["edge"], match["kind"], match["indent"]
        if edge == "BEGIN":
            if open_kind is not None:
                raise CourseBuildError(
                    notebook,
                    f"'### BEGIN {kind}' inside the '### BEGIN {open_kind}' block opened at "
                    f"line {open_line}; close that block first with '### END {open_kind}'",
                    cell,
                    number,
                )
            open_kind, open_line = kind, number
            if kind == SOLUTION:
                out.extend(_stub(lines, number, indent, cell_type, notebook, cell))
        else:
            if open_kind is None:
                raise CourseBuildError(
                    notebook,
                    f"'### END {kind}' without a '### BEGIN {kind}' before it",
                    cell,
                    number,
                )
            if kind != open_kind:
                raise CourseBuildError(
                    notebook,
                    f"'### END {kind}' closes the '### BEGIN {open_kind}' block opened at "
                    f"line {open_line}; expected '### END {open_kind}'",
                    cell,
                    number,
                )
            open_kind = None
    if open_kind is not None:
        raise CourseBuildError(
            notebook,
            f"'### BEGIN {open_kind}' is never closed; add '### END {open_kind}' after the block",
            cell,
            open_line,
        )
    return "\n".join(out)


def _stub(
    lines: list[str], number: int, indent: str, cell_type: str, notebook: str, cell: int
) -> list[str]:
    """The lines replacing the solution block whose BEGIN marker is on line ``number``."""
    if cell_type != "code":
        return [f"{indent}YOUR ANSWER HERE"]
    if not indent:
        raise CourseBuildError(
            notebook,
            "solution block at column 0: put exercise code inside a function (def ...) that "
            "the check calls, so the student notebook still runs to the end",
            cell,
            number,
        )
    name = _enclosing_function(lines, number) or f"exercise in {notebook}, cell index {cell}"
    return [
        f"{indent}# YOUR CODE HERE",
        f'{indent}raise NotImplementedError("{name}: replace these lines with your code")',
    ]


def _enclosing_function(lines: list[str], number: int) -> str | None:
    """Qualified name of the innermost ``def`` around 1-based line ``number``, if any."""
    # IPython magics and shell escapes are not Python; blank them out for the parser.
    python = [re.sub(r"^([ \t]*)[%!].*$", r"\1pass", line) for line in lines]
    try:
        tree = ast.parse("\n".join(python))
    except SyntaxError:
        tree = None
    if tree is not None:
        found = _innermost_def(tree, number, prefix="")
        if found is not None:
            return found
    return _enclosing_def_by_indent(lines, number)


def _innermost_def(node: ast.AST, number: int, prefix: str) -> str | None:
    """Walk classes and functions whose span contains line ``number``."""
    found = None
    for child in ast.iter_child_nodes(node):
        if not isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            continue
        end = child.end_lineno or child.lineno
        if not child.lineno <= number <= end:
            continue
        name = prefix + child.name
        inner = _innermost_def(child, number, name + ".")
        if inner is not None:
            found = inner
        elif not isinstance(child, ast.ClassDef):
            found = name
    return found


def _enclosing_def_by_indent(lines: list[str], number: int) -> str | None:
    """Fallback for cells that do not parse: scan upwards for a less-indented ``def``."""
    level = _indent_width(lines[number - 1])
    for line in reversed(lines[: number - 1]):
        stripped = line.strip()
        if not stripped or stripped.startswith("#"):
            continue
        width = _indent_width(line)
        if width < level:
            match = _DEF.match(line)
            if match:
                return match["name"]
            level = width
            if level == 0:
                return None
    return None


def _indent_width(line: str) -> int:
    return len(line) - len(line.lstrip(" \t"))


# --- notebooks ------------------------------------------------------------------------


def _kept_cells(solution: NotebookNode, name: str) -> list[tuple[int, str, str]]:
    """The solution's cells a student notebook keeps: (index, source, student source)."""
    kept = []
    for index, cell in enumerate(solution.cells):
        tags = cell.get("metadata", {}).get("tags", [])
        if HIDDEN_TAG in tags:
            continue
        source = cell.source if isinstance(cell.source, str) else "".join(cell.source)
        new_source = student_source(source, cell.cell_type, notebook=name, cell=index)
        if (
            cell.cell_type == "code"
            and not new_source.strip()
            and f"### BEGIN {HIDDEN_TESTS}" in source
        ):
            continue  # the cell held nothing but hidden tests
        kept.append((index, source, new_source))
    return kept


def student_notebook(solution: NotebookNode, name: str) -> NotebookNode:
    """Build the student version of a solution notebook (``name`` like ``"01_joystick"``)."""
    return _student_notebook(solution, name, _kept_cells(solution, name))


def _student_notebook(solution: NotebookNode, name: str,
                      kept: list[tuple[int, str, str]]) -> NotebookNode:
    """The student notebook of the solution's ``kept`` cells (:func:`_kept_cells`)."""
    nb = nbformat.v4.new_notebook()
    nb.metadata = {"kernelspec": dict(KERNELSPEC), "language_info": {"name": "python"}}
    seen_ids: set[str] = set()
    for index, _, new_source in kept:
        cell = solution.cells[index]
        cell_id = _cell_id(cell, name, index, seen_ids)
        metadata = _student_metadata(cell.get("metadata", {}))
        if cell.cell_type == "code":
            new = nbformat.v4.new_code_cell(new_source, id=cell_id, metadata=metadata)
        elif cell.cell_type == "markdown":
            new = nbformat.v4.new_markdown_cell(new_source, id=cell_id, metadata=metadata)
            if "attachments" in cell:
                new.attachments = cell.attachments
        else:
            new = nbformat.v4.new_raw_cell(new_source, id=cell_id, metadata=metadata)
        nb.cells.append(new)
    return nb


def nbgrader_source(solution: NotebookNode, name: str) -> NotebookNode:
    """The chapter's nbgrader source notebook (:mod:`abcwc.course_nbgrader`): the student
    notebook's cells with the solution's source and nbgrader's metadata."""
    kept = _kept_cells(solution, name)
    exercises = [_exercise(source, solution.cells[index].cell_type, index)
                 for index, source, _ in kept]
    try:
        return course_nbgrader.nbgrader_notebook(
            _student_notebook(solution, name, kept), [source for _, source, _ in kept],
            exercises)
    except course_nbgrader.CheckCellError as exc:
        raise CourseBuildError(name, str(exc), kept[exc.cell][0]) from None


def _exercise(source: str, cell_type: str, cell: int) -> str | None:
    """The exercise's name: the function around the cell's first solution block (a
    written answer: ``answer_<cell index>``); ``None`` when the cell has no block."""
    lines = source.split("\n")
    for number, line in enumerate(lines, start=1):
        match = _MARKER.match(line)
        if match and match["edge"] == "BEGIN" and match["kind"] == SOLUTION:
            if cell_type != "code":
                return f"answer_{cell}"
            return _enclosing_function(lines, number) or f"cell_{cell}"
    return None


def _student_metadata(metadata: dict[str, Any]) -> dict[str, Any]:
    kept = {key: metadata[key] for key in KEPT_CELL_METADATA if key in metadata}
    tags = [tag for tag in kept.pop("tags", []) if tag != HIDDEN_TAG]
    if tags:
        kept["tags"] = tags
    return kept


def _cell_id(cell: NotebookNode, name: str, index: int, seen: set[str]) -> str:
    """Keep the solution's cell id; make a stable one if it has none (nbformat < 4.5)."""
    cell_id = cell.get("id") or hashlib.sha1(f"{name}:{index}".encode()).hexdigest()[:8]
    while cell_id in seen:
        cell_id = hashlib.sha1(f"{cell_id}:{index}".encode()).hexdigest()[:8]
    seen.add(cell_id)
    return cell_id


def render(
    solution_path: Path, solution: NotebookNode | None = None, *, nbgrader: bool = False
) -> str:
    """The exact text of the student notebook built from ``solution_path`` (``solution``:
    the notebook already read from it); with ``nbgrader``, of its nbgrader source."""
    if solution is None:
        solution = nbformat.read(solution_path, as_version=4)
    form = nbgrader_source if nbgrader else student_notebook
    try:
        nb = form(solution, solution_path.stem)
    except CourseBuildError as exc:  # name the file rather than the chapter
        raise CourseBuildError(str(solution_path), exc.detail, exc.cell, exc.line) from None
    text = nbformat.writes(nb, version=4)
    return text if text.endswith("\n") else text + "\n"


# --- directories ----------------------------------------------------------------------


def plan(
    solutions_dir: str | Path = "solutions", course_dir: str | Path = "course"
) -> list[Change]:
    """Everything a build would change in ``course_dir``; an empty list if up to date.

    Every solution notebook is converted before anything is reported, so a bad marker
    anywhere raises :class:`CourseBuildError` and a build writes nothing.
    """
    source, target_dir = Path(solutions_dir), Path(course_dir)
    if not source.is_dir():
        raise CourseBuildError(
            str(source),
            "no such directory of solution notebooks",
        )
    wanted: dict[str, str] = {}
    chapters: dict[str, NotebookNode] = {}
    for path in sorted(source.glob("*.ipynb")):
        if not NOTEBOOK_NAME.match(path.name):
            raise CourseBuildError(
                str(path), "chapter notebooks are named NN_topic.ipynb, e.g. 01_joystick.ipynb"
            )
        chapters[path.name] = nbformat.read(path, as_version=4)
        wanted[path.name] = render(path, chapters[path.name])
    wanted[FRONT_PAGE] = front_page(chapters)
    for name, solution in chapters.items():
        wanted[course_nbgrader.source_path(Path(name).stem)] = render(
            source / name, solution, nbgrader=True)
    wanted[f"{course_nbgrader.DIRECTORY}/nbgrader_config.py"] = course_nbgrader.CONFIG
    wanted[f"{course_nbgrader.DIRECTORY}/.gitignore"] = course_nbgrader.GITIGNORE

    changes = []
    for name, text in wanted.items():
        target = target_dir / name
        if not target.is_file():
            changes.append(Change(target, "missing", text))
        elif target.read_bytes() != text.encode("utf-8"):
            changes.append(Change(target, "out of date", text))
    if target_dir.is_dir():
        sources = target_dir / course_nbgrader.DIRECTORY / "source"
        for path in sorted([*target_dir.iterdir(), *sources.glob("*/*.ipynb")]):
            name = path.relative_to(target_dir).as_posix()
            if path.is_file() and not path.name.startswith(".") and name not in wanted:
                changes.append(Change(path, "no solution", None))
    return changes


def apply(changes: Sequence[Change]) -> None:
    """Write or remove the files listed in ``changes``."""
    for change in changes:
        if change.text is None:
            change.path.unlink()
            folder = change.path.parent  # a chapter's folder in course/nbgrader/source?
            if folder.parent.parts[-2:] == (course_nbgrader.DIRECTORY, "source") and not any(
                    folder.iterdir()):
                folder.rmdir()
        else:
            change.path.parent.mkdir(parents=True, exist_ok=True)
            with open(change.path, "w", encoding="utf-8", newline="\n") as f:
                f.write(change.text)


def build(
    solutions_dir: str | Path = "solutions", course_dir: str | Path = "course", check: bool = False
) -> list[Path]:
    """Regenerate ``course_dir`` from ``solutions_dir``; return the paths changed.

    With ``check=True`` nothing is written and the returned paths are the stale ones
    (out of date, missing, or with no solution).
    """
    changes = plan(solutions_dir, course_dir)
    if not check:
        apply(changes)
    return [change.path for change in changes]


def run(
    solutions_dir: str | Path | None = None,
    course_dir: str | Path | None = None,
    check: bool = False,
) -> int:
    """``abcwc course build [--check]``: build (or check) and print what changed; the exit
    code (1: ``check`` found ``course_dir`` out of date).

    The folders default to ``solutions/`` and ``course/`` in the current directory, the
    root of a checkout of the repository.

    Raises:
        NotACheckoutError: no folder given and no ``solutions/`` here.
        CourseBuildError: a folder or a notebook is wrong; nothing was written.
    """
    if solutions_dir is None:
        solutions_dir = Path("solutions")
        if not solutions_dir.is_dir():
            raise NotACheckoutError(
                f"no solutions/ in {Path.cwd()}: `abcwc course build` works on a checkout of "
                "the abcwc repository; run it from the repository's root or pass --solutions DIR"
            )
    course_dir = Path("course") if course_dir is None else Path(course_dir)
    changes = plan(solutions_dir, course_dir)
    total = len(list(Path(solutions_dir).glob("*.ipynb")))
    if not changes:
        print(f"{course_dir}/ is up to date ({total} notebook{'' if total == 1 else 's'})")
        return 0
    if check:
        for change in changes:
            print(f"stale: {change.path} ({change.reason})")
        print(f"{course_dir}/ is out of date: run `abcwc course build`")
        return 1
    apply(changes)
    for change in changes:
        verb = "removed" if change.text is None else "wrote"
        print(f"{verb} {change.path} ({change.reason})")
    return 0
