"""Which lidar blob is the followed person: a gate on where she can be and how fast she
can have got there.

The tag names the person; between two readings of it the lidar says where she is. A
passer-by who crosses her way is a blob of the same size a few tenths of a metre from
her, and a follower that takes the blob nearest its prediction can swap her for him:
her track then jumps to his pace, and the chair follows him up the corridor. Three
rules keep the track on her (gated nearest neighbour, as a track-while-scan radar keeps
its targets apart: Bar-Shalom and Fortmann, *Tracking and Data Association*, 1988,
section 2.3):

* **Where.** Only a candidate within ``gate`` m of the prediction can be her.
* **How fast.** A candidate whose update would put the track's speed over
  ``max_speed`` (a brisk walk is 1.5-2 m/s; people at work walk under 1.5) is someone
  else, or her and someone else seen as one.
* **Alone.** With two candidates inside the gate the lidar cannot say which is hers:
  neither is taken. The track coasts on its prediction until the tag is read again,
  and if it is not read in time the follower says it has lost her rather than guess.

When the tag is read it names her again: the candidate is looked for round the tag's
point instead, and a track more than ``gate`` m from the tag was on someone else and
starts again from the tag.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class IdentityGate:
    """The rules above: ``gate`` (m), ``max_speed`` (m/s)."""

    gate: float = 0.5
    max_speed: float = 1.6

    def __post_init__(self) -> None:
        for name in ("gate", "max_speed"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a finite number > 0, got {value!r}")

    def choose(self, candidates: np.ndarray, around: np.ndarray, velocity: np.ndarray,
               dt: float, beta: float) -> tuple[np.ndarray | None, str]:
        """The candidate (x, y, m) that is the person, of ``candidates`` (K, 2), near
        ``around`` (the prediction, or the tag's point) with the track at ``velocity``
        (m/s) updated ``dt`` s ago by an alpha-beta filter of velocity gain ``beta``;
        or None, with the reason: ``"none near"``, ``"two near"`` or ``"too fast"``."""
        candidates = np.asarray(candidates, dtype=float).reshape(-1, 2)
        gaps = np.hypot(*(candidates - around).T)
        near = np.flatnonzero(gaps <= self.gate)
        if not len(near):
            return None, "none near"
        if len(near) > 1:
            return None, "two near"
        chosen = candidates[near[0]]
        if dt > 0:
            speed = math.hypot(*(velocity + beta / dt * (chosen - around)))
            if speed > self.max_speed:
                return None, "too fast"
        return chosen, "taken"


__all__ = ["IdentityGate"]
