"""The link's wire: frames, their limits, and what both sides share.

Every frame is a length-prefixed JSON header followed by the messages' bytes (see
:mod:`duckielib.sim.link`); sizes are bounded on both ends.
"""

from __future__ import annotations

import json
import re
import socket
import struct
import time
import weakref
from typing import Any, Dict, List, Optional, Tuple

from duckielib.errors import DuckielibError
from duckielib.ros import names
from duckielib.ros.log import LEVEL_NAMES, LogRecord
from duckielib.ros.rospy.topics import AnyMsg, Subscriber

__all__ = [
    "HEADER_DEPTH",
    "HEADER_LIMIT",
    "LOG_LIMIT",
    "LinkError",
    "MESSAGE_LIMIT",
    "NAME_LIMIT",
    "NodesStopped",
    "OutOfWallTime",
    "TAKEN_LIMIT",
    "TOPIC_LIMIT",
    "VERSION",
    "nests_deeper",
    "receive",
    "send",
]

#: The largest JSON header of a frame, in bytes.
HEADER_LIMIT = 1024 * 1024
#: The most bytes of messages one frame may carry (a camera image is about 20 kB).
MESSAGE_LIMIT = 16 * 1024 * 1024
#: The most bytes of messages the robot takes from the nodes in one run (the reference's
#: mission sends about 0.2 MB): a node that floods a topic cannot fill the grader's disk.
TAKEN_LIMIT = 100 * 1024 * 1024
#: The most topics the nodes may publish to, and the longest name they may use.
TOPIC_LIMIT = 200
NAME_LIMIT = 256
#: The most characters of the nodes' log lines handed over at the end.
LOG_LIMIT = 2 * 1024 * 1024
#: The first word of the exchange, so that each side knows it speaks to the other.
VERSION = "duckielib-link-1"

_SIZES = struct.Struct("!II")


class LinkError(DuckielibError):
    """The other side broke the exchange: it closed it, was too slow, or sent what is refused."""


class OutOfWallTime(LinkError):
    """The run's wall-clock time was over before the nodes' side answered."""


class NodesStopped(DuckielibError):
    """The nodes' side stopped before the run's end.

    Attributes:
        kind: ``"solution"`` when a part of the solution is unwritten, ``"mission"`` otherwise.
        why: the sentence that says what stopped it.
    """

    def __init__(self, kind: str, why: str) -> None:
        super().__init__(why)
        self.kind = kind
        self.why = why


# -- the wire ---------------------------------------------------------------------------------


def send(sock: socket.socket, header: Dict[str, Any], blobs: List[bytes] = ()) -> None:  # type: ignore[assignment]
    """Send one frame: the header as JSON, then the bytes of ``blobs``, one after the other."""
    head = json.dumps(header, separators=(",", ":")).encode("utf-8")
    body = b"".join(blobs)
    try:
        sock.sendall(_SIZES.pack(len(head), len(body)) + head + body)
    except OSError as error:
        raise LinkError(f"the other side closed the link ({error.strerror or error})") from None


#: What each socket received past the frame last read (a frame often comes in one read).
_received: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


class _Waiting:
    """How to wait for the other side's answer: look for it briefly before sleeping on it.

    The two sides take turns, each answering in about a tenth of a millisecond. Sleeping on
    the socket costs more than that when the processor idles in between (waking up is slow on
    a virtual machine), so a side first looks for the answer for up to :data:`SPIN_S`. When
    the answer seldom comes in that time (the processors are busy with other work, where
    looking only takes time from it), it goes back to sleeping at once, and tries looking
    again now and then.
    """

    def __init__(self) -> None:
        self.hits = 0.5  # how often looking found the answer lately (a moving average)
        self.count = 0

    def receive(self, sock: socket.socket, size: int) -> bytes:
        self.count += 1
        if self.hits >= 0.5 or self.count % 64 == 0:
            until = time.perf_counter() + SPIN_S
            while time.perf_counter() < until:
                try:
                    chunk = sock.recv(size, socket.MSG_DONTWAIT)
                except BlockingIOError:
                    continue
                self.hits = 0.9 * self.hits + 0.1
                return chunk
            self.hits *= 0.9
        return sock.recv(size)


#: Seconds a side looks for the other's answer before it sleeps on the socket.
SPIN_S = 0.0003
_waiting = _Waiting()


def _fill(sock: socket.socket, buffer: bytearray, size: int) -> None:
    """Read from ``sock`` until ``buffer`` holds ``size`` bytes."""
    while len(buffer) < size:
        want = min(max(1 << 16, size - len(buffer)), 1 << 20)
        chunk = _waiting.receive(sock, want) if sock.gettimeout() != 0 else sock.recv(want)
        if not chunk:
            raise LinkError("the other side closed the link")
        buffer += chunk


def receive(sock: socket.socket, timeout: Optional[float]) -> Tuple[Dict[str, Any], bytes]:
    """Receive one frame: its header (a JSON object) and its bytes.

    Raises:
        LinkError: if the other side closed the link, sent a frame over the limits, a header
            that is not a JSON object with a string ``k``, or sent nothing for ``timeout`` s.
    """
    if sock.gettimeout() != timeout:
        sock.settimeout(timeout)
    buffer = _received.setdefault(sock, bytearray())
    try:
        _fill(sock, buffer, _SIZES.size)
        head_size, body_size = _SIZES.unpack_from(buffer)
        if head_size > HEADER_LIMIT or body_size > MESSAGE_LIMIT:
            raise LinkError(f"a frame of {head_size + body_size} bytes is over the limit")
        end = _SIZES.size + head_size + body_size
        _fill(sock, buffer, end)
    except socket.timeout:
        raise LinkError(f"the other side sent nothing for {timeout:.0f} s") from None
    except OSError as error:
        raise LinkError(f"the link broke ({error.strerror or error})") from None
    head = bytes(buffer[_SIZES.size : _SIZES.size + head_size])
    body = bytes(buffer[_SIZES.size + head_size : end])
    del buffer[:end]
    try:
        text = head.decode("utf-8")
        if nests_deeper(text, HEADER_DEPTH):
            raise LinkError(f"a frame's header nests more than {HEADER_DEPTH} levels deep")
        header = json.loads(text)
    except (UnicodeDecodeError, ValueError, RecursionError):
        raise LinkError("a frame's header is not JSON") from None
    if not isinstance(header, dict) or not isinstance(header.get("k"), str):
        raise LinkError("a frame's header is not an object with a kind")
    return header, body


#: How deep a frame's header may nest lists and objects (the robot's and the nodes' nest 4).
HEADER_DEPTH = 32
_STRINGS = re.compile(r'"(?:[^"\\]|\\.)*"')
_BRACKETS_ONLY = {ord(c): None for c in map(chr, range(128)) if c not in "[]{}"}


def nests_deeper(text: str, limit: int) -> bool:
    """Whether the JSON ``text`` nests lists and objects more than ``limit`` levels deep.

    Read without recursion, before a JSON decoder (which recurses) sees the text: a frame of a
    million ``[`` is refused here rather than stopping the reader with a RecursionError.
    """
    depth = 0
    for char in _STRINGS.sub("", text).translate(_BRACKETS_ONLY):
        if char in "[{":
            depth += 1
            if depth > limit:
                return True
        elif char in "]}" and depth > 0:
            depth -= 1
    return False


def _cut(body: bytes, sizes: List[int]) -> List[bytes]:
    """``body`` cut into pieces of ``sizes`` bytes, which must add up to all of it."""
    if any(type(size) is not int or size < 0 for size in sizes) or sum(sizes) != len(body):
        raise LinkError("a frame's message sizes do not match its bytes")
    pieces, start = [], 0
    for size in sizes:
        pieces.append(body[start : start + size])
        start += size
    return pieces


class _Forward(Subscriber):
    """A subscription of the link: takes each message's bytes as published, for the other side.

    Like the bag recorder's subscription, it relies on the private
    ``Subscriber._enqueue(data)``, which rospy calls with each message's serialized bytes.
    """

    def __init__(self, topic: str, outbox: List[Tuple[str, bytes]]) -> None:
        self._outbox = outbox
        self._topic = topic
        super().__init__(topic, AnyMsg, queue_size=None)

    def _enqueue(self, data: bytes) -> None:  # overrides rospy's private method: see above
        self._outbox.append((self._topic, data))


def _deliver(record: Any, data: bytes) -> None:
    """Hand ``data`` to the topic's subscribers as ``publish()`` does, except the link's own.

    A message from the other side is never sent back to it.
    """
    record.message_count += 1
    for subscriber in list(record.subscribers):
        if not isinstance(subscriber, _Forward):
            subscriber._enqueue(data)


def _log_records(given: Any, size: int = 0) -> List[LogRecord]:
    """The nodes' log lines as records, each given as ``[time, level, node, text]``.

    Anything else is dropped, and what comes past LOG_LIMIT characters (``size`` taken already).
    """
    if not isinstance(given, list):
        return []
    records = []
    for item in given:
        if not (isinstance(item, list) and len(item) == 4):
            continue
        when, level, node, text = item
        if not (
            type(when) in (int, float)
            and level in LEVEL_NAMES
            and isinstance(node, str)
            and isinstance(text, str)
        ):
            continue
        size += len(node) + len(text)
        if size > LOG_LIMIT:
            break
        records.append(LogRecord(float(when), level, node[:NAME_LIMIT], text[:LOG_LIMIT]))
    return records


def _split_name(full: str) -> Tuple[str, str]:
    """A node's global name as (base name, namespace)."""
    namespace, _, base = full.rpartition("/")
    return base, namespace + "/"


def _legal_global(name: Any) -> bool:
    return (
        isinstance(name, str)
        and 1 < len(name) <= NAME_LIMIT
        and name.startswith("/")
        and names.is_legal_name(name)
        and name == names.canonical(name)
    )


# -- the robot's side -------------------------------------------------------------------------
