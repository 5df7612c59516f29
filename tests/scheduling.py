"""How the suite's modules go to pytest-xdist's workers when one of them crashes.

``make test`` hands whole modules to the workers (``--dist loadscope``). When a worker's
process dies in a test (a crash in native code, ``os._exit``, the kernel's OOM killer),
pytest-xdist 3.8.0 reports that test as failed and starts a new worker, but its scheduler then:

- puts every module the dead worker was given back in the queue, those it had finished
  too; a finished module reaches a worker as an empty batch, which the worker never reports
  done, so that worker gets no more work. Once every worker holds such a batch, the run
  waits for ever, with the failure untold;
- runs the test that crashed again, which may crash the next worker the same way;
- gives the new worker a single test and waits for it, while the worker waits to know the
  test after it before it runs one;
- may give work to a new worker that has not yet collected the tests, and stops on a
  ``KeyError``.

:class:`CrashSafeScopes` is xdist's own scheduler with those steps done as the run needs:
only what was left of the dead worker's modules goes back, without the test that crashed, a
worker always knows its next test or that there is none, and a worker gets work once it has
collected. ``tests/conftest.py`` makes it the scheduler of ``--dist loadscope``.
"""

from __future__ import annotations

from typing import Any, Dict, Optional

from xdist.scheduler import LoadScopeScheduling

__all__ = ["CrashSafeScopes"]

#: A module's tests and whether each is done, by test id.
Unit = Dict[str, bool]


class CrashSafeScopes(LoadScopeScheduling):
    """pytest-xdist's ``loadscope`` scheduling, which a worker's crash cannot stall."""

    def remove_node(self, node: Any) -> Optional[str]:
        """Forget a worker that ended; if it died in a test, that test's id.

        The rest of its modules go back to the queue, first, so that they start soon.
        """
        workload: Dict[str, Unit] = self.assigned_work.pop(node)
        left = {scope: unit for scope, unit in workload.items() if not all(unit.values())}
        if not left:
            return None
        crashed = next(test for unit in left.values() for test, done in unit.items() if not done)
        for unit in left.values():
            if crashed in unit:
                unit[crashed] = True  # reported failed by xdist; not run again
        waiting = {scope: unit for scope, unit in left.items() if not all(unit.values())}
        for scope, unit in reversed(list(waiting.items())):
            self.workqueue[scope] = unit
            self.workqueue.move_to_end(scope, last=False)
        for other in self.assigned_work:
            self._reschedule(other)
        return crashed

    def _reschedule(self, node: Any) -> None:
        if node not in self.registered_collections:
            return  # a new worker still collecting: it is given work once it has collected
        super()._reschedule(node)
        # A worker runs a test once it knows the next one: never leave it one test to run
        # while the queue still holds work.
        while (
            not node.shutting_down
            and self.workqueue
            and node in self.assigned_work
            and self._pending_of(self.assigned_work[node]) < 2
        ):
            self._assign_work_unit(node)
        if not self.workqueue and not node.shutting_down:
            node.shutdown()  # what it holds is the last: it runs it all, then ends
