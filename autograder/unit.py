"""Grading one student: the unit of a class's grading, in a process of its own.

Whatever one student's files do to the grader (a notebook nbgrader cannot handle, a hang, a
crash, all memory), it happens in this unit's process and stops there: the class's other
students, and the results already written, are not touched. A unit runs on any worker of the
class's Dask cluster (:mod:`autograder.grade`), which starts ``python -I -m autograder.unit
FOLDER`` (:func:`autograder.launch.run_unit`: unprivileged, on a file system of the student's
own, where the grader runs as root); this module is that process.

Inside, nbgrader works as it does for a class, on a gradebook of this unit's own (a copy of the
class's, which holds the hidden tests): the student's notebooks are repaired against the release
(:mod:`autograder.tamper`), autograded with their cells run in the sandbox
(:mod:`autograder.sandbox`), and exported to drive the missions
(:mod:`autograder.driving`). The grader reads back only what it asked for: the executed notebook
a sandboxed run prints (bounded), and the mission's files through :mod:`autograder.files`. The
notebooks it exports are its own repaired copies, in a folder no sandbox sees. No line of the
submission runs here: the tests' namespace comes from the course alone (:mod:`autograder.calls`).
"""

from __future__ import annotations

import dataclasses
import json
import os
import shutil
import sys
import tempfile
import time
import traceback
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

from autograder.notebook_problems import cell_seconds, cells_that_stopped, disk_full, slow_cells

__all__ = ["GraderFailed", "main"]

#: What of a student's files the notebook's folder gets: not notebooks (the repaired one is
#: written there), not hidden files, not Python modules (a ``numpy.py`` next to the notebook
#: would stand in for numpy in the tests).
SKIPPED = ("*.ipynb", ".*", "*.py", "*.pyc", "*.pth", "*.so")


class GraderFailed(Exception):
    """The grader's side failed on this student (nbgrader, its disk, its database): no grade."""


def _sandboxed_execute_class(unit: _Unit):
    """The class that takes the place of nbgrader's Execute: the notebook runs in the sandbox."""
    import nbformat
    from nbgrader.preprocessors import Execute

    from autograder.sandbox.inside.notebook import METADATA_KEY, NOT_RUN, mark_not_run

    class SandboxedExecute(Execute):
        def preprocess(self, nb, resources):
            name = resources["nbgrader"]["assignment"]
            began = time.monotonic()
            sent, tests = _remote_tests(nb)
            run = _TestsHere(unit, nb.cells, tests, _course_cells(unit, name), name)
            left = unit.limits.student_seconds - unit.timings["notebooks"]
            if left < 1:
                why = (
                    f"was not run: the student's notebooks had used the "
                    f"{unit.limits.student_seconds} s the grader gives them in all"
                )
                text, problem = None, why
            else:
                seconds = min(unit.limits.submission_seconds, left)
                text, problem = unit.server.run(name, nbformat.writes(sent), run.test, seconds)
            executed = None
            if text is not None:
                try:
                    executed = nbformat.reads(text, as_version=4)
                    if len(executed.cells) != len(nb.cells):
                        raise ValueError("cells added or lost")
                except Exception:  # damaged: the notebook's run is not trusted
                    executed = None
                    problem = "answered with something that is not the notebook sent"
            if executed is not None:
                outputs = run.outputs
                for index, grade_id in tests.items():
                    cell = executed.cells[index]
                    cell.source = nb.cells[index].source
                    cell.metadata.pop(METADATA_KEY, None)
                    ran = outputs.get(grade_id)
                    cell.outputs = (
                        [nbformat.from_dict(out) for out in ran]
                        if ran is not None
                        else [
                            nbformat.v4.new_output(
                                "error",
                                ename=NOT_RUN,
                                evalue=_NOT_RUN_TEST,
                                traceback=[_NOT_RUN_TEST],
                            )
                        ]
                    )
            unit.timings["notebooks"] += time.monotonic() - began
            unit.timings[f"notebook:{name}"] = time.monotonic() - began
            if executed is None:
                mark_not_run(nb, f"This cell did not run: the notebook {problem}.")
                unit.problems.append(f"{name}: the notebook {problem}.")
                return nb, resources
            unit.timings["cells"] += cell_seconds(executed)
            found = executed.metadata.pop(METADATA_KEY, {}).get("problems", [])
            unit.problems.extend(f"{name}: {problem}" for problem in found)
            unit.problems.extend(cells_that_stopped(name, nb, executed, unit.limits.cell_seconds))
            unit.problems.extend(slow_cells(name, nb, executed, unit.limits.slow_cell_seconds))
            return executed, resources

    return SandboxedExecute


_NOT_RUN_TEST = "This test did not run: the notebook's kernel stopped before it."


def _is_test(cell: Any) -> bool:
    """Whether ``cell`` is a test cell (code nbgrader grades that is not an answer)."""
    meta = cell.get("metadata", {}).get("nbgrader", {})
    return cell.cell_type == "code" and bool(meta.get("grade")) and not meta.get("solution")


def _remote_tests(notebook: Any) -> Tuple[Any, Dict[int, str]]:
    """The notebook to send to the sandbox: each test the grader runs on its side left empty.

    Returns:
        The notebook to send, and ``{cell index: grade_id}`` of the tests left empty there
        (every test cell).
    """
    import copy

    from autograder.sandbox.inside.notebook import METADATA_KEY
    from autograder.verdict import split_hidden

    sent = copy.deepcopy(notebook)
    tests: Dict[int, str] = {}
    for index, cell in enumerate(sent.cells):
        cell.get("metadata", {}).pop(METADATA_KEY, None)  # only the grader marks a cell
        grade_id = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id", "")
        if not _is_test(cell):
            continue
        source, cell.source = cell.source, ""  # a copy of a test is sent empty too
        if grade_id not in tests.values():
            # Whether it has hidden tests, which run after the notebook's last cell.
            hidden = bool(split_hidden(source)[1])
            cell.metadata[METADATA_KEY] = {"remote": True, "hidden": hidden}
            tests[index] = grade_id
    return sent, tests


def _course_cells(unit: Any, name: str) -> List[Any]:
    """The cells of the course's own notebook ``name`` (its source, with the answers)."""
    import nbformat

    path = unit.course_dir / "source" / name / f"{name}.ipynb"
    return list(nbformat.read(path, as_version=4).cells)


class _TestsHere:
    """Runs a notebook's tests in the unit's process, as the sandbox reaches each of them.

    The tests' namespace and the names they may ask of the kernel come from the course's own
    notebook (``course``), never from the submission: a cell a student added runs in the
    sandbox only. A test's visible part runs where the notebook reaches it, its hidden part
    after the notebook's last cell (:class:`autograder.verdict.TestRun`), both through one
    :class:`autograder.calls.Link`, so a student's object fetched at the test's place is the
    one called later.
    """

    def __init__(
        self,
        unit: Any,
        cells: List[Any],
        tests: Dict[int, str],
        course: List[Any],
        name: str,
    ) -> None:
        from autograder.calls import Link
        from autograder.sandbox.server import SHARED_INSIDE
        from autograder.verdict import answer_names, prelude

        self.unit = unit
        self.sources = {grade_id: cells[index].source for index, grade_id in tests.items()}
        self.space: Dict[str, Any] = prelude(course)
        self.answers = answer_names(course)
        self.broken = _broken_rules(unit, cells, course, name)
        self.runs: Dict[str, Any] = {}
        paths = {str(unit.shared): SHARED_INSIDE} if unit.use_sandbox else {}
        self.link = Link(self._send, paths)
        self.ask: Any = None
        self.until = 0.0

    @property
    def outputs(self) -> Dict[str, List[Dict[str, Any]]]:
        """Each test's outputs, by ``grade_id``; a test whose hidden part never ran fails."""
        for run in self.runs.values():
            run.not_run()
        return {grade_id: run.outputs for grade_id, run in self.runs.items()}

    def _send(self, request: Dict[str, Any]) -> str:
        seconds = self.unit.limits.cell_seconds
        return self.ask(json.dumps(request), self.until, seconds)

    def test(self, kind: str, grade_id: str, ask: Any) -> None:
        """Run a part of test ``grade_id`` (one the grader sent empty), asking through ``ask``.

        ``kind`` is ``"test"`` (its visible part), ``"hidden"`` (its hidden part) or
        ``"rerun"`` (all of it anew, in a new kernel after one died, if its hidden part was
        still to run).
        """
        from autograder.robots import robot_names
        from autograder.verdict import TestRun

        if grade_id not in self.sources:
            return
        run = self.runs.get(grade_id)
        if kind != "test" and (run is None or not run.waiting):
            return
        self.ask, self.until = ask, time.monotonic() + self.unit.limits.cell_seconds
        # A test that runs the student's nodes: the robot here, the nodes in the sandbox.
        robot = robot_names(self.unit, self.space, self.until)
        self.space.update(robot)
        saved = tempfile.tempdir
        tempfile.tempdir = str(self.unit.shared)
        before = self.link.calls
        try:
            if run is not None and kind == "hidden":
                run.cell.update(robot)
                run.run_hidden()
            else:
                run = TestRun(self.sources[grade_id], grade_id, self.space, self.answers)
                self.runs[grade_id] = run
                broken = [self.broken[name] for name in run.asked() if name in self.broken]
                if broken:  # the answer breaks the notebook's rules: the test fails, unasked
                    run.refuse(" ".join(broken))
                    return
                run.run_visible(self.link)
                if kind == "rerun":
                    run.run_hidden()
        finally:
            tempfile.tempdir = saved
        self.unit.timings["calls"] = self.unit.timings.get("calls", 0) + self.link.calls - before
        largest = max(self.unit.timings.get("largest_answer", 0), self.link.largest)
        self.unit.timings["largest_answer"] = largest


def _broken_rules(unit: Any, cells: List[Any], course: List[Any], name: str) -> Dict[str, str]:
    """The notebook's graded names whose answers break its rules (:mod:`autograder.rules`).

    The rules are read from the code, never by running it. If the reading fails (the grader's
    fault, not the student's), no rule is held against the notebook, and that is said.
    """
    from autograder.rules import broken_rules

    try:
        return broken_rules(cells, course, name)
    except Exception as error:
        unit.problems.append(
            f"{name}: the grader could not read the notebook's code to check its rules "
            f"({type(error).__name__}); no rule was held against it."
        )
        return {}


@dataclasses.dataclass
class _Unit:
    """One student's grading, inside the unit's process."""

    folder: Path
    task: Dict[str, Any]
    problems: List[str] = dataclasses.field(default_factory=list)
    #: Runs the tests drove that the driving score would drive again, by mission (the bags).
    runs: Dict[str, Path] = dataclasses.field(default_factory=dict)
    timings: Dict[str, float] = dataclasses.field(
        default_factory=lambda: dict.fromkeys(("notebooks", "cells", "nbgrader", "driving"), 0.0)
    )

    def __post_init__(self) -> None:
        from autograder.sandbox import Limits, unit_user
        from autograder.sandbox.limits import STUDENT_DISK_VARIABLE

        self.student: str = self.task["student"]
        self.names: List[str] = list(self.task["names"])
        self.course: List[str] = list(self.task["course"])
        # A user of its own: the process limit then counts this student's processes only.
        uid = int(self.task.get("uid") or unit_user())
        self.limits = dataclasses.replace(Limits(**self.task["limits"]), uid=uid)
        self.use_sandbox = bool(self.task["use_sandbox"])
        self.course_dir = Path(self.task["course_dir"])
        self.root = self.folder / "nbgrader"
        # The sandboxes write on a file system of the student's own where there is one.
        self.student_disk = Path(os.environ.get(STUDENT_DISK_VARIABLE) or self.folder)
        self.sandboxes = self.student_disk / "sandboxes"
        self.export = self.folder / "export"
        self.shared = self.folder / "shared"
        from autograder.sandbox.server import NotebookServer

        self.server = NotebookServer(self.sandboxes, self.limits, self.use_sandbox, self.shared)

    def hand_in(self, name: str, aside: List[str]) -> bool:
        """Repair one notebook and lay it out for nbgrader, the sandbox and the export."""
        import nbformat

        from autograder.tamper import repair

        said = self.problems if name in self.names else aside
        submitted = self.folder / "submission" / name
        handed_in = submitted / f"{name}.ipynb"
        if not handed_in.is_file():
            said.append(f"{name}: no {name}.ipynb in the submission")
            return False
        release = self.course_dir / "release" / name / f"{name}.ipynb"
        notebook, found = repair(handed_in, release)
        said.extend(found)
        target = self.root / "submitted" / self.student / name
        shutil.copytree(submitted, target)
        nbformat.write(notebook, target / f"{name}.ipynb")
        box = self.sandboxes / name
        shutil.copytree(submitted, box, ignore=shutil.ignore_patterns(*SKIPPED))
        nbformat.write(notebook, box / f"{name}.ipynb")
        for path in [self.sandboxes, box, *box.rglob("*")]:
            os.chown(path, self.limits.uid, self.limits.uid, follow_symlinks=False)
        (self.export / name).mkdir()
        nbformat.write(notebook, self.export / name / f"{name}.ipynb")
        return True

    def grade(self) -> Dict[str, Any]:
        from autograder.course import nbgrader_api, nbgrader_config

        began = time.monotonic()
        self.root.mkdir()
        self.sandboxes.mkdir()
        self.export.mkdir()
        self.shared.mkdir()
        self.shared.chmod(0o755)
        shutil.copy(self.course_dir / "gradebook.db", self.root / "gradebook.db")
        config = nbgrader_config(
            root=self.root,
            release=self.course_dir / "release",
            db=self.root / "gradebook.db",
            source=self.course_dir / "source",
        )
        config.CourseDirectory.submitted_directory = "submitted"
        config.CourseDirectory.autograded_directory = "autograded"
        config.Autograde.autograde_preprocessors = [
            _sandboxed_execute_class(self) if getattr(pp, "__name__", "") == "Execute" else pp
            for pp in _default_autograde_preprocessors()
        ]
        api = nbgrader_api(config)
        try:
            return self._grade(api, config, began)
        finally:
            self.server.stop()
            from autograder.sandbox import end_student_groups

            end_student_groups(self.limits.uid)

    def _disk_full(self) -> None:
        """Say it when the student's code filled the file system it writes on."""
        size = disk_full(self.student_disk) if self.student_disk != self.folder else None
        if size is not None:
            self.problems.append(
                f"The notebooks filled the {size} the grader gives a student's files: what they "
                "wrote after that failed (the cells that raised say where)."
            )

    def _grade(self, api: Any, config: Any, began: float) -> Dict[str, Any]:
        aside: List[str] = []
        handed_in = [name for name in self.course if self.hand_in(name, aside)]
        messages: Dict[Tuple[str, str], str] = {}
        from autograder.feedback import failure_messages

        for name in [name for name in handed_in if name in self.names]:
            before = time.monotonic() - self.timings["notebooks"]
            outcome = api.autograde(name, self.student, force=True, create=True)
            self.timings["nbgrader"] += time.monotonic() - self.timings["notebooks"] - before
            if not outcome["success"]:  # the grader's failure, not the student's: no grade
                raise GraderFailed(f"nbgrader could not grade {name} ({_why(outcome)})")
            graded = self.root / "autograded" / self.student / name / f"{name}.ipynb"
            if graded.is_file():
                (self.folder / "out" / "autograded").mkdir(exist_ok=True)
                shutil.copy(graded, self.folder / "out" / "autograded" / f"{name}.ipynb")
            for grade_id, message in failure_messages(graded).items():
                messages[(name, grade_id)] = message
        self.server.stop()
        self._disk_full()
        cells, to_grade = _scores(config, self.student, self.names)
        missions: Dict[str, Any] = {}
        if self.task.get("driving"):
            from autograder.driving import drive_missions, not_driven

            before = time.monotonic()
            if handed_in:
                missions = drive_missions(
                    self.export,
                    self.student_disk / "driving",
                    self.limits,
                    self.use_sandbox,
                    runs=self.runs,
                )
                for name, driving in missions.items():
                    # The grader's folders mean nothing to the student.
                    driving.reasons = [_without(reason, self.folder) for reason in driving.reasons]
                    if driving.timed_out:  # the instructor should know: the limit may be tight
                        self.problems.append(
                            f"Driving: the {name} mission did not end within "
                            f"{self.limits.mission_seconds} s of wall time."
                        )
            else:
                missions = not_driven("No notebook was handed in: there was nothing to drive.")
            self.timings["driving"] = time.monotonic() - before
        from autograder.results import StudentResult, to_data

        self.timings["unit"] = time.monotonic() - began
        # The most memory this process held, in MB (a student's answers cannot swell it).
        import resource

        self.timings["grader_memory_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

        return to_data(
            StudentResult(
                self.student, cells=cells, problems=self.problems, messages=messages,
                missions=missions, timings=self.timings, to_grade=to_grade,
            )
        )  # fmt: skip


def _without(text: str, folder: Path) -> str:
    """``text`` with the paths below ``folder`` (the unit's own) said as the student knows them."""
    text = text.replace(f"{folder}/export", "your notebooks' folder")
    return text.replace(str(folder), "the grader's folder")


def _default_autograde_preprocessors() -> list:
    from nbgrader.converters import Autograde

    return list(Autograde.class_traits()["autograde_preprocessors"].default())


def _why(outcome: Dict[str, object]) -> str:
    from autograder.course import log_tail

    lines = [line for line in log_tail(outcome).splitlines() if line.strip()]
    return lines[-1][:300] if lines else "no log"


def _scores(
    config: Any, student: str, names: List[str]
) -> Tuple[Dict[Tuple[str, str], Tuple[float, float]], List[Tuple[str, str]]]:
    """The student's scores from the unit's gradebook, and the cells that wait for a person.

    A test never graded scores 0; an answer in words has no automatic score: it waits for a
    person's grade (nbgrader's Formgrader) and scores 0 until then.
    """
    from nbgrader.api import Gradebook, MissingEntry

    cells: Dict[Tuple[str, str], Tuple[float, float]] = {}
    to_grade: List[Tuple[str, str]] = []
    with Gradebook(config.CourseDirectory.db_url) as gradebook:
        for name in names:
            for notebook in gradebook.find_assignment(name).notebooks:
                for cell in notebook.grade_cells:
                    cells[(name, cell.name)] = (0.0, float(cell.max_score))
            try:
                submission = gradebook.find_submission(name, student)
            except MissingEntry:
                continue
            for notebook in submission.notebooks:
                for grade in notebook.grades:
                    cells[(name, grade.name)] = (float(grade.score), float(grade.max_score))
                    if grade.auto_score is None:
                        to_grade.append((name, grade.name))
    return cells, to_grade


def main(argv: Optional[List[str]] = None) -> int:
    """``python -m autograder.unit FOLDER``: grade the student of ``FOLDER/task.json``."""
    import warnings

    warnings.filterwarnings("ignore")  # nbgrader's gradebook warns about its session
    folder = Path((argv or sys.argv[1:])[0])
    task = json.loads((folder / "task.json").read_text(encoding="utf-8"))
    try:
        data = _Unit(folder, task).grade()
    except Exception as error:  # any failure of the grader's on this student: said, not spread
        lines = traceback.format_exception_only(type(error), error)
        print(lines[-1].strip(), file=sys.stderr)
        return 1
    from autograder.results import write_atomic

    write_atomic(folder / "out" / "result.json", json.dumps(data))
    return 0


if __name__ == "__main__":
    sys.exit(main())
