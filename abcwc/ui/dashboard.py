"""The rider's dashboard: pick a place, watch the chair drive there, stop it at any time.

``Dashboard(chair, mission)`` shows, in JupyterLab or as a standalone Voila page:

* the map, with the costmap (faint), the places, the plan, the tracked people (and where
  each will be in 1 s) and the chair drawn to scale at its estimated pose, over the goal
  ring rather than under it; a click on it sends the chair to the point clicked (the
  mission's ``go_to((x, y))``, the pixel turned into metres by the map's own transform);
* a button per destination, a command box (typed commands in the mission's grammar:
  "go to the <place>", "follow me", "stop") and a big stop button;
* the mission's state and the reason for it, what became of the last command, the
  safety filter's last intervention (``chair.safety.reason``), how often the view
  redrew, and on a simulator where the chair truly is and how fast it moves.

In a notebook::

    dashboard = Dashboard(chair, mission)   # any body: SimBase, or an abcwc.hw body
    dashboard.show()                         # or let it be a cell's last line

**Live.** Nothing blocks the kernel. A command starts the drive as an asyncio task on the
kernel's own event loop: it steps the body ``yield_periods`` control periods at a time
and then awaits ``asyncio.sleep``, so button presses, pointer moves and image updates
flow between steps. On a simulator the task keeps to wall-clock time (``time_scale``
simulated seconds per second; more runs faster); a real body's ``step`` already waits
for its next frame. The map is redrawn ``redraw_hz`` times a second while the chair
moves (only what moves is drawn again, :mod:`abcwc.ui.map_view`), and the task ends once
the mission is no longer driving and the chair is still. The map is drawn at the pixel
size it is shown, times the screen's device pixel ratio, so it stays sharp.

**One thread.** JupyterLab (4.4 and later, with ipykernel 7) may deliver widget
messages on a kernel *subshell*: another thread, with an event loop of its own, that
keeps widgets answering while a cell runs. A button handled there would change the
mission while the drive task steps it on the main thread (a stop in the middle of the
navigator's decision left the mission "failed: cancelled"). So every widget callback is
handed to the dashboard's own loop (``call_soon_threadsafe``; the loop running where the
dashboard was made), and the mission, the body and the drawing are only ever touched
from that one thread.

**One errand at a time.** A second command while the mission drives is queued
(``on_busy="queue"``: it starts when the errand ends, and a newer one takes its place) or
refused (``on_busy="refuse"``), and the view says which. Stop always acts at once and
empties the queue.

**Access without a hand** (:mod:`abcwc.ui.access`, whose notes weigh the timings).
*Dwell*: resting the pointer (moved by an eye tracker or a head mouse) on a destination
or on stop for ``dwell_seconds`` picks it. The trade: a short dwell is fast, but picks
whatever the eyes rest on while reading the screen (the Midas touch, false selections);
a long one avoids them but makes every choice slow. *Switch scanning*: with scanning on,
the destinations and stop light up in turn, ``scan_seconds`` each, and the switch key
(space by default; a sip-and-puff switch usually types one) picks the lit one. The
trade: the longest wait is ``scan_seconds`` x the number of options (half that on
average), so a fast scan saves time but asks for a quick, exact press, and a rider who
is slow to press picks the neighbour.

**Standalone (Voila).** ``abcwc dashboard [--world W]`` serves this package's
:data:`NOTEBOOK` (a dashboard on the simulated chair in the world named by the
environment variable :data:`WORLD_VARIABLE`) as a page of its own: the command it runs
is :func:`voila_command`, with :data:`VOILA_OPTIONS`; any other notebook whose last line
is a dashboard is served the same way::

    voila dashboard.ipynb --MappingKernelManager.cull_interval=5 \\
        --MappingKernelManager.cull_idle_timeout=10

Closing or leaving the page first stops the chair (the browser hook says the page is
going). Then the kernel must go: Voila's own shutdown request on closing (Voila 0.5.13)
is refused by its server (HTTP 403, the page carries no ``_xsrf`` cookie), so the
culling settings release it: the server shuts down a kernel that has no page connected
and has been idle for 10 s, checking every 5 s (a kernel with its page open is never
culled: ``cull_connected`` stays False). The dashboard's tasks end once the chair is
still and scanning ends after its rounds, so a closed page's kernel falls idle.
"""

from __future__ import annotations

import asyncio
import html
import math
import sys
import time
import uuid
from collections.abc import Callable
from pathlib import Path

from abcwc.behaviours.mission import Mission, MissionState
from abcwc.geometry import wrap_angle
from abcwc.perception.speech.commands import SpokenCommand
from abcwc.types import Pose2D
from abcwc.ui.access import DwellSelector, FrontEnd, SwitchScanner
from abcwc.ui.map_view import MapView

DRIVING_STATES = frozenset({MissionState.LOCALISING, MissionState.NAVIGATING,
                            MissionState.FOLLOWING, MissionState.WAITING})
"""The mission states in which the mission moves the chair."""
ON_BUSY = ("queue", "refuse")
VOILA_OPTIONS = ("--MappingKernelManager.cull_interval=5",
                 "--MappingKernelManager.cull_idle_timeout=10")
"""Voila's options for a dashboard page: release a kernel 10-15 s after its page went."""
VOILA_IP = "127.0.0.1"
"""Where Voila listens: this machine only (a page that drives a chair is not offered to
the network)."""
NOTEBOOK = Path(__file__).with_name("dashboard.ipynb")
"""The standalone page: a dashboard on a simulated chair (``abcwc dashboard``)."""
WORLD_VARIABLE = "ABCWC_DASHBOARD_WORLD"
"""The environment variable that names :data:`NOTEBOOK`'s world (a name or a .json
file; default the lab)."""
STOP = "stop"
STILL_WINDOW = 0.3  # s: the chair is still when its estimate moved less than
STILL_DISTANCE = 0.005  # m and
STILL_TURN = 0.01  # rad over the last STILL_WINDOW


def _positive(name: str, value: object, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
            value > 0 and not math.isnan(value)):
        raise ValueError(f"{name} must be a number > 0 {unit}, got {value!r}")
    return float(value)


class Dashboard:
    """Drive ``chair`` by ``mission`` (an :class:`abcwc.behaviours.mission.Mission`)
    from a live view (module notes).

    ``width`` is the map's width in CSS px; ``time_scale`` simulated seconds per wall
    second (``math.inf``: as fast as the machine goes; a real body keeps real time
    itself); the drive yields every ``yield_periods`` control periods and redraws at
    ``redraw_hz``; ``dwell`` starts with dwell to select on (a toggle in the view
    switches it), ``dwell_seconds`` and ``scan_seconds`` time the two ways of choosing
    without a hand, a scan ends after ``scan_rounds`` rounds with no press, and
    ``switch_key`` is the scanning switch (a ``KeyboardEvent.key``);
    ``on_busy`` says what a second command during an errand does ("queue" or "refuse").
    """

    def __init__(self, chair: object, mission: Mission, *, width: int = 760,
                 time_scale: float = 1.0, yield_periods: int = 5, redraw_hz: float = 10.0,
                 dwell: bool = False, dwell_seconds: float = 1.0, scan_seconds: float = 1.5,
                 scan_rounds: int = 3, switch_key: str = " ", on_busy: str = "queue"):
        import ipywidgets as widgets

        if on_busy not in ON_BUSY:
            raise ValueError(f"on_busy must be one of {ON_BUSY}, got {on_busy!r}")
        if isinstance(yield_periods, bool) or not isinstance(yield_periods, int) \
                or yield_periods < 1:
            raise ValueError(f"yield_periods must be a whole number >= 1, got "
                             f"{yield_periods!r}")
        self.time_scale = _positive("time_scale", time_scale, "(simulated s per wall s)")
        self.redraw_hz = _positive("redraw_hz", redraw_hz, "Hz")
        self.yield_periods, self.on_busy = yield_periods, on_busy
        self.chair, self.mission = chair, mission
        self.navigator = mission.navigator
        self.destinations = [name for name in mission.destinations if name != "start"]
        if not self.destinations:
            raise ValueError("the mission has no destinations (places other than 'start')")
        if STOP in self.destinations:
            raise ValueError(f"a destination may not be called {STOP!r}: it is the stop "
                             f"button's name")
        self.dwell = DwellSelector(dwell_seconds)
        self.scanner = SwitchScanner([*self.destinations, STOP], scan_seconds, scan_rounds)
        self.frame = chair.read()
        self.queued: tuple[str, Callable[[], object]] | None = None
        self.intervention: tuple[float, str] | None = None  # (t s, the filter's reason)
        self.redraw_times: list[float] = []  # loop s of every redraw while driving
        self.picks: list[tuple[str, str]] = []  # (how, option) of every choice made
        self._task: asyncio.Task | None = None
        self._scan_task: asyncio.Task | None = None
        self._loop = _running_loop()  # the one the dashboard drives from (module notes)
        self._track: list[tuple[float, float, float, float]] = []  # t, estimate x, y, th
        self._truth_speed = 0.0
        self.token = f"abcwc-{uuid.uuid4().hex[:8]}"

        world = getattr(chair, "world", None)
        self.map = MapView(self.navigator.global_costmap,
                           getattr(world, "walls", None),
                           {n: p for n, p in mission.destinations.items()},
                           chair.params, width=width)
        self.front_end = FrontEnd(token=self.token, switch_key=switch_key)
        self.front_end.on_msg(self._handler(self._on_front_end))
        self.front_end.observe(self._handler(self._on_pixel_ratio), names="pixel_ratio")
        big = widgets.Layout(width="220px", height="44px")
        self.buttons = {}
        for name in self.destinations:
            button = widgets.Button(description=name.replace("_", " "), layout=big,
                                    tooltip=f"go to the {name.replace('_', ' ')}")
            button.style.font_size = "16px"
            button.on_click(self._handler(lambda _b, name=name: self.choose(name, "button")))
            self.buttons[name] = button
        self.stop_button = widgets.Button(description="STOP", button_style="danger",
                                          tooltip="stop the chair now",
                                          layout=widgets.Layout(width="220px", height="90px"))
        self.stop_button.style.font_size = "30px"
        self.stop_button.style.font_weight = "bold"
        self.stop_button.on_click(self._handler(lambda _b: self.choose(STOP, "button")))
        self.buttons[STOP] = self.stop_button
        for name, button in self.buttons.items():
            button.add_class(self.token)
            button.add_class(f"{self.token}-{name}")
        self.command_box = widgets.Text(placeholder='type "go to the ..." and press enter',
                                        continuous_update=False,
                                        layout=widgets.Layout(width="400px"))
        self.command_box.observe(self._handler(self._on_typed), names="value")
        self.dwell_toggle = widgets.ToggleButton(
            value=bool(dwell), description="dwell to select",
            tooltip=f"rest the pointer on a choice for {self.dwell.dwell_seconds:g} s to "
                    f"pick it")
        self.dwell_toggle.observe(self._handler(lambda _change: self._light()), names="value")
        self.scan_toggle = widgets.ToggleButton(value=False, description="switch scanning",
                                                tooltip="light the choices in turn; the "
                                                "switch key picks the lit one")
        self.scan_toggle.observe(self._handler(self._on_scan_toggle), names="value")
        self.state_line = widgets.HTML()
        self.notice_line = widgets.HTML()
        self.safety_line = widgets.HTML()
        self.view_line = widgets.HTML()
        self.truth_line = widgets.HTML()
        self.access_line = widgets.HTML()
        for line, name in ((self.state_line, "state"), (self.notice_line, "notice"),
                           (self.safety_line, "safety"), (self.view_line, "view"),
                           (self.truth_line, "truth"), (self.access_line, "access")):
            line.add_class(f"abcwc-dashboard-{name}")
        self.map.image.add_class("abcwc-dashboard-map")
        self.map.image.add_class(f"{self.token}-map")  # the hook reports clicks on it
        side = widgets.VBox([self.stop_button, *[self.buttons[n] for n in self.destinations]],
                            layout=widgets.Layout(flex="0 0 auto"))
        self.widget = widgets.VBox([
            self.state_line,
            widgets.HBox([self.map.image, side]),
            widgets.HBox([self.command_box, self.dwell_toggle, self.scan_toggle]),
            self.notice_line, self.access_line, self.safety_line, self.view_line,
            self.truth_line, self.front_end])
        self._say("choose a destination")
        self.redraw()

    # ------------------------------------------------------------------ one loop
    def _home_loop(self) -> asyncio.AbstractEventLoop:
        """The event loop the dashboard drives from: the one running where it was made,
        else the first on which it is asked to act; RuntimeError when none runs."""
        if self._loop is None:
            self._loop = _event_loop()
        return self._loop

    def _handler(self, act: Callable[..., object]) -> Callable[..., None]:
        """``act`` as a widget callback that runs on the dashboard's own event loop,
        handed over to it when the message arrives on another thread's loop (module
        notes)."""

        def handle(*args: object) -> None:
            here = _running_loop()
            home = self._loop or here
            if home is None or here is home or home.is_closed():  # nothing to race
                act(*args)
            else:
                home.call_soon_threadsafe(act, *args)

        return handle

    # ------------------------------------------------------------------ showing
    def show(self) -> None:
        """Display the dashboard (in a notebook or a Voila page)."""
        from IPython.display import display

        display(self.widget)

    def _repr_mimebundle_(self, **kwargs: object) -> object:
        return self.widget._repr_mimebundle_(**kwargs)

    def close(self) -> None:
        """Stop the drive and the scanning, and close the widgets."""
        for task in (self._task, self._scan_task):
            if task is not None:
                task.cancel()
        self.chair.stop()
        _close_tree(self.widget)

    # ------------------------------------------------------------------ commands
    @property
    def busy(self) -> bool:
        """Whether the mission is driving (its state one of :data:`DRIVING_STATES`)."""
        return self.mission.state in DRIVING_STATES

    @property
    def driving(self) -> bool:
        """Whether the drive task runs (the mission drives or the chair still rolls)."""
        return self._task is not None and not self._task.done()

    def choose(self, option: str, how: str = "button") -> None:
        """``option`` (a destination or ``"stop"``) was picked ``how`` ("button",
        "dwell", "switch")."""
        self._home_loop()  # before anything changes
        self.picks.append((how, option))
        if how != "dwell":
            self.dwell.picked(option)
        if option == STOP:
            self.stop(f"stop picked by {how}" if how != "button" else "stop pressed")
        elif option in self.destinations:
            place = option
            self._request(f"go to the {place.replace('_', ' ')}",
                          lambda: self.mission.go_to(place, reason=f"{place} picked by {how}"))
        else:
            raise ValueError(f"unknown option {option!r}; allowed: "
                             f"{', '.join([*self.destinations, STOP])}")

    def command(self, text: str | SpokenCommand) -> None:
        """A typed command, in the mission's grammar; a phrase it does not know is
        shown with the list of those it does."""
        self._home_loop()  # before anything changes
        try:
            spoken = (text if isinstance(text, SpokenCommand)
                      else self.mission.commands.parse(text))
        except ValueError as error:
            self._say(html.escape(str(error)), "error")
            return
        if spoken.phrase == STOP:
            self.queued = None
            self.mission.command(text)
            self._say("stopped (typed); nothing queued")
            self._start_drive()
            return
        self._request(spoken.phrase, lambda: self.mission.command(text))

    def click(self, px: float, py: float) -> None:
        """A click on the map ``(px, py)`` CSS px from its top left: go to that point
        (:meth:`MapView.to_map <abcwc.ui.map_view.MapView.to_map>`); a click off the map
        is shown and does nothing."""
        self._home_loop()  # before anything changes
        try:
            x, y = self.map.to_map(px, py)
        except ValueError as error:
            self._say(html.escape(str(error)), "error")
            return
        self._request(f"go to ({x:.1f}, {y:.1f}) m",
                      lambda: self.mission.go_to((x, y), reason="map clicked"))

    def stop(self, reason: str = "stop pressed") -> None:
        """Stop at once (the chair brakes through the safety filter) and empty the queue."""
        self._home_loop()  # before anything changes
        dropped = self.queued
        self.queued = None
        self.mission.stop(reason)
        self._say(f"stopped ({html.escape(reason)})"
                  + (f"; dropped the queued \u201c{dropped[0]}\u201d" if dropped else ""))
        self._start_drive()

    def _request(self, label: str, start: Callable[[], object]) -> None:
        """Start ``label`` now, or queue or refuse it while an errand runs."""
        if self.busy:
            doing = self._doing()
            if self.on_busy == "refuse":
                self._say(f"refused \u201c{label}\u201d: still {doing}; press stop first",
                          "refused")
                return
            replaced = self.queued
            self.queued = (label, start)
            self._say(f"queued \u201c{label}\u201d: it starts when {doing} ends"
                      + (f" (instead of \u201c{replaced[0]}\u201d)" if replaced else ""),
                      "queued")
            return
        self._begin(label, start)

    def _begin(self, label: str, start: Callable[[], object]) -> None:
        try:
            start()
        except ValueError as error:
            self._say(f"\u201c{label}\u201d: {html.escape(str(error))}", "error")
            return
        if self.mission.state is MissionState.FAILED:  # a goal in a wall, no path, ...
            self._say(f"\u201c{label}\u201d failed at once: "
                      f"{html.escape(str(self.mission.reason))}", "error")
        else:
            self._say(f"started \u201c{label}\u201d")
        self._start_drive()

    def _doing(self) -> str:
        goal = self.mission.goal
        state = self.mission.state.value
        if isinstance(goal, str):
            return f"{state} to the {goal.replace('_', ' ')}"
        if isinstance(goal, Pose2D):
            return f"{state} to ({goal.x:.1f}, {goal.y:.1f})"
        return state

    def _on_typed(self, change: dict) -> None:
        text = change["new"].strip()
        if text:
            self.command_box.value = ""  # fires again with "", which is ignored
            self.command(text)

    # ------------------------------------------------------------------ driving
    def _start_drive(self) -> None:
        """Run the drive task on the running event loop unless it already runs."""
        if not self.driving:
            self._task = self._home_loop().create_task(self._drive())

    async def _drive(self) -> None:
        """Step the body, keeping to ``time_scale``, until the mission stops driving and
        the chair is still; then start the queued command, if any."""
        loop = asyncio.get_running_loop()
        wall0, t0 = loop.time(), self.frame.t
        self._track.clear()
        self.redraw_times.clear()
        last_draw = -math.inf
        # redraws fall on the yields: one is due half a yield early rather than a yield late
        chunk = self.yield_periods * self.chair.period / self.time_scale
        draw_every = max(0.0, 1.0 / self.redraw_hz - 0.5 * chunk)
        try:
            while True:
                before = self._truth()
                for _ in range(self.yield_periods):
                    self.chair.send(self.mission(self.frame),
                                    self.mission.decided_at)
                    self._note_safety()
                    self.frame = self.chair.step()
                self._note_motion(before)
                if not self.busy and self.queued is not None:
                    label, start = self.queued
                    self.queued = None
                    self._begin(label, start)
                if loop.time() - last_draw >= draw_every:
                    last_draw = loop.time()
                    self.redraw_times.append(last_draw)
                    self.redraw()
                if not self.busy and self._still():
                    break
                ahead = wall0 + (self.frame.t - t0) / self.time_scale - loop.time()
                await asyncio.sleep(max(0.0, ahead))
        except Exception as error:  # shown, not lost in a task nobody awaits
            self.chair.stop()
            self._say(f"the drive stopped on an error: {html.escape(repr(error))}", "error")
            raise
        self.redraw()

    def _note_safety(self) -> None:
        safety = getattr(self.chair, "safety", None)
        reason = getattr(safety, "reason", None)
        if reason:
            self.intervention = (self.frame.t, reason)

    def _truth(self) -> tuple[float, float, float] | None:
        pose = getattr(self.chair, "pose", None)  # a simulator's truth; a real body has none
        return (self.frame.t, pose.x, pose.y) if isinstance(pose, Pose2D) else None

    def _note_motion(self, before: tuple[float, float, float] | None) -> None:
        estimate = self.navigator.localizer.pose
        self._track.append((self.frame.t, estimate.x, estimate.y, estimate.theta))
        after = self._truth()
        if before is not None and after is not None and after[0] > before[0]:
            self._truth_speed = math.hypot(after[1] - before[1],
                                           after[2] - before[2]) / (after[0] - before[0])

    def _still(self) -> bool:
        """Whether the estimate moved less than STILL_DISTANCE m and STILL_TURN rad in
        the last STILL_WINDOW s."""
        if not self._track or self._track[-1][0] - self._track[0][0] < STILL_WINDOW:
            return False
        now = self._track[-1]
        recent = [row for row in self._track if row[0] >= now[0] - STILL_WINDOW]
        first = recent[0]
        turn = abs(wrap_angle(now[3] - first[3]))
        return math.hypot(now[1] - first[1], now[2] - first[2]) < STILL_DISTANCE \
            and turn < STILL_TURN

    # ------------------------------------------------------------------ showing
    def redraw(self) -> None:
        """Draw the map and write the status lines as they are now."""
        nav = self.navigator
        going = self.mission.goal is not None
        plan = nav.path.points if going and nav.path is not None else None
        self.map.draw(nav.localizer.pose, plan, nav.people.moving_discs(),
                      nav.goal if going else None)
        state = self.mission.state.value
        reason = html.escape(self.mission.reason)
        self.state_line.value = (f"<span style='font-size:20px'><b>{state}</b>"
                                 f"{' &mdash; ' + reason if reason else ''}</span>")
        if self.intervention is None:
            self.safety_line.value = "safety filter: no intervention yet"
        else:
            t, why = self.intervention
            self.safety_line.value = (f"safety filter, last intervention at t = {t:.1f} s: "
                                      f"{html.escape(why)}")
        rate = self.redraw_rate()
        self.view_line.value = ("view: " + (f"redrawn {rate:.1f} times/s while driving"
                                            if math.isfinite(rate) else "ready")
                                + f" (t = {self.frame.t:.1f} s)")
        truth = self._truth()
        if truth is not None:
            self.truth_line.value = (f"simulator truth: chair at ({truth[1]:.2f}, "
                                     f"{truth[2]:.2f}) m, moving at "
                                     f"{self._truth_speed:.2f} m/s")

    def redraw_rate(self) -> float:
        """Redraws per second (wall clock) over the latest drive; NaN before one."""
        times = self.redraw_times
        if len(times) < 3:
            return math.nan
        return (len(times) - 1) / (times[-1] - times[0])

    def _say(self, text: str, kind: str = "info") -> None:
        colour = {"refused": "#b00020", "error": "#b00020", "queued": "#8a5a00"}.get(
            kind, "#222")
        self.notice_line.value = (f"<span class='abcwc-{kind}' style='color:{colour}; "
                                  f"font-size:15px'>{text}</span>")

    # ------------------------------------------------------------------ access
    def _on_pixel_ratio(self, change: dict) -> None:
        self.map.set_pixel_ratio(float(change["new"]))
        self.redraw()

    def _on_front_end(self, _widget: object, content: dict, _buffers: object) -> None:
        event, option = content.get("event"), content.get("option")
        now = time.monotonic()
        if event == "enter" and option in self.buttons and self.dwell_toggle.value:
            self.dwell.enter(option, now)
            self._light()
            self._home_loop().call_later(self.dwell.dwell_seconds + 0.02,
                                                  self._dwell_check)
        elif event == "leave":
            self.dwell.leave(option, now)
            self._light()
        elif event == "map click":
            shown = (content.get("width"), content.get("height"))
            if all(isinstance(v, (int, float)) and v > 0 for v in shown):
                self.click(content["x"] * self.map.width / shown[0],
                           content["y"] * self.map.height / shown[1])
        elif event == "page closed":
            if self.busy or self.driving:
                self.stop("the page was closed")
        elif event == "switch":
            option = self.scanner.press(now)
            if option is not None:
                self.choose(option, "switch")

    def _dwell_check(self) -> None:
        option = self.dwell.poll(time.monotonic())
        if option is not None and self.dwell_toggle.value:
            self._light()
            self.choose(option, "dwell")

    def _on_scan_toggle(self, change: dict) -> None:
        if change["new"]:
            self.scanner.start(time.monotonic())
            self.front_end.scanning = True
            self._scan_task = self._home_loop().create_task(self._scan())
        else:
            self.scanner.stop()
            self.front_end.scanning = False
            if self._scan_task is not None and self._scan_task is not asyncio.current_task():
                self._scan_task.cancel()
                self._light()

    async def _scan(self) -> None:
        """Light the options in turn until scanning is switched off or its rounds end."""
        while self.scanner.scanning(time.monotonic()):
            self._light()
            now = time.monotonic()
            await asyncio.sleep(max(0.0, self.scanner.next_change(now) - now) + 0.005)
        self._scan_task = None
        self.scan_toggle.value = False
        self._light()
        self.access_line.value = (f"scanning ended after {self.scanner.rounds} rounds with "
                                  f"no press; switch it on again to choose")

    def _light(self) -> None:
        """Colour the buttons: the scanned one lit (warning), the dwelt-on one (info)."""
        now = time.monotonic()
        lit = self.scanner.lit(now)
        for name, button in self.buttons.items():
            base = "danger" if name == STOP else ""
            button.button_style = ("warning" if name == lit else
                                   "info" if name == self.dwell.option and name != STOP
                                   else base)
        if lit is not None:
            self.access_line.value = (f"scanning: <b class='abcwc-lit'>{lit}</b> is lit; "
                                      f"press {self._key_name()} to pick it")
        elif self.dwell.option is not None:
            self.access_line.value = (f"dwell: resting on <b>{self.dwell.option}</b>, "
                                      f"picked after {self.dwell.dwell_seconds:g} s")
        else:
            self.access_line.value = ""

    def _key_name(self) -> str:
        key = self.front_end.switch_key
        return "space" if key == " " else key


def voila_command(port: int = 8866, open_browser: bool = True,
                  notebook: Path = NOTEBOOK) -> list[str]:
    """The command that serves ``notebook`` as a standalone page with Voila on
    ``port``, on :data:`VOILA_IP`, with :data:`VOILA_OPTIONS` (a closed page's kernel is
    released), opening the page in a browser if ``open_browser``."""
    if isinstance(port, bool) or not isinstance(port, int) or not 1 <= port <= 65535:
        raise ValueError(f"the port must be a whole number 1..65535, got {port!r}")
    return [sys.executable, "-m", "voila", str(notebook), f"--port={port}",
            f"--Voila.ip={VOILA_IP}", *VOILA_OPTIONS,
            *([] if open_browser else ["--no-browser"])]


def _running_loop() -> asyncio.AbstractEventLoop | None:
    """The event loop running in this thread, or None."""
    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        return None


def _event_loop() -> asyncio.AbstractEventLoop:
    """The running event loop; RuntimeError saying what is needed when none runs."""
    try:
        return asyncio.get_running_loop()
    except RuntimeError:
        raise RuntimeError("the dashboard drives from a running asyncio event loop (a "
                           "Jupyter kernel's, or one started with asyncio.run); there is "
                           "none here") from None


def _close_tree(widget: object) -> None:
    """Close ``widget`` and every widget inside it."""
    for child in getattr(widget, "children", ()):
        _close_tree(child)
    widget.close()
