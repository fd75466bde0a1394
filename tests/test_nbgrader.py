"""course/nbgrader/ as nbgrader reads it: its cells, and a chapter graded by nbgrader itself.

The truth the grading is held to is the worked chapter's stored outputs: each check
printed one line there (``✔ pass — <check>: ...``), so a chapter has as many points as
lines, and a student who wrote nothing sees each check's "not yet" line for those
checks.
"""

from __future__ import annotations

import html
import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import nbformat
import pytest

from abcwc.checks import NOT_YET, PASS, CheckResult, NotYet
from abcwc.checks.report import NOT_WRITTEN
from abcwc.course import CourseBuildError, build, nbgrader_source
from abcwc.nbval_plugin import KERNEL_ENV

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = Path(__file__).resolve().parent / "data" / "notebooks"
CHAPTER = "15_costmaps"
"""The quickest chapter with exercises and checks: about 5 s a run (4 exercises, 4 checks)."""
CHECK_LINE = re.compile(rf"^(?:{PASS}|{NOT_YET}) — (?P<name>[^:]+): ", re.M)


def stored_check_names(cell: nbformat.NotebookNode) -> list[str]:
    """The checks whose lines a solution cell's stored outputs show."""
    text = "".join(out.get("text", "") + out.get("data", {}).get("text/plain", "")
                   for out in cell.get("outputs", []))
    return CHECK_LINE.findall(text)


def nbgrader_meta(cell: nbformat.NotebookNode) -> dict:
    return cell.metadata["nbgrader"]


# --- the form of the chapters ---------------------------------------------------------


@pytest.mark.parametrize("name", sorted(p.stem for p in (ROOT / "solutions").glob("*.ipynb")))
def test_every_check_is_a_locked_graded_cell_and_every_exercise_a_solution_cell(name):
    solution = nbformat.read(ROOT / "solutions" / f"{name}.ipynb", as_version=4)
    source = nbformat.read(ROOT / "course" / "nbgrader" / "source" / name / f"{name}.ipynb",
                           as_version=4)
    by_id = {cell.id: cell for cell in solution.cells}
    graded, exercises, locked = [], [], []
    for cell in source.cells:
        meta = nbgrader_meta(cell)
        original = by_id[cell.id]
        if meta["grade"]:
            graded.append(cell.id)
            assert meta["locked"] and meta["points"] == 1
            assert cell.source.endswith(".raise_for_nbgrader()")
        elif meta["solution"]:
            exercises.append(cell.id)
            assert not meta["locked"] and cell.source == original.source
        else:
            locked.append(cell.id)
            assert meta["locked"] and cell.source == original.source
        assert cell.get("outputs", []) == []
    assert graded == [c.id for c in solution.cells if stored_check_names(c)]
    assert exercises == [c.id for c in solution.cells if "### BEGIN SOLUTION" in c.source]
    assert len(graded) + len(exercises) + len(locked) == len(solution.cells)
    grade_ids = [nbgrader_meta(cell)["grade_id"] for cell in source.cells]
    assert len(set(grade_ids)) == len(grade_ids)


def test_example_chapter_cells_kinds_and_names():
    """A written answer is graded by hand; a check by ``check(...)`` is named by it."""
    solution = nbformat.read(EXAMPLES / "solutions" / "00_example.ipynb", as_version=4)
    source = nbgrader_source(solution, "00_example")
    kinds = {cell.id: (nbgrader_meta(cell)["grade_id"], nbgrader_meta(cell)["grade"],
                       nbgrader_meta(cell)["solution"], nbgrader_meta(cell)["locked"])
             for cell in source.cells}
    assert kinds == {
        "intro": ("cell-intro", False, False, True),
        "imports": ("cell-imports", False, False, True),
        "exercise-text": ("exercise-answer_2", True, True, False),
        "exercise": ("exercise-wheel_distance", False, True, False),
        "check": ("check-wheel_distance", True, False, True),
        "fallback": ("cell-fallback", False, False, True),
        "plot": ("cell-plot", False, False, True),
    }  # the cell of hidden tests alone and the cell tagged hidden are left out, as in course/
    check = next(cell for cell in source.cells if cell.id == "check")
    assert "### BEGIN HIDDEN TESTS" in check.source  # nbgrader hides them, and grades with them


def test_two_checks_in_one_cell_are_refused(tmp_path):
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell("x = 1"),
                nbformat.v4.new_code_cell("result1 = check_a(f)\nresult2 = check_b(g)")]
    (tmp_path / "solutions").mkdir()
    nbformat.write(nb, tmp_path / "solutions" / "01_two.ipynb")
    with pytest.raises(CourseBuildError, match=r"01_two.ipynb, cell index 1: one check per "
                                               r"cell: this cell assigns result1, result2"):
        build(tmp_path / "solutions", tmp_path / "course")
    assert not (tmp_path / "course").exists()


def test_a_not_yet_raises_only_while_nbgrader_runs_the_notebook(monkeypatch):
    passed = CheckResult("pot mapping", True, "all 3 match")
    not_yet = CheckResult("pot mapping", False, "joystick 398 gave 250, expected 253")
    monkeypatch.delenv("NBGRADER_EXECUTION", raising=False)
    not_yet.raise_for_nbgrader()  # a student's own run goes on
    for execution in ("autograde", "validate"):
        monkeypatch.setenv("NBGRADER_EXECUTION", execution)
        passed.raise_for_nbgrader()
        with pytest.raises(NotYet) as info:
            not_yet.raise_for_nbgrader()
        assert str(info.value) == not_yet.line


# --- nbgrader grades a chapter --------------------------------------------------------


def nbgrader(course: Path, env: dict[str, str], *args: str) -> str:
    """Run ``nbgrader ARGS`` in the course folder; its log (stderr)."""
    done = subprocess.run([sys.executable, "-m", "nbgrader", *args], cwd=course, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    return done.stderr


@pytest.fixture
def isolated_env(tmp_path: Path) -> dict[str, str]:
    """nbgrader and its kernels with a home of their own (no user or Jupyter config), the
    notebook tests' kernel settings, and no chair: a grader's machine has none, so the
    chapter's real-chair cell says it is skipped."""
    home = tmp_path / "home"
    env = {key: value for key, value in os.environ.items()
           if not key.startswith(("JUPYTER", "NBGRADER", "IPYTHON", "ABCWC_"))}
    env.update({key: value for key, value in KERNEL_ENV.items()
                if value is not None and key != "ABCWC_PORT"})
    env.update(HOME=str(home), JUPYTER_CONFIG_DIR=str(home / ".jupyter"),
               JUPYTER_DATA_DIR=str(home / "data"), JUPYTER_RUNTIME_DIR=str(home / "runtime"),
               IPYTHONDIR=str(home / ".ipython"),
               PATH=os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")]))
    return env


def submit(course: Path, student: str, nb: dict) -> None:
    folder = course / "submitted" / student / CHAPTER
    folder.mkdir(parents=True)
    (folder / f"{CHAPTER}.ipynb").write_text(json.dumps(nb))


def test_nbgrader_grades_solution_full_untouched_zero_and_catches_an_edited_check(
        tmp_path, isolated_env):
    course = tmp_path / "course"
    (course / "source").mkdir(parents=True)
    shutil.copy(ROOT / "course" / "nbgrader" / "nbgrader_config.py", course)
    shutil.copytree(ROOT / "course" / "nbgrader" / "source" / CHAPTER,
                    course / "source" / CHAPTER)
    worked = nbformat.read(ROOT / "solutions" / f"{CHAPTER}.ipynb", as_version=4)
    checks = [name for cell in worked.cells for name in stored_check_names(cell)]
    assert len(checks) == 4

    nbgrader(course, isolated_env, "generate_assignment", CHAPTER)
    released = json.loads((course / "release" / CHAPTER / f"{CHAPTER}.ipynb").read_text())
    assert "### BEGIN SOLUTION" not in json.dumps(released)
    submit(course, "solution",
           json.loads((course / "source" / CHAPTER / f"{CHAPTER}.ipynb").read_text()))
    submit(course, "untouched", released)
    # the edit that would pass every check: drop the line that fails a "not yet"
    tampered = json.loads(json.dumps(released))
    for cell in tampered["cells"]:
        if cell["metadata"]["nbgrader"]["grade"]:
            lines = "".join(cell["source"]).split("\n")
            cell["source"] = "\n".join([*lines[:-1], "# the check's last line, taken out"])
    submit(course, "tampered", tampered)

    log = nbgrader(course, isolated_env, "autograde", CHAPTER)
    nbgrader(course, isolated_env, "generate_feedback", CHAPTER)

    from nbgrader.api import Gradebook

    with Gradebook(f"sqlite:///{course / 'gradebook.db'}") as gradebook:
        scores = {student: (gradebook.find_submission(CHAPTER, student).score,
                            gradebook.find_submission(CHAPTER, student).max_score)
                  for student in ("solution", "untouched", "tampered")}
    assert scores == {"solution": (4.0, 4.0), "untouched": (0.0, 4.0), "tampered": (0.0, 4.0)}

    # the edited check cells: found by their checksums, put back, and graded as written
    grade_ids = [cell["metadata"]["nbgrader"]["grade_id"] for cell in released["cells"]
                 if cell["metadata"]["nbgrader"]["grade"]]
    changed = re.findall(r"Attribute 'checksum' for cell (\S+) has changed!", log)
    assert changed == grade_ids

    # the untouched chapter ran to the end: every cell ran, and only the checks raised
    graded = json.loads(
        (course / "autograded" / "untouched" / CHAPTER / f"{CHAPTER}.ipynb").read_text())
    code = [cell for cell in graded["cells"] if cell["cell_type"] == "code"]
    assert all(cell["execution_count"] is not None for cell in code)
    raised = [(cell["metadata"]["nbgrader"]["grade_id"], out["ename"]) for cell in code
              for out in cell["outputs"] if out["output_type"] == "error"]
    assert raised == [(grade_id, "NotYet") for grade_id in grade_ids]

    feedback = (course / "feedback" / "untouched" / CHAPTER / f"{CHAPTER}.html").read_text()
    for name in checks:
        assert html.escape(f"{name}: {NOT_WRITTEN}") in feedback
