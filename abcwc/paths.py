"""Where the project's data lives, and whether abcwc runs from a checkout.

The library reads its chair parameters and worlds from a data folder: the repository's
top-level ``data/`` when abcwc runs from a checkout (``pip install -e .``), else the
copy an installed wheel ships as ``abcwc/data``. Set ``ABCWC_DATA`` to use another copy
(for example a class's own worlds).

A few tools work on the repository itself rather than on the library (``abcwc course
build`` and the notebook benchmark read ``solutions/``; the firmware in the loop builds
``firmware/``); they call :func:`require_checkout`, which says so when abcwc is an
installed copy.
"""

from __future__ import annotations

import os
import tempfile
from collections.abc import Callable
from importlib import resources
from pathlib import Path
from typing import TypeVar

__all__ = ["CACHE_ENV", "DATA_ENV", "NotACheckoutError", "cache_folder", "checkout_root",
           "data_dir", "read_document", "require_checkout", "write_whole"]

_Parsed = TypeVar("_Parsed")

DATA_ENV = "ABCWC_DATA"
"""Environment variable naming a data folder to use instead of the project's own."""

CACHE_ENV = "ABCWC_CACHE_DIR"
"""Environment variable naming the folder where slow, deterministic results are kept
(:func:`cache_folder`)."""

_PACKAGE_DIR = Path(__file__).resolve().parent


class NotACheckoutError(FileNotFoundError):
    """A tool that works on the repository ran from an installed copy of abcwc."""


def checkout_root() -> Path | None:
    """The repository checkout this ``abcwc`` is imported from, or ``None`` when installed.

    A checkout is recognised by the ``pyproject.toml`` beside the package folder; an
    installed package sits in ``site-packages``, which has none.
    """
    root = _PACKAGE_DIR.parent
    return root if (root / "pyproject.toml").is_file() else None


def require_checkout(what: str) -> Path:
    """The checkout's root; :class:`NotACheckoutError` naming ``what`` when there is none."""
    root = checkout_root()
    if root is None:
        raise NotACheckoutError(
            f"{what} needs a checkout of the abcwc repository, but abcwc is installed at "
            f"{_PACKAGE_DIR}; clone the repository and run `pip install -e .` in it"
        )
    return root


def data_dir() -> Path:
    """The data folder: ``$ABCWC_DATA`` if set, else the checkout's ``data/``, else the
    copy installed with the package (``abcwc/data``).

    Raises:
        FileNotFoundError: ``$ABCWC_DATA`` is not a folder, or no data folder exists.
    """
    override = os.environ.get(DATA_ENV)
    if override:
        path = Path(override)
        if not path.is_dir():
            raise FileNotFoundError(f"{DATA_ENV}={override} is not a folder")
        return path
    tried = []
    root = checkout_root()
    if root is not None:
        tried.append(root / "data")
    packaged = resources.files("abcwc") / "data"
    if isinstance(packaged, Path):  # not inside a zip file
        tried.append(packaged)
    for path in tried:
        if path.is_dir():
            return path
    raise FileNotFoundError(
        f"abcwc data folder not found (looked in {', '.join(map(str, tried))}); reinstall "
        f"abcwc or set {DATA_ENV} to a copy of the repository's data/"
    )


def cache_folder() -> Path:
    """Where slow, deterministic results are kept between runs (seeded drives:
    :mod:`abcwc.experiments.disk_cache`; synthesised speech:
    :mod:`abcwc.perception.speech.synthesis`): ``$ABCWC_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/abcwc``, else ``~/.cache/abcwc``. Deleting it only costs time."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV])
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "abcwc"


def write_whole(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` by way of a temporary file beside it, renamed over it:
    a reader in another process finds the old file or the new one, never half of one.
    Raises ``OSError`` where it cannot be written."""
    with tempfile.NamedTemporaryFile(dir=path.parent, suffix=path.suffix,
                                     delete=False) as out:
        out.write(data)
    os.replace(out.name, path)


def read_document(path: Path, parse: Callable[[str], _Parsed], *,
                  parse_errors: tuple[type[Exception], ...], error: type[Exception],
                  kind: str, language: str) -> _Parsed:
    """``parse(path's text)``; a missing file or a parse error raises ``error`` naming the
    file: ``"<path>: no such <kind>"`` or ``"<path>: not valid <language> (<why>)"``."""
    try:
        return parse(Path(path).read_text())
    except FileNotFoundError:
        raise error(f"{path}: no such {kind}") from None
    except parse_errors as exc:
        raise error(f"{path}: not valid {language} ({exc})") from None
