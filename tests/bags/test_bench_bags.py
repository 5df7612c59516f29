"""The bags benchmark runs and prints well-formed figures (its speed is never asserted)."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from duckielib.tools.bench import BENCHMARKS
from duckielib.tools.bench import bags as bench_bags


def test_bags_benchmark_is_registered():
    assert BENCHMARKS["bags"][0] == "duckielib.tools.bench.bags"


@pytest.mark.slow
def test_bags_benchmark_figures():
    figures = bench_bags.run()
    names = [name for name, _ in figures]
    values = dict(figures)

    assert names[-2:] == ["bag_odometry_seconds", "rosbag_read_seconds"]
    assert len(set(names)) == len(names)
    assert values["bag_messages"] == "100000"
    assert values["bag_odometry_updates"] == "49999"
    odometry = values["bag_odometry_seconds"]
    assert float(odometry) > 0
    assert len(odometry.split(".")[1]) == 3
    if not Path("/usr/bin/rosbag").exists():
        assert values["rosbag_read_seconds"] == "unavailable"
        pytest.skip("/usr/bin/rosbag is missing, so rosbag's read time is not measured.")
    rosbag = values["rosbag_read_seconds"]
    assert rosbag != "unavailable", values.get("rosbag_unavailable_because")
    assert float(rosbag) > 0
    assert len(rosbag.split(".")[1]) == 3


def test_rosbag_read_without_debian_python_says_why(monkeypatch, tmp_path):
    monkeypatch.setattr(bench_bags, "_SYSTEM_PYTHON", tmp_path / "no-python3")
    seconds, why = bench_bags._rosbag_read(tmp_path / "encoders.bag", 100_000)
    assert math.isnan(seconds)
    assert "no-python3 is missing" in why
    assert "make ros" in why
