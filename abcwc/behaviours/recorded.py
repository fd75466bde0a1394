"""Drive a recorded list of commands: the same drive again, whatever drove it first.

A survey that a lesson measures (chapter 14's SLAM with and without loop closure) must
not change when the behaviour that first drove it is improved. :class:`RecordedDrive`
replays ``(t, v, w)`` rows, each command held from its time (s after the replay's first
frame) until the next row's, and succeeds at the last row's time. On the simulator,
with the same seed and start, the replay retraces the recorded drive: the commands go
through the same safety filter and the same body.

:func:`read_drive` reads a drive from a CSV file (``t_s,v_m_per_s,w_rad_per_s``, ``#``
comment lines allowed), as ``data/drives/floor_survey.csv`` is.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from abcwc.behaviours.base import _CLOCK_SLACK, BehaviourBase
from abcwc.types import SensorFrame, Twist


def read_drive(path: str | Path) -> np.ndarray:
    """(K, 3) rows of ``t`` (s from the start), ``v`` (m/s), ``w`` (rad/s) from a CSV file
    with the header ``t_s,v_m_per_s,w_rad_per_s``."""
    path = Path(path)
    lines = [line for line in path.read_text().splitlines()
             if line.strip() and not line.lstrip().startswith("#")]
    if not lines or lines[0].replace(" ", "") != "t_s,v_m_per_s,w_rad_per_s":
        raise ValueError(f"{path} must begin (after # comments) with the header "
                         f"t_s,v_m_per_s,w_rad_per_s")
    return np.loadtxt(lines[1:], delimiter=",", ndmin=2)


class RecordedDrive(BehaviourBase):
    """Replay ``commands`` ((K, 3): ``t`` s from the first frame, ``v`` m/s, ``w``
    rad/s; ``t`` from 0, increasing): each held until the next row's ``t``; succeeded at
    the last row's ``t`` (its command is not driven)."""

    def __init__(self, commands: np.ndarray):
        super().__init__()
        rows = np.asarray(commands, dtype=float)
        if rows.ndim != 2 or rows.shape[1] != 3 or len(rows) < 2:
            raise ValueError(f"commands must be (K, 3) rows of t, v, w with K >= 2, "
                             f"got shape {rows.shape}")
        if not np.isfinite(rows).all():
            raise ValueError("commands must be finite numbers (s, m/s, rad/s)")
        if rows[0, 0] != 0.0 or (np.diff(rows[:, 0]) <= 0).any():
            raise ValueError("the commands' times must start at 0 s and increase")
        self.commands = rows
        self._start: float | None = None

    @classmethod
    def from_csv(cls, path: str | Path) -> RecordedDrive:
        """The drive in ``path`` (:func:`read_drive`)."""
        return cls(read_drive(path))

    @property
    def duration(self) -> float:
        """s from the first frame to the end of the drive."""
        return float(self.commands[-1, 0])

    def update(self, frame: SensorFrame) -> Twist:
        if self._start is None:
            self._start = frame.t
        elapsed = frame.t - self._start
        if elapsed + _CLOCK_SLACK >= self.duration:
            self.succeed()
            return Twist(0.0, 0.0)
        row = int(np.searchsorted(self.commands[:, 0], elapsed + _CLOCK_SLACK, "right")) - 1
        _, v, w = self.commands[row]
        return Twist(float(v), float(w))

    def reset(self) -> None:
        """Play the drive again from its start, at the next frame."""
        super().reset()
        self._start = None


__all__ = ["RecordedDrive", "read_drive"]
