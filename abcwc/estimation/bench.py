"""Benchmark: EKF predict + wheel-update cycles per second, both back ends."""

from __future__ import annotations

import time

from abcwc.estimation.ekf import ChairEkf
from abcwc.types import Pose2D


def _cycles_per_second(backend: str, cycles: int, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        ekf = ChairEkf(Pose2D(), backend=backend)
        start = time.perf_counter()
        for _ in range(cycles):
            ekf.predict(0.02)
            ekf.update_wheels(0.010, 0.011, 0.02)
        best = min(best, time.perf_counter() - start)
    return cycles / best


def bench_ekf(cycles: int = 5000, repeats: int = 5) -> dict[str, float]:
    """EKF predict+update cycles per second (best of ``repeats``): fast and filterpy."""
    return {
        "ekf_fast_cycles_per_s": _cycles_per_second("fast", cycles, repeats),
        "ekf_filterpy_cycles_per_s": _cycles_per_second("filterpy", cycles, repeats),
    }
