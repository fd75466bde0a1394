"""A class on a real JupyterHub: JupyterHub from PyPI with configurable-http-proxy from npm
on 127.0.0.1, the dummy authenticator and local-process servers. Two students log in at
once, each starts a server, pulls the course by chapter 00's nbgitpuller link and runs the
chapter through the server (contents, sessions and the kernel's websocket), every cell
without an error, in a kernel of their own server; at the
end the hub and every process it started are gone. Without jupyterhub or the proxy the
test is skipped, and under CI (``CI=true``) it fails instead. ``abcwc hubtrial`` runs
larger classes and prints their times and memory."""

from __future__ import annotations

import os
import shutil
import subprocess

import nbformat
import psutil
import pytest

from abcwc.paths import checkout_root

UNDER_CI = os.environ.get("CI", "").lower() == "true"
STUDENTS = 2


def _missing() -> str | None:
    try:
        import jupyterhub  # noqa: F401
    except ImportError:
        return "jupyterhub is not installed: pip install -e '.[test]'"
    try:
        import nbgitpuller  # noqa: F401
    except ImportError:
        return "nbgitpuller is not installed: pip install -e '.[test]'"
    if shutil.which("configurable-http-proxy") is None:
        return "configurable-http-proxy is not on PATH: npm install -g configurable-http-proxy"
    return None


def test_students_run_a_chapter_each_on_their_own_server(tmp_path):
    missing = _missing()
    if missing:
        if UNDER_CI:
            pytest.fail(missing)
        pytest.skip(missing)
    from abcwc.hub import CHAPTER, LocalHub, run_class

    code_cells = sum(cell.cell_type == "code"
                     for cell in nbformat.read(checkout_root() / CHAPTER, as_version=4).cells)
    hub = LocalHub(tmp_path, start_timeout=90).start()
    try:
        result = run_class(hub, STUDENTS)
        assert hub.servers() == {}, "a student's server still runs after the class"
        started = [hub.process.pid, *(p.pid for p in psutil.Process(
            hub.process.pid).children(recursive=True))]
        assert len(started) >= 2  # the hub and its proxy
    finally:
        hub.stop()
    alive = [pid for pid in started if psutil.pid_exists(pid)
             and psutil.Process(pid).status() != psutil.STATUS_ZOMBIE]
    assert alive == [], "the hub or its proxy still runs after stop()"

    names = {f"student{k + 1}" for k in range(STUDENTS)}
    assert {run.student for run in result.students} == names
    for run in result.students:
        assert run.errors == (), f"{run.student}'s chapter failed: {run.errors}"
        assert run.cells == code_cells
        # nbgitpuller put the committed chapter into the student's home
        pulled = hub.home(run.student) / run.chapter
        assert run.chapter == f"abcwc/{CHAPTER}"
        assert pulled.read_bytes() == subprocess.run(
            ["git", "show", f"HEAD:{CHAPTER}"], cwd=checkout_root(), capture_output=True,
            check=True).stdout
        assert run.kernel_user == run.student
        # a server with its kernel holds numpy, matplotlib and the simulator: well over
        # 100 MB resident, and no server of this sort reaches 4 GB
        assert 100 < run.peak_memory_mb < 4096
        assert 0 < run.chapter_seconds < result.wall_seconds


def test_the_readmes_nbgitpuller_link_opens_a_course_chapter():
    from urllib.parse import parse_qs, urlsplit

    from abcwc.hub import nbgitpuller_link

    readme = (checkout_root() / "README.md").read_text(encoding="utf-8")
    link = readme.split("<!-- nbgitpuller-link -->", 1)[1].split("```")[1].strip()
    link = link.removeprefix("text").strip()
    parts = urlsplit(link)
    assert parts.path == "/hub/user-redirect/git-pull"
    query = {key: values[0] for key, values in parse_qs(parts.query).items()}
    folder = query["repo"].rstrip("/").split("/")[-1]  # where nbgitpuller clones it
    tree, _, chapter = query["urlpath"].partition(f"/{folder}/")
    assert tree == "lab/tree"
    assert chapter.startswith("course/") and (checkout_root() / chapter).is_file()
    assert link == nbgitpuller_link(f"{parts.scheme}://{parts.netloc}", query["repo"], chapter,
                                    query["branch"])


@pytest.mark.parametrize("buffers", [[], [b"abc"], [b"abc", b"\x00\xff\x01"]])
def test_a_binary_kernel_frame_reads_as_the_server_wrote_it(buffers):
    from jupyter_server.services.kernels.connection.base import serialize_binary_message

    from abcwc.hub import _decode

    msg = {"header": {"msg_id": "m1", "msg_type": "comm_msg"}, "parent_header": {},
           "metadata": {}, "content": {"data": {"value": "é"}}, "channel": "iopub"}
    assert _decode(serialize_binary_message({**msg, "buffers": buffers})) == msg


def _class(chapter_seconds: list[float], memory_mb: float = 400.0):
    from abcwc.hub import ClassRun, StudentRun

    return ClassRun(tuple(StudentRun(f"s{k}", "abcwc/course/00_tour.ipynb", 2.0, seconds, 20,
                                     (), f"s{k}", memory_mb)
                          for k, seconds in enumerate(chapter_seconds)),
                    wall_seconds=max(chapter_seconds) + 3.0)


def test_the_doubling_point_is_the_first_class_twice_as_slow_as_the_smallest():
    from abcwc.hub import class_figures, doubling_point

    classes = {1: _class([4.0]), 2: _class([4.0, 5.0]), 4: _class([7.0, 8.9]),
               8: _class([16.0] * 8)}
    # means 4.0, 4.5, 7.95 (1.99 times: not yet double) and 16.0
    assert doubling_point(classes) == 8
    assert doubling_point({k: classes[k] for k in (1, 2, 4)}) is None
    rows = class_figures(classes)
    assert [row["students"] for row in rows] == [1, 2, 4, 8]
    assert rows[2]["slowdown"] == pytest.approx(7.95 / 4.0)
    assert rows[1]["chapter_max_s"] == 5.0 and rows[3]["memory_max_mb"] == 400.0
    with pytest.raises(ValueError, match="no classes measured"):
        doubling_point({})


def test_hubtrial_prints_each_class_and_the_doubling_point(monkeypatch, capsys):
    import json

    from abcwc import hub
    from abcwc.cli import main

    started = []

    class FakeHub:
        def __init__(self, folder):
            self.folder = folder

        def check_chapter(self, chapter):
            started.append(chapter)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            pass

    times = {1: [4.0], 2: [4.2, 4.4], 4: [8.0, 8.4, 8.2, 8.6]}
    monkeypatch.setattr(hub, "LocalHub", FakeHub)
    monkeypatch.setattr(hub, "run_class", lambda running, size, chapter, prefix:
                        _class(times[size], memory_mb=426.0))
    assert main(["hubtrial", "--students", "4,1,2", "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "a chapter's time doubles at 4 students" in text
    assert main(["hubtrial", "--students", "1,2", "--json", "--quiet"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert [row["students"] for row in figures["classes"]] == [1, 2]
    assert figures["doubling_students"] is None
    assert figures["classes"][1]["chapter_mean_s"] == pytest.approx(4.3)
    assert started == ["course/00_tour.ipynb"] * 2
