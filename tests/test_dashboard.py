"""The dashboard's logic without a browser: errands checked against the simulator's
truth, the queue and refusal, stop, typed commands, the asyncio drive's pacing and
redraw rate, dwell and switch scanning (their clocks and the browser hook's messages),
and a map drawn at its shown size. The browser tests are tests/test_dashboard_browser.py."""

from __future__ import annotations

import asyncio
import io
import math
import time

import numpy as np
import pytest
from PIL import Image

from abcwc.behaviours.mission import Mission
from abcwc.sim import SimBase
from abcwc.sim.world import load_world
from abcwc.ui.access import DwellSelector, SwitchScanner
from abcwc.ui.dashboard import Dashboard
from abcwc.ui.map_view import CSS_DPI, MARGINS, MapView
from abcwc.ui.teleop import TeleopPanel

LAB = load_world("lab").places


def _dashboard(**options: object) -> Dashboard:
    chair = SimBase("lab", seed=1, lidar=True, people=False)
    options.setdefault("time_scale", math.inf)
    return Dashboard(chair, Mission.for_world(chair.world, chair=chair), **options)


def _distance(pose: object, place: str) -> float:
    return math.hypot(pose.x - LAB[place].x, pose.y - LAB[place].y)


async def _until(condition, seconds: float = 30.0) -> None:
    """Let the event loop run until ``condition()`` holds (wall ``seconds`` at most)."""
    deadline = time.monotonic() + seconds
    while not condition():
        assert time.monotonic() < deadline, "timed out"
        await asyncio.sleep(0.005)


async def _drive_ends(d: Dashboard) -> None:
    while d.driving:
        await d._task


def _rests(d: Dashboard, periods: int = 25) -> float:
    """m the chair's true pose moves over ``periods`` more periods of the mission."""
    before = d.chair.pose
    for _ in range(periods):
        d.chair.send(d.mission(d.frame), d.mission.decided_at)
        d.frame = d.chair.step()
    return math.hypot(d.chair.pose.x - before.x, d.chair.pose.y - before.y)


# ---------------------------------------------------------------- errands
def test_a_destination_button_drives_the_chair_there():
    async def errand():
        d = _dashboard()
        d.buttons["centre"].click()
        assert d.driving and "started" in d.notice_line.value
        await _drive_ends(d)
        return d

    d = asyncio.run(errand())
    assert _distance(d.chair.pose, "centre") < 0.35  # the navigator's tolerance and some
    assert d.mission.state == "arrived" and "arrived" in d.state_line.value
    assert _rests(d) < 0.01
    assert "moving at 0.0" in d.truth_line.value


def test_a_click_on_the_map_drives_the_chair_to_that_point():
    """The browser hook's message for a click (CSS px on the image as shown, here shown
    at twice its size) reaches the mission as go_to((x, y)) in metres."""
    target = (7.0, 6.0)  # free floor in the lab, away from its places

    async def clicked():
        d = _dashboard()
        px, py = d.map.to_pixel(*target)
        d._on_front_end(None, {"event": "map click", "x": 2 * px, "y": 2 * py,
                               "width": 2 * d.map.width, "height": 2 * d.map.height}, None)
        assert d.driving and "started" in d.notice_line.value
        await _drive_ends(d)
        return d

    d = asyncio.run(clicked())
    assert d.mission.state == "arrived" and "(7.00, 6.00) m" in d.mission.reason
    assert math.hypot(d.chair.pose.x - target[0], d.chair.pose.y - target[1]) < 0.35
    assert _rests(d) < 0.01


def test_a_click_off_the_map_is_refused_in_the_view():
    async def clicked():
        d = _dashboard()
        d.click(5.0, 5.0)  # in the left margin, over the y axis's labels
        return d

    d = asyncio.run(clicked())
    assert "off the map" in d.notice_line.value and d.mission.transitions == []


def test_a_clicked_pixel_is_turned_into_metres_through_the_views_transform():
    """The corners of the plotted map sit MARGINS CSS px in from the image's edges (the
    axes box the view builds), at any pixel ratio; a click there is the map's corner."""
    view = _dashboard().map
    left, right, top, bottom = MARGINS
    x0, x1, y0, y1 = view.extent
    for ratio in (1.0, 2.0):
        view.set_pixel_ratio(ratio)
        assert view.to_map(left, view.height - bottom) == pytest.approx((x0, y0), abs=1e-6)
        assert view.to_map(view.width - right, top) == pytest.approx((x1, y1), abs=1e-6)
        # metres per CSS px: the map's size over the axes box's
        across = (x1 - x0) / (view.width - left - right)
        up = (y1 - y0) / (view.height - top - bottom)
        x, y = view.to_map(left + 100, view.height - bottom - 50)
        assert (x, y) == pytest.approx((x0 + 100 * across, y0 + 50 * up), abs=1e-6)
    with pytest.raises(ValueError, match="off the map"):
        view.to_map(left - 5, top + 20)
    with pytest.raises(ValueError, match="finite"):
        view.to_map(float("nan"), 20.0)


def test_widget_messages_on_another_threads_loop_act_on_the_dashboards_own():
    """JupyterLab may handle widget messages on a kernel subshell (another thread with
    its own event loop): a button pressed there must change the mission on the
    dashboard's thread, between the drive's steps, never in the middle of one."""
    import threading

    acted_on = []
    home = threading.get_ident()

    def on_a_subshell(press) -> None:
        async def handle() -> None:  # with a running loop of this thread's own
            press()

        asyncio.run(handle())

    async def errand():
        d = _dashboard(time_scale=1.0)
        for name in ("go_to", "stop"):
            method = getattr(d.mission, name)
            setattr(d.mission, name, lambda *a, _m=method, _n=name, **k: (
                acted_on.append((_n, threading.get_ident())), _m(*a, **k))[1])
        loop = asyncio.get_running_loop()
        await loop.run_in_executor(None, on_a_subshell, d.buttons["door"].click)
        await _until(lambda: d.frame.t > 1.0, 10.0)
        await loop.run_in_executor(None, on_a_subshell, d.stop_button.click)
        await _drive_ends(d)
        return d

    d = asyncio.run(errand())
    assert [name for name, _ in acted_on] == ["go_to", "stop"]
    assert all(thread == home for _, thread in acted_on)
    assert [t.after for t in d.mission.transitions] == ["navigating", "idle"]
    assert _rests(d) < 0.01


def test_a_second_command_while_driving_is_queued_then_run():
    async def errands():
        d = _dashboard(on_busy="queue")
        d.choose("centre")
        await _until(lambda: d.frame.t > 2.0)
        d.buttons["bench"].click()
        notice = d.notice_line.value
        assert d.queued is not None
        await _drive_ends(d)
        return d, notice

    d, notice = asyncio.run(errands())
    assert "queued" in notice and "go to the bench" in notice and "centre" in notice
    assert [t.after for t in d.mission.transitions] == ["navigating", "arrived",
                                                        "navigating", "arrived"]
    assert _distance(d.chair.pose, "bench") < 0.35
    assert d.queued is None


def test_a_second_command_while_driving_is_refused_when_so_set():
    async def errands():
        d = _dashboard(on_busy="refuse")
        d.choose("centre")
        await _until(lambda: d.frame.t > 2.0)
        d.command("go to the bench")
        notice = d.notice_line.value
        await _drive_ends(d)
        return d, notice

    d, notice = asyncio.run(errands())
    assert "refused" in notice and "go to the bench" in notice and "press stop" in notice
    assert [t.after for t in d.mission.transitions] == ["navigating", "arrived"]
    assert _distance(d.chair.pose, "centre") < 0.35


def test_stop_mid_drive_stops_the_chair_and_drops_the_queue():
    async def errand():
        d = _dashboard()
        d.choose("door")
        await _until(lambda: d.frame.t > 3.0)
        d.choose("table")  # queued
        speed = d._truth_speed
        d.stop_button.click()
        await _drive_ends(d)
        return d, speed

    d, speed = asyncio.run(errand())
    assert speed > 0.2  # it was driving when stop was pressed
    assert d.mission.state == "idle" and d.queued is None
    assert "dropped the queued" in d.notice_line.value
    assert _distance(d.chair.pose, "door") > 1.0
    assert _rests(d) < 0.01


def test_typed_commands_go_through_the_grammar():
    async def typed():
        d = _dashboard()
        d.command_box.value = "fly to the moon"
        refused = d.notice_line.value
        d.command_box.value = "Go to the table."
        assert d.command_box.value == ""
        await _drive_ends(d)
        return d, refused

    d, refused = asyncio.run(typed())
    assert "is not a command" in refused and "go to the table" in refused
    assert '"go to the table"' in d.mission.transitions[0].reason
    assert _distance(d.chair.pose, "table") < 0.35


def test_an_errand_that_fails_at_once_says_why():
    from abcwc.sim.world import world_from_dict

    box = world_from_dict({"name": "box", "walls": [[[0, 0], [8, 0], [8, 8], [0, 8], [0, 0]]],
                           "places": {"start": [2.0, 2.0, 0.0], "shelf": [8.0, 4.0, 0.0]}})

    async def walled():
        chair = SimBase(box, seed=1, lidar=True, people=False)
        d = Dashboard(chair, Mission.for_world(box, chair=chair), time_scale=math.inf)
        d.choose("shelf")  # on the east wall
        await _drive_ends(d)
        return d

    d = asyncio.run(walled())
    assert d.mission.state == "failed"
    assert "failed at once" in d.notice_line.value and "inside a wall" in d.notice_line.value
    assert _rests(d) < 0.01


def test_the_drive_yields_to_the_event_loop_and_keeps_real_time():
    """At real time the drive task sleeps between chunks: other coroutines (the widget
    messages' handlers) run meanwhile, the simulated clock keeps to the wall clock and
    the map is redrawn at least 5 times a second, each time a different picture."""
    pictures = []

    async def drive():
        d = _dashboard(time_scale=1.0)
        d.map.image.observe(lambda change: pictures.append(change["new"]), names="value")
        ticks = 0
        d.choose("door")
        start, t0 = time.monotonic(), d.frame.t
        while time.monotonic() - start < 2.0:
            await asyncio.sleep(0.01)
            ticks += 1
        simulated = d.frame.t - t0
        d.stop()
        await _drive_ends(d)
        return d, ticks, simulated

    d, ticks, simulated = asyncio.run(drive())
    assert ticks > 100  # a 10 ms ticker ran all along
    assert simulated == pytest.approx(2.0, abs=0.3)
    assert d.redraw_rate() >= 5.0
    assert len(pictures) >= 10 and len(set(pictures)) >= 0.9 * len(pictures)


# ---------------------------------------------------------------- access
def test_dwell_picks_once_after_the_dwell_time():
    dwell = DwellSelector(0.8)
    dwell.enter("table", 10.0)
    assert dwell.poll(10.7) is None and dwell.progress(10.4) == pytest.approx(0.5)
    assert dwell.poll(10.8) == "table"
    assert dwell.poll(12.0) is None  # once per dwell
    dwell.leave("table", 12.1)
    dwell.enter("table", 12.2)
    dwell.leave("table", 12.9)  # left before the time: nothing
    assert dwell.poll(13.5) is None
    dwell.enter("door", 14.0)
    dwell.picked("door")  # clicked: the dwell picks nothing more
    assert dwell.poll(15.0) is None
    with pytest.raises(ValueError, match="dwell_seconds"):
        DwellSelector(0.0)


def test_switch_scanning_lights_each_option_in_turn_and_ends_after_its_rounds():
    scan = SwitchScanner(["a", "b", "c"], scan_seconds=0.5, rounds=2)
    assert scan.lit(0.0) is None and not scan.scanning(0.0)
    scan.start(10.0)
    assert [scan.lit(10.0 + 0.5 * k + 0.1) for k in range(7)] == \
        ["a", "b", "c", "a", "b", "c", None]
    assert scan.next_change(10.6) == pytest.approx(11.0)
    assert scan.longest_wait == pytest.approx(1.5)
    assert scan.press(11.2) == "c"  # and starts again from the first
    assert scan.lit(11.3) == "a"
    with pytest.raises(ValueError, match="rounds"):
        SwitchScanner(["a"], rounds=0)
    with pytest.raises(ValueError, match="at least one option"):
        SwitchScanner([])


def test_dwell_and_the_switch_pick_through_the_browser_hooks_messages():
    async def access():
        d = _dashboard(dwell_seconds=0.3, scan_seconds=0.15)
        d._on_front_end(None, {"event": "enter", "option": "table"}, None)
        await asyncio.sleep(0.5)
        off = d.mission.transitions[:]  # dwell is off by default: nothing picked
        d.dwell_toggle.value = True
        d._on_front_end(None, {"event": "leave", "option": "table"}, None)
        d._on_front_end(None, {"event": "enter", "option": "table"}, None)
        await asyncio.sleep(0.15)
        early = d.mission.transitions[:]
        await _until(lambda: d.mission.state == "navigating", 2.0)
        d._on_front_end(None, {"event": "leave", "option": "table"}, None)
        d.stop()
        await _drive_ends(d)
        d.scan_toggle.value = True
        assert d.front_end.scanning
        await _until(lambda: "bench</b> is lit" in d.access_line.value, 2.0)  # as seen
        assert d.buttons["bench"].button_style == "warning"
        d._on_front_end(None, {"event": "switch"}, None)
        picked = d.mission.transitions[-1].reason
        d.stop()
        await _drive_ends(d)
        # three rounds of six options at 0.15 s, then scanning switches itself off
        await _until(lambda: not d.scan_toggle.value, 5.0)
        return d, off, early, picked

    d, off, early, picked = asyncio.run(access())
    assert off == [] and early == []
    assert d.mission.transitions[0].reason.startswith("table picked by dwell")
    assert picked.startswith("bench picked by switch")
    assert not d.front_end.scanning and "scanning ended" in d.access_line.value
    assert ("switch", "bench") in d.picks


def test_it_drives_the_firmware_in_the_loop_body_the_same_way(harness_files):
    """The same dashboard on our firmware on a simulated Arduino (simavr) driving the
    simulated chair: the body a demo on the real chair's interface uses."""
    from abcwc.hw.fil_base import FirmwareInLoopBase
    chair = FirmwareInLoopBase("lab", seed=1, lidar=True, people=False, build=False)
    try:
        async def errand():
            d = Dashboard(chair, Mission.for_world(chair.world, chair=chair),
                          time_scale=math.inf)
            d.choose("centre")
            await _drive_ends(d)
            return d

        d = asyncio.run(errand())
        assert d.mission.state == "arrived"
        assert _distance(chair.pose, "centre") < 0.35
        assert _rests(d) < 0.01
    finally:
        chair.close()


def test_the_safety_filters_last_intervention_is_shown():
    async def deflected():
        d = _dashboard()
        d.choose("door")
        await _until(lambda: d.frame.t > 2.0)
        before = d.safety_line.value
        d.chair.set_joystick(fb=128, lr=180)  # a hand on the joystick: it wins
        await _until(lambda: d.frame.t > 2.6)
        d.chair.release_joystick()
        d.stop()
        await _drive_ends(d)
        return d, before

    d, before = asyncio.run(deflected())
    assert before == "safety filter: no intervention yet"
    assert "last intervention at t = " in d.safety_line.value
    assert "joystick" in d.safety_line.value


def test_closing_the_page_stops_the_chair():
    async def closing():
        d = _dashboard()
        d.choose("door")
        await _until(lambda: d.frame.t > 2.0)
        d._on_front_end(None, {"event": "page closed"}, None)
        await _drive_ends(d)
        return d

    d = asyncio.run(closing())
    assert d.mission.state == "idle" and d.mission.reason == "the page was closed"
    assert _distance(d.chair.pose, "door") > 1.0


# ---------------------------------------------------------------- drawing
def _png_size(png: bytes) -> tuple[int, int]:
    return Image.open(io.BytesIO(png)).size


def test_the_map_is_drawn_at_its_shown_size_times_the_pixel_ratio():
    d = _dashboard(width=700)
    view = d.map
    assert view.image.layout.width == "700px"
    assert view.image.layout.height == f"{view.height}px"
    assert _png_size(view.image.value) == (700, view.height)
    d.front_end.pixel_ratio = 2.0  # what the browser reports
    assert _png_size(view.image.value) == (1400, 2 * view.height)
    # metres per CSS px the same across and up: the map is not stretched
    (x0, y0), (x1, y1) = view.to_pixel(0.0, 0.0), view.to_pixel(10.0, 5.0)
    assert (x1 - x0) / 10.0 == pytest.approx((y0 - y1) / 5.0, rel=0.01)
    sizes = [text.get_fontsize() * CSS_DPI / 72.0 for text in view.ax.figure.findobj(
        lambda artist: hasattr(artist, "get_fontsize") and artist.get_text())]
    assert len(sizes) > 10 and min(sizes) >= 11.0


def test_the_chair_is_drawn_over_the_goal_ring():
    view = MapView(_dashboard().navigator.global_costmap, None, {},
                   SimBase("lab").params, width=760)
    goal = LAB["centre"]
    ring = view._goal.get_markersize() * CSS_DPI / 72.0 / 2  # the ring's radius, CSS px
    ring_css = view.to_pixel(goal.x, goal.y)[0] + ring, view.to_pixel(goal.x, goal.y)[1]

    def pixel(png: bytes) -> np.ndarray:
        image = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=int)
        return image[round(ring_css[1]), round(ring_css[0])]

    ring_alone = pixel(view.draw(None, goal=goal))
    under_chair = pixel(view.draw(goal, goal=goal))
    orange = np.array([255, 127, 14])
    assert np.abs(ring_alone - orange).sum() < 60
    assert np.abs(under_chair - orange).sum() > 150


def test_tracked_people_are_drawn_where_they_are():
    view = _dashboard().map
    person = np.array([[8.0, 6.5, 0.5, 0.0, 0.3]])  # x, y, vx, vy, radius
    css = view.to_pixel(8.0, 6.5)

    def pixel(png: bytes) -> np.ndarray:
        image = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"), dtype=int)
        return image[round(css[1]), round(css[0])]

    empty, with_person = pixel(view.draw(None)), pixel(view.draw(None, people=person))
    assert np.abs(with_person - empty).sum() > 100


def test_the_teleop_panel_is_sharp_at_its_size():
    panel = TeleopPanel(SimBase("lab"), size=(600, 400))
    assert panel.image.layout.width == "600px" and panel.image.layout.height == "400px"
    assert _png_size(panel.image.value) == (600, 400)
    panel.front_end.pixel_ratio = 2.0
    assert _png_size(panel.image.value) == (1200, 800)
    with pytest.raises(ValueError, match="size"):
        TeleopPanel(SimBase("lab"), size=(100, 50))


def test_it_needs_an_event_loop_to_drive_and_closes_only_its_own_widgets():
    import ipywidgets

    d = _dashboard()
    with pytest.raises(RuntimeError, match="running asyncio event loop"):
        d.choose("centre")
    assert d.mission.state == "idle" and d.mission.transitions == []
    other = ipywidgets.Button()
    d.close()
    assert d.map.image.comm is None and d.stop_button.comm is None
    assert other.comm is not None


@pytest.mark.parametrize("options, message", [
    ({"on_busy": "ignore"}, "on_busy must be one of"),
    ({"yield_periods": 0}, "yield_periods"),
    ({"time_scale": 0.0}, "time_scale"),
    ({"redraw_hz": -1.0}, "redraw_hz"),
    ({"dwell_seconds": float("nan")}, "dwell_seconds"),
    ({"scan_rounds": 0}, "rounds"),
    ({"width": 100}, "width"),
])
def test_bad_options_are_refused_saying_what_is_allowed(options, message):
    with pytest.raises(ValueError, match=message):
        _dashboard(**options)
