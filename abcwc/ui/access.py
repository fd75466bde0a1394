"""Choosing without a hand: dwell to select and switch scanning, and the browser hook
that carries the pointer, the switch and the screen's pixel ratio to the kernel.

The thesis's riders choose by gaze, by head gesture or by a sip-and-puff switch (its
1.1 and 5.3.4). Two ways of choosing serve them:

* **Dwell to select** (:class:`DwellSelector`): the pointer resting on an option for
  ``dwell_seconds`` picks it, so an eye tracker or a head mouse that only moves the
  pointer is enough. A short dwell is quick but picks what the eyes merely rest on while
  reading (the "Midas touch" of gaze interfaces, Jacob 1991); a long one is safe but
  slow and tiring. An option picked once is not picked again until the pointer leaves it.
* **Switch scanning** (:class:`SwitchScanner`): the options light up in turn,
  ``scan_seconds`` each, and one switch (a key, a sip-and-puff tube, a big button) picks
  the lit one. The wait for an option is up to ``scan_seconds x number of options``
  (half that on average), so a fast scan saves time but asks for a quick, exact press
  that a rider with slow or tremulous movement misses, picking the neighbour instead.

The logic here is plain Python with an explicit clock (s), so it is tested without a
browser. :class:`FrontEnd` is the small browser hook (an anywidget, which runs in
JupyterLab and in Voila alike): ipywidgets has no hover event and no document-wide key
press, and an image widget no click, so it reports the pointer entering and leaving the
option buttons (marked with CSS classes), the switch key while scanning is on, a click
on the map, ``window.devicePixelRatio``, and that the page is being closed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import anywidget
import traitlets


def _seconds(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
            math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a finite number of seconds > 0, got {value!r}")
    return float(value)


class DwellSelector:
    """Pick the option the pointer has rested on for ``dwell_seconds`` (s).

    Call :meth:`enter` and :meth:`leave` as the pointer moves (with the time, s) and
    :meth:`poll` to learn whether a dwell has completed; each dwell picks once.
    """

    def __init__(self, dwell_seconds: float = 1.0):
        self.dwell_seconds = _seconds("dwell_seconds", dwell_seconds)
        self.option: str | None = None  # under the pointer
        self._since = math.nan
        self._picked = False

    def enter(self, option: str, t: float) -> None:
        """The pointer came onto ``option`` at ``t`` s."""
        if option != self.option:
            self.option, self._since, self._picked = option, float(t), False

    def leave(self, option: str | None = None, t: float | None = None) -> None:
        """The pointer left ``option`` (default whichever it was on)."""
        if option is None or option == self.option:
            self.option, self._since, self._picked = None, math.nan, False

    def picked(self, option: str) -> None:
        """``option`` was picked another way (clicked): its dwell picks nothing more."""
        if option == self.option:
            self._picked = True

    def progress(self, t: float) -> float:
        """How far the current dwell has gone, 0..1 (0 when on no option)."""
        if self.option is None or self._picked:
            return 0.0
        return min(1.0, max(0.0, (t - self._since) / self.dwell_seconds))

    def poll(self, t: float) -> str | None:
        """The option picked at ``t`` s, once per dwell; None otherwise."""
        if self.option is None or self._picked or t - self._since < self.dwell_seconds:
            return None
        self._picked = True
        return self.option


class SwitchScanner:
    """Light ``options`` in turn, ``scan_seconds`` each, from :meth:`start`; a switch
    press picks the lit one and starts the scan again from the first option. After
    ``rounds`` rounds with no press the scan ends (nothing is lit), as scanning
    keyboards pause rather than cycle for a rider who has looked away."""

    def __init__(self, options: Sequence[str], scan_seconds: float = 1.5, rounds: int = 3):
        if not options:
            raise ValueError("switch scanning needs at least one option")
        if isinstance(rounds, bool) or not isinstance(rounds, int) or rounds < 1:
            raise ValueError(f"rounds must be a whole number >= 1, got {rounds!r}")
        self.options = list(options)
        self.scan_seconds = _seconds("scan_seconds", scan_seconds)
        self.rounds = rounds
        self.started: float | None = None

    def scanning(self, t: float) -> bool:
        """Whether an option is lit at ``t`` s (started, and not past its rounds)."""
        return self._turn(t) is not None

    def _turn(self, t: float) -> int | None:
        if self.started is None:
            return None
        turn = math.floor((t - self.started) / self.scan_seconds)
        return turn if turn < self.rounds * len(self.options) else None

    def start(self, t: float) -> None:
        """Start scanning at ``t`` s, the first option lit."""
        self.started = float(t)

    def stop(self) -> None:
        self.started = None

    def lit(self, t: float) -> str | None:
        """The option lit at ``t`` s (None when not scanning)."""
        turn = self._turn(t)
        return None if turn is None else self.options[turn % len(self.options)]

    def next_change(self, t: float) -> float:
        """When (s) the light moves on after ``t``."""
        turn = self._turn(t)
        return math.inf if turn is None else self.started + (turn + 1) * self.scan_seconds

    def press(self, t: float) -> str | None:
        """The switch was pressed at ``t`` s: the lit option (None when none is lit);
        the scan starts again from the first option."""
        option = self.lit(t)
        if option is not None:
            self.start(t)
        return option

    @property
    def longest_wait(self) -> float:
        """s: the longest wait for an option to light (scan time x number of options)."""
        return self.scan_seconds * len(self.options)


_ESM = """
function optionOf(element, token) {
  for (const name of element.classList) {
    if (name.startsWith(token + "-")) return name.slice(token.length + 1);
  }
  return null;
}

function render({ model, el }) {
  const token = model.get("token");
  el.style.display = "none";
  const reportRatio = () => {
    model.set("pixel_ratio", window.devicePixelRatio || 1);
    model.save_changes();
  };
  reportRatio();
  const ratioQuery = window.matchMedia(`(resolution: ${window.devicePixelRatio}dppx)`);
  ratioQuery.addEventListener("change", reportRatio);
  let current = null;
  const over = (event) => {
    const target = event.target.closest ? event.target.closest("." + token) : null;
    const option = target ? optionOf(target, token) : null;
    if (option === current) return;
    if (current !== null) model.send({ event: "leave", option: current });
    if (option !== null) model.send({ event: "enter", option: option });
    current = option;
  };
  // the switch: taken before the page sees it (no scrolling, no focused button pressed)
  const isSwitch = (event) => {
    if (!model.get("scanning") || event.key !== model.get("switch_key")) return false;
    const tag = (event.target.tagName || "").toLowerCase();
    return tag !== "input" && tag !== "textarea";
  };
  const keyDown = (event) => {
    if (!isSwitch(event)) return;
    event.preventDefault();
    event.stopPropagation();
    if (document.activeElement && document.activeElement.tagName === "BUTTON") {
      document.activeElement.blur();
    }
    if (!event.repeat) model.send({ event: "switch" });
  };
  const keyUp = (event) => {
    if (!isSwitch(event)) return;
    event.preventDefault();
    event.stopPropagation();
  };
  // a click on the map: where, in CSS px from the image's top left, and its shown size
  const click = (event) => {
    const map = event.target.closest ? event.target.closest("." + token + "-map") : null;
    if (map === null) return;
    const box = map.getBoundingClientRect();
    model.send({ event: "map click", x: event.clientX - box.left, y: event.clientY - box.top,
                 width: box.width, height: box.height });
  };
  // the page is going (closed, reloaded, left): the kernel may still drive a chair
  const leaving = () => model.send({ event: "page closed" });
  document.addEventListener("pointerover", over, true);
  document.addEventListener("keydown", keyDown, true);
  document.addEventListener("keyup", keyUp, true);
  document.addEventListener("click", click, true);
  window.addEventListener("beforeunload", leaving);
  return () => {
    window.removeEventListener("beforeunload", leaving);
    document.removeEventListener("pointerover", over, true);
    document.removeEventListener("keydown", keyDown, true);
    document.removeEventListener("keyup", keyUp, true);
    document.removeEventListener("click", click, true);
    ratioQuery.removeEventListener("change", reportRatio);
  };
}
export default { render };
"""


class FrontEnd(anywidget.AnyWidget):
    """The invisible browser hook (module notes). Options are elements with the CSS
    classes ``token`` and ``token-<option>``, the map the element with the class
    ``token-map``; messages arrive through ``on_msg`` as
    ``{"event": "enter" | "leave", "option": name}``, ``{"event": "switch"}``,
    ``{"event": "map click", "x": px, "y": px, "width": px, "height": px}`` (where the
    map was clicked from its top left and the size it is shown at, CSS px) and, when
    the page is closed or left, ``{"event": "page closed"}``."""

    _esm = _ESM
    token = traitlets.Unicode("").tag(sync=True)
    scanning = traitlets.Bool(False).tag(sync=True)
    switch_key = traitlets.Unicode(" ").tag(sync=True)
    pixel_ratio = traitlets.Float(1.0).tag(sync=True)
