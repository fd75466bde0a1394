"""What the browser tests share: Debian's ``chromium`` (Playwright drives it; no browser
download), and a skip (a failure under CI) when it or Playwright is missing."""

from __future__ import annotations

import os
import shutil

import pytest

CHROMIUM = shutil.which("chromium")


def require_browser() -> None:
    """Skip the test (fail it under CI) unless chromium and Playwright are installed."""
    missing = []
    if CHROMIUM is None:
        missing.append("Debian's chromium")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        missing.append("playwright (pip)")
    if missing:
        message = f"browser tests need {' and '.join(missing)}"
        if os.environ.get("CI") == "true":
            pytest.fail(message)
        pytest.skip(message)


