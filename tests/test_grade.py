"""Grading a class: real nbgrader, student code in a bubblewrap sandbox, students in parallel."""

from __future__ import annotations

import csv
import html
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Optional

import nbformat
import pytest

from autograder.course import ROOT
from autograder.grade import grade_class
from autograder.sandbox import NOBODY, Limits, check_sandbox, sandboxed_command

pytestmark = pytest.mark.slow

ASSIGNMENT = "03_frames"


@pytest.fixture(scope="module")
def sandbox():
    if shutil.which("bwrap") is None:
        pytest.skip("bubblewrap is not installed; run `make ros`.")
    check_sandbox()


def run_inside(tmp_path: Path, code: str, limits: Optional[Limits] = None):
    """Run Python ``code`` in a sandbox whose folder is ``tmp_path/box``."""
    folder = tmp_path / "box"
    folder.mkdir(exist_ok=True)
    os.chown(folder, NOBODY, NOBODY)
    command = sandboxed_command([sys.executable, "-c", code], folder, limits or Limits())
    return subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)


def test_the_sandbox_has_no_network(sandbox, tmp_path):
    result = run_inside(
        tmp_path,
        "import socket\n"
        "try:\n"
        "    socket.create_connection(('1.1.1.1', 53), timeout=3)\n"
        "    print('connected')\n"
        "except OSError as error:\n"
        "    print('refused', error.errno)\n",
    )
    assert result.stdout.startswith("refused"), result.stdout + result.stderr


def test_the_sandbox_hides_the_course_and_the_grader(sandbox, tmp_path):
    (tmp_path / "gradebook.db").write_text("hidden tests")
    code = (
        "import os, pathlib\n"
        f"print(os.getuid(), pathlib.Path({str(ROOT / 'solutions')!r}).exists(),"
        f" pathlib.Path({str(tmp_path / 'gradebook.db')!r}).exists(),"
        f" pathlib.Path({str(ROOT / 'course')!r}).exists())\n"
        "open('/sandbox/mine.txt', 'w').write('ok')\n"
        "try:\n"
        "    open('/etc/hostname-new', 'w')\n"
        "except OSError:\n"
        "    print('read-only')\n"
    )
    result = run_inside(tmp_path, code)
    assert result.stdout.split() == [str(NOBODY), "False", "False", "False", "read-only"], (
        result.stderr
    )
    assert (tmp_path / "box" / "mine.txt").read_text() == "ok"


def test_the_sandbox_limits_memory_and_processes(sandbox, tmp_path):
    memory = run_inside(
        tmp_path,
        "try:\n    block = bytearray(20 * 1024**3)\nexcept MemoryError:\n    print('no memory')\n",
    )
    assert memory.stdout.strip() == "no memory", memory.stderr
    forks = run_inside(
        tmp_path,
        "import os, time\n"
        "children = 0\n"
        "try:\n"
        "    for _ in range(200):\n"
        "        if os.fork() == 0:\n"
        "            time.sleep(5); os._exit(0)\n"
        "        children += 1\n"
        "except OSError:\n"
        "    pass\n"
        "print(children)\n",
        Limits(processes=50),
    )
    assert int(forks.stdout.split()[-1]) < 60, forks.stdout + forks.stderr


def _submission(folder: Path, student: str, source: Path, edit=None) -> None:
    target = folder / student / ASSIGNMENT
    shutil.copytree(source / ASSIGNMENT, target)
    if edit is not None:
        path = target / f"{ASSIGNMENT}.ipynb"
        notebook = nbformat.read(path, as_version=4)
        edit(notebook)
        nbformat.write(notebook, path)


def _loop_forever(notebook) -> None:
    for cell in notebook.cells:
        if cell.get("metadata", {}).get("nbgrader", {}).get("grade_id") == "wrap_angle":
            cell.source = "def wrap_angle(theta):\n    while True:\n        pass\n"


def test_a_class_is_graded_in_parallel_with_one_gradebook(sandbox, tmp_path):
    submissions = tmp_path / "submissions"
    _submission(submissions, "ada", ROOT / "solutions")
    _submission(submissions, "ben", ROOT / "course")
    _submission(submissions, "cy", ROOT / "solutions", edit=_loop_forever)
    (submissions / "dee").mkdir()
    lines = []
    results = grade_class(
        submissions,
        tmp_path / "out",
        jobs=2,
        limits=Limits(cell_seconds=5, submission_seconds=120),
        names=[ASSIGNMENT],
        progress=lines.append,
    )
    by_name = {result.student: result for result in results}
    assert by_name["ada"].total == by_name["ada"].max_total > 0
    assert by_name["ben"].total == 0
    assert by_name["ben"].max_total == by_name["ada"].max_total
    # An endless loop costs its own tests only (the cell's time runs out).
    cy = {grade_id: score for (_, grade_id), (score, _) in by_name["cy"].cells.items()}
    assert cy["test_wrap_angle"] == 0
    assert cy["test_rotation_matrix"] > 0
    assert by_name["dee"].problems == [f"{ASSIGNMENT}: no {ASSIGNMENT}.ipynb in the submission"]
    assert len(lines) == 4
    assert lines[-1].startswith("4/4 graded")
    with (tmp_path / "out" / "grades.csv").open() as handle:
        rows = {row["student"]: row for row in csv.DictReader(handle)}
    assert set(rows) == {"ada", "ben", "cy", "dee"}
    assert float(rows["ada"]["total"]) == by_name["ada"].total
    assert rows["ada"]["max_total"] == rows["ben"]["max_total"]
    assert {"driving_score", "problems", f"{ASSIGNMENT}:test_wrap_angle"} <= set(rows["ada"])
    assert json.loads((tmp_path / "out" / "skipped.json").read_text()) == []
    # Only 03_frames was handed in: the export lacks the mission's parts, so no driving score.
    assert rows["ada"]["driving_score"] == "0"
    assert rows["ada"]["driving_problems"].startswith("The mission could not run:")
    # Feedback: one page each, with the failed tests' messages and never a hidden test's code.
    pages = {name: (tmp_path / "out" / "feedback" / f"{name}.html").read_text() for name in rows}
    assert "CellTimeoutError" in pages["cy"]
    assert "is not written yet" in pages["ben"]
    assert pages["ada"].count(">passed<") == 4
    assert ">failed<" not in pages["ada"]
    reference = nbformat.read(ROOT / "solutions" / ASSIGNMENT / f"{ASSIGNMENT}.ipynb", 4)
    hidden = [
        line.strip()
        for cell in reference.cells
        for region in cell.source.split("### BEGIN HIDDEN TESTS")[1:]
        for line in region.split("### END HIDDEN TESTS")[0].splitlines()
        if len(line.strip()) > 20
    ]
    assert len(hidden) > 20
    for page in pages.values():
        assert not [line for line in hidden if html.escape(line) in page]


def test_duckie_grade_refuses_a_missing_folder(tmp_path):
    result = subprocess.run(
        [sys.executable, "-m", "duckielib.cli", "grade", str(tmp_path / "nope"), "--out", "x"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 1
    assert result.stderr.startswith("duckie: There is no folder")
    assert "Traceback" not in result.stderr


def test_notebooks_linked_to_the_reference_are_neither_graded_nor_driven(sandbox, tmp_path):
    student = tmp_path / "submissions" / "eve"
    for notebook in sorted((ROOT / "solutions").glob("*/*.ipynb")):
        (student / notebook.parent.name).mkdir(parents=True)
        (student / notebook.parent.name / notebook.name).symlink_to(notebook)
    before = {path: path.read_bytes() for path in (ROOT / "solutions").glob("*/*.ipynb")}
    (result,) = grade_class(
        tmp_path / "submissions", tmp_path / "out", names=[ASSIGNMENT], limits=Limits()
    )
    assert {path: path.read_bytes() for path in before} == before, "a link was written through"
    assert result.total == 0
    assert result.problems == [f"{ASSIGNMENT}: the notebook is a link; the release was graded"]
    assert result.driving.score == 0
    assert result.driving.reasons[0].startswith("The mission could not run: Finish notebook")
