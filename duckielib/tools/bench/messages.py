"""Benchmark: how fast the course's messages are built, serialized and read back.

The in-process graph passes every encoder tick, command and LED change through these classes,
and the bag module writes their bytes, so their cost bounds how fast a simulated mission runs.
"""

from __future__ import annotations

import importlib
import sys
import time
from typing import Callable, List, Tuple

_ROUNDS = 20_000


def _rate(action: Callable[[], object], rounds: int = _ROUNDS) -> float:
    """Operations per second of ``action``, best of three runs."""
    best = float("inf")
    for _ in range(3):
        start = time.perf_counter()
        for _ in range(rounds):
            action()
        best = min(best, time.perf_counter() - start)
    return rounds / best


def run() -> List[Tuple[str, str]]:
    """Measure message import time and per-message costs; headline: encoder round trips/s."""
    for name in [name for name in sys.modules if name.startswith("duckielib.messages")]:
        del sys.modules[name]
    start = time.perf_counter()
    messages = importlib.import_module("duckielib.messages")
    import_ms = (time.perf_counter() - start) * 1000

    tick = messages.WheelEncoderStamped(data=-41234, resolution=135, type=1)
    tick_bytes = tick.to_bytes()
    pattern = messages.LEDPattern(
        color_list=["red"] * 5,
        rgb_vals=[messages.ColorRGBA(0.8, 0.0, 0.0, 1.0) for _ in range(5)],
        color_mask=[1] * 5,
        frequency=0.0,
        frequency_mask=[0] * 5,
    )
    cls = messages.WheelEncoderStamped

    def round_trip() -> object:
        return cls.from_bytes(cls(data=12, resolution=135, type=1).to_bytes())

    return [
        ("import_messages_ms", f"{import_ms:.1f}"),
        ("encoder_build_per_s", f"{_rate(lambda: cls(data=12, resolution=135, type=1)):.0f}"),
        ("encoder_serialize_per_s", f"{_rate(tick.to_bytes):.0f}"),
        ("encoder_deserialize_per_s", f"{_rate(lambda: cls.from_bytes(tick_bytes)):.0f}"),
        ("led_pattern_serialize_per_s", f"{_rate(pattern.to_bytes, _ROUNDS // 4):.0f}"),
        ("encoder_round_trips_per_s", f"{_rate(round_trip):.0f}"),
    ]
