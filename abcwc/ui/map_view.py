"""The dashboard's map, drawn at exactly the pixel size it is shown.

A PNG scaled by the browser is soft (scaled up) or loses lines (scaled down). So the
figure is ``width x height`` CSS pixels at 96 dpi times the screen's device pixel ratio,
and the image widget is pinned to ``width x height`` CSS pixels: one image pixel per
screen pixel. Text is ``font_px`` CSS pixels high (9 pt at 96 dpi is 12 px).

Redrawing at 5-10 Hz is cheap because only what moves is drawn each time (matplotlib's
blitting): the walls, the faint costmap and the place names are drawn once into a
background; each frame restores it and draws the plan, the goal, the people and the
chair on top, then encodes the pixels as PNG (zlib level 1: fast, still lossless).
"""

from __future__ import annotations

import io
import math

import numpy as np

from abcwc.navigation.costmap import Costmap
from abcwc.params import ChairParams
from abcwc.types import Pose2D

CSS_DPI = 96.0
"""A CSS pixel is 1/96 inch."""
MARGINS = (58, 8, 10, 34)
"""CSS px around the map (left, right, top, bottom): room for the axes' labels."""


def figure_for(width: int, height: int, pixel_ratio: float) -> object:
    """A matplotlib Figure (no pyplot) of ``width x height`` CSS px at ``pixel_ratio``
    image pixels per CSS px."""
    from matplotlib.figure import Figure

    return Figure(figsize=(width / CSS_DPI, height / CSS_DPI), dpi=CSS_DPI * pixel_ratio)


def png_bytes(canvas: object, level: int = 1) -> bytes:
    """The Agg canvas's pixels as PNG (zlib ``level``; RGB, no alpha)."""
    from PIL import Image

    rgba = np.asarray(canvas.buffer_rgba())
    out = io.BytesIO()
    Image.fromarray(rgba[..., :3]).save(out, format="PNG", compress_level=level)
    return out.getvalue()


def points_to_css_px(points: float) -> float:
    """A font size in points (1/72 inch) in CSS pixels (1/96 inch)."""
    return points * CSS_DPI / 72.0


class MapView:
    """The map (``costmap`` faint, ``walls`` (N, 4) segments, ``places`` named) as an
    ``ipywidgets.Image`` ``width`` CSS px wide and as high as the map's aspect asks."""

    def __init__(self, costmap: Costmap, walls: np.ndarray | None,
                 places: dict[str, Pose2D], params: ChairParams, width: int = 760,
                 pixel_ratio: float = 1.0, font_px: float = 12.0):
        import ipywidgets as widgets

        if isinstance(width, bool) or not isinstance(width, int) or width < 200:
            raise ValueError(f"width must be a whole number of CSS px >= 200, got {width!r}")
        if not (math.isfinite(font_px) and font_px >= 11):
            raise ValueError(f"font_px must be >= 11 CSS px to be readable, got {font_px!r}")
        self.costmap, self.walls, self.places, self.params = costmap, walls, places, params
        self.font_points = font_px * 72.0 / CSS_DPI
        x0, y0 = costmap.origin.x, costmap.origin.y
        self.extent = (x0, x0 + costmap.width * costmap.resolution,
                       y0, y0 + costmap.height * costmap.resolution)
        left, right, top, bottom = MARGINS
        map_w = self.extent[1] - self.extent[0]
        map_h = self.extent[3] - self.extent[2]
        self.width = width
        self.height = int(round(top + bottom + (width - left - right) * map_h / map_w))
        self.image = widgets.Image(format="png", layout=widgets.Layout(
            width=f"{self.width}px", height=f"{self.height}px", object_fit="fill",
            flex="0 0 auto"))
        self.pixel_ratio = float("nan")
        self.set_pixel_ratio(pixel_ratio)

    # ------------------------------------------------------------------ building
    def set_pixel_ratio(self, pixel_ratio: float) -> None:
        """Rebuild the figure for ``pixel_ratio`` image pixels per CSS pixel."""
        if not (math.isfinite(pixel_ratio) and 0.5 <= pixel_ratio <= 4):
            raise ValueError(f"pixel_ratio must be within 0.5..4, got {pixel_ratio!r}")
        if pixel_ratio == self.pixel_ratio:
            return
        self.pixel_ratio = float(pixel_ratio)
        self._build()

    def _build(self) -> None:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.collections import LineCollection, PatchCollection

        from abcwc.viz.costmap import costmap_colours
        from abcwc.viz.scene import ChairArtist

        fig = figure_for(self.width, self.height, self.pixel_ratio)
        self.canvas = FigureCanvasAgg(fig)
        left, right, top, bottom = MARGINS
        self.ax = ax = fig.add_axes((left / self.width, bottom / self.height,
                                     1 - (left + right) / self.width,
                                     1 - (top + bottom) / self.height))
        size = self.font_points
        ax.imshow(self.costmap.cost, cmap=costmap_colours(), vmin=0, vmax=255,
                  origin="lower", interpolation="nearest", extent=self.extent, alpha=0.3)
        if self.walls is not None and len(self.walls):
            ax.add_collection(LineCollection(np.asarray(self.walls).reshape(-1, 2, 2),
                                             colors="0.2", linewidths=1.5, zorder=2))
        for name, place in self.places.items():
            ax.plot([place.x], [place.y], "o", color="tab:purple", markersize=3, zorder=3)
            # a name in the right quarter goes on the place's left, inside the map
            left = place.x > self.extent[0] + 0.75 * (self.extent[1] - self.extent[0])
            ax.annotate(name.replace("_", " "), (place.x, place.y),
                        xytext=(-4 if left else 4, 3), ha="right" if left else "left",
                        textcoords="offset points", fontsize=size, color="tab:purple",
                        zorder=3)
        ax.set_xlim(*self.extent[:2])
        ax.set_ylim(*self.extent[2:])
        ax.set_aspect("auto")  # the axes' box already has the map's aspect
        ax.tick_params(labelsize=size, length=3, pad=2)
        ax.set_xlabel("x (m)", fontsize=size, labelpad=0)
        ax.set_ylabel("y (m)", fontsize=size, labelpad=0)
        ax.grid(True, color="0.92", linewidth=0.6)
        ax.set_axisbelow(True)
        (self._plan,) = ax.plot([], [], color="tab:green", linewidth=2, zorder=4,
                                animated=True)
        # the goal is a ring under the chair, so the chair is never hidden by it
        (self._goal,) = ax.plot([], [], "o", markersize=16, markerfacecolor="none",
                                markeredgecolor="tab:orange", markeredgewidth=2.5,
                                zorder=4, animated=True)
        self._people = PatchCollection([], facecolor=(0.55, 0.34, 0.29, 0.45),
                                       edgecolor="tab:brown", zorder=5, animated=True)
        ax.add_collection(self._people)
        self._walking = LineCollection([], colors="tab:brown", linewidths=1.5, zorder=5,
                                       animated=True)
        ax.add_collection(self._walking)
        self._chair = ChairArtist(ax, self.params, zorder=6, alpha=0.6)
        for patch in self._chair.artists:
            patch.set_animated(True)
        self.canvas.draw()
        self._background = self.canvas.copy_from_bbox(fig.bbox)

    # ------------------------------------------------------------------ drawing
    def draw(self, chair: Pose2D | None, plan: np.ndarray | None = None,
             people: np.ndarray | None = None, goal: Pose2D | None = None) -> bytes:
        """Draw the chair at ``chair``, the ``plan`` ((K, 2) m), the tracked ``people``
        ((M, 5): x, y, vx, vy, radius) with where they will be in 1 s, and the ``goal``;
        show it in the image and return the PNG."""
        from matplotlib.patches import Circle

        plan = np.zeros((0, 2)) if plan is None else np.asarray(plan, dtype=float)
        self._plan.set_data(plan[:, 0], plan[:, 1])
        self._goal.set_data([goal.x] if goal else [], [goal.y] if goal else [])
        people = np.zeros((0, 5)) if people is None else np.asarray(people, dtype=float)
        self._people.set_paths([Circle((p[0], p[1]), p[4]) for p in people])
        self._walking.set_segments([[(p[0], p[1]), (p[0] + p[2], p[1] + p[3])]
                                    for p in people])
        self.canvas.restore_region(self._background)
        for artist in (self._plan, self._goal, self._people, self._walking):
            self.ax.draw_artist(artist)
        self._chair.set_visible(chair is not None)
        if chair is not None:
            self._chair.update(chair)
            for patch in self._chair.artists:
                self.ax.draw_artist(patch)
        self.canvas.blit(self.ax.figure.bbox)
        png = png_bytes(self.canvas)
        self.image.value = png
        return png

    @property
    def pixel_size(self) -> tuple[int, int]:
        """The image's size in image pixels (width, height)."""
        width, height = self.canvas.get_width_height(physical=True)
        return int(width), int(height)

    def to_pixel(self, x: float, y: float) -> tuple[float, float]:
        """Where the map point ``(x, y)`` (m) is on the image, in CSS px from its top left."""
        px, py = self.ax.transData.transform((x, y)) / self.pixel_ratio
        return float(px), float(self.height - py)

    def to_map(self, px: float, py: float) -> tuple[float, float]:
        """The map point (m) at ``(px, py)`` CSS px from the image's top left (a click):
        :meth:`to_pixel` undone through the same axes transform. ValueError for a point
        off the map (in the margins round it, or not finite)."""
        if not (math.isfinite(px) and math.isfinite(py)):
            raise ValueError(f"a point on the image is finite CSS px, got ({px!r}, {py!r})")
        display = (px * self.pixel_ratio, (self.height - py) * self.pixel_ratio)
        x, y = self.ax.transData.inverted().transform(display)
        x0, x1, y0, y1 = self.extent
        if not (x0 <= x <= x1 and y0 <= y <= y1):
            raise ValueError(f"({px:.0f}, {py:.0f}) px is off the map: the map spans "
                             f"x {x0:.1f}..{x1:.1f} m and y {y0:.1f}..{y1:.1f} m")
        return float(x), float(y)
