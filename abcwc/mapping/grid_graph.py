"""A simulated pose graph with known truth: a random walk on a city-block grid.

In the spirit of Olson, Leonard and Teller's Manhattan world ("Fast iterative alignment
of pose graphs with poor initial estimates", ICRA 2006; the M3500 data set): a robot
drives one block (``step`` m) at a time in a square city of about ``poses / 4``
crossings, turning left or right or keeping on at each crossing (and away from the
city's edge). Consecutive poses get an odometry edge; whenever the robot is back at a
crossing it passed before (at least ``min_gap`` poses ago), it gets loop-closure edges
to up to ``loops_per_pose`` of those earlier visits. Every measurement is the true
relative pose perturbed by zero-mean Gaussian noise of standard deviations ``sigma``
(m, m, rad), drawn in SE(2)'s tangent space, so that at the true poses each edge's error
``e = Log(z^-1 (+) x_i^-1 (+) x_j)`` is exactly that noise and its chi2 has 3 degrees
of freedom: at the optimum the total is close to ``3 M - 3 (N - 1)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from abcwc.geometry import compose, relative, wrap_angle
from abcwc.mapping.g2o import PoseGraph, chain_odometry


@dataclass(frozen=True)
class SimulatedGraph:
    """A pose graph (initial poses: the chained noisy odometry) and the true poses."""

    graph: PoseGraph
    truth: np.ndarray


def se2_exp(tangent: np.ndarray) -> np.ndarray:
    """SE(2)'s exponential of (M, 3) tangent vectors ``(rho_x, rho_y, theta)``: the poses
    ``(V(theta) rho, theta)``, ``V = [[sin t / t, -(1 - cos t) / t], [(1 - cos t) / t,
    sin t / t]]`` (Eade 2017, sec. 3; series near 0)."""
    theta = tangent[:, 2]
    small = np.abs(theta) < 1e-6
    safe = np.where(small, 1.0, theta)
    a = np.where(small, 1.0 - theta**2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, theta / 2.0, (1.0 - np.cos(safe)) / safe)
    x, y = tangent[:, 0], tangent[:, 1]
    return np.stack([a * x - b * y, b * x + a * y, wrap_angle(theta)], axis=1)


def grid_world(poses: int, seed: int, loops_per_pose: int = 1, step: float = 1.0,
               sigma: tuple[float, float, float] = (0.05, 0.05, 0.01),
               min_gap: int = 10) -> SimulatedGraph:
    """A seeded random-walk pose graph of ``poses`` poses; see the module notes.

    ``sigma`` (m, m, rad) are the measurement noise's standard deviations, and the edges'
    information is ``diag(sigma)^-2``: the noise model is right.
    """
    if not (isinstance(poses, int) and poses >= 2):
        raise ValueError(f"poses must be an integer >= 2, got {poses!r}")
    if not (isinstance(loops_per_pose, int) and loops_per_pose >= 0):
        raise ValueError(f"loops_per_pose must be an integer >= 0, got {loops_per_pose!r}")
    if not (math.isfinite(step) and step > 0):
        raise ValueError(f"step must be a finite length > 0 m, got {step!r}")
    if len(sigma) != 3 or not all(math.isfinite(s) and s > 0 for s in sigma):
        raise ValueError(f"sigma must be three finite standard deviations > 0, got {sigma!r}")
    rng = np.random.default_rng(seed)
    half = max(2, round(math.sqrt(poses) / 4))   # the city: crossings -half..half each way
    moves = np.array([[1, 0], [0, 1], [-1, 0], [0, -1]])  # heading 0, 1, 2, 3 quarter turns
    cells = np.zeros((poses, 2), dtype=np.int64)
    quarters = np.zeros(poses, dtype=np.int64)
    wishes = rng.choice([-1, 0, 0, 1], size=poses)      # keep on half the time
    for k in range(1, poses):  # a walk: each crossing depends on the one before
        for turn in (wishes[k], 1, -1, 2):               # turn away from the city's edge
            heading = (quarters[k - 1] + turn) % 4
            cell = cells[k - 1] + moves[heading]
            if np.all(np.abs(cell) <= half):
                break
        cells[k], quarters[k] = cell, heading
    truth = np.column_stack([cells * step, wrap_angle(quarters * (math.pi / 2))])

    pairs = [(k, k + 1) for k in range(poses - 1)]
    visits: dict[tuple[int, int], list[int]] = {}
    for k, cell in enumerate(map(tuple, cells.tolist())):
        earlier = [v for v in visits.get(cell, []) if k - v >= min_gap]
        if earlier and loops_per_pose:
            chosen = rng.choice(earlier, size=min(loops_per_pose, len(earlier)), replace=False)
            pairs += [(int(v), k) for v in chosen]
        visits.setdefault(cell, []).append(k)
    edges = np.array(pairs, dtype=np.int64)

    noise = rng.normal(0.0, 1.0, (len(edges), 3)) * np.asarray(sigma)
    measurements = compose(relative(truth[edges[:, 0]], truth[edges[:, 1]]), se2_exp(-noise))
    information = np.broadcast_to(np.diag(1.0 / np.asarray(sigma) ** 2),
                                  (len(edges), 3, 3)).copy()
    ids = np.arange(poses)
    initial = chain_odometry(ids, edges, measurements)
    graph = PoseGraph(ids, initial, edges, measurements, information, poses_from="odometry")
    return SimulatedGraph(graph, truth)
