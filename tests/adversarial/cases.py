"""The adversarial submissions: what a student might hand in, on purpose or by accident.

Each case is notebook 03_frames filled with the reference answers (full marks, 9 points) and
then changed: a cell inserted (after the cell it names), answers replaced, or the file itself
broken. ``{paths}`` in a cell's code is filled in with the grader's own paths at test time, so
a case can try to reach them. What an instructor wants from each case is asserted in
``test_adversarial.py``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, Optional, Tuple

#: The assignment the cases are built on, and its points.
ASSIGNMENT = "03_frames"
FULL_MARKS = 9.0

#: A mission node that announces every state in its colour and holds every stop, but sleeps
#: instead of driving: the robot never leaves its start (exported after the student's own).
NEVER_DRIVES = """\
def mission_node(mission):
    rospy.init_node("mission_node")
    announce = rospy.Publisher("~state", String, queue_size=10, latch=True)
    shutdown = rospy.Publisher("shutdown", Empty, queue_size=1)
    rospy.wait_for_service("light_service_node/set_color", timeout=10.0)
    set_color = rospy.ServiceProxy("light_service_node/set_color", ChangePattern)
    for state in mission.states:
        set_color(String(data=state.color))
        announce.publish(String(data=state.name))
        for move in state.moves:
            rospy.sleep(move.seconds if isinstance(move, Stop) else 2.0)
    announce.publish(String(data="done"))
    shutdown.publish(Empty())
"""


#: A mission node that never drives but makes the recorded truth follow the ideal path: it
#: moves the simulator's robot body itself (found through the garbage collector), publishes
#: ideal poses as the simulator's ground truth, and would steer on the true pose if it were
#: offered. In one process with the simulator this once scored full driving marks.
FORGES_THE_DRIVE = """\
def mission_node(mission):
    import gc

    rospy.init_node("mission_node")
    announce = rospy.Publisher("~state", String, queue_size=10, latch=True)
    shutdown = rospy.Publisher("shutdown", Empty, queue_size=1)
    truth = rospy.Publisher("simulator_node/ground_truth_pose", Pose2DStamped, queue_size=10)
    rospy.wait_for_service("light_service_node/set_color", timeout=10.0)
    set_color = rospy.ServiceProxy("light_service_node/set_color", ChangePattern)
    simulators = [item for item in gc.get_objects() if type(item).__name__ == "Simulator"]
    try:
        rospy.wait_for_message("simulator_node/ground_truth_pose", Pose2DStamped, timeout=1.0)
        rospy.loginfo("the true pose is offered")
    except rospy.ROSException:
        rospy.loginfo("no true pose offered")
    x, y, theta = mission.start
    home = (x, y, theta)

    def place(pose):
        for simulator in simulators:
            simulator.robot.body.position = (pose[0], pose[1])
            simulator.robot.body.angle = pose[2]
        truth.publish(Pose2DStamped(x=pose[0], y=pose[1], theta=pose[2]))

    for state in mission.states:
        set_color(String(data=state.color))
        announce.publish(String(data=state.name))
        for move in state.moves:
            if isinstance(move, Stop):
                rospy.sleep(move.seconds)
                continue
            if isinstance(move, Straight):
                goal = (
                    x + move.distance * math.cos(theta),
                    y + move.distance * math.sin(theta),
                    theta,
                )
            elif isinstance(move, Rotate):
                goal = (x, y, theta + move.angle)
            else:
                goal = home
            for step in range(1, 41):
                share = step / 40
                pose = tuple(a + share * (b - a) for a, b in zip((x, y, theta), goal))
                place(pose)
                rospy.sleep(0.05)
            x, y, theta = goal
    announce.publish(String(data="done"))
    shutdown.publish(Empty())
"""


@dataclass(frozen=True)
class Case:
    """One adversarial submission.

    Attributes:
        cell: code inserted as a new cell.
        after: the ``grade_id`` of the cell it goes after (None: after the imports cell).
        answers: ``grade_id -> code`` replacing the reference answers.
        raw: the notebook file's whole text instead of a notebook (a malformed file).
        empty: the student's folder is empty.
        link: a symbolic link of that name is put in the folder, pointing at the gradebook.
        files: other files put next to the notebook, ``name -> text``.
        blank: the released notebook, every answer left unwritten, instead of the reference.
        top_files: files put in the student's own folder, beside the assignment folders.
    """

    cell: Optional[str] = None
    after: Optional[str] = None
    answers: Dict[str, str] = field(default_factory=dict)
    raw: Optional[str] = None
    empty: bool = False
    link: Optional[str] = None
    files: Dict[str, str] = field(default_factory=dict)
    blank: bool = False
    top_files: Dict[str, str] = field(default_factory=dict)


_TRY_READ = """\
import os
readable = []
for path in {paths}:
    try:
        if os.path.isdir(path):
            os.listdir(path)
        else:
            open(path, "rb").read(16)
        readable.append(path)
    except OSError:
        pass
print("readable:", readable)
"""

_TRY_WRITE = """\
import os
written = []
for folder in {paths} + ["/etc", "/usr", os.path.dirname(os.__file__)]:
    try:
        with open(os.path.join(folder, "pwned.txt"), "w") as handle:
            handle.write("pwned")
        written.append(folder)
    except OSError:
        pass
print("written:", written)
"""

_PATCH_HELPERS = """\
import math
import numpy
import numpy.testing

math.isclose = lambda *args, **kwargs: True
numpy.allclose = lambda *args, **kwargs: True
numpy.testing.assert_allclose = lambda *args, **kwargs: None


class _Anything:
    def __getattr__(self, name):
        return lambda *args, **kwargs: True


np = _Anything()
get_ipython().set_custom_exc((Exception,), lambda *args, **kwargs: None)
"""

# Each of these attacks gave marks for blank answers when the tests ran in the student's kernel.
_TURN_THE_TESTS_OFF = """\
import ast
import os

ip = get_ipython()


class _Swallow(ast.NodeTransformer):
    # Every later cell is wrapped in try/except BaseException: pass.
    def visit_Module(self, node):
        handler = ast.ExceptHandler(type=ast.Name("BaseException", ast.Load()), name=None,
                                    body=[ast.Pass()])
        body = [ast.Try(body=node.body or [ast.Pass()], handlers=[handler], orelse=[],
                        finalbody=[])]
        return ast.fix_missing_locations(ast.Module(body=body, type_ignores=[]))


ip.ast_transformers.append(_Swallow())
ip.input_transformers_post.append(
    lambda lines: [line.replace("assert ", "pass  # ") for line in lines]
)
# A startup file for the kernels of the notebooks after this one.
startup = os.path.join(ip.profile_dir.location, "startup")
os.makedirs(startup, exist_ok=True)
with open(os.path.join(startup, "00-pass.py"), "w") as handle:
    handle.write("import math\\nmath.isclose = lambda *a, **k: True\\n")
# The grader's answer pipe, if it can be reached: write a forged reply on it.
opened = []
for pid in [p for p in os.listdir("/proc") if p.isdigit() and int(p) != os.getpid()]:
    for fd in range(3, 12):
        try:
            with open(f"/proc/{pid}/fd/{fd}", "wb", buffering=0) as pipe:
                pipe.write(b"\\x00" * 8)
            opened.append(f"{pid}/{fd}")
        except OSError:
            pass
try:
    with open(f"/proc/{os.getppid()}/mem", "rb") as memory:
        memory.read(1)
    opened.append("mem")
except OSError:
    pass
print("opened:", opened)
"""

# Answers that look for the expected value in the test's frames, or return an array that
# compares equal to anything.
_PEEKING_ANSWERS = {
    "wrap_angle": """\
import sys


def wrap_angle(theta):
    frame = sys._getframe(1)
    while frame is not None:
        for name in ("expected", "want", "wanted"):
            if name in frame.f_locals:
                return frame.f_locals[name]
        frame = frame.f_back
    return 0.0
""",
    "rotation_matrix": """\
import numpy as np


class _Yes(np.ndarray):
    __hash__ = None

    def __eq__(self, other):
        return np.ones(self.shape, dtype=bool)

    def __array_function__(self, function, types, args, kwargs):
        return True

    def __array_ufunc__(self, ufunc, method, *inputs, **kwargs):
        return np.ones(self.shape, dtype=bool)


def rotation_matrix(theta):
    return np.zeros((2, 2)).view(_Yes)
""",
}

# A module beside the student's notebooks that would take the grader over if the grader ran
# the student's imports: it leaves a mark beside itself and makes every test pass.
_TAKE_OVER = """\
import os
import pathlib

try:
    pathlib.Path(__file__).with_name("TAKEN_OVER").write_text(str(os.getuid()))
except OSError:
    pass
try:
    import autograder.verdict

    autograder.verdict.TestRun._run = lambda self, code: None
except Exception:
    pass
"""

# Code that fills every place it may write, until the disk says no.
_FILL_THE_DISK = """\
import os

for folder in (".", "/tmp"):
    written = 0
    try:
        with open(os.path.join(folder, "filler.bin"), "wb") as handle:
            while True:
                handle.write(bytes(16 * 1024**2))
                written += 16
    except OSError as error:
        print(folder, "full after", written, "MB:", error.strerror)
"""

# A correct wrap_angle that keeps every angle it is given, and tries to leave each one where
# the grader reads notes (a path outside the student's folders); the last cell raises with
# all it kept.
_RECORDS_ITS_INPUTS = """\
import math

SEEN = []


def wrap_angle(theta):
    SEEN.append(repr(theta))
    try:
        open(f"/etc/seen-{theta!r}", "w")
    except OSError:
        pass
    wrapped = float(theta) % (2 * math.pi)
    return 0.0 if wrapped >= 2 * math.pi else wrapped
"""

# A result of full marks, written wherever the grader's process for the student keeps its own.
_FORGE_A_RESULT = """\
import json
import os

forged = {"student": "forges_a_result", "cells": {}, "problems": [], "complete": True}
written = []
for path in ("/unit/out/result.json", "/unit/result.json", "../../out/result.json",
             "../out/result.json", "result.json"):
    try:
        with open(path, "w") as handle:
            json.dump(forged, handle)
        written.append(os.path.abspath(path))
    except OSError:
        pass
print("written:", written)
"""

# A user namespace of its own, where the code would be root.
_MAKE_A_NAMESPACE = """\
import ctypes
import os

libc = ctypes.CDLL(None, use_errno=True)
made = libc.unshare(0x10000000)  # CLONE_NEWUSER
print("unshare:", made, os.strerror(ctypes.get_errno()) if made else "made")
"""

CASES: Dict[str, Case] = {
    "reference": Case(),
    "infinite_loop": Case(cell="while True:\n    pass\n"),
    "sys_exit": Case(cell="import sys\n\nsys.exit(1)\n"),
    "os_exit": Case(cell="import os\n\nos._exit(0)\n", after="test_wrap_angle"),
    "kernel_crash": Case(cell="import ctypes\n\nctypes.string_at(0)\n"),
    "memory_20gb": Case(cell="block = bytearray(20 * 1024**3)\n"),
    "fork_bomb": Case(cell="import os\n\nwhile True:\n    os.fork()\n"),
    "network": Case(
        cell="import socket\n\nsocket.create_connection(('pypi.org', 443), timeout=5)\n"
    ),
    "read_outside": Case(cell=_TRY_READ),
    "write_outside": Case(cell=_TRY_WRITE),
    "symlink_out": Case(cell=_TRY_READ.replace("{paths}", "['gradebook.db']"), link="gradebook.db"),
    "monkey_patch": Case(
        cell=_PATCH_HELPERS,
        after="world_from_start",
        answers={
            "wrap_angle": "def wrap_angle(theta):\n    return 0.0\n",
            "rotation_matrix": "def rotation_matrix(theta):\n    return [[1, 0], [0, 1]]\n",
        },
    ),
    "shadow_numpy": Case(
        files={"numpy.py": "def allclose(*args, **kwargs):\n    return True\n"},
        answers={
            "rotation_matrix": (
                "import numpy as np\n\n\ndef rotation_matrix(theta):\n    return np.eye(2)\n"
            )
        },
    ),
    "stderr": Case(
        cell="import sys\nimport warnings\n\nprint('a message on stderr', file=sys.stderr)\n"
        "warnings.warn('a warning')\n"
    ),
    "raises_outside_tests": Case(
        cell="print(undefined_name)\n",
        answers={"wrap_angle": "def wrap_angle(theta):\n    return theta\n"},
    ),
    "tests_turned_off": Case(cell=_TURN_THE_TESTS_OFF, blank=True),
    # Busy loops left running in the background, in sessions of their own.
    "busy_loops": Case(
        cell="import subprocess\nimport sys\n\nfor _ in range(8):\n"
        "    subprocess.Popen([sys.executable, '-c', 'while True: pass'], "
        "start_new_session=True)\n"
    ),
    # Correct answers that warn and log on stderr while the tests call them.
    "warns": Case(
        answers={
            "wrap_angle": "import logging\nimport math\nimport warnings\n\n\n"
            "def wrap_angle(theta):\n    warnings.warn('wrapping')\n"
            "    logging.warning('wrapping %s', theta)\n"
            "    wrapped = float(theta) % (2 * math.pi)\n"
            "    return 0.0 if wrapped >= 2 * math.pi else wrapped\n"
        }
    ),
    "peeking": Case(answers=_PEEKING_ANSWERS),
    "reads_history": Case(
        cell="raise RuntimeError('|'.join(In) + repr(Out))\n", after="test_wrap_angle"
    ),
    # Folder names nbgrader or a file system would not take as an id, with correct work.
    "st[1] with\na new line ": Case(),
    "l" * 250: Case(),
    "malformed": Case(raw='{"cells": [ this is not a notebook'),
    "empty": Case(empty=True),
    # Blank answers, and an import of a module beside the notebooks, by the path the grader's
    # own folder would give it (the grading is started beside submissions/).
    "imports_beside": Case(
        blank=True,
        top_files={"take_over.py": _TAKE_OVER},
        cell="import take_over\nimport submissions.imports_beside.take_over\n",
    ),
    # Names the tests read, rebound in the kernel, with junk answers that count on them.
    "rebinds_names": Case(
        cell="from unittest.mock import call as math\nfrom unittest.mock import call as abs\n",
        after="test_world_from_start",
        answers={
            "wrap_angle": "def wrap_angle(theta):\n    return math.isclose(theta, theta)\n",
            "rotation_matrix": "def rotation_matrix(theta):\n    return abs(theta)\n",
        },
    ),
    "fills_the_disk": Case(cell=_FILL_THE_DISK),
    # An answer of 48 MB: that test fails, and the grader's memory does not swell.
    "answers_48mb": Case(
        answers={"wrap_angle": "def wrap_angle(theta):\n    return 'x' * 48_000_000\n"}
    ),
    "records_its_inputs": Case(
        answers={"wrap_angle": _RECORDS_ITS_INPUTS},
        cell="raise ValueError('seen: ' + ', '.join(SEEN))\n",
        after="test_world_from_start",
    ),
    "sleeps": Case(cell="import time\n\ntime.sleep(9)\n", after="test_wrap_angle"),
    # Attacks on the grader's process for a student: a result of full marks written where the
    # grader keeps its own, every process the code can signal killed, a user namespace, a
    # kernel that dies after the last test's visible part (the hidden parts run again).
    "forges_a_result": Case(cell=_FORGE_A_RESULT, blank=True),
    "kills_everything": Case(
        cell="import os\nimport signal\n\nos.kill(-1, signal.SIGKILL)\n", after="test_wrap_angle"
    ),
    "makes_a_namespace": Case(cell=_MAKE_A_NAMESPACE),
    "dies_at_the_end": Case(cell="import os\n\nos._exit(0)\n", after="test_world_from_start"),
    # Answers one library call does, which notebook 03 forbids: tf's matrix, and matplotlib's
    # transform behind a helper in a cell the student added.
    "library_answers": Case(
        cell="from matplotlib.transforms import Affine2D\n\n\ndef _moved(pose, point):\n"
        "    x, y, theta = pose\n"
        "    return tuple(Affine2D().rotate(theta).translate(x, y).transform([point])[0])\n",
        answers={
            "rotation_matrix": "from tf.transformations import euler_matrix\n\n\n"
            "def rotation_matrix(theta):\n    return euler_matrix(0, 0, theta)[:2, :2]\n",
            "world_from_robot": "def world_from_robot(pose, point):\n"
            "    return _moved(pose, point)\n",
        },
    ),
}


def expected_loss(name: str) -> Tuple[str, ...]:
    """The tests a case must fail (every other test scores full marks), or ``("*",)``: all."""
    return {
        "os_exit": ("test_rotation_matrix", "test_world_from_robot", "test_world_from_start"),
        "kernel_crash": ("*",),
        # Its cell calls get_ipython(), through which any answer could be rebound unseen: the
        # grader cannot hold the notebook's rules, and says so for every answer.
        "monkey_patch": ("*",),
        "shadow_numpy": ("test_rotation_matrix",),
        "raises_outside_tests": ("test_wrap_angle",),
        "tests_turned_off": ("*",),
        "peeking": ("test_wrap_angle", "test_rotation_matrix"),
        "malformed": ("*",),
        "empty": ("*",),
        "imports_beside": ("*",),
        "rebinds_names": ("test_wrap_angle", "test_rotation_matrix"),
        "answers_48mb": ("test_wrap_angle",),
        "library_answers": ("test_rotation_matrix", "test_world_from_robot"),
        "forges_a_result": ("*",),
        # Its own sandbox's processes die, the notebook's server among them: nothing is left
        # to run the notebook or its tests.
        "kills_everything": ("*",),
    }.get(name, ())
