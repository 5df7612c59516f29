"""Gates with the class grader: the solutions score full marks, the release zero, mistakes lose.

One class is graded once per run, as an instructor grades it with ``duckie grade`` (real
nbgrader, each notebook in the sandbox, the driving score), and every test here reads its
results (``graded_course``, tests/shared_runs.py, which other modules read too):
``reference`` is the released course with every graded cell filled with the reference code,
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
)

from autograder.driving import MISSIONS
from duckielib.solution import CONTRACT, load_solution

pytestmark = [pytest.mark.slow, pytest.mark.notebook, pytest.mark.timeout(1200)]


@pytest.fixture(scope="module")
def graded(graded_course):
    return graded_course


def test_the_reference_code_scores_full_marks_in_every_cell(graded):
    _, results, _ = graded
    cells = results["reference"].cells
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


def test_a_finished_course_graded_in_the_sandbox_scores_everything_with_no_problem(graded):
    # Every notebook as the grader runs it: in the sandbox, whole, with the driving score. A
    # cell that needs a file the sandbox does not show (notebook 11 reads the robot project
    # and pyproject.toml) would be a problem here, though nbgrader scored its tests.
    root, results, _ = graded
    result = results["reference"]
    assert result.problems == []
    # Full marks in everything the grader scores. The answers in words were left as released
    # (the filled course writes code only): nbgrader scores an unanswered answer 0 by itself.
    answers = {key: value for key, value in result.cells.items() if key[1].startswith("answer_")}
    assert len(answers) == 8
    assert {value[0] for value in answers.values()} == {0.0}
    assert result.to_grade == []
    unanswered = "No answer was written here, so it scores 0."
    assert {result.messages.get(key) for key in answers} == {unanswered}
    page = (root / "out" / "feedback" / "reference.html").read_text()
    assert f"<td>answer_speed</td><td>0 / 2</td><td>{unanswered}</td>" in page
    assert result.total == result.max_total - sum(most for _, most in answers.values()) > 60
    assert result.driving_score == 100
    assert {name: driving.score for name, driving in result.missions.items()} == dict.fromkeys(
        MISSIONS, 100
    ), {name: driving.reasons for name, driving in result.missions.items()}
    # The main mission is played back on the page; the others show their figure only.
    assert page.count('src="data:image/gif;base64,') == 1
    assert page.count('src="data:image/png;base64,') == len(MISSIONS)


def test_each_notebooks_grading_is_timed_and_adds_up_to_the_whole(graded):
    # How long each takes is a figure (duckie bench notebooks, duckie bench grade), not a gate.
    _, results, _ = graded
    timings = results["reference"].timings
    seconds = {name: timings[f"notebook:{name}"] for name in NAMES}
    print({name: round(value, 1) for name, value in seconds.items()})
    assert min(seconds.values()) > 0
    assert sum(seconds.values()) == pytest.approx(timings["notebooks"], abs=0.01)


def test_the_courses_answers_are_far_below_what_the_grader_reads_of_one(graded):
    # The grader refuses an answer over ANSWER_LIMIT (that test fails): the course's own must
    # stay well inside it. Its longest is a camera image, 640x480x3 bytes in base64.
    from autograder.sandbox.inside.wire import ANSWER_LIMIT

    _, results, _ = graded
    timings = results["reference"].timings
    assert 1_200_000 < timings["largest_answer"] < 1_300_000
    assert timings["largest_answer"] * 3 < ANSWER_LIMIT
    # The grader's process for one student stays small.
    assert timings["grader_memory_mb"] < 1024


def test_the_untouched_release_scores_zero_and_runs_to_the_end(graded):
    root, results, _ = graded
    cells = results["untouched"].cells
    assert {key: value[0] for key, value in cells.items() if value[0] != 0} == {}
    assert sum(value[1] for value in cells.values()) > 0
    for name in NAMES:
        notebook = load(notebook_path(root / "out" / "work" / "autograded" / "untouched", name))
        code = [cell for cell in notebook["cells"] if cell["cell_type"] == "code"]
        not_run = [index for index, cell in enumerate(code) if cell["execution_count"] is None]
        assert not not_run, f"{name}: code cells {not_run} never ran (did the kernel die?)"
    assert results["untouched"].driving_score == 0


def test_each_wrong_solution_loses_marks_in_its_own_test_cell(graded):
    _, results, mistakes = graded
    cells = results["mistaken"].cells
    assert mistakes
    kept = {
        key: cells[(key[0], f"test_{key[1]}")]
        for key in mistakes
        if cells[(key[0], f"test_{key[1]}")][0] >= cells[(key[0], f"test_{key[1]}")][1]
    }
    assert not kept, f"wrong solutions that kept full marks: {kept}"


def test_a_filled_course_exports_as_a_complete_solution(graded):
    root, _, _ = graded
    solution = load_solution(root / "submissions" / "reference", required=list(CONTRACT))
    assert solution.delta_phi(10, 0, 135)[1] == 10
