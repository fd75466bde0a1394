"""Where the project's data lives.

The library reads its chair parameters and worlds from the repository's top-level
``data/`` folder. Set ``ABCWC_DATA`` to use another copy (for example a class's own
worlds).
"""

from __future__ import annotations

import os
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parent.parent


def data_dir() -> Path:
    """The data folder: ``$ABCWC_DATA`` if set, else ``<repo>/data``."""
    override = os.environ.get("ABCWC_DATA")
    path = Path(override) if override else REPO_ROOT / "data"
    if not path.is_dir():
        raise FileNotFoundError(
            f"abcwc data folder {path} not found; install abcwc from a checkout "
            "(pip install -e .) or set ABCWC_DATA to a copy of the repository's data/"
        )
    return path
