"""Results kept on disk: a second call (here or in another process) reads what the first
computed, and a change of the arguments, the code or a constant it reads is a new key."""

from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from abcwc.experiments import disk_cache
from abcwc.experiments.disk_cache import cached_on_disk, call_key

SCALE = 2.0
calls: list[int] = []


def _drive(seed: int) -> np.ndarray:
    calls.append(seed)
    return np.random.default_rng(seed).normal(size=3) * SCALE


def test_a_second_call_reads_the_first_result(tmp_path, monkeypatch):
    monkeypatch.setenv("ABCWC_CACHE_DIR", str(tmp_path))
    calls.clear()
    cached = cached_on_disk(_drive)
    first = cached(4)
    assert np.array_equal(cached(4), first) and calls == [4]
    assert np.array_equal(first, _drive(4))  # the same as computing it
    cached(5)
    assert calls == [4, 4, 5]
    assert len(list(tmp_path.glob("_drive-*.pickle"))) == 2


def test_the_key_follows_the_arguments_the_code_and_the_constants(monkeypatch):
    key = call_key(_drive, (4,), {})
    assert call_key(_drive, (5,), {}) != key
    monkeypatch.setitem(_drive.__globals__, "SCALE", 3.0)
    assert call_key(_drive, (4,), {}) != key
    monkeypatch.setitem(_drive.__globals__, "SCALE", 2.0)
    assert call_key(_drive, (4,), {}) == key

    def other(seed: int) -> np.ndarray:
        return np.random.default_rng(seed).normal(size=3) * SCALE

    assert call_key(other, (4,), {}) != key


def _drive_for(seed: int, seconds: float = 60.0) -> float:
    return seed * seconds


def test_a_call_is_keyed_by_its_bound_arguments():
    """Positional or by name, the default given or not: one call, one key."""
    key = call_key(_drive_for, (1, 60.0), {})
    assert call_key(_drive_for, (), {"seed": 1, "seconds": 60.0}) == key
    assert call_key(_drive_for, (1,), {"seconds": 60.0}) == key
    assert call_key(_drive_for, (1,), {}) == key
    assert call_key(_drive_for, (1, 30.0), {}) != key
    with pytest.raises(TypeError, match="_drive_for"):
        call_key(_drive_for, (1,), {"minutes": 1.0})


def test_a_call_with_an_object_of_no_repr_is_run_not_kept(tmp_path, monkeypatch):
    """An argument shown as ``<... object at 0x...>`` would make a new key every call:
    such a call runs and leaves nothing behind."""
    monkeypatch.setenv("ABCWC_CACHE_DIR", str(tmp_path))
    calls.clear()
    cached = cached_on_disk(_drive_for)
    assert call_key(_drive_for, (object(),), {}) is None
    assert cached(1, 2.0) == 2.0 and cached(1, 2.0) == 2.0
    assert len(list(tmp_path.glob("_drive_for-*.pickle"))) == 1
    with pytest.raises(TypeError):  # run, as without the cache: object() * 2.0
        cached(object(), 2.0)
    assert len(list(tmp_path.glob("_drive_for-*.pickle"))) == 1


def test_processes_take_turns_and_the_second_reads_the_first(tmp_path):
    script = textwrap.dedent("""
        import time
        from abcwc.experiments.disk_cache import cached_on_disk
        def slow(n):
            print("computed", flush=True)
            time.sleep(1.0)
            return n * 2
        assert cached_on_disk(slow)(21) == 42
    """)
    env = {"ABCWC_CACHE_DIR": str(tmp_path), "PATH": "/usr/bin:/bin"}
    runs = [subprocess.Popen([sys.executable, "-c", script], env=env, stdout=subprocess.PIPE,
                             text=True) for _ in range(2)]
    outputs = [run.communicate(timeout=60)[0] for run in runs]
    assert all(run.returncode == 0 for run in runs)
    assert sum(out.count("computed") for out in outputs) == 1


def test_where_nothing_can_be_written_it_simply_runs(tmp_path, monkeypatch):
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setenv("ABCWC_CACHE_DIR", str(blocked / "cache"))
    calls.clear()
    cached = cached_on_disk(_drive)
    cached(1)
    cached(1)
    assert calls == [1, 1]
    assert disk_cache.cache_folder() == blocked / "cache"


def test_the_key_follows_the_blas_kernels(monkeypatch):
    """A result kept under other BLAS kernels (OPENBLAS_CORETYPE), whose sums round
    otherwise, is not read: chapter 14's loop closures follow those last bits."""
    monkeypatch.setenv("OPENBLAS_CORETYPE", "Haswell")
    haswell = call_key(_drive, (4,), {})
    assert call_key(_drive, (4,), {}) == haswell
    monkeypatch.setenv("OPENBLAS_CORETYPE", "Prescott")
    assert call_key(_drive, (4,), {}) != haswell
    monkeypatch.delenv("OPENBLAS_CORETYPE")
    assert call_key(_drive, (4,), {}) != haswell
