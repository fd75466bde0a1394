"""A class on a JupyterHub, on this machine: the hub, its students, and what each costs.

:class:`LocalHub` starts JupyterHub (PyPI ``jupyterhub``) with configurable-http-proxy
(npm ``configurable-http-proxy``, found on ``PATH``) on 127.0.0.1 at free ports, with
JupyterHub's dummy authenticator (any name, no password) and its simple local-process
spawner (every student's server a process of this machine's user, with a home folder of
its own under the hub's folder). It serves the course as a git repository, ``abcwc``, made
from this checkout's last commit. Its kernels get the test suite's kernel environment
(:data:`abcwc.nbval_plugin.KERNEL_ENV`: this checkout on the path, ``ABCWC_PORT=simavr``
where the firmware in the loop can run).

:func:`run_student` is one student: log in through the hub's login form, ask the hub for
an API token, start a server, follow the chapter's nbgitpuller link
(:func:`nbgitpuller_link`, the one the README gives instructors) and pull the course into
their home as its page does, read the chapter through the server's contents API, open a
session (a kernel) for it through the sessions API and run its code cells in order over
the kernel's websocket (the Jupyter messaging protocol, as JupyterLab does). :func:`run_class`
runs N students at once and samples each server's memory (the resident set of the server
and its kernel) while they work. Every wait is bounded; :meth:`LocalHub.stop` stops the
servers and the hub and kills what is left of the processes it started.
"""

from __future__ import annotations

import json
import os
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
import uuid
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from html.parser import HTMLParser
from pathlib import Path
from typing import Any
from urllib.parse import unquote, urlencode

from abcwc.nbval_plugin import KERNEL_ENV
from abcwc.paths import require_checkout

__all__ = ["CHAPTER", "ClassRun", "HubError", "LocalHub", "StudentRun", "class_figures",
           "class_table", "doubling_point", "free_port", "nbgitpuller_link", "proxy_command",
           "run_class", "run_student"]

CHAPTER = "course/00_tour.ipynb"
"""The chapter a trial runs by default (the quickest that drives the chair: about 4 s alone
on one core, the real-chair cell on the simulated Arduino among them)."""

HTTP_TIMEOUT = 30.0  # s for one HTTP request to the hub or a server
MEMORY_SAMPLE_PERIOD = 0.25  # s between samples of the servers' memory


class HubError(RuntimeError):
    """The hub or a student's server did not do what was asked in time (the message says
    what, with the end of the hub's log where it helps)."""


def proxy_command() -> str:
    """The path of ``configurable-http-proxy`` on ``PATH``.

    Raises:
        FileNotFoundError: it is not there (the message says how to install it).
    """
    found = shutil.which("configurable-http-proxy")
    if found is None:
        raise FileNotFoundError("JupyterHub needs configurable-http-proxy on PATH: "
                                "npm install -g configurable-http-proxy (Node.js 20 or newer)")
    return found


def nbgitpuller_link(hub: str, repository: str, chapter: str, branch: str = "main") -> str:
    """The link that opens ``chapter`` (a path in the repository) for a student on the
    JupyterHub at ``hub``: nbgitpuller pulls ``repository``'s ``branch`` into their home
    (into a folder named as the repository's last path part, as nbgitpuller names it) and
    opens the chapter in JupyterLab. nbgitpuller's link format:
    https://nbgitpuller.readthedocs.io/en/latest/topic/url-options.html"""
    folder = repository.rstrip("/").split("/")[-1]
    query = urlencode({"repo": repository, "branch": branch,
                       "urlpath": f"lab/tree/{folder}/{chapter}"})
    return f"{hub.rstrip('/')}/hub/user-redirect/git-pull?{query}"


def course_repository(checkout: Path, where: Path, branch: str = "main") -> Path:
    """A git repository at ``where`` holding ``checkout``'s last commit (one commit deep)
    on ``branch``: what the class pulls."""
    if not (checkout / ".git").exists():
        raise FileNotFoundError(f"{checkout} is not a git checkout: the hub serves the course "
                                f"from the repository's last commit")
    for command in (["git", "init", "-q", "-b", branch, str(where)],
                    ["git", "-C", str(where), "fetch", "-q", "--depth", "1",
                     f"file://{checkout}", "HEAD"],
                    ["git", "-C", str(where), "checkout", "-q", "-B", branch, "FETCH_HEAD"]):
        subprocess.run(command, check=True, capture_output=True, timeout=120)
    return where


def free_port() -> int:
    """A TCP port on 127.0.0.1 that nothing listens on now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _kernel_environment() -> dict[str, str]:
    """The test suite's kernel environment, for every student's server and its kernels."""
    return {key: value for key, value in KERNEL_ENV.items() if value is not None}


class LocalHub:
    """JupyterHub on 127.0.0.1 with the dummy authenticator and local-process servers.

    Use it as a context manager (``with LocalHub(folder) as hub:``), which starts it and
    stops it (and every process it started) at the end.

    Args:
        folder: the hub's folder (its database, log, the course's repository and every
            student's home); made if missing.
        checkout: the git checkout whose last commit the class pulls (default: this one).
        start_timeout: seconds to wait for the hub, and for a student's server, to answer.
    """

    def __init__(self, folder: str | Path, checkout: str | Path | None = None,
                 start_timeout: float = 60.0) -> None:
        if start_timeout <= 0:
            raise ValueError(f"start_timeout must be positive seconds, got {start_timeout}")
        self.folder = Path(folder).resolve()
        self.checkout = (Path(checkout).resolve() if checkout is not None
                         else require_checkout("a class on a JupyterHub"))
        self.repository = self.folder / "abcwc"
        self.start_timeout = start_timeout
        self.url = ""
        self.process: subprocess.Popen | None = None
        self._started_pids: set[int] = set()
        self._admin_token = secrets.token_hex(32)

    @property
    def log_path(self) -> Path:
        return self.folder / "jupyterhub.log"

    def home(self, student: str) -> Path:
        """A student's home folder (the server's working folder)."""
        return self.folder / "home" / student

    def _config(self, port: int, hub_port: int, api_port: int) -> str:
        """The hub's configuration file, ``jupyterhub_config.py``."""
        server_args = ["--ServerApp.allow_root=True"] if os.geteuid() == 0 else []
        settings = {
            "JupyterHub.ip": "127.0.0.1",
            "JupyterHub.port": port,
            "JupyterHub.hub_ip": "127.0.0.1",
            "JupyterHub.hub_port": hub_port,
            "JupyterHub.db_url": f"sqlite:///{self.folder / 'jupyterhub.sqlite'}",
            "JupyterHub.cookie_secret_file": str(self.folder / "cookie_secret"),
            "JupyterHub.authenticator_class": "dummy",
            "JupyterHub.spawner_class": "simple",
            "JupyterHub.cleanup_servers": True,
            "ConfigurableHTTPProxy.command": [proxy_command()],
            "ConfigurableHTTPProxy.api_url": f"http://127.0.0.1:{api_port}",
            "ConfigurableHTTPProxy.pid_file": str(self.folder / "proxy.pid"),
            "Authenticator.allow_all": True,
            # this trial's own service, which stops the students' servers at the end
            "JupyterHub.services": [{"name": "class-trial", "api_token": self._admin_token}],
            "JupyterHub.load_roles": [{"name": "class-trial", "services": ["class-trial"],
                                       "scopes": ["admin:servers", "read:users"]}],
            "SimpleLocalProcessSpawner.home_dir_template": str(self.home("{username}")),
            "Spawner.cmd": [sys.executable, "-m", "jupyterhub.singleuser"],
            "Spawner.args": server_args,
            "Spawner.environment": _kernel_environment(),
            "Spawner.start_timeout": int(self.start_timeout),
            "Spawner.http_timeout": int(self.start_timeout),
            "Spawner.default_url": "/lab",
        }
        lines = ["# written by abcwc.hub.LocalHub", "c = get_config()  # noqa"]
        lines += [f"c.{key} = {value!r}" for key, value in settings.items()]
        return "\n".join(lines) + "\n"

    def start(self) -> LocalHub:
        """Start the hub and wait (bounded) until its API answers."""
        import requests

        if self.process is not None:
            raise HubError("this hub is already started")
        self.folder.mkdir(parents=True, exist_ok=True)
        course_repository(self.checkout, self.repository)
        port, hub_port, api_port = free_port(), free_port(), free_port()
        config = self.folder / "jupyterhub_config.py"
        config.write_text(self._config(port, hub_port, api_port), encoding="utf-8")
        self.url = f"http://127.0.0.1:{port}"
        with open(self.log_path, "wb") as log:
            self.process = subprocess.Popen(
                [sys.executable, "-m", "jupyterhub", "-f", str(config)], cwd=self.folder,
                stdout=log, stderr=subprocess.STDOUT, start_new_session=True)
        deadline = time.monotonic() + self.start_timeout
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise HubError(f"JupyterHub exited ({self.process.returncode}) while "
                               f"starting:\n{self.log_tail()}")
            try:
                if requests.get(f"{self.url}/hub/api/", timeout=2.0).status_code == 200:
                    self._note_processes()
                    return self
            except requests.RequestException:
                pass
            time.sleep(0.2)
        self.stop()
        raise HubError(f"JupyterHub did not answer within {self.start_timeout:.0f} s:\n"
                       f"{self.log_tail()}")

    def _note_processes(self) -> None:
        """Remember every process below the hub, so that :meth:`stop` can end them."""
        import psutil

        if self.process is None:
            return
        try:
            hub = psutil.Process(self.process.pid)
            self._started_pids.update(p.pid for p in hub.children(recursive=True))
        except psutil.NoSuchProcess:
            pass

    def servers(self) -> dict[str, list[Any]]:
        """Each running student's server and its kernels (``psutil.Process`` es), by name.

        A server is a process below the hub whose working folder is a student's home.
        """
        import psutil

        if self.process is None:
            return {}
        found: dict[str, list[Any]] = {}
        try:
            below = psutil.Process(self.process.pid).children(recursive=False)
        except psutil.NoSuchProcess:
            return {}
        homes = self.folder / "home"
        for proc in below:
            try:
                cwd = Path(proc.cwd())
                if cwd.parent == homes:
                    found[cwd.name] = [proc, *proc.children(recursive=True)]
            except (psutil.NoSuchProcess, psutil.AccessDenied):
                continue
        self._started_pids.update(p.pid for tree in found.values() for p in tree)
        return found

    def log_tail(self, lines: int = 30) -> str:
        """The last lines of the hub's log."""
        if not self.log_path.is_file():
            return "(no log)"
        text = self.log_path.read_text(encoding="utf-8", errors="replace")
        return "\n".join(text.splitlines()[-lines:])

    def stop(self, timeout: float = 15.0) -> None:
        """Stop the hub (which stops its servers and proxy), then kill whatever it started
        that is still running. Safe to call twice."""
        import psutil

        if self.process is None:
            return
        self._note_processes()
        if self.process.poll() is None:
            os.killpg(self.process.pid, signal.SIGTERM)
            try:
                self.process.wait(timeout)
            except subprocess.TimeoutExpired:
                os.killpg(self.process.pid, signal.SIGKILL)
                self.process.wait(timeout)
        for pid in self._started_pids:
            try:
                psutil.Process(pid).kill()
            except psutil.NoSuchProcess:
                pass
        self.process = None

    def stop_server(self, student: str) -> None:
        """Stop a student's server through the hub's API and wait (bounded) until the hub
        says it is gone."""
        import requests

        headers = {"Authorization": f"token {self._admin_token}"}
        _check(requests.delete(f"{self.url}/hub/api/users/{student}/server", headers=headers,
                               timeout=HTTP_TIMEOUT), [202, 204], f"stopping {student}'s server")
        deadline = time.monotonic() + self.start_timeout
        while True:
            user = _check(requests.get(f"{self.url}/hub/api/users/{student}", headers=headers,
                                       timeout=HTTP_TIMEOUT), [200], f"{student}'s model").json()
            if not user.get("servers"):
                return
            if time.monotonic() > deadline:
                raise HubError(f"{student}'s server still there {self.start_timeout:.0f} s "
                               f"after it was stopped")
            time.sleep(0.2)

    def check_chapter(self, chapter: str) -> None:
        """Refuse a chapter that is not a notebook of the course a student's home holds."""
        path = Path(chapter)
        course = self.checkout / "course"
        if (path.parts[:1] != ("course",) or path.suffix != ".ipynb"
                or not (self.checkout / path).is_file()):
            names = ", ".join(f"course/{p.name}" for p in sorted(course.glob("*.ipynb")))
            raise ValueError(f"no chapter {chapter!r} in the students' course folder; "
                             f"one of: {names}")

    def __enter__(self) -> LocalHub:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()


@dataclass(frozen=True)
class CellResult:
    """One executed cell: the kernel's reply status, its printed text and its error."""

    status: str
    stdout: str
    error: str | None


def _decode(frame: str | bytes) -> dict:
    """A kernel message from a websocket frame: JSON text, or jupyter_server's binary
    form for a message with buffers (a widget's, say): the count n of parts as a
    big-endian uint32, n uint32 offsets, then the JSON message and its buffers."""
    if isinstance(frame, str):
        return json.loads(frame)
    parts = int.from_bytes(frame[:4], "big")
    offsets = [int.from_bytes(frame[4 + 4 * k:8 + 4 * k], "big") for k in range(parts)]
    end = offsets[1] if parts > 1 else len(frame)
    return json.loads(frame[offsets[0]:end].decode("utf-8"))


class KernelChannel:
    """A kernel's websocket (``/api/kernels/<id>/channels``), spoken in the Jupyter
    messaging protocol's JSON form: one execute request at a time, its reply and the
    outputs that follow it on iopub until the kernel is idle again."""

    def __init__(self, url: str, token: str, timeout: float) -> None:
        import websocket

        self.session = uuid.uuid4().hex
        self.socket = websocket.create_connection(
            f"{url}?session_id={self.session}", header=[f"Authorization: token {token}"],
            timeout=timeout)

    def close(self) -> None:
        self.socket.close()

    def _send(self, msg_type: str, content: dict) -> str:
        msg_id = uuid.uuid4().hex
        self.socket.send(json.dumps({
            "header": {"msg_id": msg_id, "msg_type": msg_type, "session": self.session,
                       "username": "student", "version": "5.3"},
            "parent_header": {}, "metadata": {}, "content": content, "channel": "shell",
            "buffers": []}))
        return msg_id

    def _replies(self, msg_id: str, timeout: float):
        """The messages answering ``msg_id`` until its reply has come and the kernel is
        idle again; :class:`HubError` after ``timeout`` seconds."""
        import websocket

        deadline = time.monotonic() + timeout
        replied = idle = False
        while not (replied and idle):
            left = deadline - time.monotonic()
            if left <= 0:
                raise HubError(f"no answer from the kernel within {timeout:.0f} s")
            self.socket.settimeout(left)
            try:
                msg = _decode(self.socket.recv())
            except websocket.WebSocketTimeoutException:
                continue
            if msg.get("parent_header", {}).get("msg_id") != msg_id:
                continue
            if msg["channel"] == "shell" and msg["msg_type"].endswith("_reply"):
                replied = True
            if msg["msg_type"] == "status" and msg["content"]["execution_state"] == "idle":
                idle = True
            yield msg

    def wait_ready(self, timeout: float) -> None:
        """Ask for the kernel's info until it answers (a kernel just started may miss the
        first request)."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                for _ in self._replies(self._send("kernel_info_request", {}), 5.0):
                    pass
                return
            except HubError:
                if time.monotonic() > deadline:
                    raise HubError(f"the kernel did not answer within {timeout:.0f} s") \
                        from None

    def execute(self, code: str, timeout: float) -> CellResult:
        """Run ``code`` and collect its printed text, its error and the reply's status."""
        msg_id = self._send("execute_request", {
            "code": code, "silent": False, "store_history": True, "user_expressions": {},
            "allow_stdin": False, "stop_on_error": True})
        status, stdout, error = "", [], None
        for msg in self._replies(msg_id, timeout):
            kind, content = msg["msg_type"], msg["content"]
            if kind == "stream" and content["name"] == "stdout":
                stdout.append(content["text"])
            elif kind == "error":
                error = f"{content['ename']}: {content['evalue']}"
            elif kind == "execute_reply":
                status = content["status"]
        return CellResult(status, "".join(stdout), error)


@dataclass(frozen=True)
class StudentRun:
    """One student's run of a chapter through the hub.

    Attributes:
        student: the name they logged in with.
        chapter: the notebook run, its path in the student's home (where nbgitpuller put it).
        start_seconds: wall seconds from asking the hub for a server to its being ready.
        chapter_seconds: wall seconds from opening the chapter's session to the last cell's
            reply (the kernel's start included).
        cells: code cells run.
        errors: each failing cell's index and error (empty: the chapter ran clean).
        kernel_user: ``JUPYTERHUB_USER`` as the chapter's kernel saw it.
        peak_memory_mb: the largest resident set (MB) of the student's server and its
            kernel together, sampled every :data:`MEMORY_SAMPLE_PERIOD` s (0 when not
            sampled).
    """

    student: str
    chapter: str
    start_seconds: float
    chapter_seconds: float
    cells: int
    errors: tuple[tuple[int, str], ...]
    kernel_user: str
    peak_memory_mb: float = 0.0


def _check(response: Any, expected: Sequence[int], what: str) -> Any:
    if response.status_code not in expected:
        raise HubError(f"{what}: HTTP {response.status_code} {response.text[:300]}")
    return response


class _PullPage(HTMLParser):
    """The ``data-`` attributes of nbgitpuller's page (what its script pulls, and where it
    then sends the student)."""

    def __init__(self) -> None:
        super().__init__()
        self.data: dict[str, str] = {}

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        for name, value in attrs:
            if name.startswith("data-") and value is not None:
                self.data[name[5:]] = unquote(value)


def _pull(api: Any, server: str, link: str, web: Any, timeout: float) -> str:
    """Follow an nbgitpuller ``link`` as the student's browser (the hub sends it on to
    their server), then pull as the page's script does, through the server's
    ``git-pull/api`` event stream; return the chapter's path the page then opens."""
    page = _check(web.get(link, timeout=HTTP_TIMEOUT), [200], "the nbgitpuller link")
    if not page.url.startswith(f"{server}/git-pull"):
        raise HubError(f"the nbgitpuller link ended at {page.url}, not the server's git-pull")
    parser = _PullPage()
    parser.feed(page.text)
    wanted = {key: parser.data[key] for key in ("repo", "branch", "targetpath")
              if key in parser.data}
    deadline = time.monotonic() + timeout
    with api.get(f"{server}/git-pull/api", params=wanted, stream=True,
                 timeout=HTTP_TIMEOUT) as events:
        _check(events, [200], "the pull")
        for line in events.iter_lines(decode_unicode=True):
            if time.monotonic() > deadline:
                raise HubError(f"the pull took more than {timeout:.0f} s")
            if not line or not line.startswith("data:"):
                continue
            event = json.loads(line[5:])
            if event.get("phase") == "error":
                raise HubError(f"the pull failed: {event.get('message')}")
            if event.get("phase") == "finished":
                break
        else:
            raise HubError("the pull's event stream ended before it finished")
    return parser.data["path"].removeprefix("lab/tree/")


def run_student(hub: LocalHub, student: str, chapter: str = CHAPTER,
                cell_timeout: float = 120.0) -> StudentRun:
    """One student logs in, starts a server, pulls the course by the chapter's
    nbgitpuller link and runs ``chapter`` (a path in the repository) cell by cell. See the
    module's docstring for the steps."""
    import requests

    web = requests.Session()
    # log in through the form, as a browser does (the form carries the _xsrf cookie)
    _check(web.get(f"{hub.url}/hub/login", timeout=HTTP_TIMEOUT), [200], "the login page")
    xsrf = web.cookies.get("_xsrf", "")
    _check(web.post(f"{hub.url}/hub/login", data={"username": student, "password": "",
                                                  "_xsrf": xsrf},
                    allow_redirects=False, timeout=HTTP_TIMEOUT), [302], f"{student}'s login")
    xsrf = web.cookies.get("_xsrf", "")  # the logged-in session's own
    token = _check(web.post(f"{hub.url}/hub/api/users/{student}/tokens",
                            json={"note": "class trial", "expires_in": 3600},
                            headers={"X-XSRFToken": xsrf}, timeout=HTTP_TIMEOUT),
                   [200, 201], f"{student}'s API token").json()["token"]
    api = requests.Session()
    api.headers["Authorization"] = f"token {token}"

    began = time.monotonic()
    _check(api.post(f"{hub.url}/hub/api/users/{student}/server", timeout=HTTP_TIMEOUT),
           [201, 202], f"{student}'s server start")
    deadline = began + hub.start_timeout
    while True:
        user = _check(api.get(f"{hub.url}/hub/api/users/{student}", timeout=HTTP_TIMEOUT),
                      [200], f"{student}'s model").json()
        if user.get("servers", {}).get("", {}).get("ready"):
            break
        if time.monotonic() > deadline:
            raise HubError(f"{student}'s server not ready within {hub.start_timeout:.0f} s:"
                           f"\n{hub.log_tail()}")
        time.sleep(0.2)
    start_seconds = time.monotonic() - began

    server = f"{hub.url}/user/{student}"
    link = nbgitpuller_link(hub.url, f"file://{hub.repository}", chapter)
    chapter = _pull(api, server, link, web, hub.start_timeout)
    began = time.monotonic()
    notebook = _check(api.get(f"{server}/api/contents/{chapter}", params={"content": 1},
                              timeout=HTTP_TIMEOUT), [200], f"{student}'s chapter").json()
    session = _check(api.post(f"{server}/api/sessions", json={
        "path": chapter, "name": Path(chapter).name, "type": "notebook",
        "kernel": {"name": "python3"}}, timeout=HTTP_TIMEOUT), [201], f"{student}'s kernel")
    kernel = session.json()["kernel"]["id"]
    channel = KernelChannel(
        f"{server.replace('http', 'ws', 1)}/api/kernels/{kernel}/channels", token,
        HTTP_TIMEOUT)
    try:
        channel.wait_ready(hub.start_timeout)
        errors = []
        code_cells = [cell for cell in notebook["content"]["cells"]
                      if cell["cell_type"] == "code"]
        for index, cell in enumerate(code_cells):
            result = channel.execute(cell["source"], cell_timeout)
            if result.status != "ok" or result.error:
                errors.append((index, result.error or result.status))
        chapter_seconds = time.monotonic() - began
        probe = channel.execute("import os; print(os.environ.get('JUPYTERHUB_USER'))",
                                cell_timeout)
    finally:
        channel.close()
    return StudentRun(student, chapter, start_seconds, chapter_seconds, len(code_cells),
                      tuple(errors), probe.stdout.strip())


@dataclass
class _MemorySampler:
    """Samples each student's server tree's resident set in a thread; keeps the peaks."""

    hub: LocalHub
    peaks_mb: dict[str, float] = field(default_factory=dict)
    _stop: threading.Event = field(default_factory=threading.Event)

    def sample(self) -> None:
        import psutil

        for student, tree in self.hub.servers().items():
            total = 0
            for proc in tree:
                try:
                    total += proc.memory_info().rss
                except psutil.NoSuchProcess:
                    continue
            mb = total / 2**20
            self.peaks_mb[student] = max(self.peaks_mb.get(student, 0.0), mb)

    def run(self) -> None:
        while not self._stop.wait(MEMORY_SAMPLE_PERIOD):
            self.sample()

    def __enter__(self) -> _MemorySampler:
        self._thread = threading.Thread(target=self.run, daemon=True)
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(MEMORY_SAMPLE_PERIOD * 10)


@dataclass(frozen=True)
class ClassRun:
    """N students at once: each one's run and the wall time for the whole class."""

    students: tuple[StudentRun, ...]
    wall_seconds: float


def run_class(hub: LocalHub, students: int, chapter: str = CHAPTER, prefix: str = "student",
              cell_timeout: float = 120.0) -> ClassRun:
    """``students`` students (``<prefix>1``...) log in at once and each runs ``chapter``;
    their servers are stopped at the end (so the next class starts from none)."""
    if students < 1:
        raise ValueError(f"students must be 1 or more, got {students}")
    hub.check_chapter(chapter)
    names = [f"{prefix}{k + 1}" for k in range(students)]
    began = time.monotonic()
    with _MemorySampler(hub) as sampler, ThreadPoolExecutor(students) as pool:
        runs = list(pool.map(lambda name: run_student(hub, name, chapter, cell_timeout),
                             names))
        sampler.sample()
    wall = time.monotonic() - began
    with_memory = tuple(StudentRun(**{**run.__dict__,
                                      "peak_memory_mb": sampler.peaks_mb.get(run.student, 0.0)})
                        for run in runs)
    for name in names:
        hub.stop_server(name)
    return ClassRun(with_memory, wall)




def doubling_point(classes: dict[int, ClassRun]) -> int | None:
    """The smallest class size whose mean chapter time is at least twice the smallest
    class's (``None``: no class measured was that slow)."""
    if not classes:
        raise ValueError("no classes measured")
    sizes = sorted(classes)
    base = _mean([run.chapter_seconds for run in classes[sizes[0]].students])
    for size in sizes[1:]:
        if _mean([run.chapter_seconds for run in classes[size].students]) >= 2 * base:
            return size
    return None


def _mean(values: Sequence[float]) -> float:
    return sum(values) / len(values)


def class_figures(classes: dict[int, ClassRun]) -> list[dict[str, float | int]]:
    """Per class size: wall seconds per student's chapter (mean, max) and its ratio to
    the smallest class's mean, seconds to a ready server (mean), each server's peak
    resident memory (MB; mean, max), the whole class's wall seconds and the cells that
    failed."""
    sizes = sorted(classes)
    base = _mean([run.chapter_seconds for run in classes[sizes[0]].students])
    rows = []
    for size in sizes:
        runs = classes[size].students
        chapter = [run.chapter_seconds for run in runs]
        memory = [run.peak_memory_mb for run in runs]
        rows.append({
            "students": size, "chapter_mean_s": _mean(chapter), "chapter_max_s": max(chapter),
            "slowdown": _mean(chapter) / base,
            "server_start_mean_s": _mean([run.start_seconds for run in runs]),
            "memory_mean_mb": _mean(memory), "memory_max_mb": max(memory),
            "class_wall_s": classes[size].wall_seconds,
            "failed_cells": sum(len(run.errors) for run in runs)})
    return rows


def class_table(classes: dict[int, ClassRun], chapter: str = CHAPTER) -> str:
    """:func:`class_figures` as a text table, with the doubling point under it."""
    lines = [f"{chapter}, each student on a server of their own, all at once",
             "students  chapter s (mean  max)  x N=1  server start s  memory MB (mean  max)"
             "  class s  failed cells"]
    for row in class_figures(classes):
        lines.append(
            f"{row['students']:8d}  {row['chapter_mean_s']:16.1f} {row['chapter_max_s']:5.1f}"
            f"  {row['slowdown']:5.2f}  {row['server_start_mean_s']:14.1f}"
            f"  {row['memory_mean_mb']:16.0f} {row['memory_max_mb']:5.0f}"
            f"  {row['class_wall_s']:7.1f}  {row['failed_cells']:12d}")
    double = doubling_point(classes)
    lines.append("a chapter's time doubles at "
                 + (f"{double} students" if double else "none of these class sizes"))
    return "\n".join(lines)
