"""The 2D SLAM benchmark data the project ships, and its reference figures.

``data/slam/`` holds the public benchmark data: the three real laser logs of Kümmerle et
al., "On measuring the accuracy of SLAM algorithms", Autonomous Robots 27(4), 2009 (ACES,
MIT CSAIL and FR079, with their ground-truth relations) and the standard pose graphs
Manhattan M3500, MIT and CSAIL. ``data/slam/README.md`` gives their provenance, line
formats, the published figures and each file's SHA-256. Like the rest of ``data/``, the
folder is found by :func:`abcwc.paths.data_dir` (a checkout's ``data/``, or the copy an
installed wheel carries as ``abcwc/data``); ``ABCWC_SLAM_DATA`` names another folder.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from abcwc.paths import DATA_ENV, data_dir

SLAM_DATA_ENV = "ABCWC_SLAM_DATA"
"""Environment variable naming a folder to read the SLAM benchmark files from instead."""


@dataclass(frozen=True)
class GraphReference:
    """A benchmark pose graph's file name and GTSAM 4.3's Levenberg-Marquardt on it (pose 0
    fixed, from the file's vertices or the chained odometry): chi2 at the start, chi2
    reached, and its solve time (s) on a 2-core machine like the project's."""

    file: str
    chi2_start: float
    chi2_gtsam: float
    seconds_gtsam: float


REFERENCE_GRAPHS = {
    "manhattan": GraphReference("manhattan.g2o.gz", 2.703e10, 3549.0, 0.20),
    "CSAIL": GraphReference("CSAIL.g2o.gz", 2.144e6, 40.55, 0.03),
    "MIT": GraphReference("MIT.g2o.gz", 7.097e9, 770.2, 0.14),
}
"""The figures of ``data/slam/README.md``, by graph name."""


LOG_FACTS: dict[str, dict] = {
    "aces": {"max_range": 50.0},
    "mit-csail": {},
    "fr079": {"laser_offset": (0.04, 0.0, 0.0)},
}
"""What each benchmark log's FLASER lines do not carry, as ``read_carmen_log`` options
(``data/slam/README.md``: ACES's laser reaches 50 m, FR079's sits 0.04 m ahead of the
base). Facts of the files, not tuning: the methods take no other per-log setting."""


def slam_data_dir() -> Path:
    """The folder of the SLAM benchmark files: ``$ABCWC_SLAM_DATA`` if set, else
    ``slam/`` in :func:`abcwc.paths.data_dir` (which honours ``$ABCWC_DATA``)."""
    override = os.environ.get(SLAM_DATA_ENV)
    return Path(override) if override else data_dir() / "slam"


def slam_file(name: str) -> Path:
    """The benchmark file ``name`` (for example ``"aces.clf.gz"``) in :func:`slam_data_dir`.

    Raises:
        FileNotFoundError: the file is not there; the message names the folder and how
            it was chosen.
    """
    folder = slam_data_dir()
    path = folder / name
    if path.is_file():
        return path
    override = os.environ.get(SLAM_DATA_ENV)
    remedy = (f"{SLAM_DATA_ENV}={override} chose that folder: point it at a copy of the "
              "repository's data/slam, or unset it" if override else
              f"the folder is slam/ of abcwc's data folder (${DATA_ENV} if set, else the "
              "checkout's data/ or the installed abcwc/data): restore the file from the "
              f"repository, or set {SLAM_DATA_ENV} to a folder that has it")
    raise FileNotFoundError(f"SLAM benchmark file {name} not found in {folder}; {remedy}")
