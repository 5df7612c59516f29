"""How long a straight side takes."""


def side_seconds(length, speed):
    """Seconds to drive `length` metres at `speed` m/s."""
    return length / speed
