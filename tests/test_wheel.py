"""The built package installs anywhere: the wheel carries ``data/`` (the SLAM benchmark
data among it) as ``abcwc/data``, and its ``abcwc demo`` and SLAM benchmarks run outside
the checkout; the sdist carries ``data/`` too.

The wheel is built without build isolation (no download: hatchling comes with the test
extra) and installed, without its dependencies, into a fresh venv that sees the packages
of the environment running the tests (a ``.pth`` file adds that environment's
site-packages after the venv's own), so the test takes seconds and needs no network,
whether pytest runs from a venv or from the system's Python. This checkout's own abcwc is
installed in that environment too (``pip install -e .``); the test checks the venv's copy
is the one found.
"""

from __future__ import annotations

import importlib.util
import os
import site
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
    assert "abcwc/ui/dashboard.ipynb" in names  # abcwc dashboard's page
    assert not any(name.startswith(("data/", "tests/", "solutions/")) for name in names)
    assert "abcwc/data/slam/fr079.clf.gz" in names  # the largest file, 2.2 MB
    # the SLAM data is 4.8 MB of it; the code, worlds and parameters 0.4 MB
    assert wheel.stat().st_size < 6_000_000


def test_sdist_ships_data_at_the_top(tmp_path):
    run(sys.executable, "-m", "hatchling", "build", "-t", "sdist", "-d", tmp_path, cwd=ROOT)
    (sdist,) = tmp_path.glob("abcwc-*.tar.gz")
    with tarfile.open(sdist) as archive:
        names = {name.split("/", 1)[1] for name in archive.getnames() if "/" in name}
    assert set(DATA_FILES) <= names
    assert {"pyproject.toml", "abcwc/paths.py"} <= names


def outer_site_dirs() -> list[str]:
    """The site-packages folders of the environment running the tests (a venv's own, or
    the system's), and the user's when this Python reads it."""
    user = [site.getusersitepackages()] if site.ENABLE_USER_SITE else []
    return [*site.getsitepackages(), *user]


def venv_seeing_this_environment(venv: Path) -> Path:
    """A new venv at ``venv`` whose Python also imports what this environment has
    installed, after its own packages; its bin folder."""
    run(sys.executable, "-m", "venv", "--without-pip", venv, cwd=venv.parent)
    bin_dir = venv / ("Scripts" if os.name == "nt" else "bin")
    purelib = run(bin_dir / "python", "-c",
                  "import sysconfig; print(sysconfig.get_paths()['purelib'])",
                  cwd=venv.parent).stdout.strip()
    # .pth lines that start with "import" run: addsitedir also reads those folders' .pth
    (Path(purelib) / "outer_environment.pth").write_text("".join(
        f"import site; site.addsitedir({folder!r})\n" for folder in outer_site_dirs()))
    return bin_dir


def test_installed_wheel_runs_the_demo_outside_the_checkout(wheel, tmp_path):
    venv = tmp_path / "venv"
    bin_dir = venv_seeing_this_environment(venv)
    python = bin_dir / "python"
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "ABCWC_DATA", "ABCWC_SLAM_DATA", "ABCWC_PORT",
                        "PYTHONHOME", "VIRTUAL_ENV")}
    # this environment's pip, run by the venv's python, installs into the venv
    run(python, "-m", "pip", "install", "--no-deps", "--no-index", "--ignore-installed",
        "--disable-pip-version-check", "-q", wheel, cwd=tmp_path, env=env)

    where = run(python, "-c", "import sysconfig, abcwc, abcwc.paths as p; "
                "from abcwc.mapping.slam_data import slam_file; "
                "print(sysconfig.get_paths()['purelib']); print(abcwc.__file__); "
                "print(p.data_dir()); print(p.checkout_root()); "
                "print(slam_file('aces.clf.gz'))", cwd=tmp_path, env=env)
    site_dir, module, data, checkout, aces = where.stdout.splitlines()
    package = Path(site_dir) / "abcwc"
    assert Path(site_dir).resolve().is_relative_to(venv.resolve())
    assert Path(module) == package / "__init__.py"  # the venv's copy, not the checkout's
    assert Path(data) == package / "data" and checkout == "None"
    assert Path(aces) == package / "data" / "slam" / "aces.clf.gz"

    out = tmp_path / "demo"
    done = run(bin_dir / "abcwc", "demo", "--mission", "wander", "--seconds", "5", "--quiet",
               "--out", out,
               cwd=tmp_path, env=env)
    assert "sonar-avoidance wander in lab" in done.stdout
    for name in ("demo_wander.png", "demo_wander.gif", "demo_wander.npz"):
        assert (out / name).stat().st_size > 1000

    # the SLAM benchmark logs are read from the installed copy
    done = run(bin_dir / "abcwc", "bench", "carmen", "--repeats", "1", cwd=tmp_path, env=env)
    for name, scans in (("aces", 7374), ("mit-csail", 1988), ("fr079", 4934)):
        assert f"parse {name}.clf.gz ({scans} scans)" in done.stdout

    # what needs the repository says so
    refused = subprocess.run([bin_dir / "abcwc", "bench", "notebooks"], cwd=tmp_path,
                             env=env, capture_output=True, text=True, timeout=120)
    assert refused.returncode == 2 and refused.stderr.startswith(
        "abcwc: error: the notebooks benchmark (it runs solutions/) needs a checkout of the "
        "abcwc repository"), refused.stderr
