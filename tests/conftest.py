"""Shared fixtures: an ideal chair and noise-free parameters."""

from __future__ import annotations

from dataclasses import replace

import pytest

from abcwc.params import ChairParams, default_params


def noise_free(params: ChairParams | None = None) -> ChairParams:
    """The chair's parameters with every sensor's noise switched off."""
    p = params or default_params()
    return replace(
        p,
        sonar=replace(p.sonar, noise_std=0.0),
        ir=replace(p.ir, noise_std=0.0),
        lidar=replace(p.lidar, noise_std=0.0),
        depth_scan=replace(p.depth_scan, noise_std=0.0),
        gyro=replace(p.gyro, noise_std=0.0, bias_std=0.0, bias_walk_std=0.0),
    )


@pytest.fixture
def params() -> ChairParams:
    return default_params()
