"""Grading on a real Dask cluster: a scheduler and two workers started as an instructor would.

The cluster's processes are Dask's own command-line tools (``dask scheduler``, ``dask
worker``) on 127.0.0.1; the class is graded through them and must get exactly the grades of
the local run. One worker is killed while it grades a student: no student is lost, its task
runs again on the other worker. Also here: a run interrupted and run again grades only what
is left, and a student whose files changed is graded again.
"""

from __future__ import annotations

import dataclasses
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import nbformat
import pytest
from pace import seconds

from autograder.bench import filled_notebook
from autograder.cluster import dask_cluster
from autograder.course import ROOT
from autograder.grade import grade_class
from autograder.sandbox import Limits

pytestmark = [pytest.mark.slow, pytest.mark.timeout(600)]

ASSIGNMENT = "03_frames"
LIMITS = Limits(cell_seconds=seconds(20), submission_seconds=seconds(120))


def _class(folder: Path) -> Path:
    """Four students of 03_frames: two solved it, one left it as released, one broke an answer."""
    for student in ("ada", "ben", "cy", "dee"):
        target = folder / student / ASSIGNMENT
        shutil.copytree(ROOT / "course" / ASSIGNMENT, target)
        if student == "cy":
            continue
        notebook = filled_notebook(ASSIGNMENT)
        if student == "dee":
            for cell in notebook.cells:
                if cell.get("metadata", {}).get("nbgrader", {}).get("grade_id") == "wrap_angle":
                    cell.source = "def wrap_angle(theta):\n    return theta\n"
        nbformat.write(notebook, target / f"{ASSIGNMENT}.ipynb")
    return folder


def _grades(results):
    return {result.student: (result.cells, result.problems) for result in results}


@pytest.fixture(scope="module")
def graded_here(sandbox, tmp_path_factory):
    """The class graded on this machine (a local cluster of two): its folders and results."""
    root = tmp_path_factory.mktemp("local")
    submissions = _class(root / "submissions")
    results = grade_class(
        submissions, root / "out", jobs=2, names=[ASSIGNMENT], limits=LIMITS, driving=False
    )
    return submissions, root / "out", results


@pytest.fixture
def cluster():
    """A scheduler and two workers without nannies: a killed worker stays dead."""
    with dask_cluster(2) as running:
        yield running.address


def test_a_cluster_grades_as_the_local_run_and_loses_no_student_to_a_dead_worker(
    graded_here, tmp_path, cluster
):
    submissions, _, local = graded_here
    killed = []

    def kill_a_busy_worker() -> None:
        from distributed import Client

        with Client(cluster, timeout="30s") as client:
            deadline = time.monotonic() + 120
            while time.monotonic() < deadline:
                busy = [worker for worker, keys in client.processing().items() if keys]
                if busy:
                    (pid,) = client.run(os.getpid, workers=busy[:1]).values()
                    os.kill(pid, signal.SIGKILL)
                    killed.append(busy[0])
                    return
                time.sleep(0.2)

    killer = threading.Thread(target=kill_a_busy_worker)
    killer.start()
    remote = grade_class(
        submissions,
        tmp_path / "remote",
        names=[ASSIGNMENT],
        limits=LIMITS,
        driving=False,
        scheduler=cluster,
    )
    killer.join()
    assert killed, "no worker was busy to be killed"
    assert _grades(remote) == _grades(local)
    by_name = {result.student: result for result in remote}
    assert by_name["ada"].total == by_name["ada"].max_total == 9
    assert by_name["cy"].total == 0
    assert dict(by_name["dee"].cells)[(ASSIGNMENT, "test_wrap_angle")][0] == 0
    assert all(result.complete for result in remote)


def test_duckie_grade_refuses_a_scheduler_that_is_not_there(tmp_path):
    (tmp_path / "submissions" / "ada").mkdir(parents=True)
    command = [sys.executable, "-m", "duckielib.tools.cli", "grade", str(tmp_path / "submissions")]
    command += ["--out", str(tmp_path / "out"), "--scheduler", "tcp://127.0.0.1:9", "--no-sandbox"]
    result = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)
    assert result.returncode == 1
    assert result.stderr.startswith("duckie: No Dask scheduler answered at tcp://127.0.0.1:9")
    assert "Traceback" not in result.stderr


def test_a_second_run_grades_only_the_new_and_the_changed(graded_here, tmp_path):
    # The class as graded once (a copy of its folders), graded again after changes.
    submissions, out = tmp_path / "submissions", tmp_path / "out"
    shutil.copytree(graded_here[0], submissions, symlinks=True)
    shutil.copytree(graded_here[1], out, symlinks=True)
    first = graded_here[2]
    lines = []
    kept = {path.name: path.stat().st_mtime_ns for path in (out / "results").iterdir()}
    # Ben fixes nothing, Cy solves it at last, and Eve hands in late.
    shutil.copytree(submissions / "ada", submissions / "eve")
    shutil.copy(
        submissions / "ada" / ASSIGNMENT / f"{ASSIGNMENT}.ipynb", submissions / "cy" / ASSIGNMENT
    )
    second = grade_class(
        submissions, out, names=[ASSIGNMENT], limits=LIMITS, driving=False, progress=lines.append
    )
    now = {path.name: path.stat().st_mtime_ns for path in (out / "results").iterdir()}
    assert [line.split(" graded")[0] for line in lines] == ["4/5", "5/5"]
    assert {name for name in now if now[name] != kept.get(name)} == {"cy.json", "eve.json"}
    by_name = {result.student: result for result in second}
    assert by_name["cy"].total == by_name["eve"].total == 9
    assert _grades([r for r in second if r.student in ("ada", "ben", "dee")]) == _grades(
        [r for r in first if r.student in ("ada", "ben", "dee")]
    )
    rows = (out / "grades.csv").read_text().splitlines()
    assert [row.split(",")[0] for row in rows[1:]] == ["ada", "ben", "cy", "dee", "eve"]


def test_ctrl_c_keeps_the_students_graded_so_far_and_the_next_run_finishes(sandbox, tmp_path):
    submissions = _class(tmp_path / "submissions")
    out = tmp_path / "out"
    command = [sys.executable, "-m", "duckielib.tools.cli", "grade", str(submissions), "--out"]
    command += [str(out), "--assignment", ASSIGNMENT, "--no-driving", "--jobs", "2"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 240
    while time.monotonic() < deadline and not list((out / "results").glob("*.json")):
        time.sleep(0.2)
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=120)
    kept = sorted(path.stem for path in (out / "results").glob("*.json"))
    assert 1 <= len(kept) < 4, stdout
    assert process.returncode == 130, stderr
    assert "duckie: interrupted. The students graded so far are in" in stderr
    assert "Traceback" not in stderr
    rows = (out / "grades.csv").read_text().splitlines()
    assert sorted(row.split(",")[0] for row in rows[1:]) == kept
    again = subprocess.run(command, capture_output=True, text=True, timeout=300, check=False)
    assert again.returncode == 0, again.stderr
    graded_now = [line for line in again.stdout.splitlines() if " graded (" in line]
    assert len(graded_now) == 4 - len(kept)
    rows = (out / "grades.csv").read_text().splitlines()
    assert [row.split(",")[0] for row in rows[1:]] == ["ada", "ben", "cy", "dee"]


def test_a_ctrl_c_while_a_student_is_recorded_waits_until_the_record_is_whole(tmp_path):
    # The race CI once hit: Ctrl-C between a student's results/ file and the class's CSV.
    from autograder.grade import _whole_on_ctrl_c

    def record() -> None:
        with _whole_on_ctrl_c():
            (tmp_path / "results.json").write_text("{}")
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)  # the signal is delivered here, in the middle of the record
            (tmp_path / "grades.csv").write_text("student\n")

    before = signal.getsignal(signal.SIGINT)
    with pytest.raises(KeyboardInterrupt):
        record()
    assert sorted(path.name for path in tmp_path.iterdir()) == ["grades.csv", "results.json"]
    assert signal.getsignal(signal.SIGINT) is before


def test_a_unit_that_cannot_grade_says_so_and_asks_to_be_run_again(tmp_path):
    from autograder.launch import run_unit
    from autograder.results import from_data

    task = {
        "student": "ada",
        "names": [ASSIGNMENT],
        "course": [ASSIGNMENT],
        "limits": dataclasses.asdict(LIMITS),
        "use_sandbox": False,
        "driving": False,
    }
    answer = run_unit(task, {f"{ASSIGNMENT}/{ASSIGNMENT}.ipynb": b"{}"}, tmp_path / "no-course")
    result = from_data(answer["result"])
    assert not result.complete
    (problem,) = result.problems
    assert problem.startswith("Not graded: the grader's process for this student stopped (")
    assert problem.endswith("; run duckie grade again to grade this student.")
    assert answer["autograded"] == {}
