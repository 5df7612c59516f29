"""Formgrader on a class hub: run as the hub's own unprivileged account, in a view of its own.

Formgrader is the hub's service for instructors (``/services/formgrader/``): it shows the
autograded notebooks and writes the grades and comments a person gives into the gradebook. It
needs nothing of root. JupyterHub runs as root (it starts each student's server as that
student) and starts its services as root, so the service's command, ``python -m
autograder.hub_formgrader HUB``, gives root up before Formgrader starts:

- Formgrader runs as the hub's own account (:func:`service_account`: a system account named
  after the hub's folder, ``duckiebot-hub`` for ``/srv/duckiebot-hub``, that ``duckie hub
  start`` makes, with no password, no home and no login shell), with no capability and no way
  to gain one. Not an instructor's own account: one Formgrader serves every instructor of the
  hub, and whoever took its page over (a student's script past the sanitiser and the policy of
  :mod:`autograder.formgrade_csp`, a stolen instructor's login) would get what that account
  may do. An instructor's account has a home, a password, and perhaps sudo; this one may only
  read and write the grading folder.
- It sees a view of the machine of its own (bubblewrap, as the grader's process for a student
  does, :mod:`autograder.sandbox.unit_process`): the system, the Python environment and the
  course's code read-only, ``grading/work`` (the gradebook, the autograded notebooks) the one
  folder it writes to, and, where ``solutions/`` is, an empty folder per assignment (Formgrader
  lists the assignments from the source's folders). Not ``solutions/`` itself (this repository
  is closed to other users), the hub's accounts and passwords, the exchange or any home.
- Its server opens no terminal (``terminals_enabled`` off) and starts no kernel
  (:class:`NoKernels` refuses, and no kernel is offered); Formgrader's buttons that run
  students' code or write elsewhere (generate, release, collect, autograde, feedback) answer
  403: grading is ``duckie grade``'s, in its sandbox, and the exchange's steps ``duckie hub``'s.

Files (:func:`share_grading`): ``grading/`` belongs to root and the account's group (2750:
nobody else gets in); ``grading/work`` is 3770: the group may write there (SQLite writes the
gradebook's journal beside it), and the sticky bit keeps it from replacing what root made (a
link planted there could make root write elsewhere). Root makes the names it writes first: the
gradebook (``root:GROUP``, 0660; SQLite gives each journal the owner and mode of its database),
``release/``, ``autograded/``, ``submitted/``. ``duckie grade`` writes its files 0600, as root:
while Formgrader runs, this command, still root outside the view, makes each file and folder
root made in ``grading/work`` readable by the group (:func:`share`), opening each without
following links and changing only root's own.
"""

from __future__ import annotations

import json
import os
import pwd
import re
import shutil
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

from jupyter_server.services.kernels.kernelmanager import AsyncMappingKernelManager
from tornado import web

__all__ = [
    "NoKernels",
    "server_command",
    "service_account",
    "share",
    "share_grading",
    "view_command",
]

#: This module's name, as Formgrader's server imports it (it runs as ``__main__`` too).
MODULE = "autograder.hub_formgrader"
#: Why the service starts no kernel, as its server answers.
NO_KERNEL = (
    "Formgrader on the hub runs no kernel and no terminal: grade with `duckie grade` on the "
    "hub's machine, where each student's code runs in its sandbox."
)
#: Formgrader's buttons that run students' code or write outside the gradebook.
REFUSED_ACTIONS = (
    "AssignHandler",
    "UnReleaseHandler",
    "ReleaseHandler",
    "CollectHandler",
    "AutogradeHandler",
    "GenerateAllFeedbackHandler",
    "ReleaseAllFeedbackHandler",
    "GenerateFeedbackHandler",
    "ReleaseFeedbackHandler",
)
#: The names root writes in ``grading/work``: made by root before Formgrader may write there.
ROOTS_FOLDERS = ("release", "autograded", "submitted")
ROOTS_FILES = ("gradebook.db", "nbgrader_config.py", "course.json")
#: The size of the service's ``/tmp`` (its home and Jupyter's runtime files).
TMP_BYTES = 256 * 1024**2
#: How often the launcher looks for root's new files, and for how long after a change.
SHARE_EVERY_S = 1.0
SHARE_AFTER_CHANGE_S = 10.0
SHARE_ANYWAY_S = 60.0


class NoKernels(AsyncMappingKernelManager):
    """The service's kernel manager: it starts no kernel, so no code runs in its server."""

    # Awaited by the server, as AsyncMappingKernelManager's own (typed by a synchronous base).
    async def start_kernel(self, *args: Any, **kwargs: Any) -> str:  # type: ignore[override]
        """Refuse: a kernel's, a console's or a notebook's request answers 403."""
        raise web.HTTPError(403, NO_KERNEL)


def service_account(root: Path) -> str:
    """The name of the hub's own account: its folder's name (``duckiebot-hub``), as a login."""
    name = re.sub(r"[^a-z0-9_-]", "-", Path(root).name.lower())
    if not re.match(r"[a-z_]", name):
        name = "hub-" + name
    return name[:32]


def grading_work(root: Path) -> Path:
    """The folder Formgrader serves and writes: nbgrader's course tree of the class."""
    return Path(root) / "grading" / "work"


def share_grading(grading: Path, gid: int) -> Path:
    """Give ``grading`` to root and the group ``gid``, and its ``work/`` as Formgrader needs it.

    See this module's docstring for the modes. A name root writes in ``work/`` that is not
    root's (a link or a file another user made there) is removed and made again by root.

    Returns:
        ``grading/work``.
    """
    grading.mkdir(exist_ok=True)
    os.chown(grading, 0, gid)
    grading.chmod(0o2750)
    work = grading / "work"
    work.mkdir(exist_ok=True)
    os.chown(work, 0, gid)
    work.chmod(0o3770)
    for name in [*ROOTS_FOLDERS, *ROOTS_FILES]:
        path = work / name
        if path.is_symlink() or (path.exists() and path.lstat().st_uid != 0):
            if path.is_dir() and not path.is_symlink():
                shutil.rmtree(path)
            else:
                path.unlink()
    for name in ROOTS_FOLDERS:
        (work / name).mkdir(exist_ok=True)
    database = os.open(
        work / "gradebook.db", os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o660
    )
    try:
        os.fchown(database, 0, gid)
        os.fchmod(database, 0o660)
    finally:
        os.close(database)
    share(work, gid)
    return work


def share(work: Path, gid: int) -> int:
    """Make each file and folder root made in ``work`` readable by the group ``gid``.

    The gradebook is made writable by the group too. Each entry is opened without following a
    link and changed only if it is root's own (a file with one name only): what the account
    made itself, or linked there, is left as it is.

    Returns:
        How many entries were changed.
    """
    changed = 0
    for folder, folders, files, descriptor in os.fwalk(work, follow_symlinks=False):
        at_top = Path(folder) == Path(work)
        for name in [*folders, *files]:
            writable = at_top and name.startswith("gradebook.db")
            changed += _share_one(descriptor, name, gid, writable)
    return changed


def _share_one(folder: int, name: str, gid: int, writable: bool) -> bool:
    """Give the group ``gid`` the entry ``name`` of the open folder ``folder``, if root's."""
    try:
        found = os.stat(name, dir_fd=folder, follow_symlinks=False)
    except OSError:  # gone meanwhile
        return False
    is_folder = stat.S_ISDIR(found.st_mode)
    wanted = (0o2050 if is_folder else 0o040) | (0o020 if writable else 0)
    if (
        found.st_uid != 0
        or not (is_folder or stat.S_ISREG(found.st_mode))
        or (found.st_gid == gid and found.st_mode & wanted == wanted)
    ):
        return False
    flags = os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | os.O_NOCTTY | os.O_CLOEXEC
    try:
        handle = os.open(name, flags, dir_fd=folder)
    except OSError:
        return False
    try:
        return _give(handle, found, gid, wanted)
    finally:
        os.close(handle)


def _give(handle: int, found: os.stat_result, gid: int, wanted: int) -> bool:
    """Give the open entry ``handle`` to the group ``gid``, if it is still root's ``found``."""
    opened = os.fstat(handle)
    if (
        opened.st_uid != 0
        or (opened.st_dev, opened.st_ino) != (found.st_dev, found.st_ino)
        or (not stat.S_ISDIR(opened.st_mode) and opened.st_nlink != 1)
    ):
        return False
    try:
        if opened.st_gid != gid:
            os.fchown(handle, -1, gid)
        os.fchmod(handle, stat.S_IMODE(opened.st_mode) | wanted)
    except OSError:  # a file system that refuses: left as it is, tried again later
        return False
    return True


def server_command(work: Path) -> List[str]:
    """Formgrader's server: JupyterLab with Formgrader on ``work``, no terminal, no kernel."""
    return [
        str(Path(sys.executable).parent / "jupyterhub-singleuser"),
        f"--ServerApp.root_dir={work}",
        # A strict Content-Security-Policy on Formgrader's pages (autograder.formgrade_csp), and
        # Formgrader's buttons that run code refused (this module).
        "--ServerApp.jpserver_extensions=autograder.formgrade_csp=True",
        f"--ServerApp.jpserver_extensions={MODULE}=True",
        "--ServerApp.terminals_enabled=False",
        f"--ServerApp.kernel_manager_class={MODULE}.NoKernels",
        "--KernelSpecManager.allowed_kernelspecs=none",
    ]


def view_command(
    root: Path, account: pwd.struct_passwd, assignments: Sequence[str], source: Path
) -> List[str]:
    """The command line that runs Formgrader's server as ``account``, in a view of its own.

    Args:
        root: the hub's folder: Formgrader writes its ``grading/work`` and sees nothing else
            of it.
        account: the hub's account, which the server runs as.
        assignments: the course's assignments, shown as empty folders in ``source``.
        source: where Formgrader's configuration says the course's source is.
    """
    from autograder.sandbox.bubblewrap import (
        folders_above,
        generated_robot_folders,
        namespaces,
        read_only_view,
    )
    from autograder.sandbox.unit_process import grader_paths

    bwrap = shutil.which("bwrap")
    if bwrap is None:
        raise FileNotFoundError(
            "bubblewrap (bwrap) is not installed: install it (Debian: apt-get install "
            "bubblewrap, or `make ros`), then start the hub again."
        )
    work = grading_work(root)
    args = [bwrap, *namespaces(network=False)]  # the hub reaches it over the network
    tmp = ["--perms", "1777", "--size", str(TMP_BYTES), "--tmpfs", "/tmp"]
    shown, made = read_only_view(grader_paths(), tmp)
    args += shown

    def folders(*paths: str) -> None:
        for path in paths:
            if path not in made:
                args.extend(["--perms", "0755", "--dir", path])
                made.add(path)

    # `duckie robot prepare` writes a solution into the robot project: out of sight, as in the
    # students' sandboxes.
    for path in generated_robot_folders():
        args += ["--tmpfs", path]
    for name in assignments:
        folders(*folders_above(str(source / name)), str(source / name))
    folders(*folders_above(str(work)))
    args += [
        "--bind", str(work), str(work),
        "--dev", "/dev",
        "--proc", "/proc",
        "--chdir", str(work),
        # Only to become the account just below; setpriv then drops every capability.
        "--cap-add", "CAP_SETUID",
        "--cap-add", "CAP_SETGID",
        "setpriv",
        f"--reuid={account.pw_uid}",
        f"--regid={account.pw_gid}",
        "--clear-groups",
        "--no-new-privs",
        "--inh-caps=-all",
        "--bounding-set=-all",
        "--",
    ]  # fmt: skip
    return args + server_command(work)


def server_environment(account: pwd.struct_passwd, given: Mapping[str, str]) -> Dict[str, str]:
    """The server's environment: its own, and what JupyterHub gave the service (``given``).

    Given as the environment, never on a command line: JupyterHub's token for the service is
    in it, and every user of the machine can read a process's command line.
    """
    environment = {
        "HOME": "/tmp",
        "USER": account.pw_name,
        "LOGNAME": account.pw_name,
        "SHELL": "/usr/sbin/nologin",
        "PATH": f"{Path(sys.executable).parent}:/usr/bin:/bin",
        "LANG": given.get("LANG", "C.UTF-8"),
        "PYTHONDONTWRITEBYTECODE": "1",
    }
    environment.update(
        {key: value for key, value in given.items() if key.startswith("JUPYTERHUB_")}
    )
    return environment


def _die_with_hub() -> None:
    """Be stopped when JupyterHub, which started this command, ends (Linux)."""
    import ctypes

    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


def _changed(work: Path) -> Tuple[Optional[Tuple[int, int, int]], ...]:
    """What tells that root wrote in ``work``: the gradebook's and the folder's changes."""
    marks: List[Optional[Tuple[int, int, int]]] = []
    for path in (work / "gradebook.db", work, work / "autograded", work / "submitted"):
        try:
            found = path.stat()
        except OSError:
            marks.append(None)
            continue
        marks.append((found.st_ino, found.st_mtime_ns, found.st_size))
    return tuple(marks)


def run(root: Path) -> int:
    """Run Formgrader for the hub in ``root`` until it ends or JupyterHub stops it.

    Formgrader runs in its view as the hub's account; this process stays root meanwhile, to
    share what ``duckie grade`` writes (:func:`share`), at most about a second after it does.

    Returns:
        Formgrader's exit status.
    """
    from autograder.course import ROOT, assignments

    root = Path(root).absolute()
    try:
        account = pwd.getpwnam(service_account(root))
    except KeyError:
        print(
            f"The hub's account {service_account(root)} is missing: start the hub with "
            "`duckie hub start`, which makes it.",
            file=sys.stderr,
        )
        return 1
    _die_with_hub()
    work = share_grading(root / "grading", account.pw_gid)
    source = (ROOT / "solutions").resolve()
    command = view_command(root, account, assignments(source), source)
    server = subprocess.Popen(command, env=server_environment(account, os.environ), cwd=work)

    def stop(number: int, frame: Optional[Any]) -> None:
        server.terminate()

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    last, changed_at, shared_at = _changed(work), time.monotonic(), time.monotonic()
    while True:
        try:
            return server.wait(timeout=SHARE_EVERY_S)
        except subprocess.TimeoutExpired:
            pass
        now, seen = time.monotonic(), _changed(work)
        if seen != last:
            last, changed_at = seen, now
        if now - changed_at < SHARE_AFTER_CHANGE_S or now - shared_at > SHARE_ANYWAY_S:
            share(work, account.pw_gid)
            shared_at = now


# -- inside Formgrader's server ------------------------------------------------------------------


def _jupyter_server_extension_points() -> list:
    return [{"module": MODULE}]


def _load_jupyter_server_extension(serverapp: Any) -> None:
    """Refuse Formgrader's buttons that run students' code or write outside the gradebook."""
    from nbgrader.server_extensions.formgrader import apihandlers

    def refuse(self: web.RequestHandler, *args: Any) -> None:
        # As the server's API answers (Formgrader's own error page would say "not authorized").
        self.set_status(403)
        self.set_header("Content-Type", "application/json")
        self.finish(json.dumps({"message": NO_KERNEL}))

    for name in REFUSED_ACTIONS:
        getattr(apihandlers, name).post = refuse


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: python -m autograder.hub_formgrader HUB")
    sys.exit(run(Path(sys.argv[1])))
