"""Where the data comes from: ``$ABCWC_DATA``, the checkout's ``data/``, or the wheel's
``abcwc/data`` (tests/test_wheel.py installs a wheel to see that last one)."""

from __future__ import annotations

from pathlib import Path

import pytest

from abcwc import paths
from abcwc.paths import NotACheckoutError, checkout_root, data_dir, require_checkout

ROOT = Path(__file__).resolve().parent.parent


@pytest.fixture(autouse=True)
def no_override(monkeypatch):
    monkeypatch.delenv("ABCWC_DATA", raising=False)


def test_a_checkout_reads_its_top_level_data():
    assert checkout_root() == ROOT == require_checkout("this test")
    assert data_dir() == ROOT / "data"


def test_abcwc_data_overrides_and_must_be_a_folder(monkeypatch, tmp_path):
    monkeypatch.setenv("ABCWC_DATA", str(tmp_path))
    assert data_dir() == tmp_path
    monkeypatch.setenv("ABCWC_DATA", str(tmp_path / "nope"))
    with pytest.raises(FileNotFoundError, match=r"ABCWC_DATA=.*nope is not a folder"):
        data_dir()


def test_installed_copy_without_data_says_where_it_looked(monkeypatch):
    # installed (no checkout), and this package folder has no data/ beside its modules
    monkeypatch.setattr(paths, "checkout_root", lambda: None)
    with pytest.raises(FileNotFoundError) as error:
        data_dir()
    message = str(error.value)
    assert str(ROOT / "abcwc" / "data") in message and "set ABCWC_DATA" in message


def test_installed_copy_refuses_what_needs_the_repository(monkeypatch):
    monkeypatch.setattr(paths, "checkout_root", lambda: None)
    with pytest.raises(NotACheckoutError, match="the thing needs a checkout of the abcwc"):
        require_checkout("the thing")
    assert issubclass(NotACheckoutError, FileNotFoundError)  # the CLI's user error
