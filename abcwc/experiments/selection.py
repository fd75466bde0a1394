"""Choosing a destination without a hand: switch scanning and dwell, a seeded model.

The thesis's riders choose by gaze or by a switch (its 1.1 and 5.3.4). Two ways of
choosing one of ``options`` buttons trade speed against mistakes:

* **Switch scanning.** The buttons light up in turn, ``interval`` s each, from the
  first; the rider presses the switch a reaction time after the one wanted lights up.
  The press picks the button lit *at the press*, so a reaction slower than the interval
  picks a later one: a false selection. The time to select is ``(k - 1) interval + RT``
  for the k-th button.
* **Dwell.** The rider's gaze (an eye tracker moving the pointer) looks at the buttons
  in a random order until it finds the one wanted, one fixation each, and then rests on
  it for the ``dwell`` time, which picks it. A fixation on another button that lasts the
  dwell time picks that one instead: a false selection (the "Midas touch"). The time to
  select is the fixations before the target plus the dwell.

Reaction times and fixations are lognormal (a median and the spread of the log). What
the model was given is ours, not measured on riders: a switch press a median 0.6 s after
the light with a spread of 0.3 (slower than the 0.2-0.3 s of an unimpaired hand), and
fixations of a median 0.25 s with a spread of 0.5 (about the quarter of a second eye
movement reviews give for reading and search). The target is uniform among the buttons.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["SelectionTrials", "dwell_trials", "scan_false_rate", "scanning_trials"]

OPTIONS = 9
"""The floor world's destinations: the buttons a rider chooses among."""
REACTION_MEDIAN = 0.6
"""s, the median time from a button lighting up to the switch press (our setting)."""
REACTION_SPREAD = 0.3
"""The standard deviation of the log of the reaction time (our setting)."""
FIXATION_MEDIAN = 0.25
"""s, the median fixation on a button while looking for the one wanted (our setting)."""
FIXATION_SPREAD = 0.5
"""The standard deviation of the log of a fixation (our setting)."""


@dataclass(frozen=True)
class SelectionTrials:
    """Seeded trials of one way of choosing at one setting (``setting`` s: the scan
    interval or the dwell time): each trial's time to select (s) and whether it picked
    a button other than the one wanted."""

    method: str
    setting: float
    times: np.ndarray
    wrong: np.ndarray

    @property
    def mean_time(self) -> float:
        """s, the mean time to select."""
        return float(self.times.mean())

    @property
    def false_rate(self) -> float:
        """The share of trials that picked the wrong button (0..1)."""
        return float(self.wrong.mean())


def _check(setting: float, name: str, trials: int, options: int) -> None:
    if isinstance(setting, bool) or not isinstance(setting, (int, float)) or not (
            math.isfinite(setting) and setting > 0):
        raise ValueError(f"{name} must be a finite number of seconds > 0, got {setting!r}")
    for what, value in (("trials", trials), ("options", options)):
        if isinstance(value, bool) or not isinstance(value, int) or value < 1:
            raise ValueError(f"{what} must be a whole number >= 1, got {value!r}")


def scanning_trials(interval: float, trials: int = 4000, options: int = OPTIONS,
                    seed: int = 0) -> SelectionTrials:
    """Switch scanning at ``interval`` s a button (module notes), ``trials`` times."""
    _check(interval, "interval", trials, options)
    rng = np.random.default_rng(seed)
    target = rng.integers(0, options, trials)
    reaction = REACTION_MEDIAN * np.exp(REACTION_SPREAD * rng.standard_normal(trials))
    lit_at_press = (target + np.floor(reaction / interval).astype(int)) % options
    return SelectionTrials("scanning", float(interval), target * interval + reaction,
                           lit_at_press != target)


def dwell_trials(dwell: float, trials: int = 4000, options: int = OPTIONS,
                 seed: int = 0) -> SelectionTrials:
    """Dwell selection with a ``dwell`` s rest (module notes), ``trials`` times."""
    _check(dwell, "dwell", trials, options)
    rng = np.random.default_rng(seed)
    before = rng.integers(0, options, trials)  # buttons looked at before the target
    looks = FIXATION_MEDIAN * np.exp(FIXATION_SPREAD * rng.standard_normal((trials,
                                                                            options)))
    looked = np.arange(options) < before[:, None]
    lingered = looked & (looks >= dwell)
    wrong = lingered.any(axis=1)
    first = np.argmax(lingered, axis=1)  # the first look that lasted the dwell
    spent = np.where(looked, looks, 0.0)
    upto = np.where(wrong, first, before)
    times = (np.where(np.arange(options) < upto[:, None], spent, 0.0).sum(axis=1) + dwell)
    return SelectionTrials("dwell", float(dwell), times, wrong)


def scan_false_rate(interval: float) -> float:
    """The share of false selections of switch scanning at ``interval`` s, in closed
    form: the chance that the reaction time is at least the interval,
    ``1 - Phi(ln(interval / median) / spread)``, with Phi the standard normal CDF."""
    _check(interval, "interval", 1, 1)
    z = math.log(interval / REACTION_MEDIAN) / REACTION_SPREAD
    return 0.5 * math.erfc(z / math.sqrt(2.0))
