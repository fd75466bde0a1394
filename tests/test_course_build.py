"""Tests for ``abcwc course build`` and for how the notebooks run under nbval."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import nbformat
import pytest
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

from abcwc import cli
from abcwc.course import CourseBuildError, build, plan, student_notebook, student_source

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = Path(__file__).resolve().parent / "data" / "notebooks"


def main(args: list[str]) -> int:
    """``abcwc course build ARGS``; its exit status."""
    return cli.main(["course", "build", *args])


def code(source: str) -> str:
    """Student version of a code cell written with textwrap.dedent."""
    return student_source(textwrap.dedent(source).strip("\n"), "code", notebook="01_x", cell=2)


def write_solution(directory: Path, name: str, *cells: nbformat.NotebookNode) -> Path:
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / name
    nbformat.write(new_notebook(cells=list(cells)), path)
    return path


# --- cell sources ---------------------------------------------------------------------


def test_solution_in_function_becomes_named_stub_at_marker_indentation():
    got = code(
        """
        def pot_from_joystick(adc: int) -> int:
            \"\"\"Map a joystick reading to a pot step.\"\"\"
            scale = 2
            ### BEGIN SOLUTION
            return adc * scale
            ### END SOLUTION
        """
    )
    assert got == textwrap.dedent(
        """\
        def pot_from_joystick(adc: int) -> int:
            \"\"\"Map a joystick reading to a pot step.\"\"\"
            scale = 2
            # YOUR CODE HERE
            raise NotImplementedError("pot_from_joystick: replace these lines with your code")"""
    )


def test_nested_block_keeps_its_deeper_indentation_and_method_qualname():
    got = code(
        """
        class Controller:
            def step(
                self,
                v: float,
            ) -> float:
                if v > 0:
                    ### BEGIN SOLUTION
                    return v
                    ### END SOLUTION
                return 0.0
        """
    )
    assert "            # YOUR CODE HERE\n" in got
    assert '            raise NotImplementedError("Controller.step: replace' in got
    assert got.endswith("        return 0.0")


def test_tabs_and_magics_still_name_the_function():
    source = "%matplotlib inline\ndef f(x):\n\t### BEGIN SOLUTION\n\treturn x\n\t### END SOLUTION"
    got = student_source(source, "code", notebook="01_x", cell=0)
    assert got == (
        "%matplotlib inline\ndef f(x):\n\t# YOUR CODE HERE\n"
        '\traise NotImplementedError("f: replace these lines with your code")'
    )


def test_unparsable_cell_falls_back_to_indentation_scan():
    source = "def g(x):\n    ### BEGIN SOLUTION\n    return x +\n    ### END SOLUTION"
    got = student_source(source, "code", notebook="01_x", cell=0)
    assert 'NotImplementedError("g: ' in got


def test_indented_block_outside_a_function_is_named_by_notebook_and_cell():
    got = code(
        """
        try:
            ### BEGIN SOLUTION
            x = 1
            ### END SOLUTION
        except NotImplementedError:
            x = 0
        """
    )
    assert 'raise NotImplementedError("exercise in 01_x, cell index 2: replace' in got


def test_solution_block_at_column_0_is_an_error():
    with pytest.raises(CourseBuildError, match="column 0: put exercise code inside a function"):
        code(
            """
            x = 1
            ### BEGIN SOLUTION
            y = 2
            ### END SOLUTION
            """
        )


def test_markdown_solution_becomes_your_answer_here():
    source = "Why?\n\n### BEGIN SOLUTION\nBecause.\nReally.\n### END SOLUTION\nNext."
    assert student_source(source, "markdown") == "Why?\n\nYOUR ANSWER HERE\nNext."


def test_hidden_tests_are_dropped_wherever_they_are():
    got = code(
        """
        def compare(fn):
            assert fn(1) == 2
            ### BEGIN HIDDEN TESTS
            assert fn(2) == 4
            ### END HIDDEN TESTS
            return "ok"
        ### BEGIN HIDDEN TESTS
        assert compare(lambda x: 2 * x) == "ok"
        ### END HIDDEN TESTS
        """
    )
    assert got == 'def compare(fn):\n    assert fn(1) == 2\n    return "ok"'


def test_cell_without_markers_is_unchanged():
    source = "x = 1  # BEGIN SOLUTIONS are mentioned only in prose\n\nprint(x)\n"
    assert student_source(source, "code") == source


@pytest.mark.parametrize(
    ("source", "line", "message"),
    [
        ("def f():\n    ### BEGIN SOLUTION\n    return 1", 2, "never closed"),
        ("def f():\n    return 1\n    ### END SOLUTION", 3, "without a '### BEGIN SOLUTION'"),
        (
            "def f():\n    ### BEGIN SOLUTION\n    return 1\n    ### END HIDDEN TESTS",
            4,
            "closes the '### BEGIN SOLUTION' block opened at line 2",
        ),
        (
            "def f():\n    ### BEGIN SOLUTION\n    ### BEGIN HIDDEN TESTS\n",
            3,
            "inside the '### BEGIN SOLUTION' block opened at line 2",
        ),
        ("def f():\n    ## BEGIN SOLUTION\n    return 1", 2, "malformed marker '## BEGIN"),
        ("def f():\n    ### begin solution\n    return 1", 2, "malformed marker"),
        ("def f():\n    ###BEGIN HIDDEN TESTS\n", 2, "'### BEGIN HIDDEN TESTS'"),
    ],
)
def test_bad_markers_name_notebook_cell_and_line(source, line, message):
    with pytest.raises(CourseBuildError, match=message) as info:
        student_source(source, "code", notebook="solutions/03_sonar.ipynb", cell=7)
    assert str(info.value).startswith(f"solutions/03_sonar.ipynb, cell index 7, line {line}: ")
    assert (info.value.cell, info.value.line) == (7, line)


# --- notebooks ------------------------------------------------------------------------


def test_student_notebook_clears_outputs_drops_hidden_cells_and_metadata():
    run = new_code_cell("print(1)", id="a", execution_count=3, metadata={"scrolled": True})
    run.outputs = [nbformat.v4.new_output("stream", name="stdout", text="1\n")]
    solution = new_notebook(
        cells=[
            run,
            new_code_cell("secret()", id="b", metadata={"tags": ["hidden"]}),
            new_code_cell("### BEGIN HIDDEN TESTS\nassert 1\n### END HIDDEN TESTS", id="c"),
            new_code_cell("x = 2", id="d", metadata={"tags": ["hidden-not", "nbval-skip"]}),
            new_markdown_cell("text", id="e", metadata={"tags": ["hidden"]}),
        ],
        metadata={"kernelspec": {"name": "x", "display_name": "X"}, "widgets": {"state": 1}},
    )
    nb = student_notebook(solution, "01_x")
    assert [cell.id for cell in nb.cells] == ["a", "d"]
    assert nb.cells[0].outputs == [] and nb.cells[0].execution_count is None
    assert nb.cells[0].metadata == {}
    assert nb.cells[1].metadata == {"tags": ["hidden-not", "nbval-skip"]}
    assert nb.metadata == {
        "kernelspec": {
            "display_name": "Python 3 (ipykernel)",
            "language": "python",
            "name": "python3",
        },
        "language_info": {"name": "python"},
    }


def test_cells_without_ids_get_stable_ones(tmp_path):
    nb = new_notebook(cells=[new_code_cell("x = 1"), new_code_cell("y = 2")])
    nb.nbformat_minor = 4
    for cell in nb.cells:
        del cell["id"]
    (tmp_path / "solutions").mkdir()
    nbformat.write(nb, tmp_path / "solutions" / "02_old.ipynb")
    build(tmp_path / "solutions", tmp_path / "course")
    first = (tmp_path / "course" / "02_old.ipynb").read_bytes()
    build(tmp_path / "solutions", tmp_path / "course-again")
    assert (tmp_path / "course-again" / "02_old.ipynb").read_bytes() == first
    ids = [cell.id for cell in nbformat.reads(first.decode(), as_version=4).cells]
    assert len(set(ids)) == 2


# --- directories and the command line -------------------------------------------------


@pytest.fixture
def course_tree(tmp_path: Path) -> tuple[Path, Path]:
    """A solutions/ with two chapters and an empty course/ beside it."""
    solutions, course = tmp_path / "solutions", tmp_path / "course"
    write_solution(
        solutions,
        "01_one.ipynb",
        new_code_cell("def f():\n    ### BEGIN SOLUTION\n    return 1\n    ### END SOLUTION"),
    )
    write_solution(solutions, "02_two.ipynb", new_markdown_cell("# Two"))
    return solutions, course


def test_build_writes_every_chapter_and_rebuild_is_byte_identical(course_tree):
    solutions, course = course_tree
    assert build(solutions, course) == [
        course / "01_one.ipynb",
        course / "02_two.ipynb",
        course / "README.md",
        course / "nbgrader" / "source" / "01_one" / "01_one.ipynb",
        course / "nbgrader" / "source" / "02_two" / "02_two.ipynb",
        course / "nbgrader" / "nbgrader_config.py",
        course / "nbgrader" / ".gitignore",
    ]
    before = {p: p.read_bytes() for p in course.rglob("*") if p.is_file()}
    assert all(text.endswith(b"}\n") for path, text in before.items() if path.suffix == ".ipynb")
    assert build(solutions, course) == []
    assert build(solutions, course, check=True) == []
    assert {p: p.read_bytes() for p in course.rglob("*") if p.is_file()} == before


def test_check_mode_reports_changed_missing_and_extra_files_and_writes_nothing(course_tree):
    solutions, course = course_tree
    build(solutions, course)
    (course / "02_two.ipynb").unlink()
    edited = course / "01_one.ipynb"
    edited.write_text(edited.read_text().replace("YOUR CODE HERE", "my attempt"))
    (course / "99_orphan.ipynb").write_text("{}")
    (course / ".ipynb_checkpoints").mkdir()  # JupyterLab's own folder is left alone
    graded = course / "nbgrader"
    (graded / "source" / "02_two" / "02_two.ipynb").write_text("{}")
    (graded / "source" / "99_orphan").mkdir()
    (graded / "source" / "99_orphan" / "99_orphan.ipynb").write_text("{}")
    (graded / "release" / "01_one").mkdir(parents=True)  # nbgrader's own, left alone
    (graded / "release" / "01_one" / "01_one.ipynb").write_text("{}")
    (graded / "gradebook.db").write_text("")
    snapshot = sorted(p.relative_to(course).as_posix() for p in course.rglob("*"))

    changes = plan(solutions, course)
    assert [(c.path.relative_to(course).as_posix(), c.reason) for c in changes] == [
        ("01_one.ipynb", "out of date"),
        ("02_two.ipynb", "missing"),
        ("nbgrader/source/02_two/02_two.ipynb", "out of date"),
        ("99_orphan.ipynb", "no solution"),
        ("nbgrader/source/99_orphan/99_orphan.ipynb", "no solution"),
    ]
    assert build(solutions, course, check=True) == [c.path for c in changes]
    assert sorted(p.relative_to(course).as_posix() for p in course.rglob("*")) == snapshot

    build(solutions, course)
    assert sorted(p.relative_to(course).as_posix() for p in course.rglob("*")) == [
        ".ipynb_checkpoints",
        "01_one.ipynb",
        "02_two.ipynb",
        "README.md",
        "nbgrader",
        "nbgrader/.gitignore",
        "nbgrader/gradebook.db",
        "nbgrader/nbgrader_config.py",
        "nbgrader/release",
        "nbgrader/release/01_one",
        "nbgrader/release/01_one/01_one.ipynb",
        "nbgrader/source",
        "nbgrader/source/01_one",
        "nbgrader/source/01_one/01_one.ipynb",
        "nbgrader/source/02_two",
        "nbgrader/source/02_two/02_two.ipynb",
    ]
    assert build(solutions, course, check=True) == []


def test_bad_marker_in_a_notebook_names_the_file_and_writes_nothing(course_tree):
    solutions, course = course_tree
    write_solution(
        solutions,
        "03_bad.ipynb",
        new_markdown_cell("intro"),
        new_code_cell("def g():\n    ### BEGIN SOLUTION\n    return 2\n"),
    )
    with pytest.raises(CourseBuildError) as info:
        build(solutions, course)
    assert str(info.value).startswith(f"{solutions / '03_bad.ipynb'}, cell index 1, line 2: ")
    assert not course.exists()


def test_solution_notebooks_must_be_named_by_chapter(course_tree):
    solutions, course = course_tree
    write_solution(solutions, "scratch.ipynb", new_markdown_cell("x"))
    with pytest.raises(CourseBuildError, match="named NN_topic.ipynb"):
        build(solutions, course)


def test_main_build_and_check_exit_codes_and_messages(course_tree, capsys):
    solutions, course = course_tree
    args = ["--solutions", str(solutions), "--course", str(course)]

    assert main([*args, "--check"]) == 1
    out = capsys.readouterr().out.splitlines()
    assert out == [
        f"stale: {course / '01_one.ipynb'} (missing)",
        f"stale: {course / '02_two.ipynb'} (missing)",
        f"stale: {course / 'README.md'} (missing)",
        f"stale: {course / 'nbgrader/source/01_one/01_one.ipynb'} (missing)",
        f"stale: {course / 'nbgrader/source/02_two/02_two.ipynb'} (missing)",
        f"stale: {course / 'nbgrader/nbgrader_config.py'} (missing)",
        f"stale: {course / 'nbgrader/.gitignore'} (missing)",
        f"{course}/ is out of date: run `abcwc course build`",
    ]
    assert not course.exists()

    assert main(args) == 0
    assert capsys.readouterr().out.splitlines()[0] == f"wrote {course / '01_one.ipynb'} (missing)"
    assert main([*args, "--check"]) == 0
    assert capsys.readouterr().out == f"{course}/ is up to date (2 notebooks)\n"


def test_main_reports_build_errors_with_exit_code_2(tmp_path, capsys):
    assert main(["--solutions", str(tmp_path / "nope"), "--course", str(tmp_path)]) == 2
    assert capsys.readouterr().err == (
        f"abcwc: error: {tmp_path / 'nope'}: no such directory of solution notebooks\n")


def test_example_course_notebook_is_up_to_date():
    """tests/data/notebooks/course holds the expected build of the example solution."""
    assert build(EXAMPLES / "solutions", EXAMPLES / "course", check=True) == []


# --- the repository's own notebooks ---------------------------------------------------


def test_course_folder_is_up_to_date():
    stale = build(ROOT / "solutions", ROOT / "course", check=True)
    assert not stale, f"course/ is out of date ({', '.join(map(str, stale))}): " + (
        "run `abcwc course build`"
    )


@pytest.mark.parametrize("path", sorted((ROOT / "solutions").glob("*.ipynb")), ids=lambda p: p.name)
def test_solution_notebooks_are_stored_run_top_to_bottom(path):
    """nbval only compares cells that have stored outputs, so solutions must be run."""
    counts = [
        cell.execution_count
        for cell in nbformat.read(path, as_version=4).cells
        if cell.cell_type == "code" and cell.source.strip()
    ]
    assert counts == list(range(1, len(counts) + 1)), (
        f"{path.name} must be saved after a fresh top-to-bottom run (execution counts 1, 2, "
        f"3, ...; got {counts}); e.g. jupyter nbconvert --to notebook --execute --inplace"
    )


# --- nbval on the example notebooks ---------------------------------------------------

NBVAL_INI = """\
[pytest]
addopts = -p abcwc.nbval_plugin --nbval --nbval-current-env --nbval-cell-timeout=120
    -p no:cacheprovider --ignore-glob=course/nbgrader/*
testpaths = solutions course
"""


@pytest.fixture
def nbval_workspace(tmp_path: Path) -> Path:
    """A copy of the repository's notebook test setup with the example chapter built."""
    (tmp_path / "tests").mkdir()
    shutil.copy(ROOT / "tests" / "nbval_sanitize.cfg", tmp_path / "tests")
    (tmp_path / "pytest.ini").write_text(NBVAL_INI)
    shutil.copytree(EXAMPLES / "solutions", tmp_path / "solutions")
    build(tmp_path / "solutions", tmp_path / "course")
    return tmp_path


def run_nbval(workspace: Path, **env_vars: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, PYTHONPATH=str(ROOT), **env_vars)
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-rfE", "--color=no", "-W", "ignore"],
        cwd=workspace,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )


def edit_cell(path: Path, cell_id: str, **changes) -> None:
    nb = nbformat.read(path, as_version=4)
    (cell,) = [cell for cell in nb.cells if cell.id == cell_id]
    cell.update(changes)
    nbformat.write(nb, path)


def test_nbval_compares_solutions_and_runs_course_lax(nbval_workspace):
    # A wrong stored output in course/ does not matter: it only has to run to the end.
    stale = nbformat.v4.new_output("stream", name="stdout", text="something else\n")
    edit_cell(
        nbval_workspace / "course" / "00_example.ipynb", "check", execution_count=4, outputs=[stale]
    )
    # The student copy runs as on a laptop with no chair, whatever the caller's ABCWC_PORT
    student = nbval_workspace / "course" / "00_example.ipynb"
    nb = nbformat.read(student, as_version=4)
    nb.cells.append(nbformat.v4.new_code_cell(
        "import os\nassert 'ABCWC_PORT' not in os.environ, os.environ['ABCWC_PORT']"))
    nbformat.write(nb, student)
    # The kernels get the inline backend (so figures are still shown) whatever the caller's
    # MPLBACKEND says; the stored solution prints the backend and a figure's text/plain.
    result = run_nbval(nbval_workspace, MPLBACKEND="Agg", ABCWC_PORT="simavr")
    assert result.returncode == 0, result.stdout + result.stderr
    assert "13 passed" in result.stdout  # 7 solution cells + 6 course cells


def test_nbval_fails_on_changed_solution_output_and_on_course_errors(nbval_workspace):
    solution = nbval_workspace / "solutions" / "00_example.ipynb"
    nb = nbformat.read(solution, as_version=4)
    (cell,) = [cell for cell in nb.cells if cell.id == "check"]
    for mime, text in cell.outputs[0].data.items():  # a check's line, as text and HTML
        cell.outputs[0].data[mime] = text.replace("all 3", "all 4")
    nbformat.write(nb, solution)
    edit_cell(
        nbval_workspace / "course" / "00_example.ipynb", "plot", source="raise RuntimeError('boom')"
    )

    result = run_nbval(nbval_workspace)
    assert result.returncode == 1
    failed = sorted(line for line in result.stdout.splitlines() if line.startswith("FAILED"))
    assert [line.split(" - ")[0] for line in failed] == [
        "FAILED course/00_example.ipynb::Cell 4",
        "FAILED solutions/00_example.ipynb::Cell 3",
    ]
    assert "all 4 distances match" in result.stdout  # nbval shows stored vs new output


def test_student_notebook_runs_to_the_end_with_not_yet_and_fallback(tmp_path, monkeypatch):
    from nbclient import NotebookClient

    build(EXAMPLES / "solutions", tmp_path)
    nb = nbformat.read(tmp_path / "00_example.ipynb", as_version=4)
    monkeypatch.setenv("PYTHONPATH", str(ROOT))
    monkeypatch.setenv("MPLBACKEND", "module://matplotlib_inline.backend_inline")
    NotebookClient(nb, timeout=120, kernel_name="python3").execute()

    text = "".join(  # printed lines, and a check's line shown as text/plain beside its HTML
        out.get("text", "") or out.get("data", {}).get("text/plain", "") + "\n"
        for cell in nb.cells if cell.cell_type == "code" for out in cell.outputs
        if "image/png" not in out.get("data", {})
    )
    assert text.splitlines() == [
        "module://matplotlib_inline.backend_inline",
        "… not yet — wheel distance: not written yet "
        "(the cell above still raises NotImplementedError)",
        "→ the rest of this notebook uses abcwc's own reference_wheel_distance instead",
        "2500 ticks roll 2.3562 m",
    ]
    plot = nb.cells[-1].outputs
    assert [out.output_type for out in plot] == ["display_data"]
    assert "image/png" in plot[0].data


def test_a_chapters_notebooks_and_checks_are_scheduled_together():
    """Under ``--dist loadscope`` a chapter's two notebooks and its checks' tests are one
    scope (one worker runs them, in collection order); every other scope is xdist's own."""
    from abcwc.nbval_plugin import ChapterScopeScheduling, chapter_scope

    for scope in ("solutions/10_the_ekf.ipynb", "course/10_the_ekf.ipynb",
                  "tests/test_checks_ch10.py"):
        assert chapter_scope(scope) == "chapter 10"
    assert chapter_scope("tests/test_follow.py") == "chapter 17"  # the same lab trials
    assert chapter_scope("tests/test_marker_fixes.py") == "chapter 10"  # its camera drives
    for scope in ("tests/test_slam.py", "tests/test_dwa.py::TestWindow",
                  "tests/test_checks_ch00_ch01.py", "course/nbgrader/source/10/10.ipynb",
                  "course/README.md", "solutions/10_the_ekf.py"):
        assert chapter_scope(scope) == scope
    scheduler = ChapterScopeScheduling.__new__(ChapterScopeScheduling)  # needs no workers
    assert scheduler._split_scope("course/04_speech_commands.ipynb::Cell 12") == "chapter 04"
    assert scheduler._split_scope("tests/test_slam.py::test_x[fr079-0.061]") == \
        "tests/test_slam.py"


def test_the_slow_scopes_are_handed_out_first_in_their_order():
    from collections import OrderedDict

    from abcwc.nbval_plugin import put_first

    queue = OrderedDict.fromkeys(["chapter 01", "tests/test_a.py", "tests/test_slam.py",
                                  "chapter 10"])
    slow = ["chapter 10", "tests/test_follow.py", "tests/test_slam.py"]
    handed = []
    while queue:
        put_first(queue, slow)
        handed.append(queue.popitem(last=False)[0])
    assert handed == ["chapter 10", "tests/test_slam.py", "chapter 01", "tests/test_a.py"]


def test_the_slow_scopes_name_test_files_and_chapters(pytestconfig):
    slow = pytestconfig.getini("slow_scopes")
    assert slow
    for scope in slow:
        if scope.startswith("chapter "):
            assert list((ROOT / "solutions").glob(f"{scope.split()[1]}_*.ipynb")), scope
        else:
            assert (ROOT / scope).is_file() and scope.startswith("tests/"), scope
