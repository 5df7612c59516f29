"""Helpers for the bag tests: tiny bags built in ``tmp_path``, classic odometry functions."""

from __future__ import annotations

import math

from duckielib.bags import BagWriter
from duckielib.messages import WheelEncoderStamped

LEFT = "/duckiebot/left_wheel_encoder_node/tick"
RIGHT = "/duckiebot/right_wheel_encoder_node/tick"


def encoder(ticks, stamp_ns):
    msg = WheelEncoderStamped(data=ticks, resolution=135, type=1)
    msg.header.stamp.secs, msg.header.stamp.nsecs = divmod(stamp_ns, 1_000_000_000)
    return msg


def write_encoders(path, left, right, skew_ns=0, compression="none"):
    """A bag of encoder messages; ``left``/``right`` are lists of (record time ns, ticks)."""
    with BagWriter(path, compression) as writer:
        events = [(t, LEFT, ticks) for t, ticks in left] + [(t, RIGHT, ticks) for t, ticks in right]
        for t, topic, ticks in sorted(events, key=lambda event: event[0]):
            writer.write(topic, encoder(ticks, max(0, t - skew_ns)), t)
    return path


def delta_phi(ticks, prev_ticks, resolution):
    return 2 * math.pi * (ticks - prev_ticks) / resolution, ticks


def estimate_pose(
    R,  # noqa: N803 - the course's signature
    baseline,
    x_prev,
    y_prev,
    theta_prev,
    delta_phi_left,
    delta_phi_right,
):
    left, right = R * delta_phi_left, R * delta_phi_right
    distance, turn = (left + right) / 2, (right - left) / baseline
    return (
        x_prev + distance * math.cos(theta_prev),
        y_prev + distance * math.sin(theta_prev),
        (theta_prev + turn) % (2 * math.pi),
    )


class WheelPairing:
    """The course's pairing rule: a pair once both wheels reported, changes accumulated."""

    def __init__(self, resolution=135):
        self.resolution = resolution
        self.prev = {}
        self.change = {"left": 0.0, "right": 0.0}
        self.reported = set()

    def add(self, wheel, ticks):
        if wheel not in self.change:
            raise ValueError(f"wheel must be 'left' or 'right', not {wheel!r}")
        if wheel in self.prev:
            change, self.prev[wheel] = delta_phi(ticks, self.prev[wheel], self.resolution)
            self.change[wheel] += change
        else:
            self.prev[wheel] = ticks
        self.reported.add(wheel)
        if len(self.reported) < 2:
            return None
        pair = (self.change["left"], self.change["right"])
        self.change = {"left": 0.0, "right": 0.0}
        self.reported = set()
        return pair
