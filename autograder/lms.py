"""Grades out to a learning management system: the gradebook import files of Canvas and Moodle.

``duckie feedback OUT --export canvas FILE --roster ROSTER`` writes what each LMS imports:

- **Canvas** (Grades > Import): the columns of Canvas's own gradebook export, ``Student``,
  ``ID``, ``SIS User ID``, ``SIS Login ID`` and ``Section``, then one column per assignment
  and one for the driving score, with a ``Points Possible`` row. The best roster is that very
  export (Grades > Export): its rows carry the ids Canvas matches students by, and an
  assignment column already there (``01_getting_started (1234)``) is filled under its own
  header, so the grades land in the existing assignment rather than a new one.
- **Moodle** (Grades > Import > CSV file): ``Email address`` and ``Username``, to map to the
  user fields of the same names, then one column per assignment and the driving score.

A roster is any CSV with a login column (``SIS Login ID``, ``login``, ``username``) or an
email column (``email``, ``Email address``); Canvas's export and Moodle's participant lists
both are. A student (the name their submission was graded under) is matched to the row whose
login, email, or email's part before the ``@`` is that name, letter case aside. Every roster
row gets a line; a student who submitted nothing, or nothing of an assignment, gets empty
cells (the LMS leaves them as they were). A graded student the roster does not list is said,
never dropped silently.

Scores are the points each assignment scored (answers waiting for a person count 0 until
graded), and the driving score out of 100.
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

from autograder.course import CourseError
from autograder.results import StudentResult, write_atomic

__all__ = ["FORMATS", "Export", "Roster", "export_grades", "read_roster"]

#: The LMSs whose import files are written.
FORMATS = ("canvas", "moodle")

#: The columns of a roster that may hold each field, lowercase, in order of preference.
_LOGIN = ("sis login id", "login", "username", "user name", "login id")
_EMAIL = ("email address", "email", "e-mail", "e-mail address", "sis email")
_CANVAS_IDS = ("student", "id", "sis user id", "sis login id", "section")

#: The driving score's column.
DRIVING = "Driving (out of 100)"

#: A Canvas column header that names an existing assignment: ``Name (1234)``.
_CANVAS_ASSIGNMENT = re.compile(r"^(?P<name>.*\S)\s+\((?P<id>\d+)\)$")


@dataclass
class Roster:
    """A class list, as read from a CSV file.

    Attributes:
        header: the file's columns, as written.
        rows: each student's row, by column (as written).
        login: the column that holds logins, or None.
        email: the column that holds email addresses, or None.
    """

    header: List[str]
    rows: List[Dict[str, str]]
    login: Optional[str]
    email: Optional[str]

    def keys(self, row: Dict[str, str]) -> List[str]:
        """What a student's name may be to match ``row``: login, email, email's local part."""
        found = []
        login = (row.get(self.login or "") or "").strip()
        email = (row.get(self.email or "") or "").strip()
        for key in (login, email, email.split("@")[0] if "@" in email else ""):
            if key:
                found.append(key.casefold())
        return found


def _column(header: Sequence[str], names: Iterable[str]) -> Optional[str]:
    by_name = {column.strip().casefold(): column for column in header}
    return next((by_name[name] for name in names if name in by_name), None)


def read_roster(path: Path) -> Roster:
    """Read a class list: a CSV with a login or an email column.

    Raises:
        CourseError: if the file cannot be read or has neither column (said in a sentence).
    """
    try:
        text = path.read_text(encoding="utf-8-sig")  # a spreadsheet's byte order mark dropped
    except (OSError, UnicodeDecodeError) as error:
        raise CourseError(f"Cannot read the roster {path}: {error}.") from None
    reader = csv.DictReader(io.StringIO(text))
    header = list(reader.fieldnames or [])
    login, email = _column(header, _LOGIN), _column(header, _EMAIL)
    if login is None and email is None:
        raise CourseError(
            f"The roster {path} has no column of logins ({', '.join(_LOGIN)}) or of email "
            f"addresses ({', '.join(_EMAIL)}); its columns are: {', '.join(header) or 'none'}."
        )
    rows = [
        row
        for row in reader
        if not (row.get(header[0]) or "").strip().casefold().startswith("points possible")
    ]
    return Roster(header, rows, login, email)


@dataclass
class Export:
    """What an export wrote.

    Attributes:
        path: the file written.
        format: ``"canvas"`` or ``"moodle"``.
        matched: graded students and the roster row each was matched to (its index).
        unmatched: graded students the roster does not list.
        without_submission: roster rows no graded student matched.
    """

    path: Path
    format: str
    matched: Dict[str, int] = field(default_factory=dict)
    unmatched: List[str] = field(default_factory=list)
    without_submission: List[int] = field(default_factory=list)

    def text(self) -> str:
        """What was written, and who is missing on either side, in sentences."""
        upload = {
            "canvas": "in Canvas, Grades > Import, then choose this file",
            "moodle": "in Moodle, Grades > Import > CSV file; map Email address to the user's "
            "email address, and each grade column to its grade item (or a new one)",
        }[self.format]
        lines = [
            f"wrote {self.path}: {len(self.matched)} students' grades for "
            f"{self.format.capitalize()}; upload it {upload}."
        ]
        if self.without_submission:
            lines.append(
                f"{len(self.without_submission)} students of the roster have no graded "
                "submission: their cells are empty, which the import leaves as they were."
            )
        if self.unmatched:
            lines.append(
                f"{len(self.unmatched)} graded students are not in the roster, so they are not "
                f"in the file: {', '.join(self.unmatched)}. Add them to the roster (their "
                "login or email), then export again."
            )
        return "\n".join(lines)


def _assignment_scores(
    results: Sequence[StudentResult], assignments: Sequence[str]
) -> Tuple[Dict[str, Dict[str, float]], Dict[str, float]]:
    """Each student's points by assignment, and each assignment's points possible."""
    scores: Dict[str, Dict[str, float]] = {}
    possible: Dict[str, float] = dict.fromkeys(assignments, 0.0)
    for result in results:
        mine = scores.setdefault(result.shown, {})
        if not result.complete:  # not graded (the grader's side stopped): empty, as without
            continue
        most: Dict[str, float] = {}
        for (assignment, _), (score, top) in result.cells.items():
            mine[assignment] = mine.get(assignment, 0.0) + score
            most[assignment] = most.get(assignment, 0.0) + top
        for assignment, top in most.items():
            possible[assignment] = max(possible.get(assignment, 0.0), top)
    return scores, possible


def _number(value: Optional[float]) -> str:
    return "" if value is None else f"{round(value, 2):g}"


def _matched(results: Sequence[StudentResult], roster: Roster, export: Export) -> None:
    """Match each graded student to a roster row (by login, email, or email's local part)."""
    by_key: Dict[str, int] = {}
    for index, row in enumerate(roster.rows):
        for key in roster.keys(row):
            by_key.setdefault(key, index)
    for result in results:
        found = by_key.get(result.shown.strip().casefold())
        if found is None:
            export.unmatched.append(result.shown)
        else:
            export.matched[result.shown] = found
    seen = set(export.matched.values())
    export.without_submission = [i for i in range(len(roster.rows)) if i not in seen]


def _canvas_ids(roster: Roster, row: Dict[str, str]) -> List[str]:
    """A row's Student, ID, SIS User ID, SIS Login ID and Section, as Canvas matches them."""
    fields = []
    for name in _CANVAS_IDS:
        column = _column(roster.header, [name])
        fields.append((row.get(column) or "") if column else "")
    login = (row.get(roster.login) or "") if roster.login else ""
    fields[0] = fields[0] or login
    fields[3] = fields[3] or login
    return fields


def export_grades(
    results: Sequence[StudentResult],
    assignments: Sequence[str],
    roster_path: Path,
    kind: str,
    path: Path,
) -> Export:
    """Write ``path``, the gradebook import file of ``kind`` (``canvas`` or ``moodle``).

    Args:
        results: the class's results (``write_grades`` gives them).
        assignments: the assignments, in the course's order.
        roster_path: the class list (see the module's text).
        kind: the LMS.
        path: the file to write (replaced whole, never left half-written).

    Raises:
        CourseError: for an unknown LMS, or a roster that cannot be read.
    """
    if kind not in FORMATS:
        raise CourseError(f"Grades can be exported for {' or '.join(FORMATS)}, not {kind!r}.")
    roster = read_roster(roster_path)
    export = Export(path, kind)
    _matched(results, roster, export)
    student_of = {index: name for name, index in export.matched.items()}
    scores, possible = _assignment_scores(results, assignments)
    driving = {result.shown: result.driving_score for result in results}
    any_driving = any(value is not None for value in driving.values())
    existing = {}  # an assignment's existing Canvas column, by the assignment's name
    for column in roster.header:
        found = _CANVAS_ASSIGNMENT.match(column.strip())
        if found and found.group("name") in assignments:
            existing[found.group("name")] = column
    grade_columns = [existing.get(name, name) for name in assignments]
    grade_columns += [DRIVING] if any_driving else []

    buffer = io.StringIO()
    writer = csv.writer(buffer)
    if kind == "canvas":
        writer.writerow(["Student", "ID", "SIS User ID", "SIS Login ID", "Section", *grade_columns])
        writer.writerow(
            ["Points Possible", "", "", "", ""]
            + [_number(possible.get(name)) for name in assignments]
            + (["100"] if any_driving else [])
        )
    else:
        writer.writerow(["Email address", "Username", *grade_columns])
    for index, row in enumerate(roster.rows):
        student = student_of.get(index)
        mine = scores.get(student, {}) if student is not None else {}
        grades = [_number(mine.get(name)) if student is not None else "" for name in assignments]
        if any_driving:
            grades.append(_number(driving.get(student)) if student is not None else "")
        if kind == "canvas":
            writer.writerow([*_canvas_ids(roster, row), *grades])
        else:
            email = (row.get(roster.email) or "") if roster.email else ""
            login = (row.get(roster.login) or "") if roster.login else ""
            writer.writerow([email, login, *grades])
    write_atomic(path, buffer.getvalue())
    return export
