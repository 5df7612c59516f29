"""A class hub on one machine: JupyterHub for the students, nbgrader's exchange between them.

Students need only a browser. Each logs in with a Unix account of the machine (``duckie hub
users`` makes one per row of a roster), gets JupyterLab with the course's configuration and
nbgrader's Assignment List, fetches each assignment there, submits it there, and later fetches
the feedback page. Instructors release, collect, grade and return from a shell on the machine
(as root, who runs the hub), and grade the answers in words in Formgrader, a service of the hub
that only the hub's instructors can open.

A hub folder (``--hub``, default :data:`DEFAULT_HUB`) holds:

    hub.json              who may log in: the students and the instructors (0600: JupyterHub,
                          root, reads it)
    passwords.csv         the first password of each account ``duckie hub users`` made (0600)
    jupyterhub_config.py  written by ``duckie hub start`` (0600); jupyterhub_config.local.py,
                          if there, is read after it (your authenticator, your certificate)
    env/                  the students' Python: the student edition and JupyterHub, made with
                          a Python every user may run (never this repository: it holds
                          solutions/), with the course's Jupyter configuration in env/etc/jupyter
    proxy/                configurable-http-proxy, from npm, unless one is on the PATH
    exchange/             nbgrader's exchange; the course is :data:`COURSE_ID`
    course/               the instructors' nbgrader folder: release/, submitted/ (what
                          ``duckie hub collect`` gathered), feedback/ (0700, root's)
    grading/              where ``duckie grade`` writes the class's grades; Formgrader
                          serves grading/work (root and the hub's account only)
    state/                the hub's database, its cookie secret, the proxy's pid (0700)

Isolation is the machine's own: each student's server and kernels run as their Unix user, each
home is 0700, the exchange's inbound folder lets a student write but not list, and feedback is
released under a name only the student's own submission secret gives. The hub starts a server
only for an account of ``hub.json`` (never root or another account of the machine, even when an
instructor, a hub admin, asks).

Nothing an instructor reaches through the hub runs as root. Formgrader runs as the hub's own
account (a system account ``duckie hub start`` makes, named after the hub's folder), in a view
of the machine that holds only what it needs, with no terminal and no kernel
(:mod:`autograder.hub_formgrader` says why that account and how).
"""

# Over 600 lines: one class hub from accounts to returned feedback, whose steps share the hub
# folder's layout and configuration templates; the Kubernetes image (`write_image` and its
# templates, about 120 lines) could stand on its own.

from __future__ import annotations

import json
import os
import pwd
import re
import secrets
import shutil
import stat
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence

from autograder.course import IGNORED, ROOT, CourseError
from autograder.formgrade import write_config
from autograder.hub_formgrader import service_account, share_grading
from autograder.lms import read_roster

__all__ = [
    "COURSE_ID",
    "DEFAULT_HUB",
    "Hub",
    "HubError",
    "account_name",
    "collect",
    "create_accounts",
    "has_certificate",
    "lateness",
    "plain_http",
    "write_image",
    "prepare",
    "reachable_by_others",
    "release",
    "return_feedback",
]

#: Where a hub lives unless told: a folder every user can reach (the students' Python is there).
DEFAULT_HUB = Path("/srv/duckiebot-hub")

#: The course's name in nbgrader's exchange (``--course``).
COURSE_ID = "duckiebot"

#: The version of configurable-http-proxy installed from npm when none is on the PATH.
PROXY_PACKAGE = "configurable-http-proxy@4.6.3"

#: The first uid of a person's account (Debian's UID_MIN): below are the system's own.
FIRST_UID = 1000

#: A Unix account name useradd accepts everywhere: a letter first, at most 32 characters.
_ACCOUNT = re.compile(r"^[a-z_][a-z0-9_-]{0,31}$")

#: The students' JupyterLab: the Assignment List and Validate (every cell checked), not the
#: instructors' tools; terminals run the user's own shell.
_SERVER_CONFIG = {
    "ServerApp": {
        "jpserver_extensions": {
            "nbgrader.server_extensions.formgrader": False,
            "nbgrader.server_extensions.assignment_list": True,
            "nbgrader.server_extensions.course_list": False,
            "nbgrader.server_extensions.validate_assignment": True,
            # Language servers: none is installed, and looking for them runs npm several times
            # at every server's start (seconds of processor with a class logging in at once).
            "jupyter_lsp": False,
        },
        "terminado_settings": {"shell_command": ["/bin/sh", "-c", 'exec "${SHELL:-/bin/sh}"']},
    }
}
_PAGE_CONFIG = {
    "disabledExtensions": {
        "@jupyter/nbgrader:formgrader": True,
        "@jupyter/nbgrader:create-assignment": True,
        "@jupyter/nbgrader:course-list": True,
        "@jupyterlab/apputils-extension:announcements": True,
    }
}

_HUB_CONFIG = """\
# Written by `duckie hub start`, again at each start: put your own settings (another
# authenticator, memory limits...) in jupyterhub_config.local.py beside it, read last.
import json
from pathlib import Path

c = get_config()  # noqa: F821 - given by JupyterHub when it reads this file
hub = Path({hub!r})
settings = json.loads((hub / "hub.json").read_text(encoding="utf-8"))

c.JupyterHub.bind_url = {bind_url!r}
c.JupyterHub.hub_bind_url = {hub_bind_url!r}
c.JupyterHub.db_url = "sqlite:///" + str(hub / "state" / "jupyterhub.sqlite")
c.JupyterHub.cookie_secret_file = str(hub / "state" / "jupyterhub_cookie_secret")
c.ConfigurableHTTPProxy.command = [{proxy!r}]
c.ConfigurableHTTPProxy.pid_file = str(hub / "state" / "proxy.pid")
c.ConfigurableHTTPProxy.api_url = {proxy_api!r}

# The machine's accounts (PAM): `duckie hub users ROSTER` made one per student.
c.PAMAuthenticator.open_sessions = False
c.Authenticator.allowed_users = set(settings["students"]) | set(settings["instructors"])
c.Authenticator.admin_users = set(settings["instructors"])
c.JupyterHub.load_groups = {{"instructors": {{"users": settings["instructors"]}}}}

# Each user's JupyterLab runs as their own Unix user, from the students' Python, in their home.
c.Spawner.cmd = [str(hub / "env" / "bin" / "jupyterhub-singleuser")]
c.Spawner.default_url = "/lab"
c.Spawner.notebook_dir = "~"
c.Spawner.env_keep = ["LANG", "LC_ALL"]
c.Spawner.environment = {{
    "PATH": str(hub / "env" / "bin") + ":/usr/local/bin:/usr/bin:/bin",
    "VIRTUAL_ENV": str(hub / "env"),
}}
c.Spawner.http_timeout = 120
c.Spawner.start_timeout = 180


# A server only for a person of hub.json: never root or another account of the machine, even
# when an instructor (a hub admin) adds that user to the hub and asks for its server.
def only_the_class(spawner):
    import pwd

    name = spawner.user.name
    if name not in c.Authenticator.allowed_users or pwd.getpwnam(name).pw_uid < {first_uid}:
        raise ValueError(
            f"{{name}} is not a student or an instructor of this hub: it starts servers for "
            "the accounts of hub.json only (`duckie hub users`)."
        )


c.Spawner.pre_spawn_hook = only_the_class

# Formgrader on the class `duckie grade --out {{hub}}/grading` graded, for instructors only: as
# the hub's own account, in a view of its own, with no terminal and no kernel (see
# autograder/hub_formgrader.py).
c.JupyterHub.services = [
    {{
        "name": "formgrader",
        "url": {formgrader_url!r},
        "command": {formgrader_command!r},
        "cwd": str(hub / "grading" / "work"),
        "oauth_no_confirm": True,
        "environment": {{"JUPYTERHUB_DEFAULT_URL": "/formgrader"}},
    }}
]
c.JupyterHub.load_roles = [
    {{
        "name": "formgraders",
        "groups": ["instructors"],
        "scopes": ["access:services!service=formgrader"],
    }}
]

local = hub / "jupyterhub_config.local.py"
if local.is_file():
    exec(compile(local.read_text(encoding="utf-8"), str(local), "exec"))
"""

_COURSE_CONFIG = """\
# Written by `duckie hub`: the instructors' side of nbgrader's exchange for this hub.
c = get_config()  # noqa: F821 - given by nbgrader when it reads this file
c.CourseDirectory.root = {root!r}
c.CourseDirectory.course_id = {course!r}
c.Exchange.root = {exchange!r}
"""

_STUDENT_NBGRADER = """\
# Written by `duckie hub start`: the students' side of nbgrader's exchange, and Validate
# checking every cell (as the grader runs them).
c = get_config()  # noqa: F821 - given by nbgrader when it reads this file
c.CourseDirectory.course_id = {course!r}
c.Exchange.root = {exchange!r}
c.Validator.validate_all = True
"""


class HubError(CourseError):
    """The hub cannot be made, started or used as asked (the message says why and what to do)."""


@dataclass
class Hub:
    """A hub folder and its settings (``hub.json``).

    Attributes:
        root: the hub's folder.
        students: the students' account names.
        instructors: the instructors' account names (hub admins, who may open Formgrader).
    """

    root: Path
    students: List[str] = field(default_factory=list)
    instructors: List[str] = field(default_factory=list)

    @classmethod
    def load(cls, root: Path) -> Hub:
        """The hub in ``root``, with the accounts ``duckie hub users`` recorded (none yet: [])."""
        root = Path(root).absolute()
        settings = root / "hub.json"
        if not settings.is_file():
            return cls(root)
        try:
            data = json.loads(settings.read_text(encoding="utf-8"))
        except PermissionError:
            raise HubError(
                f"Cannot read {settings}: the class list is root's only. Run the command with sudo."
            ) from None
        except (OSError, ValueError) as error:
            raise HubError(f"Cannot read {settings}: {error}.") from None
        return cls(root, list(data.get("students", [])), list(data.get("instructors", [])))

    def save(self) -> None:
        """Write ``hub.json``, for root only: the class list (JupyterHub reads it as root)."""
        self.root.mkdir(parents=True, exist_ok=True)
        self.root.chmod(0o755)
        data = {"students": sorted(self.students), "instructors": sorted(self.instructors)}
        _write(self.root / "hub.json", json.dumps(data, indent=2) + "\n", 0o600)

    @property
    def env(self) -> Path:
        """The students' Python."""
        return self.root / "env"

    @property
    def exchange(self) -> Path:
        """The exchange, where nbgrader passes files between students and instructors."""
        return self.root / "exchange"

    @property
    def course(self) -> Path:
        """The instructors' nbgrader folder."""
        return self.root / "course"

    @property
    def grading(self) -> Path:
        """Where ``duckie grade`` writes the class's grades."""
        return self.root / "grading"

    @property
    def state(self) -> Path:
        """The hub's own files (database, cookie secret)."""
        return self.root / "state"


def _write(path: Path, text: str, mode: int) -> None:
    """Write ``path`` whole with ``mode``, never readable by others in between."""
    partial = path.with_name(path.name + ".tmp")
    descriptor = os.open(partial, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
    with os.fdopen(descriptor, "w", encoding="utf-8") as handle:
        handle.write(text)
    partial.chmod(mode)
    partial.replace(path)


def _private_folder(path: Path) -> Path:
    path.mkdir(parents=True, exist_ok=True)
    path.chmod(0o700)
    return path


def _run(
    argv: Sequence[str], what: str, cwd: Optional[Path] = None, env: Optional[Dict[str, str]] = None
) -> str:
    """Run a command; its output, or a :class:`HubError` with its last lines."""
    try:
        done = subprocess.run(
            list(argv), cwd=cwd, env=env, capture_output=True, text=True, check=False, timeout=1800
        )
    except OSError as error:
        raise HubError(f"Cannot {what}: {error}.") from None
    output = (done.stdout or "") + (done.stderr or "")
    if done.returncode != 0:
        tail = "\n".join(output.strip().splitlines()[-8:])
        raise HubError(f"Cannot {what} ({argv[0]} exited with {done.returncode}):\n{tail}")
    return output


def _need_root(what: str) -> None:
    if os.geteuid() != 0:
        raise HubError(
            f"{what} needs root (JupyterHub starts each student's server as their own Unix "
            "user): run it with sudo."
        )


# -- accounts -----------------------------------------------------------------------------------


def account_name(key: str) -> str:
    """A roster's login or email as a Unix account name (``Ada.L@uni.edu`` gives ``ada.l``...).

    Raises:
        HubError: if the name cannot be one (said with what to change).
    """
    name = key.strip().split("@")[0].casefold().replace(".", "_")
    if not _ACCOUNT.match(name):
        raise HubError(
            f"{key!r} cannot be a Unix account name: use a login of lowercase letters, digits, "
            "'_' or '-', starting with a letter, at most 32 characters."
        )
    return name


def roster_accounts(roster_path: Path) -> List[str]:
    """The account name of every student of a roster (its login, else its email's local part)."""
    roster = read_roster(roster_path)
    names: List[str] = []
    for number, row in enumerate(roster.rows, start=2):
        keys = [
            (row.get(column) or "").strip() for column in (roster.login, roster.email) if column
        ]
        key = next((key for key in keys if key), "")
        if not key:
            raise HubError(f"Row {number} of {roster_path} has no login and no email address.")
        name = account_name(key)
        if name in names:
            raise HubError(
                f"Two students of {roster_path} would share the account {name!r} (row {number})."
            )
        names.append(name)
    if not names:
        raise HubError(f"The roster {roster_path} lists no student.")
    return names


def _account_exists(name: str) -> bool:
    try:
        pwd.getpwnam(name)
    except KeyError:
        return False
    return True


def create_accounts(
    hub: Hub,
    roster_path: Optional[Path],
    instructors: Sequence[str] = (),
    progress: Optional[Callable[[str], None]] = None,
) -> Dict[str, str]:
    """Make a Unix account for each student of the roster and each instructor not yet there.

    Each new account gets a home only its user can open and a random first password; the
    passwords are added to ``hub/passwords.csv`` (readable by root only). Existing accounts are
    left as they are. The students and instructors are recorded in ``hub/hub.json``.

    Returns:
        The new accounts' first passwords, by name.
    """
    _need_root("Making the students' accounts")
    say = progress or (lambda line: None)
    students = roster_accounts(roster_path) if roster_path else []
    teachers = [account_name(name) for name in instructors]
    for name in students:
        if name in teachers:
            raise HubError(f"{name} is both a student of the roster and an instructor.")
    if shutil.which("useradd") is None or shutil.which("chpasswd") is None:
        raise HubError("useradd and chpasswd are missing: install Debian's passwd package.")
    for name in [*teachers, *students]:
        if _account_exists(name) and pwd.getpwnam(name).pw_uid < FIRST_UID:
            raise HubError(
                f"{name} is a system account of this machine (uid {pwd.getpwnam(name).pw_uid}): "
                "give that student another login in the roster."
            )
    passwords = hub.root / "passwords.csv"
    hub.save()  # the hub's folder, before the first password goes into it
    created: Dict[str, str] = {}
    for name in [*teachers, *students]:
        if _account_exists(name):
            say(f"{name}: the account exists, left as it is")
            continue
        _run(
            ["useradd", "--create-home", "--shell", "/bin/bash", "--comment", "duckiebot", name],
            f"make the account {name}",
        )
        password = secrets.token_urlsafe(9)
        done = subprocess.run(
            ["chpasswd"], check=False, input=f"{name}:{password}\n", text=True, capture_output=True
        )
        if done.returncode != 0:
            raise HubError(f"Cannot set the password of {name}: {done.stderr.strip()}.")
        created[name] = password
        # Kept at once: an account whose password is lost would need root to open.
        old = passwords.read_text(encoding="utf-8") if passwords.is_file() else "account,password\n"
        _write(passwords, old + f"{name},{password}\n", 0o600)
        say(f"{name}: account made")
    for name in [*teachers, *students]:
        Path(pwd.getpwnam(name).pw_dir).chmod(0o700)  # a home only its user opens
    hub.students = sorted(set(hub.students) | set(students))
    hub.instructors = sorted(set(hub.instructors) | set(teachers))
    hub.save()
    return created


# -- the environment and the configuration ---------------------------------------------------


def reachable_by_others(path: Path) -> bool:
    """Whether any user of the machine can get into the folder ``path``.

    It and every folder above it let others through: then they can open every file in it that
    others may read, whether they can list the folder or not.
    """
    path = Path(path).absolute()
    return all(folder.stat().st_mode & stat.S_IXOTH for folder in [path, *path.parents])


def _python(python: Optional[str]) -> str:
    """A Python 3.11+ every user can run: Debian's, where the course's own is private."""
    candidates = [python] if python else ["/usr/bin/python3", sys.executable]
    for candidate in candidates:
        if not candidate or not Path(candidate).exists():
            continue
        real = Path(candidate).resolve()
        if not python and not reachable_by_others(real.parent):
            continue
        done = subprocess.run(
            [candidate, "-c", "import sys, venv; print(sys.version_info >= (3, 11))"],
            capture_output=True,
            text=True,
            check=False,
        )
        if done.stdout.strip() == "True":
            return candidate
    raise HubError(
        "No Python 3.11 or newer that every user can run was found: install Debian's python3 "
        "and python3-venv, or give one with --python."
    )


def _install_env(hub: Hub, python: Optional[str], say: Callable[[str], None]) -> None:
    """The students' Python: the student edition and JupyterHub, at the repository's versions."""
    from autograder.edition import build_edition

    edition = hub.root / "edition"
    if edition.exists():
        shutil.rmtree(edition)
    say("building the student edition (what students receive) ...")
    built = build_edition(edition)
    stamp = hub.env / ".duckie-edition"
    if stamp.is_file() and stamp.read_text(encoding="utf-8").strip() == built.commit:
        say("the students' Python is up to date")
        shutil.rmtree(edition)
        return
    if not (hub.env / "bin" / "python").exists():
        interpreter = _python(python)
        say(f"making the students' Python in {hub.env} with {interpreter} ...")
        _run([interpreter, "-m", "venv", str(hub.env)], "make the students' Python")
    pip = [str(hub.env / "bin" / "python"), "-m", "pip", "install", "--quiet"]
    constraints = ["-c", str(ROOT / "constraints.txt")]
    say("installing the course's library, JupyterLab, nbgrader and JupyterHub (a few minutes) ...")
    _run([*pip, "--upgrade", "pip"], "upgrade pip in the students' Python")
    _run([*pip, *constraints, str(edition), "jupyterhub"], "install the students' Python")
    # The same version number with new files: the library itself is installed again.
    _run([*pip, "--no-deps", "--force-reinstall", str(edition)], "install the course's library")
    stamp.write_text(built.commit + "\n", encoding="utf-8")
    shutil.rmtree(edition)


def _install_proxy(hub: Hub, say: Callable[[str], None]) -> str:
    found = shutil.which("configurable-http-proxy")
    if found:
        return found
    local = hub.root / "proxy" / "node_modules" / ".bin" / "configurable-http-proxy"
    if local.exists():
        return str(local)
    npm = shutil.which("npm")
    if npm is None:
        raise HubError(
            "JupyterHub needs configurable-http-proxy, from npm: install Node.js and npm "
            "(Debian's nodejs and npm packages), then start the hub again."
        )
    say(f"installing {PROXY_PACKAGE} from npm ...")
    _run(
        [npm, "install", "--silent", "--prefix", str(hub.root / "proxy"), PROXY_PACKAGE],
        "install configurable-http-proxy",
    )
    return str(local)


def _configure_env(hub: Hub) -> None:
    """The course's Jupyter configuration, in the students' Python (every server reads it)."""
    _write_jupyter_config(hub.env / "etc" / "jupyter", hub.exchange)


def _write_jupyter_config(etc: Path, exchange: Path) -> None:
    (etc / "labconfig").mkdir(parents=True, exist_ok=True)
    _write(etc / "jupyter_server_config.json", json.dumps(_SERVER_CONFIG, indent=2) + "\n", 0o644)
    _write(etc / "labconfig" / "page_config.json", json.dumps(_PAGE_CONFIG, indent=2) + "\n", 0o644)
    text = _STUDENT_NBGRADER.format(course=COURSE_ID, exchange=str(exchange))
    _write(etc / "nbgrader_config.py", text, 0o644)


def _formgrader_account(hub: Hub) -> pwd.struct_passwd:
    """The hub's own account, which Formgrader runs as; made the first time.

    It is a system account with no password, no home and no login shell; an account of that
    name that is not the hub's is refused.
    """
    name = service_account(hub.root)
    comment = f"Formgrader of the class hub {hub.root}"
    if name in hub.students or name in hub.instructors:
        raise HubError(
            f"The hub's own account would be {name}, the account of one of its people: move "
            "the hub to a folder of another name (--hub)."
        )
    if not _account_exists(name):
        if shutil.which("useradd") is None:
            raise HubError("useradd is missing: install Debian's passwd package.")
        _run(
            ["useradd", "--system", "--user-group", "--no-create-home", "--home-dir",
             "/nonexistent", "--shell", "/usr/sbin/nologin", "--comment", comment, name],
            f"make the hub's account {name}",
        )  # fmt: skip
    found = pwd.getpwnam(name)
    if found.pw_gecos != comment or found.pw_uid == 0 or found.pw_uid >= FIRST_UID:
        raise HubError(
            f"The account {name} exists and is not this hub's own ({found.pw_gecos!r}): move "
            f"the hub to a folder of another name (--hub), or remove that account first."
        )
    return found


def _configure_course(hub: Hub) -> None:
    _private_folder(hub.course)
    text = _COURSE_CONFIG.format(root=str(hub.course), course=COURSE_ID, exchange=str(hub.exchange))
    _write(hub.course / "nbgrader_config.py", text, 0o600)
    hub.exchange.mkdir(parents=True, exist_ok=True)
    hub.exchange.chmod(0o777)  # nbgrader's own mode for the exchange's root


def prepare(
    hub: Hub,
    port: int = 8000,
    ip: str = "127.0.0.1",
    python: Optional[str] = None,
    progress: Optional[Callable[[str], None]] = None,
) -> Path:
    """Make or bring up to date everything the hub runs on; its ``jupyterhub_config.py``.

    It also makes the hub's own account, which Formgrader runs as, and gives it the grading
    folder (:mod:`autograder.hub_formgrader`).

    Raises:
        HubError: if not root, if no student or instructor was added, if students could read
            this repository's ``solutions/``, if bubblewrap is missing, if the hub's account
            would be another's, or if an install fails.
    """
    _need_root("Starting the hub")
    say = progress or (lambda line: None)
    if not hub.students and not hub.instructors:
        raise HubError(
            f"{hub.root} has no accounts yet: add them first with "
            f"`duckie hub users ROSTER.csv --instructor NAME --hub {hub.root}`."
        )
    if reachable_by_others(ROOT / "solutions"):
        raise HubError(
            f"Every user of this machine can read {ROOT / 'solutions'} (the answers and hidden "
            f"tests): close the repository first (chmod o-rwx {ROOT}), then start the hub again."
        )
    if shutil.which("bwrap") is None:
        raise HubError(
            "Formgrader runs in a view of its own that bubblewrap makes, and bwrap is missing: "
            "install it (`make ros`, or apt-get install bubblewrap), then start the hub again."
        )
    hub.save()
    _install_env(hub, python, say)
    _configure_env(hub)
    proxy = _install_proxy(hub, say)
    _private_folder(hub.state)
    _configure_course(hub)
    account = _formgrader_account(hub)
    work = share_grading(hub.grading, account.pw_gid)
    write_config(work)
    formgrader_port = port + 2
    # Started as root by JupyterHub, it runs Formgrader as the hub's account.
    command = [sys.executable, "-I", "-m", "autograder.hub_formgrader", str(hub.root)]
    config = _HUB_CONFIG.format(
        first_uid=FIRST_UID,
        hub=str(hub.root),
        bind_url=f"http://{ip}:{port}",
        hub_bind_url=f"http://127.0.0.1:{port + 1}",
        proxy=proxy,
        proxy_api=f"http://127.0.0.1:{port + 3}",
        formgrader_url=f"http://127.0.0.1:{formgrader_port}",
        formgrader_command=command,
    )
    path = hub.root / "jupyterhub_config.py"
    _write(path, config, 0o600)
    return path


def has_certificate(hub: Hub) -> bool:
    """Whether ``jupyterhub_config.local.py`` gives the hub a certificate (it serves HTTPS)."""
    local = hub.root / "jupyterhub_config.local.py"
    return local.is_file() and "ssl_cert" in local.read_text(encoding="utf-8")


def plain_http(hub: Hub, ip: str) -> bool:
    """Whether the hub, on ``ip``, serves other machines without a certificate of its own.

    Then passwords cross the network in the clear, unless a proxy with HTTPS is in front.
    """
    return ip not in ("127.0.0.1", "localhost", "::1") and not has_certificate(hub)


def hub_command(hub: Hub) -> List[str]:
    """The command line that runs the hub prepared in ``hub`` (run it in ``hub/state``)."""
    return [
        str(Path(sys.executable).parent / "jupyterhub"),
        "-f",
        str(hub.root / "jupyterhub_config.py"),
    ]


# -- the exchange --------------------------------------------------------------------------------


def _nbgrader(hub: Hub, *arguments: str) -> str:
    if not (hub.course / "nbgrader_config.py").is_file():
        raise HubError(f"{hub.root} is not a hub yet: start it first with `duckie hub start`.")
    argv = [sys.executable, "-m", "nbgrader", *arguments]
    # nbgrader makes a gradebook with the alembic command of its own environment.
    path = os.pathsep.join([str(Path(sys.executable).parent), os.environ.get("PATH", "")])
    env = {**os.environ, "PATH": path}
    return _run(argv, f"run nbgrader {arguments[0]}", cwd=hub.course, env=env)


def release(
    hub: Hub, assignment: str, due: Optional[str] = None, release_root: Path = ROOT / "course"
) -> List[str]:
    """Put ``course/ASSIGNMENT`` into the exchange, where students fetch it; its notebooks.

    Args:
        hub: the hub.
        assignment: an assignment of ``release_root`` (``05_odometry``).
        release_root: the released course (this repository's ``course/``).
        due: the due date (``2026-12-01 17:00`` with a time zone or UTC): ``duckie hub collect
            --before-due`` then takes each student's last submission before it.
    """
    _need_root("Releasing an assignment")
    source = release_root / assignment
    if not source.is_dir():
        known = sorted(path.name for path in release_root.iterdir() if path.is_dir())
        raise HubError(f"There is no assignment {assignment!r} in course/: {', '.join(known)}.")
    target = hub.course / "release" / assignment
    if target.exists():
        shutil.rmtree(target)
    shutil.copytree(source, target, ignore=shutil.ignore_patterns(*IGNORED))
    if due:
        _nbgrader(hub, "db", "assignment", "add", assignment, f"--duedate={due}")
    _nbgrader(hub, "release_assignment", assignment, "--force")
    return sorted(path.name for path in target.glob("*.ipynb"))


def collect(hub: Hub, assignment: str, before_due: bool = False) -> List[str]:
    """Gather every student's latest submission of ``assignment`` into ``hub/course/submitted``.

    A newer submission replaces one collected before (nbgrader's ``collect --update``); with
    ``before_due``, each student's last one before the due date. Returns who has one.
    """
    _need_root("Collecting submissions")
    arguments = ["collect", assignment, "--update"]
    if before_due:
        arguments.append("--before-duedate")
    _nbgrader(hub, *arguments)
    submitted = hub.course / "submitted"
    return sorted(folder.name for folder in submitted.glob("*") if (folder / assignment).is_dir())


def lateness(hub: Hub, assignment: str) -> Dict[str, float]:
    """How late each collected submission of ``assignment`` is, in seconds (late ones only).

    Measured as nbgrader measures it: the submission's time (its ``timestamp.txt``) against the
    due date ``duckie hub release --due`` set; no due date, nobody late.
    """
    from nbgrader.api import Gradebook, MissingEntry
    from nbgrader.utils import parse_utc

    database = hub.course / "gradebook.db"
    if not database.is_file():
        return {}
    with Gradebook(f"sqlite:///{database}", COURSE_ID) as gradebook:
        try:
            due = gradebook.find_assignment(assignment).duedate
        except MissingEntry:
            return {}
    if due is None:
        return {}
    late: Dict[str, float] = {}
    for stamp in sorted((hub.course / "submitted").glob(f"*/{assignment}/timestamp.txt")):
        moment = parse_utc(stamp.read_text(encoding="utf-8").strip())
        seconds = (moment - due).total_seconds()
        if seconds > 0:
            late[stamp.parent.parent.name] = seconds
    return late


@dataclass
class Returned:
    """What ``duckie hub return`` gave back: the students whose pages went out, and who not."""

    returned: List[str] = field(default_factory=list)
    not_graded: List[str] = field(default_factory=list)


def return_feedback(hub: Hub, assignment: str, grading: Optional[Path] = None) -> Returned:
    """Hand each collected student their feedback page, through nbgrader's exchange.

    The page ``duckie grade`` (or ``duckie feedback``) wrote for each student, in ``grading``
    (default ``hub/grading``), becomes the feedback of each notebook they submitted of
    ``assignment``; students get it with Fetch Feedback in the Assignment List.
    """
    _need_root("Returning feedback")
    grading = Path(grading or hub.grading)
    done = Returned()
    for folder in sorted((hub.course / "submitted").glob(f"*/{assignment}")):
        student = folder.parent.name
        page = grading / "feedback" / f"{student}.html"
        if not page.is_file():
            done.not_graded.append(student)
            continue
        target = hub.course / "feedback" / student / assignment
        target.mkdir(parents=True, exist_ok=True)
        for name in ("timestamp.txt", "submission_secret.txt"):
            if (folder / name).is_file():
                shutil.copyfile(folder / name, target / name)
        for notebook in sorted(folder.glob("*.ipynb")):
            html = target / f"{notebook.stem}.html"
            shutil.copyfile(page, html)
            html.chmod(0o644)  # readable under its secret name only
        done.returned.append(student)
    if done.returned:
        _nbgrader(hub, "release_feedback", assignment)
    return done


# -- a hub beyond one machine: Zero to JupyterHub on Kubernetes ---------------------------------

#: Where nbgrader's exchange is mounted in the students' pods.
POD_EXCHANGE = Path("/srv/nbgrader/exchange")

_DOCKERFILE = """\
# The students' image for a class hub on Kubernetes (Zero to JupyterHub), written by
# `duckie hub image`: the student edition of the course (no solutions, no grader), JupyterLab
# with the course's configuration and nbgrader's Assignment List, and jupyterhub-singleuser.
# Build and push it:  docker build -t {image}:{tag} . && docker push {image}:{tag}
FROM python:3.11-slim-bookworm
# ffmpeg: a run player saved as MP4 (notebook 10).
RUN apt-get update \\
    && apt-get install -y --no-install-recommends ffmpeg \\
    && rm -rf /var/lib/apt/lists/*
RUN useradd --create-home --uid 1000 --gid 100 --shell /bin/bash jovyan
COPY edition /opt/duckiebot-course
RUN python -m pip install --no-cache-dir -c /opt/duckiebot-course/constraints.txt \\
        /opt/duckiebot-course jupyterhub
# The course's Jupyter configuration: Validate checks every cell, the Assignment List talks
# to the exchange mounted at {exchange}.
COPY jupyter /usr/local/etc/jupyter
USER 1000
WORKDIR /home/jovyan
ENV SHELL=/bin/bash
EXPOSE 8888
CMD ["jupyterhub-singleuser"]
"""

_VALUES = """\
# Zero to JupyterHub values for the course (the jupyterhub Helm chart, 4.x), written by
# `duckie hub image`:
#   helm upgrade --install duckiebot jupyterhub/jupyterhub --values values.yaml
# Sized from `duckie bench hub` (see the README): about 220 MB per student after a notebook's
# Run All, and one core runs about one notebook's Run All at a time at full speed.
singleuser:
  image:
    name: {image}
    tag: "{tag}"
  defaultUrl: /lab
  cmd: jupyterhub-singleuser
  memory:
    guarantee: 512M
    limit: 2G
  cpu:
    guarantee: 0.25
    limit: 2
  storage:
    capacity: 2Gi
    extraVolumes:
      # nbgrader's exchange: one ReadWriteMany volume (NFS, CephFS...) shared by every pod
      # and the instructors' machine, made before the install.
      - name: nbgrader-exchange
        persistentVolumeClaim:
          claimName: nbgrader-exchange
    extraVolumeMounts:
      - name: nbgrader-exchange
        mountPath: {exchange}
hub:
  config:
    JupyterHub:
      authenticator_class: {authenticator}
    Authenticator:
      admin_users: {instructors}
      allowed_users: {students}
  extraConfig:
    duckiebot-accounts: |
      # Each student's pod runs as a Unix user of its own, as on one machine: nbgrader's
      # exchange then keeps each submission to its student (one uid for all would let every
      # student read every submission). USER names the student for nbgrader.
      c.KubeSpawner.uid = lambda spawner: 100000 + spawner.user.id
      c.KubeSpawner.gid = 100
      c.KubeSpawner.fs_gid = 100
      c.KubeSpawner.environment.update({{"USER": lambda spawner: spawner.user.name}})
"""


def write_image(
    out: Path,
    image: str,
    hub: Optional[Hub] = None,
    authenticator: str = "nativeauthenticator.NativeAuthenticator",
    progress: Optional[Callable[[str], None]] = None,
) -> Path:
    """Write a Docker build folder for the students' image, and its Zero to JupyterHub values.

    ``out`` gets the student edition (``edition/``), the course's Jupyter configuration
    (``jupyter/``), a ``Dockerfile`` and ``values.yaml`` (the image, the exchange's volume, the
    accounts of ``hub`` if given, each student's pod its own uid).

    Raises:
        HubError: if ``out`` exists and is not empty.
    """
    from autograder.edition import build_edition

    out = Path(out).absolute()
    if out.exists() and any(out.iterdir()):
        raise HubError(f"{out} is not empty: give a new folder for the image's files.")
    say = progress or (lambda line: None)
    say("building the student edition (what students receive) ...")
    edition = build_edition(out / "edition")
    shutil.rmtree(out / "edition" / ".git")
    _write_jupyter_config(out / "jupyter", POD_EXCHANGE)
    tag = edition.commit[:12]
    _write(
        out / "Dockerfile",
        _DOCKERFILE.format(image=image, tag=tag, exchange=str(POD_EXCHANGE)),
        0o644,
    )
    students = sorted(hub.students) if hub else []
    instructors = sorted(hub.instructors) if hub else []
    values = _VALUES.format(
        image=image,
        tag=tag,
        exchange=str(POD_EXCHANGE),
        authenticator=authenticator,
        instructors=json.dumps(instructors),
        students=json.dumps(students + instructors),
    )
    _write(out / "values.yaml", values, 0o644)
    return out
