"""Benchmark: replaying odometry from a long encoder bag, and reading it with ROS 1's rosbag.

The bag holds 100,000 WheelEncoderStamped messages (50,000 per wheel, 30 Hz each, the right
wheel 4 ms after the left, header stamps set), about 28 minutes of a drive that goes forward
while weaving, stops, then reverses, so the cumulative counts rise and then fall below zero.
It is written uncompressed with :class:`~duckielib.bags.BagWriter` into a temporary folder.

Measured, best of three, wall-clock:
- ``bag_odometry_seconds`` (headline): :func:`~duckielib.bags.replay_odometry` from the bag's
  path to the final pose (open, read, decode both wheels, pair readings and update the pose
  with the course's reference solution, exported from ``solutions/``), on one core.
- ``rosbag_read_seconds``: the same bag read with Debian's ROS 1 rosbag in a ``/usr/bin/python3``
  process: ``rosbag.Bag`` opened and ``read_messages`` over both encoder topics, touching each
  message's ``data`` and ``header.stamp``. The time is taken inside that process, after its
  imports, so interpreter start-up is not counted. ``unavailable`` without Debian's packages.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any, Callable, List, Tuple, TypeVar

import numpy as np

from duckielib.bags import Bag, BagWriter, read_encoders, replay_odometry
from duckielib.errors import DuckielibError
from duckielib.messages import Header, WheelEncoderStamped
from duckielib.rostime import Time
from duckielib.solution import load_solution

_PER_WHEEL = 50_000
_RATE_HZ = 30.0
_RIGHT_OFFSET_NS = 4_000_000
_START_NS = 1_700_000_000_000_000_000
_RESOLUTION = 135
# A constant of the .msg definition, which a type checker cannot see.
_INCREMENTAL: int = WheelEncoderStamped.ENCODER_TYPE_INCREMENTAL  # type: ignore[attr-defined]
_LEFT = "/db1/left_wheel_encoder_node/tick"
_RIGHT = "/db1/right_wheel_encoder_node/tick"
_SYSTEM_PYTHON = Path("/usr/bin/python3")
_RUNS = 3
_T = TypeVar("_T")

#: Runs in Debian's Python: reads the bag's encoder topics, prints its own elapsed seconds.
_ROSBAG_SCRIPT = """
import json, sys, time
import rosbag

path, topics = sys.argv[1], sys.argv[2:]
start = time.perf_counter()
count = 0
total = 0
with rosbag.Bag(path) as bag:
    for _, msg, _ in bag.read_messages(topics=topics):
        total += msg.data
        stamp = msg.header.stamp
        count += 1
elapsed = time.perf_counter() - start
print(json.dumps({"seconds": elapsed, "messages": count, "ticks": total, "last": stamp.secs}))
"""


def _wheel_ticks(times_s: np.ndarray, side: float) -> np.ndarray:
    """Cumulative ticks of one wheel at ``times_s`` (s, shape (N,)); side +1 left, -1 right.

    Forward at about 8 rad/s while weaving for 45% of the drive, stopped for 5%, then back.
    """
    duration = times_s[-1] + 1 / _RATE_HZ
    phase = times_s / duration
    direction = np.where(phase < 0.45, 1.0, np.where(phase < 0.5, 0.0, -1.0))
    weave = 1.5 * np.sin(2 * np.pi * times_s / 20.0) * side
    omega = direction * (8.0 + weave)  # rad/s
    angle = np.cumsum(omega) / _RATE_HZ
    return np.floor(angle * _RESOLUTION / (2 * np.pi)).astype(np.int64) - 17


def _write_bag(path: Path) -> float:
    """Write the benchmark's bag; return the seconds it took."""
    times_s = np.arange(_PER_WHEEL) / _RATE_HZ
    base_ns = _START_NS + np.round(times_s * 1e9).astype(np.int64)
    wheels = (
        (_LEFT, "left_wheel", base_ns, _wheel_ticks(times_s, 1.0)),
        (_RIGHT, "right_wheel", base_ns + _RIGHT_OFFSET_NS, _wheel_ticks(times_s, -1.0)),
    )
    start = time.perf_counter()
    writer = BagWriter(path)
    try:
        for index in range(_PER_WHEEL):
            for topic, frame, stamps, ticks in wheels:
                stamp_ns = int(stamps[index])
                message = WheelEncoderStamped(
                    header=Header(seq=index, stamp=Time.from_nsec(stamp_ns), frame_id=frame),
                    data=int(ticks[index]),
                    resolution=_RESOLUTION,
                    type=_INCREMENTAL,
                )
                # Recorded 1.2 ms after the stamp, as a recorder on the robot would.
                writer.write(topic, message, stamp_ns + 1_200_000)
    finally:
        writer.close()
    return time.perf_counter() - start


def _best(function: Callable[..., _T], *args: Any) -> Tuple[float, _T]:
    """Best wall-clock seconds of three calls, and the last call's result."""
    best = math.inf
    for _ in range(_RUNS):
        start = time.perf_counter()
        result = function(*args)
        best = min(best, time.perf_counter() - start)
    return best, result


def _debian_env() -> dict:
    """A clean environment for Debian's Python: no virtual environment, no PYTHONPATH."""
    return {"PATH": "/usr/bin:/bin", "HOME": os.environ.get("HOME", "/tmp"), "LANG": "C.UTF-8"}


def _rosbag_read(path: Path, messages: int) -> Tuple[float, str]:
    """Best seconds of three reads with Debian's rosbag, or (nan, why it is unavailable).

    Raises:
        DuckielibError: if rosbag is installed but cannot read the bag.
    """
    if not _SYSTEM_PYTHON.exists():
        return math.nan, f"{_SYSTEM_PYTHON} is missing; install Debian's ROS 1 with `make ros`"
    script = path.with_name("read_with_rosbag.py")
    script.write_text(_ROSBAG_SCRIPT)
    best = math.inf
    for _ in range(_RUNS):
        result = subprocess.run(
            [str(_SYSTEM_PYTHON), str(script), str(path), _LEFT, _RIGHT],
            env=_debian_env(),
            capture_output=True,
            text=True,
            timeout=600,
            check=False,
        )
        if result.returncode != 0:
            last = (result.stderr.strip().splitlines() or ["no output"])[-1]
            if "ModuleNotFoundError" in last or "ImportError" in last:
                return math.nan, (
                    f"Debian's rosbag is not installed ({last}); install it with `make ros`"
                )
            raise DuckielibError(f"Debian's rosbag could not read the benchmark's bag: {last}")
        report = json.loads(result.stdout)
        if report["messages"] != messages:
            raise DuckielibError(
                f"Debian's rosbag read {report['messages']} messages of the benchmark's bag, "
                f"not {messages}."
            )
        best = min(best, report["seconds"])
    return best, ""


def run() -> List[Tuple[str, str]]:
    """Write the bag, time odometry from it and rosbag's read of it; headline last."""
    solution = load_solution()
    with tempfile.TemporaryDirectory(prefix="duckie-bench-bags-") as folder:
        path = Path(folder) / "encoders.bag"
        write_s = _write_bag(path)
        size_mb = path.stat().st_size / 1e6
        start = time.perf_counter()
        bag = Bag(path)
        open_ms = (time.perf_counter() - start) * 1000
        read_s, _ = _best(read_encoders, path)
        odometry_s, track = _best(replay_odometry, path, solution)
        rosbag_s, why = _rosbag_read(path, bag.message_count)
    x, y, theta = track.final_pose
    figures = [
        ("bag_messages", str(bag.message_count)),
        ("bag_duration_s", f"{bag.duration:.1f}"),
        ("bag_size_mb", f"{size_mb:.2f}"),
        ("bag_write_seconds", f"{write_s:.3f}"),
        ("bag_open_ms", f"{open_ms:.1f}"),
        ("bag_read_encoders_seconds", f"{read_s:.3f}"),
        ("bag_odometry_updates", str(len(track) - 1)),
        ("bag_final_pose", f"x={x:.4f} m, y={y:.4f} m, theta={theta:.4f} rad"),
        ("bag_odometry_us_per_message", f"{odometry_s / bag.message_count * 1e6:.2f}"),
    ]
    if math.isnan(rosbag_s):
        figures.append(("rosbag_unavailable_because", why))
        figures.append(("bag_odometry_seconds", f"{odometry_s:.3f}"))
        figures.append(("rosbag_read_seconds", "unavailable"))
        return figures
    figures.append(("rosbag_read_over_odometry", f"{rosbag_s / odometry_s:.1f}"))
    figures.append(("bag_odometry_seconds", f"{odometry_s:.3f}"))
    figures.append(("rosbag_read_seconds", f"{rosbag_s:.3f}"))
    return figures
