"""The student's functions, called from the grader: tests whose verdict no student code can reach.

A test cell of a graded notebook does not run in the student's kernel. The grader runs it in
its own process (:func:`run_test`), in a namespace of its own: the notebook's imports, done by
the grader, and the test's own code. Each name the test needs from the student (``delta_phi``,
``WheelPairing``) is a :class:`Remote`: calling it, or reading an attribute of what it returned,
sends a request to the kernel in the sandbox, which does only that (``delta_phi(42, 42, 135)``)
and answers with the result as plain data. The grader decodes the answer strictly
(:func:`decode`: numbers, strings, bytes, lists, tuples, dicts, sets, numpy arrays of plain
dtypes; anything else stays in the kernel and is named by a handle) and compares it with what
the test expects, in its own process. The test's code, its expected values and its verdict
never enter a process that runs student code: the kernel sees only the inputs it is called with.

What the kernel answers is the student's answer, whatever the student's code did to the kernel
(an AST transformer, a patched ``math.isclose``, a forged reply): the grader trusts none of it
beyond its value. A handle compares equal only to itself, so a student's object cannot claim to
equal the expected value (the expected value is never sent to it).

This file is also the kernel's side: the sandbox's server runs its source in each kernel as a
module of its own (:data:`KERNEL_MODULE`), and calls :func:`answer` there. It imports nothing
of the grader.

Tests that run the student's nodes on a robot (a node, a mission) run here too: the robot in
the grader, the nodes in the sandbox, talking through topics and services only
(:mod:`autograder.robots`).
"""

# Over 600 lines: the kernel runs this file's source as one module that can import nothing of
# the grader, so the value codec both sides share, the kernel's side and the grader's side of
# the calls stay together, each in its own part of the file.

from __future__ import annotations

import base64
import builtins
import json
import re
import sys
from typing import Any, Callable, Dict, List, Optional

#: The environment variables the student's code may read that a test sets (``robot_topic``
#: reads the robot's name): each call carries their values in the grader's process, and the
#: kernel sets them (or removes them) before it calls the student's code.
PASSED_ENVIRONMENT = ("VEHICLE_NAME",)
#: The module the kernel's side lives in, in the kernel.
KERNEL_MODULE = "__duckie_calls__"
#: How deep a value may nest (lists in lists ...).
MAX_DEPTH = 64
#: The most digits an integer may have.
MAX_DIGITS = 4300
#: The most items ``iter`` reads from a student's object.
MAX_ITEMS = 1_000_000
#: How much of a student object's ``repr`` comes back, in characters.
MAX_TEXT = 2000
#: The numpy dtypes an array may have, as ``dtype.str`` (little-endian, plain numbers).
DTYPES = frozenset(
    {"|b1", "|i1", "<i2", "<i4", "<i8", "|u1", "<u2", "<u4", "<u8", "<f2", "<f4", "<f8",
     "<c8", "<c16"}
)  # fmt: skip


_INTEGER = re.compile(rf"-?[0-9]{{1,{MAX_DIGITS}}}\Z")


class DecodeError(ValueError):
    """The kernel answered with something that is not plain data in the expected form."""


# ---------------------------------------------------------------------------------------------
# Both sides: plain data as JSON.


def encode(  # noqa: PLR0911, PLR0912 - one branch per kind of value
    value: Any, keep: Callable[[Any], List[Any]], depth: int = 0
) -> Any:
    """``value`` as JSON-ready data; what is not plain data becomes ``keep(value)`` (a handle)."""
    if depth > MAX_DEPTH:
        raise ValueError("the value nests too deeply")
    np = sys.modules.get("numpy")
    kind = type(value)
    if value is None:
        return ["n"]
    if kind is bool:
        return ["b", value]
    if kind is int:
        return ["i", str(value)]
    if kind is float:
        return ["f", repr(value)]
    if kind is complex:
        return ["c", repr(value.real), repr(value.imag)]
    if kind is str:
        return ["s", value]
    if kind in (bytes, bytearray):
        return ["y", base64.b64encode(bytes(value)).decode("ascii")]
    if (
        np is not None
        and isinstance(value, (np.ndarray, np.generic))
        and value.dtype.newbyteorder("<").str in DTYPES
    ):
        array = np.ascontiguousarray(value, dtype=value.dtype.newbyteorder("<"))
        data = base64.b64encode(array.tobytes()).decode("ascii")
        if isinstance(value, np.generic):  # a numpy number keeps its type (np.float64)
            return ["g", array.dtype.str, data]
        return ["a", array.dtype.str, list(array.shape), data]
    if isinstance(value, (list, tuple)):
        tag = "l" if isinstance(value, list) else "t"
        return [tag, [encode(item, keep, depth + 1) for item in value]]
    if isinstance(value, dict):
        return ["d", [[encode(k, keep, depth + 1), encode(v, keep, depth + 1)]
                      for k, v in value.items()]]  # fmt: skip
    if isinstance(value, (set, frozenset)):
        return ["e", [encode(item, keep, depth + 1) for item in value]]
    return keep(value)


def decode(  # noqa: PLR0911, PLR0912 - one branch per kind of value
    data: Any, handle: Callable[[int, str], Any], depth: int = 0
) -> Any:
    """The value ``data`` (from :func:`encode`) stands for, checked at every step.

    Args:
        data: what ``json.loads`` gave.
        handle: turns ``(number, type name)`` into the object a handle stands for.
        depth: how deep ``data`` lies in the value being decoded.

    Raises:
        DecodeError: ``data`` is not in the form :func:`encode` gives.
    """
    if depth > MAX_DEPTH:
        raise DecodeError("the value nests too deeply")
    if not isinstance(data, list) or not data or not isinstance(data[0], str):
        raise DecodeError("a value is not tagged")
    tag, rest = data[0], data[1:]
    try:
        if tag == "n" and not rest:
            return None
        if tag == "b" and len(rest) == 1 and type(rest[0]) is bool:
            return rest[0]
        if tag == "i" and len(rest) == 1 and type(rest[0]) is str and _INTEGER.match(rest[0]):
            return int(rest[0])
        if tag == "f" and len(rest) == 1 and type(rest[0]) is str and len(rest[0]) <= 40:
            return float(rest[0])
        if tag == "c" and len(rest) == 2 and all(type(p) is str and len(p) <= 40 for p in rest):
            return complex(float(rest[0]), float(rest[1]))
        if tag == "s" and len(rest) == 1 and type(rest[0]) is str:
            return str(rest[0])
        if tag == "y" and len(rest) == 1 and type(rest[0]) is str:
            return base64.b64decode(rest[0].encode("ascii"), validate=True)
        if tag in ("l", "t", "e") and len(rest) == 1 and type(rest[0]) is list:
            items = [decode(item, handle, depth + 1) for item in rest[0]]
            return {"l": list, "t": tuple, "e": set}[tag](items)
        if tag == "d" and len(rest) == 1 and type(rest[0]) is list:
            pairs = {}
            for pair in rest[0]:
                if type(pair) is not list or len(pair) != 2:
                    raise DecodeError("a dict's item is not a pair")
                pairs[decode(pair[0], handle, depth + 1)] = decode(pair[1], handle, depth + 1)
            return pairs
        if tag == "a" and len(rest) == 3:
            return _decode_array(*rest)
        if tag == "g" and len(rest) == 2:
            return _decode_array(rest[0], [], rest[1])[()]
        if tag == "h" and len(rest) == 2 and type(rest[0]) is int and type(rest[1]) is str:
            return handle(rest[0], rest[1][:200])
    except (TypeError, ValueError, OverflowError) as error:
        if isinstance(error, DecodeError):
            raise
        raise DecodeError(f"a value tagged {tag!r} is damaged: {error}") from None
    raise DecodeError(f"a value tagged {tag[:10]!r} is not in the expected form")


def _decode_array(dtype: Any, shape: Any, data: Any) -> Any:
    import numpy as np

    if dtype not in DTYPES or type(shape) is not list or type(data) is not str:
        raise DecodeError("an array is not in the expected form")
    if len(shape) > 32 or not all(type(n) is int and n >= 0 for n in shape):
        raise DecodeError("an array's shape is not a list of sizes")
    raw = base64.b64decode(data.encode("ascii"), validate=True)
    kind = np.dtype(dtype)
    count = 1
    for n in shape:
        count *= n
    if count * kind.itemsize != len(raw):
        raise DecodeError("an array's data does not fill its shape")
    return np.frombuffer(raw, dtype=kind).astype(kind.newbyteorder("="), copy=True).reshape(shape)


# ---------------------------------------------------------------------------------------------
# The kernel's side.

_KEPT: Dict[int, Any] = {}


def _keep(value: Any) -> List[Any]:
    number = len(_KEPT) + 1
    _KEPT[number] = value
    kind = type(value)
    return ["h", number, f"{kind.__module__}.{kind.__qualname__}"]


def _kept(number: int, name: str) -> Any:
    if number not in _KEPT:
        raise LookupError(f"no object number {number}")
    return _KEPT[number]


def _describe(error: BaseException) -> Dict[str, Any]:
    import traceback

    lines = traceback.format_exception(type(error), error, error.__traceback__)
    # The first frame is this module's own call: the student's frames follow.
    return {
        "type": type(error).__name__,
        "message": str(error)[:MAX_TEXT],
        "traceback": [line[:MAX_TEXT] for line in lines[-30:]],
    }


def answer(text: str) -> str:
    """Do the request ``text`` (JSON) in this kernel; the answer, as JSON text."""
    try:
        request = json.loads(text)
        value = _do(request)
        return json.dumps({"value": encode(value, _keep)})
    except KeyboardInterrupt:  # the test's time limit
        return json.dumps({"broken": "the student's code ran out of time"})
    except BaseException as error:  # the student's error is the answer
        return json.dumps({"raised": _describe(error)})


def serve(path: str) -> None:
    """Answer the grader's calls for one test, over the Unix socket ``path``, until it ends.

    Each request and answer is a frame of :mod:`autograder.sandbox.inside.wire` (an 8-byte
    big-endian length, then JSON text), read here with a copy of the wire's few lines: this
    file runs in the kernel, which imports nothing of the grader. The test's
    time limit interrupts the kernel (KeyboardInterrupt): the call then answers that the time
    ran out, and the serving ends. The variables of :data:`PASSED_ENVIRONMENT` the calls set
    are put back as they were when the test began.
    """
    import os
    import socket

    # The test's environment variables are the kernel's again once it is over.
    before = {name: os.environ.get(name) for name in PASSED_ENVIRONMENT}
    connection = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
    try:
        connection.connect(path)
        stream = connection.makefile("rb")
        while True:
            head = stream.read(8)
            if len(head) < 8:
                return
            data = stream.read(int.from_bytes(head, "big"))
            if data == b"end":
                return
            reply = answer(data.decode("utf-8"))
            raw = reply.encode("utf-8")
            connection.sendall(len(raw).to_bytes(8, "big") + raw)
            if reply.startswith('{"broken"'):
                return
    except KeyboardInterrupt:
        return
    finally:
        connection.close()
        _set_environment(before)


def _set_environment(values: Dict[str, Any]) -> None:
    """Set the variables of :data:`PASSED_ENVIRONMENT` a call carries (None: remove it)."""
    import os

    for name, value in values.items():
        if name not in PASSED_ENVIRONMENT:
            continue
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = str(value)


def _do(request: Dict[str, Any]) -> Any:  # noqa: PLR0911 - one branch per request
    op = request["op"]
    if op == "get":
        from IPython import get_ipython

        space = get_ipython().user_ns
        if request["name"] not in space:
            raise NameError(f"name {request['name']!r} is not defined")
        return space[request["name"]]
    target = _kept(request["target"], "")
    if op == "call":
        args = decode(request["args"], _kept)
        kwargs = decode(request["kwargs"], _kept)
        _set_environment(dict(request.get("environment", {})))
        return target(*args, **kwargs)
    if op == "attr":
        return getattr(target, request["name"])
    if op == "item":
        return target[decode(request["key"], _kept)]
    if op == "len":
        return len(target)
    if op == "bool":
        return bool(target)
    if op == "iter":
        items = []
        for item in target:
            items.append(item)
            if len(items) > MAX_ITEMS:
                raise ValueError(f"more than {MAX_ITEMS} items")
        return items
    if op == "repr":
        return repr(target)[:MAX_TEXT]
    if op == "str":
        return str(target)[:MAX_TEXT]
    raise ValueError(f"unknown request {op!r}")


# ---------------------------------------------------------------------------------------------
# The grader's side.


class StudentError(Exception):
    """An error the student's code raised, of a kind Python does not define."""


class CallsBroken(Exception):
    """The kernel could not answer (it died, ran out of time, or answered nonsense)."""


class AnswerRefused(CallsBroken):
    """The student's code answered a call with more data than the grader reads."""


def _too_long(size: int) -> str:
    from autograder.sandbox.inside.wire import ANSWER_LIMIT

    return (
        f"your code answered one call of this test with {size / 1e6:.1f} MB of data; the grader "
        f"reads at most {ANSWER_LIMIT / 1e6:.1f} MB of one answer, far more than any answer of "
        "the course needs, so this test fails"
    )


class Abandon(BaseException):
    """The notebook's run is over (its time, or its sandbox, ended): the test stops at once."""


#: Module prefixes whose classes a handle may claim to be an instance of (for ``isinstance``).
_CLAIMABLE = ("matplotlib.", "numpy.", "duckielib.")


class Remote:
    """An object of the student's, in the kernel; everything asked of it is asked there."""

    __slots__ = ("_number", "_kind", "_link")

    def __init__(self, number: int, kind: str, link: Link) -> None:
        object.__setattr__(self, "_number", number)
        object.__setattr__(self, "_kind", kind)
        object.__setattr__(self, "_link", link)

    def _ask(self, op: str, **more: Any) -> Any:
        return self._link.ask({"op": op, "target": self._number, **more})

    def __getattr__(self, name: str) -> Any:
        if name.startswith("__"):
            raise AttributeError(name)
        return self._ask("attr", name=name)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("the grader does not change the student's objects")

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        """Call the student's object in the kernel with these (plain) arguments."""
        import os

        return self._ask(
            "call",
            args=self._link.encode(list(args)),
            kwargs=self._link.encode(dict(kwargs)),
            environment={name: os.environ.get(name) for name in PASSED_ENVIRONMENT},
        )

    def __len__(self) -> int:
        got = self._ask("len")
        if type(got) is not int or got < 0:
            raise TypeError(f"the length of a {self._kind} is not a number")
        return got

    def __bool__(self) -> bool:
        got = self._ask("bool")
        if type(got) is not bool:
            raise TypeError(f"the truth of a {self._kind} is not a bool")
        return got

    def __iter__(self) -> Any:
        got = self._ask("iter")
        if type(got) is not list:
            raise TypeError(f"a {self._kind} could not be iterated")
        return iter(got)

    def __getitem__(self, key: Any) -> Any:
        return self._ask("item", key=self._link.encode(key))

    def __repr__(self) -> str:
        got = self._ask("repr")
        return got[:MAX_TEXT] if type(got) is str else f"<{self._kind}>"

    def __str__(self) -> str:
        got = self._ask("str")
        return got[:MAX_TEXT] if type(got) is str else f"<{self._kind}>"

    def __eq__(self, other: Any) -> bool:
        return self is other

    def __ne__(self, other: Any) -> bool:
        return self is not other

    def __hash__(self) -> int:
        return hash((self._number, id(self._link)))

    @property  # type: ignore[misc]
    def __class__(self) -> type:
        claimed = _claimed_class(self._kind)
        return claimed if claimed is not None else type(self)


def _claimed_class(kind: str) -> Optional[type]:
    """The library class named ``kind`` (``module.Name``), when it is one of a known library's."""
    import importlib

    if not kind.startswith(_CLAIMABLE):
        return None
    module, _, name = kind.rpartition(".")
    try:
        found = getattr(importlib.import_module(module), name)
    except Exception:
        return None
    return found if isinstance(found, type) else None


_REMOTE_CLASSES: Dict[str, type] = {}


def _remote_class(kind: str) -> type:
    """A subclass of :class:`Remote` named as the student's class, for messages."""
    short = kind.rpartition(".")[2] or "object"
    if not short.isidentifier():
        short = "object"
    if short not in _REMOTE_CLASSES:
        _REMOTE_CLASSES[short] = type(short, (Remote,), {"__slots__": ()})
    return _REMOTE_CLASSES[short]


class Link:
    """The grader's end of the calls: sends requests to the kernel, decodes the answers.

    Args:
        send: sends a request (a dict) and returns the kernel's answer text, or raises
            :class:`CallsBroken`.
        paths: ``{grader's folder: the same folder in the sandbox}``, for paths passed as
            arguments.
    """

    def __init__(self, send: Callable[[Dict[str, Any]], str], paths: Dict[str, str]) -> None:
        self.send = send
        self.paths = paths
        self.calls = 0
        #: The longest answer the kernel gave, in characters.
        self.largest = 0

    def encode(self, value: Any) -> Any:
        """``value`` as data for the kernel (paths moved into the sandbox's view)."""

        def refuse(item: Any) -> List[Any]:
            if isinstance(item, Remote) and item._link is self:
                return ["h", item._number, item._kind]
            raise TypeError(f"the grader cannot pass a {type(item).__name__} to student code")

        return encode(self._in_sandbox(value), refuse)

    def _in_sandbox(self, value: Any) -> Any:
        import os

        if isinstance(value, os.PathLike):
            value = os.fspath(value)
        if isinstance(value, str):
            for outside, inside in self.paths.items():
                if value == outside or value.startswith(outside.rstrip("/") + "/"):
                    _readable(outside, value)
                    return inside + value[len(outside.rstrip("/")) :]
            return value
        if type(value) in (list, tuple):
            return type(value)(self._in_sandbox(item) for item in value)
        if type(value) is dict:
            return {key: self._in_sandbox(item) for key, item in value.items()}
        return value

    def get(self, name: str) -> Any:
        """The student's global ``name``, as a value or a :class:`Remote`."""
        return self.ask({"op": "get", "name": name})

    def ask(self, request: Dict[str, Any]) -> Any:
        """Send ``request`` to the kernel; the value it answered, or the error it raised."""
        self.calls += 1
        from duckielib.sim.link.wire import nests_deeper

        text = self.send(request)
        self.largest = max(self.largest, len(text))
        if nests_deeper(text, MAX_DEPTH + 4):  # read without recursing, before json does
            raise CallsBroken(f"the kernel's answer nests more than {MAX_DEPTH} levels deep")
        try:
            reply = json.loads(text)
        except ValueError:
            reply = None
        if type(reply) is dict and len(reply) == 1 and "broken" in reply:
            raise CallsBroken(str(reply["broken"])[:MAX_TEXT])
        if type(reply) is dict and len(reply) == 1 and type(reply.get("refused")) is int:
            raise AnswerRefused(_too_long(reply["refused"]))
        if type(reply) is dict and len(reply) == 1 and "raised" in reply:
            raise _student_error(reply["raised"])
        if type(reply) is not dict or len(reply) != 1 or "value" not in reply:
            raise CallsBroken("the kernel answered with something the grader cannot read")
        try:
            return decode(reply["value"], self._handle)
        except (DecodeError, RecursionError) as error:
            raise CallsBroken(f"the kernel's answer could not be read ({error})") from None

    def _handle(self, number: int, kind: str) -> Remote:
        return _remote_class(kind)(number, kind, self)


def _readable(root: str, path: str) -> None:
    """Let the sandbox's user read ``path`` and the folders from ``root`` down to it."""
    from pathlib import Path

    here = Path(path)
    chain = [here, *here.parents]
    for item in chain:
        if not str(item).startswith(root.rstrip("/")) or not item.exists():
            continue
        if item.is_symlink():
            continue
        item.chmod(0o755 if item.is_dir() else 0o644)
        if item.is_dir() and item == here:
            for inner in item.rglob("*"):
                if not inner.is_symlink():
                    inner.chmod(0o755 if inner.is_dir() else 0o644)


#: The errors a student's code may raise that a test can expect (``except ValueError``).
_KNOWN_ERRORS = {
    name: value
    for name, value in vars(builtins).items()
    if isinstance(value, type) and issubclass(value, Exception)
}


class RaisedInKernel(Exception):
    """Carries the student's traceback lines with the error raised in the grader."""


def _student_error(raised: Any) -> BaseException:
    if type(raised) is not dict:
        return CallsBroken("the kernel's error could not be read")
    name = str(raised.get("type", "Exception"))[:100]
    message = str(raised.get("message", ""))[:MAX_TEXT]
    lines = raised.get("traceback", [])
    lines = [str(line)[:MAX_TEXT] for line in lines[:30]] if type(lines) is list else []
    kind = _KNOWN_ERRORS.get(name)
    if kind is None:
        error: BaseException = StudentError(f"{name}: {message}" if message else name)
    else:
        try:
            error = kind(message)
        except Exception:
            error = StudentError(f"{name}: {message}")
    error.__cause__ = RaisedInKernel("".join(lines))
    return error
