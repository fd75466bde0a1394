"""Time plots of a run's signals, one panel per signal on a shared time axis."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from abcwc.geometry import encoder_ticks_to_wheel_distance, inverse_transform_points
from abcwc.log import RunLog
from abcwc.params import ChairParams, default_params
from abcwc.viz._common import decimate


def true_velocity(log: RunLog) -> tuple[np.ndarray, np.ndarray]:
    """Forward speed v (m/s) and turn rate w (rad/s) per row from the true poses.

    v is the x (forward) part of each row's world displacement seen from the chair's
    heading; w the heading's rate of change, unwrapped.
    """
    pose, dt = log.pose, log.period or 1.0
    if len(pose) < 2:
        return np.zeros(len(pose)), np.zeros(len(pose))
    moved = np.column_stack([np.gradient(pose[:, 0]), np.gradient(pose[:, 1])])
    headings = np.column_stack([np.zeros((len(pose), 2)), pose[:, 2]])
    v = inverse_transform_points(headings, moved)[:, 0] / dt
    return v, np.gradient(np.unwrap(pose[:, 2])) / dt


def encoder_velocity(log: RunLog, params: ChairParams | None = None,
                     ) -> tuple[np.ndarray, np.ndarray]:
    """v (m/s) and w (rad/s) per row from the encoder counts (``params``' wheel sizes,
    default the nominal ones).

    Each wheel's travel per period comes from
    :func:`abcwc.geometry.encoder_ticks_to_wheel_distance` (counter wrap corrected); a
    row's speed is the mean of the periods either side of it (``np.gradient``'s central
    difference), one-sided at the ends.
    """
    p, dt = params or default_params(), log.period or 1.0
    if len(log) < 2:
        return np.zeros(len(log)), np.zeros(len(log))
    travel = encoder_ticks_to_wheel_distance(log.ticks, p.distance_per_count)
    per_row = np.empty((len(log), 2))
    per_row[0], per_row[-1] = travel[0], travel[-1]
    per_row[1:-1] = (travel[:-1] + travel[1:]) / 2.0
    wheels = per_row / dt
    return wheels.mean(axis=1), (wheels[:, 1] - wheels[:, 0]) / p.wheel_base


def _has_pose(log: RunLog) -> bool:
    return bool(np.isfinite(log.pose[:, :2]).any())


def _velocity(log: RunLog, rows: np.ndarray, ax: Axes, which: int, unit: str) -> None:
    source = true_velocity(log) if _has_pose(log) else encoder_velocity(log)
    name = "true" if _has_pose(log) else "encoders"
    ax.plot(log.t[rows], source[which][rows], label=name)
    command = log.cmd_twist[rows, which]
    if np.isfinite(command).any():
        ax.plot(log.t[rows], command, "--", label="commanded")
    wanted = log.channels.get("wanted_twist")
    if wanted is not None and not np.array_equal(wanted[rows, which], command, equal_nan=True):
        ax.plot(log.t[rows], wanted[rows, which], ":", color="k", linewidth=1,
                label="wanted (before the safety filter)")
    ax.set_ylabel(unit)


def _v(log: RunLog, rows: np.ndarray, ax: Axes) -> None:
    _velocity(log, rows, ax, 0, "v (m/s)")


def _w(log: RunLog, rows: np.ndarray, ax: Axes) -> None:
    _velocity(log, rows, ax, 1, "w (rad/s)")


def _pots(log: RunLog, rows: np.ndarray, ax: Axes) -> None:
    for col, name in enumerate(("fb", "lr")):
        (line,) = ax.plot(log.t[rows], log.pots[rows, col], label=f"{name} on pot")
        sent = log.cmd_pots[rows, col].astype(float)
        sent[sent < 0] = np.nan
        if np.isfinite(sent).any():
            ax.plot(log.t[rows], sent, "--", color=line.get_color(), label=f"{name} sent")
    ax.axhline(default_params().pot_neutral, color="0.6", linewidth=0.8)
    ax.set_ylim(0, 260)
    ax.set_ylabel("pot byte")


def _sonar(log: RunLog, rows: np.ndarray, ax: Axes) -> None:
    ax.plot(log.t[rows], log.sonar[rows], label="sonar")
    ax.set_ylabel("sonar (m)")


def _ir(log: RunLog, rows: np.ndarray, ax: Axes) -> None:
    readings = np.where(np.isfinite(log.ir[rows]), log.ir[rows], np.nan)
    for k in range(readings.shape[1]):
        ax.plot(log.t[rows], readings[:, k], label=f"IR {k}")
    ax.set_ylabel("IR (m)")


def _ticks(log: RunLog, rows: np.ndarray, ax: Axes) -> None:
    ax.plot(log.t[rows], log.ticks[rows, 0], label="left")
    ax.plot(log.t[rows], log.ticks[rows, 1], label="right")
    ax.set_ylabel("encoder counts")


def _gyro(log: RunLog, rows: np.ndarray, ax: Axes) -> None:
    ax.plot(log.t[rows], log.gyro_z[rows], linewidth=0.8, label="gyro z")
    ax.set_ylabel("gyro (rad/s)")


def _collisions(log: RunLog, rows: np.ndarray, ax: Axes) -> None:
    ax.step(log.t[rows], log.collisions[rows], where="post", color="tab:red",
            label="collisions")
    ax.yaxis.set_major_locator(MaxNLocator(integer=True))
    ax.set_ylabel("collisions")


SAFETY_KINDS = ("obstacle", "speed limit", "joystick", "stale command")
"""How the safety filter's reasons begin, one band each in the ``safety`` panel."""


def _safety(log: RunLog, rows: np.ndarray, ax: Axes) -> None:
    """One band per kind of the safety filter's changes (the RunLog's ``safety``
    channel), filled where it changed the command for that reason."""
    reasons = log.channels.get("safety")
    if reasons is None:
        reasons = np.full(len(log), "")
    for k, kind in enumerate(SAFETY_KINDS):
        hit = np.char.find(reasons[rows].astype(str), kind) >= 0
        ax.fill_between(log.t[rows], k, k + 0.8, where=hit, step="post", alpha=0.5,
                        label=kind)
    ax.set_yticks(np.arange(len(SAFETY_KINDS)) + 0.4, SAFETY_KINDS, fontsize=7)
    ax.set_ylim(-0.2, len(SAFETY_KINDS))
    ax.set_ylabel("filter")


SIGNALS: dict[str, Callable[[RunLog, np.ndarray, Axes], None]] = {
    "v": _v, "w": _w, "pots": _pots, "sonar": _sonar, "ir": _ir, "ticks": _ticks,
    "gyro": _gyro, "collisions": _collisions, "safety": _safety,
}


def plot_signals(log: RunLog, names: Sequence[str] = ("v", "w", "pots", "sonar"),
                 max_points: int = 4000, figsize: tuple[float, float] | None = None) -> Figure:
    """Time plots of ``names``, one panel each, sharing the time axis.

    Names: ``v`` and ``w`` (true speed and turn rate, or from the encoders on a real
    chair, with the commanded Twist dashed and, where the safety filter changed it, the
    wanted one dotted), ``pots`` (bytes on the pot, sent ones dashed), ``sonar``, ``ir``,
    ``ticks``, ``gyro``, ``collisions``, ``safety`` (where the filter changed the command,
    by kind). Long logs are
    thinned to ``max_points`` samples. Returns the Figure.
    """
    import matplotlib.pyplot as plt

    names = [names] if isinstance(names, str) else list(names)
    unknown = [n for n in names if n not in SIGNALS]
    if unknown or not names:
        raise ValueError(f"unknown signal(s) {unknown or names}; choose from {', '.join(SIGNALS)}")
    if len(log) == 0:
        raise ValueError("the log is empty: nothing to plot")
    size = figsize or (8.0, 1.2 + 1.6 * len(names))
    fig, axes = plt.subplots(len(names), 1, sharex=True, figsize=size, layout="constrained",
                             squeeze=False)
    rows = decimate(len(log), max_points)
    for name, ax in zip(names, axes[:, 0]):
        SIGNALS[name](log, rows, ax)
        ax.grid(True, color="0.9", linewidth=0.6)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    axes[-1, 0].set_xlabel("t (s)")
    return fig


def plot_safety_filter(filtered: RunLog, bare: RunLog | None = None,
                       gap: Callable[[RunLog], np.ndarray] | None = None,
                       gap_label: str = "gap (m)", title: str | None = None) -> Figure:
    """The safety filter at work on one run, and the same controller bare if given.

    Top: the speed the controller wanted, the speed the filter sent and the true speed
    (the bare run's true speed in grey); middle, with ``gap``: ``gap(log)`` per row for
    each run (m, e.g. from the chair's front edge to a wall), contacts marked; bottom:
    where the filter changed the command, by kind (the ``safety`` channel). Returns the
    Figure.
    """
    import matplotlib.pyplot as plt

    if len(filtered) == 0:
        raise ValueError("the log is empty: nothing to plot")
    runs = {"through the filter": filtered} | ({"bare": bare} if bare is not None else {})
    panels = 2 + (gap is not None)
    fig, axes = plt.subplots(panels, 1, sharex=True, figsize=(8.5, 2.0 + 1.6 * panels),
                             layout="constrained", squeeze=False,
                             gridspec_kw={"height_ratios": [3] + [2] * (gap is not None) + [1]})
    ax_v, ax_why = axes[0, 0], axes[-1, 0]
    ax_v.plot(filtered.t, filtered.wanted_twist[:, 0], "k--", linewidth=1, label="wanted")
    ax_v.plot(filtered.t, filtered.cmd_twist[:, 0], color="tab:orange",
              label="sent by the filter")
    colours = {"through the filter": "tab:blue", "bare": "0.55"}
    for name, log in runs.items():
        ax_v.plot(log.t, true_velocity(log)[0], color=colours[name], label=f"true, {name}")
        if gap is not None:
            ax_gap = axes[1, 0]
            ax_gap.plot(log.t, gap(log), color=colours[name], label=name)
            touched = np.flatnonzero(np.diff(log.collisions, prepend=0) > 0)
            ax_gap.plot(log.t[touched], gap(log)[touched], "x", color="tab:red",
                        markersize=9, mew=2, label="contact" if len(touched) else None)
            ax_gap.set_ylabel(gap_label)
    ax_v.set_ylabel("v (m/s)")
    ax_v.set_title(title or "the safety filter: wanted, sent and true speed")
    _safety(filtered, np.arange(len(filtered)), ax_why)
    ax_why.set_xlabel("t (s)")
    for ax in axes[:, 0]:
        ax.grid(True, color="0.9", linewidth=0.6)
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    return fig
