"""The shared 2D SLAM benchmark data and its reference figures.

The project keeps the public benchmark data (Kümmerle et al., "On measuring the accuracy
of SLAM algorithms", Autonomous Robots 2009, and the standard pose graphs Manhattan
M3500, MIT and CSAIL) outside the repository, in ``../shared/data/slam`` beside the
checkout; ``ABCWC_SLAM_DATA`` points elsewhere. Tests and benchmarks read it from there.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

from abcwc.paths import checkout_root

SLAM_DATA_ENV = "ABCWC_SLAM_DATA"


@dataclass(frozen=True)
class GraphReference:
    """A shared pose graph's file name and GTSAM 4.3's Levenberg-Marquardt on it (pose 0
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
"""The figures of the data's README, by graph name."""


LOG_FACTS: dict[str, dict] = {
    "aces": {"max_range": 50.0},
    "mit-csail": {},
    "fr079": {"laser_offset": (0.04, 0.0, 0.0)},
}
"""What each shared log's FLASER lines do not carry, as ``read_carmen_log`` options (the
data README: ACES's laser reaches 50 m, FR079's sits 0.04 m ahead of the base). Facts of
the files, not tuning: the methods take no other per-log setting."""


def slam_data_dir() -> Path:
    """``$ABCWC_SLAM_DATA`` if set, else ``shared/data/slam`` beside the checkout (which
    may not exist: callers check)."""
    override = os.environ.get(SLAM_DATA_ENV)
    if override:
        return Path(override)
    root = checkout_root()
    return (root.parent if root else Path.cwd()) / "shared" / "data" / "slam"
