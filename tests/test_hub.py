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
