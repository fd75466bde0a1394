"""Costmaps drawn the way RViz shows them (its "costmap" colour scheme), and DWA's
trajectories over them.

Free cells are left clear, inflated cells run from blue (cheap) through red (costly),
``INSCRIBED`` cells are cyan, ``LETHAL`` cells magenta and unknown cells grey, over the
map frame in metres.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import ListedColormap

from abcwc.mapping.grid import OccupancyGrid
from abcwc.navigation.costmap import INSCRIBED, LETHAL, NO_INFORMATION, Costmap, Footprint
from abcwc.navigation.dwa import DwaResult
from abcwc.viz._common import new_axes


def costmap_colours() -> ListedColormap:
    """256 colours, one per cost byte, after RViz's costmap scheme."""
    colours = np.zeros((256, 4))
    ramp = np.linspace(0.0, 1.0, INSCRIBED - 1)[:, None]
    colours[1:INSCRIBED] = np.hstack([ramp, np.zeros_like(ramp), 1.0 - ramp,
                                      np.full_like(ramp, 0.55)])  # blue -> red
    colours[INSCRIBED] = (0.0, 1.0, 1.0, 0.8)  # cyan
    colours[LETHAL] = (1.0, 0.0, 1.0, 0.9)  # magenta
    colours[NO_INFORMATION] = (0.6, 0.6, 0.6, 0.5)  # grey
    return ListedColormap(colours, name="costmap")


def plot_costmap(costmap: Costmap, ax: Axes | None = None) -> Axes:
    """Draw ``costmap`` (axis-aligned, yaw 0) in the map frame (m); returns the Axes."""
    if abs(costmap.origin.theta) > 1e-12:
        raise ValueError("plot_costmap draws axis-aligned costmaps (origin yaw 0)")
    ax = new_axes(ax)
    x0, y0 = costmap.origin.x, costmap.origin.y
    extent = (x0, x0 + costmap.width * costmap.resolution,
              y0, y0 + costmap.height * costmap.resolution)
    ax.imshow(costmap.cost, cmap=costmap_colours(), vmin=0, vmax=255, origin="lower",
              extent=extent, interpolation="nearest")
    ax.set(xlabel="x (m)", ylabel="y (m)", aspect="equal")
    return ax


def plot_occupancy(grid: OccupancyGrid, ax: Axes | None = None) -> Axes:
    """Draw an occupancy grid's p(occupied) (axis-aligned) as map_server's image does:
    white free, black occupied, grey unknown (p = 0.5)."""
    if abs(grid.origin.theta) > 1e-12:
        raise ValueError("plot_occupancy draws axis-aligned grids (origin yaw 0)")
    ax = new_axes(ax)
    x0, y0 = grid.origin.x, grid.origin.y
    extent = (x0, x0 + grid.width * grid.resolution, y0, y0 + grid.height * grid.resolution)
    ax.imshow(grid.probability(), cmap="gray_r", vmin=0.0, vmax=1.0, origin="lower",
              extent=extent, interpolation="nearest")
    ax.set(xlabel="x (m)", ylabel="y (m)", aspect="equal")
    return ax


def plot_footprint(footprint: Footprint, ax: Axes | None = None) -> Axes:
    """The chair's footprint (base_link, m) with its inscribed and circumscribed circles
    (costmap_2d's two radii) and the base_link origin."""
    from matplotlib.patches import Circle, Polygon

    ax = new_axes(ax, (4.5, 4.0))
    ax.add_patch(Polygon(footprint.polygon, closed=True, facecolor=(0.2, 0.4, 0.8, 0.3),
                         edgecolor="tab:blue", linewidth=1.5, label="footprint"))
    for radius, colour, name in ((footprint.inscribed_radius, "tab:cyan", "inscribed"),
                                 (footprint.circumscribed_radius, "tab:red",
                                  "circumscribed")):
        ax.add_patch(Circle((0.0, 0.0), radius, fill=False, edgecolor=colour, linewidth=1.5,
                            label=f"{name} {radius:.2f} m"))
    ax.plot([0.0], [0.0], "k+", markersize=10, label="base_link")
    reach = footprint.circumscribed_radius * 1.15
    ax.set(xlim=(-reach, reach), ylim=(-reach, reach), aspect="equal", xlabel="x (m)",
           ylabel="y (m)")
    ax.legend(loc="lower left", fontsize=8)
    return ax


def plot_dwa(result: DwaResult, ax: Axes | None = None, legend: bool = True) -> Axes:
    """One DWA decision: every sampled trajectory, the dropped ones grey and dashed, the
    others coloured by their cost (cheap green to dear red), the chosen one black."""
    ax = new_axes(ax)
    valid = np.flatnonzero(result.valid)
    for k in np.flatnonzero(~result.valid):
        ax.plot(result.poses[k, :, 0], result.poses[k, :, 1], color="0.6", linewidth=0.6,
                linestyle="--")
    if valid.size:
        costs = result.cost[valid]
        span = float(np.ptp(costs)) or 1.0
        colours = plt.get_cmap("RdYlGn_r")((costs - costs.min()) / span)
        for k, colour in zip(valid, colours):
            ax.plot(result.poses[k, :, 0], result.poses[k, :, 1], color=colour, linewidth=0.9)
    if result.best >= 0:
        ax.plot(result.poses[result.best, :, 0], result.poses[result.best, :, 1], "k-",
                linewidth=2.2, label=f"chosen (v {result.command.v:.2f} m/s, "
                                     f"w {result.command.w:.2f} rad/s)")
    if legend:
        ax.plot([], [], color="0.6", linestyle="--", label="dropped: would touch")
        ax.legend(loc="lower left", fontsize=8)
    ax.set(aspect="equal", xlabel="x (m)", ylabel="y (m)")
    return ax
