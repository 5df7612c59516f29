"""Grading a class: real nbgrader, student code in a bubblewrap sandbox, students in parallel."""

from __future__ import annotations

import csv
import html
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Optional

import nbformat
import pytest
from pace import seconds

from autograder.course import ROOT
from autograder.driving import MISSIONS
from autograder.grade import grade_class, raised_outside_tests
from autograder.sandbox import NOBODY, Limits, sandboxed_command
from autograder.sandbox.inside.notebook import NOT_RUN
from duckielib.tools import deploy as robot_project

pytestmark = pytest.mark.slow

ASSIGNMENT = "03_frames"


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


def test_the_sandbox_reads_matplotlibs_font_list_and_cannot_change_the_graders(sandbox, tmp_path):
    # matplotlib finds the machine's fonts listed (it would list them again, 0.2 s of CPU, in
    # every sandbox); the list is the grader's, which a student's code cannot write.
    from autograder.sandbox.bubblewrap import font_list

    before = font_list().read_bytes()
    result = run_inside(
        tmp_path,
        "import logging, os\n"
        "logging.basicConfig(level=logging.INFO)\n"
        "from matplotlib import font_manager\n"
        "from matplotlib.font_manager import findfont\n"
        "print(os.path.isfile(findfont('DejaVu Sans')))\n"
        "(name,) = os.listdir(os.environ['MPLCONFIGDIR'])\n"
        "try:\n"
        "    open(os.path.join(os.environ['MPLCONFIGDIR'], name), 'w').write('{}')\n"
        "except OSError as error:\n"
        "    print('refused', error.strerror)\n",
    )
    assert result.stdout.split("\n")[:2] == ["True", "refused Read-only file system"], (
        result.stdout + result.stderr
    )
    assert "generated new fontManager" not in result.stderr
    assert font_list().read_bytes() == before


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
    # Of the grader, only what runs inside: the server's package and the calls' kernel side.
    grader = ROOT / "autograder"
    seen = [grader / "sandbox" / "inside" / "serve.py", grader / "calls.py"]
    hidden = [grader / "grade.py", grader / "sandbox" / "server.py", grader / "unit.py"]
    paths = [str(path) for path in seen + hidden]
    code += f"print(*[pathlib.Path(path).exists() for path in {paths!r}])\n"
    result = run_inside(tmp_path, code)
    assert result.stdout.split() == [
        str(NOBODY), "False", "False", "False", "read-only", "True", "True", "False", "False",
        "False",
    ], result.stderr  # fmt: skip
    assert (tmp_path / "box" / "mine.txt").read_text() == "ok"


def test_the_sandbox_shows_the_robot_project_but_not_a_prepared_solution(
    sandbox, tmp_path, monkeypatch
):
    # Notebook 11 reads the robot project; `duckie robot prepare` may have written the
    # reference solution into its deploy/ folder on the grader's machine. Nothing else of the
    # repository is shown (the robot's modules are chosen by folder, not read from a file).
    project = tmp_path / "robot_nodes"
    (project / "deploy").mkdir(parents=True)
    (project / "Dockerfile").write_text("FROM duckietown\n")
    (project / "deploy" / "solution.py").write_text("ANSWERS = 42\n")
    (tmp_path / "pyproject.toml").write_text("[tool.duckielib]\n")
    (tmp_path / "gradebook.db").write_text("hidden tests")
    monkeypatch.setattr(robot_project, "PROJECT", project)
    monkeypatch.setattr(robot_project, "ROOT", tmp_path)
    code = (
        "import pathlib\n"
        f"project = pathlib.Path({str(project)!r})\n"
        "print((project / 'Dockerfile').read_text().strip())\n"
        "print((project / 'deploy' / 'solution.py').exists())\n"
        "print((project.parent / 'pyproject.toml').exists())\n"
        "print((project.parent / 'gradebook.db').exists())\n"
    )
    result = run_inside(tmp_path, code)
    assert result.stdout.splitlines() == [
        "FROM duckietown",
        "False",
        "False",
        "False",
    ], result.stderr


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


def test_a_new_gradebook_is_stamped_as_alembic_heads_says_with_no_command_started(
    tmp_path, monkeypatch
):
    import sqlite3

    from nbgrader.api import Gradebook
    from nbgrader.dbutil import write_alembic_ini

    from autograder.course import gradebook_revision, nbgrader_api, nbgrader_config

    ini = tmp_path / "alembic.ini"
    write_alembic_ini(str(ini), f"sqlite:///{tmp_path / 'any.db'}")
    heads = subprocess.run(
        [str(Path(sys.executable).parent / "alembic"), "-c", str(ini), "heads"],
        capture_output=True,
        text=True,
        check=True,
    )
    assert heads.stdout.split()[0] == gradebook_revision()
    nbgrader_api(nbgrader_config(root=tmp_path, db=tmp_path / "gradebook.db"))
    monkeypatch.setenv("PATH", str(tmp_path / "no-programs-here"))  # no alembic to start
    with Gradebook(f"sqlite:///{tmp_path / 'new.db'}"):
        pass
    with sqlite3.connect(tmp_path / "new.db") as database:
        (stamped,) = database.execute("SELECT version_num FROM alembic_version").fetchall()
    assert stamped == (gradebook_revision(),)


def test_a_class_is_graded_in_parallel_with_one_gradebook(sandbox, tmp_path):
    submissions = tmp_path / "submissions"
    _submission(submissions, "ada", ROOT / "solutions")
    _submission(submissions, "ben", ROOT / "course")
    _submission(submissions, "cy", ROOT / "solutions", edit=_loop_forever)
    (submissions / "dee").mkdir()
    lines = []
    unpacked = set(Path(tempfile.gettempdir()).glob("duckie-course-*"))
    results = grade_class(
        submissions,
        tmp_path / "out",
        jobs=2,
        limits=Limits(cell_seconds=seconds(15), submission_seconds=seconds(120)),
        names=[ASSIGNMENT],
        progress=lines.append,
    )
    by_name = {result.student: result for result in results}
    # The course each worker unpacked went with the worker's own folder.
    assert set(Path(tempfile.gettempdir()).glob("duckie-course-*")) == unpacked
    assert by_name["ada"].total == by_name["ada"].max_total > 0
    assert by_name["ben"].total == 0
    assert by_name["ben"].max_total == by_name["ada"].max_total
    # An endless loop costs its own tests only (the cell's time runs out).
    cy = {grade_id: score for (_, grade_id), (score, _) in by_name["cy"].cells.items()}
    assert cy["test_wrap_angle"] == 0
    assert cy["test_rotation_matrix"] > 0
    assert by_name["dee"].problems == [f"{ASSIGNMENT}: no {ASSIGNMENT}.ipynb in the submission"]
    # The release's demo cells call the unwritten functions: each is named; its tests are not.
    assert not [problem for problem in by_name["ada"].problems if "raised" in problem]
    (raised,) = by_name["ben"].problems
    assert "): NotImplementedError" in raised
    _check_raised(raised, tmp_path / "out", "ben")
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
    assert [rows["ada"][f"driving:{name}"] for name in MISSIONS] == ["0"] * 4
    assert rows["ada"]["driving_problems"].startswith(
        "square_then_circle: The mission could not run to its end: Finish notebook"
    )
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


def _check_raised(problem: str, out: Path, student: str) -> None:
    """``problem`` names exactly the cells outside the tests whose run raised, none twice."""
    path = out / "work" / "autograded" / student / ASSIGNMENT / f"{ASSIGNMENT}.ipynb"
    cells = nbformat.read(path, 4).cells
    tests = [i for i, cell in enumerate(cells, 1) if cell.metadata.get("nbgrader", {}).get("grade")]
    raised = [
        i
        for i, cell in enumerate(cells, 1)
        if i not in tests and any(o.output_type == "error" for o in cell.get("outputs", []))
    ]
    # The release's test cells raise (NotImplementedError): they are failed tests only.
    assert [i for i in tests if any(o.output_type == "error" for o in cells[i - 1].outputs)]
    named = [int(number) for number in re.findall(r"(?:: |; )cell (\d+) \(", problem)]
    assert named == raised, problem
    assert problem.startswith(f"{ASSIGNMENT}: {len(raised)} cells outside the tests raised: ")


def test_duckie_grade_names_the_cells_outside_the_tests_that_raised_without_a_sandbox(tmp_path):
    """The real command, without bubblewrap: the class's CSV and the feedback page say it."""
    submissions, out = tmp_path / "submissions", tmp_path / "out"
    _submission(submissions, "fay", ROOT / "course", edit=_stray_cell)
    command = [sys.executable, "-m", "duckielib.tools.cli", "grade", str(submissions), "--out"]
    command += [str(out), "--assignment", ASSIGNMENT, "--no-driving", "--no-sandbox"]
    result = subprocess.run(command, capture_output=True, text=True, timeout=300, check=False)
    assert result.returncode == 0, result.stdout + result.stderr
    with (out / "grades.csv").open() as handle:
        (row,) = csv.DictReader(handle)
    (problem,) = row["problems"].split(" | ")
    # The stray cell went in as the third cell; the release's demo cells raise after it.
    stray = "cell 3 (print(undefined_name)  # a stray line): NameError: name 'undefined_name'"
    assert f": {stray} is not defined; cell " in problem
    _check_raised(problem, out, "fay")
    assert html.escape(problem) in (out / "feedback" / "fay.html").read_text()


def _stray_cell(notebook) -> None:
    notebook.cells.insert(2, nbformat.v4.new_code_cell("\nprint(undefined_name)  # a stray line\n"))


def _error(ename: str, evalue: str):
    return nbformat.v4.new_output("error", ename=ename, evalue=evalue, traceback=["the trace"])


def test_every_raising_cell_is_named_once_and_tests_and_cells_not_run_are_left_out():
    test = nbformat.v4.new_code_cell("assert f() == 1", metadata={"nbgrader": {"grade": True}})
    sent = nbformat.v4.new_notebook(
        cells=[
            nbformat.v4.new_markdown_cell("# A title"),
            nbformat.v4.new_code_cell(
                "\n   \n    value = compute_something_with_a_rather_long_name(1, 2, 3)"
            ),
            test,
            nbformat.v4.new_code_cell("plot(value)"),
            nbformat.v4.new_code_cell("after_the_crash()"),
            nbformat.v4.new_code_cell("while True:\n    pass"),
        ]
    )
    executed = nbformat.reads(nbformat.writes(sent), as_version=4)
    outputs = [
        [],
        [_error("\x1b[0;31mValueError\x1b[0m", "a message\non two lines " + "x" * 200)],
        [_error("AssertionError", "f() should be 1")],
        [nbformat.v4.new_output("stream", text="fine"), _error("NameError", "no 'value'")],
        [_error(NOT_RUN, "This cell did not run: the kernel died.")],
        [_error("CellTimeoutError", "")],
    ]
    for cell, cell_outputs in zip(executed.cells, outputs):
        if cell.cell_type == "code":
            cell.outputs = cell_outputs
    # A student cannot make a cell a test: which cells are tests is read from what was sent.
    executed.cells[3].metadata["nbgrader"] = {"grade": True}
    problem = raised_outside_tests("07_control", sent, executed, cell_seconds=5)
    assert problem == (
        "07_control: 3 cells outside the tests raised: "
        "cell 2 (value = compute_something_with_a_rather_long_name…): ValueError: a message "
        f"on two lines {'x' * 96}…; "
        "cell 4 (plot(value)): NameError: no 'value'; "
        "cell 6 (while True:): CellTimeoutError: still running after the 5 s a cell may take"
    )
    assert raised_outside_tests("07_control", sent, sent) is None


def test_duckie_grade_refuses_a_missing_folder(tmp_path):
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "duckielib.tools.cli",
            "grade",
            str(tmp_path / "nope"),
            "--out",
            "x",
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 1
    assert result.stderr.startswith("duckie: There is no folder")
    assert "Traceback" not in result.stderr


def test_duckie_grade_refuses_a_folder_without_a_submission(tmp_path):
    submissions = tmp_path / "submissions"
    submissions.mkdir()
    (submissions / "notes.txt").write_text("the class list")
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "duckielib.tools.cli",
            "grade",
            str(submissions),
            "--out",
            str(tmp_path / "out"),
        ],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 1
    assert result.stderr == (
        f"duckie: No submission was found in {submissions}: it must hold one folder (or .zip) "
        "per student, named after them (skipped: notes.txt: neither a folder nor a .zip).\n"
    )
    assert not (tmp_path / "out").exists(), "no empty grades.csv"


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
    # The links are never read: nothing of the reference is graded, exported or driven.
    assert result.total == 0
    assert result.problems == [
        f"{ASSIGNMENT}: {ASSIGNMENT}.ipynb is a symbolic link; it was left out.",
        f"{ASSIGNMENT}: no {ASSIGNMENT}.ipynb in the submission",
    ]
    assert result.driving_score == 0
    nothing = "No notebook was handed in: there was nothing to drive."
    assert {name: driving.reasons for name, driving in result.missions.items()} == {
        name: [nothing] for name in MISSIONS
    }
