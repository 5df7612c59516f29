"""Answers graded by a person: they wait in the gradebook, and a grade given there is never lost.

A course source with one answer cell in words (an nbgrader manually graded cell) next to the
autograded tests of 03_frames. ``duckie grade`` leaves the answer to a person: it counts for
nothing until graded, its column stays empty and ``to_grade`` counts it. A grade given in
nbgrader's Formgrader, opened on the graded class by ``duckie formgrade``, shows at the next
run, and stays when the student's files change and they are graded again.
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

import nbformat
import pytest

from autograder.bench import filled_notebook
from autograder.course import ROOT
from autograder.grade import grade_class
from autograder.sandbox import Limits

pytestmark = pytest.mark.slow

ASSIGNMENT = "03_frames"
ANSWER = "answer_frames"


def _answer_cell(text: str):
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


@contextlib.contextmanager
def _formgrader(out):
    """``duckie formgrade OUT`` running; a function that calls its pages and API."""
    port, token = _free_port(), "formgrade-test"
    command = [sys.executable, "-m", "duckielib.cli", "formgrade", str(out), "--"]
    command += ["--no-browser", f"--port={port}", f"--ServerApp.token={token}"]
    server = subprocess.Popen(
        command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
    )

    def ask(method, path, body=None, as_json=True):
        request = urllib.request.Request(
            f"http://127.0.0.1:{port}/formgrader/{path}",
            method=method,
            data=None if body is None else json.dumps(body).encode(),
            headers={"Authorization": f"token {token}"},
        )
        with urllib.request.urlopen(request, timeout=30) as answer:
            text = answer.read().decode()
        return json.loads(text) if as_json else text

    try:
        deadline = time.monotonic() + 60
        while True:
            try:
                ask("GET", "api/assignments")
                break
            except OSError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.3)
        yield ask
    finally:
        os.killpg(server.pid, signal.SIGTERM)
        server.wait(timeout=30)


def _free_port():
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def _rows(out):
    with (out / "grades.csv").open() as handle:
        return {row["student"]: row for row in csv.DictReader(handle)}


def test_an_answer_in_words_waits_for_a_person_and_keeps_their_grade(sandbox, tmp_path):
    source = tmp_path / "source"
    shutil.copytree(ROOT / "solutions" / ASSIGNMENT, source / ASSIGNMENT)
    path = source / ASSIGNMENT / f"{ASSIGNMENT}.ipynb"
    notebook = nbformat.read(path, as_version=4)
    rubric = "**Rubric (2 points).** A full answer names the rotation by theta."
    notebook.cells.append(_answer_cell(f"### BEGIN SOLUTION\n{rubric}\n### END SOLUTION"))
    nbformat.write(notebook, path)
    student = filled_notebook(ASSIGNMENT)
    student.cells.append(_answer_cell("The robot frame turns with theta, so I rotate by it."))
    folder = tmp_path / "submissions" / "ada" / ASSIGNMENT
    folder.mkdir(parents=True)
    nbformat.write(student, folder / f"{ASSIGNMENT}.ipynb")
    out = tmp_path / "out"
    options = {"names": [ASSIGNMENT], "source": source, "driving": False, "limits": Limits()}

    (first,) = grade_class(tmp_path / "submissions", out, **options)
    assert first.to_grade == [(ASSIGNMENT, ANSWER)]
    assert first.total == 9
    assert first.max_total == 11
    row = _rows(out)["ada"]
    assert (row["to_grade"], row[f"{ASSIGNMENT}:{ANSWER}"], row["total"]) == ("1", "", "9")
    page = (out / "feedback" / "ada.html").read_text()
    assert "your instructor grades this answer" in page

    # A person grades the answer in Formgrader, opened by `duckie formgrade`: its page shows the
    # student's answer, and its API (what the page calls) takes the points.
    from nbgrader.api import Gradebook

    database = f"sqlite:///{out / 'work' / 'gradebook.db'}"
    with Gradebook(database) as gradebook:
        grade = gradebook.find_grade(ANSWER, ASSIGNMENT, ASSIGNMENT, "ada")
        assert grade.needs_manual_grade
        assert grade.auto_score is None
    with _formgrader(out) as ask:
        (submitted,) = ask("GET", f"api/submitted_notebooks/{ASSIGNMENT}/{ASSIGNMENT}")
        assert (submitted["student"], submitted["needs_manual_grade"]) == ("ada", True)
        page = ask("GET", f"submissions/{submitted['id']}/?index=0", as_json=False)
        assert "The robot frame turns with theta, so I rotate by it." in page
        assert "A full answer names the rotation by theta." in page  # the rubric, beside it
        grades = ask("GET", f"api/grades?submission_id={submitted['id']}")
        (answer,) = [grade for grade in grades if grade["name"] == ANSWER]
        given = ask("PUT", f"api/grade/{answer['id']}", {"manual_score": 1.5})
        assert given["manual_score"] == 1.5
        comments = ask("GET", f"api/comments?submission_id={submitted['id']}")
        (comment,) = [item for item in comments if item["name"] == ANSWER]
        said = "Good: name which way theta turns the frame."
        ask("PUT", f"api/comment/{comment['id']}", {"manual_comment": said})

    # `duckie feedback` folds the grade and the comment in at once, running nothing.
    command = [sys.executable, "-m", "duckielib.cli", "feedback", str(out)]
    folded = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)
    assert folded.returncode == 0, folded.stderr
    assert "0 answers still wait for a grade" in folded.stdout
    row = _rows(out)["ada"]
    assert (row["to_grade"], row[f"{ASSIGNMENT}:{ANSWER}"], row["total"]) == ("0", "1.5", "10.5")
    page = (out / "feedback" / "ada.html").read_text()
    assert "graded by your instructor" in page and said in page
    assert "A full answer names" not in page  # the rubric stays with the instructor

    (again,) = grade_class(tmp_path / "submissions", out, **options)
    assert again.to_grade == []
    assert again.comments == {(ASSIGNMENT, ANSWER): said}
    row = _rows(out)["ada"]
    assert (row["to_grade"], row[f"{ASSIGNMENT}:{ANSWER}"], row["total"]) == ("0", "1.5", "10.5")

    # The student hands in again: graded anew, and the person's grade stays.
    student.cells.insert(2, nbformat.v4.new_code_cell("print('one more try')"))
    nbformat.write(student, folder / f"{ASSIGNMENT}.ipynb")
    (regraded,) = grade_class(tmp_path / "submissions", out, **options)
    assert regraded.total == 10.5
    with Gradebook(database) as gradebook:
        grade = gradebook.find_grade(ANSWER, ASSIGNMENT, ASSIGNMENT, "ada")
        assert grade.manual_score == 1.5
        assert grade.needs_manual_grade  # nbgrader's rule: a person's grade is to be reviewed
    assert _rows(out)["ada"][f"{ASSIGNMENT}:{ANSWER}"] == "1.5"


def test_duckie_feedback_refuses_a_folder_that_was_never_graded(tmp_path):
    command = [sys.executable, "-m", "duckielib.cli", "feedback", str(tmp_path / "grading")]
    result = subprocess.run(command, capture_output=True, text=True, timeout=60, check=False)
    assert result.returncode == 1
    assert result.stderr == (
        f"duckie: {tmp_path / 'grading'} holds no graded class: grade it first with "
        f"`duckie grade SUBMISSIONS --out {tmp_path / 'grading'}`.\n"
    )


def test_duckie_formgrade_refuses_a_folder_that_was_never_graded(tmp_path):
    command = [sys.executable, "-m", "duckielib.cli", "formgrade", str(tmp_path / "grading")]
    result = subprocess.run(command, capture_output=True, text=True, timeout=60, check=False)
    assert result.returncode == 1
    assert result.stderr == (
        f"duckie: {tmp_path / 'grading'} has no gradebook: grade the class first with "
        f"`duckie grade SUBMISSIONS --out {tmp_path / 'grading'}`.\n"
    )
