"""Pictures of a robot description and of a frame tree.

:func:`plot_description` draws a URDF's shapes from above (x forward, y left) or from
the side (x forward, z up), each shape's outline the projection of its corners, and
marks the sensors' frames with their x axes. :func:`plot_frame_tree` draws which frame
hangs from which, as ``view_frames`` does for tf2.
"""

from __future__ import annotations

import math

import numpy as np
from matplotlib.axes import Axes
from matplotlib.patches import Circle, Polygon
from scipy.spatial import ConvexHull

from abcwc.description import RobotDescription, Shape
from abcwc.frames import FrameTree
from abcwc.params import ChairParams
from abcwc.viz._common import DEPTH_COLOR, IR_COLOR, LIDAR_COLOR, SONAR_COLOR, new_axes

SHAPE_COLOURS = {"box": "0.80", "cylinder": "0.35", "sphere": "0.55"}
SENSOR_COLOUR = "tab:red"


def _corners(shape: Shape) -> np.ndarray:
    """(8, 3) corners of the shape's bounding box in its own frame."""
    if shape.kind == "box":
        half = np.array(shape.dimensions) / 2
    elif shape.kind == "cylinder":
        radius, length = shape.dimensions
        half = np.array([radius, radius, length / 2])
    else:
        half = np.full(3, shape.dimensions[0])
    signs = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    return signs * half


def plot_description(description: RobotDescription, ax: Axes | None = None,
                     view: str = "top", sensors: tuple[str, ...] | None = None,
                     label_sensors: bool = True) -> Axes:
    """Draw ``description``'s visual shapes seen from ``view`` ("top" or "side") in the
    root frame (m), and each frame of ``sensors`` (default: links named ``*_link``) as a
    dot with an arrow along its x axis."""
    if view not in ("top", "side"):
        raise ValueError(f"view must be 'top' or 'side', got {view!r}")
    ax = new_axes(ax, figsize=(6, 5))
    axes = (0, 1) if view == "top" else (0, 2)
    order = []
    for link in description.links.values():
        if link.visual is not None:
            pose = description.transform(link.name) @ link.visual.origin
            depth = pose[2, 3] if view == "top" else -pose[1, 3]
            order.append((depth, link, pose))
    for _, link, pose in sorted(order, key=lambda item: item[0]):
        shape = link.visual
        assert shape is not None
        colour = SHAPE_COLOURS[shape.kind]
        normal = 2 if view == "top" else 1  # the axis the view looks along
        if shape.kind == "sphere" or (shape.kind == "cylinder"
                                      and abs(pose[normal, 2]) > 0.99):
            patch = Circle((pose[axes[0], 3], pose[axes[1], 3]), shape.dimensions[0])
        else:
            corners = _corners(shape) @ pose[:3, :3].T + pose[:3, 3]
            flat = corners[:, axes]
            hull = ConvexHull(flat)
            patch = Polygon(flat[hull.vertices], closed=True)
        patch.set(facecolor=colour, edgecolor="k", linewidth=0.6, alpha=0.7)
        ax.add_patch(patch)
    names = sensors if sensors is not None else tuple(
        name for name in description.links if name.endswith("_link"))
    for name in names:
        pose = description.transform(name)
        origin, x_axis = pose[axes, 3], pose[axes, 0]
        ax.plot(*origin, "o", color=SENSOR_COLOUR, markersize=4)
        if np.hypot(*x_axis) > 1e-6:
            ax.annotate("", origin + 0.08 * x_axis, origin,
                        arrowprops={"arrowstyle": "->", "color": SENSOR_COLOUR})
        if label_sensors:
            ax.annotate(name, origin, xytext=(4, 4), textcoords="offset points", fontsize=7,
                        color=SENSOR_COLOUR)
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x (m), forward")
    ax.set_ylabel("y (m), left" if view == "top" else "z (m), up")
    ax.set_title(f"{description.name}: {'from above' if view == 'top' else 'from the side'}")
    return ax


def plot_frame_tree(tree: FrameTree, ax: Axes | None = None, root: str | None = None) -> Axes:
    """Draw the frames as a tree, each parent above its children (tf2's view_frames)."""
    ax = new_axes(ax, figsize=(10, 4))
    roots = [f for f in tree.frames if tree.parent(f) is None]
    top = root if root is not None else roots[0]
    positions: dict[str, tuple[float, int]] = {}
    next_leaf = [0.0]

    def place(frame: str, depth: int) -> float:
        children = tree.children(frame)
        if not children:
            x = next_leaf[0]
            next_leaf[0] += 1.0
        else:
            xs = [place(child, depth + 1) for child in children]
            x = (min(xs) + max(xs)) / 2
        positions[frame] = (x, depth)
        return x

    place(top, 0)
    for frame, (x, depth) in positions.items():
        parent = tree.parent(frame)
        if parent in positions:
            px, pdepth = positions[parent]
            ax.plot([px, x], [-pdepth, -depth], "-", color="0.6", linewidth=0.8, zorder=1)
    for frame, (x, depth) in positions.items():
        leaf = not tree.children(frame)
        ax.text(x, -depth, frame, ha="center", va="top" if leaf else "center", fontsize=7,
                zorder=3, rotation=90 if leaf else 0,
                bbox={"boxstyle": "round,pad=0.25", "facecolor": "white",
                      "edgecolor": "0.3"})
    ax.set_xlim(-1, next_leaf[0])
    ax.set_ylim(-max(d for _, d in positions.values()) - 0.8, 0.6)
    ax.axis("off")
    return ax


def plot_vertical_coverage(params: ChairParams, ax: Axes | None = None, reach: float = 4.0,
                           objects: list[tuple[float, float, float, float, str]] | None = None
                           ) -> Axes:
    """What each forward range sensor sees in the vertical plane ahead of the chair (x
    forward from base_link, z up, m): the lidar's plane, the IR ranger's beam, the
    sonar's cone and the depth scan's band of rows, each from its mount and height over
    its ranges (cut at ``reach`` m); ``objects`` as ``(x0, x1, z0, z1, label)``
    rectangles."""
    from matplotlib.patches import Rectangle

    ax = new_axes(ax, figsize=(10, 3.5))
    sensors = (
        ("lidar", params.lidar, 0.0, LIDAR_COLOR),
        ("depth scan", params.depth_scan, params.depth_scan.vertical_half_angle, DEPTH_COLOR),
        ("sonar", params.sonar, params.sonar.vertical_half_angle, SONAR_COLOR),
    )
    for name, spec, half, colour in sensors:
        x0, z0 = spec.mount[0], spec.height
        near, far = spec.min_range, min(spec.max_range, reach)
        slope = math.tan(half)
        xs = np.array([near, far, far, near])
        zs = np.array([near * slope, far * slope, -far * slope, -near * slope])
        if half > 0:
            ax.add_patch(Polygon(np.column_stack([x0 + xs, z0 + zs]), closed=True,
                                 facecolor=colour, alpha=0.25, edgecolor=colour,
                                 label=f"{name} ({spec.height:.2f} m)"))
        else:
            ax.plot([x0 + near, x0 + far], [z0, z0], color=colour, linewidth=2,
                    label=f"{name} ({spec.height:.2f} m)")
        ax.plot([x0, x0 + near], [z0, z0], ":", color=colour, linewidth=1)
    ir_x = float(params.ir.mounts[0, 0])
    ax.plot([ir_x + params.ir.min_range, ir_x + min(params.ir.max_range, reach)],
            [params.ir.height] * 2, color=IR_COLOR, linewidth=2,
            label=f"IR ranger ({params.ir.height:.2f} m)")
    for x0, x1, z0, z1, label in objects or []:
        ax.add_patch(Rectangle((x0, z0), x1 - x0, z1 - z0, facecolor="0.45",
                               edgecolor="k", linewidth=0.6))
        ax.annotate(label, (x1, z1), xytext=(3, 3), textcoords="offset points", fontsize=8)
    front = params.length - params.axle_to_rear
    ax.add_patch(Rectangle((-params.axle_to_rear, 0.0), params.length, params.height,
                           facecolor="none", edgecolor="0.3", linestyle="--"))
    ax.annotate("chair", (front, params.height), xytext=(3, -10), textcoords="offset points",
                fontsize=8, color="0.3")
    ax.set_xlim(-params.axle_to_rear - 0.1, reach + 0.5)
    ax.set_ylim(0.0, 1.6)
    ax.set_xlabel("x ahead of base_link (m)")
    ax.set_ylabel("height (m)")
    ax.legend(loc="upper right", fontsize=8)
    return ax
