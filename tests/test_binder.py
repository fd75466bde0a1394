"""The repository builds on Binder as it is: repo2docker (``--no-build``, which writes the
Dockerfile without Docker) reads ``.binder/`` and its Dockerfile installs the project from
pyproject.toml on a Python the project supports, the Debian packages the library's own
messages name for the firmware in the loop and the synthesisers, builds the firmware's
simavr harness, and starts the servers with real-chair cells on the simulated Arduino
where the harness built."""

from __future__ import annotations

import contextlib
import io
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from abcwc.connect import SIMAVR_PORT
from abcwc.hw.fil_base import TOOL_PACKAGES
from abcwc.perception.speech.synthesis import DEBIAN_PACKAGES

if sys.version_info >= (3, 11):
    import tomllib
else:
    import tomli as tomllib

ROOT = Path(__file__).resolve().parent.parent
BINDER = ROOT / ".binder"

pytest.importorskip("repo2docker", reason="pip install jupyter-repo2docker (the test extra)")


@pytest.fixture(scope="module")
def dockerfile() -> str:
    """What ``repo2docker --no-build ROOT`` prints: the Dockerfile it would build."""
    from repo2docker.__main__ import make_r2d

    r2d = make_r2d(["--no-build", str(ROOT)])
    r2d.initialize([])
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        r2d.build()
    return printed.getvalue()


def apt_installed(dockerfile: str) -> set[str]:
    """The packages of the Dockerfile's ``apt-get install`` lines."""
    found: set[str] = set()
    for line in re.findall(r"apt-get install --yes --no-install-recommends ([^&\n]+)",
                           dockerfile):
        found.update(line.split())
    return found


def test_the_dockerfile_installs_the_packages_the_library_asks_for(dockerfile):
    installed = apt_installed(dockerfile)
    wanted = {package for packages in (*TOOL_PACKAGES.values(), *DEBIAN_PACKAGES.values())
              for package in packages.split()}
    wanted.add("libelf-dev")  # the harness links -lelf (firmware/Makefile)
    assert "-lelf" in (ROOT / "firmware" / "Makefile").read_text(encoding="utf-8")
    assert wanted <= installed, f"missing from .binder/apt.txt: {sorted(wanted - installed)}"


def test_binder_installs_only_packages_ci_tests_with(dockerfile):
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    ci_packages = set(re.search(r"packages=\(([^)]*)\)", ci).group(1).split())
    extra = apt_installed(dockerfile) - ci_packages
    # what repo2docker's base image itself installs is no business of ours
    ours = {line.partition("#")[0].strip()
            for line in (BINDER / "apt.txt").read_text(encoding="utf-8").splitlines()} - {""}
    assert not (extra & ours), f"Binder installs packages CI never uses: {sorted(extra & ours)}"


def test_the_dockerfile_installs_the_project_from_the_checkout(dockerfile):
    copy = dockerfile.index("COPY --chown=0:0 src/ ${REPO_DIR}/")
    install = dockerfile.index('pip install --no-cache-dir -r ".binder/requirements.txt"')
    assert copy < install, "the requirements are installed before the checkout is copied"
    requirements = [line.strip() for line in
                    (BINDER / "requirements.txt").read_text(encoding="utf-8").splitlines()
                    if line.strip() and not line.startswith("#")]
    assert requirements == ["-e ."]
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert project["name"] == "abcwc"


def test_the_image_python_is_one_the_project_supports(dockerfile):
    from packaging.specifiers import SpecifierSet

    # the conda environment's lock file, environment.py-X.Y-linux-64.lock, whose name
    # the Dockerfile spells escaped ("." as -2e, "-" as -2d)
    found = re.search(r"environment(?:\.|-2e)py(?:-|-2d)(\d+)(?:\.|-2e)(\d+)", dockerfile)
    version = f"{found.group(1)}.{found.group(2)}"
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    assert version in SpecifierSet(project["requires-python"])


def test_the_image_builds_the_firmware_harness(dockerfile):
    assert "RUN ./.binder/postBuild" in dockerfile
    post_build = (BINDER / "postBuild").read_text(encoding="utf-8")
    assert "make -C firmware harness" in post_build
    # where the start script looks for what it built
    assert "firmware/build/abcwc_harness" in (BINDER / "start").read_text(encoding="utf-8")
    assert re.search(r"^\$\(BUILD\)/abcwc_harness:",
                     (ROOT / "firmware" / "Makefile").read_text(encoding="utf-8"), re.M)
    assert re.search(r"^harness:", (ROOT / "firmware" / "Makefile").read_text(encoding="utf-8"),
                     re.M)
    assert subprocess.run(["bash", "-n", str(BINDER / "postBuild")]).returncode == 0


@pytest.mark.parametrize("given, harness, expected", [
    (None, True, SIMAVR_PORT), (None, False, None), ("/dev/ttyACM0", True, "/dev/ttyACM0")])
def test_the_start_script_puts_real_chair_cells_on_the_simulated_arduino(
        dockerfile, tmp_path, given, harness, expected):
    assert 'ENV R2D_ENTRYPOINT="${REPO_DIR}/.binder/start"' in dockerfile
    if harness:  # what postBuild leaves when the harness built
        built = tmp_path / "firmware" / "build" / "abcwc_harness"
        built.parent.mkdir(parents=True)
        built.write_text("#!/bin/sh\n")
        built.chmod(0o755)
    env = {key: value for key, value in os.environ.items() if key != "ABCWC_PORT"}
    env["REPO_DIR"] = str(tmp_path)
    if given is not None:
        env["ABCWC_PORT"] = given
    seen = subprocess.run(["bash", str(BINDER / "start"), "printenv", "ABCWC_PORT"], env=env,
                          capture_output=True, text=True, timeout=30)
    assert (seen.stdout.strip() or None) == expected
