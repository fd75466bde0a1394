"""The notebook panels as a person uses them: JupyterLab in headless Chromium (Debian's
``chromium``, driven by Playwright), a click on the navigator's map, and the chair
drives to the point clicked (the status line reports the simulator's true pose)."""

from __future__ import annotations

import os
import re
import shutil
import socket
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator

import nbformat
import pytest

CHROMIUM = shutil.which("chromium")


def _require_browser() -> None:
    missing = []
    if CHROMIUM is None:
        missing.append("Debian's chromium")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        missing.append("playwright (pip)")
    if missing:
        message = f"browser tests need {' and '.join(missing)}"
        if os.environ.get("CI") == "true":
            pytest.fail(message)
        pytest.skip(message)


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def lab(tmp_path) -> Iterator[str]:
    """A JupyterLab server on a free port, serving a notebook that shows the panel."""
    _require_browser()
    notebook = nbformat.v4.new_notebook()
    notebook.cells = [nbformat.v4.new_code_cell(
        "%matplotlib widget\n"
        "from abcwc.ui.navigator_panel import NavigatorPanel\n"
        "panel = NavigatorPanel.for_world('floor', seed=1, people=False)\n"
        "panel")]
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3",
                                       "language": "python"}
    nbformat.write(notebook, tmp_path / "panel.ipynb")
    port = _free_port()
    server = subprocess.Popen(
        [sys.executable, "-m", "jupyter", "lab", "--no-browser", f"--port={port}",
         "--ServerApp.token=", "--ServerApp.password=", "--ServerApp.ip=127.0.0.1",
         f"--ServerApp.root_dir={tmp_path}", "--LabApp.news_url=",
         "--ServerApp.disable_check_xsrf=True", "--allow-root"],
        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    url = f"http://127.0.0.1:{port}/"
    deadline = time.monotonic() + 60
    while True:
        try:
            urllib.request.urlopen(url + "api/status", timeout=2)
            break
        except OSError:
            if time.monotonic() > deadline or server.poll() is not None:
                server.kill()
                pytest.fail("JupyterLab did not start within 60 s")
            time.sleep(0.5)
    try:
        yield url
    finally:
        server.terminate()
        try:
            server.wait(timeout=10)
        except subprocess.TimeoutExpired:
            server.kill()


def test_a_click_on_the_map_drives_the_chair_to_that_point(lab):
    from playwright.sync_api import sync_playwright

    from abcwc.behaviours.navigator import Navigator
    from abcwc.sim.world import load_world
    from abcwc.ui.navigator_panel import MAP_AXES

    # where on the canvas the map point (8.0, 9.0) is: the panel's map fills MAP_AXES
    # of the figure with the global costmap's extent
    costmap = Navigator.for_world(load_world("floor")).global_costmap
    x0, y0 = costmap.origin.x, costmap.origin.y
    x1, y1 = x0 + costmap.width * costmap.resolution, y0 + costmap.height * costmap.resolution
    target = (8.0, 9.0)
    fx = MAP_AXES[0] + (target[0] - x0) / (x1 - x0) * MAP_AXES[2]
    fy = MAP_AXES[1] + (target[1] - y0) / (y1 - y0) * MAP_AXES[3]

    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM,
                                             args=["--no-sandbox", "--disable-gpu"])
        page = browser.new_page(viewport={"width": 1400, "height": 1000})
        page.goto(lab + "lab/tree/panel.ipynb")
        page.wait_for_selector(".jp-Notebook", timeout=60_000)
        page.get_by_text(re.compile(r"\| Idle")).first.wait_for(timeout=60_000)  # kernel up
        page.locator(".jp-Cell").first.click()
        page.keyboard.press("Shift+Enter")
        status = page.locator(".widget-label", has_text="click the map")
        status.wait_for(timeout=90_000)
        canvas = page.locator(".jupyter-matplotlib-canvas-div canvas").last
        canvas.wait_for(timeout=30_000)
        box = canvas.bounding_box()
        page.mouse.click(box["x"] + fx * box["width"], box["y"] + (1 - fy) * box["height"])
        done = page.locator(".widget-label", has_text=re.compile("after .* s; chair at"))
        done.wait_for(timeout=180_000)
        text = done.inner_text()
        browser.close()
    assert text.startswith("succeeded"), text
    x, y = map(float, re.search(r"chair at \(([-\d.]+), ([-\d.]+)\)", text).groups())
    start = load_world("floor").places["start"]
    assert abs(x - start.x) > 5.0  # it drove
    # the goal tolerance (0.25 m) plus the click's rounding to a pixel (0.06 m)
    assert ((x - target[0]) ** 2 + (y - target[1]) ** 2) ** 0.5 < 0.35
