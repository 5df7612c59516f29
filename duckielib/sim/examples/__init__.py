"""Runnable examples of the simulator; run one with ``python -m duckielib.sim.examples.NAME``.

Examples:
    square: drive a square open-loop and compare the true path with the encoder ticks.
"""

from __future__ import annotations

__all__: list = []
