"""Gates with real nbgrader: the solutions score full marks, the release scores zero, mistakes lose.

Three students are autograded on every assignment, as an instructor would grade them:
``filled`` is the released course with every graded cell filled with the reference code,
``untouched`` is the released course as students receive it, and ``mistaken`` has the first
deliberately wrong solution of every graded cell (see ``wrong_*.py``).
"""

from __future__ import annotations

import pytest
from coursetools import (
    NAMES,
    answer_keys,
    load,
    notebook_path,
    reference_answers,
    student_copy,
    wrong_solutions,
)

from autograder.course import autograde
from duckielib.solution import CONTRACT, load_solution

pytestmark = [pytest.mark.slow, pytest.mark.notebook, pytest.mark.timeout(1200)]


@pytest.fixture(scope="module")
def graded(tmp_path_factory):
    root = tmp_path_factory.mktemp("grading")
    filled = reference_answers()
    first_mistakes = {}
    for (name, grade_id, _), text in wrong_solutions().items():
        first_mistakes.setdefault((name, grade_id), text)
    students = {
        "filled": student_copy(root / "filled", filled),
        "untouched": student_copy(root / "untouched", {}),
        "mistaken": student_copy(root / "mistaken", first_mistakes),
    }
    scores = autograde(students, root / "nbgrader")
    return root, scores, first_mistakes


def test_the_reference_code_scores_full_marks_in_every_cell(graded):
    _, scores, _ = graded
    cells = scores["filled"].cells
    assert cells, "no graded cell was found"
    answers = answer_keys()
    short = {
        key: value for key, value in cells.items() if value[0] != value[1] and key not in answers
    }
    assert not short, f"cells below full marks: {short}"
    # Answers in words wait for a person: left as released, nbgrader scores them 0 by itself.
    assert {key: cells[key] for key in answers} == {
        key: (0.0, cells[key][1]) for key in answers
    }
    assert {name for name, _ in cells} == set(NAMES)


def test_each_notebook_runs_in_under_a_minute_and_all_in_three(graded):
    _, scores, _ = graded
    seconds = scores["filled"].seconds
    print({name: round(value, 1) for name, value in seconds.items()})
    slow = {name: value for name, value in seconds.items() if value >= 60}
    assert not slow, f"notebooks over 60 s: {slow}"
    assert sum(seconds.values()) < 180


def test_the_untouched_release_scores_zero_and_runs_to_the_end(graded):
    root, scores, _ = graded
    cells = scores["untouched"].cells
    assert {key: value[0] for key, value in cells.items() if value[0] != 0} == {}
    assert sum(value[1] for value in cells.values()) > 0
    for name in NAMES:
        notebook = load(notebook_path(root / "nbgrader" / "autograded" / "untouched", name))
        code = [cell for cell in notebook["cells"] if cell["cell_type"] == "code"]
        not_run = [index for index, cell in enumerate(code) if cell["execution_count"] is None]
        assert not not_run, f"{name}: code cells {not_run} never ran (did the kernel die?)"


def test_each_wrong_solution_loses_marks_in_its_own_test_cell(graded):
    _, scores, mistakes = graded
    cells = scores["mistaken"].cells
    assert mistakes
    kept = {
        key: cells[(key[0], f"test_{key[1]}")]
        for key in mistakes
        if cells[(key[0], f"test_{key[1]}")][0] >= cells[(key[0], f"test_{key[1]}")][1]
    }
    assert not kept, f"wrong solutions that kept full marks: {kept}"


def test_a_filled_course_exports_as_a_complete_solution(graded):
    root, _, _ = graded
    solution = load_solution(root / "filled", required=list(CONTRACT))
    assert solution.delta_phi(10, 0, 135)[1] == 10
