"""Plots of known-object detection: keypoints, matches, the outline found, and the sweeps
that measure how far and how reliably a sign is found."""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import numpy as np
from matplotlib.axes import Axes

from abcwc.experiments.sign_sweep import SignSweep
from abcwc.perception.known_objects import Detection
from abcwc.viz._common import new_axes


def plot_keypoints(gray: np.ndarray, keypoints: Iterable, ax: Axes | None = None,
                   title: str = "") -> Axes:
    """``gray`` with each keypoint as a circle of its scale (OpenCV's ``size``, px) and
    a tick along its orientation."""
    ax = new_axes(ax, (7.0, 4.0))
    ax.imshow(gray, cmap="gray", vmin=0, vmax=255)
    points = list(keypoints)
    for k in points:
        radius = k.size / 2
        ax.add_patch(_circle(k.pt, radius))
        angle = np.radians(k.angle)
        ax.plot([k.pt[0], k.pt[0] + radius * np.cos(angle)],
                [k.pt[1], k.pt[1] + radius * np.sin(angle)], "-", color="tab:orange",
                linewidth=0.6)
    ax.set(xlabel="u (px)", ylabel="v (px)", title=title or f"{len(points)} keypoints")
    return ax


def _circle(centre: tuple[float, float], radius: float):
    from matplotlib.patches import Circle

    return Circle(centre, radius, fill=False, color="tab:orange", linewidth=0.6)


def plot_detections(view: np.ndarray, detections: Iterable[Detection],
                    ax: Axes | None = None) -> Axes:
    """The view with each detection's outline: green when verified, red when the word
    region disagreed, labelled with its name, inliers and correlation."""
    ax = new_axes(ax, (7.0, 5.25))
    ax.imshow(view, cmap="gray" if view.ndim == 2 else None, vmin=0, vmax=255)
    for found in detections:
        outline = np.vstack([found.outline, found.outline[:1]])
        colour = "tab:green" if found.verified else "tab:red"
        ax.plot(*outline.T, "-", color=colour, linewidth=1.8)
        ax.annotate(f"{found.name}: {found.inliers} inliers, correlation "
                    f"{found.correlation:.2f}", found.outline[0], xytext=(0, 4),
                    textcoords="offset points", color=colour, fontsize=8, va="bottom")
    ax.set(xlabel="u (px)", ylabel="v (px)")
    return ax


def plot_sign_sweeps(sweeps: Mapping[str, SignSweep], threshold: float | None = None,
                     axes: tuple[Axes, Axes] | None = None) -> tuple[Axes, Axes]:
    """Left: each sweep's share of views found (verified) in 1 m bands of distance.
    Right: the word region's correlation of every match, by sweep, and ``threshold``."""
    if axes is None:
        import matplotlib.pyplot as plt

        _, axes = plt.subplots(1, 2, figsize=(12, 3.6), layout="constrained")
    rate_ax, corr_ax = axes
    edges = np.arange(1.0, 10.0, 1.0)
    for name, sweep in sweeps.items():
        if sweep.shown != sweep.sought:
            continue
        rates = [sweep.rate(sweep.verified, (a, a + 1.0)) for a in edges[:-1]]
        rate_ax.plot(edges[:-1] + 0.5, rates, "o-", label=f"{name} (to "
                     f"{sweep.farthest(sweep.verified):.1f} m, {np.median(sweep.ms):.0f} ms)")
    rate_ax.set(xlabel="distance from the camera (m)", ylabel="share found",
                ylim=(-0.05, 1.05), title="found and verified")
    rate_ax.legend(fontsize=8)
    for k, sweep in enumerate(sweeps.values()):
        values = sweep.correlation[sweep.matched]
        corr_ax.plot(values, np.full(len(values), k), "|", markersize=14,
                     color="tab:green" if sweep.shown == sweep.sought else "tab:red")
    if threshold is not None:
        corr_ax.axvline(threshold, color="0.3", linestyle="--", linewidth=1)
    corr_ax.set(yticks=range(len(sweeps)), yticklabels=list(sweeps), ylim=(-0.6, len(sweeps) - 0.4),
                xlabel="word region's correlation with the EXIT sign's", xlim=(-0.3, 1.05),
                title="every match steps 1-4 reported")
    return rate_ax, corr_ax


__all__ = ["plot_detections", "plot_keypoints", "plot_sign_sweeps"]
