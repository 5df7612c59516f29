"""``make lab`` opens the course: JupyterLab serves course/'s notebooks with a python3 kernel."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import time
import urllib.request

import pytest
from coursetools import NAMES

from autograder.course import ROOT

pytestmark = [pytest.mark.slow, pytest.mark.notebook]

TOKEN = "course-lab-test"


def free_port():
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def get(port, path):
    url = f"http://127.0.0.1:{port}{path}?token={TOKEN}"
    with urllib.request.urlopen(url, timeout=5) as response:
        return json.loads(response.read())


def test_jupyterlab_serves_the_course_with_a_python3_kernel(tmp_path):
    port = free_port()
    env = {**os.environ, "JUPYTER_RUNTIME_DIR": str(tmp_path), "JUPYTER_CONFIG_DIR": str(tmp_path)}
    options = f"--no-browser --port={port} --ip=127.0.0.1 --IdentityProvider.token={TOKEN}"
    server = subprocess.Popen(
        ["make", "--no-print-directory", "lab", f"LAB_ARGS={options}"],
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        env=env,
        start_new_session=True,
    )
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                listing = get(port, "/api/contents")
                break
            except OSError:
                assert time.monotonic() < deadline, "JupyterLab did not start within 60 s"
                time.sleep(0.5)
        assert sorted(item["name"] for item in listing["content"]) == NAMES
        first = get(port, f"/api/contents/{NAMES[0]}")
        assert [item["name"] for item in first["content"]] == [f"{NAMES[0]}.ipynb"]
        assert "python3" in get(port, "/api/kernelspecs")["kernelspecs"]
        assert "@jupyterlab" in json.dumps(get(port, "/lab/api/settings"))
    finally:
        os.killpg(server.pid, signal.SIGTERM)
        server.wait(timeout=30)
