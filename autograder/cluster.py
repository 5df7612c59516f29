"""A Dask cluster of separate processes on this machine, started with Dask's own commands.

``duckie grade --scheduler ADDRESS`` grades on any running Dask cluster. :func:`dask_cluster`
starts one here as an instructor would start it by hand (``dask scheduler``, ``dask worker``),
for the benchmark's cluster figure and the tests: the same code path as a cluster of many
machines, with the network traffic of a real one.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator, List

__all__ = ["Cluster", "dask_cluster"]


@dataclass
class Cluster:
    """A running cluster: its scheduler's address and its processes.

    Attributes:
        address: the scheduler's address (``tcp://127.0.0.1:PORT``).
        processes: the scheduler's process, then each worker's.
    """

    address: str
    processes: List[subprocess.Popen] = field(default_factory=list)


def _dask(*args: str) -> subprocess.Popen:
    return subprocess.Popen(
        [str(Path(sys.executable).parent / "dask"), *args],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        start_new_session=True,
    )


@contextlib.contextmanager
def dask_cluster(workers: int = 2, nanny: bool = False) -> Iterator[Cluster]:
    """A scheduler and ``workers`` single-thread workers on 127.0.0.1, stopped on leaving.

    Args:
        workers: how many worker processes.
        nanny: whether each worker runs under a nanny (which restarts it if it dies); without,
            a killed worker stays dead.

    Raises:
        RuntimeError: if the cluster did not come up within a minute.
    """
    from distributed import Client

    with tempfile.TemporaryDirectory(prefix="duckie-dask-") as folder:
        address_file = Path(folder) / "scheduler.json"
        cluster = Cluster(address="")
        try:
            cluster.processes.append(
                _dask("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                      "--scheduler-file", str(address_file))
            )  # fmt: skip
            deadline = time.monotonic() + 60
            while not address_file.is_file():
                if time.monotonic() > deadline:
                    raise RuntimeError("The Dask scheduler did not start within 60 s.")
                time.sleep(0.1)
            cluster.address = json.loads(address_file.read_text())["address"]
            for _ in range(workers):
                cluster.processes.append(
                    _dask("worker", cluster.address, "--nthreads", "1", "--no-dashboard",
                          "--host", "127.0.0.1", "--memory-limit", "0",
                          *(() if nanny else ("--no-nanny",)))
                )  # fmt: skip
            with Client(cluster.address, timeout="60s") as client:
                client.wait_for_workers(workers, timeout=60)
            yield cluster
        finally:
            for process in cluster.processes:
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(process.pid, signal.SIGKILL)
                process.wait(timeout=30)
