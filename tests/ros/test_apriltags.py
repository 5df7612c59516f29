"""Duckietown's AprilTag detector is freed in the order its C library needs.

See duckielib.ros.apriltags.

Each case runs in a process of its own under glibc's checking allocator, which fills freed
memory with a pattern, so reading memory already freed crashes at once rather than damaging
the heap for a crash much later.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from pace import seconds

#: glibc's checking allocator (part of libc6 on Debian 12).
MALLOC_DEBUG = sorted(str(path) for path in Path("/lib").glob("*-linux-gnu/libc_malloc_debug.so.0"))

MAKE_AND_DROP = """
import numpy as np
from dt_apriltags import Detector
for _ in range(20):
    detector = Detector(families="tag36h11")
    detector.detect(np.zeros((48, 64), np.uint8))
    del detector
print("freed")
"""

CASES = {
    "no fix": MAKE_AND_DROP,
    "duckielib.ros first": "import duckielib.ros\n" + MAKE_AND_DROP,
    "dt_apriltags first": MAKE_AND_DROP.replace(
        "from dt_apriltags import Detector\n",
        "from dt_apriltags import Detector\nimport duckielib.ros\n",
    ),
}


def run_checked(code: str) -> subprocess.CompletedProcess:
    env = {
        "LD_PRELOAD": MALLOC_DEBUG[0],
        "MALLOC_CHECK_": "3",
        "GLIBC_TUNABLES": "glibc.malloc.perturb=165",
        "PATH": "/usr/bin:/bin",
    }
    return subprocess.run(
        [sys.executable, "-c", code],
        check=False,
        capture_output=True,
        text=True,
        env=env,
        timeout=seconds(60),
    )


@pytest.fixture(scope="module", autouse=True)
def _allocator():
    assert MALLOC_DEBUG, "glibc's libc_malloc_debug.so.0 is missing (package libc6)"


def test_the_released_detector_reads_freed_memory_when_dropped():
    # What the fix is for: without it, the checking allocator catches the library at it.
    result = run_checked(CASES["no fix"])
    assert result.returncode != 0
    assert "freed" not in result.stdout


@pytest.mark.parametrize("case", ["duckielib.ros first", "dt_apriltags first"])
def test_with_duckielib_ros_imported_detectors_are_freed_cleanly(case):
    result = run_checked(CASES[case])
    assert result.returncode == 0, result.stderr[-2000:]
    assert result.stdout.strip() == "freed"


def test_the_fixed_clean_up_frees_once():
    import dt_apriltags

    import duckielib.ros  # noqa: F401  (registers the fix)

    detector = dt_apriltags.Detector(families="tag36h11")
    assert type(detector).__del__.__module__ == "duckielib.ros.apriltags"
    detector.__del__()
    assert detector.tag_detector_ptr is None
    assert detector.tag_families == {}
    detector.__del__()  # a second call (the garbage collector's) does nothing
