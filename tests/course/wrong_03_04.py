"""Deliberately wrong solutions for notebooks 03_frames and 04_kinematics.

Each entry replaces the graded cell of that ``grade_id`` in the released notebook; the cell
``test_<grade_id>`` must then score less than its points.
"""

WRONG = {
    # 03_frames
    "wrap_angle": {
        "math.fmod keeps negative angles negative": """
import math

import numpy as np


def wrap_angle(theta):
    return math.fmod(theta, 2.0 * math.pi)
""",
        "angle returned unchanged": """
import math

import numpy as np


def wrap_angle(theta):
    return float(theta)
""",
        "plain modulo returns 2*pi just below 0": """
import math

import numpy as np


def wrap_angle(theta):
    return float(theta) % (2.0 * math.pi)
""",
        "wrapped into [-pi, pi) instead": """
import math

import numpy as np


def wrap_angle(theta):
    return (float(theta) + math.pi) % (2.0 * math.pi) - math.pi
""",
    },
    "rotation_matrix": {
        "transposed (clockwise rotation)": """
import math

import numpy as np


def rotation_matrix(theta):
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, s], [-s, c]])
""",
        "sin and cos swapped": """
import math

import numpy as np


def rotation_matrix(theta):
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[s, -c], [c, s]])
""",
    },
    "world_from_robot": {
        "rotation ignored (only translation)": """
import math

import numpy as np


def world_from_robot(robot_pose, point):
    x, y, theta = robot_pose
    return np.asarray(point, dtype=float) + np.array([x, y], dtype=float)
""",
        "translation ignored (only rotation)": """
import math

import numpy as np


def world_from_robot(robot_pose, point):
    x, y, theta = robot_pose
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]]) @ np.asarray(point, dtype=float)
""",
        "translated before rotating": """
import math

import numpy as np


def world_from_robot(robot_pose, point):
    x, y, theta = robot_pose
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]]) @ (np.asarray(point, dtype=float) + np.array([x, y]))
""",
    },
    "world_from_start": {
        "heading not wrapped": """
import math

import numpy as np


def world_from_start(pose, start=(0.32, 0.32, math.pi / 2)):
    x_s, y_s, theta_s = pose
    x0, y0, theta0 = start
    c, s = math.cos(theta0), math.sin(theta0)
    return (float(x0 + c * x_s - s * y_s), float(y0 + s * x_s + c * y_s), float(theta0 + theta_s))
""",
        "rotated by minus the start heading": """
import math

import numpy as np


def world_from_start(pose, start=(0.32, 0.32, math.pi / 2)):
    x_s, y_s, theta_s = pose
    x0, y0, theta0 = start
    c, s = math.cos(-theta0), math.sin(-theta0)
    theta = (theta0 + theta_s) % (2.0 * math.pi)
    return (float(x0 + c * x_s - s * y_s), float(y0 + s * x_s + c * y_s), float(theta))
""",
        "start heading not added to the heading": """
import math

import numpy as np


def world_from_start(pose, start=(0.32, 0.32, math.pi / 2)):
    x_s, y_s, theta_s = pose
    x0, y0, theta0 = start
    c, s = math.cos(theta0), math.sin(theta0)
    theta = theta_s % (2.0 * math.pi)
    return (float(x0 + c * x_s - s * y_s), float(y0 + s * x_s + c * y_s), float(theta))
""",
    },
    # 04_kinematics
    "forward_kinematics": {
        "half baseline": """
import math

import numpy as np


def forward_kinematics(omega_left, omega_right, R, baseline):
    v = R * (omega_left + omega_right) / 2.0
    omega = R * (omega_right - omega_left) / (baseline / 2.0)
    return v, omega
""",
        "left and right swapped": """
import math

import numpy as np


def forward_kinematics(omega_left, omega_right, R, baseline):
    v = R * (omega_left + omega_right) / 2.0
    omega = R * (omega_left - omega_right) / baseline
    return v, omega
""",
        "sum of the wheels instead of their mean": """
import math

import numpy as np


def forward_kinematics(omega_left, omega_right, R, baseline):
    v = R * (omega_left + omega_right)
    omega = R * (omega_right - omega_left) / baseline
    return v, omega
""",
    },
    "inverse_kinematics": {
        "half baseline (omega * baseline instead of omega * baseline / 2)": """
import math

import numpy as np


def inverse_kinematics(v, omega, R, baseline):
    omega_left = (v - omega * baseline) / R
    omega_right = (v + omega * baseline) / R
    return omega_left, omega_right
""",
        "left and right swapped": """
import math

import numpy as np


def inverse_kinematics(v, omega, R, baseline):
    omega_left = (v + omega * baseline / 2.0) / R
    omega_right = (v - omega * baseline / 2.0) / R
    return omega_left, omega_right
""",
        "rim speeds returned, not divided by R": """
import math

import numpy as np


def inverse_kinematics(v, omega, R, baseline):
    return v - omega * baseline / 2.0, v + omega * baseline / 2.0
""",
    },
    "duty_cycles": {
        "trim sign swapped": """
import math

import numpy as np


def duty_cycles(v, omega, R, baseline, gain, trim, k, limit):
    omega_right = (v + omega * baseline / 2.0) / R
    omega_left = (v - omega * baseline / 2.0) / R
    u_right = omega_right * (gain - trim) / k
    u_left = omega_left * (gain + trim) / k
    return min(max(u_left, -limit), limit), min(max(u_right, -limit), limit)
""",
        "no clipping to the limit": """
import math

import numpy as np


def duty_cycles(v, omega, R, baseline, gain, trim, k, limit):
    omega_right = (v + omega * baseline / 2.0) / R
    omega_left = (v - omega * baseline / 2.0) / R
    return omega_left * (gain - trim) / k, omega_right * (gain + trim) / k
""",
        "gain ignored": """
import math

import numpy as np


def duty_cycles(v, omega, R, baseline, gain, trim, k, limit):
    omega_right = (v + omega * baseline / 2.0) / R
    omega_left = (v - omega * baseline / 2.0) / R
    u_right = omega_right * (1.0 + trim) / k
    u_left = omega_left * (1.0 - trim) / k
    return min(max(u_left, -limit), limit), min(max(u_right, -limit), limit)
""",
        "clipped only from above (reversing not limited)": """
import math

import numpy as np


def duty_cycles(v, omega, R, baseline, gain, trim, k, limit):
    omega_right = (v + omega * baseline / 2.0) / R
    omega_left = (v - omega * baseline / 2.0) / R
    u_right = omega_right * (gain + trim) / k
    u_left = omega_left * (gain - trim) / k
    return min(u_left, limit), min(u_right, limit)
""",
        "(u_right, u_left) returned in the wrong order": """
import math

import numpy as np


def duty_cycles(v, omega, R, baseline, gain, trim, k, limit):
    omega_right = (v + omega * baseline / 2.0) / R
    omega_left = (v - omega * baseline / 2.0) / R
    u_right = min(max(omega_right * (gain + trim) / k, -limit), limit)
    u_left = min(max(omega_left * (gain - trim) / k, -limit), limit)
    return u_right, u_left
""",
    },
}
