"""Send the chair somewhere by clicking the map: RViz's "2D Nav Goal" in a notebook.

The panel shows the map, the global costmap (RViz's colours), the plan, the people and
the chair (its true pose in the simulator, the navigator's estimate as a cross), and
follows it live. Click a free spot on the map, or pick a named place and press "go":
the navigator drives there (or says why it cannot), redrawing every ``refresh`` s, and
the status line gives the outcome. In JupyterLab::

    %matplotlib widget
    from abcwc.ui.navigator_panel import NavigatorPanel
    panel = NavigatorPanel.for_world("floor", seed=1)
    panel

The map is an interactive matplotlib canvas (ipympl), so a click arrives in the kernel
as the map point under the pointer. While the chair drives the kernel is busy: a click
made meanwhile is taken when the drive ends.
"""

from __future__ import annotations

import math

import numpy as np

from abcwc.behaviours.navigator import Navigator
from abcwc.types import Pose2D

MAP_AXES = (0.07, 0.09, 0.91, 0.85)
"""Where the map sits in the figure (left, bottom, width, height as fractions): fixed,
so that a point of the map has a known place on the canvas."""


class NavigatorPanel:
    """Drive ``chair`` with ``navigator`` to goals clicked on the map or picked by name.

    ``refresh`` (s of simulated time) is how often the map is redrawn while driving,
    ``max_seconds`` the longest one drive may take before it is cancelled.
    """

    def __init__(self, chair: object, navigator: Navigator, refresh: float = 1.0,
                 max_seconds: float = 300.0):
        import ipywidgets as widgets

        if not (math.isfinite(refresh) and refresh > 0):
            raise ValueError(f"refresh must be a finite number > 0 s, got {refresh!r}")
        if not (math.isfinite(max_seconds) and max_seconds > 0):
            raise ValueError(f"max_seconds must be a finite number > 0 s, got {max_seconds!r}")
        self.chair, self.navigator = chair, navigator
        self.refresh, self.max_seconds = float(refresh), float(max_seconds)
        self.frame = chair.read()
        self.outcomes: list[str] = []
        places = sorted(navigator.places)
        self.place = widgets.Dropdown(options=places, value=places[0] if places else None,
                                      description="place")
        self.go_button = widgets.Button(description="go", tooltip="drive to the place")
        self.go_button.on_click(lambda _button: self.go(self.place.value))
        self.status = widgets.Label(value="click the map, or pick a place and press go")
        self.canvas = self._build_canvas()
        self.widget = widgets.VBox([widgets.HBox([self.place, self.go_button]), self.status,
                                    self.canvas])
        self.redraw()

    @classmethod
    def for_world(cls, world: str = "floor", seed: int = 0, people: bool = True,
                  **options: object) -> NavigatorPanel:
        """A simulated chair with a lidar in ``world`` and a navigator on its walls."""
        from abcwc.sim import SimBase

        chair = SimBase(world, seed=seed, lidar=True, people=people)
        return cls(chair, Navigator.for_world(chair.world), **options)  # type: ignore[arg-type]

    def _repr_mimebundle_(self, **kwargs: object) -> object:
        return self.widget._repr_mimebundle_(**kwargs)

    # ------------------------------------------------------------------ driving
    def go(self, goal: Pose2D | tuple[float, ...] | str) -> str:
        """Drive to ``goal`` (as :meth:`Navigator.go_to` takes it) until the navigator
        ends or ``max_seconds`` pass; the outcome, also shown in the status line."""
        nav = self.navigator
        try:
            nav.go_to(goal)
        except ValueError as error:
            return self._say(str(error))
        start = self.chair.t
        next_draw = start + self.refresh
        self._say(f"driving to ({nav.goal.x:.2f}, {nav.goal.y:.2f})")
        while nav.running and self.chair.t - start < self.max_seconds:
            self.chair.send(nav(self.frame), nav.decided_at)
            self.frame = self.chair.step()
            if self.chair.t >= next_draw:
                next_draw += self.refresh
                self.redraw()
        if nav.running:
            nav.cancel()
        for _ in range(25):  # come to rest
            self.chair.send(nav(self.frame), nav.decided_at)
            self.frame = self.chair.step()
        self.redraw()
        truth = self.chair.pose
        outcome = (f"{nav.status.value}" + (f" ({nav.failure})" if nav.failure else "")
                   + f" after {self.chair.t - start:.1f} s; chair at ({truth.x:.2f}, "
                   f"{truth.y:.2f})")
        self.outcomes.append(outcome)
        return self._say(outcome)

    def click(self, x: float, y: float) -> str:
        """What a click on the map at ``(x, y)`` (m) does: drive there."""
        return self.go((float(x), float(y)))

    def _on_press(self, event: object) -> None:
        if getattr(event, "inaxes", None) is self.ax and event.xdata is not None:
            self.click(event.xdata, event.ydata)

    def _say(self, text: str) -> str:
        self.status.value = text
        return text

    # ------------------------------------------------------------------ drawing
    def _build_canvas(self) -> object:
        from ipympl.backend_nbagg import new_figure_manager_given_figure
        from matplotlib.figure import Figure
        from matplotlib.patches import Circle

        from abcwc.viz.costmap import costmap_colours
        from abcwc.viz.scene import ChairArtist, plot_world

        fig = Figure(figsize=(9.0, 5.0), dpi=80)
        self.ax = ax = fig.add_axes(MAP_AXES)
        world = getattr(self.chair, "world", None)
        costmap = self.navigator.global_costmap
        x0, y0 = costmap.origin.x, costmap.origin.y
        self._costmap_image = ax.imshow(
            costmap.cost, cmap=costmap_colours(), vmin=0, vmax=255, origin="lower",
            interpolation="nearest", extent=(x0, x0 + costmap.width * costmap.resolution,
                                             y0, y0 + costmap.height * costmap.resolution))
        if world is not None:
            plot_world(world, ax)
        ax.set_aspect("auto")  # the axes fill MAP_AXES exactly
        ax.set_xlim(x0, x0 + costmap.width * costmap.resolution)
        ax.set_ylim(y0, y0 + costmap.height * costmap.resolution)
        (self._plan,) = ax.plot([], [], color="tab:green", linewidth=2, zorder=5)
        (self._estimate,) = ax.plot([], [], "x", color="black", markersize=8, zorder=8)
        (self._goal,) = ax.plot([], [], "*", color="tab:orange", markersize=14, zorder=8)
        self._chair = ChairArtist(ax, self.chair.params)
        self._people = [ax.add_patch(Circle(w.circle[:2], w.circle[2], zorder=7,
                                            facecolor=(0.55, 0.34, 0.29, 0.5),
                                            edgecolor="tab:brown"))
                        for w in getattr(self.chair, "walkers", [])]
        manager = new_figure_manager_given_figure(id(fig), fig)
        canvas = manager.canvas
        canvas.header_visible = False
        canvas.toolbar_visible = False
        canvas.resizable = False
        canvas.mpl_connect("button_press_event", self._on_press)
        return canvas

    def redraw(self) -> None:
        """Show the chair, its estimate, the people, the plan and the goal now."""
        nav = self.navigator
        truth, estimate = self.chair.pose, nav.localizer.pose
        self._chair.update(truth)
        self._estimate.set_data([estimate.x], [estimate.y])
        for disc, walker in zip(self._people, getattr(self.chair, "walkers", [])):
            disc.set_center(walker.circle[:2])
        points = nav.path.points if nav.path is not None else np.zeros((0, 2))
        self._plan.set_data(points[:, 0], points[:, 1])
        goal = nav.goal
        self._goal.set_data([goal.x] if goal else [], [goal.y] if goal else [])
        self.canvas.draw_idle()
