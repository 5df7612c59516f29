"""All of one student's sandboxed processes share control groups: their CPUs, memory, processes."""

from __future__ import annotations

import dataclasses
import subprocess
import sys
import time

import pytest

from autograder.sandbox import Limits, end_student_groups, joined, student_groups, unit_user


def test_a_students_processes_share_their_limits_and_end_with_the_groups():
    limits = dataclasses.replace(
        Limits(), uid=unit_user(), cpus=0.5, total_memory_bytes=2 * 1024**3, processes=40
    )
    groups = student_groups(limits)
    if not groups:
        pytest.skip("this machine lets the grader make no control group")
    try:
        values = {}
        for group in groups:
            for name in ("cpu.cfs_quota_us", "cpu.max", "memory.limit_in_bytes", "memory.max",
                         "pids.max"):  # fmt: skip
                if (group / name).exists():
                    values[name] = (group / name).read_text().split()
        assert values.get("cpu.cfs_quota_us", values.get("cpu.max"))[0] == "50000"
        assert values.get("memory.limit_in_bytes", values.get("memory.max")) == [str(2 * 1024**3)]
        assert values["pids.max"] == ["40"]
        # A process that starts a busy child: both are in every group.
        script = (
            "import subprocess, sys, time\n"
            "subprocess.Popen([sys.executable, '-c', 'while True: pass'])\n"
            "time.sleep(60)\n"
        )
        process = subprocess.Popen(joined(groups, [sys.executable, "-c", script]))
        deadline = time.monotonic() + 10
        while any(len((g / "cgroup.procs").read_text().split()) < 2 for g in groups):
            assert time.monotonic() < deadline, "the child never joined the groups"
            time.sleep(0.05)
        for group in groups:
            assert str(process.pid) in (group / "cgroup.procs").read_text().split()
    finally:
        end_student_groups(limits.uid)
    process.wait(timeout=10)  # killed with everything in the groups
    assert process.returncode == -9
    assert not any(group.exists() for group in groups)
