"""Benchmark: the whole mission (graph, nodes, odometry, bag) against real time.

The square-then-circle mission on the ideal virtual Duckiebot with the reference solution, as
``duckie mission`` runs it: the drivers, the odometry node running the solution's functions,
the solution's light service and mission nodes, and the bag recorder. The figures leave out the
plots, which are drawn after the run. The headline is the real-time factor (simulated seconds
per wall-clock second of the run), best of three runs; ``summary.json`` reports the same figure
for each run.
"""

from __future__ import annotations

import tempfile
from typing import List, Tuple

from duckielib.runner import run_mission
from duckielib.solution import MISSION_PARTS, load_solution

_RUNS = 3


def run() -> List[Tuple[str, str]]:
    """Run the mission three times; return the figures of the fastest run."""
    from duckielib.bags import Bag

    solution = load_solution(required=MISSION_PARTS)
    runs = []
    for _ in range(_RUNS):
        with tempfile.TemporaryDirectory() as folder:
            result = run_mission(solution, out=folder, animation=False)
            runs.append((result, Bag(result.files["bag"]).message_count))
    best, messages = min(runs, key=lambda item: item[0].wall_s)
    return [
        ("mission_simulated_s", f"{best.simulated_s:.1f}"),
        ("mission_wall_s", f"{best.wall_s:.3f}"),
        ("mission_bag_messages", str(messages)),
        ("mission_realtime_factor", f"{best.realtime_factor:.0f}"),
    ]
