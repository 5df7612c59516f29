"""nbgrader's Formgrader on a class that ``duckie grade`` graded: where a person grades answers.

``duckie grade --out grading/`` leaves nbgrader's course tree in ``grading/work/``: the gradebook
(scores, and the answers in words that wait for a person), the release and the autograded
notebooks. Each answer in words is shown there with its rubric right under it
(:func:`for_formgrader`: the rubric is the source's solution region of the answer cell, put back
by ``duckie grade`` into the notebooks Formgrader shows, never into the students' feedback).
:func:`prepare` writes the ``nbgrader_config.py`` that tells Formgrader where each
of them is (the hidden tests' source stays where it is, in ``solutions/``), and
:func:`command` the JupyterLab command line that opens it, with nbgrader's instructor tools and
without the students' configuration. Grades given there go into the gradebook; the next
``duckie grade``, or ``duckie feedback`` at once, reads them, with the comments given there,
into ``grades.csv`` and the feedback pages.
"""

from __future__ import annotations

import json
import os
import re
import sys
from pathlib import Path
from typing import Dict, Iterable, List, Mapping, Sequence, Tuple

from autograder.course import ROOT, CourseError

__all__ = ["RUBRIC_TAG", "command", "for_formgrader", "prepare", "rubrics"]

#: The tag of the cell that holds an answer's rubric in the notebooks Formgrader shows.
RUBRIC_TAG = "rubric"
_REGION = re.compile(r"### BEGIN SOLUTION\n(.*?)### END SOLUTION", re.S)

_CONFIG = """\
# Written by `duckie formgrade`: nbgrader's Formgrader on the class graded here.
c = get_config()  # noqa: F821 - given by nbgrader when it reads this file
c.CourseDirectory.root = {root!r}
c.CourseDirectory.source_directory = {source!r}
c.CourseDirectory.release_directory = "release"
c.CourseDirectory.submitted_directory = "submitted"
c.CourseDirectory.autograded_directory = "autograded"
c.CourseDirectory.db_url = {db!r}
# What students wrote is shown as text: no script in an answer or an output runs in this page.
c.HTMLExporter.sanitize_html = True
"""


def prepare(out: Path, source: Path = ROOT / "solutions") -> Path:
    """Write ``out/work/nbgrader_config.py`` for Formgrader; the folder it runs in.

    Raises:
        CourseError: if ``out`` holds no gradebook (``duckie grade`` has not graded there).
    """
    work = Path(out).resolve() / "work"
    database = work / "gradebook.db"
    if not database.is_file():
        raise CourseError(
            f"{out} has no gradebook: grade the class first with "
            f"`duckie grade SUBMISSIONS --out {out}`."
        )
    (work / "submitted").mkdir(exist_ok=True)
    text = _CONFIG.format(
        root=str(work), source=str(Path(source).resolve()), db=f"sqlite:///{database}"
    )
    (work / "nbgrader_config.py").write_text(text, encoding="utf-8")
    return work


def command(work: Path, extra: Sequence[str] = ()) -> List[str]:
    """The JupyterLab command line that opens Formgrader on ``work`` (run it in ``work``)."""
    argv = [
        str(Path(sys.executable).parent / "jupyter"),
        "lab",
        f"--ServerApp.root_dir={work}",
        "--LabApp.default_url=/formgrader",
    ]
    if os.getuid() == 0:
        argv.append("--allow-root")
    return argv + list(extra)


def _source_text(cell: Mapping) -> str:
    text = cell.get("source", "")
    return "".join(text) if isinstance(text, list) else str(text)


def rubrics(source: Path, names: Iterable[str]) -> Dict[Tuple[str, str], str]:
    """The rubric of each answer in words of ``names``: ``(assignment, grade_id) -> text``.

    An answer in words is a markdown cell that nbgrader grades by hand (``grade`` and
    ``solution``); its rubric is the text of its solution region in the course source.
    """
    found: Dict[Tuple[str, str], str] = {}
    for name in names:
        path = Path(source) / name / f"{name}.ipynb"
        try:
            notebook = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        for cell in notebook.get("cells", []):
            marks = cell.get("metadata", {}).get("nbgrader", {})
            if cell.get("cell_type") != "markdown" or not (
                marks.get("grade") and marks.get("solution")
            ):
                continue
            region = _REGION.search(_source_text(cell))
            if region and region.group(1).strip():
                found[(name, str(marks.get("grade_id")))] = region.group(1).strip()
    return found


def for_formgrader(text: str, name: str, known: Mapping[Tuple[str, str], str]) -> str:
    """The autograded notebook ``text`` (JSON) of assignment ``name``, as Formgrader shows it.

    Each answer in words gets its rubric in a cell right after it. Every markdown cell's HTML is
    shown as text (``<`` written ``&lt;``): Formgrader renders markdown unsanitised in the
    instructor's own JupyterLab, so a tag in a student's answer (``<img onerror=...>``) would
    run there. Outputs are sanitised by Formgrader's exporter (``nbgrader_config.py`` of
    :func:`prepare`). Cells already tagged :data:`RUBRIC_TAG` are dropped first, so the result
    is the same however often this runs. Text that is not a notebook is returned as it is.
    """
    try:
        notebook = json.loads(text)
        cells = list(notebook["cells"])
    except (ValueError, KeyError, TypeError):
        return text
    kept = []
    for cell in cells:
        if not isinstance(cell, dict):
            return text
        if RUBRIC_TAG in cell.get("metadata", {}).get("tags", []):
            continue
        kept.append(cell)
        if cell.get("cell_type") != "markdown":
            continue
        cell["source"] = _source_text(cell).replace("<", "&lt;")
        grade_id = cell.get("metadata", {}).get("nbgrader", {}).get("grade_id")
        rubric = known.get((name, str(grade_id)))
        if rubric is not None:
            added = {
                "cell_type": "markdown",
                "metadata": {"tags": [RUBRIC_TAG]},
                "source": f"*For the grader, not in the student's notebook:* {rubric}",
            }
            if "id" in cell:  # nbformat 4.5 and later: every cell has an id
                added["id"] = re.sub(r"[^A-Za-z0-9_-]", "-", f"rubric-{grade_id}")[:64]
            kept.append(added)
    notebook["cells"] = kept
    return json.dumps(notebook, indent=1, ensure_ascii=False) + "\n"
