"""The LED tables match Duckietown's LED emitter (spec: duckiebot-interface.md, LED emitter)."""

from __future__ import annotations

import math

import pytest

from duckielib import leds
from duckielib.errors import ConfigError

SPEC_COLORS = {
    "switchedoff": (0, 0, 0),
    "white": (1, 1, 1),
    "green": (0, 1, 0),
    "red": (1, 0, 0),
    "blue": (0, 0, 1),
    "yellow": (1, 0.8, 0),
    "purple": (1, 0, 1),
    "cyan": (0, 1, 1),
    "pink": (1, 0, 0.5),
}
SOLID = ("WHITE", "RED", "GREEN", "BLUE", "YELLOW", "LIGHT_OFF", "light_off")
OTHERS = (
    "CAR_SIGNAL_PRIORITY",
    "CAR_SIGNAL_SACRIFICE_FOR_PRIORITY",
    "CAR_SIGNAL_A",
    "CAR_SIGNAL_GREEN",
    "CAR_DRIVING",
    "OBSTACLE_ALERT",
    "OBSTACLE_STOPPED",
    "POPO",
)


def test_colors_are_the_emitters():
    assert leds.COLORS == SPEC_COLORS
    assert leds.LED_SCALE == 0.8


def test_led_index_order():
    assert leds.LED_COUNT == 5
    assert leds.LED_POSITIONS == (
        "front-left",
        "rear-left",
        "top-front-middle",
        "rear-right",
        "front-right",
    )


def test_every_pattern_of_the_spec_exists():
    assert set(leds.PATTERNS) == set(SOLID) | set(OTHERS)
    for name, pattern in leds.PATTERNS.items():
        assert pattern.name == name
        assert len(pattern.color_list) == 5
        assert len(pattern.frequency_mask) == 5


@pytest.mark.parametrize("name", SOLID)
def test_solid_patterns_do_not_blink(name):
    pattern = leds.pattern_named(name)
    assert pattern.frequency == 0
    assert not pattern.blinking
    assert leds.colors_at(pattern, 0.0) == leds.colors_at(pattern, 0.37)


def test_blinking_frequencies_are_the_emitters():
    assert leds.FREQUENCIES == (1.9, 4.0, 5.7, 7.8, 10.6)
    expected = {
        "CAR_SIGNAL_PRIORITY": 5.7,
        "CAR_SIGNAL_SACRIFICE_FOR_PRIORITY": 1.9,
        "CAR_SIGNAL_A": 4.0,
        "CAR_SIGNAL_GREEN": 5.7,
        "OBSTACLE_ALERT": 1.9,
        "OBSTACLE_STOPPED": 4.0,
        "POPO": 4.0,
        "CAR_DRIVING": 0.0,
    }
    for name, frequency in expected.items():
        assert leds.pattern_named(name).frequency == frequency


def test_named_colours_are_scaled():
    assert leds.pattern_colors(leds.pattern_named("RED")) == ((0.8, 0.0, 0.0),) * 5
    assert leds.pattern_colors(leds.pattern_named("WHITE")) == ((0.8, 0.8, 0.8),) * 5
    yellow = leds.pattern_colors(leds.pattern_named("YELLOW"))[0]
    assert yellow == pytest.approx((0.8, 0.64, 0.0))
    assert leds.pattern_colors(leds.pattern_named("LIGHT_OFF")) == ((0.0, 0.0, 0.0),) * 5


def test_popo_colours_by_led():
    colors = leds.pattern_colors(leds.pattern_named("POPO"))
    assert colors == (
        (0.0, 0.0, 0.8),
        (0.8, 0.0, 0.0),
        (0.0, 0.0, 0.0),
        (0.0, 0.0, 0.8),
        (0.8, 0.0, 0.0),
    )


def test_blinking_toggles_every_half_period():
    pattern = leds.pattern_named("CAR_SIGNAL_A")  # white/red, outer and middle blink at 4 Hz
    white, red, off = (0.8, 0.8, 0.8), (0.8, 0.0, 0.0), (0.0, 0.0, 0.0)
    on = (white, red, white, red, white)
    dark = (off, red, off, red, off)
    assert leds.colors_at(pattern, 0.0) == on
    assert leds.colors_at(pattern, 0.124) == on
    assert leds.colors_at(pattern, 0.126) == dark
    assert leds.colors_at(pattern, 0.249) == dark
    assert leds.colors_at(pattern, 0.251) == on
    assert leds.colors_at(pattern, 10.13) == dark


def test_unknown_pattern_name_is_a_clear_error():
    with pytest.raises(ConfigError, match=r"no LED pattern called 'ORANGE'.*WHITE"):
        leds.pattern_named("ORANGE")


def test_custom_pattern_one_colour_for_all():
    pattern = leds.custom_pattern("cyan")
    assert pattern.name == "custom"
    assert pattern.color_list == ("cyan",) * 5
    assert not pattern.blinking
    assert leds.pattern_colors(pattern) == ((0.0, 0.8, 0.8),) * 5


def test_custom_pattern_rgb_colours_are_shown_unscaled():
    pattern = leds.custom_pattern([(1, 0.5, 0), "red", "red", "red", (0.2, 0.2, 0.2)])
    colors = leds.pattern_colors(pattern)
    assert colors[0] == (1.0, 0.5, 0.0)
    assert colors[1] == (0.8, 0.0, 0.0)
    assert leds.pattern_colors(leds.custom_pattern((0.1, 0.2, 0.3))) == ((0.1, 0.2, 0.3),) * 5


def test_custom_pattern_blinks_with_its_mask():
    pattern = leds.custom_pattern("green", frequency=2.0, frequency_mask=[0, 0, 1, 0, 0])
    assert pattern.blinking
    colors = leds.colors_at(pattern, 0.3)  # second half of the first 0.5 s period
    assert colors[2] == (0.0, 0.0, 0.0)
    assert colors[0] == (0.0, 0.8, 0.0)


def test_custom_pattern_empty_mask_blinks_every_led():
    pattern = leds.custom_pattern("blue", frequency=1.0, frequency_mask=[])
    assert pattern.frequency_mask == (1, 1, 1, 1, 1)
    assert leds.colors_at(pattern, 0.75) == ((0.0, 0.0, 0.0),) * 5


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ((["red", "blue"],), "one colour or 5 colours"),
        (("orange",), "does not know"),
        (((1.5, 0, 0),), "in \\[0, 1\\]"),
        (("red", -1.0), "frequency"),
        (("red", math.nan), "frequency"),
        (("red", 1.0, [1, 0, 1]), "frequency mask"),
        (("red", 1.0, [1, 0, 2, 0, 1]), "frequency mask"),
    ],
)
def test_custom_pattern_rejects_bad_input(arguments, message):
    with pytest.raises(ConfigError, match=message):
        leds.custom_pattern(*arguments)
