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
