"""The Duckiebot's five LEDs: colours, named patterns and blinking, as its LED emitter has them.

This is robot data, shared by the simulator and the LED emitter node. The tables are those of
Duckietown's LED emitter (``LED_protocol.yaml`` of dt-core, distro daffy):

- LED index order: 0 front-left, 1 rear-left, 2 top/front-middle, 3 rear-right, 4 front-right
  (:data:`LED_POSITIONS`).
- Colours are RGB triples in [0, 1] (:data:`COLORS`); the emitter scales named colours by
  :data:`LED_SCALE` (0.8) before sending them to the LEDs.
- A pattern (:class:`Pattern`) gives each LED a colour, a blinking frequency in Hz (0 for solid)
  and a frequency mask saying which LEDs blink. The emitter toggles the blinking LEDs every
  ``1 / (2 * frequency)`` seconds, so a blinking LED is on for half of each period; here it is on
  in the first half, counted from the moment the pattern was set.
- The emitter starts with :data:`START_PATTERN` (WHITE) and turns the LEDs off on shutdown
  (:data:`OFF_PATTERN`).

Example::

    pattern = pattern_named("CAR_SIGNAL_A")
    colors_at(pattern, seconds=0.3)  # five (r, g, b) triples, scaled by 0.8
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

from duckielib.errors import ConfigError

__all__ = [
    "LED_COUNT",
    "LED_POSITIONS",
    "LED_SCALE",
    "COLORS",
    "FREQUENCIES",
    "Pattern",
    "PATTERNS",
    "START_PATTERN",
    "OFF_PATTERN",
    "pattern_named",
    "custom_pattern",
    "pattern_colors",
    "colors_shown",
    "colors_at",
]

#: An RGB colour, each channel in [0, 1].
RGB = Tuple[float, float, float]

#: Number of LEDs on a Duckiebot.
LED_COUNT = 5

#: Where each LED sits, by index.
LED_POSITIONS: Tuple[str, ...] = (
    "front-left",
    "rear-left",
    "top-front-middle",
    "rear-right",
    "front-right",
)

#: Factor the emitter applies to named colours to limit the LEDs' brightness.
LED_SCALE = 0.8

#: Named colours, unscaled, RGB in [0, 1].
COLORS: Dict[str, RGB] = {
    "switchedoff": (0.0, 0.0, 0.0),
    "white": (1.0, 1.0, 1.0),
    "green": (0.0, 1.0, 0.0),
    "red": (1.0, 0.0, 0.0),
    "blue": (0.0, 0.0, 1.0),
    "yellow": (1.0, 0.8, 0.0),
    "purple": (1.0, 0.0, 1.0),
    "cyan": (0.0, 1.0, 1.0),
    "pink": (1.0, 0.0, 0.5),
}

#: The emitter's blinking frequencies f1..f5, in Hz.
FREQUENCIES: Tuple[float, ...] = (1.9, 4.0, 5.7, 7.8, 10.6)

#: Pattern the emitter shows when it starts.
START_PATTERN = "WHITE"

#: Pattern the emitter shows when it shuts down.
OFF_PATTERN = "LIGHT_OFF"

Color = Union[str, RGB]


@dataclass(frozen=True)
class Pattern:
    """One LED pattern: a colour per LED and which of them blink, how fast.

    Attributes:
        name: the pattern's name (``"custom"`` for a custom pattern).
        color_list: five colours, by LED index; each a name of :data:`COLORS` (scaled by
            :data:`LED_SCALE` when shown) or an RGB triple in [0, 1] (shown as given).
        frequency: blinking frequency in Hz; 0 for a solid pattern.
        frequency_mask: five flags, by LED index; 1 if that LED blinks.
    """

    name: str
    color_list: Tuple[Color, ...]
    frequency: float
    frequency_mask: Tuple[int, ...]

    @property
    def blinking(self) -> bool:
        """Whether any LED of this pattern blinks."""
        return self.frequency > 0 and any(self.frequency_mask)


def _solid(name: str, color: str) -> Pattern:
    return Pattern(name, (color,) * LED_COUNT, 0.0, (0,) * LED_COUNT)


def _blinking(name: str, colors: Sequence[str], frequency: float, mask: Sequence[int]) -> Pattern:
    return Pattern(name, tuple(colors), frequency, tuple(mask))


_F1, _F2, _F3, _F4, _F5 = FREQUENCIES
_WRWRW = ("white", "red", "white", "red", "white")

#: The emitter's named patterns.
PATTERNS: Dict[str, Pattern] = {
    pattern.name: pattern
    for pattern in (
        _blinking(
            "CAR_SIGNAL_PRIORITY",
            ("purple", "red", "purple", "red", "purple"),
            _F3,
            (1, 0, 1, 0, 1),
        ),
        _blinking("CAR_SIGNAL_SACRIFICE_FOR_PRIORITY", _WRWRW, _F1, (1, 0, 1, 0, 1)),
        _blinking("CAR_SIGNAL_A", _WRWRW, _F2, (1, 0, 1, 0, 1)),
        _blinking("CAR_SIGNAL_GREEN", ("green",) * LED_COUNT, _F3, (1,) * LED_COUNT),
        Pattern("CAR_DRIVING", _WRWRW, 0.0, (0,) * LED_COUNT),
        _solid("WHITE", "white"),
        _solid("RED", "red"),
        _solid("GREEN", "green"),
        _solid("BLUE", "blue"),
        _solid("YELLOW", "yellow"),
        _solid("LIGHT_OFF", "switchedoff"),
        _solid("light_off", "switchedoff"),
        _blinking(
            "OBSTACLE_ALERT",
            ("white", "yellow", "white", "yellow", "white"),
            _F1,
            (0, 1, 0, 1, 0),
        ),
        _blinking("OBSTACLE_STOPPED", _WRWRW, _F2, (0, 1, 0, 1, 0)),
        _blinking("POPO", ("blue", "red", "switchedoff", "blue", "red"), _F2, (1, 1, 0, 1, 1)),
    )
}


def pattern_named(name: str) -> Pattern:
    """The named pattern ``name``, for example ``"RED"`` or ``"CAR_SIGNAL_A"``.

    Raises:
        ConfigError: if there is no pattern of that name.
    """
    pattern = PATTERNS.get(name)
    if pattern is None:
        raise ConfigError(
            f"There is no LED pattern called {name!r}; choose one of: {', '.join(PATTERNS)}."
        )
    return pattern


def _check_color(color: Any, index: int) -> Color:
    if isinstance(color, str):
        if color not in COLORS:
            raise ConfigError(
                f"LED {index} has the colour {color!r}, which the emitter does not know; "
                f"use one of: {', '.join(COLORS)}, or an (r, g, b) triple in [0, 1]."
            )
        return color
    try:
        triple = tuple(float(channel) for channel in color)
    except (TypeError, ValueError):
        triple = ()
    if len(triple) != 3 or not all(math.isfinite(c) and 0.0 <= c <= 1.0 for c in triple):
        raise ConfigError(
            f"LED {index} has the colour {color!r}; give a colour name or an (r, g, b) triple "
            "with each channel in [0, 1]."
        )
    return (triple[0], triple[1], triple[2])


def _is_triple(value: object) -> bool:
    return (
        isinstance(value, (tuple, list))
        and len(value) == 3
        and all(isinstance(channel, (int, float)) for channel in value)
    )


def custom_pattern(
    color_list: Union[Color, Sequence[Color]],
    frequency: float = 0.0,
    frequency_mask: Optional[Sequence[int]] = None,
    name: str = "custom",
) -> Pattern:
    """A custom pattern, checked as the emitter's ``set_custom_pattern`` service takes it.

    Args:
        color_list: one colour for all LEDs, or five colours by LED index; a colour is a name of
            :data:`COLORS` or an RGB triple in [0, 1].
        frequency: blinking frequency in Hz, 0 for solid.
        frequency_mask: five 0/1 flags saying which LEDs blink; empty or None means all of them
            when ``frequency`` is not 0.
        name: the pattern's name.

    Raises:
        ConfigError: if a colour is unknown, the list does not have five colours, the frequency
            is negative or not finite, or the mask does not have five 0/1 flags.
    """
    if isinstance(color_list, str) or _is_triple(color_list):
        colors: Tuple[object, ...] = (color_list,) * LED_COUNT
    else:
        colors = tuple(color_list)
    if len(colors) != LED_COUNT:
        raise ConfigError(
            f"An LED pattern needs one colour or {LED_COUNT} colours (one per LED), "
            f"not {len(colors)}."
        )
    checked = tuple(_check_color(color, index) for index, color in enumerate(colors))
    try:
        frequency = float(frequency)
    except (TypeError, ValueError):
        frequency = math.nan
    if not (math.isfinite(frequency) and frequency >= 0):
        raise ConfigError(
            f"An LED pattern's frequency must be a finite number of Hz >= 0, not {frequency!r}."
        )
    if not frequency_mask:
        mask = (1 if frequency > 0 else 0,) * LED_COUNT
    else:
        mask = tuple(int(flag) for flag in frequency_mask)
        if len(mask) != LED_COUNT or any(flag not in (0, 1) for flag in mask):
            raise ConfigError(
                f"An LED pattern's frequency mask needs {LED_COUNT} flags of 0 or 1, "
                f"not {list(frequency_mask)!r}."
            )
    return Pattern(name, checked, frequency, mask)


def named_pattern(color_list: Sequence[object], frequency: float) -> Optional[Pattern]:
    """The named pattern whose colour names and blinking frequency these are, or None."""
    names = tuple(color_list)
    for name, pattern in PATTERNS.items():
        if name.islower():
            continue  # "light_off" is an alias of LIGHT_OFF
        if pattern.color_list == names and math.isclose(pattern.frequency, frequency, abs_tol=1e-3):
            return pattern
    return None


def pattern_of_message(
    color_list: Sequence[str],
    rgb_vals: Sequence[RGB],
    frequency: float,
    frequency_mask: Sequence[int],
) -> Pattern:
    """The pattern an ``LEDPattern`` message makes the LEDs show, as the LED driver reads it.

    A message with a named pattern's colour names and frequency (what the emitter sends) is
    that pattern. Any other shows its ``rgb_vals`` as given, or its colour names when it has
    no ``rgb_vals``: one colour for all five LEDs, or five by LED index.

    Raises:
        ConfigError: if the message gives no colour, a number of colours other than one or
            five, an unknown colour name, or an invalid frequency or mask.
    """
    named = named_pattern(color_list, frequency)
    if named is not None:
        return named
    colors: List[Color] = [(float(r), float(g), float(b)) for r, g, b in rgb_vals]
    if not colors:
        colors = [str(name) for name in color_list]
    if not colors:
        raise ConfigError("An LEDPattern message needs rgb_vals or color_list; it has neither.")
    return custom_pattern(colors[0] if len(colors) == 1 else colors, frequency, frequency_mask)


def _shown(color: Color) -> RGB:
    if isinstance(color, str):
        red, green, blue = COLORS[color]
        return (red * LED_SCALE, green * LED_SCALE, blue * LED_SCALE)
    return color


def pattern_colors(pattern: Pattern) -> Tuple[RGB, ...]:
    """The five colours the pattern shows when its blinking LEDs are on (named ones scaled)."""
    return tuple(_shown(color) for color in pattern.color_list)


def colors_at(pattern: Pattern, seconds: float) -> Tuple[RGB, ...]:
    """The five colours shown ``seconds`` after the pattern was set.

    Args:
        pattern: the pattern shown.
        seconds: time since the pattern was set, in seconds (>= 0).

    Returns:
        Five RGB triples in [0, 1], by LED index; blinking LEDs are off in the second half of
        each period.
    """
    colors = pattern_colors(pattern)
    if not pattern.blinking:
        return colors
    if math.floor(max(seconds, 0.0) * 2.0 * pattern.frequency) % 2 == 0:
        return colors
    off = (0.0, 0.0, 0.0)
    return tuple(off if flag else color for color, flag in zip(colors, pattern.frequency_mask))


def colors_shown(patterns: Sequence[Tuple[float, Pattern]], t: float) -> Tuple[RGB, ...]:
    """The five colours shown at ``t`` by the last of ``patterns`` set by then.

    Args:
        patterns: the patterns set, as (time set in seconds, pattern), in time order.
        t: the time, in seconds.

    Returns:
        Five RGB triples in [0, 1], by LED index: all off before the first pattern, blinking
        LEDs off in the second half of each period.
    """
    shown: Optional[Tuple[float, Pattern]] = None
    for since, pattern in patterns:
        if since > t:
            break
        shown = (since, pattern)
    if shown is None:
        return ((0.0, 0.0, 0.0),) * LED_COUNT
    return colors_at(shown[1], t - shown[0])
