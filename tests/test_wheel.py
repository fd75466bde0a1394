"""The built package installs anywhere: the wheel carries ``data/`` as ``abcwc/data`` and
its ``abcwc demo`` runs outside the checkout; the sdist carries ``data/`` too.

The wheel is built without build isolation (no download: hatchling comes with the test
extra) and installed, without its dependencies, into a venv that sees this Python's
packages, so the test takes seconds. This checkout's own abcwc may be installed in that
Python as well (``pip install -e .``); the test checks the venv's copy is the one found.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DATA_FILES = sorted(p.relative_to(ROOT).as_posix() for p in (ROOT / "data").rglob("*")
                    if p.is_file())

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("hatchling") is None
    and os.environ.get("CI", "").lower() != "true",  # under CI a missing hatchling fails
    reason="hatchling is not installed (pip install -e '.[test]')",
)


def run(*args: str | Path, cwd: Path, env: dict[str, str] | None = None,
        timeout: float = 120) -> subprocess.CompletedProcess:
    done = subprocess.run([str(a) for a in args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=timeout)
    assert done.returncode == 0, f"{args} failed:\n{done.stdout}\n{done.stderr}"
    return done


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    dist = tmp_path_factory.mktemp("dist")
    run(sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation",
        "--disable-pip-version-check", "-q", "-w", dist, ROOT, cwd=dist)
    (path,) = dist.glob("abcwc-*.whl")
    return path


def test_wheel_ships_data_inside_the_package(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    assert DATA_FILES and {f"abcwc/{name}" for name in DATA_FILES} <= names
    assert "abcwc/paths.py" in names and "abcwc/py.typed" in names
    assert not any(name.startswith(("data/", "tests/", "solutions/")) for name in names)


def test_sdist_ships_data_at_the_top(tmp_path):
    run(sys.executable, "-m", "hatchling", "build", "-t", "sdist", "-d", tmp_path, cwd=ROOT)
    (sdist,) = tmp_path.glob("abcwc-*.tar.gz")
    with tarfile.open(sdist) as archive:
        names = {name.split("/", 1)[1] for name in archive.getnames() if "/" in name}
    assert set(DATA_FILES) <= names
    assert {"pyproject.toml", "abcwc/paths.py"} <= names


def test_installed_wheel_runs_the_demo_outside_the_checkout(wheel, tmp_path):
    venv = tmp_path / "venv"
    run(sys.executable, "-m", "venv", "--system-site-packages", "--without-pip", venv,
        cwd=tmp_path)
    bin_dir = venv / ("Scripts" if os.name == "nt" else "bin")
    python = bin_dir / "python"
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "ABCWC_DATA", "ABCWC_PORT", "PYTHONHOME")}
    # the system pip, run by the venv's python, installs into the venv
    run(python, "-m", "pip", "install", "--no-deps", "--no-index", "--ignore-installed",
        "--disable-pip-version-check", "-q", wheel, cwd=tmp_path, env=env)

    where = run(python, "-c", "import sysconfig, abcwc, abcwc.paths as p; "
                "print(sysconfig.get_paths()['purelib']); print(abcwc.__file__); "
                "print(p.data_dir()); print(p.checkout_root())", cwd=tmp_path, env=env)
    site, module, data, checkout = where.stdout.splitlines()
    package = Path(site) / "abcwc"
    assert Path(site).resolve().is_relative_to(venv.resolve())
    assert Path(module) == package / "__init__.py"  # the venv's copy, not the checkout's
    assert Path(data) == package / "data" and checkout == "None"

    out = tmp_path / "demo"
    done = run(bin_dir / "abcwc", "demo", "--seconds", "5", "--quiet", "--out", out,
               cwd=tmp_path, env=env)
    assert "sonar-avoidance wander in lab" in done.stdout
    for name in ("demo_wander.png", "demo_wander.gif", "demo_wander.npz"):
        assert (out / name).stat().st_size > 1000

    # what needs the repository says so
    refused = subprocess.run([bin_dir / "abcwc", "bench", "notebooks"], cwd=tmp_path,
                             env=env, capture_output=True, text=True, timeout=120)
    assert refused.returncode == 2 and refused.stderr.startswith(
        "abcwc: error: the notebooks benchmark (it runs solutions/) needs a checkout of the "
        "abcwc repository"), refused.stderr
