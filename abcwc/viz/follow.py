"""Plots of the camera, the tags it reads and the follower's runs."""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from abcwc.experiments.follow_trial import FollowResult, HandOverDemo
from abcwc.experiments.tag_sweep import TagSweep
from abcwc.perception.tags import MIN_POSE_SIDE_PX, TagDetection
from abcwc.viz._common import new_axes


def plot_camera_view(pixels: np.ndarray, ax: Axes | None = None,
                     detections: Iterable[TagDetection] = ()) -> Axes:
    """The camera's image (grey or RGB) with each detected tag outlined and labelled
    (its id or text), in image pixels (u right, v down)."""
    ax = new_axes(ax, (7.0, 5.25))
    ax.imshow(pixels, cmap="gray" if pixels.ndim == 2 else None, vmin=0, vmax=255)
    for found in detections:
        outline = np.vstack([found.corners, found.corners[:1]])
        colour = "tab:orange" if found.kind == "aruco" else "tab:green"
        ax.plot(*outline.T, "-", color=colour, linewidth=1.5)
        ax.plot(*found.corners[0], "o", color=colour, markersize=4)  # the top-left
        label = f"ArUco {found.marker_id}" if found.kind == "aruco" else f"QR '{found.text}'"
        ax.annotate(label, found.corners[0], xytext=(0, -6), textcoords="offset points",
                    color=colour, fontsize=8, ha="left", va="bottom")
    ax.set(xlabel="u (px)", ylabel="v (px)")
    return ax


def plot_tag_sweep(sweep: TagSweep, axes: tuple[Axes, Axes] | None = None
                   ) -> tuple[Axes, Axes]:
    """Left: which code was read at each view's distance (ArUco, QR, QR on the image
    enlarged twice). Right: the marker's range error against distance, views under
    :data:`MIN_POSE_SIDE_PX` across hollow."""
    if axes is None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(1, 2, figsize=(12, 3.6), layout="constrained")
    read, errors = axes
    rows = [("ArUco marker", sweep.found, "tab:orange"), ("QR code", sweep.qr, "tab:green"),
            ("QR code, image x2", sweep.qr_upscaled, "tab:olive")]
    for k, (name, seen, colour) in enumerate(rows):
        read.plot(sweep.distance[seen], np.full(seen.sum(), k), "|", color=colour,
                  markersize=14, label=f"{name}: to {sweep.farthest(seen):.1f} m")
        read.plot(sweep.distance[~seen], np.full((~seen).sum(), k), "x", color="0.6",
                  markersize=4)
    read.set(yticks=range(len(rows)), yticklabels=[r[0] for r in rows], ylim=(-0.6, 2.6),
             xlabel="distance from the camera (m)", title="read (|) or not (x)")
    read.legend(fontsize=8, loc="lower right")
    ranged = sweep.side_px >= MIN_POSE_SIDE_PX
    for mask, style, name in ((ranged, "o", f"marker >= {MIN_POSE_SIDE_PX:.0f} px"),
                              (sweep.found & ~ranged, "o", "narrower")):
        errors.plot(sweep.distance[mask], 100 * sweep.range_error[mask], style,
                    markersize=4, fillstyle="full" if mask is ranged else "none",
                    label=name)
    errors.axhspan(-3, 3, color="tab:green", alpha=0.1, label="+-3 %")
    errors.set(xlabel="distance from the camera (m)", ylabel="range error (%)",
               title="the marker's range from its pose")
    errors.legend(fontsize=8)
    return read, errors


def plot_follow_runs(runs: Mapping[str, FollowResult], distance: float = 1.0,
                     tolerance: float = 0.3) -> Figure:
    """Distance to the tag (truth) and the turn rate sent, against time, one line per
    run; the distance band shaded, the decisions without a reading of the tag marked."""
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(11, 5.5), sharex=True,
                                      layout="constrained")
    top.axhspan(distance - tolerance, distance + tolerance, color="tab:green", alpha=0.1,
                label=f"{distance} +- {tolerance} m")
    for name, run in runs.items():
        line, = top.plot(run.t, run.distance, linewidth=1.2,
                         label=f"{name}: {100 * run.held(distance, tolerance):.0f} % in band")
        blind = ~run.seen
        top.plot(run.t[blind], np.full(blind.sum(), -0.15 - 0.12 * len(top.lines) / 2), "|",
                 color=line.get_color(), markersize=4)
        bottom.plot(run.t, run.w, linewidth=1.0, color=line.get_color(), label=name)
    top.set(ylabel="camera to tag (m)", ylim=(-0.5, None),
            title="distance behind the person (ticks below: tag not read)")
    top.legend(fontsize=8, loc="upper left")
    bottom.axhline(0.0, color="0.5", linewidth=0.5)
    bottom.set(xlabel="t (s)", ylabel="turn rate sent (rad/s)")
    bottom.legend(fontsize=8, loc="upper left")
    return fig


def plot_hand_over(demo: HandOverDemo, ax: Axes | None = None, margin: float = 0.8) -> Axes:
    """The map the follower handed over (walls black, free white, unknown grey), the
    navigator's plan on it (dashed), the route the chair drove (the simulator's truth)
    and the goal; cropped to what the route and the seen cells cover, plus ``margin``
    m."""
    from abcwc.types import Pose2D
    from abcwc.viz.report import plot_map_and_route

    ax = plot_map_and_route(demo.grid, demo.track, places={"goal": Pose2D(*demo.goal)},
                            ax=ax)
    ax.plot(*demo.plan.T, "--", color="tab:orange", linewidth=1.5, label="the first plan")
    grid = demo.grid
    rows, cols = np.nonzero(grid.known())
    seen = grid.cell_to_world(rows, cols)
    points = np.vstack([seen, demo.track[:, :2], demo.plan])
    low, high = points.min(axis=0) - margin, points.max(axis=0) + margin
    ax.set(xlim=(low[0], high[0]), ylim=(low[1], high[1]),
           title="the map of one scan, handed to the navigator")
    ax.legend(loc="lower right", fontsize=8, framealpha=0.85)
    return ax


__all__ = ["plot_camera_view", "plot_follow_runs", "plot_hand_over", "plot_tag_sweep"]
