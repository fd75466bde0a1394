"""The dashboard as a rider uses it, in a real browser (Debian's ``chromium`` driven by
Playwright), in JupyterLab and as the standalone Voila page exactly as ``abcwc dashboard``
serves it (the package's notebook, the same Voila command): a destination button drives
the chair there (checked against the simulator's truth), the map redraws while it
drives (screenshots differ), a second command is queued or refused in the view, stop
stops it (truth speed ~0), dwell and switch scanning pick destinations, a click on the
map (JupyterLab) sends the chair to the point clicked, the map is drawn
at its shown size times the device pixel ratio, and closing the Voila page releases its
kernel process."""

from __future__ import annotations

import os
import re
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import nbformat
import pytest

from abcwc.hub import free_port
from abcwc.ui.dashboard import VOILA_IP, WORLD_VARIABLE, voila_command
from tests.browser_helpers import CHROMIUM, require_browser

CENTRE = (5.0, 4.0)  # the lab world's places the errands go to
BENCH = (6.8, 3.2)
TRUTH = re.compile(r"chair at \(([-\d.]+), ([-\d.]+)\) m, moving at ([-\d.]+) m/s")


def _notebook(path: Path, on_busy: str) -> None:
    """A notebook whose one cell shows a dashboard on the lab world's simulator."""
    notebook = nbformat.v4.new_notebook()
    notebook.cells = [nbformat.v4.new_code_cell(
        "from abcwc.sim import SimBase\n"
        "from abcwc.ui.dashboard import Dashboard\n"
        "from abcwc.behaviours.mission import Mission\n"
        "chair = SimBase('lab', seed=1, lidar=True, people=False)\n"
        "dashboard = Dashboard(chair, Mission.for_world(chair.world, chair=chair),\n"
        f"                      dwell_seconds=0.8, scan_seconds=1.0, on_busy={on_busy!r})\n"
        "dashboard")]
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                       "language": "python"}
    nbformat.write(notebook, path)


def _serve(command: list[str], port: int, log: Path,
           env: dict[str, str] | None = None) -> subprocess.Popen:
    """Start a server, its output to ``log``, and wait until it listens on ``port`` (a
    GET could start a kernel)."""
    with open(log, "wb") as out:
        server = subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT, env=env)
    deadline = time.monotonic() + 60
    while True:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=2).close()
            return server
        except OSError:
            if time.monotonic() > deadline or server.poll() is not None:
                server.kill()
                pytest.fail(f"{command[2]} did not start within 60 s")
            time.sleep(0.5)


def _stop(server: subprocess.Popen) -> None:
    server.terminate()
    try:
        server.wait(timeout=10)
    except subprocess.TimeoutExpired:
        server.kill()


@pytest.fixture
def lab(tmp_path) -> Iterator[str]:
    """JupyterLab serving a dashboard notebook (second commands refused)."""
    require_browser()
    _notebook(tmp_path / "dashboard.ipynb", on_busy="refuse")
    port = free_port()
    url = f"http://127.0.0.1:{port}/"
    server = _serve(
        [sys.executable, "-m", "jupyter", "lab", "--no-browser", f"--port={port}",
         "--ServerApp.token=", "--ServerApp.password=", "--ServerApp.ip=127.0.0.1",
         f"--ServerApp.root_dir={tmp_path}", "--LabApp.news_url=",
         "--ServerApp.disable_check_xsrf=True", "--allow-root"], port,
        tmp_path / "server.log")
    try:
        yield url + "lab/tree/dashboard.ipynb"
    finally:
        _stop(server)


@pytest.fixture
def voila(tmp_path) -> Iterator[tuple[str, subprocess.Popen, Path]]:
    """The standalone page as ``abcwc dashboard --world lab --no-browser`` serves it:
    the package's notebook, Voila run by the same command (second commands queued, the
    dashboard's default; a closed page's kernel culled)."""
    require_browser()
    port = free_port()
    url = f"http://{VOILA_IP}:{port}/"
    log = tmp_path / "server.log"
    server = _serve(voila_command(port, open_browser=False), port, log,
                    env={**os.environ, WORLD_VARIABLE: "lab"})
    try:
        yield url, server, log
    finally:
        _stop(server)


def _truth(page) -> tuple[float, float, float]:
    text = page.locator(".abcwc-dashboard-truth").inner_text()
    x, y, speed = map(float, TRUTH.search(text).groups())
    return x, y, speed


def _state(page) -> str:
    return page.locator(".abcwc-dashboard-state").inner_text()


def _wait_for(page, locator_class: str, pattern: str, timeout: float = 60.0) -> str:
    """Wait until the line ``locator_class`` matches ``pattern``; its text."""
    line = page.locator(f".{locator_class}")
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        text = line.inner_text()
        if re.search(pattern, text):
            return text
        page.wait_for_timeout(100)
    pytest.fail(f"{locator_class} never matched {pattern!r}; it reads {line.inner_text()!r}")


def _wait_still(page, timeout: float = 20.0) -> tuple[float, float, float]:
    """The truth once the drive task has let the chair come to rest."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        x, y, speed = _truth(page)
        if speed < 0.02:
            page.wait_for_timeout(1000)
            later = _truth(page)
            if abs(later[0] - x) < 0.01 and abs(later[1] - y) < 0.01:
                return later
        page.wait_for_timeout(200)
    pytest.fail(f"the chair did not stop: {page.locator('.abcwc-dashboard-truth').inner_text()}")


def _exercise(page, second_command: str) -> dict:
    """The whole rider's session on a shown dashboard; what was measured."""
    measured = {}
    image = page.locator("img.abcwc-dashboard-map")
    image.wait_for(timeout=120_000)
    page.wait_for_timeout(1000)  # the pixel ratio reported, the map redrawn for it
    # sharp: one image pixel per screen pixel
    size = image.evaluate("i => [i.naturalWidth, i.naturalHeight, "
                          "i.getBoundingClientRect().width, i.getBoundingClientRect().height,"
                          " window.devicePixelRatio]")
    measured["image"] = size
    assert size[0] == pytest.approx(size[2] * size[4], abs=1)
    assert size[1] == pytest.approx(size[3] * size[4], abs=1)

    # 1. a destination button drives the chair there; the map is live meanwhile
    started = time.monotonic()
    page.locator("button", has_text=re.compile(r"^centre$")).click()
    shots = []
    for _ in range(4):
        page.wait_for_timeout(1000)
        shots.append(image.screenshot())
    assert len(set(shots)) == len(shots), "the map did not change while the chair drove"
    _wait_for(page, "abcwc-dashboard-state", r"arrived", timeout=60)
    x, y, _ = _wait_still(page)
    measured["errand_s"] = time.monotonic() - started
    assert ((x - CENTRE[0]) ** 2 + (y - CENTRE[1]) ** 2) ** 0.5 < 0.35, (x, y)
    rate = float(re.search(r"redrawn ([\d.]+) times/s",
                           page.locator(".abcwc-dashboard-view").inner_text()).group(1))
    measured["redraw_hz"] = rate
    assert rate >= 5.0

    # 2. a second command while one drives is queued or refused, visibly; stop stops
    page.locator("button", has_text=re.compile(r"^bench$")).click()
    _wait_for(page, "abcwc-dashboard-state", r"navigating")
    page.wait_for_timeout(800)
    box = page.get_by_placeholder(re.compile("type"))
    box.fill("go to the door")
    box.press("Enter")
    notice = _wait_for(page, "abcwc-dashboard-notice", second_command)
    assert "go to the door" in notice
    moving = _truth(page)
    assert moving[2] > 0.05, f"not driving when stop was pressed: {moving}"
    page.locator("button", has_text="STOP").click()
    _wait_for(page, "abcwc-dashboard-state", r"idle")
    x, y, speed = _wait_still(page)
    assert speed < 0.02
    assert ((x - BENCH[0]) ** 2 + (y - BENCH[1]) ** 2) ** 0.5 > 0.3, "it reached the bench"
    assert "door" not in _state(page)  # nothing queued ran after the stop

    # 3. dwell (switched on): the pointer resting on "table" picks it; on STOP stops
    page.locator("button", has_text="dwell to select").click()
    table = page.locator("button", has_text=re.compile(r"^table$")).bounding_box()
    page.mouse.move(table["x"] + table["width"] / 2, table["y"] + table["height"] / 2)
    _wait_for(page, "abcwc-dashboard-state", r"navigating .*table picked by dwell", 10)
    stop = page.locator("button", has_text="STOP").bounding_box()
    page.mouse.move(stop["x"] + stop["width"] / 2, stop["y"] + stop["height"] / 2)
    _wait_for(page, "abcwc-dashboard-state", r"idle .*stop picked by dwell", 10)
    page.mouse.move(5, 5)
    _wait_still(page)
    page.locator("button", has_text="dwell to select").click()

    # 4. switch scanning: space picks the lit destination
    page.locator("button", has_text="switch scanning").click()
    lit = _wait_for(page, "abcwc-dashboard-access", r"corridor is lit", 20)
    page.keyboard.press(" ")
    picked = _wait_for(page, "abcwc-dashboard-state", r"picked by switch", 10)
    measured["scan"] = (lit, picked)
    assert "corridor picked by switch" in picked
    page.locator("button", has_text="STOP").click()
    _wait_for(page, "abcwc-dashboard-state", r"idle")
    _wait_still(page)
    return measured


def _click_the_map(page, target: tuple[float, float] = (7.0, 6.0)) -> float:
    """Click the map at ``target`` (m; free floor in the lab) and wait until the chair
    has driven there (the simulator's truth); the seconds it took. Where the point is on
    the image comes from the view's layout: the lab's costmap extent plotted inside the
    image less MARGINS (CSS px)."""
    from abcwc.behaviours.navigator import Navigator
    from abcwc.sim.world import load_world
    from abcwc.ui.map_view import MARGINS

    costmap = Navigator.for_world(load_world("lab")).global_costmap
    x0, y0 = costmap.origin.x, costmap.origin.y
    x1, y1 = x0 + costmap.width * costmap.resolution, y0 + costmap.height * costmap.resolution
    box = page.locator("img.abcwc-dashboard-map").bounding_box()
    left, right, top, bottom = MARGINS
    px = left + (target[0] - x0) / (x1 - x0) * (box["width"] - left - right)
    py = top + (y1 - target[1]) / (y1 - y0) * (box["height"] - top - bottom)
    started = time.monotonic()
    page.mouse.click(box["x"] + px, box["y"] + py)
    _wait_for(page, "abcwc-dashboard-state", r"navigating .*map clicked", 10)
    _wait_for(page, "abcwc-dashboard-state", r"arrived", 60)
    x, y, _ = _wait_still(page)
    # the goal tolerance (0.25 m) plus a click's rounding to a CSS px (~0.02 m)
    assert ((x - target[0]) ** 2 + (y - target[1]) ** 2) ** 0.5 < 0.35, (x, y)
    return time.monotonic() - started


def _launch(playwright):
    return playwright.chromium.launch(executable_path=CHROMIUM,
                                      args=["--no-sandbox", "--disable-gpu"])


def test_the_dashboard_in_jupyterlab(lab):
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        browser = _launch(playwright)
        page = browser.new_page(viewport={"width": 1400, "height": 1100})
        page.goto(lab)
        page.wait_for_selector(".jp-Notebook", timeout=60_000)
        page.get_by_text(re.compile(r"\| Idle")).first.wait_for(timeout=60_000)
        page.locator(".jp-Cell").first.click()
        page.keyboard.press("Shift+Enter")
        measured = _exercise(page, r"refused")
        measured["click_errand_s"] = _click_the_map(page)
        browser.close()
    print(measured)


def test_the_dashboard_under_voila_and_its_kernel_released(voila):
    from playwright.sync_api import sync_playwright

    url, server, log = voila
    with sync_playwright() as playwright:
        browser = _launch(playwright)
        page = browser.new_page(viewport={"width": 1200, "height": 1000},
                                device_scale_factor=2)
        page.goto(url, timeout=120_000)
        measured = _exercise(page, r"queued")
        (pid,) = _kernels(server.pid)  # the page's kernel, and no other
        assert _alive(pid)
        closed = time.monotonic()
        page.goto("about:blank")  # leaving the page, as closing its tab does
        page.close()
        deadline = closed + 60
        while _alive(pid) and time.monotonic() < deadline:
            time.sleep(0.2)
        measured["kernel_gone_s"] = time.monotonic() - closed
        browser.close()
    print(measured)
    text = log.read_text()
    assert "idle durations > 10 seconds at 5 second intervals" in text  # the culling
    assert not _alive(pid), f"the kernel process outlived the page by 60 s:\n{text[-3000:]}"


def _kernels(server: int) -> list[int]:
    """The process ids of the kernels process ``server`` started (its ipykernel children)."""
    kernels = []
    for status in Path("/proc").glob("[0-9]*/status"):
        try:
            fields = dict(line.split(":\t", 1) for line in status.read_text().splitlines()
                          if ":\t" in line)
            command = (status.parent / "cmdline").read_bytes()
        except (FileNotFoundError, ProcessLookupError):
            continue
        if int(fields["PPid"]) == server and b"ipykernel" in command:
            kernels.append(int(fields["Pid"]))
    return kernels


def _alive(pid: int) -> bool:
    """Whether process ``pid`` runs (a zombie waiting to be reaped does not)."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except FileNotFoundError:
        return False
    return "\nState:\tZ" not in status and os.path.exists(f"/proc/{pid}")
