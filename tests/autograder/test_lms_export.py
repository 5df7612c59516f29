"""Grades out to Canvas and Moodle: the gradebook import files, students matched by a roster."""

from __future__ import annotations

import csv

import pytest

from autograder.course import CourseError
from autograder.driving import Driving
from autograder.lms import DRIVING, export_grades, read_roster
from autograder.results import StudentResult
from duckielib.tools.cli import main

ASSIGNMENTS = ["01_getting_started", "02_ros_concepts"]


def driving(score):
    return Driving(score=score)


@pytest.fixture
def results():
    alice = StudentResult(
        "alice",
        cells={
            ("01_getting_started", "a"): (2.0, 2.0),
            ("01_getting_started", "b"): (1.0, 3.0),
            ("02_ros_concepts", "c"): (4.5, 5.0),
        },
        missions={"square_then_circle": driving(90.0), "d_shape": driving(70.0)},
    )
    bob = StudentResult(
        "bob.smith",
        cells={("01_getting_started", "a"): (0.0, 2.0), ("01_getting_started", "b"): (3.0, 3.0)},
        missions={"square_then_circle": driving(40.0)},
    )
    dave = StudentResult("dave", cells={("01_getting_started", "a"): (2.0, 2.0)})
    return [alice, bob, dave]


def rows(path):
    with path.open(newline="", encoding="utf-8") as file:
        return list(csv.reader(file))


def test_canvas_import_fills_the_rosters_rows_and_its_existing_assignment(results, tmp_path):
    roster = tmp_path / "canvas_export.csv"
    roster.write_text(  # Canvas's own gradebook export, with its byte order mark
        "\ufeffStudent,ID,SIS User ID,SIS Login ID,Section,"
        "01_getting_started (5501),Current Score\n"
        "    Points Possible,,,,,5,\n"
        '"Liddell, Alice",101,2001,alice,Lab A,,\n'
        '"Smith, Bob",102,2002,BOB.SMITH,Lab B,,\n'
        '"Lee, Carol",103,2003,carol,Lab A,,\n',
        encoding="utf-8",
    )
    target = tmp_path / "canvas_import.csv"
    export = export_grades(results, ASSIGNMENTS, roster, "canvas", target)
    assert rows(target) == [
        [
            *["Student", "ID", "SIS User ID", "SIS Login ID", "Section"],
            *["01_getting_started (5501)", "02_ros_concepts", DRIVING],
        ],
        ["Points Possible", "", "", "", "", "5", "5", "100"],
        ["Liddell, Alice", "101", "2001", "alice", "Lab A", "3", "4.5", "80"],
        ["Smith, Bob", "102", "2002", "BOB.SMITH", "Lab B", "3", "", "40"],  # no 02 handed in
        ["Lee, Carol", "103", "2003", "carol", "Lab A", "", "", ""],  # nothing handed in
    ]
    assert export.unmatched == ["dave"]
    assert export.without_submission == [2]
    said = export.text()
    assert said.startswith(f"wrote {target}: 2 students' grades for Canvas; upload it in Canvas")
    assert "1 students of the roster have no graded submission" in said
    assert "1 graded students are not in the roster, so they are not in the file: dave." in said


def test_moodle_import_matches_by_email_and_keeps_every_roster_row(results, tmp_path):
    roster = tmp_path / "participants.csv"
    roster.write_text(  # a Moodle participants list
        "First name,Last name,Username,Email address\n"
        "Alice,Liddell,aliddell,alice@uni.example\n"
        "Bob,Smith,bsmith,bob.smith@uni.example\n"
        "Dave,Jones,djones,dave@uni.example\n",
        encoding="utf-8",
    )
    target = tmp_path / "moodle_import.csv"
    export = export_grades(results, ASSIGNMENTS, roster, "moodle", target)
    assert rows(target) == [
        ["Email address", "Username", "01_getting_started", "02_ros_concepts", DRIVING],
        ["alice@uni.example", "aliddell", "3", "4.5", "80"],
        ["bob.smith@uni.example", "bsmith", "3", "", "40"],
        ["dave@uni.example", "djones", "2", "", ""],  # graded, never drove
    ]
    assert export.unmatched == []
    assert "map Email address to the user's email address" in export.text()


def test_a_roster_without_logins_or_emails_and_a_bad_export_are_said(tmp_path, capsys):
    roster = tmp_path / "names.csv"
    roster.write_text("First name,Last name\nAlice,Liddell\n", encoding="utf-8")
    with pytest.raises(CourseError, match=r"has no column of logins .* its columns are: First"):
        read_roster(roster)
    assert main(["feedback", str(tmp_path), "--export", "blackboard", "out.csv"]) == 1
    assert "--export takes canvas or moodle, not 'blackboard'." in capsys.readouterr().err
    assert main(["feedback", str(tmp_path), "--export", "canvas", "out.csv"]) == 1
    assert "--export needs --roster ROSTER.csv" in capsys.readouterr().err
    assert not (tmp_path / "out.csv").exists()
