"""nbgrader's Formgrader on a class that ``duckie grade`` graded: where a person grades answers.

``duckie grade --out grading/`` leaves nbgrader's course tree in ``grading/work/``: the gradebook
(scores, and the answers in words that wait for a person), the release and the autograded
notebooks. :func:`prepare` writes the ``nbgrader_config.py`` that tells Formgrader where each
of them is (the hidden tests' source stays where it is, in ``solutions/``), and
:func:`command` the JupyterLab command line that opens it, with nbgrader's instructor tools and
without the students' configuration. Grades given there go into the gradebook; the next
``duckie grade`` reads them into ``grades.csv`` and the feedback pages.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import List, Sequence

from autograder.course import ROOT, CourseError

__all__ = ["command", "prepare"]

_CONFIG = """\
# Written by `duckie formgrade`: nbgrader's Formgrader on the class graded here.
c = get_config()  # noqa: F821 - given by nbgrader when it reads this file
c.CourseDirectory.root = {root!r}
c.CourseDirectory.source_directory = {source!r}
c.CourseDirectory.release_directory = "release"
c.CourseDirectory.submitted_directory = "submitted"
c.CourseDirectory.autograded_directory = "autograded"
c.CourseDirectory.db_url = {db!r}
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
