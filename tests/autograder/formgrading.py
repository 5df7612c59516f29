"""A small class with one answer in words, graded, and nbgrader's Formgrader opened on it.

The course source is 03_frames with one more cell: an answer in words (a markdown cell that
nbgrader leaves to a person) whose solution region is the rubric. The class is one student, ada,
with the reference answers and a written answer. The manual grading tests grade it with
:func:`autograder.grade.grade_class`, give the answer its points in Formgrader, which
``duckie formgrade`` opens, and fold them in with ``duckie feedback``.
"""

from __future__ import annotations

import contextlib
import csv
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
import urllib.request
from dataclasses import dataclass
from pathlib import Path

import nbformat

from autograder.bench import filled_notebook
from autograder.course import ROOT
from autograder.grade import grade_class
from autograder.results import StudentResult
from autograder.sandbox import Limits

ASSIGNMENT = "03_frames"
ANSWER = "answer_frames"
RUBRIC = "**Rubric (2 points).** A full answer names the rotation by theta."
WRITTEN = "The robot frame turns with theta, so I rotate by it."


def answer_cell(text: str) -> nbformat.NotebookNode:
    """An answer in words worth 2 points, graded by a person, holding ``text``."""
    return nbformat.v4.new_markdown_cell(
        text,
        metadata={
            "nbgrader": {
                "grade": True,
                "solution": True,
                "locked": False,
                "task": False,
                "points": 2,
                "grade_id": ANSWER,
                "schema_version": 3,
            }
        },
    )


@dataclass
class SmallClass:
    """The course source and ada's submission, written under one folder.

    Attributes:
        source: the course source: 03_frames with the answer in words and its rubric.
        submissions: the class's submissions, ``submissions/ada/03_frames/03_frames.ipynb``.
        student: ada's notebook, as written to :attr:`handed_in`.
        handed_in: the path of ada's notebook.
    """

    source: Path
    submissions: Path
    student: nbformat.NotebookNode
    handed_in: Path

    def grade(self, out: Path) -> list[StudentResult]:
        """Grade the class into ``out`` without driving: one result, ada's."""
        return grade_class(
            self.submissions,
            out,
            names=[ASSIGNMENT],
            source=self.source,
            driving=False,
            limits=Limits(),
        )


def small_class(root: Path) -> SmallClass:
    """Write the course source and ada's submission under ``root``."""
    source = root / "source"
    shutil.copytree(ROOT / "solutions" / ASSIGNMENT, source / ASSIGNMENT)
    path = source / ASSIGNMENT / f"{ASSIGNMENT}.ipynb"
    notebook = nbformat.read(path, as_version=4)
    notebook.cells.append(answer_cell(f"### BEGIN SOLUTION\n{RUBRIC}\n### END SOLUTION"))
    nbformat.write(notebook, path)
    student = filled_notebook(ASSIGNMENT)
    student.cells.append(answer_cell(WRITTEN))
    folder = root / "submissions" / "ada" / ASSIGNMENT
    folder.mkdir(parents=True)
    handed_in = folder / f"{ASSIGNMENT}.ipynb"
    nbformat.write(student, handed_in)
    return SmallClass(source, root / "submissions", student, handed_in)


@dataclass
class Formgrader:
    """``duckie formgrade`` running on ``port``, its pages and API reached with ``token``."""

    port: int
    token: str

    def url(self, path: str = "") -> str:
        """The address of ``path`` on the server, token included, as a browser opens it."""
        return f"http://127.0.0.1:{self.port}/{path}?token={self.token}"

    def ask(self, method: str, path: str, body=None, as_json: bool = True):
        """Call Formgrader's page or API ``path`` (under ``formgrader/``); its answer."""
        request = urllib.request.Request(
            f"http://127.0.0.1:{self.port}/formgrader/{path}",
            method=method,
            data=None if body is None else json.dumps(body).encode(),
            headers={"Authorization": f"token {self.token}"},
        )
        with urllib.request.urlopen(request, timeout=30) as answer:
            text = answer.read().decode()
        return json.loads(text) if as_json else text


@contextlib.contextmanager
def formgrader(out: Path):
    """``duckie formgrade OUT`` running, until the block ends; yields its :class:`Formgrader`."""
    server = Formgrader(free_port(), "formgrade-test")
    command = [sys.executable, "-m", "duckielib.tools.cli", "formgrade", str(out), "--"]
    command += ["--no-browser", f"--port={server.port}", f"--ServerApp.token={server.token}"]
    process = subprocess.Popen(
        command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
    )
    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                server.ask("GET", "api/assignments")
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.3)
        yield server
    finally:
        os.killpg(process.pid, signal.SIGTERM)
        process.wait(timeout=30)


def duckie(*args: str) -> subprocess.CompletedProcess:
    """Run the ``duckie`` command line with ``args``; its exit status and output."""
    command = [sys.executable, "-m", "duckielib.tools.cli", *args]
    return subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def rows(out: Path) -> dict:
    """``grades.csv`` of ``out``: each student's row, by student."""
    with (out / "grades.csv").open() as handle:
        return {row["student"]: row for row in csv.DictReader(handle)}


def check_folded(out: Path, points: str, comment: str) -> str:
    """Run ``duckie feedback OUT`` and check that the grade and comment given reached
    ``grades.csv`` and ada's feedback page (never the rubric); return the page."""
    folded = duckie("feedback", str(out))
    assert folded.returncode == 0, folded.stderr
    assert "0 answers still wait for a grade" in folded.stdout
    row = rows(out)["ada"]
    total = f"{9 + float(points):g}"
    assert (row["to_grade"], row[f"{ASSIGNMENT}:{ANSWER}"], row["total"]) == ("0", points, total)
    page = (out / "feedback" / "ada.html").read_text()
    assert f"<td>{ANSWER}</td><td>{points} / 2</td>" in page
    assert f'<pre class="comment">{comment}</pre>' in page
    assert "A full answer names the rotation by theta." not in page
    assert "For the grader" not in page
    return page
