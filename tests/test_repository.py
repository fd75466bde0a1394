"""The repository stands on its own: no tracked file refers to a folder beside the
checkout, so a fresh clone has everything its tests, notebooks and benchmarks read."""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
# written in pieces, so that this file does not match itself
OUTSIDE = re.compile("|".join(re.escape(a + b) for a, b in (
    ("../", "shared"), ("shared/", "data"), ("/work/", "shared"))))


def tracked_text_files(root: Path) -> list[Path]:
    """Every file git tracks under ``root`` that reads as UTF-8 text."""
    listed = subprocess.run(["git", "ls-files", "-z"], cwd=root, capture_output=True,
                            check=True).stdout.decode().split("\0")
    files = []
    for name in filter(None, listed):
        path = root / name
        if not path.is_file():  # deleted in the work tree, not yet committed
            continue
        data = path.read_bytes()
        try:
            data.decode("utf-8")
        except UnicodeDecodeError:
            continue
        if b"\0" not in data:
            files.append(path)
    return files


def outside_references(path: Path) -> list[str]:
    """``file:line: text`` for every line of ``path`` that names a folder outside."""
    return [f"{path}:{number}: {line.strip()[:120]}"
            for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
            if OUTSIDE.search(line)]


@pytest.fixture(scope="module")
def files() -> list[Path]:
    if not (ROOT / ".git").exists():
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(f"{ROOT} is not a git checkout")
        pytest.skip("not a git checkout (an unpacked sdist): nothing to list")
    return tracked_text_files(ROOT)


def test_no_tracked_file_refers_to_a_folder_beside_the_checkout(files):
    names = {p.relative_to(ROOT).as_posix() for p in files}
    assert {"README.md", "pyproject.toml", "tests/test_layers.py",
            "solutions/14_slam_with_loop_closure.ipynb"} <= names
    found = [hit for path in files for hit in outside_references(path)]
    assert not found, "\n".join(found)


def test_the_check_finds_each_kind_of_reference(tmp_path):
    sample = tmp_path / "sample.md"
    sample.write_text("".join(f"read {a}{b} here\n" for a, b in (
        ("../", "shared/x"), ("the shared/", "data/slam folder"), ("/work/", "shared/y"))))
    assert [hit.split(":")[1] for hit in outside_references(sample)] == ["1", "2", "3"]
    sample.write_text("a recording, shared\nshared by all the states\n")
    assert outside_references(sample) == []
