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

__all__ = ["RUBRIC_TAG", "command", "for_formgrader", "prepare", "rubrics", "write_config"]

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
    return write_config(work, source)


def write_config(work: Path, source: Path = ROOT / "solutions") -> Path:
    """Write ``work/nbgrader_config.py``: Formgrader on the gradebook ``work`` holds or will."""
    (work / "submitted").mkdir(exist_ok=True)
    text = _CONFIG.format(
        root=str(work), source=str(Path(source).resolve()), db=f"sqlite:///{work / 'gradebook.db'}"
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
        # A strict Content-Security-Policy on Formgrader's pages (see autograder/formgrade_csp).
        "--ServerApp.jpserver_extensions=autograder.formgrade_csp=True",
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


#: What an output may show in Formgrader (pictures as data; no SVG, no script, no widget).
_SHOWN = ("text/plain", "text/html", "text/markdown", "text/latex", "image/png", "image/jpeg",
          "image/gif")  # fmt: skip
#: The kinds of link a student's answer or output may hold.
SAFE_SCHEMES = frozenset({"http", "https", "mailto"})
_INLINE_LINK = re.compile(r"(\]\(\s*)([^)\s]*)")
_REFERENCE = re.compile(r"^(\s{0,3}\[[^\]]*\]:\s*)(\S+)", re.M)


def _safe_url(url: str) -> bool:
    """Whether ``url`` (as a student wrote it) leads only to a web or mail address, or nowhere."""
    import html

    plain = re.sub(r"[\x00-\x20\\<>]", "", html.unescape(html.unescape(url))).lower()
    scheme = re.match(r"([a-z][a-z0-9+.-]*):", plain)
    return scheme is None or scheme.group(1) in SAFE_SCHEMES


def safe_markdown(text: str) -> str:
    """A student's markdown as Formgrader may show it: HTML as text, no link to a script."""

    def link(found: re.Match) -> str:
        return found.group(1) + (found.group(2) if _safe_url(found.group(2)) else "#")

    text = text.replace("<", "&lt;")
    return _REFERENCE.sub(link, _INLINE_LINK.sub(link, text))


def _safe_output(output: Dict) -> Dict:
    """A cell's output with only what :data:`_SHOWN` allows, its HTML cleaned by nh3."""
    import nh3

    kind = output.get("output_type")
    if kind not in ("display_data", "execute_result"):
        return {key: value for key, value in output.items() if key != "metadata"}
    data = {}
    for mime, value in (output.get("data") or {}).items():
        if mime not in _SHOWN:
            continue
        text = "".join(value) if isinstance(value, list) else str(value)
        if mime == "text/html":
            text = nh3.clean(text, url_schemes=set(SAFE_SCHEMES))
        elif mime == "text/markdown":
            text = safe_markdown(text)
        data[mime] = text
    metadata = {}
    for mime, value in (output.get("metadata") or {}).items():
        if mime.startswith("image/") and isinstance(value, dict):
            size = {
                key: int(number)
                for key, number in value.items()
                if key in ("width", "height")
                and isinstance(number, (int, float))
                and not isinstance(number, bool)
                and 0 < number < 100_000
            }
            if size:
                metadata[mime] = size
    safe = {"output_type": kind, "data": data, "metadata": metadata}
    if kind == "execute_result":
        safe["execution_count"] = output.get("execution_count")
    return safe


def for_formgrader(text: str, name: str, known: Mapping[Tuple[str, str], str]) -> str:
    """The autograded notebook ``text`` (JSON) of assignment ``name``, as Formgrader shows it.

    Each answer in words gets its rubric in a cell right after it. What the student wrote is made
    safe to show in the instructor's JupyterLab, where a script would act with the instructor's
    rights: every markdown cell's HTML is shown as text (:func:`safe_markdown`, which also
    turns links to anything but web and mail addresses into ``#``), and every output keeps only
    text, HTML cleaned by nh3, and PNG, JPEG and GIF pictures whose size, if any, is a number
    (:func:`_safe_output`). Formgrader's own exporter sanitises again (``nbgrader_config.py`` of
    :func:`prepare`), and its pages run under a strict policy (:mod:`autograder.formgrade_csp`).
    Cells already tagged :data:`RUBRIC_TAG` are dropped first, so the result is the same
    however often this runs. Text that is not a notebook is returned as it is.
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
        if cell.get("cell_type") == "code":
            cell["outputs"] = [
                _safe_output(output)
                for output in cell.get("outputs", [])
                if isinstance(output, dict)
            ]
        if cell.get("cell_type") != "markdown":
            continue
        cell.pop("attachments", None)
        cell["source"] = safe_markdown(_source_text(cell))
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
