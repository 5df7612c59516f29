"""The simulator benchmark and the runnable square example."""

from __future__ import annotations

import re
import subprocess
import sys

from duckielib.sim.examples import square
from duckielib.tools.bench import BENCHMARKS, run_benchmark


def test_sim_benchmark_prints_its_headline_last():
    assert "sim" in BENCHMARKS
    figures = run_benchmark("sim")
    names = [name for name, _ in figures]
    assert names[-1] == "sim_realtime_factor"
    assert float(figures[-1][1]) > 0
    values = dict(figures)
    assert values["sim_simulated_s"] == "60.0"
    assert values["sim_encoder_samples"] == "3600"
    assert int(values["sim_led_changes_seen"]) > 100


def test_duckie_bench_sim_ends_with_the_real_time_factor():
    result = subprocess.run(
        [sys.executable, "-m", "duckielib.tools.cli", "bench", "sim"],
        capture_output=True,
        text=True,
        check=True,
    )
    assert re.fullmatch(r"sim_realtime_factor: \d+", result.stdout.strip().splitlines()[-1])


def test_ideal_square_closes_and_ticks_match_travel():
    run = square.SquareRun(seed=0, noise="ideal")
    reports = run.run()
    assert len(reports) == 16
    for report in reports:
        for counted, travelled in zip(report.ticks_counted, report.ticks_travelled):
            if report.leg.name == "stop" and report.turn_deg != 0:
                continue  # coasting backwards after a turn counts up (the sign rule)
            assert abs(counted - travelled) <= 1.5
    x0, y0, _ = run.sim.trace.poses()[0]
    x, y, _ = run.sim.pose
    assert ((x - x0) ** 2 + (y - y0) ** 2) ** 0.5 < 0.06


def test_realistic_square_does_not_close():
    run = square.SquareRun(seed=0, noise="realistic")
    run.run()
    x0, y0, _ = run.sim.trace.poses()[0]
    x, y, _ = run.sim.pose
    assert ((x - x0) ** 2 + (y - y0) ** 2) ** 0.5 > 0.3


def test_square_example_runs_as_a_module(tmp_path):
    figure = tmp_path / "square.png"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "duckielib.sim.examples.square",
            "--noise",
            "realistic",
            "--plot",
            str(figure),
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    assert "noise profile: realistic" in result.stdout
    assert "misses closing by" in result.stdout
    assert figure.read_bytes()[:4] == b"\x89PNG"
