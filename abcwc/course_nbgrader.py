"""The course as an nbgrader course folder: ``course/nbgrader/``.

``abcwc course build`` writes it beside the student notebooks, from the same solution
notebooks (there is no second copy of a chapter to keep in step):

- ``source/NN_topic/NN_topic.ipynb``: each chapter as an nbgrader source notebook, one
  assignment per chapter, named like the chapter;
- ``nbgrader_config.py``: the course's nbgrader settings (:data:`CONFIG`);
- ``.gitignore``: the folders and the gradebook nbgrader writes there (a class's
  submissions and grades stay out of the repository).

An instructor runs nbgrader's own commands in ``course/nbgrader/`` (or in a copy of it)::

    nbgrader generate_assignment 01_joystick_to_wheels   # release/: what students get
    nbgrader autograde 01_joystick_to_wheels             # grades submitted/<student>/...
    nbgrader generate_feedback 01_joystick_to_wheels     # feedback/: one HTML page each

A chapter's source notebook has the student notebook's cells, with the solution's
source, no outputs, and nbgrader's cell metadata (``metadata.nbgrader``, schema 3):

- An **exercise** (a cell with a ``### BEGIN SOLUTION`` block) is a solution cell,
  ``grade_id`` ``exercise-<function>``; nbgrader itself replaces the block with its stub
  when it releases the chapter. nbgrader grades written answers by hand only, so an
  exercise in a markdown cell is also a manually graded cell worth 1 point.
- A **check** (a code cell with a top-level ``result = ...`` assignment, or
  ``result_<name> = ...`` or ``result<N> = ...``: the chapters call each check that way)
  is a locked, autograded test cell worth 1 point, ``grade_id`` ``check-<check>``. It
  ends with one more line, ``result.raise_for_nbgrader()``
  (:meth:`abcwc.checks.CheckResult.raise_for_nbgrader`): while nbgrader grades, a "not
  yet" raises, so the cell scores 0 and the feedback shows the check's line; for a student
  it does nothing and the notebook runs to the end as in ``course/``. A code cell with
  ``### BEGIN HIDDEN TESTS`` is a test cell too: nbgrader leaves the block out of the
  student's copy and puts it back to grade.
- Every other cell is **locked** (``grade_id`` ``cell-<cell id>``): read-only in the
  student's copy, and when a submission has changed one (a check cell included),
  ``nbgrader autograde`` puts back the original, found by its checksum, and logs
  ``Attribute 'checksum' for cell <grade_id> has changed!``.
"""

from __future__ import annotations

import ast
import re
from collections.abc import Sequence

import nbformat
from nbformat import NotebookNode

__all__ = ["CHECK_POINTS", "CONFIG", "DIRECTORY", "GITIGNORE", "CheckCellError",
           "nbgrader_notebook", "source_path"]

DIRECTORY = "nbgrader"
"""The nbgrader course folder, in ``course/``."""
CHECK_POINTS = 1
"""Points for each check (and each written answer, graded by hand)."""

CONFIG = '''\
"""nbgrader's settings for the abcwc course (written by `abcwc course build`)."""

c = get_config()  # noqa: F821 - nbgrader provides get_config in its config files

c.CourseDirectory.course_id = "abcwc"
# seconds a cell may run when nbgrader executes a submission (its default is 30); the
# longest cells of the worked chapters take about 75 s, more on a busy grading machine
c.Execute.timeout = 600
'''
"""``course/nbgrader/nbgrader_config.py``."""

GITIGNORE = """\
# what nbgrader writes here: the students' copies, their submissions and the grades
/release/
/submitted/
/autograded/
/feedback/
/gradebook.db
"""
"""``course/nbgrader/.gitignore``."""



class CheckCellError(ValueError):
    """A cell holds two checks; ``cell`` is its index in the student notebook."""

    def __init__(self, message: str, cell: int) -> None:
        super().__init__(message)
        self.cell = cell


_RESULT = re.compile(r"^result(\d*|_\w+)$")
_SLUG = re.compile(r"[^A-Za-z0-9_-]+")


def source_path(chapter: str) -> str:
    """Where chapter ``chapter`` (e.g. ``"01_joystick_to_wheels"``) goes, relative to
    ``course/``."""
    return f"{DIRECTORY}/source/{chapter}/{chapter}.ipynb"


def nbgrader_notebook(
    student: NotebookNode, sources: Sequence[str], exercises: Sequence[str | None]
) -> NotebookNode:
    """The nbgrader source notebook of a chapter.

    ``student`` is the chapter's student notebook; ``sources[i]`` is the solution's
    source of its cell ``i``, and ``exercises[i]`` the exercise's name (the function the
    solution block is in, or any name for a written answer), or ``None`` when cell ``i``
    is not an exercise.
    """
    if not len(student.cells) == len(sources) == len(exercises):
        raise ValueError(f"{len(student.cells)} cells, but {len(sources)} sources and "
                         f"{len(exercises)} exercise names")
    nb = nbformat.v4.new_notebook(metadata=dict(student.metadata))
    seen: set[str] = set()
    for index, (cell, source, exercise) in enumerate(zip(student.cells, sources, exercises)):
        new = nbformat.from_dict(dict(cell))
        new.source = source
        if new.cell_type == "code":
            new.outputs, new.execution_count = [], None
        if exercise is not None:
            manual = new.cell_type != "code"
            meta = _meta(_unique(f"exercise-{exercise}", seen), solution=True, grade=manual)
        elif new.cell_type == "code" and (result := _check_result(source, index)) is not None:
            variable, check = result
            new.source = source.rstrip("\n") + f"\n{variable}.raise_for_nbgrader()"
            meta = _meta(_unique(f"check-{check}", seen), grade=True, locked=True)
        elif new.cell_type == "code" and "### BEGIN HIDDEN TESTS" in source:
            meta = _meta(_unique(f"tests-{cell.id}", seen), grade=True, locked=True)
        else:
            meta = _meta(_unique(f"cell-{cell.id}", seen), locked=True)
        new.metadata = {**cell.metadata, "nbgrader": meta}
        nb.cells.append(new)
    return nb


def _meta(grade_id: str, *, solution: bool = False, grade: bool = False,
          locked: bool = False) -> dict[str, object]:
    """nbgrader's cell metadata (schema 3) for a cell of those kinds."""
    meta: dict[str, object] = {"grade": grade, "grade_id": grade_id, "locked": locked}
    if grade:
        meta["points"] = CHECK_POINTS
    meta.update({"schema_version": 3, "solution": solution, "task": False})
    return meta


def _unique(grade_id: str, seen: set[str]) -> str:
    """``grade_id`` with what nbgrader allows in a name, ``-2``, ``-3``... on repeats."""
    base = _SLUG.sub("_", grade_id)
    unique, n = base, 1
    while unique in seen:
        n += 1
        unique = f"{base}-{n}"
    seen.add(unique)
    return unique


def _check_result(source: str, index: int) -> tuple[str, str] | None:
    """``(variable, check)`` for a check cell's ``result... = <check>(...)``, else None.

    ``check`` is the called function's name (``pot_mapping`` for ``ch01.pot_mapping``).
    A cell with two such assignments is refused: each check cell holds one check.
    """
    python = "\n".join(re.sub(r"^([ \t]*)[%!].*$", r"\1pass", line)
                       for line in source.split("\n"))
    try:
        tree = ast.parse(python)
    except SyntaxError:
        return None
    found = [
        (statement.targets[0].id, _called_name(statement.value))
        for statement in tree.body
        if isinstance(statement, ast.Assign)
        and len(statement.targets) == 1
        and isinstance(statement.targets[0], ast.Name)
        and _RESULT.match(statement.targets[0].id)
        and isinstance(statement.value, ast.Call)
    ]
    if len(found) > 1:
        names = ", ".join(variable for variable, _ in found)
        raise CheckCellError(f"one check per cell: this cell assigns {names}; split it in "
                             "two", index)
    return found[0] if found else None


def _called_name(call: ast.Call) -> str:
    """``pot_mapping`` for ``ch01.pot_mapping(...)`` and ``pot_mapping(...)``; for
    ``check("wheel distance", ...)``, the check's name, ``wheel distance``."""
    func = call.func
    name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "check")
    if (name == "check" and call.args and isinstance(call.args[0], ast.Constant)
            and isinstance(call.args[0].value, str)):
        return call.args[0].value
    return name
