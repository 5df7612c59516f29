"""An instructor grades an answer in words in Formgrader, in Chromium, as a person does.

The class of :mod:`formgrading` is graded; ``duckie formgrade`` opens nbgrader's Formgrader on it
and the test clicks its way to ada's submission: Manual Grading, the assignment, the notebook,
Show All Names, ada. There it reads the answer and its rubric, types the points and a comment
into the page's own inputs and leaves each with Tab, which is when Formgrader saves. Then
``duckie feedback`` folds them into ``grades.csv`` and ada's feedback page. ada's notebook also
holds a script in every other place a student controls that Formgrader shows (a markdown cell,
outputs, their metadata): opening her submission runs none of them and loads nothing from
elsewhere.
"""

from __future__ import annotations

import time

import nbformat
import pytest
from formgrading import (
    ANSWER,
    ASSIGNMENT,
    RUBRIC,
    WRITTEN,
    check_folded,
    formgrader,
    small_class,
)
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


@pytest.fixture(scope="module")
def opened(sandbox, tmp_path_factory):
    """ada's class graded, with a script in every place a student controls besides the answer
    (:func:`_hostile`), and Formgrader opened on it: ``(ada's result, out, server)``."""
    root = tmp_path_factory.mktemp("formgrade")
    course = small_class(root)
    _hostile(course)
    out = root / "out"
    (graded,) = course.grade(out)
    with formgrader(out) as server:
        yield graded, out, server


def test_an_instructor_grades_an_answer_in_formgrader_and_feedback_shows_it(
    opened, browser, tmp_path
):
    graded, out, server = opened
    assert graded.to_grade == [(ASSIGNMENT, ANSWER)]
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


#: A PNG of one pixel.
_PIXEL = (
    "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8BQDwAEhQ"
    "GAhKmMIQAAAABJRU5ErkJggg=="
)
#: What each attack does if it runs: a flag on the window and a file written through the
#: Jupyter server's contents API, with the instructor's rights.
_RUN = "window.{flag}=1;fetch('/api/contents/{flag}.txt',{{method:'PUT'}})"


def _hostile(course):
    """ada's notebook with a script in every place she controls that Formgrader shows."""
    text = (
        f'See <img src=x onerror="{_RUN.format(flag="ANSWER_RAN")}"> and '
        f"[a link](javascript:{_RUN.format(flag='LINK_RAN')}) and [another][1]\n\n"
        f"[1]: jav&#x61;script:{_RUN.format(flag='REFERENCE_RAN')}\n"
    )
    course.student.cells.insert(-1, nbformat.v4.new_markdown_cell(text))
    shown = f"""\
from IPython.display import HTML, Javascript, display, publish_display_data

publish_display_data(
    data={{"image/png": "{_PIXEL}", "text/plain": "a picture"}},
    metadata={{
        "image/png": {{"width": "1 onerror={_RUN.format(flag="WIDTH_RAN")}", "height": 1}},
        "filenames": {{"image/png": "http://outside.invalid/picture.png"}},
    }},
)
display(HTML('<script>{_RUN.format(flag="OUTPUT_RAN")}</script>'
             '<img src="http://outside.invalid/html.png"><b>bold</b>'))
display(Javascript("{_RUN.format(flag="SCRIPT_RAN")}"))
svg = '<svg xmlns="http://www.w3.org/2000/svg" onload="{_RUN.format(flag="SVG_RAN")}"/>'
display({{"image/svg+xml": svg}}, raw=True)
"""
    course.student.cells.insert(-1, nbformat.v4.new_code_cell(shown))
    nbformat.write(course.student, course.handed_in)


def test_opening_a_hostile_submission_in_formgrader_runs_no_script_and_loads_nothing_else(
    opened, browser
):
    _, out, server = opened
    flags = ["ANSWER_RAN", "LINK_RAN", "REFERENCE_RAN", "WIDTH_RAN", "OUTPUT_RAN", "SCRIPT_RAN",
             "SVG_RAN"]  # fmt: skip
    page = browser.new_page(viewport={"width": 1400, "height": 900})
    page.set_default_timeout(30_000)
    requests, blocked = [], []
    page.on("request", lambda request: requests.append(request.url))
    page.on(
        "console",
        lambda message: (
            blocked.append(message.text) if "Content Security Policy" in message.text else None
        ),
    )
    page.goto(server.url())
    page.get_by_role("link", name="Manual Grading").click()
    page.locator("#main-table").get_by_role("link", name=ASSIGNMENT).click()
    page.locator("#main-table").get_by_role("link", name=ASSIGNMENT).click()
    page.get_by_role("link", name="Submission #1").wait_for()
    page.get_by_text("Show All Names").click()  # Formgrader's own onclick still works
    page.get_by_role("link", name="ada", exact=True).click()
    page.wait_for_url("**/formgrader/submissions/**")
    page.locator(f"input#{ANSWER}.score").wait_for()
    frame = page.main_frame
    # The student's links, clicked as an instructor might.
    for name in ("a link", "another"):
        links = page.get_by_role("link", name=name, exact=True)
        if links.count():
            links.first.click()
    page.wait_for_timeout(500)
    ran = {flag: frame.evaluate(f"window.{flag} === 1") for flag in flags}
    assert not any(ran.values()), ran
    # The policy is in force on this page: an inline handler put into it now does not run.
    frame.evaluate(
        """() => { const box = document.createElement("div");
        box.innerHTML = '<img src="data:," onerror="window.PROBE_RAN = 1">';
        document.body.appendChild(box); }"""
    )
    page.wait_for_timeout(500)
    assert frame.evaluate("window.PROBE_RAN === 1") is False
    local = f"http://127.0.0.1:{server.port}/"
    assert [url for url in requests if not url.startswith((local, "data:"))] == []
    page.close()
    written = [flag for flag in flags if (out / "work" / f"{flag}.txt").exists()]
    assert written == []
    # Formgrader's own scripts ran (the page showed the score box and the student's name), and
    # what the policy blocked is the probe alone: every handler of Formgrader's own is allowed.
    assert len(blocked) == 1, blocked
    assert "inline event handler" in blocked[0]
