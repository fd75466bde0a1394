"""Absolute position fixes made from a simulated run's ground truth.

A stand-in for a sensor that measures the chair's whole pose now and then (a camera
seeing a surveyed marker, a beacon system): the true pose, with seeded Gaussian noise.
Only a study on a simulated log can make them (a real chair's log has no true pose);
:mod:`abcwc.experiments.nees` feeds them to the EKF as a controlled test of its
consistency.
"""

from __future__ import annotations

import math

import numpy as np

from abcwc.log import RunLog
from abcwc.types import Pose2D


def absolute_fixes(log: RunLog, every: float, std: tuple[float, float, float],
                   seed: int = 0) -> dict[int, Pose2D]:
    """Noisy fixes from the log's ground truth every ``every`` seconds: {row: pose}.

    ``std`` (m, m, rad) is the fixes' noise, three finite numbers ``>= 0``.
    """
    if not (isinstance(every, (int, float)) and math.isfinite(every) and every > 0):
        raise ValueError(f"every must be a finite interval > 0 s, got {every!r}")
    stds = np.asarray(std, dtype=float)
    if stds.shape != (3,) or not np.isfinite(stds).all() or (stds < 0).any():
        raise ValueError(f"std (m, m, rad) must be 3 finite numbers >= 0, got {std!r}")
    if not log.has_ground_truth:
        raise ValueError("absolute fixes need a log with ground truth (a simulated run's)")
    rng = np.random.default_rng(seed)
    rows = np.flatnonzero(np.diff(np.floor((log.t - log.t[0]) / every), prepend=0) > 0)
    noise = rng.standard_normal((len(rows), 3)) * stds
    return {int(k): Pose2D(*(log.pose[k] + e)) for k, e in zip(rows, noise)}
