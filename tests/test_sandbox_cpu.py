"""All of one student's sandboxed processes share a control group that holds them to their CPUs."""

from __future__ import annotations

import subprocess
import sys
import time

import pytest

from autograder.sandbox import cpu_share, end_cpu_share, joined, unit_user


def test_a_students_processes_are_held_to_their_cpus_and_ended_with_the_group():
    uid = unit_user()
    group = cpu_share(uid, 0.5)
    if group is None:
        pytest.skip("this machine lets the grader make no control group of CPU time")
    try:
        if (group / "cpu.cfs_quota_us").exists():
            assert (group / "cpu.cfs_quota_us").read_text().strip() == "50000"
        else:
            assert (group / "cpu.max").read_text().split() == ["50000", "100000"]
        # A process that starts a busy child: both are in the group.
        script = (
            "import subprocess, sys, time\n"
            "subprocess.Popen([sys.executable, '-c', 'while True: pass'])\n"
            "time.sleep(60)\n"
        )
        process = subprocess.Popen(joined(group, [sys.executable, "-c", script]))
        deadline = time.monotonic() + 10
        while len((group / "cgroup.procs").read_text().split()) < 2:
            assert time.monotonic() < deadline, "the child never joined the group"
            time.sleep(0.05)
        assert process.pid in [int(pid) for pid in (group / "cgroup.procs").read_text().split()]
    finally:
        end_cpu_share(uid)
    process.wait(timeout=10)  # killed with everything in the group
    assert process.returncode == -9
    assert not group.exists()
