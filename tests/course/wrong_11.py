"""Deliberately wrong solutions of notebook 11_to_the_robot, one dict entry per mistake.

Each value is the full source of a replacement for the graded cell named by the key; the test
cell ``test_<grade_id>`` must lose marks with it.
"""

WRONG = {
    "safe_command": {
        "never stops": """\
def safe_command(v, omega, last_tick, now, timeout=0.5):
    return float(v), float(omega)
""",
        "ignores None and crashes": """\
def safe_command(v, omega, last_tick, now, timeout=0.5):
    if now < last_tick or now - last_tick > timeout:
        return 0.0, 0.0
    return float(v), float(omega)
""",
        "ignores None and drives": """\
def safe_command(v, omega, last_tick, now, timeout=0.5):
    if last_tick is not None and (now < last_tick or now - last_tick > timeout):
        return 0.0, 0.0
    return float(v), float(omega)
""",
        "stops at exactly the timeout (>= instead of >)": """\
def safe_command(v, omega, last_tick, now, timeout=0.5):
    if last_tick is None or now < last_tick or now - last_tick >= timeout:
        return 0.0, 0.0
    return float(v), float(omega)
""",
        "drives on when the clock goes backwards": """\
def safe_command(v, omega, last_tick, now, timeout=0.5):
    if last_tick is None or now - last_tick > timeout:
        return 0.0, 0.0
    return float(v), float(omega)
""",
        "takes a tick at time 0.0 for no tick": """\
def safe_command(v, omega, last_tick, now, timeout=0.5):
    if not last_tick or now < last_tick or now - last_tick > timeout:
        return 0.0, 0.0
    return float(v), float(omega)
""",
        "returns the command unconverted": """\
def safe_command(v, omega, last_tick, now, timeout=0.5):
    if last_tick is None or now < last_tick or now - last_tick > timeout:
        return 0, 0
    return v, omega
""",
    },
    "stamp_gaps": {
        "returns gap lengths instead of pairs": """\
import numpy as np


def stamp_gaps(stamps, period, tolerance=0.5):
    stamps = np.asarray(stamps, dtype=float)
    intervals = np.diff(stamps)
    return [float(gap) for gap in intervals[intervals > period * (1 + tolerance)]]
""",
        "ignores the tolerance": """\
import numpy as np


def stamp_gaps(stamps, period, tolerance=0.5):
    stamps = np.asarray(stamps, dtype=float)
    return [
        (float(stamps[i]), float(stamps[i + 1]))
        for i in range(len(stamps) - 1)
        if stamps[i + 1] - stamps[i] > period
    ]
""",
        "misses the last gap": """\
import numpy as np


def stamp_gaps(stamps, period, tolerance=0.5):
    stamps = np.asarray(stamps, dtype=float)
    return [
        (float(stamps[i]), float(stamps[i + 1]))
        for i in range(len(stamps) - 2)
        if stamps[i + 1] - stamps[i] > period * (1 + tolerance)
    ]
""",
        "misses the first gap": """\
import numpy as np


def stamp_gaps(stamps, period, tolerance=0.5):
    stamps = np.asarray(stamps, dtype=float)
    return [
        (float(stamps[i - 1]), float(stamps[i]))
        for i in range(2, len(stamps))
        if stamps[i] - stamps[i - 1] > period * (1 + tolerance)
    ]
""",
        "counts an interval of exactly the limit as a gap": """\
import numpy as np


def stamp_gaps(stamps, period, tolerance=0.5):
    stamps = np.asarray(stamps, dtype=float)
    return [
        (float(stamps[i]), float(stamps[i + 1]))
        for i in range(len(stamps) - 1)
        if stamps[i + 1] - stamps[i] >= period * (1 + tolerance)
    ]
""",
        "multiplies period by the tolerance alone": """\
import numpy as np


def stamp_gaps(stamps, period, tolerance=0.5):
    stamps = np.asarray(stamps, dtype=float)
    return [
        (float(stamps[i]), float(stamps[i + 1]))
        for i in range(len(stamps) - 1)
        if stamps[i + 1] - stamps[i] > period * tolerance
    ]
""",
        "crashes on a single stamp": """\
import numpy as np


def stamp_gaps(stamps, period, tolerance=0.5):
    stamps = np.asarray(stamps, dtype=float)
    if stamps[1] - stamps[0] < 0:
        return []
    return [
        (float(stamps[i]), float(stamps[i + 1]))
        for i in range(len(stamps) - 1)
        if stamps[i + 1] - stamps[i] > period * (1 + tolerance)
    ]
""",
    },
}
