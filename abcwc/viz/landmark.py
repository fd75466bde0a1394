"""The geometry of going to a landmark (thesis eqns 11-12, figure 38), drawn: the
distance and heading error to a goal, and why the heading error must be wrapped."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from abcwc.geometry import wrap_angle
from abcwc.types import Pose2D
from abcwc.viz.scene import plot_chair


def _angle_arc(ax: Axes, centre: tuple[float, float], radius: float, start: float, end: float,
               color: str, label: str | None = None,
               label_at: tuple[float, float] | None = None, **style: object) -> None:
    """An arc from angle ``start`` to ``end`` (rad) about ``centre``, its arrow at ``end``,
    with ``label`` at ``label_at`` (x, y)."""
    a = np.linspace(start, end, 80)
    x, y = centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)
    ax.plot(x[:-2], y[:-2], color=color, **style)
    ax.annotate("", xy=(x[-1], y[-1]), xytext=(x[-4], y[-4]),
                arrowprops=dict(arrowstyle="-|>", color=color, lw=1.2))
    if label:
        ax.text(*label_at, label, color=color, ha="center", va="center", fontsize=11)


def plot_distance_and_bearing() -> Figure:
    """Two panels: eqns 11-12 for one pose and goal (rho, the bearing atan2 and the heading
    error alpha), and a goal behind the chair across the +-180 degree line, where alpha
    unwrapped is the long way round."""
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12.5, 5.2), layout="constrained",
                                   gridspec_kw=dict(width_ratios=[1.25, 1]))

    # left: eqns 11-12 for one pose and goal
    p0, goal = Pose2D(1.0, 1.0, math.radians(15)), (6.5, 5.0)
    bearing = math.atan2(goal[1] - p0.y, goal[0] - p0.x)
    plot_chair(p0, ax1)
    ax1.plot(*goal, marker="*", markersize=18, color="tab:red", zorder=9)
    ax1.text(goal[0] - 0.15, goal[1] + 0.3, r"goal $P_d = (x_d, y_d)$", fontsize=11, ha="center")
    ax1.text(p0.x + 0.1, p0.y - 0.65, r"chair $P_0 = (x_0, y_0, \theta_0)$", fontsize=11,
             ha="center")
    ax1.plot([p0.x, goal[0]], [p0.y, goal[1]], color="tab:red", lw=1.5, ls="--")
    ax1.text(3.4, 3.05, r"$\rho$", color="tab:red", fontsize=16)
    ax1.plot([p0.x, goal[0], goal[0]], [p0.y, p0.y, goal[1]], color="0.55", lw=1, ls=":")
    ax1.text((p0.x + goal[0]) / 2 + 1.2, p0.y - 0.3, r"$x_d - x_0$", color="0.35", ha="center")
    ax1.text(goal[0] + 0.12, 4.1, r"$y_d - y_0$", color="0.35")
    reach = 5.2
    ax1.plot([p0.x, p0.x + reach * math.cos(p0.theta)], [p0.y, p0.y + reach * math.sin(p0.theta)],
             color="tab:blue", lw=1.5)
    ax1.text(p0.x + reach * math.cos(p0.theta) + 0.1, p0.y + reach * math.sin(p0.theta), "heading",
             color="tab:blue", va="center")
    _angle_arc(ax1, (p0.x, p0.y), 1.4, 0.0, p0.theta, "tab:blue", r"$\theta_0$", (2.65, 1.22))
    _angle_arc(ax1, (p0.x, p0.y), 3.3, 0.0, bearing, "0.4")
    ax1.annotate(r"atan2$(y_d - y_0,\ x_d - x_0)$", xytext=(5.1, 2.75), color="0.3", fontsize=11,
                 xy=(p0.x + 3.3 * math.cos(0.5), p0.y + 3.3 * math.sin(0.5)),
                 arrowprops=dict(arrowstyle="-", color="0.5", lw=0.8))
    _angle_arc(ax1, (p0.x, p0.y), 2.4, p0.theta, bearing, "tab:green", r"$\alpha$", (3.55, 2.15))
    ax1.set(xlim=(0.0, 8.4), ylim=(0.0, 5.6), xlabel="x (m)", ylabel="y (m)",
            title=f"eqns 11-12: here rho = {math.hypot(goal[0] - p0.x, goal[1] - p0.y):.2f} m, "
                  f"alpha = {math.degrees(bearing - p0.theta):+.1f}°")
    ax1.set_aspect("equal")
    ax1.grid(True, color="0.92")

    # right: why alpha must be wrapped
    p1 = Pose2D(0.0, 0.0, math.radians(170))
    goal2 = (3.0 * math.cos(math.radians(-170)), 3.0 * math.sin(math.radians(-170)))
    plot_chair(p1, ax2)
    ax2.plot(*goal2, marker="*", markersize=18, color="tab:red", zorder=9)
    ax2.plot([0, goal2[0]], [0, goal2[1]], color="tab:red", lw=1.2, ls="--")
    ax2.plot([0, 3.0 * math.cos(p1.theta)], [0, 3.0 * math.sin(p1.theta)], color="tab:blue", lw=1.2)
    ax2.text(goal2[0] + 0.1, goal2[1] - 0.35, "goal: bearing -170°", color="tab:red", ha="center")
    ax2.text(-2.9, 0.85, "heading 170°", color="tab:blue", ha="center")
    raw = math.radians(-170) - p1.theta
    wrapped = wrap_angle(raw)
    _angle_arc(ax2, (0, 0), 1.1, p1.theta, p1.theta + raw, "tab:orange",
              f"unwrapped: {math.degrees(raw):.0f}°\n(the long way round)", (1.75, -1.45), ls="--")
    _angle_arc(ax2, (0, 0), 2.2, p1.theta, p1.theta + wrapped, "tab:green",
              f"wrapped: {math.degrees(wrapped):+.0f}°", (-2.75, -0.05))
    ax2.set(xlim=(-3.6, 2.6), ylim=(-2.2, 2.2), xlabel="x (m)", ylabel="y (m)",
            title="one direction, two turns: wrap alpha into (-180°, 180°]")
    ax2.set_aspect("equal")
    ax2.grid(True, color="0.92")
    return fig
