"""What a node finds on a Duckiebot that a laptop lacks, for ``duckie run``.

- **The robot's** ``/data``: a node that records to ``/data/bags/run.bag`` or creates
  ``/data/logs/mine`` writes into the run's folder instead (``OUT/data/``, which holds the
  robot's ``bags``, ``config``, ``logs`` and ``stats`` folders), for plain file calls
  (``open``, ``os``, ``pathlib``) and the ``rosbag`` API alike; nothing is written to the
  laptop's ``/``.
- **Simulated clocks**: ``time.time()``, ``monotonic()`` and ``perf_counter()`` (and their
  ``_ns`` forms) called from the project's own files, in a node's code, read the simulated
  clock, as ``time.sleep`` already waits simulated seconds: a controller that takes its dt from
  ``time.time()`` sees the dt it would see on the robot. Libraries and everything outside the
  nodes keep the wall clock.
- **The host's name** is the robot's (``VEHICLE_NAME``) for ``socket.gethostname()``,
  ``os.uname()`` and ``platform.node()`` called from the project's node code, as in a
  container that shares the robot's network.
- **Windows**: ``cv2.imshow`` shows no window here; each window's latest frame is saved as
  ``OUT/windows/NAME.png``, every frame goes into the run's bag as the image topic
  ``/cv2_windows/NAME/compressed`` (which ``ImageView.from_bag`` plays in a notebook), and the
  run says so once. ``cv2.waitKey`` returns -1 (no key).

Laptop side; never deployed.
"""

from __future__ import annotations

import builtins
import contextlib
import io
import os
import re
import sys
import time
from pathlib import Path
from typing import Any, Callable, Dict, Iterator, List, Optional

__all__ = ["node_clocks", "robot_data", "robot_hostname", "window_topic", "windows_saved"]

#: The robot's data volume, as nodes name it.
ROBOT_DATA = "/data"
#: Folders of a Duckiebot's /data that nodes write into without creating them (students' nodes
#: record to /data/bags/... directly: their bags came back from their robots).
ROBOT_DATA_FOLDERS = ("bags", "config", "logs", "stats")

#: The os functions whose first argument is a path (the second too for rename and replace).
_ONE_PATH = (
    "open",
    "stat",
    "lstat",
    "mkdir",
    "makedirs",
    "listdir",
    "scandir",
    "remove",
    "unlink",
    "rmdir",
    "access",
    "chmod",
)
_TWO_PATHS = ("rename", "replace")


@contextlib.contextmanager
def robot_data(folder: Path) -> Iterator[Path]:
    """While inside, paths in ``/data`` lead to ``folder`` (created); yields it."""
    for sub in ROBOT_DATA_FOLDERS:
        (folder / sub).mkdir(parents=True, exist_ok=True)
    target = str(folder)

    def mapped(path: Any) -> Any:
        if isinstance(path, int):  # a file descriptor
            return path
        try:
            text = os.fspath(path)
        except TypeError:
            return path
        if isinstance(text, bytes):
            return path
        if text == ROBOT_DATA or text.startswith(ROBOT_DATA + "/"):
            return target + text[len(ROBOT_DATA) :]
        return path

    def one_path(function: Callable[..., Any]) -> Callable[..., Any]:
        def call(path: Any, *args: Any, **kwargs: Any) -> Any:
            return function(mapped(path), *args, **kwargs)

        call.__wrapped__ = function  # type: ignore[attr-defined]
        return call

    def two_paths(function: Callable[..., Any]) -> Callable[..., Any]:
        def call(source: Any, destination: Any, *args: Any, **kwargs: Any) -> Any:
            return function(mapped(source), mapped(destination), *args, **kwargs)

        call.__wrapped__ = function  # type: ignore[attr-defined]
        return call

    saved: Dict[Any, Dict[str, Any]] = {os: {}, builtins: {}, io: {}}
    for name in _ONE_PATH:
        saved[os][name] = getattr(os, name)
    for name in _TWO_PATHS:
        saved[os][name] = getattr(os, name)
    saved[builtins]["open"] = builtins.open
    saved[io]["open"] = io.open
    try:
        for name in _ONE_PATH:
            setattr(os, name, one_path(saved[os][name]))
        for name in _TWO_PATHS:
            setattr(os, name, two_paths(saved[os][name]))
        builtins.open = one_path(saved[builtins]["open"])
        io.open = builtins.open
        yield folder
    finally:
        for module, functions in saved.items():
            for name, function in functions.items():
                setattr(module, name, function)


#: The clocks of ``time`` a node's code may read.
_CLOCKS = ("time", "monotonic", "perf_counter", "time_ns", "monotonic_ns", "perf_counter_ns")


def _node_code_under(root: Path) -> Callable[[int], bool]:
    """A test, ``called(depth)``: is this code, ``depth`` frames up, the project's node code?

    True when that frame's file is under ``root`` and it runs in a node's code (not a library,
    not the notebook).
    """
    from duckielib.ros.rospy.timing import calling_node

    prefix = str(root) + os.sep

    def called(depth: int) -> bool:
        caller = sys._getframe(depth + 1).f_code.co_filename
        return caller.startswith(prefix) and calling_node() is not None

    return called


@contextlib.contextmanager
def node_clocks(root: Path, simulated: Callable[[], float]) -> Iterator[None]:
    """While inside, the clocks read from files under ``root``, in a node's code, are simulated.

    Args:
        root: the project's folder: only its own files see the simulated clock.
        simulated: the simulated time, in seconds.
    """
    in_node_code = _node_code_under(root)
    walls = {name: getattr(time, name) for name in _CLOCKS}
    epoch = walls["time"]() - simulated()  # time.time() goes on from the wall clock's now

    def clock(name: str) -> Callable[[], Any]:
        wall = walls[name]
        offset = epoch if name.startswith("time") else 0.0
        in_ns = name.endswith("_ns")

        def read() -> Any:
            if not in_node_code(1):
                return wall()
            seconds = simulated() + offset
            return int(seconds * 1_000_000_000) if in_ns else seconds

        read.__wrapped__ = wall  # type: ignore[attr-defined]
        return read

    try:
        for name in _CLOCKS:
            setattr(time, name, clock(name))
        yield
    finally:
        for name, wall in walls.items():
            setattr(time, name, wall)


@contextlib.contextmanager
def robot_hostname(root: Path, name: str) -> Iterator[None]:
    """While inside, the project's node code finds the robot's name as the host's name.

    On a Duckiebot the container shares the robot's network, and its host name is the
    robot's name: nodes read it with ``socket.gethostname()``, ``os.uname()`` or
    ``platform.node()`` (to build their topics' names, or to tell robots apart). Called from
    the project's own files in a node's code, those give ``name``; elsewhere, the laptop's.
    """
    import platform
    import socket

    in_node_code = _node_code_under(root)
    laptop_hostname, laptop_uname, laptop_node = socket.gethostname, os.uname, platform.node

    def gethostname() -> str:
        return name if in_node_code(1) else laptop_hostname()

    def uname() -> Any:
        found = laptop_uname()
        if not in_node_code(1):
            return found
        return os.uname_result((found.sysname, name, found.release, found.version, found.machine))

    def node() -> str:
        return name if in_node_code(1) else laptop_node()

    try:
        socket.gethostname, platform.node = gethostname, node
        os.uname = uname
        yield
    finally:
        socket.gethostname, os.uname, platform.node = laptop_hostname, laptop_uname, laptop_node


def window_topic(window: str) -> str:
    """The topic of a ``cv2`` window's frames in a run: ``/cv2_windows/NAME/compressed``."""
    name = re.sub(r"[^A-Za-z0-9_]+", "_", str(window)).strip("_") or "window"
    return f"/cv2_windows/{name}/compressed"


@contextlib.contextmanager
def windows_saved(
    folder: Path, notes: List[str], publish: Optional[Callable[[str, bytes], None]] = None
) -> Iterator[Dict[str, int]]:
    """While inside, ``cv2``'s windows save their frames in ``folder``; yields frames by window.

    Each window's latest frame is ``folder/NAME.png``; with ``publish``, every frame is also
    handed to ``publish(topic, jpeg)`` (the topic of :func:`window_topic`), so a run's bag
    holds the window as an image topic that ``ImageView.from_bag`` plays. The first frame
    shown adds a sentence to ``notes``.
    """
    import cv2
    import numpy as np

    shown: Dict[str, int] = {}

    def imshow(window: str, image: Any) -> None:
        if not shown:
            folder.mkdir(parents=True, exist_ok=True)
            where = f"each window's latest frame is saved in {folder}"
            if publish is not None:
                where += ", and all its frames are in run.bag on /cv2_windows/NAME/compressed"
            notes.append(f"cv2.imshow shows no window here: {where}.")
        shown[window] = shown.get(window, 0) + 1
        frame = np.asarray(image)
        if frame.dtype.kind == "f":  # imshow shows floats as 0..1, as 8-bit images 0..255
            frame = (np.clip(frame, 0.0, 1.0) * 255).round().astype(np.uint8)
        safe = re.sub(r"[^\w.-]+", "_", str(window)) or "window"
        cv2.imwrite(str(folder / f"{safe}.png"), frame)
        if publish is not None:
            encoded, jpeg = cv2.imencode(".jpg", frame)
            if encoded:
                publish(window_topic(window), jpeg.tobytes())

    def nothing(*args: Any, **kwargs: Any) -> None:
        return None

    def wait_key(delay: int = 0) -> int:
        return -1

    standing_in = {
        "imshow": imshow,
        "namedWindow": nothing,
        "waitKey": wait_key,
        "destroyWindow": nothing,
        "destroyAllWindows": nothing,
    }
    saved = {name: getattr(cv2, name) for name in standing_in if hasattr(cv2, name)}
    try:
        for name, function in standing_in.items():
            setattr(cv2, name, function)
        yield shown
    finally:
        for name, function in saved.items():
            setattr(cv2, name, function)
