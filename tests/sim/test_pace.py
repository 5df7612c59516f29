"""The virtual Duckiebot node's pace: simulated time at ``~rate``, slower under load, no bursts."""

from __future__ import annotations

import pytest

from duckielib.sim.ros_node import PHYSICS_STEP_S, Pace


class WallClock:
    """A wall clock that moves only when the pace sleeps or a step takes time."""

    def __init__(self) -> None:
        self.now = 100.0
        self.slept: list = []

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.slept.append(seconds)
        self.now += seconds


def run(pace: Pace, wall: WallClock, steps: range, step_cost=lambda step: 0.0):
    """Advance ``steps`` physics steps; return the wall time at which each was published."""
    published = []
    for step in steps:
        wall.now += step_cost(step)
        pace.wait(step * PHYSICS_STEP_S)
        published.append(wall.now)
    return published


def test_simulated_time_runs_at_the_rate_when_steps_are_cheap():
    wall = WallClock()
    pace = Pace(2.0, clock=wall, sleep=wall.sleep)
    published = run(pace, wall, range(1, 201))
    assert published[-1] - 100.0 == pytest.approx(200 * PHYSICS_STEP_S / 2.0)


def test_a_stall_slows_simulated_time_instead_of_bursting_to_catch_up():
    wall = WallClock()
    pace = Pace(2.0, max_lag=0.02, clock=wall, sleep=wall.sleep)
    # Step 50 takes half a wall second (the machine was busy elsewhere).
    published = run(pace, wall, range(1, 201), lambda step: 0.5 if step == 50 else 0.0)
    after = published[49:]  # from step 50 on
    # Over any stretch after the stall, simulated time runs ahead of the rate by at most
    # max_lag of wall time (a burst would publish about 100 steps at once).
    ahead = max(
        (j - i) * PHYSICS_STEP_S / 2.0 - (after[j] - after[i])
        for i in range(len(after))
        for j in range(i + 1, len(after))
    )
    assert ahead == pytest.approx(0.02, abs=1e-9)
    assert published[-1] - published[48] == pytest.approx(0.5 + 150 * PHYSICS_STEP_S / 2 - 0.02)


def test_small_lags_are_made_up():
    wall = WallClock()
    pace = Pace(1.0, max_lag=0.02, clock=wall, sleep=wall.sleep)
    published = run(pace, wall, range(1, 101), lambda step: 0.015 if step == 10 else 0.0)
    assert published[-1] - 100.0 == pytest.approx(100 * PHYSICS_STEP_S)
