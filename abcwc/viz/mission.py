"""The mission's state machine, drawn from its rule, and its states over a run."""

from __future__ import annotations

from collections.abc import Callable, Sequence

from matplotlib.axes import Axes
from matplotlib.patches import Rectangle

from abcwc.behaviours.base import Status
from abcwc.behaviours.mission import ERRAND_STATES, MissionState, Situation, next_state
from abcwc.viz._common import new_axes

__all__ = ["PROBES", "plot_state_machine", "plot_timeline", "probe_rule"]

_RUNNING = Status.RUNNING
_ALL = tuple(MissionState)
_ON_AN_ERRAND = (*ERRAND_STATES, MissionState.FOLLOWING)
_NO_ERRAND = tuple(state for state in MissionState if state not in _ON_AN_ERRAND)
PROBES: dict[str, tuple[Situation, tuple[MissionState, ...]]] = {
    "joystick": (Situation(joystick=True), _ALL),
    "go to": (Situation(command="go to", status=_RUNNING), _ALL),
    "go to, no way": (Situation(command="go to", status=Status.FAILED, failure="no path"),
                      _ALL),
    "follow": (Situation(command="follow", status=_RUNNING), _ALL),
    "stop": (Situation(command="stop"), _ALL),
    "arrived": (Situation(status=Status.SUCCEEDED), _ON_AN_ERRAND),
    "failed": (Situation(status=Status.FAILED, failure="stuck"), _ON_AN_ERRAND),
    "lost": (Situation(status=_RUNNING, lost=True), _ON_AN_ERRAND),
    "waiting": (Situation(status=_RUNNING, waiting=True), _ON_AN_ERRAND),
    "blocked": (Situation(status=_RUNNING, waiting=True, blocked=True), _ON_AN_ERRAND),
    "found / clear": (Situation(status=_RUNNING), _ON_AN_ERRAND),
    "released": (Situation(), _NO_ERRAND),
}
"""Named situations to probe a rule with, and the states to ask it in: one of each
thing the mission can see (the errand's news only on an errand; a quiet period with no
errand, such as the joystick let go, only without one)."""

_PLACES = {MissionState.IDLE: (0.0, 1.0), MissionState.NAVIGATING: (2.0, 2.0),
           MissionState.WAITING: (3.6, 3.2), MissionState.LOCALISING: (3.6, 0.8),
           MissionState.ARRIVED: (6.6, 2.8), MissionState.FAILED: (6.6, 0.6),
           MissionState.FOLLOWING: (2.0, -0.6), MissionState.MANUAL_OVERRIDE: (0.0, 3.0)}
_GROUP = (1.2, 0.35, 3.3, 3.3)  # x, y, width, height of the box round ERRAND_STATES


def probe_rule(rule: Callable = next_state,
               probes: dict[str, tuple[Situation, tuple[MissionState, ...]]] = PROBES
               ) -> dict[tuple[MissionState, MissionState], list[str]]:
    """``{(before, after): [the probes that make it]}``: ``rule`` asked with every probe
    in its states (what it answers None to is left out)."""
    edges: dict[tuple[MissionState, MissionState], list[str]] = {}
    for name, (situation, states) in probes.items():
        for state in states:
            decided = rule(state, situation)
            if decided is not None:
                edges.setdefault((state, MissionState(decided[0])), []).append(name)
    return edges


def plot_state_machine(rule: Callable = next_state, ax: Axes | None = None) -> Axes:
    """The states as boxes and ``rule``'s transitions as labelled arrows, found by
    :func:`probe_rule`. A probe that leads to one state from every other state (a
    command, the joystick) is written under the drawing, and one that leads from each
    state of an errand to the same state is drawn once, from the box round them."""
    ax = new_axes(ax, (10.0, 5.5))
    edges = probe_rule(rule)
    everywhere, grouped = {}, {}
    for name in PROBES:
        made = {(before, after) for (before, after), names in edges.items() if name in names}
        targets = {after for _, after in made}
        if len(targets) == 1 and {b for b, _ in made} >= set(MissionState) - targets:
            everywhere[name] = next(iter(targets))
            continue
        for target in targets - set(ERRAND_STATES):
            if all((state, target) in made for state in ERRAND_STATES):
                grouped.setdefault(target, []).append(name)
    gx, gy, gw, gh = _GROUP
    ax.add_patch(Rectangle((gx, gy), gw, gh, fill=False, linestyle="--", edgecolor="0.5"))
    ax.text(gx + 0.05, gy + gh - 0.12, "on an errand", fontsize=8, color="0.4", va="top")
    for target, names in grouped.items():
        _arrow(ax, (gx + gw, gy + gh / 2), _PLACES[target], names, shrink_from=0)
    for (before, after), names in edges.items():
        shown = [n for n in names if n not in everywhere
                 and not (before in ERRAND_STATES and n in grouped.get(after, ()))]
        if shown and before is not after:
            _arrow(ax, _PLACES[before], _PLACES[after], shown)
    for state, (x, y) in _PLACES.items():
        ax.text(x, y, state.value, ha="center", va="center", fontsize=9.5,
                bbox={"boxstyle": "round,pad=0.4", "fc": "lightyellow", "ec": "0.3"})
    note = "; ".join(f"{name}: to {state.value}" for name, state in everywhere.items())
    ax.text(3.3, -1.35, f"from every state: {note}" if note else "", ha="center",
            fontsize=8)
    ax.set(xlim=(-0.9, 7.5), ylim=(-1.6, 3.9))
    ax.set_axis_off()
    return ax


def _arrow(ax: Axes, start: tuple[float, float], end: tuple[float, float], names: list[str],
           shrink_from: float = 22) -> None:
    """A curved arrow from ``start`` to ``end`` with the probes' names by its middle."""
    (x0, y0), (x1, y1) = start, end
    ax.annotate("", (x1, y1), (x0, y0), arrowprops={
        "arrowstyle": "-|>", "color": "tab:blue", "shrinkA": shrink_from, "shrinkB": 22,
        "connectionstyle": "arc3,rad=0.18"})
    dx, dy = 0.09 * (y1 - y0), -0.09 * (x1 - x0)  # to the arc's middle, off the chord
    sideways = abs(dx) > abs(dy)  # the label goes on the arc's outer side
    ax.text((x0 + x1) / 2 + dx, (y0 + y1) / 2 + dy, ", ".join(names), fontsize=7.5,
            ha=("left" if dx > 0 else "right") if sideways else "center",
            va="center" if sideways else ("bottom" if dy > 0 else "top"),
            color="tab:blue", bbox={"boxstyle": "round,pad=0.15", "fc": "white",
                                    "ec": "none", "alpha": 0.85})


def plot_timeline(timeline: list[tuple[float, float, str]],
                  events: Sequence[tuple[float, str, float, float]] = (),
                  ax: Axes | None = None) -> Axes:
    """The mission's states over a run (:func:`~abcwc.behaviours.mission.mission_timeline`)
    as bars along the time axis, one row per state, and the ``events`` (t s, name, x m,
    y m; an errand's) as marked lines across them."""
    ax = new_axes(ax, (10.0, 2.8))
    rows = {state.value: k for k, state in enumerate(MissionState)}
    colours = dict(zip(rows, ("0.6", "tab:blue", "tab:orange", "tab:purple", "gold",
                              "tab:red", "tab:green", "black")))
    for start, end, state in timeline:
        ax.barh(rows[state], end - start, left=start, height=0.6, color=colours[state])
    for t, name, _, _ in events:
        ax.axvline(t, color="#d81b60", linewidth=1.2)
        ax.annotate(name, (t, -0.6), fontsize=8, color="#d81b60", annotation_clip=False)
    ax.set_yticks(list(rows.values()), list(rows))
    ax.invert_yaxis()
    ax.set_xlabel("t (s)")
    return ax
