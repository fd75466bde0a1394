"""Where the tests find the real SLAM benchmark logs (kept outside the repository).

``../shared/data/slam`` beside the repository's root, or ``ABCWC_SLAM_DATA``. Tests
that need a file skip when it is missing, and fail instead under CI=true.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from abcwc.mapping.slam_data import slam_data_dir

UNDER_CI = os.environ.get("CI", "").lower() == "true"
SLAM_DATA = slam_data_dir()


def slam_file(name: str) -> Path:
    """The benchmark file ``name``; skips the test (fails under CI) if it is absent."""
    path = SLAM_DATA / name
    if not path.is_file():
        message = f"SLAM benchmark file {path} not found (set ABCWC_SLAM_DATA)"
        if UNDER_CI:
            pytest.fail(message)
        pytest.skip(message)
    return path
