"""What one student's grading may use: the sandbox's limits, in one place.

:mod:`.bubblewrap` applies them to each sandboxed process, :mod:`.groups` to all of a student's
processes together, :mod:`.unit_process` to the grader's own process for that student.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["NOBODY", "STUDENT_DISK_VARIABLE", "Limits"]

#: The unprivileged user and group the code runs as unless told.
NOBODY = 65534
#: The environment variable that names the folder the student's sandboxes write in, where it is
#: a file system of that student's own (:mod:`.unit_process`).
STUDENT_DISK_VARIABLE = "DUCKIE_STUDENT_DISK"


@dataclass(frozen=True)
class Limits:
    """What one submission may use.

    Attributes:
        cell_seconds: wall time of one notebook cell.
        submission_seconds: wall time of one notebook, all cells and the kernel's start.
        memory_bytes: address space of each process (a 20 GB allocation fails at once).
        processes: processes and threads of the sandbox user (a fork bomb stops there).
        cpu_seconds: CPU time of each process.
        mission_seconds: wall time of the driving run (the mission on the virtual Duckiebot).
        stall_seconds: wall time a node of the driving run may compute without calling rospy
            (simulated time stands still meanwhile) before the run stops it, saying why.
        file_bytes: the largest file a process may write (its standard output too).
        output_bytes: the most the grader reads of a run's standard output and error.
        uid: the unprivileged user (and group) the code runs as. The process limit counts
            every process of that user, so each student's grading uses a user of its own
            (:func:`unit_user`): a fork bomb cannot starve another student's sandbox.
        cpus: how many CPUs all of one student's sandboxed processes may use together, where
            the machine lets the grader make control groups (:func:`student_groups`): busy
            loops a student leaves running slow only that student's grading.
        total_memory_bytes: the memory all of one student's sandboxed processes may use
            together (a control group, as ``cpus``).
        disk_bytes: what one student's code may write in all while it is graded: the files of
            all their sandboxes and their ``/tmp`` (a file system of that size, see
            :mod:`.unit_process`), so one student cannot fill the disk the others, or their
            own grading, need.
        grader_memory_bytes: the address space of the grader's own process for one student
            (:mod:`.unit_process`).
        student_seconds: wall time of all of one student's notebooks together (each has its
            ``submission_seconds`` too): the notebooks after it are not run, said.
        slow_cell_seconds: a cell outside the tests that takes longer is named in the
            student's problems (the course's slowest, notebook 11's run of the robot
            project, takes about 6 s on an idle machine).
    """

    cell_seconds: int = 60
    submission_seconds: int = 600
    memory_bytes: int = 4 * 1024**3
    processes: int = 256
    cpu_seconds: int = 900
    mission_seconds: int = 180
    stall_seconds: int = 10
    file_bytes: int = 1024**3
    output_bytes: int = 256 * 1024**2
    uid: int = NOBODY
    cpus: float = 1.0
    total_memory_bytes: int = 6 * 1024**3
    disk_bytes: int = 2 * 1024**3
    grader_memory_bytes: int = 4 * 1024**3
    student_seconds: int = 1800
    slow_cell_seconds: int = 30
