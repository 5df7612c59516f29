"""How fast this machine runs Python, for the time limits the tests give the code they run.

A test that proves a limit stops what never ends (a cell's 5 s, a mission's 20 s) sets the
limit tight, so that it costs little waiting. Those limits were set on a machine where
:func:`loop_seconds` takes :data:`REFERENCE_SECONDS`; on a slower machine each grows by the
same factor, the pace, so that a limit stops only what never ends and never what is merely
slow. The pace is measured once, by the first process that asks, and handed on in the
environment (:data:`VARIABLE`): pytest's workers and what they start agree on it. Set it by
hand (``DUCKIE_TEST_PACE=2 make test``) to try the suite as on a slower machine.
"""

from __future__ import annotations

import math
import os
import time

#: The environment variable that holds the pace.
VARIABLE = "DUCKIE_TEST_PACE"
#: :func:`loop_seconds` where the suite's limits hold as set. A machine where ``duckie bench sim``
#: gives about 800 takes 0.07 to 0.09 s, a pace of about 2.5, which the suite needs there.
REFERENCE_SECONDS = 0.03


def loop_seconds() -> float:
    """The best of five timings of two million additions in pure Python."""
    best = math.inf
    for _ in range(5):
        start = time.perf_counter()
        total = 0
        for number in range(2_000_000):
            total += number
        best = min(best, time.perf_counter() - start)
    return best


def pace() -> float:
    """How many times slower than the reference this machine is (1 on a faster one)."""
    value = os.environ.get(VARIABLE)
    if value is None:
        value = f"{max(1.0, loop_seconds() / REFERENCE_SECONDS):.2f}"
        os.environ[VARIABLE] = value
    return float(value)


def seconds(limit: float) -> int:
    """``limit`` seconds of the reference machine, in whole seconds of this one."""
    return math.ceil(limit * pace())
