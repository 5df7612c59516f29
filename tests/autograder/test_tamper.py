"""Tampered notebooks: repaired against the release, then graded by real nbgrader.

Every case starts from a student who filled 03_frames with the reference code (full marks),
damages the notebook one way, and checks the sentence :func:`repair` reports and, for the
cases marked graded, the scores real ``nbgrader autograde`` gives the repaired notebook.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Callable, Dict, List, NamedTuple, Optional

import nbformat
import pytest
from nbgrader.nbgraderformat import MetadataValidator

from autograder.bench import filled_notebook
from autograder.course import ROOT, autograde
from autograder.tamper import repair

NAME = "03_frames"
RELEASE = ROOT / "course" / NAME / f"{NAME}.ipynb"
FULL = {
    "test_wrap_angle": 2.0,
    "test_rotation_matrix": 2.0,
    "test_world_from_robot": 2.0,
    "test_world_from_start": 3.0,
}
NOT_READABLE = (
    f"{NAME}: not a readable notebook ({{}}); the release notebook was graded in its place, "
    "so it scores zero."
)


def filled() -> nbformat.NotebookNode:
    """The release with every answer cell holding the reference code, as a student types it."""
    return filled_notebook(NAME)


def at(notebook: nbformat.NotebookNode, grade_id: str) -> int:
    return next(
        index
        for index, cell in enumerate(notebook.cells)
        if cell.metadata.get("nbgrader", {}).get("grade_id") == grade_id
    )


def dumped(notebook: nbformat.NotebookNode) -> str:
    # json, not nbformat.writes: the damage must reach the file unrepaired.
    return json.dumps(notebook, indent=1)


def delete(grade_id: str) -> Callable[[nbformat.NotebookNode], str]:
    def edit(notebook):
        del notebook.cells[at(notebook, grade_id)]
        return dumped(notebook)

    return edit


def duplicate_test(notebook):
    twin = copy.deepcopy(notebook.cells[at(notebook, "test_wrap_angle")])
    twin.id, twin.source = "twin0001", "pass\n"
    notebook.cells.insert(at(notebook, "test_wrap_angle") + 1, twin)
    return dumped(notebook)


def duplicate_answer(notebook):
    twin = copy.deepcopy(notebook.cells[at(notebook, "wrap_angle")])
    twin.id = "twin0002"
    notebook.cells.insert(at(notebook, "wrap_angle") + 1, twin)
    return dumped(notebook)


def rename_grade_id(notebook):
    notebook.cells[at(notebook, "test_wrap_angle")].metadata.nbgrader.grade_id = "mine"
    return dumped(notebook)


def own_cell_with_grade_id(notebook):
    notebook.cells[1].metadata["nbgrader"] = {"grade": False, "grade_id": "mine", "locked": True}
    return dumped(notebook)


def change_cell_id(notebook):
    notebook.cells[at(notebook, "test_wrap_angle")].id = "changed1"
    return dumped(notebook)


def invalid_cell_id(notebook):
    notebook.cells[at(notebook, "test_wrap_angle")].id = "not valid!"
    notebook.cells[3].id = notebook.cells[1].id
    return dumped(notebook)


def edit_tests(notebook):
    """test_wrap_angle passes on a wrong answer, test_rotation_matrix on a right one."""
    notebook.cells[at(notebook, "wrap_angle")].source = "def wrap_angle(theta):\n    return theta\n"
    for grade_id in ("test_wrap_angle", "test_rotation_matrix"):
        notebook.cells[at(notebook, grade_id)].source = "pass\n"
    return dumped(notebook)


def remove_metadata(notebook):
    del notebook.cells[at(notebook, "test_wrap_angle")].metadata["nbgrader"]
    return dumped(notebook)


def change_points_and_id(notebook):
    notebook.cells[at(notebook, "test_wrap_angle")].metadata.nbgrader.points = 100
    notebook.cells[at(notebook, "test_rotation_matrix")].id = "changed2"
    return dumped(notebook)


def kernel(name: str, language: Optional[str] = None) -> Callable[[nbformat.NotebookNode], str]:
    def edit(notebook):
        notebook.metadata.kernelspec = {"name": name, "display_name": name, "language": "x"}
        if language is not None:
            notebook.metadata.language_info = {"name": language, "version": "1.9"}
        return dumped(notebook)

    return edit


def nbformat_3(notebook):
    return nbformat.writes(nbformat.convert(notebook, 3))


def move_test_above_answer(notebook):
    test = notebook.cells.pop(at(notebook, "test_wrap_angle"))
    notebook.cells.insert(at(notebook, "wrap_angle"), test)
    return dumped(notebook)


def sections_swapped(notebook):
    """Section 4 (cells 23 to 30) moved before section 1: the student's order, kept."""
    cells = notebook.cells
    notebook.cells = cells[:5] + cells[23:31] + cells[5:23] + cells[31:]
    return dumped(notebook)


class Case(NamedTuple):
    tamper: Callable[[nbformat.NotebookNode], str]
    problems: List[str]
    scores: Optional[Dict[str, float]]  # None: not graded by nbgrader (the sentence is enough)


def scores(**changed: float) -> Dict[str, float]:
    return {**FULL, **changed}


CASES = {
    "untouched": Case(dumped, [], None),
    "deleted_test": Case(
        delete("test_wrap_angle"),
        [f"{NAME}: the test cell test_wrap_angle was deleted; it was put back and graded."],
        FULL,  # put back, it runs on the student's right answer (plain nbgrader: 0)
    ),
    "deleted_answer": Case(
        delete("wrap_angle"),
        [
            f"{NAME}: the answer cell wrap_angle was deleted; the released cell was put back, "
            "so it scores as unanswered."
        ],
        scores(test_wrap_angle=0.0),
    ),
    "duplicated_test": Case(
        duplicate_test,
        [f"{NAME}: the test cell test_wrap_angle appeared 2 times; only the first was kept."],
        FULL,
    ),
    "duplicated_answer": Case(
        duplicate_answer,
        [
            f"{NAME}: the answer cell wrap_angle appeared 2 times; "
            "the others stay as ordinary cells."
        ],
        None,
    ),
    "renamed_grade_id": Case(
        rename_grade_id,
        [
            f"{NAME}: the test cell test_wrap_angle had its grade id changed to 'mine'; "
            "it was restored and graded."
        ],
        FULL,
    ),
    "unknown_grade_id": Case(
        own_cell_with_grade_id,
        [f"{NAME}: a cell had the unknown grade id 'mine'; it was graded as an ordinary cell."],
        None,
    ),
    "changed_cell_id": Case(change_cell_id, [], None),
    "invalid_cell_id": Case(
        invalid_cell_id,
        [f"{NAME}: 2 cell id(s) were not valid or not unique; new ones were given."],
        None,
    ),
    "edited_tests": Case(
        edit_tests,
        [
            f"{NAME}: the test cell test_wrap_angle was edited; the original was put back "
            "and graded.",
            f"{NAME}: the test cell test_rotation_matrix was edited; the original was put back "
            "and graded.",
        ],
        scores(test_wrap_angle=0.0),  # the original test ran on the wrong answer
    ),
    "removed_metadata": Case(
        remove_metadata,
        [
            f"{NAME}: the test cell test_wrap_angle had lost its nbgrader metadata; "
            "it was restored and graded."
        ],
        FULL,
    ),
    "changed_points_and_id": Case(
        change_points_and_id,
        [f"{NAME}: the test cell test_wrap_angle claimed 100 points; it was graded out of 2."],
        FULL,
    ),
    "kernel_python2": Case(
        kernel("python2"),
        [
            f"{NAME}: the notebook asked for the kernel 'python2'; it was graded with python3 as "
            "released."
        ],
        None,
    ),
    "kernel_ir": Case(
        kernel("ir"),
        [
            f"{NAME}: the notebook asked for the kernel 'ir'; it was graded with python3 "
            "as released."
        ],
        None,
    ),
    "extra_kernel": Case(
        kernel("my-own-env", "julia"),
        [
            f"{NAME}: the notebook asked for the kernel 'my-own-env' in 'julia'; it was graded "
            "with python3 as released."
        ],
        FULL,
    ),
    "not_json": Case(
        lambda notebook: dumped(notebook)[:5000],
        [NOT_READABLE.format("it is not JSON")],
        None,  # the release itself: the course's gates prove it scores zero
    ),
    "empty_file": Case(lambda notebook: "", [NOT_READABLE.format("the file is empty")], None),
    "json_not_a_notebook": Case(
        lambda notebook: '{"cells": []}',
        [NOT_READABLE.format("it is JSON but not a notebook of nbformat 3 or 4")],
        None,
    ),
    "nbformat_3": Case(
        nbformat_3,
        [f"{NAME}: the notebook was in nbformat 3; it was converted to 4 and graded."],
        None,
    ),
    "test_above_answer": Case(
        move_test_above_answer,
        [
            f"{NAME}: the test cell test_wrap_angle was moved above the cell it follows; "
            "it was put back after it."
        ],
        FULL,  # plain nbgrader: 0, the test runs before wrap_angle exists
    ),
    "sections_swapped": Case(sections_swapped, [], None),
}
GRADED = sorted(name for name, case in CASES.items() if case.scores is not None)


def repaired(case: str, folder: Path):
    path = folder / f"{case}.ipynb"
    path.write_text(CASES[case].tamper(filled()), encoding="utf-8")
    return repair(path, RELEASE)


@pytest.mark.parametrize("case", sorted(CASES))
def test_repair_reports_each_problem_in_one_sentence(case, tmp_path):
    notebook, problems = repaired(case, tmp_path)
    assert problems == CASES[case].problems
    nbformat.validate(notebook)
    MetadataValidator().validate_nb(notebook)
    release = nbformat.read(RELEASE, as_version=4)
    wanted = [
        cell.metadata.nbgrader["grade_id"] for cell in release.cells if "nbgrader" in cell.metadata
    ]
    got = [
        cell.metadata.nbgrader["grade_id"] for cell in notebook.cells if "nbgrader" in cell.metadata
    ]
    assert sorted(got) == sorted(wanted)
    if case != "sections_swapped":
        assert got == wanted
    assert notebook.metadata.kernelspec.name == "python3"
    if case in ("not_json", "empty_file", "json_not_a_notebook"):
        assert notebook == nbformat.read(RELEASE, as_version=4)


def test_repair_keeps_the_students_own_cell_order(tmp_path):
    notebook, _ = repaired("sections_swapped", tmp_path)
    got = [
        cell.metadata.nbgrader["grade_id"] for cell in notebook.cells if "nbgrader" in cell.metadata
    ]
    assert got[:2] == ["world_from_start", "test_world_from_start"]
    assert [cell.source for cell in notebook.cells] == [
        cell.source for cell in nbformat.reads(sections_swapped(filled()), as_version=4).cells
    ]


def test_a_duplicated_answer_keeps_its_copy_as_an_ordinary_cell(tmp_path):
    notebook, _ = repaired("duplicated_answer", tmp_path)
    index = at(notebook, "wrap_angle")
    assert "nbgrader" not in notebook.cells[index + 1].metadata
    assert notebook.cells[index + 1].source == notebook.cells[index].source


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    """Every graded case, repaired, autograded by real nbgrader in one work folder."""
    root = tmp_path_factory.mktemp("tamper")
    students = {}
    for case in GRADED:
        folder = root / "students" / case / NAME
        folder.mkdir(parents=True)
        notebook, _ = repaired(case, root)
        nbformat.write(notebook, folder / f"{NAME}.ipynb")
        students[case] = folder.parent
    return autograde(students, root / "work", names=[NAME])


@pytest.mark.slow
@pytest.mark.parametrize("case", GRADED)
def test_a_repaired_notebook_gets_the_scores_it_deserves(graded, case):
    cells = graded[case].cells
    assert {grade_id: score for (_, grade_id), (score, _) in cells.items()} == CASES[case].scores
    assert {grade_id: most for (_, grade_id), (_, most) in cells.items()} == FULL


def test_a_binary_file_is_graded_as_the_release(tmp_path):
    path = tmp_path / f"{NAME}.ipynb"
    path.write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe")
    notebook, problems = repair(path, RELEASE)
    assert problems == [NOT_READABLE.format("it is not UTF-8 text")]
    assert notebook == nbformat.read(RELEASE, as_version=4)


def test_an_answer_in_words_deleted_or_turned_into_code_is_put_back_as_an_answer(tmp_path):
    # Notebook 10 has two answers in words: one deleted, one turned into a code cell.
    release = ROOT / "course" / "10_bag_analysis" / "10_bag_analysis.ipynb"
    notebook = nbformat.read(release, as_version=4)
    ids = [cell.metadata.get("nbgrader", {}).get("grade_id") for cell in notebook.cells]
    del notebook.cells[ids.index("answer_bag_final")]
    index = ids.index("answer_theta_wrap") - 1
    typed = "The heading wraps when the robot faces east."
    notebook.cells[index] = nbformat.v4.new_code_cell(
        typed, metadata=notebook.cells[index].metadata, id=notebook.cells[index].id
    )
    nbformat.write(notebook, tmp_path / "10_bag_analysis.ipynb")
    fixed, problems = repair(tmp_path / "10_bag_analysis.ipynb", release)
    assert problems == [
        "10_bag_analysis: the answer cell answer_bag_final was deleted; the released cell was "
        "put back, so it scores as unanswered."
    ]
    answers = {
        cell.metadata.nbgrader["grade_id"]: cell
        for cell in fixed.cells
        if cell.metadata.get("nbgrader", {}).get("grade_id", "").startswith("answer_")
    }
    assert answers["answer_bag_final"].source == "YOUR ANSWER HERE"
    assert (answers["answer_theta_wrap"].cell_type, answers["answer_theta_wrap"].source) == (
        "markdown",
        typed,
    )
