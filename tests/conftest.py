"""Shared fixtures: an ideal chair, noise-free parameters and an empty test world."""

from __future__ import annotations

from dataclasses import replace

import pytest

from abcwc.params import ChairParams, default_params
from abcwc.sim.world import World, world_from_dict


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


def box_world(width: float = 40.0, height: float = 40.0, extra: list | None = None,
              centred: bool = False) -> World:
    """An empty rectangular room from (0, 0) to (width, height), start in the middle
    facing +x; ``centred`` puts the room's middle (and the start) at the origin."""
    x0, y0 = (-width / 2, -height / 2) if centred else (0.0, 0.0)
    x1, y1 = x0 + width, y0 + height
    walls = [[[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]]] + (extra or [])
    return world_from_dict({
        "name": "box", "walls": walls,
        "places": {"start": [(x0 + x1) / 2, (y0 + y1) / 2, 0.0]},
    })


@pytest.fixture
def params() -> ChairParams:
    return default_params()
