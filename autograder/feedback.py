"""Per-student feedback: one self-contained HTML page a student learns from.

For each test of each notebook the page shows the points and, when it failed, the message the
test gave (the assertion's sentence, or the error's name and text); for each answer in words,
the points a person gave in Formgrader and their comment. Hidden tests' code is never shown:
only their messages, which the instructor wrote for students; nor are the answers' rubrics. The
driving part shows each mission's score, what went wrong, the states the robot went through
and its trajectory.
"""

from __future__ import annotations

import base64
import html
from pathlib import Path
from typing import TYPE_CHECKING, Dict, List, Optional, Set, Tuple

from autograder.driving import MAX_SCORE, POINTS, Driving

if TYPE_CHECKING:  # pragma: no cover - types only
    from autograder.results import StudentResult

__all__ = ["failure_messages", "write_feedback"]

Key = Tuple[str, str]

#: The longest message shown for one test, in characters.
MESSAGE_LIMIT = 600

_STYLE = """
body { font-family: system-ui, sans-serif; max-width: 60rem; margin: 2rem auto; padding: 0 1rem;
       color: #1d1d1f; line-height: 1.45; }
h1 { font-size: 1.6rem; } h2 { margin-top: 2rem; border-bottom: 1px solid #ddd; }
table { border-collapse: collapse; width: 100%; margin: 0.5rem 0 1rem; }
th, td { text-align: left; padding: 0.3rem 0.6rem; border-bottom: 1px solid #eee;
         vertical-align: top; }
.pass { color: #1a7f37; } .fail { color: #b3261e; }
pre { white-space: pre-wrap; margin: 0; font-size: 0.9rem; }
.comment { background: #eef4ff; padding: 0.3rem 0.5rem; border-radius: 4px; }
.note { background: #fff4e5; padding: 0.5rem 0.8rem; border-radius: 4px; }
img { max-width: 100%; border: 1px solid #ddd; }
"""


def failure_messages(notebook_path: Path) -> Dict[str, str]:
    """The message of each failed test cell of an autograded notebook, by ``grade_id``.

    Only the error's name and text are kept, never its traceback (which would quote the
    hidden tests' code).
    """
    import nbformat

    try:
        notebook = nbformat.read(notebook_path, as_version=4)
    except Exception:  # an unreadable notebook has no messages to show
        return {}
    messages: Dict[str, str] = {}
    for cell in notebook.cells:
        meta = cell.get("metadata", {}).get("nbgrader", {})
        if cell.cell_type != "code" or not meta.get("grade") or not meta.get("grade_id"):
            continue
        errors = [out for out in cell.get("outputs", []) if out.get("output_type") == "error"]
        if errors:
            error = errors[-1]
            name, value = str(error.get("ename", "Error")), str(error.get("evalue", ""))
            if name == "NotImplementedError":
                text = (
                    "A function this test calls is not written yet (it raises NotImplementedError)."
                )
            elif name in ("AssertionError", "NotRun", "RuleBroken") and value:
                text = value
            else:
                text = f"{name}: {value}" if value else name
            messages[meta["grade_id"]] = _shorten(text or name)
    return messages


def _shorten(text: str) -> str:
    return text if len(text) <= MESSAGE_LIMIT else text[: MESSAGE_LIMIT - 1] + "…"


def _e(value: object) -> str:
    """``value`` for the page: escaped, without a terminal's control sequences."""
    from duckielib.tools.handin import without_controls

    return html.escape(without_controls(str(value)))


def _tests_section(result: StudentResult, names: List[str], answers: Set[Key]) -> List[str]:
    parts: List[str] = []
    for name in names:
        cells = [(key[1], value) for key, value in result.cells.items() if key[0] == name]
        if not cells:
            continue
        score = sum(value[0] for _, value in cells)
        most = sum(value[1] for _, value in cells)
        parts.append(f"<h2>{_e(name)}: {score:g} / {most:g}</h2>")
        parts.append("<table><tr><th>Test or answer</th><th>Points</th><th>Result</th></tr>")
        for grade_id, (got, out_of) in cells:
            message = result.messages.get((name, grade_id))
            comment = result.comments.get((name, grade_id))
            if (name, grade_id) in result.to_grade:
                verdict = "your instructor grades this answer"
            elif (name, grade_id) in answers:
                verdict = _e(message) if message else "graded by your instructor"
                if comment:
                    verdict += f'<pre class="comment">{_e(comment)}</pre>'
            elif got >= out_of:
                verdict = '<span class="pass">passed</span>'
            else:
                shown = message or "Some checks did not pass."
                verdict = f'<span class="fail">failed</span><pre>{_e(shown)}</pre>'
            if comment and (name, grade_id) not in answers:
                verdict += f'<pre class="comment">Your instructor: {_e(comment)}</pre>'
            parts.append(
                f"<tr><td>{_e(grade_id)}</td><td>{got:g} / {out_of:g}</td><td>{verdict}</td></tr>"
            )
        parts.append("</table>")
        graded = {grade_id for grade_id, _ in cells}
        others = [
            (cell, text)
            for (assignment, cell), text in sorted(result.comments.items())
            if assignment == name and cell not in graded
        ]
        if others:
            items = "".join(
                f'<li><strong>{_e(cell)}</strong>: <pre class="comment">{_e(text)}</pre></li>'
                for cell, text in others
            )
            parts.append(f"<p>Your instructor's comments on your code:</p><ul>{items}</ul>")
    return parts


#: What each mission is, for the feedback's headings.
_MISSION_TITLES = {
    "square_then_circle": "square then circle",
    "d_shape": "the D",
    "straight": "the straight-line task (1.25 m forward, then back)",
    "rotation": "the rotation task (90° clockwise, then back)",
}


def _driving_sections(result: StudentResult) -> List[str]:
    parts: List[str] = []
    if result.missions:
        parts.append(
            f"<h2>Driving: {result.driving_score:g} / {MAX_SCORE:g}</h2><p>Your exported "
            "code drove each mission on the virtual Duckiebot; the driving score is the mean of "
            "the missions' scores.</p>"
        )
    for name, driving in result.missions.items():
        parts += _driving_section(name, driving)
    return parts


def _driving_section(mission: str, driving: Driving) -> List[str]:
    title = _MISSION_TITLES.get(mission, mission)
    parts = [f"<h3>Driving {_e(title)}: {driving.score:g} / {MAX_SCORE:g}</h3>"]
    labels = {
        "bag": "a readable bag with the mission's states",
        "states": "the states and LED colours in order, then 'done'",
        "stops": "every stop held for its time, standing still",
    }
    parts.append("<table><tr><th>Check</th><th>Points</th></tr>")
    for key, most in (driving.out_of or POINTS).items():
        got = driving.parts.get(key, 0.0)
        label = labels.get(key, f"what the robot really did in state {key}")
        parts.append(f"<tr><td>{_e(label)}</td><td>{got:g} / {most:g}</td></tr>")
    parts.append("</table>")
    motion = [state for state in (driving.summary or {}).get("motion", []) if state.get("checks")]
    if motion:
        parts.append(
            "<table><tr><th>State</th><th>Move</th><th>Measured</th><th>Asked for</th>"
            "<th>Result</th></tr>"
        )
        for state in motion:
            for check in state["checks"]:
                unit = check.get("unit", "")
                measured = check.get("measured")
                shown = "nothing" if measured is None else f"{measured:g} {unit}"
                verdict = "passed" if check.get("passed") else "failed"
                parts.append(
                    f"<tr><td>{_e(state.get('state'))}</td><td>{_e(check.get('what'))}</td>"
                    f"<td>{_e(shown)}</td><td>{_e(check.get('expected'))} {_e(unit)}</td>"
                    f'<td><span class="{"pass" if check.get("passed") else "fail"}">'
                    f"{verdict}</span></td></tr>"
                )
        parts.append("</table>")
    if driving.reasons:
        items = "".join(f"<li>{_e(reason)}</li>" for reason in driving.reasons)
        parts.append(f'<div class="note"><ul>{items}</ul></div>')
    summary = driving.summary or {}
    if summary.get("states"):
        parts.append(
            "<table><tr><th>State</th><th>LED colour</th><th>Start (s)</th><th>End (s)</th>"
            "<th>Moved (m)</th></tr>"
        )
        for state in summary["states"]:
            parts.append(
                "<tr>"
                + "".join(
                    f"<td>{_e(state.get(key))}</td>"
                    for key in ("name", "color", "start", "end", "moved")
                )
                + "</tr>"
            )
        parts.append("</table>")
        facts = [
            ("Total time (s)", summary.get("total_time")),
            ("Final pose by odometry [x, y, theta]", summary.get("final_pose_odometry")),
            ("Final pose, ground truth [x, y, theta]", summary.get("final_pose_truth")),
            ("Distance from the start at the end (m)", summary.get("distance_to_start")),
        ]
        parts.append("<table>")
        parts += [f"<tr><th>{_e(label)}</th><td>{_e(value)}</td></tr>" for label, value in facts]
        parts.append("</table>")
    if driving.figure is not None:
        data = base64.b64encode(driving.figure).decode("ascii")
        parts.append(f'<img alt="The robot\'s path" src="data:image/png;base64,{data}">')
    if driving.animation is not None:
        data = base64.b64encode(driving.animation).decode("ascii")
        parts.append("<p>The run played back: the robot, its LEDs and the state it announced.</p>")
        parts.append(f'<img alt="The run played back" src="data:image/gif;base64,{data}">')
    return parts


def write_feedback(
    path: Path, result: StudentResult, names: List[str], answers: Optional[Set[Key]] = None
) -> Path:
    """Write the feedback page of one student to ``path``.

    Args:
        path: the HTML file to write (its folder must exist).
        result: the student's grading.
        names: the assignments, in course order.
        answers: the answers in words, graded by a person: ``(assignment, grade_id)``. Their
            points and the person's comment are shown, never their rubric.
    """
    heading = f"Feedback for {result.shown}"
    parts = [
        "<!DOCTYPE html>",
        '<html lang="en"><head><meta charset="utf-8">',
        f"<title>{_e(heading)}</title><style>{_STYLE}</style></head><body>",
        f"<h1>{_e(heading)}</h1>",
    ]
    if not result.complete:
        # The grader's side stopped: no grade is given, and the next run grades again.
        items = "".join(f"<li>{_e(problem)}</li>" for problem in result.problems)
        parts.append(f'<div class="note"><p>Not graded yet:</p><ul>{items}</ul></div>')
        parts.append("</body></html>\n")
        return _written(path, parts)
    parts.append(f"<p>Tests: <strong>{result.total:g} / {result.max_total:g}</strong> points.")
    if result.missions:
        parts.append(f" Driving: <strong>{result.driving_score:g} / {MAX_SCORE:g}</strong>.")
    parts.append(
        "</p><p>Each failed test shows the message it gave. Some tests are hidden: you see "
        "their message, not their code. Run your notebook again, read the message, and "
        "compare what your function returns with what the message expected.</p>"
    )
    if result.problems:
        items = "".join(f"<li>{_e(problem)}</li>" for problem in result.problems)
        parts.append(f'<div class="note"><p>While grading:</p><ul>{items}</ul></div>')
    parts += _tests_section(result, names, answers or set())
    parts += _driving_sections(result)
    parts.append("</body></html>\n")
    return _written(path, parts)


def _written(path: Path, parts: List[str]) -> Path:
    partial = path.with_name(path.name + ".partial")
    partial.write_text("\n".join(parts), encoding="utf-8")
    partial.replace(path)
    return path
