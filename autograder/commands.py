"""The instructors' ``duckie`` commands: release, grade, formgrade, feedback, student-edition.

``duckie`` finds them through the entry point group ``duckie.commands`` (``pyproject.toml``), so
``duckielib``, which students receive, never imports ``autograder``; where ``autograder`` is not
installed, ``duckie`` simply has no instructor commands. Each handler turns its command line into
a call of this package and prints what a person needs; errors are sentences
(:class:`duckielib.errors.DuckielibError`), which ``duckie`` prints without a traceback.
"""

from __future__ import annotations

import argparse
import os
import sys
from typing import Any

from duckielib.errors import DuckielibError

__all__ = ["add_commands"]


def _release(args: argparse.Namespace) -> int:
    from autograder.course import ROOT, compare_release, release_course

    if args.check:
        differences = compare_release()
        if differences:
            for line in differences:
                print(line)
            print("course/ is stale: run 'duckie release' and commit course/.", file=sys.stderr)
            return 1
        print("course/ is identical to a fresh release of solutions/.")
        return 0
    released = release_course()
    for path in released:
        print(f"released {path.relative_to(ROOT)}")
    print(f"{len(released)} notebooks in course/; commit solutions/ and course/ together.")
    return 0


def _grade(args: argparse.Namespace) -> int:
    import warnings
    from pathlib import Path

    from autograder.grade import find_submissions, grade_class
    from autograder.sandbox import check_sandbox

    # nbgrader's own gradebook code warns about its SQLAlchemy session: nothing to act on.
    warnings.filterwarnings("ignore", module="nbgrader")

    submissions = Path(args.submissions)
    if not submissions.is_dir():
        raise DuckielibError(
            f"There is no folder {submissions}: give the folder that holds one folder (or "
            ".zip) per student."
        )
    if args.jobs < 1:
        raise DuckielibError(f"--jobs must be 1 or more, not {args.jobs}.")
    students, skipped = find_submissions(submissions)
    if not students:
        raise DuckielibError(
            f"No submission was found in {submissions}: it must hold one folder (or .zip) per "
            "student, named after them" + (f" (skipped: {'; '.join(skipped)})." if skipped else ".")
        )
    if args.no_sandbox:
        print("duckie: grading WITHOUT a sandbox: student code runs with your rights.")
    else:
        check_sandbox()
    try:
        results = grade_class(
            submissions,
            Path(args.out),
            jobs=args.jobs,
            use_sandbox=not args.no_sandbox,
            names=args.assignment or None,
            progress=lambda line: print(line, flush=True),
            driving=not args.no_driving,
            scheduler=args.scheduler,
        )
    except KeyboardInterrupt:
        print(
            "duckie: interrupted. The students graded so far are in "
            f"{Path(args.out) / 'grades.csv'}; run the same command again to grade the others.",
            file=sys.stderr,
        )
        return 130
    troubled = [result for result in results if result.problems]
    stopped = [result.student for result in results if not result.complete]
    if stopped:
        print(
            f"duckie: the grading of {len(stopped)} students stopped ({', '.join(stopped[:5])}"
            f"{', ...' if len(stopped) > 5 else ''}); run the same command again to retry them."
        )
    print(
        f"graded {len(results)} students ({len(troubled)} with problems): "
        f"{Path(args.out) / 'grades.csv'}, feedback pages in {Path(args.out) / 'feedback'}/"
    )
    return 0


def _formgrade(args: argparse.Namespace) -> int:
    from pathlib import Path

    from autograder.formgrade import command, prepare

    work = prepare(Path(args.out))
    argv = command(work, args.lab_args)
    print(f"duckie: opening nbgrader's Formgrader on {work} (Ctrl-C stops it).", flush=True)
    # JupyterLab as instructors start it: nbgrader's tools on, the students' settings off.
    env = {key: value for key, value in os.environ.items() if key != "JUPYTER_CONFIG_PATH"}
    os.chdir(work)
    os.execve(argv[0], argv, env)
    return 0  # pragma: no cover - execve does not return


def _feedback(args: argparse.Namespace) -> int:
    import warnings
    from pathlib import Path

    from autograder.course import CourseError
    from autograder.grade import write_grades

    warnings.filterwarnings("ignore", module="nbgrader")
    if args.export and args.export[0].lower() not in ("canvas", "moodle"):
        raise CourseError(f"--export takes canvas or moodle, not {args.export[0]!r}.")
    if args.export and not args.roster:
        raise CourseError(
            "--export needs --roster ROSTER.csv: the class list the LMS knows your students by "
            "(for Canvas, its gradebook export)."
        )
    results = write_grades(Path(args.out))
    waiting = sum(len(result.to_grade) for result in results)
    print(
        f"wrote {Path(args.out) / 'grades.csv'} and {len(results)} feedback pages in "
        f"{Path(args.out) / 'feedback'}/; {waiting} answers still wait for a grade."
    )
    if args.export:
        from autograder.course import assignments
        from autograder.lms import export_grades

        kind, target = args.export
        export = export_grades(
            results, assignments(), Path(args.roster), kind.lower(), Path(target)
        )
        print(export.text())
        return 1 if export.unmatched else 0
    return 0


def _student_edition(args: argparse.Namespace) -> int:
    from pathlib import Path

    from autograder.edition import build_edition

    edition = build_edition(Path(args.out), progress=lambda line: print(line, flush=True))
    print(edition.text())
    return 0


def _hub_users(hubs: Any, hub: Any, args: argparse.Namespace) -> int:
    from pathlib import Path

    if args.roster is None and not args.instructor:
        raise DuckielibError("Give a roster, an --instructor, or both.")
    roster = Path(args.roster) if args.roster else None
    created = hubs.create_accounts(
        hub, roster, args.instructor or [], progress=lambda line: print(line, flush=True)
    )
    print(
        f"{len(hub.students)} students and {len(hub.instructors)} instructors may log in to "
        f"the hub in {hub.root}."
    )
    if created:
        print(
            f"The first passwords of the {len(created)} new accounts: "
            f"{hub.root / 'passwords.csv'} (readable by root only)."
        )
    return 0


def _hub_start(hubs: Any, hub: Any, args: argparse.Namespace) -> int:
    hubs.prepare(
        hub,
        port=args.port,
        ip=args.ip,
        python=args.python,
        progress=lambda line: print(line, flush=True),
    )
    command = hubs.hub_command(hub)
    url = f"{'https' if hubs.has_certificate(hub) else 'http'}://{args.ip}:{args.port}"
    print(
        f"the hub: {url}/ (Ctrl-C stops it); Formgrader, for instructors: "
        f"{url}/services/formgrader/"
    )
    if hubs.plain_http(hub, args.ip):
        print(
            f"warning: the hub serves plain HTTP on {args.ip}: passwords would cross the network "
            "in the clear. Give it a certificate in "
            f"{hub.root / 'jupyterhub_config.local.py'} (c.JupyterHub.ssl_cert and "
            "c.JupyterHub.ssl_key), or put a proxy with HTTPS in front and serve on 127.0.0.1."
        )
    if args.prepare_only:
        print(f"prepared; start it with: cd {hub.state} && {' '.join(command)}")
        return 0
    sys.stdout.flush()
    os.chdir(hub.state)
    os.execv(command[0], command)
    return 0  # not reached: the hub runs in this process


def _hub_exchange(hubs: Any, hub: Any, args: argparse.Namespace) -> int:
    from pathlib import Path

    if args.hub_command == "release":
        notebooks = hubs.release(hub, args.assignment, due=args.due)
        print(
            f"released {args.assignment} ({', '.join(notebooks)}): students fetch it in their "
            "Assignment List."
        )
        return 0
    if args.hub_command == "collect":
        students = hubs.collect(hub, args.assignment, before_due=args.before_due)
        submitted = hub.course / "submitted"
        missing = sorted(set(hub.students) - set(students))
        none = f"; none from {', '.join(missing)}" if missing else ""
        print(f"{len(students)} submissions of {args.assignment} are in {submitted}{none}.")
        late = hubs.lateness(hub, args.assignment)
        if late:
            print(
                "after the due date: "
                + ", ".join(f"{name} ({_duration(seconds)} late)" for name, seconds in late.items())
                + "."
            )
        print(
            f"grade them with: duckie grade {submitted} --out {hub.grading} "
            f"--assignment {args.assignment}"
        )
        return 0
    grading = Path(args.grading) if args.grading else None
    returned = hubs.return_feedback(hub, args.assignment, grading)
    print(
        f"feedback on {args.assignment} returned to {len(returned.returned)} students: they "
        "fetch it in their Assignment List."
    )
    if returned.not_graded:
        print(
            f"not graded yet, so nothing returned to: {', '.join(returned.not_graded)} (run "
            f"duckie grade, then duckie feedback {grading or hub.grading})."
        )
        return 1
    return 0


def _hub_image(hubs: Any, hub: Any, args: argparse.Namespace) -> int:
    from pathlib import Path

    out = hubs.write_image(
        Path(args.out),
        args.name,
        hub=hub,
        authenticator=args.authenticator,
        progress=lambda line: print(line, flush=True),
    )
    print(
        f"Wrote {out}: build the image there (docker build -t {args.name}:TAG .; the tag is in "
        f"its Dockerfile), push it, then install the hub with {out / 'values.yaml'}."
    )
    return 0


def _duration(seconds: float) -> str:
    """A delay in words: 40 s, 12 min, 3.5 h, 2.0 days."""
    if seconds < 60:
        return f"{seconds:.0f} s"
    if seconds < 3600:
        return f"{seconds / 60:.0f} min"
    if seconds < 86400:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.1f} days"


def _hub(args: argparse.Namespace) -> int:
    from pathlib import Path

    from autograder import hub as hubs

    hub = hubs.Hub.load(Path(args.hub))
    if args.hub_command == "image":
        return _hub_image(hubs, hub, args)
    if args.hub_command == "users":
        return _hub_users(hubs, hub, args)
    if args.hub_command == "start":
        return _hub_start(hubs, hub, args)
    return _hub_exchange(hubs, hub, args)


def add_commands(commands: argparse._SubParsersAction) -> None:
    """Add the instructors' commands: release, grade, formgrade, feedback, hub, student-edition."""
    _add_release(commands)
    _add_grade(commands)
    _add_formgrade(commands)
    _add_feedback(commands)
    _add_hub(commands)
    _add_student_edition(commands)


def _add_release(commands: argparse._SubParsersAction) -> None:
    release = commands.add_parser(
        "release", help="regenerate course/ from solutions/ with nbgrader (instructors)"
    )
    release.add_argument(
        "--check", action="store_true", help="only say whether course/ is up to date"
    )
    release.set_defaults(handler=_release)


def _add_grade(commands: argparse._SubParsersAction) -> None:
    grade = commands.add_parser(
        "grade", help="autograde a class: nbgrader, a sandbox per submission, in parallel"
    )
    grade.add_argument("submissions", help="a folder with one folder (or .zip) per student")
    grade.add_argument("--out", required=True, help="where grades.csv and the work go")
    grade.add_argument(
        "--jobs",
        type=int,
        default=1,
        help="students graded at once on this machine (workers of the local Dask cluster)",
    )
    grade.add_argument(
        "--scheduler",
        help="grade on a running Dask cluster instead, given its scheduler's address "
        "(tcp://HOST:8786); its workers need the course's environment and bubblewrap",
    )
    grade.add_argument(
        "--assignment", action="append", help="grade only this assignment (repeatable)"
    )
    grade.add_argument(
        "--no-driving",
        action="store_true",
        help="skip the driving score (each student's code driving the mission)",
    )
    grade.add_argument(
        "--no-sandbox",
        action="store_true",
        help="run student code without bubblewrap (only where it cannot be installed)",
    )
    grade.set_defaults(handler=_grade)


def _add_formgrade(commands: argparse._SubParsersAction) -> None:
    formgrade = commands.add_parser(
        "formgrade",
        help="grade the answers in words of a graded class in nbgrader's Formgrader (JupyterLab)",
    )
    formgrade.add_argument("out", help="the folder `duckie grade --out` wrote")
    formgrade.add_argument(
        "lab_args", nargs="*", help="more JupyterLab options, after -- (-- --port=8890)"
    )
    formgrade.set_defaults(handler=_formgrade)


def _add_feedback(commands: argparse._SubParsersAction) -> None:
    feedback = commands.add_parser(
        "feedback",
        help="write grades.csv and the feedback pages again, with the grades and comments "
        "given in Formgrader (runs nothing)",
    )
    feedback.add_argument("out", help="the folder `duckie grade --out` wrote")
    feedback.add_argument(
        "--export",
        nargs=2,
        metavar=("LMS", "FILE"),
        help="also write FILE, the gradebook import of LMS (canvas or moodle): each "
        "assignment's points and the driving score, by student",
    )
    feedback.add_argument(
        "--roster",
        help="with --export: the class list, a CSV with a login or email column (for Canvas, "
        "its gradebook export; for Moodle, its participants list)",
    )
    feedback.set_defaults(handler=_feedback)


def _add_hub(commands: argparse._SubParsersAction) -> None:
    """``duckie hub`` and its commands: users, start, release, collect, return, image."""
    hub = commands.add_parser(
        "hub",
        help="a class hub on this machine: JupyterHub with nbgrader's exchange (as root)",
    )
    hub_commands = hub.add_subparsers(dest="hub_command", required=True, metavar="COMMAND")
    place = argparse.ArgumentParser(add_help=False)
    place.add_argument(
        "--hub", default="/srv/duckiebot-hub", help="the hub's folder (default /srv/duckiebot-hub)"
    )
    users = hub_commands.add_parser(
        "users",
        parents=[place],
        help="a Unix account for each student of a roster (and each --instructor)",
    )
    users.add_argument(
        "roster", nargs="?", help="a CSV with a login or an email column, one row per student"
    )
    users.add_argument("--instructor", action="append", help="an instructor's account (repeatable)")
    start = hub_commands.add_parser(
        "start", parents=[place], help="install what the hub needs, then run it"
    )
    start.add_argument("--port", type=int, default=8000, help="the hub's port (default 8000)")
    start.add_argument(
        "--ip",
        default="127.0.0.1",
        help="the address to serve on (default 127.0.0.1: this machine only; 0.0.0.0: every "
        "network, then over HTTPS: a certificate in jupyterhub_config.local.py or a proxy "
        "with HTTPS in front, see the README)",
    )
    start.add_argument("--python", help="the Python 3.11+ the students' environment is made with")
    start.add_argument(
        "--prepare-only", action="store_true", help="install and configure, do not run"
    )
    for name, text in (
        ("release", "put course/ASSIGNMENT into the exchange for students to fetch"),
        ("collect", "gather the latest submissions of ASSIGNMENT for grading"),
        ("return", "hand each student their feedback page on ASSIGNMENT"),
    ):
        command = hub_commands.add_parser(name, parents=[place], help=text)
        command.add_argument("assignment", help="an assignment of course/ (05_odometry)")
    hub_commands.choices["release"].add_argument(
        "--due", help="its due date, as nbgrader reads it ('2026-12-01 17:00 Europe/Zurich')"
    )
    hub_commands.choices["collect"].add_argument(
        "--before-due",
        action="store_true",
        help="each student's last submission before the due date, not their latest",
    )
    hub_commands.choices["return"].add_argument(
        "--grading", help="where duckie grade wrote the grades (HUB/grading)"
    )
    image = hub_commands.add_parser(
        "image",
        parents=[place],
        help="beyond one machine: the students' image and Zero to JupyterHub's values.yaml",
    )
    image.add_argument("out", help="a new folder for the Dockerfile, its files and values.yaml")
    image.add_argument(
        "--name",
        required=True,
        help="the image's name in your registry (registry.example.org/duckiebot-course)",
    )
    image.add_argument(
        "--authenticator",
        default="nativeauthenticator.NativeAuthenticator",
        help="the hub's authenticator class (default: NativeAuthenticator: students sign up "
        "under their roster login and an instructor authorizes them; or your LMS's LTI 1.3 "
        "or OAuth authenticator)",
    )
    hub.set_defaults(handler=_hub)


def _add_student_edition(commands: argparse._SubParsersAction) -> None:
    edition = commands.add_parser(
        "student-edition",
        help="write what students receive (course/, the library, robot_nodes/; nothing of "
        "solutions/, tests/ or autograder/) as a new git repository to push for a class",
    )
    edition.add_argument("out", help="a new or empty folder")
    edition.set_defaults(handler=_student_edition)
