"""Animations of a run: the chair moving over the world, with its trail and scans.

In a notebook::

    from IPython.display import HTML
    anim = viz.animate_run(log, chair.world)
    HTML(viz.to_html(anim))

The figure is closed once the animation is built, so it does not also show as a
still image. By default a run becomes at most 150 frames, which keeps the notebook
output to a few megabytes whatever the run's length.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib import animation
from matplotlib.artist import Artist
from matplotlib.axes import Axes

from abcwc.log import RunLog
from abcwc.params import ChairParams, default_params
from abcwc.sim.world import World
from abcwc.viz._common import (
    CHAIR_COLOR,
    DEPTH_COLOR,
    LIDAR_COLOR,
    decimate,
    poses_of,
    require_poses,
    resolve_world,
    world_figsize,
    zoom_to,
)
from abcwc.viz.scene import ChairArtist, plot_world
from abcwc.viz.sensors import scan_row, scan_to_points

MAX_FRAMES = 150
TRAIL_POINTS = 2000


def frame_rows(n: int, stride: int | None = None, max_frames: int = MAX_FRAMES) -> np.ndarray:
    """The log rows an animation shows: every ``stride``-th row, ending on the last.

    Without ``stride`` it is chosen so that there are at most ``max_frames`` frames.
    """
    if n <= 0:
        raise ValueError("the log is empty: nothing to animate")
    if stride is None:
        stride = max(1, math.ceil((n - 1) / max(max_frames - 1, 1)))
    if isinstance(stride, bool) or not isinstance(stride, (int, np.integer)) or stride < 1:
        raise ValueError(f"stride must be a positive integer (rows per frame), got {stride!r}")
    return np.arange(n - 1, -1, -int(stride))[::-1]


class _RunScene:
    """The artists of one animation and how each frame moves them."""

    def __init__(self, ax: Axes, log: RunLog, poses: np.ndarray, params: ChairParams, trail: bool,
                 scans: bool):
        self.log, self.poses = log, poses
        self.trail_rows = decimate(len(poses), TRAIL_POINTS)
        (self.trail,) = ax.plot([], [], color=CHAIR_COLOR, linewidth=1.5, zorder=4,
                                visible=trail)
        self.scans = []
        for name, mount, color in (("lidar", params.lidar.mount, LIDAR_COLOR),
                                   ("depth_scan", params.depth_scan.mount, DEPTH_COLOR)):
            if scans and getattr(log, name, None) is not None:
                dots = ax.scatter([], [], s=4, color=color, linewidths=0, zorder=5)
                self.scans.append((name, mount, dots))
        self.chair = ChairArtist(ax, params)
        self.figure = ax.figure
        self.name = ax.get_title()
        self.clock = ax.title

    def draw(self, row: int) -> list[Artist]:
        """Move everything to log row ``row``; return the artists that changed."""
        pose = self.poses[row]
        visible = bool(np.isfinite(pose).all())
        self.chair.set_visible(visible)
        if visible:
            self.chair.update(pose)
        rows = np.append(self.trail_rows[self.trail_rows < row], row)
        self.trail.set_data(self.poses[rows, 0], self.poses[rows, 1])
        for name, mount, dots in self.scans:
            found = scan_row(self.log, name, row)
            points = np.zeros((0, 2))
            if found is not None and np.isfinite(found[1]).all():
                points = scan_to_points(found[0], found[1], mount)
            dots.set_offsets(points)
        self.clock.set_text(f"{self.name}   t = {self.log.t[row] - self.log.t[0]:.1f} s")
        return [self.trail, self.clock, *self.chair.artists, *(d for _, _, d in self.scans)]


def animate_run(log: RunLog, world: World | str | None = None,
                params: ChairParams | None = None, fps: float = 10, stride: int | None = None,
                trail: bool = True, scans: bool = True, max_frames: int = MAX_FRAMES,
                zoom: float | None = None, width: float = 6.0, dpi: float = 72,
                ) -> animation.FuncAnimation:
    """The chair driving over the world, one frame every ``stride`` log rows.

    ``stride`` defaults to whatever keeps the animation within ``max_frames`` frames.
    With ``trail`` the path so far is drawn; with ``scans`` the newest lidar and
    depth-camera points (when the log has them). ``zoom`` (m) limits the view to the
    path plus that margin. Plays at ``fps`` frames per second. The animation's
    ``frame_rows`` attribute lists the log row of each frame.
    """
    import matplotlib.pyplot as plt

    if not (isinstance(fps, (int, float)) and math.isfinite(fps) and fps > 0):
        raise ValueError(f"fps must be a positive number, got {fps!r}")
    world = resolve_world(world, log)
    poses = require_poses(poses_of(log))
    rows = frame_rows(len(poses), stride, max_frames)
    fig, ax = plt.subplots(figsize=world_figsize(world.bounds, width), dpi=dpi,
                           layout="constrained")
    plot_world(world, ax)
    if zoom is not None:
        zoom_to(ax, poses, zoom)
    scene = _RunScene(ax, log, poses, params or default_params(), trail, scans)
    anim = animation.FuncAnimation(fig, scene.draw, frames=[int(r) for r in rows],
                                   init_func=lambda: scene.draw(int(rows[0])),
                                   interval=1000.0 / fps, blit=False)
    anim.frame_rows = rows
    anim.scene = scene  # for save_animation's GIF, drawn a frame's moving artists at a time
    fig.canvas.draw()  # lay the figure out once, then keep that layout for every frame
    fig.set_layout_engine(None)
    plt.close(fig)
    return anim


def to_html(anim: animation.Animation, default_mode: str = "loop") -> str:
    """The animation as self-contained HTML with play controls (``IPython.display.HTML``)."""
    return anim.to_jshtml(default_mode=default_mode)


def save_animation(anim: animation.Animation, path: str | Path, fps: float | None = None,
                   dpi: float | None = None) -> Path:
    """Write the animation to ``path``: ``.gif`` (always works) or ``.mp4`` (needs ffmpeg).

    Returns the path written.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    scene = getattr(anim, "scene", None)
    if suffix == ".gif" and isinstance(scene, _RunScene) and dpi in (None, scene.figure.dpi):
        return _save_gif_by_blitting(anim, scene, path, fps or _fps(anim))
    if suffix == ".gif":
        writer: animation.AbstractMovieWriter = animation.PillowWriter(fps=fps or _fps(anim))
    elif suffix == ".mp4":
        if not animation.writers.is_available("ffmpeg"):
            raise RuntimeError(f"cannot write {path}: MP4 needs ffmpeg, which was not found; "
                               "install ffmpeg (e.g. apt install ffmpeg or conda install "
                               "ffmpeg) or save as .gif")
        writer = animation.FFMpegWriter(fps=fps or _fps(anim))
    else:
        raise ValueError(f"cannot write {path}: unknown animation format {suffix or '(none)'!r};"
                         " use .gif or .mp4")
    anim.save(str(path), writer=writer, dpi=dpi)
    return path


def _save_gif_by_blitting(anim: animation.FuncAnimation, scene: _RunScene, path: Path,
                          fps: float) -> Path:
    """An :func:`animate_run` animation as a GIF, the same frames as matplotlib's
    ``PillowWriter`` writes, drawn faster: the still figure (world, axes, labels) once,
    then for each frame that picture restored and only the artists the frame moves drawn
    over it (matplotlib's blitting)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    figure = scene.figure
    moving = scene.draw(int(anim.frame_rows[0]))
    shown_on = figure.canvas
    try:
        for artist in moving:
            artist.set_animated(True)  # left out of the still picture
        canvas = FigureCanvasAgg(figure)
        canvas.draw()
        still = canvas.copy_from_bbox(figure.bbox)
        frames = []
        for row in anim.frame_rows:
            canvas.restore_region(still)
            for artist in sorted(scene.draw(int(row)), key=Artist.get_zorder):
                figure.draw_artist(artist)
            frames.append(Image.fromarray(np.asarray(canvas.buffer_rgba())[..., :3].copy()))
    finally:
        for artist in moving:
            artist.set_animated(False)
        figure.set_canvas(shown_on)
    frames[0].save(path, save_all=True, append_images=frames[1:], duration=int(1000 / fps),
                   loop=0)
    return path


def _fps(anim: animation.Animation) -> float:
    """Frames per second the animation was built to play at."""
    interval = getattr(anim, "_interval", 100)
    return 1000.0 / interval if interval else 10.0
