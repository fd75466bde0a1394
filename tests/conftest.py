"""Shared fixtures: an ideal chair and noise-free parameters, and the firmware harness
for simavr (built once a session; under CI a missing toolchain fails, elsewhere it skips)."""

from __future__ import annotations

import os
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


UNDER_CI = os.environ.get("CI", "").lower() == "true"


@pytest.fixture(scope="session")
def harness_files():
    """The firmware-in-the-loop harness, built (``make``) once for the session."""
    from abcwc.hw.fil_base import FirmwareToolchainError, build_harness

    try:
        return build_harness()
    except FirmwareToolchainError as exc:
        if UNDER_CI:
            pytest.fail(str(exc))
        pytest.skip(str(exc))
