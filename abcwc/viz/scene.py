"""Top-down plots of the world, the chair, its path and the people around it.

Every function draws on ``ax`` (a new figure when it is None) and returns the Axes,
except :func:`plot_run`, which returns the Figure. Nothing calls ``plt.show``.
Coordinates are the world (map) frame in metres, x right and y up, so a heading of
0 points right and positive angles turn counter-clockwise (ROS REP 103).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection, PatchCollection
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure
from matplotlib.patches import Circle, Polygon

from abcwc.geometry import transform_points
from abcwc.log import RunLog
from abcwc.params import ChairParams, default_params
from abcwc.sim.world import World
from abcwc.types import Pose2D
from abcwc.viz._common import (
    CHAIR_COLOR,
    COLLISION_COLOR,
    PEOPLE_COLOR,
    PLACE_COLOR,
    WALL_COLOR,
    PoseLike,
    as_pose,
    decimate,
    new_axes,
    poses_of,
    require_poses,
    resolve_world,
    world_figsize,
    zoom_to,
)

WORLD_MARGIN = 0.5  # m of floor shown beyond the outermost walls


def plot_world(world: World | str, ax: Axes | None = None, places: bool = True,
               color: str = WALL_COLOR, linewidth: float = 2.0) -> Axes:
    """Draw the walls (one LineCollection) and, with ``places``, the named places.

    The axes get equal aspect, metre labels, a light grid and the world's name as title.
    ``world`` is a World or a world name such as ``"lab"``.
    """
    world = resolve_world(world)
    ax = new_axes(ax, world_figsize(world.bounds))
    walls = LineCollection(world.walls.reshape(-1, 2, 2), colors=color, linewidths=linewidth,
                           capstyle="round", zorder=2)
    ax.add_collection(walls)
    if places:
        _draw_places(ax, world.places)
    xmin, ymin, xmax, ymax = world.bounds
    ax.set_xlim(xmin - WORLD_MARGIN, xmax + WORLD_MARGIN)
    ax.set_ylim(ymin - WORLD_MARGIN, ymax + WORLD_MARGIN)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.grid(True, color="0.9", linewidth=0.6)
    ax.set_axisbelow(True)
    ax.set_title(world.name)
    return ax


def _draw_places(ax: Axes, places: dict[str, Pose2D]) -> None:
    """A small dot per place with its name beside it."""
    xy = np.array([[p.x, p.y] for p in places.values()])
    ax.scatter(xy[:, 0], xy[:, 1], s=10, color=PLACE_COLOR, marker="o", zorder=3)
    for name, (x, y) in zip(places, xy):
        ax.annotate(name, (x, y), xytext=(4, 3), textcoords="offset points", fontsize=7,
                    color=PLACE_COLOR, zorder=3)


def chair_outlines(params: ChairParams | None = None) -> dict[str, np.ndarray]:
    """The chair's drawing in base_link (m): ``body``, ``wheel_left/right``, ``arrow``.

    The drive wheels sit on the axle (x = 0) at +-wheel_base/2, as long as the drive
    wheel's diameter and as wide as the gap between the wheel base and the chair's
    width; the heading arrow runs from base_link towards the front edge.
    """
    p = params or default_params()
    radius = p.drive_wheel_diameter / 2
    tyre = max(p.width - p.wheel_base, 0.03)
    outlines = {"body": np.array(p.footprint, dtype=float)}
    for name, side in (("wheel_left", 1.0), ("wheel_right", -1.0)):
        y0 = side * p.wheel_base / 2
        outlines[name] = np.array([[-radius, y0 - tyre / 2], [radius, y0 - tyre / 2],
                                   [radius, y0 + tyre / 2], [-radius, y0 + tyre / 2]])
    tip = 0.9 * (p.length - p.axle_to_rear)
    head, shaft, half_head = 0.35 * tip, 0.06 * p.width, 0.2 * p.width
    outlines["arrow"] = np.array([
        [0.0, -shaft / 2], [tip - head, -shaft / 2], [tip - head, -half_head], [tip, 0.0],
        [tip - head, half_head], [tip - head, shaft / 2], [0.0, shaft / 2]])
    return outlines


class ChairArtist:
    """The chair drawn on an Axes (body, wheels, heading arrow); move it with
    :meth:`update`. :func:`plot_chair` and the animations use it."""

    def __init__(self, ax: Axes, params: ChairParams | None = None, color: str = CHAIR_COLOR,
                 label: str | None = None, alpha: float = 0.35, zorder: float = 6):
        self.outlines = chair_outlines(params)
        styles = {
            "body": dict(facecolor=to_rgba(color, alpha), edgecolor=color, linewidth=1.5,
                         label=label),
            "wheel_left": dict(facecolor="0.15", edgecolor="0.15"),
            "wheel_right": dict(facecolor="0.15", edgecolor="0.15"),
            "arrow": dict(facecolor=color, edgecolor="white", linewidth=0.5),
        }
        self.patches = {}
        for name, outline in self.outlines.items():
            patch = Polygon(outline, closed=True, zorder=zorder, **styles[name])
            self.patches[name] = ax.add_patch(patch)

    def update(self, pose: PoseLike) -> None:
        """Place the chair at ``pose`` (Pose2D or x, y, theta)."""
        for name, outline in self.outlines.items():
            self.patches[name].set_xy(transform_points(as_pose(pose), outline))

    def set_visible(self, visible: bool) -> None:
        """Show or hide every part of the chair."""
        for patch in self.patches.values():
            patch.set_visible(visible)

    @property
    def artists(self) -> list[Polygon]:
        """The patches, for an animation's update function."""
        return list(self.patches.values())


def plot_chair(pose: PoseLike, ax: Axes | None = None, params: ChairParams | None = None,
               color: str = CHAIR_COLOR, label: str | None = None) -> Axes:
    """Draw the chair to scale at ``pose``: footprint, drive wheels and heading arrow."""
    ax = new_axes(ax)
    ChairArtist(ax, params, color=color, label=label).update(pose)
    ax.set_aspect("equal", adjustable="box")
    ax.autoscale_view()
    return ax


def plot_trajectory(log_or_poses: RunLog | np.ndarray | Sequence[Pose2D],
                    ax: Axes | None = None, label: str | None = None,
                    color: str | None = None, max_points: int = 4000, markers: bool = True,
                    **line_kwargs: object) -> Axes:
    """Draw a path (a RunLog's true poses, an (N, 3) array or a list of Pose2D).

    Long paths are thinned to ``max_points`` vertices. With ``markers`` the start is
    a hollow circle and the end a filled square in the line's colour.
    """
    poses = require_poses(poses_of(log_or_poses), "path")
    ax = new_axes(ax)
    rows = decimate(len(poses), max_points)
    (line,) = ax.plot(poses[rows, 0], poses[rows, 1], color=color, label=label,
                      linewidth=line_kwargs.pop("linewidth", 1.5), zorder=4, **line_kwargs)
    finite = np.flatnonzero(np.isfinite(poses[:, :2]).all(axis=1))
    if markers:
        first, last = poses[finite[0]], poses[finite[-1]]
        ax.plot(*first[:2], marker="o", markersize=7, markerfacecolor="white",
                markeredgecolor=line.get_color(), markeredgewidth=1.5, zorder=7)
        ax.plot(*last[:2], marker="s", markersize=5, color=line.get_color(), zorder=5)
    ax.set_aspect("equal", adjustable="box")
    return ax


def plot_people(chair_or_circles: object, ax: Axes | None = None, color: str = PEOPLE_COLOR,
                label: str | None = "people") -> Axes:
    """Draw people as discs: from a simulated chair's walkers or an (M, 3) x, y, r array."""
    ax = new_axes(ax)
    walkers = getattr(chair_or_circles, "walkers", None)
    if walkers is not None:
        circles = np.array([w.circle for w in walkers]).reshape(-1, 3)
    else:
        circles = np.asarray(chair_or_circles, dtype=float).reshape(-1, 3)
    if len(circles):
        discs = [Circle((x, y), r) for x, y, r in circles]
        ax.add_collection(PatchCollection(discs, facecolor=to_rgba(color, 0.5),
                                          edgecolor=color, zorder=5, label=label))
    return ax


def collision_rows(log: RunLog) -> np.ndarray:
    """Rows of ``log`` where its collision count goes up."""
    counts = np.asarray(log.collisions)
    return np.flatnonzero(np.diff(counts) > 0) + 1


def plot_run(log: RunLog, world: World | str | None = None, ax: Axes | None = None,
             params: ChairParams | None = None, label: str | None = "path",
             scan: bool = True, zoom: float | None = None, title: str | None = None) -> Figure:
    """One figure of a run: the world, the path, the chair at its last pose, collisions.

    ``world`` defaults to the one named in the log. With ``scan`` the run's last
    lidar (or depth-camera) scan is drawn too. ``zoom`` (m) limits the view to the
    path plus that margin. Returns the Figure (``fig.savefig(...)`` to keep it).
    """
    from abcwc.viz.sensors import plot_log_scan

    world = resolve_world(world, log)
    poses = require_poses(poses_of(log))
    ax = plot_world(world, ax)
    plot_trajectory(poses, ax, label=label, color=CHAIR_COLOR)
    finite = np.flatnonzero(np.isfinite(poses[:, :2]).all(axis=1))
    plot_chair(poses[finite[-1]], ax, params, label="chair (end)")
    if scan:
        plot_log_scan(log, len(log) - 1, ax, params)
    hits = collision_rows(log)
    if len(hits):
        ax.scatter(poses[hits, 0], poses[hits, 1], marker="X", s=70, color=COLLISION_COLOR,
                   edgecolor="white", linewidth=0.6, zorder=8,
                   label=f"collision ({len(hits)})")
    if zoom is not None:
        zoom_to(ax, poses, zoom)
    ax.set_title(title if title is not None else f"{world.name}: {log.summary()}", fontsize=10)
    ax.legend(loc="best", fontsize=8, framealpha=0.85)
    return ax.figure
