"""An errand's report: one self-contained HTML page a person can open anywhere.

It holds what a rider, an instructor or an engineer asks of an errand, in that order:
did it get there and how (a one-line summary and a table of figures), where it went (the
chair's own map with the route over it, the estimate beside the truth in the simulator),
what it was doing when (the mission's states over time, with its events), and the drive
itself (an animation). Every image is embedded (PNG and GIF as base64), so the page is
one file to mail or attach to a bug report.
"""

from __future__ import annotations

import base64
import html
import io
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure

from abcwc.behaviours.mission import mission_timeline
from abcwc.experiments.errand import ErrandResult
from abcwc.mapping.grid import FREE, OCCUPIED, UNKNOWN, OccupancyGrid
from abcwc.sim.world import World
from abcwc.types import Pose2D
from abcwc.viz._common import CHAIR_COLOR, PLACE_COLOR, new_axes
from abcwc.viz.mission import plot_timeline

ESTIMATE_COLOUR = "#ff9800"


def plot_map_and_route(grid: OccupancyGrid, track: np.ndarray,
                       estimates: np.ndarray | None = None,
                       places: Mapping[str, Pose2D] | None = None,
                       events: Sequence[tuple[float, str, float, float]] = (),
                       ax: Axes | None = None) -> Axes:
    """The chair's map (trinary: walls black, free white, unknown grey) with the route
    driven (``track``, (N, 3) m, m, rad), the chair's own estimate of it (dashed), the
    named ``places`` and the ``events`` as (t s, name, x m, y m)."""
    cells = grid.trinary()
    shown = np.full(cells.shape, 1, dtype=np.uint8)  # unknown
    shown[cells == FREE] = 0
    shown[cells == OCCUPIED] = 2
    shown[cells == UNKNOWN] = 1
    x0, y0 = grid.origin.x, grid.origin.y
    extent = (x0, x0 + grid.width * grid.resolution, y0, y0 + grid.height * grid.resolution)
    ax = new_axes(ax, (10.0, 10.0 * grid.height / max(grid.width, 1) + 1.0))
    ax.imshow(shown, origin="lower", extent=extent, interpolation="nearest",
              cmap=ListedColormap(["#ffffff", "#d9d9d9", "#000000"]), vmin=0, vmax=2)
    track = np.asarray(track, dtype=float).reshape(-1, 3)
    if len(track):
        ax.plot(track[:, 0], track[:, 1], color=CHAIR_COLOR, linewidth=2.0,
                label="route (simulator's truth)" if estimates is not None else "route")
        ax.plot(*track[0, :2], "o", color=CHAIR_COLOR, markersize=8, label="start")
        ax.plot(*track[-1, :2], "s", color=CHAIR_COLOR, markersize=8, label="end")
    if estimates is not None and len(estimates):
        estimates = np.asarray(estimates, dtype=float).reshape(-1, 3)
        ax.plot(estimates[:, 0], estimates[:, 1], "--", color=ESTIMATE_COLOUR, linewidth=1.2,
                label="the chair's estimate")
    for name, pose in (places or {}).items():
        ax.plot(pose.x, pose.y, "^", color=PLACE_COLOR, markersize=7)
        ax.annotate(name, (pose.x, pose.y), textcoords="offset points", xytext=(4, 4),
                    fontsize=9, color=PLACE_COLOR)
    for t, name, x, y in events:
        ax.plot(x, y, "*", color="#d81b60", markersize=14, zorder=6)
        ax.annotate(f"{name} ({t:.0f} s)", (x, y), textcoords="offset points",
                    xytext=(6, -12), fontsize=9, color="#d81b60")
    ax.set(xlabel="x (m)", ylabel="y (m)", aspect="equal", xlim=extent[:2], ylim=extent[2:])
    ax.legend(loc="upper right", fontsize=8, framealpha=0.85)
    return ax


def figure_png(figure: Figure, dpi: float = 110) -> bytes:
    """``figure`` as PNG bytes (closed afterwards)."""
    import matplotlib.pyplot as plt

    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(figure)
    return buffer.getvalue()


def _image(data: bytes, mime: str, alt: str) -> str:
    encoded = base64.b64encode(data).decode("ascii")
    return f'<img src="data:{mime};base64,{encoded}" alt="{html.escape(alt)}">'


def write_html_report(path: str | Path, title: str, summary: str,
                      figures: Sequence[tuple[str, str]], map_png: bytes,
                      states_png: bytes, animation_gif: bytes | None = None,
                      notes: Sequence[str] = ()) -> Path:
    """Write the report page to ``path`` (an ``.html`` file; its folder must exist):
    ``title``, the one-line ``summary``, the table of ``figures`` (name, value as text),
    the map with the route, the states over time, the animation if given, and any
    ``notes`` (lines of text, e.g. the transitions with their reasons)."""
    path = Path(path)
    if path.suffix.lower() not in (".html", ".htm"):
        raise ValueError(f"{path}: a report's name ends in .html")
    rows = "\n".join(f"<tr><th>{html.escape(name)}</th><td>{html.escape(value)}</td></tr>"
                     for name, value in figures)
    parts = [
        "<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{html.escape(title)}</title>",
        "<style>body{font-family:sans-serif;max-width:1100px;margin:2em auto;color:#222}"
        "table{border-collapse:collapse}th,td{padding:4px 12px;border-bottom:1px solid #ddd;"
        "text-align:left}img{max-width:100%}pre{background:#f5f5f5;padding:1em;"
        "white-space:pre-wrap}</style></head><body>",
        f"<h1>{html.escape(title)}</h1>", f"<p><strong>{html.escape(summary)}</strong></p>",
        "<h2>Figures</h2>", f"<table>{rows}</table>",
        "<h2>The map and the route</h2>", _image(map_png, "image/png", "map and route"),
        "<h2>The mission's states</h2>", _image(states_png, "image/png", "mission states"),
    ]
    if animation_gif is not None:
        parts += ["<h2>The drive</h2>", _image(animation_gif, "image/gif", "animation")]
    if notes:
        parts += ["<h2>What the mission did, and why</h2>",
                  f"<pre>{html.escape(chr(10).join(notes))}</pre>"]
    parts.append("</body></html>")
    path.write_text("\n".join(parts), encoding="utf-8")
    return path


def write_errand_report(result: ErrandResult, grid: OccupancyGrid, out: str | Path,
                        world: World, animation: bool = True) -> Path:
    """An errand's report in the folder ``out``: ``errand.html``
    (:func:`write_html_report`) with the chair's map ``grid`` and the route over it, the
    mission's states and the figures, and with ``animation`` the drive over ``world``
    (also written as ``errand.gif``)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    map_png = figure_png(plot_map_and_route(grid, result.track, result.estimates, world.places,
                                            result.events).figure)
    timeline = [(start - result.started_at, end - result.started_at, state)
                for start, end, state in mission_timeline(result.log)
                ] if result.log is not None else []
    states_png = figure_png(plot_timeline(timeline, result.events).figure)
    gif = None
    if animation and result.log is not None:
        from abcwc.viz.animation import animate_run, save_animation

        path = save_animation(animate_run(result.log, world, scans=False), out / "errand.gif")
        gif = path.read_bytes()
    figures = [(name.replace("_", " "), str(value)) for name, value in result.figures().items()]
    return write_html_report(out / "errand.html", f"Errand to the {result.destination}",
                             result.summary(), figures, map_png, states_png, gif,
                             result.transitions)


__all__ = ["figure_png", "plot_map_and_route",
           "write_errand_report", "write_html_report"]
