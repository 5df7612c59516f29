"""Benchmark: a class hub under load, every student running one notebook at the same moment.

``duckie bench hub`` (as root) makes a hub of its own in a new folder of ``/srv``, with
``N`` student accounts (``DUCKIE_BENCH_HUB_N``, default 20), each home holding the course with
every exercise solved (:func:`autograder.bench.filled_course`), as a student who worked through
it. The repository is closed to other users while it runs (the hub refuses to start otherwise),
and everything it made is removed at the end.

One student first runs the notebook alone (``DUCKIE_BENCH_HUB_NOTEBOOK``, default
``05_odometry``), then all ``N`` at once, each as JupyterLab's Run All does: their server is
started, a kernel opened on the notebook, and its code cells executed one after the other over
the kernel's WebSocket, stopping at the first error. Students start through the hub's REST API
with a service token (a browser's login form adds only the PAM check). Figures:

- ``env_install_s``: ``duckie hub start``'s preparation (the students' Python, the proxy), once;
- ``alone_kernel_s``, ``alone_run_all_s``: one student: from asking for their server to a
  kernel that answers, and the Run All itself;
- ``kernel_s_median`` and ``_max``, ``run_all_s_median`` and ``_max``: the same with all ``N``
  students at once;
- ``memory_mb_per_student_mean`` and ``_max``: each student's processes (server and kernel)
  after their Run All, by proportional set size (shared pages shared out), and ``hub_mb``
  (JupyterHub and its proxy);
- ``kernel_reconnects``: how often a kernel's connection closed while the kernel started and
  was opened again, as JupyterLab does (each student tries up to :data:`RECONNECTS` times);
- ``failed``: students whose server, kernel or a cell failed, with the first failure said;
- the headline, last, ``run_all_slowdown``: the median Run All at load over the one alone.
"""

from __future__ import annotations

import asyncio
import json
import os
import pwd
import secrets
import shutil
import signal
import socket
import statistics
import subprocess
import tempfile
import time
import uuid
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

from autograder.course import ROOT

#: What ``duckie bench`` lists for this benchmark.
DESCRIPTION = "a class hub: N students start JupyterLab and Run All one notebook at once"

__all__ = ["DESCRIPTION", "N", "NOTEBOOK", "free_ports", "run"]

#: Students at once.
N = int(os.environ.get("DUCKIE_BENCH_HUB_N", "20"))
#: The notebook each of them runs.
NOTEBOOK = os.environ.get("DUCKIE_BENCH_HUB_NOTEBOOK", "05_odometry")
#: The longest a cell may run before the student counts as failed.
CELL_SECONDS = 900
#: How often a student's kernel connection is opened again when the server closes it (as
#: JupyterLab does) before the student counts as failed.
RECONNECTS = 5

_LOCAL_CONFIG = """\
# Written by `duckie bench hub`: a service whose token starts servers and opens kernels.
c.JupyterHub.services.append({{"name": "duckie-bench", "api_token": {token!r}}})
c.JupyterHub.load_roles.append(
    {{
        "name": "duckie-bench",
        "services": ["duckie-bench"],
        "scopes": ["admin:users", "admin:servers", "access:servers", "read:users"],
    }}
)
c.JupyterHub.concurrent_spawn_limit = 200
"""


@dataclass
class Student:
    """One student's run: seconds to a kernel and of the Run All, or what failed."""

    name: str
    kernel_s: float = 0.0
    run_all_s: float = 0.0
    reconnects: int = 0
    failure: str = ""


def free_ports(count: int) -> int:
    """The first of ``count`` consecutive free ports on this machine's loopback."""
    for _ in range(200):
        first = 20000 + secrets.randbelow(20000)
        try:
            for port in range(first, first + count):
                with socket.socket() as probe:
                    probe.bind(("127.0.0.1", port))
        except OSError:
            continue
        return first
    raise RuntimeError("No free ports were found for the hub.")


def _code_cells(path: Path) -> List[str]:
    notebook = json.loads(path.read_text(encoding="utf-8"))
    return [
        "".join(cell["source"])
        for cell in notebook["cells"]
        if cell["cell_type"] == "code" and "".join(cell["source"]).strip()
    ]


class _Client:
    """The hub's REST API and a kernel's WebSocket, with the bench's token."""

    def __init__(self, url: str, token: str) -> None:
        from tornado.httpclient import AsyncHTTPClient

        self.url, self.token = url, token
        self.http = AsyncHTTPClient(force_instance=True, max_clients=500)

    async def call(self, method: str, path: str, body: Optional[Dict[str, Any]] = None) -> Any:
        from tornado.httpclient import HTTPRequest

        request = HTTPRequest(
            self.url + path,
            method=method,
            headers={"Authorization": f"token {self.token}"},
            body=None if body is None and method == "GET" else json.dumps(body or {}),
            request_timeout=600,
            allow_nonstandard_methods=True,
        )
        response = await self.http.fetch(request, raise_error=True)
        return json.loads(response.body) if response.body else None

    async def channels(self, user: str, kernel: str) -> Any:
        from tornado.httpclient import HTTPRequest
        from tornado.websocket import websocket_connect

        address = self.url.replace("http", "ws", 1)
        request = HTTPRequest(
            f"{address}/user/{user}/api/kernels/{kernel}/channels?session_id={uuid.uuid4().hex}",
            headers={"Authorization": f"token {self.token}"},
            request_timeout=600,
        )
        return await websocket_connect(request, max_message_size=1 << 30)


def _message(kind: str, content: Dict[str, Any]) -> Tuple[str, str]:
    identity = uuid.uuid4().hex
    message = {
        "header": {
            "msg_id": identity,
            "msg_type": kind,
            "username": "bench",
            "session": "bench",
            "version": "5.3",
            "date": "",
        },
        "parent_header": {},
        "metadata": {},
        "content": content,
        "channel": "shell",
        "buffers": [],
    }
    return identity, json.dumps(message)


async def _reply(connection: Any, identity: str, kind: str, seconds: float) -> Dict[str, Any]:
    deadline = time.monotonic() + seconds
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            raise TimeoutError(f"no {kind} within {seconds:.0f} s")
        text = await asyncio.wait_for(connection.read_message(), left)
        if text is None:
            raise ConnectionError("the kernel's connection closed")
        if isinstance(text, bytes):
            continue  # a message with binary buffers (a widget's): not a reply
        message = json.loads(text)
        if (
            message.get("parent_header", {}).get("msg_id") == identity
            and message.get("msg_type") == kind
        ):
            return message["content"]


async def _connect(client: _Client, name: str, kernel: str, done: Student) -> Any:
    """The kernel's channels once it answers, connecting again as JupyterLab does if closed."""
    for attempt in range(1, RECONNECTS + 2):
        try:
            connection = await client.channels(name, kernel)
            identity, text = _message("kernel_info_request", {})
            await connection.write_message(text)
            await _reply(connection, identity, "kernel_info_reply", 120)
            return connection
        except ConnectionError:
            if attempt > RECONNECTS:
                raise
            done.reconnects += 1
            await asyncio.sleep(1)
    raise AssertionError("not reached")


async def _student(client: _Client, name: str, cells: List[str]) -> Student:
    done = Student(name)
    started = time.monotonic()
    step = "its server"
    try:
        await client.call("POST", f"/hub/api/users/{name}/server", {})
        while True:
            model = await client.call("GET", f"/hub/api/users/{name}")
            server = (model.get("servers") or {}).get("")
            if server and server.get("ready"):
                break
            if time.monotonic() - started > 600:
                raise TimeoutError("the server was not ready within 600 s")
            await asyncio.sleep(0.5)
        step = "a kernel"
        path = f"{NOTEBOOK}/{NOTEBOOK}.ipynb"
        session = await client.call(
            "POST",
            f"/user/{name}/api/sessions",
            {"path": path, "name": path, "type": "notebook", "kernel": {"name": "python3"}},
        )
        connection = await _connect(client, name, session["kernel"]["id"], done)
        done.kernel_s = time.monotonic() - started
        step = "Run All"
        running = time.monotonic()
        for number, code in enumerate(cells, start=1):
            identity, text = _message(
                "execute_request",
                {"code": code, "silent": False, "store_history": True, "allow_stdin": False,
                 "user_expressions": {}, "stop_on_error": True},
            )  # fmt: skip
            await connection.write_message(text)
            reply = await _reply(connection, identity, "execute_reply", CELL_SECONDS)
            if reply.get("status") != "ok":
                raise RuntimeError(
                    f"code cell {number} raised {reply.get('ename')}: {reply.get('evalue')}"
                )
        done.run_all_s = time.monotonic() - running
        connection.close()
    except Exception as error:  # a student's failure is a figure, not the benchmark's end
        done.failure = f"{name}, {step}: {type(error).__name__}: {error}"
    return done


def _pss_mb(uids: List[int]) -> Dict[int, float]:
    """Proportional set size of every process of each uid, in MB."""
    sizes = dict.fromkeys(uids, 0.0)
    for process in Path("/proc").iterdir():
        if not process.name.isdigit():
            continue
        try:
            uid = process.stat().st_uid
            if uid not in sizes:
                continue
            for line in (process / "smaps_rollup").read_text().splitlines():
                if line.startswith("Pss:"):
                    sizes[uid] += int(line.split()[1]) / 1024
                    break
        except OSError:
            continue  # ended meanwhile
    return sizes


def _pss_of(pids: List[int]) -> float:
    total = 0.0
    for pid in pids:
        try:
            for line in Path(f"/proc/{pid}/smaps_rollup").read_text().splitlines():
                if line.startswith("Pss:"):
                    total += int(line.split()[1]) / 1024
        except OSError:
            continue
    return total


def _descendants(pid: int) -> List[int]:
    found = [pid]
    done = subprocess.run(["ps", "-e", "-o", "pid=,ppid=,uid="], capture_output=True, text=True,
                          check=False)  # fmt: skip
    children: Dict[int, List[int]] = {}
    for line in done.stdout.splitlines():
        child, parent, uid = (int(word) for word in line.split())
        if uid == 0:
            children.setdefault(parent, []).append(child)
    for each in found:
        found.extend(children.get(each, []))
    return found


def _median(values: List[float]) -> str:
    return f"{statistics.median(values):.1f}" if values else "n/a"


def _most(values: List[float]) -> str:
    return f"{max(values):.1f}" if values else "n/a"


def _mb(value: Optional[float]) -> str:
    return "n/a" if value is None else f"{value:.0f}"


def _homes(names: List[str], course: Path) -> None:
    """Each student's home: the filled course, theirs."""
    for name in names:
        account = pwd.getpwnam(name)
        home = Path(account.pw_dir)
        for folder in course.iterdir():
            shutil.copytree(folder, home / folder.name, dirs_exist_ok=True)
        subprocess.run(["chown", "-R", f"{name}:{account.pw_gid}", str(home)], check=True)


def _stop(process: Optional[subprocess.Popen], names: List[str], root: Path, mode: int) -> None:
    """Stop the hub, remove the accounts and the hub's folder, open the repository as it was."""
    if process is not None and process.poll() is None:
        os.killpg(process.pid, signal.SIGTERM)
        try:
            process.wait(60)
        except subprocess.TimeoutExpired:
            os.killpg(process.pid, signal.SIGKILL)
    for name in names:
        subprocess.run(["pkill", "-KILL", "-u", name], check=False)
    time.sleep(1)
    from autograder.hub_formgrader import service_account

    # The students' accounts, and the hub's own (its Formgrader's) that the start made.
    for name in [*names, service_account(root)]:
        subprocess.run(["pkill", "-KILL", "-u", name], check=False, capture_output=True)
        subprocess.run(["userdel", "--remove", name], check=False, capture_output=True)
    shutil.rmtree(root, ignore_errors=True)
    ROOT.chmod(mode)


def run(students: Optional[int] = None) -> List[Tuple[str, str]]:
    """Start a hub of ``students`` accounts, load it, and return the figures, headline last."""
    from autograder.bench import filled_course
    from autograder.hub import Hub, HubError, create_accounts, hub_command, prepare

    if os.geteuid() != 0:
        raise HubError("The hub benchmark makes Unix accounts: run it as root (sudo).")
    count = N if students is None else students
    root = Path(tempfile.mkdtemp(prefix="duckie-bench-hub-", dir="/srv"))
    suffix = secrets.token_hex(2)
    names = [f"bench{suffix}s{index:02d}" for index in range(count + 1)]  # one more: alone
    mode = ROOT.stat().st_mode & 0o7777
    process = None
    hub = Hub(root)
    try:
        roster = root / "roster.csv"
        roster.write_text("login\n" + "".join(f"{name}\n" for name in names), encoding="utf-8")
        create_accounts(hub, roster)
        ROOT.chmod(mode & ~0o007)
        port = free_ports(4)
        started = time.monotonic()
        prepare(hub, port=port)
        env_s = time.monotonic() - started
        token = secrets.token_hex(32)
        (root / "jupyterhub_config.local.py").write_text(
            _LOCAL_CONFIG.format(token=token), encoding="utf-8"
        )
        course = root / "course-filled"
        filled_course(course)
        _homes(names, course)
        log = (root / "state" / "hub.log").open("w")
        command = hub_command(hub)
        process = subprocess.Popen(
            command, cwd=root / "state", stdout=log, stderr=subprocess.STDOUT,
            start_new_session=True,
        )  # fmt: skip
        url = f"http://127.0.0.1:{port}"
        cells = _code_cells(course / NOTEBOOK / f"{NOTEBOOK}.ipynb")
        figures, results = asyncio.run(_load(url, token, names, cells, process))
        uids = {pwd.getpwnam(result.name).pw_uid: result for result in results}
        memory = _pss_mb(list(uids))
        per_student = [memory[uid] for uid, result in uids.items() if not result.failure]
        hub_mb = _pss_of(_descendants(process.pid))
    finally:
        _stop(process, names, root, mode)
    failed = [result.failure for result in results if result.failure]
    return [
        ("students", str(count)),
        ("notebook", NOTEBOOK),
        ("cores", str(os.cpu_count())),
        ("env_install_s", f"{env_s:.1f}"),
        *figures,
        ("memory_mb_per_student_mean", _mb(statistics.mean(per_student) if per_student else None)),
        ("memory_mb_per_student_max", _mb(max(per_student) if per_student else None)),
        ("hub_mb", f"{hub_mb:.0f}"),
        ("failed", f"{len(failed)}" + (f" (first: {failed[0]})" if failed else "")),
        ("run_all_slowdown", _slowdown(figures)),
    ]  # fmt: skip


def _slowdown(figures: List[Tuple[str, str]]) -> str:
    found = dict(figures)
    try:
        return f"{float(found['run_all_s_median']) / float(found['alone_run_all_s']):.1f}"
    except (KeyError, ValueError, ZeroDivisionError):
        return "n/a"


async def _load(
    url: str, token: str, names: List[str], cells: List[str], process: subprocess.Popen
) -> Tuple[List[Tuple[str, str]], List[Student]]:
    client = _Client(url, token)
    deadline = time.monotonic() + 300
    while True:
        try:
            await client.call("GET", "/hub/api/")
            break
        except Exception:
            if process.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError("The hub did not start: see its log.") from None
            await asyncio.sleep(1)
    alone = await _student(client, names[0], cells)
    if alone.failure:
        raise RuntimeError(f"Alone, the notebook does not run: {alone.failure}")
    results = await asyncio.gather(*(_student(client, name, cells) for name in names[1:]))
    good = [result for result in results if not result.failure]
    figures = [
        ("alone_kernel_s", f"{alone.kernel_s:.1f}"),
        ("alone_run_all_s", f"{alone.run_all_s:.1f}"),
        ("kernel_s_median", _median([result.kernel_s for result in good])),
        ("kernel_s_max", _most([result.kernel_s for result in good])),
        ("run_all_s_median", _median([result.run_all_s for result in good])),
        ("run_all_s_max", _most([result.run_all_s for result in good])),
        ("kernel_reconnects", str(sum(result.reconnects for result in results))),
    ]
    return figures, [alone, *results]
