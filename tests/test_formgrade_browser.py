"""An instructor grades an answer in words in Formgrader, in Chromium, as a person does.

The class of :mod:`formgrading` is graded; ``duckie formgrade`` opens nbgrader's Formgrader on it
and the test clicks its way to ada's submission: Manual Grading, the assignment, the notebook,
Show All Names, ada. There it reads the answer and its rubric, types the points and a comment
into the page's own inputs and leaves each with Tab, which is when Formgrader saves. Then
``duckie feedback`` folds them into ``grades.csv`` and ada's feedback page.
"""

from __future__ import annotations

import time

import pytest
from formgrading import ANSWER, ASSIGNMENT, RUBRIC, WRITTEN, check_folded, formgrader, small_class
from playwright.sync_api import expect

pytestmark = [pytest.mark.slow, pytest.mark.notebook]

POINTS = "1.5"
COMMENT = "Good: say which way theta turns the frame, and why the rotation comes first."


def _given(server, submission_id):
    """The points and the comment the gradebook holds for the answer: ``(score, comment)``."""
    (grade,) = [
        item
        for item in server.ask("GET", f"api/grades?submission_id={submission_id}")
        if item["name"] == ANSWER
    ]
    (comment,) = [
        item
        for item in server.ask("GET", f"api/comments?submission_id={submission_id}")
        if item["name"] == ANSWER
    ]
    return grade["manual_score"], comment["manual_comment"]


def test_an_instructor_grades_an_answer_in_formgrader_and_feedback_shows_it(
    sandbox, browser, tmp_path
):
    out = tmp_path / "out"
    (graded,) = small_class(tmp_path).grade(out)
    assert graded.to_grade == [(ASSIGNMENT, ANSWER)]

    with formgrader(out) as server:
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.set_default_timeout(30_000)
        page.goto(server.url())  # Formgrader's start page: Manage Assignments
        page.get_by_role("link", name="Manual Grading").click()
        page.locator("#main-table").get_by_role("link", name=ASSIGNMENT).click()  # assignment
        page.locator("#main-table").get_by_role("link", name=ASSIGNMENT).click()  # notebook
        page.get_by_role("link", name="Submission #1").wait_for()  # the table is filled in
        page.get_by_text("Show All Names").click()
        page.get_by_role("link", name="ada", exact=True).click()
        page.wait_for_url("**/formgrader/submissions/**")
        submission_id = page.url.rstrip("/").rsplit("/", 1)[-1]

        # The student's answer, and right after it the rubric, for the grader's eyes only.
        answer = page.locator(f".cell:has(input#{ANSWER})")
        expect(answer.locator(".panel-body")).to_have_text(WRITTEN)
        rubric = page.locator(f".cell:has(input#{ANSWER}) + .cell")
        expect(rubric).to_contain_text("For the grader, not in the student's notebook")
        expect(rubric).to_contain_text(RUBRIC.replace("**", ""))
        assert _given(server, submission_id) == (None, None)

        page.locator(f"input#{ANSWER}.score").fill(POINTS)
        page.keyboard.press("Tab")
        page.locator(f"textarea#{ANSWER}-comment").fill(COMMENT)
        page.keyboard.press("Tab")
        deadline = time.monotonic() + 30
        while _given(server, submission_id) != (float(POINTS), COMMENT):
            assert time.monotonic() < deadline, "Formgrader did not save within 30 s"
            time.sleep(0.2)
        answer.scroll_into_view_if_needed()
        page.screenshot(path=tmp_path / "formgrader.png")

        # What a person sees when they come back: the page holds what they gave.
        page.reload()
        expect(page.locator(f"input#{ANSWER}.score")).to_have_value(POINTS)
        expect(page.locator(f"textarea#{ANSWER}-comment")).to_have_value(COMMENT)
        page.close()

    check_folded(out, POINTS, COMMENT)
