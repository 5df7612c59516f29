"""The student edition (``duckie student-edition``): no answer in it, and it works from a clone.

One edition is built for the module, and cloned once; the commands a student runs are run in
the clone with the project's Python started with ``-S``: the clone's ``duckielib`` on the path,
the environment's packages beside it, and nothing of this repository (its ``autograder`` is
not importable, as in a student's environment). The release check the command makes first is
the course gate's (``tests/course/test_course_structure.py``), not repeated here.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest
import tomllib

from autograder.course import ROOT
from autograder.edition import RUN_COMMAND, WITHHELD, build_edition, leaks

pytestmark = pytest.mark.slow

SOLUTION_REGION = re.compile(r"### BEGIN SOLUTION\n(.*?)### END SOLUTION", re.S)
HIDDEN_REGION = re.compile(r"### BEGIN HIDDEN TESTS\n(.*?)### END HIDDEN TESTS", re.S)
MARKER = re.compile(r'^\s*"?#+\s*(BEGIN|END)\s+(SOLUTION|HIDDEN TESTS)', re.M)

#: The scan looks for every line of a solution or hidden-test region longer than this
#: (stripped): shorter ones are bare syntax ("return x", "else:").
SHORTEST = 20

#: Lines of a solution region that the library holds for its own reasons, and the reason.
SHARED = {
    "if isinstance(move, Stop):": (
        "duckielib/missions.py names a mission's moves (describe_move) by their type, as a "
        "mission node dispatches on them"
    ),
    "name = request.pattern_name.data": (
        "the virtual robot's LED emitter (duckielib/sim/drivers.py) reads the pattern a light "
        "service node asks it for"
    ),
}

#: What a student's edition holds at its top.
TOP = {
    ".git",
    ".gitignore",
    "Makefile",
    "README.md",
    "constraints.txt",
    "course",
    "duckielib",
    "pyproject.toml",
    "robot_nodes",
}


def git(folder: Path, *args: str) -> str:
    return subprocess.run(
        ["git", "-C", str(folder), *args], capture_output=True, text=True, check=True, timeout=60
    ).stdout


def tracked(*tops: str) -> list[str]:
    listed = git(ROOT, "ls-files", "-z", "--", *tops).split("\0")
    return [name for name in listed if name and (ROOT / name).is_file()]


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """The edition, built twice from the same repository: (first, second)."""
    folder = tmp_path_factory.mktemp("edition")
    first = build_edition(folder / "edition", check_release=False)
    second = build_edition(folder / "again", check_release=False)
    return first, second


@pytest.fixture(scope="module")
def edition(built):
    return built[0]


@pytest.fixture(scope="module")
def clone(edition, tmp_path_factory):
    folder = tmp_path_factory.mktemp("clone") / "duckiebot-course"
    subprocess.run(
        ["git", "clone", "--quiet", str(edition.folder), str(folder)], check=True, timeout=60
    )
    return folder


def files_of(folder: Path) -> list[Path]:
    return sorted(
        path
        for path in folder.rglob("*")
        if path.is_file() and path.relative_to(folder).parts[0] != ".git"
    )


def student_env(clone: Path) -> dict[str, str]:
    """The environment's packages and the clone's library on the path, nothing of ours."""
    packages = {sysconfig.get_paths()["purelib"], sysconfig.get_paths()["platlib"]}
    env = {key: value for key, value in os.environ.items() if not key.startswith("DUCKIE_")}
    env["PYTHONPATH"] = os.pathsep.join([str(clone), *sorted(packages)])
    env["MPLBACKEND"] = "Agg"
    return env


def duckie_in(clone: Path, *args: str) -> subprocess.CompletedProcess:
    """``duckie ARGS`` as a student runs it in the clone, with no ``autograder`` to import."""
    return subprocess.run(
        [sys.executable, "-S", "-m", "duckielib.tools.cli", *args],
        cwd=clone,
        env=student_env(clone),
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )


def test_the_edition_holds_what_students_need_and_nothing_of_the_instructors(edition):
    folder = edition.folder
    assert {path.name for path in folder.iterdir()} == TOP
    names = [path.relative_to(folder).as_posix() for path in files_of(folder)]
    assert names == edition.files
    assert not [name for name in names if name.split("/")[0] in WITHHELD]
    assert not [name for name in names if name.endswith(".db") or "gradebook" in name]
    # What students receive as it is: the released notebooks, the library, the robot project.
    for name in tracked("course", "duckielib", "robot_nodes", "constraints.txt"):
        assert (folder / name).read_bytes() == (ROOT / name).read_bytes(), name
    assert len(edition.notebooks) == len(list((ROOT / "solutions").glob("*/*.ipynb"))) == 11
    # No file of the withheld folders under another name either.
    withheld = {
        hashlib.sha256((ROOT / name).read_bytes()).hexdigest(): name
        for name in tracked(*WITHHELD)
        if (ROOT / name).stat().st_size
    }
    copies = [
        f"{path.relative_to(folder)} is {withheld[digest]}"
        for path in files_of(folder)
        if (digest := hashlib.sha256(path.read_bytes()).hexdigest()) in withheld
    ]
    assert copies == []
    readme = (folder / "README.md").read_text(encoding="utf-8")
    assert readme.startswith("# Duckiebot ROS course\n")
    headings = re.findall(r"^## .*$", readme, re.M)
    assert headings[0] == "## Start here"
    assert "## To the robot" in headings
    assert not {"## For instructors", "## For developers", "## Quick start"} & set(headings)
    assert "solutions/README.md" not in readme
    assert "git clone URL duckiebot-course" in readme
    assert "duckie handin" in readme
    assert "duckie export" in readme
    assert "duckie mission --solution course" in readme


def test_no_answer_or_hidden_test_reaches_the_edition(edition):
    # Every line of a solution or hidden-test region that the released notebooks do not show
    # anyway, looked for anywhere in the edition's text (notebooks as their cells' text).
    released = "\n".join(
        cell_text for path in (ROOT / "course").glob("*/*.ipynb") for cell_text in cells(path)
    )
    secret: dict[str, str] = {}
    for path in sorted((ROOT / "solutions").glob("*/*.ipynb")):
        for text in cells(path):
            for region in SOLUTION_REGION.findall(text) + HIDDEN_REGION.findall(text):
                for line in map(str.strip, region.splitlines()):
                    if worth_looking_for(line, released):
                        secret.setdefault(line, path.stem)
    assert len(secret) > 500, "the regions were found"
    scanned = {}
    for path in files_of(edition.folder):
        data = path.read_bytes()
        if b"\0" in data:
            continue  # a bag
        text = data.decode("utf-8")
        # A marker line as nbgrader reads it (code may name the markers inside a pattern).
        assert not MARKER.search(text), path
        if path.suffix == ".ipynb":
            text = "\n".join(cells(path))
        scanned[path.relative_to(edition.folder).as_posix()] = text
    everything = "\n".join(scanned.values())
    found = sorted(
        f"{secret[line]}: {line!r} in "
        + ", ".join(name for name, text in scanned.items() if line in text)
        for line in secret
        if line not in SHARED and line in everything
    )
    assert found == [], "solution or hidden-test lines in the student edition"
    assert len(scanned) > 300
    assert all(line in everything for line in SHARED), "a shared line went: drop it from SHARED"


def cells(path: Path) -> list[str]:
    notebook = json.loads(path.read_text(encoding="utf-8"))
    return [
        "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
        for cell in notebook["cells"]
    ]


def worth_looking_for(line: str, released: str) -> bool:
    """Whether a region's stripped line would tell a student something the release does not.

    Short lines are bare syntax; an import names a module students have anyway.
    """
    imports = line.startswith("import ") or (line.startswith("from ") and " import " in line)
    return len(line) > SHORTEST and not imports and line not in released


def test_the_guard_finds_markers_withheld_folders_and_gradebooks(tmp_path):
    (tmp_path / "tests").mkdir()
    (tmp_path / "tests" / "test_x.py").write_text("assert True\n")
    (tmp_path / "duckielib").mkdir()
    (tmp_path / "duckielib" / "odometry.py").write_text("### BEGIN SOLUTION\nx = 1\n")
    (tmp_path / "duckielib" / "finder.py").write_text('CUT = r"^### BEGIN HIDDEN TESTS.*"\n')
    (tmp_path / "course").mkdir()
    (tmp_path / "course" / "05.ipynb").write_text('{"source": [\n  "### END HIDDEN TESTS\\n"]}')
    (tmp_path / "gradebook.db").write_bytes(b"SQLite format 3\0")
    (tmp_path / "README.md").write_text("Nothing to hide.\n")
    assert leaks(tmp_path) == [
        "course/05.ipynb holds '### END HIDDEN TESTS'.",
        "duckielib/odometry.py holds '### BEGIN SOLUTION'.",
        "gradebook.db is a database, as nbgrader's gradebook is.",
        "tests/test_x.py is in tests/, which students never receive.",
    ]


def test_the_edition_is_one_clean_commit_and_the_same_for_the_same_repository(
    built, edition, clone
):
    assert git(edition.folder, "status", "--porcelain") == ""
    assert git(edition.folder, "rev-list", "--count", "HEAD").strip() == "1"
    assert git(edition.folder, "branch", "--show-current").strip() == "main"
    assert git(edition.folder, "rev-parse", "HEAD").strip() == edition.commit
    # Every file is committed, and .gitignore ignores none of them.
    assert git(edition.folder, "ls-files").splitlines() == edition.files
    assert git(edition.folder, "ls-files", "--cached", "--ignored", "--exclude-standard") == ""
    assert git(clone, "status", "--porcelain") == ""
    assert built[1].commit == edition.commit
    assert git(edition.folder, "log", "--format=%an").strip() == "Duckiebot course"
    # What runs write stays out of git.
    (clone / "runs" / "latest").mkdir(parents=True)
    (clone / "runs" / "latest" / "mission.bag").write_bytes(b"#ROSBAG V2.0\n")
    (clone / "course" / "05_odometry" / "odometry.png").write_bytes(b"\x89PNG")
    (clone / "ada_lovelace.zip").write_bytes(b"PK")
    try:
        assert git(clone, "status", "--porcelain") == ""
    finally:
        shutil.rmtree(clone / "runs")
        (clone / "course" / "05_odometry" / "odometry.png").unlink()
        (clone / "ada_lovelace.zip").unlink()


def test_the_editions_package_is_the_library_alone(edition):
    ours = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    theirs = tomllib.loads((edition.folder / "pyproject.toml").read_text(encoding="utf-8"))
    assert "autograder" not in (edition.folder / "pyproject.toml").read_text(encoding="utf-8")
    assert theirs["project"]["name"] == ours["project"]["name"]
    assert theirs["project"]["scripts"] == {"duckie": "duckielib.tools.cli:main"}
    assert "entry-points" not in theirs["project"]
    assert "optional-dependencies" not in theirs["project"]
    assert theirs["tool"]["setuptools"]["packages"]["find"]["include"] == ["duckielib*"]
    assert (
        theirs["tool"]["setuptools"]["package-data"] == (ours["tool"]["setuptools"]["package-data"])
    )
    dropped = [
        requirement
        for requirement in ours["project"]["dependencies"]
        if requirement not in theirs["project"]["dependencies"]
    ]
    assert dropped == [
        next(r for r in ours["project"]["dependencies"] if r.startswith(name))
        for name in ("dask", "jupyterhub", "pytest")
    ]


def test_duckie_works_in_a_clone_without_autograder(clone):
    helped = duckie_in(clone, "--help")
    assert helped.returncode == 0, helped.stderr
    for command in ("mission", "export", "handin", "bag", "robot"):
        assert f"    {command} " in helped.stdout
    for command in ("release", "grade", "formgrade", "feedback", "student-edition"):
        assert f"    {command} " not in helped.stdout
        assert f"    {command}\n" not in helped.stdout
    assert duckie_in(clone, "bench").returncode == 0

    # The untouched course: the mission stops at once, naming the notebook to finish first.
    mission = duckie_in(clone, "mission", "--solution", "course", "--no-animation", "--no-figure")
    assert mission.returncode == 1
    assert mission.stderr == (
        "duckie: Finish notebook 05_odometry: write delta_phi, estimate_pose, WheelPairing "
        "(their cells still raise NotImplementedError), save the notebook, and try again.\n"
    )
    assert mission.stdout == ""
    assert not (clone / "runs").exists()

    # No reference solution here: one sentence, and no line claiming to use one.
    default = duckie_in(clone, "mission", "--no-animation", "--no-figure")
    assert default.returncode == 1
    assert default.stdout == ""
    assert default.stderr.count("\n") == 1
    assert "reference solution is not part of this installation" in default.stderr
    assert "--solution" in default.stderr

    # duckie export writes what is there and lists, notebook by notebook, what to finish.
    export = duckie_in(clone, "export", "course", "-o", "my_solution.py")
    try:
        assert export.returncode == 0, export.stderr
        assert "Traceback" not in export.stderr + export.stdout
        lines = export.stdout.splitlines()
        assert lines[0] == "0 of 18 graded parts exported."
        assert lines[1] == "Finish notebook 02_ros_concepts: write robot_topic."
        assert lines[-1] == "Wrote my_solution.py."
        mine = duckie_in(clone, "mission", "--solution", "my_solution.py", "--no-animation")
        assert mine.returncode == 1
        assert mine.stderr.startswith("duckie: Finish notebook 05_odometry: write delta_phi")
    finally:
        (clone / "my_solution.py").unlink(missing_ok=True)


def test_make_run_does_what_the_readme_says(clone):
    readme = (clone / "README.md").read_text(encoding="utf-8")
    said = re.search(r"`make run` runs `\.venv/bin/(duckie [^`]+)`", readme)
    assert said is not None
    assert said[1] == RUN_COMMAND == "duckie mission --solution course --out runs/latest"
    # As a student types it: not inside another make (make test), which would add its own lines.
    alone = {name: value for name, value in os.environ.items() if "MAKE" not in name}
    planned = subprocess.run(
        ["make", "-n", "run"], cwd=clone, env=alone, capture_output=True, text=True, timeout=60,
        check=True,
    )  # fmt: skip
    assert planned.stdout.splitlines()[-1] == f".venv/bin/{RUN_COMMAND}"
    targets = subprocess.run(
        ["make", "help"], cwd=clone, env=alone, capture_output=True, text=True, timeout=60,
        check=True,
    )  # fmt: skip
    assert [line.split()[1] for line in targets.stdout.splitlines()] == [
        "lab",
        "run",
        "robot",
        "venv",
        "ros",
        "clean",
    ]


def test_every_duckie_command_of_the_readme_is_one_duckie_takes(clone):
    readme = (clone / "README.md").read_text(encoding="utf-8")
    commands = []
    for block in re.findall(r"```sh\n(.*?)```", readme, re.S):
        for line in block.splitlines():
            words = shlex.split(line.split(" | ")[0], comments=True)
            if words and words[0] in ("duckie", ".venv/bin/duckie"):
                commands.append(words[1:])
    assert len(commands) > 10
    parse_each = (
        "import json, sys\n"
        "from duckielib.tools.cli import _parser\n"
        "for args in json.loads(sys.argv[1]):\n"
        "    try:\n"
        "        _parser().parse_args(args)\n"
        "    except SystemExit:\n"
        "        print('refused:', ' '.join(args))\n"
    )
    result = subprocess.run(
        [sys.executable, "-S", "-c", parse_each, json.dumps(commands)],
        cwd=clone,
        env=student_env(clone),
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout == ""


def test_student_edition_refuses_a_folder_that_is_not_empty(tmp_path):
    (tmp_path / "notes.txt").write_text("mine\n")
    result = subprocess.run(
        [sys.executable, "-m", "duckielib.tools.cli", "student-edition", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 1
    assert result.stderr == (
        f"duckie: {tmp_path} is not empty: give a new or empty folder for the student edition.\n"
    )
    assert [path.name for path in tmp_path.iterdir()] == ["notes.txt"]
