"""Small helpers shared by the plotting modules: axes, poses, decimation, worlds."""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes

from abcwc.log import RunLog
from abcwc.sim.world import World, load_world
from abcwc.types import Pose2D

PoseLike = Pose2D | Sequence[float] | np.ndarray

# Colours used across the plots, so a chair, its trail and its sensors match everywhere.
WALL_COLOR = "0.2"
PLACE_COLOR = "0.35"
CHAIR_COLOR = "tab:blue"
SONAR_COLOR = "tab:orange"
IR_COLOR = "tab:purple"
LIDAR_COLOR = "tab:green"
DEPTH_COLOR = "tab:cyan"
PEOPLE_COLOR = "tab:brown"
COLLISION_COLOR = "tab:red"


def new_axes(ax: Axes | None, figsize: tuple[float, float] = (8.0, 5.0)) -> Axes:
    """``ax`` itself, or the Axes of a new pyplot figure of ``figsize`` inches."""
    if ax is not None:
        return ax
    import matplotlib.pyplot as plt

    _, ax = plt.subplots(figsize=figsize, layout="constrained")
    return ax


def world_figsize(bounds: tuple[float, float, float, float], width: float = 8.0,
                  ) -> tuple[float, float]:
    """A figure size (inches) ``width`` wide whose height suits the world's aspect."""
    xmin, ymin, xmax, ymax = bounds
    aspect = (ymax - ymin + 1.0) / max(xmax - xmin + 1.0, 1e-9)
    return width, float(np.clip(width * aspect + 0.8, 3.0, 1.6 * width))


def as_pose(pose: PoseLike) -> tuple[float, float, float]:
    """``(x, y, theta)`` from a Pose2D or any 3-sequence; ValueError otherwise."""
    if isinstance(pose, Pose2D):
        return pose.x, pose.y, pose.theta
    values = np.asarray(pose, dtype=float).ravel()
    if values.shape != (3,):
        raise ValueError(f"pose must be a Pose2D or (x, y, theta), got shape {values.shape}")
    return float(values[0]), float(values[1]), float(values[2])


def decimate(n: int, max_points: int) -> np.ndarray:
    """Row indices that thin ``n`` rows to at most ``max_points``, keeping the last."""
    if n <= max_points:
        return np.arange(n)
    step = math.ceil((n - 1) / max(max_points - 1, 1))
    return np.arange(n - 1, -1, -step)[::-1]


def poses_of(log_or_poses: RunLog | np.ndarray | Sequence[Pose2D]) -> np.ndarray:
    """An (N, 3) float array of poses from a RunLog, an array or a list of Pose2D."""
    if isinstance(log_or_poses, RunLog):
        poses = np.asarray(log_or_poses.pose, dtype=float)
    elif len(log_or_poses) and isinstance(log_or_poses[0], Pose2D):
        poses = np.array([as_pose(p) for p in log_or_poses])
    else:
        poses = np.asarray(log_or_poses, dtype=float)
    if poses.ndim != 2 or poses.shape[1] != 3:
        raise ValueError(f"poses must be an (N, 3) array of x, y, theta; got shape {poses.shape}")
    return poses


def require_poses(poses: np.ndarray, what: str = "log") -> np.ndarray:
    """``poses`` if any row is finite; else a ValueError saying why (a real-chair log)."""
    if len(poses) == 0:
        raise ValueError(f"the {what} is empty: nothing to plot")
    if not np.isfinite(poses[:, :2]).any():
        raise ValueError(f"the {what} has no ground-truth pose (a real-chair log?); "
                         "plot an estimate instead, e.g. plot_trajectory(odometry_poses)")
    return poses


def resolve_world(world: World | str | None, log: RunLog | None = None) -> World:
    """A World from a World, a world name, or the name recorded in ``log.meta``."""
    if isinstance(world, World):
        return world
    if world is None and log is not None and "world" in log.meta:
        world = str(log.meta["world"])
    if world is None:
        raise ValueError("no world given and the log does not name one; pass world=chair.world"
                         " or a world name such as 'lab'")
    return load_world(world)


def zoom_to(ax: Axes, poses: np.ndarray, margin: float) -> None:
    """Limit the view to the finite poses' extent plus ``margin`` metres each side."""
    finite = poses[np.isfinite(poses[:, :2]).all(axis=1)]
    if len(finite) == 0:
        return
    (xmin, ymin), (xmax, ymax) = finite[:, :2].min(axis=0), finite[:, :2].max(axis=0)
    ax.set_xlim(xmin - margin, xmax + margin)
    ax.set_ylim(ymin - margin, ymax + margin)
