"""Same seed and commands give a bit-identical run, in this process and in another one."""

from __future__ import annotations

import json
import subprocess
import sys

from duckielib.sim import Simulator

SCRIPT = """
import json
from duckielib.sim import Simulator

sim = Simulator(seed={seed}, noise="realistic")
for index, (left, right) in enumerate([(0.5, 0.5), (-0.4, 0.4), (1.0, 0.6), (0.0, 0.0)] * 3):
    sim.set_wheel_duties(left, right)
    sim.run_until((index + 1) * 0.7)
readings = [[r.wheel, r.time.hex(), r.ticks] for r in sim.pop_encoder_readings()]
path = [[t.hex(), x.hex(), y.hex(), theta.hex()]
        for t, x, y, theta in zip(sim.trace.times, sim.trace.xs, sim.trace.ys, sim.trace.thetas)]
print(json.dumps({{"pose": [v.hex() for v in sim.pose], "readings": readings, "path": path}}))
"""


def run_here(seed):
    namespace = {}
    lines = []
    namespace["print"] = lines.append
    exec(SCRIPT.format(seed=seed), namespace)
    return json.loads(lines[0])


def run_in_another_process(seed):
    result = subprocess.run(
        [sys.executable, "-c", SCRIPT.format(seed=seed)],
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(result.stdout)


def test_same_seed_same_run_in_one_process():
    first, second = run_here(11), run_here(11)
    assert first == second
    assert len(first["readings"]) > 400
    assert len(first["path"]) > 200


def test_same_seed_same_run_across_processes():
    assert run_in_another_process(11) == run_here(11)


def test_another_seed_changes_the_sensors_not_the_robot():
    first, other = run_here(11), run_here(12)
    assert first["readings"] != other["readings"]
    assert first["pose"] == other["pose"]


def test_how_the_clock_is_advanced_does_not_change_the_run():
    chunked = Simulator(seed=4, noise="realistic")
    stepped = Simulator(seed=4, noise="realistic")
    chunked.set_wheel_duties(0.6, 0.2)
    stepped.set_wheel_duties(0.6, 0.2)
    chunked.run_until(1.0)
    for _ in range(100):
        stepped.step()
    assert chunked.pose == stepped.pose
    assert chunked.pop_encoder_readings() == stepped.pop_encoder_readings()


def test_public_pymunk_path_gives_the_same_run(monkeypatch):
    """The fast path through Chipmunk's functions and pymunk's public API agree exactly."""
    import pymunk

    fast = run_here(seed=7)
    monkeypatch.setattr(pymunk, "cp", None, raising=False)
    assert run_here(seed=7) == fast
