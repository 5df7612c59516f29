"""Answers graded by a person: they wait in the gradebook, and a grade given there is never lost.

A course source with one answer cell in words (an nbgrader manually graded cell) next to the
autograded tests of 03_frames. ``duckie grade`` leaves the answer to a person: it counts for
nothing until graded, its column stays empty and ``to_grade`` counts it. A grade given in
nbgrader's Formgrader, opened on the graded class by ``duckie formgrade``, shows at the next
run, and stays when the student's files change and they are graded again.
"""

from __future__ import annotations

import nbformat
import pytest
from formgrading import (
    ANSWER,
    ASSIGNMENT,
    WRITTEN,
    answer_cell,
    check_folded,
    duckie,
    formgrader,
    rows,
    small_class,
)

pytestmark = pytest.mark.slow


def test_an_answer_in_words_waits_for_a_person_and_keeps_their_grade(sandbox, tmp_path):
    course = small_class(tmp_path)
    out = tmp_path / "out"

    (first,) = course.grade(out)
    assert first.to_grade == [(ASSIGNMENT, ANSWER)]
    assert first.total == 9
    assert first.max_total == 11
    row = rows(out)["ada"]
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
    with formgrader(out) as server:
        (submitted,) = server.ask("GET", f"api/submitted_notebooks/{ASSIGNMENT}/{ASSIGNMENT}")
        listed = {item["name"]: item for item in server.ask("GET", "api/assignments")}
        assert listed[ASSIGNMENT]["num_submissions"] == 1  # as its Manage Assignments page says
        assert (submitted["student"], submitted["needs_manual_grade"]) == ("ada", True)
        page = server.ask("GET", f"submissions/{submitted['id']}/?index=0", as_json=False)
        assert WRITTEN in page
        assert "A full answer names the rotation by theta." in page  # the rubric, beside it
        grades = server.ask("GET", f"api/grades?submission_id={submitted['id']}")
        (answer,) = [grade for grade in grades if grade["name"] == ANSWER]
        given = server.ask("PUT", f"api/grade/{answer['id']}", {"manual_score": 1.5})
        assert given["manual_score"] == 1.5
        comments = server.ask("GET", f"api/comments?submission_id={submitted['id']}")
        (comment,) = [item for item in comments if item["name"] == ANSWER]
        said = "Good: name which way theta turns the frame."
        server.ask("PUT", f"api/comment/{comment['id']}", {"manual_comment": said})

    # `duckie feedback` folds the grade and the comment in at once, running nothing.
    assert "graded by your instructor" in check_folded(out, "1.5", said)

    (again,) = course.grade(out)
    assert again.to_grade == []
    assert again.comments == {(ASSIGNMENT, ANSWER): said}
    row = rows(out)["ada"]
    assert (row["to_grade"], row[f"{ASSIGNMENT}:{ANSWER}"], row["total"]) == ("0", "1.5", "10.5")

    # The student hands in again: graded anew, and the person's grade stays.
    course.student.cells.insert(2, nbformat.v4.new_code_cell("print('one more try')"))
    nbformat.write(course.student, course.handed_in)
    (regraded,) = course.grade(out)
    assert regraded.total == 10.5
    with Gradebook(database) as gradebook:
        grade = gradebook.find_grade(ANSWER, ASSIGNMENT, ASSIGNMENT, "ada")
        assert grade.manual_score == 1.5
        assert grade.needs_manual_grade  # nbgrader's rule: a person's grade is to be reviewed
    assert rows(out)["ada"][f"{ASSIGNMENT}:{ANSWER}"] == "1.5"

    # The grades go out to the LMS, the person's grade in the assignment's points.
    roster = tmp_path / "participants.csv"
    roster.write_text("Username,Email address\nalovelace,ada@uni.example\n", encoding="utf-8")
    target = tmp_path / "moodle.csv"
    exported = duckie(
        "feedback", str(out), "--export", "moodle", str(target), "--roster", str(roster)
    )
    assert exported.returncode == 0, exported.stderr
    assert f"wrote {target}: 1 students' grades for Moodle" in exported.stdout
    header, ada = target.read_text().splitlines()
    columns = dict(zip(header.split(","), ada.split(",")))
    assert columns["Email address"] == "ada@uni.example"
    assert columns[ASSIGNMENT] == "10.5"


@pytest.mark.parametrize(
    ("command", "said"),
    [
        ("feedback", "holds no graded class: grade it first with"),
        ("formgrade", "has no gradebook: grade the class first with"),
    ],
)
def test_the_instructors_commands_refuse_a_folder_that_was_never_graded(tmp_path, command, said):
    result = duckie(command, str(tmp_path / "grading"))
    assert result.returncode == 1
    assert result.stderr == (
        f"duckie: {tmp_path / 'grading'} {said} "
        f"`duckie grade SUBMISSIONS --out {tmp_path / 'grading'}`.\n"
    )


def test_html_a_student_writes_never_runs_in_formgrader(sandbox, tmp_path):
    # Formgrader shows students' notebooks inside the instructor's JupyterLab: a tag in an answer
    # or a script in an output would run there, with the instructor's rights.
    course = small_class(tmp_path)
    course.student.cells[-1] = answer_cell('See <img src=x onerror="window.ANSWER_RAN=1">')
    shown = "display(HTML('<script>window.OUTPUT_RAN=1</script><b>bold</b>'))"
    course.student.cells.insert(
        -1,
        nbformat.v4.new_code_cell(
            f"from IPython.display import HTML, Javascript, display\n\n{shown}\n"
            "display(Javascript('window.SCRIPT_RAN=1'))\n"
        ),
    )
    nbformat.write(course.student, course.handed_in)
    out = tmp_path / "out"
    course.grade(out)
    with formgrader(out) as server:
        (submitted,) = server.ask("GET", f"api/submitted_notebooks/{ASSIGNMENT}/{ASSIGNMENT}")
        page = server.ask("GET", f"submissions/{submitted['id']}/?index=0", as_json=False)
    assert 'See &lt;img src=x onerror="window.ANSWER_RAN=1"&gt;' in page  # shown as text
    assert "<img src=x" not in page
    assert "<script>window.OUTPUT_RAN" not in page
    assert "<b>bold</b>" in page  # harmless HTML still shows
    assert "application/javascript" not in page
    assert "SCRIPT_RAN=1</script>" not in page
