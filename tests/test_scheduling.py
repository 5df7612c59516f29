"""A worker that crashes costs the suite one failed test: the run goes on and ends.

pytest-xdist's own ``loadscope`` scheduling, in 3.8.0, runs the crashed test again on the new
worker and then waits for ever (``tests/scheduling.py`` says why). Here a small suite of our
own runs with the suite's scheduler, in a process of its own.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from pace import seconds

MODULES = {
    "test_first.py": "def test_1(): pass\ndef test_2(): pass\ndef test_3(): pass\n",
    "test_crash.py": (
        "import os\ndef test_before(): pass\ndef test_dies(): os._exit(1)\ndef test_after(): pass\n"
    ),
    "test_aborts.py": "import os\ndef test_aborts(): os.abort()\ndef test_next(): pass\n",
    "test_single.py": "def test_alone(): pass\n",
    "test_last.py": "def test_1(): pass\ndef test_2(): pass\n",
}
CONFTEST = (
    "def pytest_xdist_make_scheduler(config, log):\n"
    "    from scheduling import CrashSafeScopes\n"
    "    return CrashSafeScopes(config, log)\n"
)


def test_a_crashed_worker_costs_its_test_only_and_the_run_ends(tmp_path):
    for name, source in {**MODULES, "conftest.py": CONFTEST}.items():
        (tmp_path / name).write_text(source)
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-n", "2", "--dist", "loadscope", "-v",
         "-p", "no:cacheprovider", "-p", "no:randomly"],
        cwd=tmp_path,
        env={"PYTHONPATH": str(Path(__file__).parent), "PATH": "/usr/bin:/bin"},
        capture_output=True,
        text=True,
        timeout=seconds(180),
        check=False,
    )  # fmt: skip
    said = done.stdout
    assert "2 failed, 9 passed" in said, said[-2000:]
    # The tests after a crash ran, on the new worker.
    for test in ("test_crash.py::test_after", "test_aborts.py::test_next", "test_single.py"):
        assert f"PASSED {test}" in said, said[-2000:]
    # Each crashed test ran once: one worker died for it, not one per restart.
    assert said.count("crashed while running 'test_crash.py::test_dies'") == 1
    assert said.count("crashed while running 'test_aborts.py::test_aborts'") == 1
