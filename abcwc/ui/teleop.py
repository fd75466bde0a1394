"""Keyboard teleoperation in a notebook: the thesis's w/a/s/d/space keys (4.1.4, A.2).

``w`` drives forward, ``s`` reverses, ``a`` turns left, ``d`` turns right and the
space bar stops. Each key sends one PotCommand: the speed slider's fraction ``f`` of
full deflection moves one pot byte ``round(f * 125)`` away from neutral 128 (clamped
to the safe 8..253), the other stays at 128. Our convention throughout the library:
FB above 128 is forward, LR below 128 turns left (counter-clockwise, ROS REP 103).

In a notebook::

    panel = TeleopPanel(abcwc.connect(), speed=0.5)
    panel.display()

Clicking a button, or typing a key in the text box, sends the command and runs the
chair for ``hold`` seconds, redrawing the plot as it goes. Between presses the
simulator waits; on the real chair the watchdog stops it 250 ms after the last command.

The plot is an image of ``size`` CSS pixels (600 x 400 by default) shown at exactly that
size and rendered at the screen's device pixel ratio (which the browser hook of
:mod:`abcwc.ui.access` reports), so it is sharp rather than stretched.
"""

from __future__ import annotations

import io
import math

import numpy as np

from abcwc.control import clamp_pot_byte, direction_pot_command
from abcwc.params import ChairParams, default_params
from abcwc.types import PotCommand, require_finite

KEYS = {"w": "forward", "a": "left", "s": "reverse", "d": "right", " ": "stop", "space": "stop"}
KEY_NAMES = "w (forward), a (left), s (reverse), d (right), space (stop)"


def key_to_pot_command(key: str, fraction: float, params: ChairParams | None = None,
                       ) -> PotCommand:
    """The PotCommand for one teleop key at ``fraction`` (0..1) of full deflection.

    The direction comes from :func:`abcwc.control.direction_pot_command`; the byte
    that moves is ``128 +- round(fraction * 125)``, clamped to the safe range 8..253.
    So ``fraction=1`` gives exactly the full-deflection command of table 6 (corrected).
    """
    p = params or default_params()
    f = require_finite("speed fraction", fraction)
    if not 0.0 <= f <= 1.0:
        raise ValueError(f"speed fraction {f:g} outside 0..1 (fraction of full deflection)")
    if not isinstance(key, str) or key.lower() not in KEYS:
        raise ValueError(f"unknown key {key!r}; allowed: {KEY_NAMES}")
    full = direction_pot_command(KEYS[key.lower()], p)
    step = round(f * p.pot_full_scale_offset)
    return PotCommand(*(_scaled(byte, step, p) for byte in (full.fb, full.lr)))


def _scaled(full_byte: int, step: int, p: ChairParams) -> int:
    """Neutral if ``full_byte`` is neutral, else ``step`` from neutral on its side."""
    offset = full_byte - p.pot_neutral
    if offset == 0:
        return p.pot_neutral
    return clamp_pot_byte(p.pot_neutral + int(math.copysign(step, offset)), p)


class TeleopPanel:
    """An ipywidgets panel that drives ``chair`` with the w/a/s/d/space keys.

    ``speed`` is the starting fraction of full deflection (0.1..1), ``hold`` the
    seconds each key press drives, and the plot (world, chair, trail) is redrawn every
    ``refresh_steps`` control periods. Building it needs no browser; :meth:`press` is
    the key handler the buttons and the text box call.
    """

    def __init__(self, chair: object, speed: float = 0.5, hold: float = 0.5,
                 refresh_steps: int = 25, world: object = None, view: float | None = None,
                 size: tuple[int, int] = (600, 400)):
        import ipywidgets as widgets

        from abcwc.ui.access import FrontEnd

        speed = require_finite("speed", speed)
        if not 0.1 <= speed <= 1.0:
            raise ValueError(f"speed {speed:g} outside 0.1..1.0 (fraction of full deflection)")
        self.hold = require_finite("hold (s)", hold)
        if self.hold <= 0:
            raise ValueError(f"hold {self.hold:g} s must be > 0")
        if isinstance(refresh_steps, bool) or not isinstance(refresh_steps, int) \
                or refresh_steps < 1:
            raise ValueError(f"refresh_steps must be a positive integer, got {refresh_steps!r}")
        self.chair = chair
        self.params = chair.params
        self.world = world if world is not None else getattr(chair, "world", None)
        self.refresh_steps = refresh_steps
        self.view = view
        self.logs: list = []
        self._trail: list[np.ndarray] = [self._pose_now()]
        self.last_command: PotCommand | None = None

        self.speed = widgets.FloatSlider(value=speed, min=0.1, max=1.0, step=0.05,
                                         description="speed", readout_format=".2f")
        self.keybox = widgets.Text(value="", placeholder="type w a s d or space",
                                   description="keys", continuous_update=True)
        self.keybox.observe(self._on_typed, names="value")
        self.buttons = {key: self._button(widgets, key) for key in ("w", "a", "s", "d", " ")}
        self.status = widgets.Label(value="ready: press a key")
        if not (isinstance(size, tuple) and len(size) == 2
                and all(isinstance(v, int) and not isinstance(v, bool) and v >= 200
                        for v in size)):
            raise ValueError(f"size must be (width, height) in whole CSS px >= 200, "
                             f"got {size!r}")
        self.size = size
        self.image = widgets.Image(format="png", layout=widgets.Layout(
            width=f"{size[0]}px", height=f"{size[1]}px", flex="0 0 auto"))
        self.front_end = FrontEnd()
        self.front_end.observe(self._on_pixel_ratio, names="pixel_ratio")
        self._figure, self._draw_chair, self._draw_trail = self._build_plot()
        self.redraw()
        pad = widgets.Layout(width="60px")
        keys = widgets.VBox([
            widgets.HBox([widgets.Label(layout=pad), self.buttons["w"]]),
            widgets.HBox([self.buttons["a"], self.buttons[" "], self.buttons["d"]]),
            widgets.HBox([widgets.Label(layout=pad), self.buttons["s"]]),
        ])
        self.widget = widgets.VBox([
            widgets.HBox([keys, widgets.VBox([self.speed, self.keybox, self.status])]),
            self.image, self.front_end,
        ])

    # ----------------------------------------------------------------- widgets
    def _button(self, widgets: object, key: str) -> object:
        label = "space" if key == " " else key
        button = widgets.Button(description=label, tooltip=f"{label}: {KEYS[key]}",
                                layout=widgets.Layout(width="60px"))
        button.on_click(lambda _button: self._safely(key))
        return button

    def _on_typed(self, change: dict) -> None:
        text = change["new"]
        if not text:
            return
        self.keybox.value = ""  # fires again with "", which is ignored
        self._safely(text[-1])

    def _safely(self, key: str) -> None:
        """Press ``key``, showing an error in the status line instead of raising."""
        try:
            self.press(key)
        except ValueError as exc:
            self.status.value = str(exc)

    def display(self) -> object:
        """The panel's widget (the last line of a cell shows it)."""
        return self.widget

    def _repr_mimebundle_(self, **kwargs: object) -> object:
        return self.widget._repr_mimebundle_(**kwargs)

    # ----------------------------------------------------------------- driving
    def press(self, key: str) -> PotCommand:
        """Send ``key``'s command at the slider's speed and drive for ``hold`` seconds."""
        command = key_to_pot_command(key, self.speed.value, self.params)
        self.last_command = command
        period = getattr(self.chair, "period", self.params.control_period)
        steps_left = max(1, round(self.hold / period))
        while steps_left > 0:
            chunk = min(self.refresh_steps, steps_left)
            log = self.chair.drive(command, chunk * period)
            self.logs.append(log)
            self._trail.append(np.asarray(log.pose, dtype=float))
            steps_left -= chunk
            self.redraw()
        name = "space" if key == " " else key.lower()
        self.status.value = (f"{name}: {KEYS[name]} fb={command.fb} lr={command.lr}, "
                             f"t = {self.logs[-1].t[-1]:.1f} s")
        return command

    @property
    def trail(self) -> np.ndarray:
        """Every pose of the session so far, (N, 3) (NaN rows on a real chair)."""
        return np.vstack(self._trail)

    def _pose_now(self) -> np.ndarray:
        frame = self.chair.read() if hasattr(self.chair, "read") else None
        pose = getattr(frame, "pose", None)
        return np.array([[pose.x, pose.y, pose.theta]]) if pose else np.full((1, 3), np.nan)

    # ----------------------------------------------------------------- plotting
    def _build_plot(self) -> tuple:
        """A figure outside pyplot (so nothing shows twice) with the world drawn once."""
        from matplotlib.patches import Circle

        from abcwc.ui.map_view import figure_for
        from abcwc.viz.scene import ChairArtist, plot_world

        fig = figure_for(*self.size, pixel_ratio=1.0)
        fig.set_layout_engine("constrained")
        ax = fig.add_subplot()
        if self.world is not None:
            plot_world(self.world, ax)
        else:
            ax.set_aspect("equal", adjustable="datalim")
            ax.grid(True, color="0.9")
        (trail,) = ax.plot([], [], color="tab:blue", linewidth=1.5, zorder=4)
        self._people = [ax.add_patch(Circle(w.circle[:2], w.circle[2], zorder=5,
                                            facecolor=(0.55, 0.34, 0.29, 0.5),
                                            edgecolor="tab:brown"))
                        for w in getattr(self.chair, "walkers", [])]
        return fig, ChairArtist(ax, self.params), trail

    def _on_pixel_ratio(self, change: dict) -> None:
        """Render at the browser's device pixel ratio (image px per CSS px)."""
        from abcwc.ui.map_view import CSS_DPI

        ratio = float(change["new"])
        if math.isfinite(ratio) and 0.5 <= ratio <= 4:
            self._figure.set_dpi(CSS_DPI * ratio)
            self.redraw()

    def redraw(self) -> None:
        """Move the chair and trail on the plot and refresh the image."""
        from abcwc.viz._common import decimate

        poses = self.trail
        rows = decimate(len(poses), 2000)
        self._draw_trail.set_data(poses[rows, 0], poses[rows, 1])
        for disc, walker in zip(self._people, getattr(self.chair, "walkers", [])):
            disc.set_center(walker.circle[:2])
        last = poses[-1]
        visible = bool(np.isfinite(last).all())
        self._draw_chair.set_visible(visible)
        ax = self._figure.axes[0]
        if visible:
            self._draw_chair.update(last)
            self._follow(ax, last)
        else:
            ax.set_title("no ground-truth pose from this chair")
        buffer = io.BytesIO()
        self._figure.savefig(buffer, format="png", dpi=self._figure.dpi)
        self.image.value = buffer.getvalue()

    def _follow(self, ax: object, pose: np.ndarray) -> None:
        """Keep a window of ``view`` metres above and below the chair (1.5 times that
        across), when set; by default the whole world if it is under 16 m across,
        else 5 m."""
        view = self.view
        if view is None and self.world is not None:
            xmin, ymin, xmax, ymax = self.world.bounds
            view = None if max(xmax - xmin, ymax - ymin) < 16 else 5.0
        if view is None and self.world is None:
            view = 3.0
        if view is not None:
            ax.set_xlim(pose[0] - 1.5 * view, pose[0] + 1.5 * view)  # the figure is 3:2
            ax.set_ylim(pose[1] - view, pose[1] + view)
