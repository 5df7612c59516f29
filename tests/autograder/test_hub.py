"""A class on the hub, in Chromium: the students fetch, work and submit in their JupyterLab, the
instructor collects, grades and returns, and each student reads their own feedback, not another's.

Everything is real: JupyterHub with the machine's accounts (PAM; ``duckie hub users`` makes
them from a Canvas roster), configurable-http-proxy from npm, each student's JupyterLab running
as their Unix user from the students' Python that ``duckie hub start`` installs, nbgrader's
exchange, the sandboxed grader and Formgrader as a hub service, run as the hub's own account.
An instructor then tries, in the browser and through the servers' APIs, every way from the hub
to a root process. The accounts and the hub's folder are removed afterwards. Making accounts
and switching users needs root.
"""

# Over 600 lines: one real hub (minutes to start) serves every test here, so the class's whole
# loop and what students and instructors can reach through it share this module.

from __future__ import annotations

import csv
import datetime
import io
import json
import os
import pwd
import re
import secrets
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List

import pytest
from pace import seconds

from autograder.bench_hub import free_ports
from autograder.course import ROOT
from autograder.hub import HubError, account_name, reachable_by_others, roster_accounts
from autograder.hub_formgrader import NO_KERNEL, service_account, share, share_grading

DUCKIE = str(Path(sys.executable).parent / "duckie")
ASSIGNMENT = "02_ros_concepts"
NOTEBOOK = f"{ASSIGNMENT}/{ASSIGNMENT}.ipynb"

#: What the students type: ada's first try and bo's only one are wrong (the name is not built
#: from the robot's), ada's second is right.
WRONG = """import os


def robot_topic(relative_name):
    return relative_name
"""
RIGHT = """import os


def robot_topic(relative_name):
    return "/" + os.environ["VEHICLE_NAME"] + "/" + relative_name
"""
ANSWERS = {
    "ada": "I listed the topics and kept /duckiebot/wheels_driver_node/wheels_cmd (ada).",
    "bo": "The command topic is /duckiebot/car_cmd_switch_node/cmd (bo).",
}
COMMENT = "Right topic; show the printout that found it."

as_root = pytest.mark.skipif(
    os.geteuid() != 0,
    reason="the hub makes Unix accounts and runs each student's server as them: run as root",
)


# -- the parts that need no hub -------------------------------------------------------------------


@pytest.mark.parametrize(
    ("key", "name"),
    [("ada", "ada"), ("Ada.Lovelace@uni.edu", "ada_lovelace"), ("b-o_2", "b-o_2")],
)
def test_a_roster_login_or_email_becomes_an_account_name(key, name):
    assert account_name(key) == name


@pytest.mark.parametrize("key", ["Ada Lovelace", "2ada", "x" * 33, "élodie"])
def test_a_name_that_cannot_be_an_account_is_said_with_what_to_change(key):
    with pytest.raises(HubError, match="cannot be a Unix account name: use a login"):
        account_name(key)


def test_a_roster_gives_each_student_one_account_and_refuses_two_sharing_one(tmp_path):
    roster = tmp_path / "roster.csv"
    roster.write_text(
        "\ufeffStudent,ID,SIS User ID,SIS Login ID,Section\n"
        "    Points Possible,,,,\n"
        "Ada,1,s1,ada,A\nBo,2,s2,bo,A\n",
        encoding="utf-8",
    )
    assert roster_accounts(roster) == ["ada", "bo"]
    roster.write_text("Email address\nada@uni.edu\nADA@other.edu\n", encoding="utf-8")
    with pytest.raises(HubError, match=r"would share the account 'ada' \(row 3\)"):
        roster_accounts(roster)


def test_reachable_by_others_looks_at_every_folder_above(tmp_path):
    inner = tmp_path / "a" / "b"
    inner.mkdir(parents=True)
    for folder in (inner, tmp_path / "a", tmp_path):
        folder.chmod(0o755)
    opened = all(folder.stat().st_mode & 0o001 for folder in tmp_path.parents)
    assert reachable_by_others(inner) is opened
    inner.chmod(0o711)  # not listed, but a file's known name still opens it
    assert reachable_by_others(inner) is opened
    (tmp_path / "a").chmod(0o750)
    assert reachable_by_others(inner) is False


@as_root
def test_a_roster_login_that_is_a_system_account_is_refused(tmp_path):
    from autograder.hub import Hub, create_accounts

    roster = tmp_path / "roster.csv"
    roster.write_text("login\nada\ndaemon\n", encoding="utf-8")
    with pytest.raises(HubError, match=r"daemon is a system account of this machine \(uid 1\)"):
        create_accounts(Hub(tmp_path / "hub"), roster)
    assert not (tmp_path / "hub" / "passwords.csv").exists()


@pytest.mark.parametrize(
    ("folder", "name"),
    [
        ("/srv/duckiebot-hub", "duckiebot-hub"),
        ("/srv/Class 2026", "class-2026"),
        ("/srv/2026", "hub-2026"),
        ("/srv/" + "x" * 40, "x" * 32),
    ],
)
def test_the_hubs_account_is_named_after_its_folder(folder, name):
    assert service_account(Path(folder)) == name


def test_the_hub_says_its_default_address_and_https_for_every_network():
    shown = " ".join(_run(DUCKIE, "hub", "start", "--help").stdout.split())
    assert "default 127.0.0.1: this machine only" in shown
    assert "then over HTTPS" in shown


@as_root
def test_the_grading_folder_is_roots_and_the_accounts_and_roots_new_files_are_shared(tmp_path):
    group = 65534  # nogroup: only the group's number matters here
    tmp_path.chmod(0o755)
    grading = tmp_path / "grading"
    work = grading / "work"
    work.mkdir(parents=True)
    # What another user planted where root will write: a link to a file of root's elsewhere.
    secret = tmp_path / "secret"
    secret.write_text("root's")
    secret.chmod(0o600)
    (work / "release").symlink_to(secret)
    share_grading(grading, group)
    assert [
        (path.name, oct(path.stat().st_mode & 0o7777), path.stat().st_uid, path.stat().st_gid)
        for path in (grading, work, work / "gradebook.db", work / "release")
    ] == [
        ("grading", "0o2750", 0, group),
        ("work", "0o3770", 0, group),
        ("gradebook.db", "0o660", 0, group),
        ("release", "0o2755", 0, group),
    ]
    assert oct(secret.stat().st_mode & 0o777) == "0o600"
    # root writes as `duckie grade` does (0600); the account's own files and links stay theirs.
    notebook = work / "autograded" / "ada" / "02" / "02.ipynb"
    notebook.parent.mkdir(parents=True)
    notebook.write_text("{}")
    notebook.chmod(0o600)
    theirs = work / "theirs.txt"
    theirs.write_text("x")
    os.chown(theirs, 65534, group)
    theirs.chmod(0o600)
    os.link(secret, work / "linked")  # two names: never changed
    (work / "pointer").symlink_to(secret)
    assert share(work, group) >= 1
    assert oct(notebook.stat().st_mode & 0o777) == "0o640"
    assert notebook.parent.stat().st_mode & 0o2050 == 0o2050
    assert oct(theirs.stat().st_mode & 0o777) == "0o600"
    assert (secret.stat().st_gid, oct(secret.stat().st_mode & 0o777)) == (0, "0o600")
    assert share(work, group) == 0  # nothing left to share


# -- a class on a real hub ----------------------------------------------------------------------


def _run(*argv: str, check: bool = True) -> subprocess.CompletedProcess:
    done = subprocess.run(argv, capture_output=True, text=True, check=False, timeout=900)
    if check and done.returncode != 0:
        raise AssertionError(
            f"{' '.join(argv)} exited {done.returncode}:\n{done.stdout}{done.stderr}"
        )
    return done


def _as(user: str, command: str) -> subprocess.CompletedProcess:
    """Run a shell command as ``user``, as they could from a terminal of their JupyterLab."""
    return _run("runuser", "-u", user, "--", "sh", "-c", command, check=False)


@dataclass
class Class:
    url: str
    root: Path
    names: Dict[str, str]  # ada -> ada1f2e
    passwords: Dict[str, str]
    roster: Path
    log: Path
    pages: Dict[str, object] = field(default_factory=dict)

    def duckie(self, *argv: str, check: bool = True) -> subprocess.CompletedProcess:
        return _run(DUCKIE, *argv, check=check)

    def hub(self, *argv: str, check: bool = True) -> subprocess.CompletedProcess:
        return self.duckie("hub", argv[0], *argv[1:], "--hub", str(self.root), check=check)


def _wait_for(url: str, process: subprocess.Popen, log: Path, seconds: float = 600) -> None:
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if process.poll() is not None:
            raise AssertionError(
                f"the hub stopped ({process.returncode}):\n{log.read_text()[-3000:]}"
            )
        try:
            with urllib.request.urlopen(url, timeout=2) as answer:
                if answer.status == 200:
                    return
        except OSError:
            time.sleep(1)
    raise AssertionError(f"the hub did not answer within {seconds} s:\n{log.read_text()[-3000:]}")


@pytest.fixture(scope="module")
def klass(tmp_path_factory):
    if os.geteuid() != 0:
        pytest.skip("the hub makes Unix accounts and runs servers as them: run as root")
    if shutil.which("npm") is None and shutil.which("configurable-http-proxy") is None:
        pytest.skip("JupyterHub's proxy comes from npm: install Node.js and npm")
    suffix = secrets.token_hex(2)
    names = {who: f"{who}{suffix}" for who in ("ada", "bo", "cy", "prof")}
    here = tmp_path_factory.mktemp("hub")
    roster = here / "export.csv"
    rows = [
        "Student,ID,SIS User ID,SIS Login ID,Section",
        "    Points Possible,,,,",
        *(
            f"{who.title()} Test,{i},sis{i},{names[who]},A"
            for i, who in enumerate(("ada", "bo", "cy"))
        ),
    ]
    roster.write_text("\n".join(rows) + "\n", encoding="utf-8")
    root = Path(tempfile.mkdtemp(prefix="duckie-hub-", dir="/srv"))
    # Only solutions/ is closed: the rest of the repository stays as the other tests need it
    # (the sandboxes and the nodes run as other users, and read the library and .venv).
    solutions = ROOT / "solutions"
    mode = solutions.stat().st_mode & 0o7777
    process = None
    try:
        done = _run(DUCKIE, "hub", "users", str(roster), "--instructor", names["prof"],
                    "--hub", str(root))  # fmt: skip
        assert "3 students and 1 instructors may log in" in done.stdout
        passwords = dict(csv.reader(io.StringIO((root / "passwords.csv").read_text())))
        assert (root / "passwords.csv").stat().st_mode & 0o777 == 0o600
        assert (root / "hub.json").stat().st_mode & 0o777 == 0o600
        # A repository every user can read is refused: its solutions/ holds the answers.
        solutions.chmod(mode | 0o005)
        if reachable_by_others(solutions):
            refused = _run(DUCKIE, "hub", "start", "--hub", str(root), check=False)
            assert refused.returncode == 1
            assert "can read" in refused.stderr
            assert "chmod o-rwx" in refused.stderr
        solutions.chmod(mode & ~0o007)
        port = free_ports(4)
        log = here / "hub.log"
        with log.open("w") as output:
            process = subprocess.Popen(
                [DUCKIE, "hub", "start", "--hub", str(root), "--port", str(port)],
                stdout=output,
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )
        url = f"http://127.0.0.1:{port}"
        _wait_for(f"{url}/hub/api", process, log)
        yield Class(url, root, names, passwords, roster, log)
    finally:
        if process is not None and process.poll() is None:
            os.killpg(process.pid, signal.SIGTERM)
            try:
                process.wait(30)
            except subprocess.TimeoutExpired:
                os.killpg(process.pid, signal.SIGKILL)
                process.wait()
        accounts = [*names.values(), service_account(root)]
        for name in accounts:
            subprocess.run(["pkill", "-KILL", "-u", name], check=False, capture_output=True)
        time.sleep(0.5)
        for name in accounts:
            subprocess.run(["userdel", "--remove", name], check=False, capture_output=True)
        shutil.rmtree(root, ignore_errors=True)
        solutions.chmod(mode)


def _login(browser, klass: Class, who: str):
    if who in klass.pages:
        return klass.pages[who]
    context = browser.new_context(viewport={"width": 1400, "height": 900})
    page = context.new_page()
    page.set_default_timeout(seconds(60) * 1000)
    page.goto(f"{klass.url}/hub/login")
    page.fill("#username_input", klass.names[who])
    page.fill("#password_input", klass.passwords[klass.names[who]])
    page.click("#login_submit")
    page.wait_for_selector("#jp-main-dock-panel", timeout=seconds(180) * 1000)
    klass.pages[who] = page
    return page


def _assignment_list(page):
    page.get_by_text("Nbgrader", exact=True).click()
    page.locator(".lm-Menu-itemLabel", has_text="Assignment List").click()
    page.locator("#released_assignments_list").wait_for()
    return page


def _fetch(page) -> None:
    """Fetch the assignment in the Assignment List, as a student does."""
    _assignment_list(page)
    released = page.locator("#released_assignments_list .list_item", has_text=ASSIGNMENT)
    released.locator("button", has_text="Fetch").click()
    page.locator("#fetched_assignments_list .list_item", has_text=ASSIGNMENT).first.wait_for()


def _type_into_notebook(page, klass: Class, who: str, code: str, answer: str) -> None:
    """Open the fetched notebook, replace the exercise and the answer, save."""
    page.goto(f"{klass.url}/user/{klass.names[who]}/lab/tree/{NOTEBOOK}")
    page.locator(".jp-Notebook .jp-Cell").first.wait_for()
    cell = page.locator(".jp-CodeCell", has_text="def robot_topic").first
    cell.scroll_into_view_if_needed()
    cell.locator(".cm-content").click()
    page.keyboard.press("Control+a")
    page.keyboard.insert_text(code)
    # The answer cell: as released, or with this student's answer from an earlier visit (the
    # notebook's cells may still be drawing, so both are waited for at once).
    answered = re.compile(f"{re.escape(ANSWERS[who][:20])}|YOUR ANSWER HERE")
    cell = page.locator(".jp-MarkdownCell", has_text=answered).first
    cell.scroll_into_view_if_needed()
    cell.dblclick()
    cell.locator(".cm-content").click()
    page.keyboard.press("Control+a")
    page.keyboard.insert_text(answer)
    page.keyboard.press("Shift+Enter")
    page.keyboard.press("Control+s")
    home = Path("/home") / klass.names[who]
    deadline = time.monotonic() + seconds(30)
    while code.strip() not in _cell(home / NOTEBOOK, "robot_topic"):
        assert time.monotonic() < deadline, f"{who}'s notebook was not saved in time"
        time.sleep(0.5)


def _cell(path: Path, grade_id: str) -> str:
    try:
        notebook = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return ""
    for cell in notebook["cells"]:
        if cell["metadata"].get("nbgrader", {}).get("grade_id") == grade_id:
            return "".join(cell["source"])
    return ""


def _submit(page, times: int) -> None:
    _assignment_list(page)
    row = page.locator("#fetched_assignments_list .list_item", has_text=ASSIGNMENT).first
    row.locator("button", has_text="Submit").click()
    submitted = page.locator("#submitted_assignments_list .list_item", has_text=ASSIGNMENT)
    deadline = time.monotonic() + seconds(60)
    while page.locator("#submitted_assignments_list").inner_text().count("UTC") < times:
        assert time.monotonic() < deadline, "the submission did not show in the list"
        time.sleep(0.5)
    assert submitted.count() >= 1


def _feedback_page(page) -> str:
    """Fetch Feedback in the Assignment List, open the page it gives, and read it."""
    _assignment_list(page)
    # The list was drawn before the feedback was returned: ask it again, as a student does.
    page.locator("#refresh_assignments_list").click()
    page.locator("#submitted_assignments_list button", has_text="Fetch Feedback").first.click()
    link = page.locator("#submitted_assignments_list a", has_text="view feedback").first
    link.wait_for()
    link.click()
    page.locator(".jp-DirListing-item", has_text=f"{ASSIGNMENT}.html").dblclick()
    deadline = time.monotonic() + seconds(60)
    while True:
        frames = [frame for frame in page.frames if frame != page.main_frame]
        for frame in frames:
            try:
                text = frame.inner_text("body", timeout=2000)
            except Exception:  # a frame still loading
                continue
            if "Feedback for" in text:
                return text
        assert time.monotonic() < deadline, "the feedback page did not open"
        time.sleep(0.5)


def _utc(offset_seconds: float = 0) -> str:
    moment = datetime.datetime.now(datetime.timezone.utc) + datetime.timedelta(
        seconds=offset_seconds
    )
    return moment.strftime("%Y-%m-%d %H:%M:%S UTC")


@pytest.mark.slow
@pytest.mark.timeout(1500)  # the students' Python installed first (1.5 min), then the class
@as_root
def test_a_class_fetches_submits_is_graded_and_reads_its_own_feedback(klass, browser, tmp_path):
    names = klass.names
    released = klass.hub("release", ASSIGNMENT, "--due", _utc(3600))
    assert f"released {ASSIGNMENT}" in released.stdout

    # ada fetches, writes a wrong function and an answer, submits; then the due date passes,
    # she fixes it and submits again, late.
    ada = _login(browser, klass, "ada")
    # Her JupyterLab is the course's: the widgets' front end (the run player, the image view)
    # and nbgrader's student tools, not its instructor tools.
    html = ada.request.get(f"{klass.url}/user/{names['ada']}/lab").text()
    start = html.index('id="jupyter-config-data"')
    start = html.index(">", start) + 1
    config = json.loads(html[start : html.index("</script>", start)])
    served = {extension["name"] for extension in config["federated_extensions"]}
    assert {"@jupyter-widgets/jupyterlab-manager", "@jupyter/nbgrader"} <= served
    assert "@jupyter/nbgrader:formgrader" in config["disabledExtensions"]
    assert "@jupyter/nbgrader:assignment-list" not in config["disabledExtensions"]
    _fetch(ada)
    _type_into_notebook(ada, klass, "ada", WRONG, ANSWERS["ada"])
    _submit(ada, 1)
    # The due date falls between the two (nbgrader's due dates count whole seconds).
    time.sleep(2)
    klass.hub("release", ASSIGNMENT, "--due", _utc())
    time.sleep(1.5)
    _type_into_notebook(ada, klass, "ada", RIGHT, ANSWERS["ada"])
    _submit(ada, 2)

    # bo submits once, wrong; cy never logs in.
    bo = _login(browser, klass, "bo")
    _fetch(bo)
    _type_into_notebook(bo, klass, "bo", WRONG, ANSWERS["bo"])
    # ...from a terminal of his JupyterLab, which checks it first as the grader runs it.
    env = klass.root / "env" / "bin"
    typed = _as(
        names["bo"],
        f"cd && HOME=/home/{names['bo']} PATH={env}:/usr/bin:/bin "
        f"duckie handin --submit {ASSIGNMENT}",
    )
    assert typed.returncode == 0, typed.stdout + typed.stderr
    assert f"Submitted {ASSIGNMENT}" in typed.stdout
    assert "test_robot_topic" in typed.stdout  # the check said which visible test fails

    # The instructor collects: before the due date, ada's first try; then the latest.
    submitted = klass.root / "course" / "submitted"
    collected = klass.hub("collect", ASSIGNMENT, "--before-due")
    assert f"2 submissions of {ASSIGNMENT}" in collected.stdout
    assert f"none from {names['cy']}" in collected.stdout
    assert _cell(submitted / names["ada"] / NOTEBOOK, "robot_topic").strip() == WRONG.strip()
    # bo's only submission came after the due date: taken all the same, and said.
    late = collected.stdout.split("after the due date: ")[1].splitlines()[0]
    assert f"{names['bo']} (" in late
    assert names["ada"] not in late
    collected = klass.hub("collect", ASSIGNMENT)
    assert _cell(submitted / names["ada"] / NOTEBOOK, "robot_topic").strip() == RIGHT.strip()
    late = collected.stdout.split("after the due date: ")[1].splitlines()[0]
    assert f"{names['ada']} (" in late
    assert " s late" in late

    grading = klass.root / "grading"
    klass.duckie("grade", str(submitted), "--out", str(grading), "--assignment", ASSIGNMENT,
                 "--no-driving", "--jobs", "2")  # fmt: skip
    grades = {row["student"]: row for row in csv.DictReader((grading / "grades.csv").open())}
    assert set(grades) == {names["ada"], names["bo"]}
    assert grades[names["ada"]][f"{ASSIGNMENT}:test_robot_topic"] == "2"
    assert grades[names["bo"]][f"{ASSIGNMENT}:test_robot_topic"] == "0"
    assert grades[names["ada"]]["to_grade"] == grades[names["bo"]]["to_grade"] == "1"

    # Formgrader is the instructor's, behind the hub's login; a student is turned away.
    prof = _login(browser, klass, "prof")
    blocked: list = []
    prof.on(
        "console",
        lambda message: (
            blocked.append(message.text) if "Content Security Policy" in message.text else None
        ),
    )
    prof.goto(f"{klass.url}/services/formgrader/")
    prof.get_by_text("Manage Assignments").first.wait_for()
    row = prof.locator("table tr", has_text=ASSIGNMENT).first
    row.wait_for()
    headers = [text.strip() for text in prof.locator("table th").all_inner_texts()]
    count = row.locator("td").nth(headers.index("# Submissions")).inner_text().strip()
    assert count == "2"
    assert blocked == []  # Formgrader's own page runs whole under its policy
    turned = bo.request.get(f"{klass.url}/services/formgrader/formgrader/manage_assignments")
    assert turned.status == 403
    assert "do not have permission to access JupyterHub service formgrader" in turned.text()
    # The instructor grades ada's answer in Formgrader, which runs as the hub's account: it
    # shows her autograded notebook (which `duckie grade` wrote as root) with the rubric, and
    # saves the points and the comment into the gradebook.
    _grade_in_formgrader(prof, klass)
    assert blocked == []
    # A regrade (nothing new collected) keeps what the instructor gave.
    klass.hub("collect", ASSIGNMENT)
    klass.duckie("grade", str(submitted), "--out", str(grading), "--assignment", ASSIGNMENT,
                 "--no-driving", "--jobs", "2")  # fmt: skip
    canvas, moodle = tmp_path / "canvas.csv", tmp_path / "moodle.csv"
    klass.duckie("feedback", str(grading), "--export", "canvas", str(canvas), "--roster",
                 str(klass.roster))  # fmt: skip
    moodle_roster = tmp_path / "participants.csv"
    moodle_roster.write_text(
        "First name,Last name,Email address\n"
        + "".join(f"{who},Test,{names[who]}@uni.edu\n" for who in ("ada", "bo", "cy")),
        encoding="utf-8",
    )
    klass.duckie("feedback", str(grading), "--export", "moodle", str(moodle), "--roster",
                 str(moodle_roster))  # fmt: skip
    rows = {row["SIS Login ID"]: row for row in csv.DictReader(canvas.open(encoding="utf-8"))}
    column = next(name for name in rows[names["ada"]] if name.startswith(ASSIGNMENT))
    assert rows[names["ada"]][column] == "3.5"  # 2 for the test, 1.5 for the answer
    assert rows[names["bo"]][column] == "0"
    assert rows[names["cy"]][column] == ""  # never submitted: left as the LMS has it
    rows = {row["Email address"]: row for row in csv.DictReader(moodle.open(encoding="utf-8"))}
    assert rows[f"{names['ada']}@uni.edu"][column] == "3.5"
    assert rows[f"{names['cy']}@uni.edu"][column] == ""

    returned = klass.hub("return", ASSIGNMENT)
    assert "returned to 2 students" in returned.stdout

    # Each student reads their own page in their JupyterLab, and not the other's.
    seen = {who: _feedback_page(page) for who, page in (("ada", ada), ("bo", bo))}
    assert f"Feedback for {names['ada']}" in seen["ada"]
    assert names["bo"] not in seen["ada"]
    assert f"Feedback for {names['bo']}" in seen["bo"]
    assert names["ada"] not in seen["bo"]
    assert COMMENT in seen["ada"]
    assert COMMENT not in seen["bo"]
    assert "3.5 / 10" in seen["ada"]

    # What a student may try, from a terminal of their own JupyterLab.
    exchange = klass.root / "exchange" / "duckiebot"
    for attempt in (
        f"ls /home/{names['bo']}",
        f"cat /home/{names['bo']}/{NOTEBOOK}",
        f"ls {exchange / 'inbound'}",
        f"ls {exchange / 'feedback'}",
        f"cat {ROOT / 'solutions' / NOTEBOOK}",
        f"ls {klass.root / 'course'}",
        f"ls {klass.root / 'grading'}",
        f"ls {klass.root / 'state'}",
        f"cat {klass.root / 'passwords.csv'}",
        f"cat {klass.root / 'jupyterhub_config.py'}",
        f"cat {klass.root / 'hub.json'}",
        f"ls {klass.root / 'grading' / 'work'}",
    ):
        tried = _as(names["ada"], attempt)
        assert tried.returncode != 0, attempt
        assert "Permission denied" in tried.stderr, attempt
    # ...and through the hub, with her own login.
    for path in (f"/user/{names['bo']}/api/contents/{ASSIGNMENT}", "/hub/api/users"):
        answer = ada.request.get(klass.url + path)
        assert answer.status == 403, (path, answer.status)
        assert "robot_topic" not in answer.text()


def _grade_in_formgrader(prof, klass: Class) -> None:
    """Give ada's answer its points and comment in Formgrader's page, as an instructor does."""
    from nbgrader.api import Gradebook

    names = klass.names
    work = klass.root / "grading" / "work"
    autograded = work / "autograded" / names["ada"] / NOTEBOOK
    # Written 0600 by root: the hub's launcher shares it with its account within a second.
    deadline = time.monotonic() + seconds(10)
    while not autograded.stat().st_mode & 0o040:
        assert time.monotonic() < deadline, "the autograded notebook was not shared in time"
        time.sleep(0.2)
    database = f"sqlite:///{work / 'gradebook.db'}"
    with Gradebook(database) as gradebook:
        submission = gradebook.find_submission_notebook(ASSIGNMENT, ASSIGNMENT, names["ada"]).id
    prof.goto(f"{klass.url}/services/formgrader/formgrader/submissions/{submission}/")
    prof.get_by_text(ANSWERS["ada"]).first.wait_for()
    prof.get_by_text("For the grader, not in the student's notebook").first.wait_for()
    # The page's grades and comments are loaded (typed before, they would be drawn over).
    prof.wait_for_function("() => formgrader.grades.loaded && formgrader.comments.loaded")
    score = prof.locator("input.score#answer_find_topic")
    comment = prof.locator("textarea#answer_find_topic-comment")
    score.fill("1.5")
    comment.click()  # leaving the score saves it
    comment.fill(COMMENT)
    score.click()  # and leaving the comment saves it
    deadline = time.monotonic() + seconds(30)
    while True:
        with Gradebook(database) as gradebook:
            grade = gradebook.find_grade("answer_find_topic", ASSIGNMENT, ASSIGNMENT, names["ada"])
            given = gradebook.find_comment(
                "answer_find_topic", ASSIGNMENT, ASSIGNMENT, names["ada"]
            ).manual_comment
            saved = (grade.manual_score, given)
        if saved == (1.5, COMMENT):
            break
        assert time.monotonic() < deadline, f"Formgrader did not save the grade: {saved}"
        time.sleep(0.5)
    # The gradebook stays root's and the group's, whoever wrote it last; no journal is left.
    found = (work / "gradebook.db").stat()
    account = pwd.getpwnam(service_account(klass.root))
    assert (found.st_uid, found.st_gid, found.st_mode & 0o777) == (0, account.pw_gid, 0o660)
    assert not (work / "gradebook.db-journal").exists()


def _processes(word: str = "") -> List[Dict[str, object]]:
    """Each process of the machine whose command line holds ``word``: its argv and status."""
    found = []
    for folder in Path("/proc").iterdir():
        if not folder.name.isdigit():
            continue
        try:
            argv = (folder / "cmdline").read_bytes().decode(errors="replace").split("\0")
            lines = (folder / "status").read_text().splitlines()
        except OSError:  # ended meanwhile
            continue
        if any(word in part for part in argv):
            status = dict(line.split(":\t", 1) for line in lines if ":\t" in line)
            found.append({"argv": argv, **status})
    return found


def _servers() -> List[Dict[str, object]]:
    """The Jupyter servers running on the machine (not the bubblewrap that starts one)."""
    return [
        found
        for found in _processes("jupyterhub-singleuser")
        if not str(found["argv"][0]).endswith("bwrap")
    ]


def _check_formgrader_process(klass: Class, account: pwd.struct_passwd) -> None:
    """Formgrader's server runs as the hub's account, and no server of the hub as root.

    It has no capability and no way to one, and it is the account's only process: no kernel,
    no terminal.
    """
    work = klass.root / "grading" / "work"
    formgrader = [found for found in _servers() if f"--ServerApp.root_dir={work}" in found["argv"]]
    assert len(formgrader) == 1, _servers()
    (server,) = formgrader
    assert server["Uid"].split() == [str(account.pw_uid)] * 4
    assert server["Gid"].split() == [str(account.pw_gid)] * 4
    assert server["Groups"].strip() == ""
    assert int(server["CapEff"], 16) == int(server["CapPrm"], 16) == 0
    assert int(server["CapBnd"], 16) == 0
    assert server["NoNewPrivs"].strip() == "1"
    assert "--allow-root" not in server["argv"]
    mine = [found for found in _processes() if found["Uid"].split()[0] == str(account.pw_uid)]
    assert [found["argv"] for found in mine] == [server["argv"]]
    assert all(found["Uid"].split()[0] != "0" for found in _servers()), _servers()


def _try_formgrader_api(prof, klass: Class, account: pwd.struct_passwd) -> None:
    """Formgrader's REST API, with the instructor's cookies, opens no way to root.

    What it does, it does as the hub's account (a file made through it is the account's); it
    refuses a terminal, a kernel, a notebook's session and Formgrader's autograde (which would
    run students' code).
    """
    base = f"{klass.url}/services/formgrader"
    xsrf = next(
        cookie["value"]
        for cookie in prof.context.cookies()
        if cookie["name"] == "_xsrf" and cookie["path"].startswith("/services/formgrader")
    )
    headers = {"X-XSRFToken": xsrf}
    made = prof.request.post(f"{base}/api/contents", headers=headers, data={"type": "file"})
    assert made.status == 201, made.text()
    path = made.json()["path"]
    assert (klass.root / "grading" / "work" / path).stat().st_uid == account.pw_uid
    assert prof.request.delete(f"{base}/api/contents/{path}", headers=headers).status == 204
    assert '"terminalsAvailable": false' in prof.request.get(f"{base}/lab").text()
    terminal = prof.request.post(f"{base}/api/terminals", headers=headers)
    assert terminal.status == 404, terminal.text()
    kernel = prof.request.post(f"{base}/api/kernels", headers=headers, data={"name": "python3"})
    assert kernel.status == 403, kernel.text()
    assert NO_KERNEL in kernel.json()["message"]
    notebook = {"path": "x.ipynb", "type": "notebook", "name": "", "kernel": {"name": "python3"}}
    session = prof.request.post(f"{base}/api/sessions", headers=headers, data=notebook)
    assert session.status >= 400, session.text()  # 500: the server wraps the refusal
    assert NO_KERNEL in session.json()["message"]
    assert prof.request.get(f"{base}/api/sessions").json() == []
    assert prof.request.get(f"{base}/api/kernels").json() == []
    student = klass.names["ada"]
    autograde = prof.request.post(
        f"{base}/formgrader/api/submission/{ASSIGNMENT}/{student}/autograde", headers=headers
    )
    assert autograde.status == 403, autograde.text()
    assert NO_KERNEL in autograde.json()["message"]


@pytest.mark.slow
@pytest.mark.timeout(900)  # the hub's start, if this test runs alone
@as_root
def test_an_instructor_finds_no_way_to_root_through_the_hub(klass, browser):
    account = pwd.getpwnam(service_account(klass.root))
    assert 0 < account.pw_uid < 1000  # a system account: no password, no home, no shell
    assert account.pw_shell == "/usr/sbin/nologin"
    prof = _login(browser, klass, "prof")
    base = f"{klass.url}/services/formgrader"
    prof.goto(f"{base}/")
    prof.get_by_text("Manage Assignments").first.wait_for()
    _check_formgrader_process(klass, account)

    # Formgrader's JupyterLab offers no terminal and no kernel: no launcher card, no Terminal
    # in File > New; its Console opens no kernel.
    prof.goto(f"{base}/lab")
    prof.locator(".jp-Launcher").first.wait_for()
    cards = prof.locator(".jp-LauncherCard").all_inner_texts()
    assert not [card for card in cards if "Terminal" in card or "Python" in card], cards
    prof.locator(".lm-MenuBar-itemLabel", has_text="File").first.click()
    prof.locator(".lm-Menu-itemLabel", has_text="New").first.click()
    submenu = prof.locator(".lm-Menu").nth(1)
    submenu.locator(".lm-Menu-itemLabel", has_text="Text File").wait_for()
    assert "Terminal" not in submenu.locator(".lm-Menu-itemLabel").all_inner_texts()
    submenu.locator(".lm-Menu-itemLabel", has_text="Console").click()
    dialog = prof.locator(".jp-Dialog", has_text="Select Kernel")
    dialog.wait_for()
    choices = dialog.locator("option").all_inner_texts()
    assert set(choices) == {"No Kernel"}, choices
    dialog.locator(".jp-mod-accept").first.click()
    time.sleep(seconds(3))
    assert prof.request.get(f"{base}/api/kernels").json() == []
    _try_formgrader_api(prof, klass, account)
    _check_formgrader_process(klass, account)

    # The hub, of which instructors are admins, starts no server for an account that is not
    # the class's: not root's, even when an instructor asks.
    hub_xsrf = next(
        cookie["value"]
        for cookie in prof.context.cookies()
        if cookie["name"] == "_xsrf" and cookie["path"].startswith("/hub")
    )
    headers = {"X-XSRFToken": hub_xsrf}
    prof.request.post(f"{klass.url}/hub/api/users/root", headers=headers)
    started = prof.request.post(f"{klass.url}/hub/api/users/root/server", headers=headers)
    assert started.status == 500, started.text()
    assert "root is not a student or an instructor of this hub" in klass.log.read_text()
    assert prof.request.get(f"{klass.url}/hub/api/users/root").json()["servers"] == {}
    assert all(found["Uid"].split()[0] != "0" for found in _servers()), _servers()


@as_root
def test_returning_feedback_before_grading_says_who_is_not_graded(tmp_path):
    from autograder.hub import Hub, return_feedback

    hub = Hub(tmp_path / "hub", ["ada"])
    folder = hub.course / "submitted" / "ada" / ASSIGNMENT
    folder.mkdir(parents=True)
    (folder / f"{ASSIGNMENT}.ipynb").write_text("{}")
    done = return_feedback(hub, ASSIGNMENT)
    assert (done.returned, done.not_graded) == ([], ["ada"])


def test_the_image_folder_holds_the_edition_and_values_that_name_the_image(tmp_path):
    import yaml

    place = tmp_path / "hub"
    place.mkdir()
    (place / "hub.json").write_text(
        json.dumps({"students": ["ada", "bo"], "instructors": ["prof"]})
    )
    out = tmp_path / "image"
    done = _run(DUCKIE, "hub", "image", str(out), "--name", "registry.example.org/course",
                "--hub", str(place))  # fmt: skip
    assert f"Wrote {out}" in done.stdout
    dockerfile = (out / "Dockerfile").read_text()
    assert dockerfile.splitlines()[4] == "FROM python:3.11-slim-bookworm"
    for line in dockerfile.splitlines():
        if line.startswith("COPY "):
            assert (out / line.split()[1]).exists(), line
    assert not (out / "edition" / "solutions").exists()
    assert not (out / "edition" / "autograder").exists()
    assert (out / "edition" / "course" / NOTEBOOK).is_file()
    values = yaml.safe_load((out / "values.yaml").read_text())
    tag = values["singleuser"]["image"]["tag"]
    assert values["singleuser"]["image"]["name"] == "registry.example.org/course"
    assert f"registry.example.org/course:{tag}" in dockerfile
    assert values["hub"]["config"]["Authenticator"]["admin_users"] == ["prof"]
    assert values["hub"]["config"]["Authenticator"]["allowed_users"] == ["ada", "bo", "prof"]
    (mount,) = values["singleuser"]["storage"]["extraVolumeMounts"]
    assert (
        f"c.Exchange.root = {mount['mountPath']!r}"
        in (out / "jupyter" / "nbgrader_config.py").read_text()
    )
    server = json.loads((out / "jupyter" / "jupyter_server_config.json").read_text())
    extensions = server["ServerApp"]["jpserver_extensions"]
    assert extensions["nbgrader.server_extensions.assignment_list"] is True
    assert extensions["nbgrader.server_extensions.formgrader"] is False
    again = _run(DUCKIE, "hub", "image", str(out), "--name", "x", "--hub", str(place), check=False)
    assert again.returncode == 1
    assert "is not empty: give a new folder" in again.stderr
    assert "Traceback" not in again.stderr
