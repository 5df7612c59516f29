"""Reading what a student handed in, or what a sandboxed run wrote, without trusting it.

A student's folder, and every folder a sandboxed run could write, may hold anything a program
can make: symbolic links to the grader's files (the reference solutions), FIFOs that block the
reader of ``open()`` for ever, sparse files of 100 GB that read as zeros, devices, sockets. The
grader reads such a folder only through this module:

- only regular files, opened with ``O_NOFOLLOW`` and ``O_NONBLOCK`` at every step of the path
  (a link anywhere on the way is refused, not followed) and checked with ``fstat`` once open,
  so nothing can be swapped in between the check and the read;
- each file, and all of a folder together, no bigger than a bound;
- everything left out is said, in one sentence per file.
"""

from __future__ import annotations

import os
import stat
import zipfile
from dataclasses import dataclass, field
from fnmatch import fnmatch
from pathlib import Path, PurePosixPath
from typing import Dict, Iterable, List, Tuple, Union

from duckielib.errors import DuckielibError

__all__ = [
    "FILE_LIMIT",
    "FOLDER_LIMIT",
    "Collected",
    "UnsafeFile",
    "collect_folder",
    "read_regular",
    "unpack_zip",
]

#: The biggest file read from a student's folder, in bytes.
FILE_LIMIT = 50 * 1024**2
#: The most read from one student's folder, all files together, in bytes.
FOLDER_LIMIT = 200 * 1024**2
#: The most files read from one student's folder (the course's folders hold a few each).
COUNT_LIMIT = 2000
#: The longest path read, in bytes, and the longest name of one file or folder in it.
PATH_LIMIT = 1024
NAME_LIMIT = 255
#: How many files left out are said one by one; the others are counted in one sentence.
SAID_LIMIT = 50

_FLAGS = os.O_RDONLY | os.O_NOFOLLOW | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0)
_KINDS = (
    (stat.S_ISLNK, "a symbolic link"),
    (stat.S_ISFIFO, "a FIFO"),
    (stat.S_ISSOCK, "a socket"),
    (stat.S_ISCHR, "a device"),
    (stat.S_ISBLK, "a device"),
    (stat.S_ISDIR, "a folder"),
)


class UnsafeFile(DuckielibError):
    """A file the grader will not read: not a regular file, reached through a link, too big."""


def _kind(mode: int) -> str:
    return next((name for test, name in _KINDS if test(mode)), "not a regular file")


def _size(count: int) -> str:
    return f"{count / 1024**2:.1f} MB" if count >= 1024**2 else f"{count} bytes"


def read_regular(base: Union[str, Path], relative: str, limit: int = FILE_LIMIT) -> bytes:
    """The bytes of the regular file ``base/relative``, following no link on the way.

    ``base`` itself is the grader's own folder and is trusted; every part of ``relative`` is
    opened without following links, so a run cannot point the grader at a file elsewhere.

    Args:
        base: a folder of the grader's.
        relative: the file's path below ``base`` (``"run/mission.bag"``).
        limit: the largest size accepted, in bytes.

    Raises:
        UnsafeFile: saying why the file is not read (missing, a link, a FIFO, too big...).
    """
    parts = PurePosixPath(relative).parts
    if not parts or any(part in ("..", "/") for part in parts):
        raise UnsafeFile(f"{relative} is not a path inside the folder.")
    folder = os.open(base, os.O_RDONLY | os.O_DIRECTORY)
    try:
        for part in parts[:-1]:
            try:
                inner = os.open(part, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW, dir_fd=folder)
            except OSError:
                raise UnsafeFile(f"{relative}: {part} is not a folder.") from None
            os.close(folder)
            folder = inner
        try:
            handle = os.open(parts[-1], _FLAGS, dir_fd=folder)
        except FileNotFoundError:
            raise UnsafeFile(f"{relative} does not exist.") from None
        except OSError:  # ELOOP: a link
            raise UnsafeFile(f"{relative} is a symbolic link.") from None
    finally:
        os.close(folder)
    with os.fdopen(handle, "rb") as opened:
        info = os.fstat(opened.fileno())
        if not stat.S_ISREG(info.st_mode):
            raise UnsafeFile(f"{relative} is {_kind(info.st_mode)}, not a file.")
        if info.st_size > limit:
            raise UnsafeFile(
                f"{relative} is {_size(info.st_size)}; at most {_size(limit)} is read."
            )
        data = opened.read(limit + 1)
    if len(data) > limit:
        raise UnsafeFile(f"{relative} grew past {_size(limit)} while it was read.")
    return data


@dataclass
class Collected:
    """The files taken from a folder, and what was left out.

    Attributes:
        files: ``relative path -> bytes`` of every file taken (POSIX paths).
        left_out: one sentence per file or folder left out, and why.
    """

    files: Dict[str, bytes] = field(default_factory=dict)
    left_out: List[str] = field(default_factory=list)
    #: The bytes taken so far, kept as files are added (:meth:`add`), so that reading a folder
    #: of many files takes time in proportion to them.
    taken: int = 0
    unsaid: int = 0

    @property
    def size(self) -> int:
        """The bytes taken, all files together."""
        return self.taken

    def add(self, name: str, data: bytes) -> None:
        """Take file ``name``."""
        self.taken += len(data) - len(self.files.get(name, b""))
        self.files[name] = data

    def leave_out(self, sentence: str) -> None:
        """Say that something was left out (the first :data:`SAID_LIMIT` one by one)."""
        if len(self.left_out) < SAID_LIMIT:
            self.left_out.append(sentence)
        else:
            self.unsaid += 1

    def cannot_take(self, name: str, count_limit: int, where: str) -> str:
        """Why file ``name`` is not taken (its name is too long, or enough files were), or ""."""
        too_long = _too_long(name)
        if too_long:
            return too_long
        if len(self.files) >= count_limit:
            return f"{name} was left out: at most {count_limit} files are read from {where}."
        return ""

    def close(self) -> Collected:
        """Say how many more were left out than were said; return this."""
        if self.unsaid:
            self.left_out.append(f"{self.unsaid} more files were left out (not listed one by one).")
            self.unsaid = 0
        return self


def _too_long(name: str) -> str:
    """Why the path ``name`` is not read, or "" if it may be."""
    raw = name.encode("utf-8", "surrogateescape")
    if len(raw) > PATH_LIMIT or any(
        len(part.encode("utf-8", "surrogateescape")) > NAME_LIMIT
        for part in PurePosixPath(name).parts
    ):
        return f"{name[:60]}... has a name longer than a file system takes; it was left out."
    return ""


def collect_folder(
    folder: Union[str, Path],
    skip: Iterable[str] = (),
    file_limit: int = FILE_LIMIT,
    folder_limit: int = FOLDER_LIMIT,
    count_limit: int = COUNT_LIMIT,
) -> Collected:
    """Every regular file below ``folder``, read safely (see the module's description).

    Links, FIFOs, sockets and devices are left out and said; so are files bigger than
    ``file_limit`` and, once ``folder_limit`` is reached, every file after it. Names that
    match a pattern of ``skip`` (``"*.pyc"``, ``".*"``) are left out without a word.

    Args:
        folder: the folder to read (itself not a link).
        skip: glob patterns of names (not paths) to leave out silently.
        file_limit: the largest file taken, in bytes.
        folder_limit: the most taken in all, in bytes.
        count_limit: the most files taken; names that are too long for a file system are left
            out too. Past :data:`SAID_LIMIT` sentences, the files left out are counted.
    """
    skip = tuple(skip)
    collected = Collected()
    root = Path(folder)
    pending: List[Tuple[Path, str]] = [(root, "")]
    while pending:
        directory, prefix = pending.pop()
        try:
            entries = sorted(os.scandir(directory), key=lambda entry: entry.name)
        except OSError as error:
            collected.left_out.append(f"{prefix or '.'}: the folder cannot be read ({error}).")
            continue
        for entry in entries:
            name = f"{prefix}{entry.name}"
            if _skipped((entry.name,), skip):
                continue
            info = entry.stat(follow_symlinks=False)
            if stat.S_ISDIR(info.st_mode):
                pending.append((Path(entry.path), f"{name}/"))
                continue
            if not stat.S_ISREG(info.st_mode):
                collected.leave_out(f"{name} is {_kind(info.st_mode)}; it was left out.")
                continue
            room = folder_limit - collected.size
            why = collected.cannot_take(name, count_limit, "a folder")
            if why:
                collected.leave_out(why)
                continue
            if info.st_size > file_limit:
                collected.leave_out(
                    f"{name} is {_size(info.st_size)}; at most {_size(file_limit)} is read. "
                    "It was left out."
                )
                continue
            if info.st_size > room:
                collected.leave_out(
                    f"{name} was left out: the folder's files passed {_size(folder_limit)}."
                )
                continue
            try:  # read as it is now, which may not be what it was a moment ago
                data = read_regular(root, name, min(file_limit, room))
            except UnsafeFile as error:
                collected.leave_out(f"{error} It was left out.")
                continue
            collected.add(name, data)
    return collected.close()


def unpack_zip(
    archive: Union[str, Path],
    skip: Iterable[str] = (),
    folder_limit: int = FOLDER_LIMIT,
    count_limit: int = COUNT_LIMIT,
) -> Collected:
    """The files of a ``.zip`` as :func:`collect_folder` gives a folder's, never written to disk.

    Members with absolute paths or ``..`` make the whole archive refused; links (zip can hold
    them as Unix modes) are left out; so is everything once ``folder_limit`` bytes or
    ``count_limit`` files are taken, and every member whose name is too long for a file system.
    A member with a part of its path matching a pattern of ``skip`` is left out silently.

    Raises:
        UnsafeFile: if the archive cannot be read or holds a path outside itself.
    """
    skip = tuple(skip)
    collected = Collected()
    try:
        with zipfile.ZipFile(archive) as opened:
            members = opened.infolist()
            for member in members:
                path = PurePosixPath(member.filename)
                if member.filename.startswith("/") or ".." in path.parts:
                    raise UnsafeFile(f"it holds the unsafe path {member.filename!r}")
            for member in members:
                mode = member.external_attr >> 16
                name = PurePosixPath(member.filename).as_posix()
                if member.is_dir() or _skipped(PurePosixPath(member.filename).parts, skip):
                    continue
                if stat.S_IFMT(mode) not in (0, stat.S_IFREG):  # a link, a FIFO...
                    collected.leave_out(f"{member.filename} is {_kind(mode)}; it was left out.")
                    continue
                why = collected.cannot_take(name, count_limit, "an archive")
                if why:
                    collected.leave_out(why)
                    continue
                if collected.size + member.file_size > folder_limit:
                    collected.leave_out(
                        f"{member.filename} was left out: the archive's files passed "
                        f"{_size(folder_limit)}."
                    )
                    continue
                with opened.open(member) as handle:
                    data = handle.read(folder_limit - collected.size + 1)
                if collected.size + len(data) > folder_limit:
                    collected.leave_out(
                        f"{member.filename} was left out: the archive's files passed "
                        f"{_size(folder_limit)}."
                    )
                    continue
                collected.add(name, data)
    except (zipfile.BadZipFile, OSError, EOFError, NotImplementedError, ValueError) as error:
        raise UnsafeFile(f"it is not a readable zip ({error})") from None
    except UnsafeFile:
        raise
    return collected.close()


def _skipped(parts: Iterable[str], skip: Iterable[str]) -> bool:
    """Whether any part of a path matches a glob pattern of ``skip``."""
    return any(fnmatch(part, pattern) for part in parts for pattern in skip)


def write_files(folder: Path, files: Dict[str, bytes]) -> None:
    """Write ``relative path -> bytes`` below ``folder`` (which the grader owns)."""
    for name, data in files.items():
        target = folder / name
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_bytes(data)
