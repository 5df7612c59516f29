"""The student edition: what students receive, as a git repository to push for a class.

``duckie student-edition OUT`` writes ``OUT``, a folder that is a git repository with one
commit, holding:

    course/          the released notebooks, exactly as in the repository (refused unless
                     they are a fresh release of solutions/: the course's gates check
                     that release, so students get what was checked)
    duckielib/       the course library (it holds no answer: the library's own rule)
    robot_nodes/     the Duckietown project notebook 11 deploys to the robot (thin nodes
                     that load the student's exported solution)
    constraints.txt  the exact versions the tests ran with
    pyproject.toml   the library's package without the instructors' parts: no autograder,
                     no instructors' commands, no grading or test dependencies
    Makefile         the students' targets: venv, lab, run, robot, ros
    README.md        a short introduction, then the README's sections for students
    .gitignore       what runs and the environment write

and nothing of ``solutions/``, ``tests/``, ``autograder/``, a gradebook or the instructors'
documentation. The files are the ones git tracks (in a repository; otherwise every file but
caches and what runs write), as they are in the working tree. The same repository gives the
same edition, commit id included: the commit's author is the course, its date the date of
the repository's last commit (or ``SOURCE_DATE_EPOCH``).

Before it commits, :func:`leaks` looks through the edition for anything that gives answers
away (solution or hidden-test markers, a withheld folder, a gradebook) and refuses if it finds
one.
"""

from __future__ import annotations

import fnmatch
import json
import os
import re
import shutil
import subprocess
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence

import tomllib

from autograder.course import IGNORED, ROOT, compare_release
from duckielib.errors import DuckielibError

__all__ = [
    "COPIED",
    "RUN_COMMAND",
    "WITHHELD",
    "Edition",
    "EditionError",
    "build_edition",
    "check_out",
    "leaks",
]

#: What students receive from the repository as it is.
COPIED = ("course", "duckielib", "robot_nodes", "constraints.txt")

#: What never reaches students: the answers and hidden tests, the project's tests, the grader.
WITHHELD = ("solutions", "tests", "autograder", ".ci")

#: A marker of a reference answer or a hidden test as nbgrader reads it: a line of its own (in
#: a notebook's JSON, a string that starts with it). Code that finds the markers (the visible
#: tests' runner cuts hidden regions out of the instructors' notebooks) names them inside a
#: pattern, never at the start of a line.
MARKER_LINE = re.compile(r'^[ \t]*"?### (BEGIN|END) (SOLUTION|HIDDEN TESTS)', re.M)

#: What ``make run`` runs in the edition (after ``.venv/bin/``): the student's own notebooks
#: drive the mission, since the edition has no reference solution.
RUN_COMMAND = "duckie mission --solution course --out runs/latest"

#: Dependencies of the repository that only instructors and the project's tests use: Dask
#: grades a class, JupyterHub serves one (a hub installs it beside the edition), pytest runs
#: the project's tests.
INSTRUCTOR_DEPENDENCIES = ("dask", "jupyterhub", "pytest")

#: Debian packages ``make ros`` installs for the grader's sandbox and the browser tests only.
INSTRUCTOR_PACKAGES = ("bubblewrap", "chromium")

#: The edition's commit: the same for the same repository.
AUTHOR = ("Duckiebot course", "course@duckietown.invalid")
#: The date when neither ``SOURCE_DATE_EPOCH`` nor the repository's history gives one.
FALLBACK_EPOCH = 315532800  # 1980-01-01

#: What is never copied when the repository is not a git repository: caches by name, and by
#: path what ``duckie robot prepare`` and running the notebooks write.
_NEVER_COPIED_NAMES = ("__pycache__", "*.pyc", ".ipynb_checkpoints", "*.egg-info", ".DS_Store")
_NEVER_COPIED_PATHS = (
    "robot_nodes/deploy",
    "robot_nodes/deploy.tmp",
    "robot_nodes/deploy.old",
    *(f"course/*/{pattern}" for pattern in IGNORED),
)

GITIGNORE = """\
# What the course's commands write: never part of the course.
.venv/
__pycache__/
*.egg-info/
.ipynb_checkpoints/
runs/
build/
dist/
# What running a notebook writes next to it.
/course/*/*.bag
/course/*/*.active
/course/*/*.png
/course/*/*.gif
/course/*/*.mp4
# The zip duckie handin writes, to hand in rather than commit.
*.zip
"""

MAKEFILE = """\
# The course's commands for students. The first use of any target creates .venv and installs
# the course's library with the exact versions of constraints.txt; later uses reinstall only
# when pyproject.toml or constraints.txt change.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
SUDO := $(shell [ "$$(id -u)" = 0 ] || echo sudo)
# Jupyter refuses to run as root unless told; LAB_ARGS passes more options (--port=8890 ...).
LAB_ROOT := $(shell [ "$$(id -u)" = 0 ] && echo --allow-root)
LAB_ARGS ?=
# The folder JupyterLab shows: this one (its course/ opens first).
LAB_DIR ?= $(CURDIR)
# The solution make robot deploys: your notebooks.
SOLUTION ?= course

# Debian's ROS 1, for running the course's nodes on a real ROS master (notebook 11), and
# ffmpeg, which writes animations as MP4.
ROS_PACKAGES := @ROS_PACKAGES@

.PHONY: help venv run lab robot ros clean

help:
\t@echo "make lab     start JupyterLab on the course's notebooks"
\t@echo "make run     your notebooks drive the square-then-circle task in the simulator"
\t@echo "make robot   ready robot_nodes/ for your Duckiebot with your notebooks (notebook 11)"
\t@echo "make venv    create .venv with the course's library (every other target does it too)"
\t@echo "make ros     install Debian's ROS 1 (notebook 11; needs apt, root or sudo)"
\t@echo "make clean   remove .venv and runs/"

$(STAMP): pyproject.toml constraints.txt
\t@$(PYTHON) -c 'import sys; sys.exit(sys.version_info < (3, 11))' || \\
\t\t{ echo "The course needs Python 3.11 or newer: run with PYTHON=python3.11 (or newer)."; \\
\t\texit 1; }
\t@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
\t$(BIN)/python -m pip install --quiet --upgrade pip
\t$(BIN)/python -m pip install --quiet -c constraints.txt -e .
\t@touch $(STAMP)

venv: $(STAMP)

# Your notebooks' solution drives the mission; until it is complete, one sentence names the
# notebook to finish first.
run: $(STAMP)
\t$(BIN)/@RUN_COMMAND@

# JupyterLab with course/ open, nbgrader's Validate checking every cell, and the course's
# commands (duckie handin ...) in its terminals.
lab: $(STAMP)
\tPATH="$(CURDIR)/$(BIN):$$PATH" \\
\tJUPYTER_CONFIG_PATH="$(CURDIR)/duckielib/lab$${JUPYTER_CONFIG_PATH:+:$$JUPYTER_CONFIG_PATH}" \\
\t\t$(BIN)/jupyter lab --ServerApp.root_dir="$(LAB_DIR)" --LabApp.default_url=/lab/tree/course \\
\t\t$(LAB_ROOT) $(LAB_ARGS)

# The course library and your solution into robot_nodes/deploy/ (SOLUTION=mine.py for a
# module made by duckie export).
robot: $(STAMP)
\t$(BIN)/duckie robot prepare --solution $(SOLUTION)

ros:
\t$(SUDO) apt-get update
\tDEBIAN_FRONTEND=noninteractive $(SUDO) apt-get install -y --no-install-recommends $(ROS_PACKAGES)

clean:
\trm -rf $(VENV) runs
"""

README = """\
# Duckiebot ROS course

Learn robot software with a Duckiebot: Jupyter notebooks that teach ROS 1 (nodes, topics,
messages, services, bags), frames, differential-drive kinematics and odometry, with
auto-graded exercises, a 2D physics simulator of the robot, and ROS nodes that run your own
code on a real Duckiebot.

This folder is the course's student edition, made by your instructor: the notebooks in
`course/`, from `@FIRST@` to `@LAST@`, the course's library in
`duckielib/`, and the robot's Duckietown project in `robot_nodes/`.

"""

#: The README's sections copied into the edition's: from the first of these headings to the
#: second (the students' sections: the quick start, the robot, the library's pieces). The
#: first is called ``## Start here`` there, where every reader is a student.
README_FROM = "## For students"
README_UNTIL = "## For instructors"


class EditionError(DuckielibError):
    """The student edition cannot be made (the message says why and what to do)."""


@dataclass
class Edition:
    """A student edition written by :func:`build_edition`.

    Attributes:
        folder: the edition's folder, a git repository.
        commit: the id of its one commit.
        files: every file of the edition (``.git/`` aside), relative to ``folder``, sorted.
        size: their size in bytes.
        notebooks: the released notebooks, relative to ``folder``.
    """

    folder: Path
    commit: str
    files: List[str] = field(default_factory=list)
    size: int = 0
    notebooks: List[str] = field(default_factory=list)

    def text(self) -> str:
        """What was written, and how to hand it to a class."""
        library = sum(name.startswith("duckielib/") for name in self.files)
        robot = sum(name.startswith("robot_nodes/") for name in self.files)
        return "\n".join(
            [
                f"Wrote {self.folder}/, the student edition: a git repository with one commit "
                f"({self.commit[:12]}), {len(self.files)} files, {self.size / 1e6:.1f} MB:",
                f"  course/       {len(self.notebooks)} released notebooks",
                f"  duckielib/    the course library, {library} files",
                f"  robot_nodes/  the robot's Duckietown project, {robot} files",
                "  README.md, Makefile, pyproject.toml, constraints.txt, .gitignore: for students",
                "Nothing of solutions/, tests/ or autograder/. Push it for your class:",
                f"  cd {self.folder} && git remote add origin URL && git push -u origin main",
            ]
        )


def check_out(out: Path) -> None:
    """Refuse ``out`` unless it is missing or an empty folder.

    Raises:
        EditionError: if ``out`` is a file or a folder that holds anything.
    """
    if out.exists() and not out.is_dir():
        raise EditionError(f"{out} is a file: give a new folder for the student edition.")
    if out.is_dir() and any(out.iterdir()):
        raise EditionError(
            f"{out} is not empty: give a new or empty folder for the student edition."
        )


def build_edition(
    out: Path,
    root: Path = ROOT,
    check_release: bool = True,
    progress: Optional[Callable[[str], None]] = None,
) -> Edition:
    """Write the student edition of the repository ``root`` into the folder ``out``.

    The edition is built beside ``out`` and moved there whole, so a failure leaves ``out`` as
    it was.

    Args:
        out: a new or empty folder.
        root: the course's repository.
        check_release: whether to refuse a ``course/`` that is not a fresh release of
            ``solutions/`` (about 15 s: nbgrader releases the course again to compare).
        progress: called with a sentence before each slow step.

    Returns:
        What was written.

    Raises:
        EditionError: if ``out`` is not empty, ``course/`` is not a fresh release, git is
            missing or fails, or the edition would give an answer away.
    """
    out = Path(out).absolute()
    check_out(out)
    if shutil.which("git") is None:
        raise EditionError("git is not installed: the student edition is a git repository.")
    notebooks = sorted(path.relative_to(root).as_posix() for path in root.glob("course/*/*.ipynb"))
    if not notebooks:
        raise EditionError(f"{root / 'course'} has no released notebook: run 'duckie release'.")
    if check_release:
        if progress is not None:
            progress("Checking that course/ is a fresh release of solutions/ (about 15 s)...")
        differences = compare_release(root / "course", root / "solutions")
        if differences:
            raise EditionError(
                f"course/ is not a fresh release of solutions/ ({len(differences)} "
                f"{'file differs' if len(differences) == 1 else 'files differ'}; 'duckie "
                "release --check' lists them): run 'duckie release', commit solutions/ and "
                "course/, and make the edition again."
            )
    out.parent.mkdir(parents=True, exist_ok=True)
    staging = Path(tempfile.mkdtemp(prefix=f".{out.name}-", dir=out.parent))
    try:
        written = _write(staging, root, notebooks)
        found = leaks(staging)
        if found:
            more = f" (and {len(found) - 1} more)" if len(found) > 1 else ""
            raise EditionError(
                "The edition would give answers away, so nothing was written: "
                f"{found[0].rstrip('.')}{more}."
            )
        commit = _commit(staging, written, root)
        if out.is_dir():
            out.rmdir()  # empty, as checked
        staging.rename(out)
    except BaseException:
        shutil.rmtree(staging, ignore_errors=True)
        raise
    return Edition(
        folder=out,
        commit=commit,
        files=written,
        size=sum((out / name).stat().st_size for name in written),
        notebooks=notebooks,
    )


def leaks(folder: Path) -> List[str]:
    """What in an edition's ``folder`` would give answers away, one sentence each.

    A file of a withheld folder (:data:`WITHHELD`), a gradebook, or a text that holds a
    solution or hidden-test marker line of the course's source notebooks (:data:`MARKER_LINE`).
    """
    found = []
    for path in sorted(folder.rglob("*")):
        relative = path.relative_to(folder)
        if relative.parts[0] == ".git" or not path.is_file():
            continue
        name = relative.as_posix()
        if relative.parts[0] in WITHHELD:
            found.append(f"{name} is in {relative.parts[0]}/, which students never receive.")
        elif path.suffix == ".db":
            found.append(f"{name} is a database, as nbgrader's gradebook is.")
        else:
            text = path.read_bytes().decode("utf-8", errors="replace")
            marker = MARKER_LINE.search(text)
            if marker is not None:
                found.append(f"{name} holds '{marker.group(0).strip().lstrip(chr(34))}'.")
    return found


def _write(staging: Path, root: Path, notebooks: Sequence[str]) -> List[str]:
    """Copy and write the edition's files into ``staging``; their relative paths, sorted."""
    copied = _source_files(root)
    for name in copied:
        source, target = root / name, staging / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(source, target)
        target.chmod(0o755 if source.stat().st_mode & 0o111 else 0o644)
    generated = {
        ".gitignore": GITIGNORE,
        "Makefile": _makefile(_read(root / "Makefile")),
        "README.md": _readme(_read(root / "README.md"), notebooks),
        "pyproject.toml": _pyproject(_read(root / "pyproject.toml")),
    }
    for name, text in generated.items():
        (staging / name).write_text(text, encoding="utf-8")
        (staging / name).chmod(0o644)
    return sorted(set(copied) | set(generated))


def _read(path: Path) -> str:
    if not path.is_file():
        raise EditionError(f"There is no {path}: the edition's {path.name} is made from it.")
    return path.read_text(encoding="utf-8")


def _source_files(root: Path) -> List[str]:
    """The files of :data:`COPIED`, relative to ``root``: those git tracks, in a repository."""
    if (root / ".git").exists():
        listed = _git(root, "ls-files", "-z", "--", *COPIED, env=_source_env()).split("\0")
        return sorted(name for name in listed if name and (root / name).is_file())
    names = []
    for top in COPIED:
        paths = [root / top] if (root / top).is_file() else sorted((root / top).rglob("*"))
        names += [
            path.relative_to(root).as_posix()
            for path in paths
            if path.is_file() and not _never_copied(path.relative_to(root).parts)
        ]
    return sorted(names)


def _never_copied(parts: Sequence[str]) -> bool:
    """Whether a file, given by its path's parts, is a cache or something a run wrote."""
    prefixes = ["/".join(parts[:end]) for end in range(1, len(parts) + 1)]
    return any(
        fnmatch.fnmatch(part, pattern) for part in parts for pattern in _NEVER_COPIED_NAMES
    ) or any(
        fnmatch.fnmatch(prefix, pattern) for prefix in prefixes for pattern in _NEVER_COPIED_PATHS
    )


def _makefile(repository_makefile: str) -> str:
    """The students' Makefile, with the repository's ROS packages but the instructors'."""
    match = re.search(r"^ROS_PACKAGES :=((?:.*\\\n)*.*)$", repository_makefile, re.M)
    if match is None:
        raise EditionError(
            "The repository's Makefile has no 'ROS_PACKAGES :=' list, which the edition's "
            "'make ros' installs."
        )
    packages = [
        name for name in match[1].replace("\\\n", " ").split() if name not in INSTRUCTOR_PACKAGES
    ]
    return MAKEFILE.replace("@ROS_PACKAGES@", " ".join(packages)).replace(
        "@RUN_COMMAND@", RUN_COMMAND
    )


def _readme(repository_readme: str, notebooks: Sequence[str]) -> str:
    """The students' README: what the edition holds, then the README's sections for students."""
    lines = repository_readme.splitlines(keepends=True)
    try:
        start = next(i for i, line in enumerate(lines) if line.rstrip() == README_FROM)
        end = next(i for i, line in enumerate(lines) if line.rstrip() == README_UNTIL)
    except StopIteration:
        raise EditionError(
            f"README.md must keep its sections '{README_FROM}' and '{README_UNTIL}': the "
            "edition's README copies the sections between them."
        ) from None
    first, last = (Path(notebooks[index]).parent.name for index in (0, -1))
    head = README.replace("@FIRST@", first).replace("@LAST@", last)
    body = ["## Start here\n", *lines[start + 1 : end]]
    return head + "".join(body).rstrip("\n") + "\n"


def _pyproject(repository_pyproject: str) -> str:
    """The students' ``pyproject.toml``: the library's package, without the instructors' parts."""
    data = tomllib.loads(repository_pyproject)
    project = dict(data["project"])
    project["dependencies"] = [
        requirement
        for requirement in project.get("dependencies", [])
        if _requirement_name(requirement) not in INSTRUCTOR_DEPENDENCIES
    ]
    scripts = project.pop("scripts", {})
    for table in ("optional-dependencies", "entry-points"):
        project.pop(table, None)
    setuptools = data.get("tool", {}).get("setuptools", {})
    packages = [
        pattern
        for pattern in setuptools.get("packages", {}).get("find", {}).get("include", [])
        if pattern.startswith("duckielib")
    ]
    package_data = {
        name: value
        for name, value in setuptools.get("package-data", {}).items()
        if name.startswith("duckielib")
    }
    tables: List[tuple] = [
        ("build-system", data["build-system"]),
        ("project", project),
        ("project.scripts", scripts),
        ("tool.setuptools.packages.find", {"include": packages or ["duckielib*"]}),
        ("tool.setuptools.package-data", package_data),
    ]
    text = (
        "# The course's library for students: `make` installs it (pip install -e .) with the\n"
        "# versions of constraints.txt.\n"
    )
    for name, values in tables:
        if values:
            text += f"\n[{name}]\n"
            text += "".join(f"{_toml_key(key)} = {_toml(value)}\n" for key, value in values.items())
    if tomllib.loads(text)["project"]["name"] != project["name"] or "autograder" in text:
        raise EditionError("The edition's pyproject.toml could not be made from the repository's.")
    return text


def _requirement_name(requirement: str) -> str:
    match = re.match(r"[A-Za-z0-9._-]+", requirement)
    return match[0].lower().replace("_", "-") if match else requirement


def _toml_key(key: str) -> str:
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else json.dumps(key)


def _toml(value: Any) -> str:
    """A TOML value for the strings, lists and small tables of a ``pyproject.toml``."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value, ensure_ascii=False)
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{_toml_key(k)} = {_toml(v)}" for k, v in value.items()) + " }"
    if isinstance(value, list):
        if not value:
            return "[]"
        return "[\n" + "".join(f"    {_toml(item)},\n" for item in value) + "]"
    raise EditionError(f"The edition's pyproject.toml cannot hold {value!r}.")


def _source_env() -> Dict[str, str]:
    """The environment for git in the repository: none of a caller's git redirections."""
    return {key: value for key, value in os.environ.items() if not key.startswith("GIT_")}


def _git(folder: Path, *args: str, env: Dict[str, str]) -> str:
    result = subprocess.run(
        ["git", "-C", str(folder), *args],
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    if result.returncode != 0:
        said = (result.stderr.strip().splitlines() or ["no message"])[-1]
        raise EditionError(f"git {args[0]} failed in {folder}: {said.rstrip('.')}.")
    return result.stdout


def _date(root: Path) -> int:
    """The edition's date: ``SOURCE_DATE_EPOCH``, else the repository's last commit's."""
    given = os.environ.get("SOURCE_DATE_EPOCH", "")
    if given.isdigit():
        return int(given)
    if (root / ".git").exists():
        with_date = _git(root, "log", "-1", "--format=%ct", env=_source_env()).strip()
        if with_date.isdigit():
            return int(with_date)
    return FALLBACK_EPOCH


def _commit(folder: Path, files: Sequence[str], root: Path) -> str:
    """Make ``folder`` a git repository whose one commit holds ``files``; the commit's id."""
    date = f"@{_date(root)} +0000"
    env = _source_env()
    env.update(
        {
            # The same edition for every instructor: no one's settings, hooks or identity.
            "GIT_CONFIG_GLOBAL": os.devnull,
            "GIT_CONFIG_NOSYSTEM": "1",
            "GIT_AUTHOR_NAME": AUTHOR[0],
            "GIT_AUTHOR_EMAIL": AUTHOR[1],
            "GIT_AUTHOR_DATE": date,
            "GIT_COMMITTER_NAME": AUTHOR[0],
            "GIT_COMMITTER_EMAIL": AUTHOR[1],
            "GIT_COMMITTER_DATE": date,
        }
    )
    _git(folder, "init", "--quiet", "--initial-branch=main", env=env)
    _git(folder, "add", "--all", env=env)
    tracked = sorted(_git(folder, "ls-files", "-z", env=env).split("\0")[:-1])
    if tracked != list(files):
        left_out = sorted(set(files) - set(tracked))
        raise EditionError(
            f"The edition's .gitignore leaves out {left_out[0] if left_out else 'a file'}: "
            "every file of the edition must be committed."
        )
    _git(folder, "commit", "--quiet", "--no-verify", "-m", _message(root), env=env)
    return _git(folder, "rev-parse", "HEAD", env=env).strip()


def _message(root: Path) -> str:
    head = ""
    if (root / ".git").exists():
        head = _git(root, "rev-parse", "--short=12", "HEAD", env=_source_env()).strip()
    return "The Duckiebot course, student edition" + (f" (from {head})" if head else "")
