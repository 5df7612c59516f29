"""The course on nbgrader: its configuration, the release of ``course/`` and autograding.

Layout (nbgrader's names in brackets): ``solutions/`` [source] holds one folder per
assignment with one notebook named like the folder; ``course/`` [release] is generated from it.
Submissions are graded in a working folder of their own, never inside the repository, so no
gradebook (which holds the hidden tests in plain text) is ever written next to ``course/``.

nbgrader facts this module handles: it runs ``alembic`` from PATH (the environment's ``bin``
is put first), ``generate_assignment`` copies every non-notebook file of an assignment folder
(files a notebook run writes are ignored), and its functions report failure in their return
value and log rather than by raising (turned into :class:`CourseError` here).
"""

from __future__ import annotations

import functools
import os
import shutil
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Dict, Iterable, List, Mapping, Optional, Tuple, Union

from duckielib.config import PROJECT_ROOT
from duckielib.errors import DuckielibError

if TYPE_CHECKING:  # both are imported where used: they are slow to import
    from nbgrader.apps import NbGraderAPI
    from traitlets.config import Config

__all__ = [
    "ROOT",
    "CourseError",
    "Scores",
    "assignments",
    "autograde",
    "compare_release",
    "gradebook_revision",
    "log_tail",
    "nbgrader_api",
    "nbgrader_config",
    "release_course",
]

#: The repository: ``solutions/`` and ``course/`` live here.
ROOT = PROJECT_ROOT

#: Files an assignment folder may hold that are never released: what running a notebook or
#: Jupyter leaves behind. Images a notebook shows belong in the notebook (cell attachments).
IGNORED = [
    ".ipynb_checkpoints",
    "*.pyc",
    "__pycache__",
    "feedback",
    "runs",
    "*.bag",
    "*.active",
    "*.png",
    "*.gif",
    "*.mp4",
    "*.html",
    "*.db",
]

PathLike = Union[str, Path]


class CourseError(DuckielibError):
    """Releasing or autograding the course failed (the message says where and why)."""


def assignments(source: PathLike = ROOT / "solutions") -> List[str]:
    """The assignment folders of ``source`` that hold a notebook, in course order."""
    return sorted(path.parent.name for path in Path(source).glob("*/*.ipynb"))


def nbgrader_config(
    root: PathLike = ROOT,
    release: PathLike = "course",
    db: Optional[PathLike] = None,
    source: PathLike = "solutions",
) -> Config:
    """The nbgrader configuration of the course.

    Args:
        root: the course root (nbgrader's ``CourseDirectory.root``).
        release: the release folder, relative to ``root`` or absolute.
        db: the gradebook database file (default: ``gradebook.db`` under ``root``).
        source: the source folder, relative to ``root`` or absolute.
    """
    from traitlets.config import Config

    config = Config()
    config.CourseDirectory.root = str(root)
    config.CourseDirectory.source_directory = str(source)
    config.CourseDirectory.release_directory = str(release)
    config.CourseDirectory.ignore = list(IGNORED)
    db_path = Path(db) if db is not None else Path(root) / "gradebook.db"
    config.CourseDirectory.db_url = f"sqlite:///{db_path}"
    config.Execute.timeout = 120
    return config


def nbgrader_api(config: Config) -> NbGraderAPI:
    """Nbgrader's API on ``config``, with the environment's programs first on PATH.

    nbgrader runs alembic by name: the environment's bin must come first on PATH. It starts
    an ``alembic heads`` process for each gradebook it makes, to stamp it with its schema's
    revision: a second of CPU each time for the same answer. From here on, in this process,
    that answer is read once by alembic's own API (:func:`gradebook_revision`).
    """
    bin_dir = str(Path(sys.executable).parent)
    if os.environ.get("PATH", "").split(os.pathsep)[0] != bin_dir:
        os.environ["PATH"] = bin_dir + os.pathsep + os.environ.get("PATH", "")
    import nbgrader.api
    from nbgrader.apps import NbGraderAPI

    nbgrader.api.get_alembic_version = gradebook_revision
    return NbGraderAPI(config=config)


@functools.lru_cache(maxsize=None)
def gradebook_revision() -> str:
    """The revision of nbgrader's gradebook schema a new gradebook is stamped with.

    The newest of nbgrader's own migrations, as ``alembic heads`` prints it, read in this
    process (80 ms, against a second for the command).
    """
    from alembic.script import ScriptDirectory
    from nbgrader.dbutil import ALEMBIC_DIR

    return str(ScriptDirectory(ALEMBIC_DIR).get_current_head())


def log_tail(result: Mapping[str, object]) -> str:
    """The last lines of an nbgrader API call's log worth showing: its errors, or its end."""
    log = str(result.get("log") or result.get("error") or "")
    errors = [line for line in log.splitlines() if "[ERROR]" in line or "Error" in line]
    return "\n".join((errors or log.splitlines())[-6:])


def release_course(
    release: PathLike = ROOT / "course", source: PathLike = ROOT / "solutions"
) -> List[Path]:
    """Generate the student notebooks of every assignment of ``source`` into ``release``.

    The release is built in a temporary folder first and replaces ``release`` only when every
    assignment succeeded, so a failure leaves the previous release as it was.

    Returns:
        The released notebooks.

    Raises:
        CourseError: if ``source`` has no assignment, or nbgrader fails on one (with its log).
    """
    source, release = Path(source).resolve(), Path(release).resolve()
    names = assignments(source)
    if not names:
        raise CourseError(f"{source} has no assignment folder with a notebook to release.")
    with tempfile.TemporaryDirectory(prefix="duckie-release-") as work:
        staged = Path(work) / "release"
        api = nbgrader_api(
            nbgrader_config(
                root=source.parent, release=staged, db=Path(work) / "gradebook.db", source=source
            )
        )
        for name in names:
            result = api.generate_assignment(name, force=True)
            if not result["success"]:
                raise CourseError(f"nbgrader could not release {name}:\n{log_tail(result)}")
        if release.exists():
            shutil.rmtree(release)
        shutil.copytree(staged, release)
    return sorted(release.glob("*/*.ipynb"))


def _files(folder: Path) -> Dict[str, bytes]:
    return {
        path.relative_to(folder).as_posix(): path.read_bytes()
        for path in sorted(folder.rglob("*"))
        if path.is_file()
    }


def compare_release(
    release: PathLike = ROOT / "course", source: PathLike = ROOT / "solutions"
) -> List[str]:
    """What differs between ``release`` and a fresh release of ``source`` (nothing is written).

    Returns:
        Sentences naming each file that is stale, missing or extra; empty when identical.
    """
    release = Path(release)
    with tempfile.TemporaryDirectory(prefix="duckie-release-check-") as work:
        release_course(Path(work) / "course", source)
        fresh = _files(Path(work) / "course")
    current = _files(release) if release.is_dir() else {}
    differences = []
    for name in sorted(set(fresh) | set(current)):
        if name not in current:
            differences.append(f"{name} is missing from {release.name}/.")
        elif name not in fresh:
            differences.append(f"{name} is in {release.name}/ but not in a fresh release.")
        elif fresh[name] != current[name]:
            differences.append(f"{name} differs from a fresh release.")
    return differences


@dataclass
class Scores:
    """Autograded scores of one student.

    Attributes:
        cells: ``(assignment, grade_id) -> (score, max_score)`` for every graded cell.
        logs: nbgrader's log of each assignment's autograding.
        seconds: how long each assignment's autograding took (wall clock).
    """

    cells: Dict[Tuple[str, str], Tuple[float, float]] = field(default_factory=dict)
    logs: Dict[str, str] = field(default_factory=dict)
    seconds: Dict[str, float] = field(default_factory=dict)

    def total(self, assignment: Optional[str] = None) -> Tuple[float, float]:
        """(score, max score), of one assignment or of all."""
        chosen = [v for (a, _), v in self.cells.items() if assignment in (None, a)]
        return sum(v[0] for v in chosen), sum(v[1] for v in chosen)


def autograde(
    submissions: Mapping[str, PathLike],
    work: PathLike,
    names: Optional[Iterable[str]] = None,
    source: PathLike = ROOT / "solutions",
) -> Dict[str, Scores]:
    """Autograde students' notebooks with nbgrader, one after the other, in ``work``.

    Args:
        submissions: each student's folder holding their assignment folders (a copy of
            ``course/`` they worked in).
        work: an empty folder for the gradebook and nbgrader's ``submitted/`` and
            ``autograded/`` trees.
        names: the assignments to grade (default: all of ``source``).
        source: the course source, whose hidden tests replace the students' test cells.

    Returns:
        Each student's scores.

    Raises:
        CourseError: if nbgrader fails on a submission (not if the student's code fails).
    """
    work = Path(work).resolve()
    work.mkdir(parents=True, exist_ok=True)
    source = Path(source).resolve()
    names = list(names) if names is not None else assignments(source)
    config = nbgrader_config(root=work, release="release", db=work / "gradebook.db", source=source)
    config.CourseDirectory.submitted_directory = "submitted"
    config.CourseDirectory.autograded_directory = "autograded"
    api = nbgrader_api(config)
    for name in names:
        result = api.generate_assignment(name, force=True)
        if not result["success"]:
            raise CourseError(f"nbgrader could not set up {name}:\n{log_tail(result)}")
    results: Dict[str, Scores] = {}
    from nbgrader.api import Gradebook

    for student, folder in submissions.items():
        scores = Scores()
        for name in names:
            target = work / "submitted" / student / name
            if target.exists():
                shutil.rmtree(target)
            shutil.copytree(Path(folder) / name, target)
            started = time.perf_counter()
            result = api.autograde(name, student, force=True, create=True)
            scores.seconds[name] = time.perf_counter() - started
            scores.logs[name] = str(result.get("log") or "")
            if not result["success"]:
                raise CourseError(
                    f"nbgrader could not autograde {name} of {student}:\n{log_tail(result)}"
                )
        with Gradebook(config.CourseDirectory.db_url) as gradebook:
            for name in names:
                for notebook in gradebook.find_submission(name, student).notebooks:
                    for grade in notebook.grades:
                        scores.cells[(name, grade.name)] = (
                            float(grade.score),
                            float(grade.max_score),
                        )
        results[student] = scores
    return results
