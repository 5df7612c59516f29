"""The mat and its walls, and the LED state the simulator reports."""

from __future__ import annotations

import pytest

from duckielib.config import TILE_SIZE
from duckielib.errors import ConfigError
from duckielib.sim import LEDState, Simulator, World
from duckielib.sim.world import COLLISION_SLOP, build_space

WHITE = (0.8, 0.8, 0.8)
OFF = (0.0, 0.0, 0.0)


def test_world_size_in_tiles():
    world = World(tiles_x=3, tiles_y=5)
    assert world.width == pytest.approx(3 * TILE_SIZE)
    assert world.height == pytest.approx(5 * TILE_SIZE)
    assert len(world.grid_lines()) == 4 + 6
    assert world.contains(0.1, 2.9)
    assert not world.contains(1.8, 1.0)
    assert not world.contains(0.1, 0.1, margin=0.2)


@pytest.mark.parametrize(
    "settings", [{"tiles_x": 0}, {"tiles_y": 2.5}, {"tile_size": -1.0}, {"tiles_x": True}]
)
def test_world_rejects_impossible_sizes(settings):
    with pytest.raises(ConfigError):
        World(**settings)


def test_space_is_set_up_in_metres():
    space = build_space(World())
    assert space.collision_slop == COLLISION_SLOP < 0.001
    assert tuple(space.gravity) == (0.0, 0.0)
    assert len(space.shapes) == 4
    assert len(build_space(World(walls=False)).shapes) == 0


def test_leds_start_white():
    sim = Simulator()
    assert sim.leds == LEDState("WHITE", (WHITE,) * 5)


def test_named_pattern_blinks_in_simulated_time():
    sim = Simulator()
    sim.run_until(1.0)
    sim.set_led_pattern("CAR_SIGNAL_A")  # 4 Hz: toggles every 0.125 s
    assert sim.leds.pattern == "CAR_SIGNAL_A"
    assert sim.leds.colors[0] == WHITE
    sim.run_until(1.13)
    assert sim.leds.colors[0] == OFF
    assert sim.leds.colors[1] == (0.8, 0.0, 0.0)
    sim.run_until(1.26)
    assert sim.leds.colors[0] == WHITE


def test_unknown_pattern_is_rejected_and_the_old_one_kept():
    sim = Simulator()
    sim.set_led_pattern("RED")
    with pytest.raises(ConfigError, match="no LED pattern called 'MAGENTA'"):
        sim.set_led_pattern("MAGENTA")
    assert sim.leds.pattern == "RED"


def test_custom_pattern():
    sim = Simulator()
    sim.set_custom_led_pattern(["red", "green", "blue", "white", (1.0, 0.5, 0.0)])
    assert sim.leds.pattern == "custom"
    assert sim.leds.colors == ((0.8, 0, 0), (0, 0.8, 0), (0, 0, 0.8), WHITE, (1.0, 0.5, 0.0))
    assert sim.led_pattern.color_list[0] == "red"


def test_trace_records_path_and_led_history():
    sim = Simulator(trace_rate_hz=10)
    sim.set_wheel_duties(0.5, 0.5)
    sim.run_until(1.0)
    sim.set_led_pattern("LIGHT_OFF")
    sim.run_until(2.0)
    trace = sim.trace
    assert len(trace) == 21
    assert trace.poses().shape == (21, 3)
    colors = trace.led_colors()
    assert colors.shape == (21, 5, 3)
    assert colors[5, 0].tolist() == list(WHITE)
    assert colors[-1].max() == 0.0
    assert trace.poses()[-1, 1] > trace.poses()[0, 1] + 0.5
    assert len(Simulator(trace_rate_hz=0).trace) == 0
