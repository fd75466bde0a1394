"""The SLAM benchmark data in ``data/slam``: every file is the one its README's table
hashes, the reference figures in the code are the README's, and the library finds the
folder (in a checkout here; tests/test_wheel.py checks an installed wheel)."""

from __future__ import annotations

import hashlib
import re
from pathlib import Path

import pytest

from abcwc.mapping.slam_data import (
    REFERENCE_GRAPHS,
    SLAM_DATA_ENV,
    slam_data_dir,
    slam_file,
)

ROOT = Path(__file__).resolve().parent.parent
FOLDER = ROOT / "data" / "slam"
README = FOLDER / "README.md"
FILE_ROW = re.compile(r"^\| `([^`]+)` \| (\d+) \| `([0-9a-f]{64})` \|$")
GRAPH_ROW = re.compile(r"^\| (\w+) \| ([\d.e]+) \| ([\d.e]+) \| ([\d.]+) s \|$")


def listed_files(readme: Path) -> dict[str, tuple[int, str]]:
    """The README's file table: name -> (bytes, SHA-256)."""
    rows = [FILE_ROW.match(line) for line in readme.read_text().splitlines()]
    return {m[1]: (int(m[2]), m[3]) for m in rows if m}


def mismatches(folder: Path, listed: dict[str, tuple[int, str]]) -> list[str]:
    """Every way the folder's files and the table differ (empty: they agree)."""
    present = {p.name for p in folder.iterdir() if p.is_file() and p.name != "README.md"}
    problems = [f"{name}: in the folder, not in the table" for name in present - set(listed)]
    problems += [f"{name}: in the table, not in the folder" for name in set(listed) - present]
    for name in sorted(present & set(listed)):
        data = (folder / name).read_bytes()
        size, digest = listed[name]
        if len(data) != size or hashlib.sha256(data).hexdigest() != digest:
            problems.append(f"{name}: {len(data)} bytes, SHA-256 "
                            f"{hashlib.sha256(data).hexdigest()}; the table says {size}, "
                            f"{digest}")
    return sorted(problems)


def test_every_file_is_the_one_the_readme_hashes():
    listed = listed_files(README)
    assert len(listed) == 9  # three logs, their relations, three graphs
    assert mismatches(FOLDER, listed) == []


def test_the_hash_check_sees_a_changed_a_missing_and_an_unlisted_file(tmp_path):
    for name in ("CSAIL.g2o.gz", "MIT.g2o.gz", "README.md"):
        (tmp_path / name).write_bytes((FOLDER / name).read_bytes())
    listed = listed_files(README)
    assert mismatches(tmp_path, {k: listed[k] for k in ("CSAIL.g2o.gz", "MIT.g2o.gz")}) == []
    changed = bytearray((FOLDER / "MIT.g2o.gz").read_bytes())
    changed[-1] ^= 1
    (tmp_path / "MIT.g2o.gz").write_bytes(bytes(changed))
    (tmp_path / "extra.relations").write_text("1 2 0 0 0 0 0 0\n")
    problems = mismatches(tmp_path, listed)
    assert any(p.startswith("MIT.g2o.gz: 43916 bytes") for p in problems)
    assert "extra.relations: in the folder, not in the table" in problems
    assert "aces.clf.gz: in the table, not in the folder" in problems
    assert not any(p.startswith("CSAIL") for p in problems)


def test_the_reference_graph_figures_are_the_readmes():
    rows = [GRAPH_ROW.match(line) for line in README.read_text().splitlines()]
    table = {m[1]: tuple(float(x) for x in m.groups()[1:]) for m in rows if m}
    assert table == {name: (r.chi2_start, r.chi2_gtsam, r.seconds_gtsam)
                     for name, r in REFERENCE_GRAPHS.items()}


def test_the_library_reads_the_repositorys_copy(monkeypatch):
    monkeypatch.delenv(SLAM_DATA_ENV, raising=False)
    monkeypatch.delenv("ABCWC_DATA", raising=False)
    assert slam_data_dir() == FOLDER
    assert slam_file("aces.relations") == FOLDER / "aces.relations"


def test_abcwc_slam_data_overrides_and_a_missing_file_is_an_error(monkeypatch, tmp_path):
    monkeypatch.setenv(SLAM_DATA_ENV, str(tmp_path))
    (tmp_path / "MIT.g2o.gz").write_bytes(b"")
    assert slam_data_dir() == tmp_path and slam_file("MIT.g2o.gz") == tmp_path / "MIT.g2o.gz"
    with pytest.raises(FileNotFoundError, match=rf"aces\.clf\.gz not found in {tmp_path}; "
                                                rf"{SLAM_DATA_ENV}=.* or unset it"):
        slam_file("aces.clf.gz")


def test_abcwc_data_moves_the_slam_folder_with_it(monkeypatch, tmp_path):
    monkeypatch.delenv(SLAM_DATA_ENV, raising=False)
    monkeypatch.setenv("ABCWC_DATA", str(tmp_path))
    assert slam_data_dir() == tmp_path / "slam"
    with pytest.raises(FileNotFoundError, match=r"fr079\.relations not found .*ABCWC_DATA"):
        slam_file("fr079.relations")
