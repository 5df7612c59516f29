"""The wire between the grader and its sandbox: both ends of it, in one module.

The grader (:mod:`autograder.sandbox.server`) starts the sandbox's server
(:mod:`autograder.sandbox.inside.serve`) and talks to it over the server's standard input and
output. Each message is a JSON object in a frame: its length as 8 bytes, big-endian, then its
UTF-8 bytes (:func:`frame`, :func:`read_frame`).

The grader says:

- ``{"folder": NAME, "notebook": TEXT}``: run this notebook in folder ``NAME``;
- ``{"call": TEXT}``: one call of a test to the student's code (see :mod:`autograder.calls`);
- ``{"end": true}``: the test is over.

The server answers:

- ``{"test": GRADE_ID}``: the run reached a test the grader runs on its side (its visible
  part); calls may follow, until ``end``. ``{"hidden": GRADE_ID}``, after the notebook's last
  cell: the test's hidden part; ``{"rerun": GRADE_ID}``: the whole test again, in a new kernel
  after one died (see ``autograder/verdict.py``);
- ``{"answer": TEXT}``: the kernel's answer to a call;
- ``{"notebook": TEXT}``: the executed notebook, the run's last word;
- ``{"problem": TEXT}``: why the notebook could not be run, the run's last word instead.

Runs inside the sandbox too: the standard library only.
"""

from __future__ import annotations

import json
from typing import Any, Dict, Optional, Union

__all__ = [
    "ANSWER_LIMIT",
    "HEADER",
    "TEST_KINDS",
    "Channel",
    "decode",
    "encode",
    "frame",
    "read_frame",
    "read_frame_within",
    "size",
]

#: The bytes of a frame's length.
HEADER = 8
#: The messages of the server that start a test's calls (see above).
TEST_KINDS = ("test", "hidden", "rerun")
#: The longest answer of the student's code to one call of a test, in bytes of JSON. The
#: course's own answers need at most about 1.3 MB (a camera image, in base64); the grader
#: reads no more, so one answer cannot swell the grader's memory.
ANSWER_LIMIT = 4 * 1024**2


def frame(data: bytes) -> bytes:
    """``data`` as one frame: its length, then itself (see :func:`read_frame`)."""
    return len(data).to_bytes(HEADER, "big") + data


def size(head: bytes) -> int:
    """The length a frame's first :data:`HEADER` bytes announce."""
    return int.from_bytes(head, "big")


def read_frame(stream: Any) -> Optional[bytes]:
    """The next frame's data from a stream that blocks; None at the end of the stream."""
    head = stream.read(HEADER)
    if len(head) < HEADER:
        return None
    wanted = size(head)
    data = stream.read(wanted)
    return data if len(data) == wanted else None


def read_frame_within(stream: Any, limit: int) -> Union[bytes, int, None]:
    """The next frame's data, or its length when it is over ``limit``; None at its end.

    A frame over the limit is read and dropped a chunk at a time, never held whole.
    """
    head = stream.read(HEADER)
    if len(head) < HEADER:
        return None
    wanted = size(head)
    if wanted <= limit:
        data = stream.read(wanted)
        return data if len(data) == wanted else None
    left = wanted
    while left > 0:
        chunk = stream.read(min(left, 1 << 20))
        if not chunk:
            return None
        left -= len(chunk)
    return wanted


def encode(message: Dict[str, Any]) -> bytes:
    """``message`` as a frame."""
    return frame(json.dumps(message).encode("utf-8"))


def decode(data: bytes) -> Dict[str, Any]:
    """A frame's data as a message; ValueError if it is not a JSON object."""
    message = json.loads(data)
    if not isinstance(message, dict):
        raise ValueError("not a message")
    return message


class Channel:
    """The server's end: what it tells the grader and hears from it during a notebook's tests."""

    def __init__(self, given: Any, answer: Any) -> None:
        self.given, self.answer = given, answer

    def say(self, message: Dict[str, Any]) -> None:
        """Send ``message`` to the grader."""
        self.answer.write(encode(message))
        self.answer.flush()

    def hear(self) -> Optional[Dict[str, Any]]:
        """The grader's next message, or None when it has closed the pipe."""
        data = read_frame(self.given)
        return None if data is None else decode(data)
