"""Deliberately wrong solutions of notebook 05_odometry, one dict entry per mistake.

Each value is the full source of a replacement for the graded cell named by the key; the test
cell ``test_<grade_id>`` must lose marks with it. The WheelPairing mistakes compute the wheel
angles themselves, so they fail for their own mistake even where delta_phi is not written.
"""

WRONG = {
    "delta_phi": {
        "absolute ticks instead of the change": """import math


def delta_phi(ticks, prev_ticks, resolution):
    return 2 * math.pi * ticks / resolution, ticks
""",
        "degrees instead of radians": """import math


def delta_phi(ticks, prev_ticks, resolution):
    return 360 * (ticks - prev_ticks) / resolution, ticks
""",
        "returns prev_ticks as the ticks to keep": """import math


def delta_phi(ticks, prev_ticks, resolution):
    return 2 * math.pi * (ticks - prev_ticks) / resolution, prev_ticks
""",
        "sign reversed": """import math


def delta_phi(ticks, prev_ticks, resolution):
    return 2 * math.pi * (prev_ticks - ticks) / resolution, ticks
""",
        "resolution fixed at 135": """import math


def delta_phi(ticks, prev_ticks, resolution):
    return 2 * math.pi * (ticks - prev_ticks) / 135, ticks
""",
    },
    "estimate_pose": {
        "half the baseline": """import math


def estimate_pose(R, baseline, x_prev, y_prev, theta_prev, delta_phi_left, delta_phi_right):
    d_left = R * delta_phi_left
    d_right = R * delta_phi_right
    d = (d_left + d_right) / 2
    delta_theta = (d_right - d_left) / (baseline / 2)
    x = x_prev + d * math.cos(theta_prev)
    y = y_prev + d * math.sin(theta_prev)
    return x, y, (theta_prev + delta_theta) % (2 * math.pi)
""",
        "left and right swapped": """import math


def estimate_pose(R, baseline, x_prev, y_prev, theta_prev, delta_phi_left, delta_phi_right):
    d_left = R * delta_phi_left
    d_right = R * delta_phi_right
    d = (d_left + d_right) / 2
    delta_theta = (d_left - d_right) / baseline
    x = x_prev + d * math.cos(theta_prev)
    y = y_prev + d * math.sin(theta_prev)
    return x, y, (theta_prev + delta_theta) % (2 * math.pi)
""",
        "no angle wrap": """import math


def estimate_pose(R, baseline, x_prev, y_prev, theta_prev, delta_phi_left, delta_phi_right):
    d_left = R * delta_phi_left
    d_right = R * delta_phi_right
    d = (d_left + d_right) / 2
    delta_theta = (d_right - d_left) / baseline
    x = x_prev + d * math.cos(theta_prev)
    y = y_prev + d * math.sin(theta_prev)
    return x, y, theta_prev + delta_theta
""",
        "moves along the new heading": """import math


def estimate_pose(R, baseline, x_prev, y_prev, theta_prev, delta_phi_left, delta_phi_right):
    d_left = R * delta_phi_left
    d_right = R * delta_phi_right
    d = (d_left + d_right) / 2
    theta = (theta_prev + (d_right - d_left) / baseline) % (2 * math.pi)
    return x_prev + d * math.cos(theta), y_prev + d * math.sin(theta), theta
""",
        "sum of the wheel distances instead of their mean": """import math


def estimate_pose(R, baseline, x_prev, y_prev, theta_prev, delta_phi_left, delta_phi_right):
    d = R * delta_phi_left + R * delta_phi_right
    delta_theta = R * (delta_phi_right - delta_phi_left) / baseline
    x = x_prev + d * math.cos(theta_prev)
    y = y_prev + d * math.sin(theta_prev)
    return x, y, (theta_prev + delta_theta) % (2 * math.pi)
""",
        "wrap with math.fmod (negative stays negative)": """import math


def estimate_pose(R, baseline, x_prev, y_prev, theta_prev, delta_phi_left, delta_phi_right):
    d = R * (delta_phi_left + delta_phi_right) / 2
    delta_theta = R * (delta_phi_right - delta_phi_left) / baseline
    x = x_prev + d * math.cos(theta_prev)
    y = y_prev + d * math.sin(theta_prev)
    return x, y, math.fmod(theta_prev + delta_theta, 2 * math.pi)
""",
        "wraps by one turn at most": """import math


def estimate_pose(R, baseline, x_prev, y_prev, theta_prev, delta_phi_left, delta_phi_right):
    d = R * (delta_phi_left + delta_phi_right) / 2
    theta = theta_prev + R * (delta_phi_right - delta_phi_left) / baseline
    if theta >= 2 * math.pi:
        theta -= 2 * math.pi
    if theta < 0:
        theta += 2 * math.pi
    return x_prev + d * math.cos(theta_prev), y_prev + d * math.sin(theta_prev), theta
""",
    },
    "WheelPairing": {
        "keeps only the last reading's change": """import math


class WheelPairing:
    def __init__(self, resolution=135):
        self.resolution = resolution
        self.last = {"left": None, "right": None}
        self.change = {"left": 0.0, "right": 0.0}
        self.reported = {"left": False, "right": False}

    def add(self, wheel, ticks):
        if wheel not in self.last:
            raise ValueError(wheel)
        if self.last[wheel] is not None:
            self.change[wheel] = 2 * math.pi * (ticks - self.last[wheel]) / self.resolution
        self.last[wheel] = ticks
        self.reported[wheel] = True
        if not all(self.reported.values()):
            return None
        pair = (self.change["left"], self.change["right"])
        self.change = {"left": 0.0, "right": 0.0}
        self.reported = {"left": False, "right": False}
        return pair
""",
        "returns a pair after every reading": """import math


class WheelPairing:
    def __init__(self, resolution=135):
        self.resolution = resolution
        self.last = {"left": None, "right": None}

    def add(self, wheel, ticks):
        if wheel not in self.last:
            raise ValueError(wheel)
        change = {"left": 0.0, "right": 0.0}
        if self.last[wheel] is not None:
            change[wheel] = 2 * math.pi * (ticks - self.last[wheel]) / self.resolution
        self.last[wheel] = ticks
        return change["left"], change["right"]
""",
        "first reading counted as a change from 0 ticks": """import math


class WheelPairing:
    def __init__(self, resolution=135):
        self.resolution = resolution
        self.last = {"left": 0, "right": 0}
        self.change = {"left": 0.0, "right": 0.0}
        self.reported = {"left": False, "right": False}

    def add(self, wheel, ticks):
        if wheel not in self.last:
            raise ValueError(wheel)
        self.change[wheel] += 2 * math.pi * (ticks - self.last[wheel]) / self.resolution
        self.last[wheel] = ticks
        self.reported[wheel] = True
        if not all(self.reported.values()):
            return None
        pair = (self.change["left"], self.change["right"])
        self.change = {"left": 0.0, "right": 0.0}
        self.reported = {"left": False, "right": False}
        return pair
""",
        "state kept in the class, shared by every pairing": """import math


class WheelPairing:
    last = {"left": None, "right": None}
    change = {"left": 0.0, "right": 0.0}
    reported = {"left": False, "right": False}

    def __init__(self, resolution=135):
        self.resolution = resolution

    def add(self, wheel, ticks):
        if wheel not in self.last:
            raise ValueError(wheel)
        if self.last[wheel] is not None:
            self.change[wheel] += 2 * math.pi * (ticks - self.last[wheel]) / self.resolution
        self.last[wheel] = ticks
        self.reported[wheel] = True
        if not all(self.reported.values()):
            return None
        pair = (self.change["left"], self.change["right"])
        for side in ("left", "right"):
            self.change[side] = 0.0
            self.reported[side] = False
        return pair
""",
        "resolution ignored": """import math


class WheelPairing:
    def __init__(self, resolution=135):
        self.last = {"left": None, "right": None}
        self.change = {"left": 0.0, "right": 0.0}
        self.reported = {"left": False, "right": False}

    def add(self, wheel, ticks):
        if wheel not in self.last:
            raise ValueError(wheel)
        if self.last[wheel] is not None:
            self.change[wheel] += 2 * math.pi * (ticks - self.last[wheel]) / 135
        self.last[wheel] = ticks
        self.reported[wheel] = True
        if not all(self.reported.values()):
            return None
        pair = (self.change["left"], self.change["right"])
        self.change = {"left": 0.0, "right": 0.0}
        self.reported = {"left": False, "right": False}
        return pair
""",
        "unknown wheel accepted": """import math


class WheelPairing:
    def __init__(self, resolution=135):
        self.resolution = resolution
        self.last = {}
        self.change = {"left": 0.0, "right": 0.0}
        self.reported = {"left": False, "right": False}

    def add(self, wheel, ticks):
        if wheel in self.last:
            self.change[wheel] = self.change.get(wheel, 0.0) + (
                2 * math.pi * (ticks - self.last[wheel]) / self.resolution
            )
        self.last[wheel] = ticks
        self.reported[wheel] = True
        if not (self.reported["left"] and self.reported["right"]):
            return None
        pair = (self.change["left"], self.change["right"])
        self.change = {"left": 0.0, "right": 0.0}
        self.reported = {"left": False, "right": False}
        return pair
""",
    },
}
