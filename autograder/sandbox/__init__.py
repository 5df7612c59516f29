"""Running a student's code under bubblewrap: the grader's wing for it.

- :mod:`.bubblewrap`: the sandbox itself (what it sees, as whom it runs, its limits) and the
  control groups that share the CPUs between students.
- :mod:`.server`: the grader's end of a sandbox that runs one student's notebooks.
- :mod:`.inside`: what runs in the sandbox (the server, the guard, the kernel zygote, the wire
  both ends speak); it imports only the standard library at load time.

The names below are the sandbox's, from :mod:`.bubblewrap`.
"""

from autograder.sandbox.bubblewrap import (
    COURSE,
    FIRST_UNIT_USER,
    INSIDE,
    NOBODY,
    Limits,
    SandboxError,
    SandboxUnavailable,
    Started,
    end_student_groups,
    joined,
    run,
    sandboxed_command,
    started,
    student_groups,
    unit_user,
)
from autograder.sandbox.unit_process import check_sandbox

__all__ = [
    "COURSE",
    "FIRST_UNIT_USER",
    "INSIDE",
    "NOBODY",
    "Limits",
    "SandboxError",
    "SandboxUnavailable",
    "Started",
    "check_sandbox",
    "end_student_groups",
    "joined",
    "run",
    "sandboxed_command",
    "started",
    "student_groups",
    "unit_user",
]
