"""Deliberately wrong solutions of notebook 06_driving, one dict entry per mistake.

Each value is the full source of a replacement for the graded cell named by the key; the test
cell ``test_<grade_id>`` must lose marks with it. The AngleTracker mistakes wrap the angles
themselves, so they fail for their own mistake even where angle_error is not written.
"""

WRONG = {
    "angle_error": {
        "no wrapping": """import math


def angle_error(target, theta):
    return target - theta
""",
        "wrapped into [0, 2 pi) instead of [-pi, pi)": """import math


def angle_error(target, theta):
    return (target - theta) % (2 * math.pi)
""",
        "sign reversed (theta - target)": """import math


def angle_error(target, theta):
    return (theta - target + math.pi) % (2 * math.pi) - math.pi
""",
        "atan2 gives +pi for half a turn, outside [-pi, pi)": """import math


def angle_error(target, theta):
    return math.atan2(math.sin(target - theta), math.cos(target - theta))
""",
        "wrapped once only, not for several turns": """import math


def angle_error(target, theta):
    error = target - theta
    if error >= math.pi:
        error -= 2 * math.pi
    elif error < -math.pi:
        error += 2 * math.pi
    return error
""",
    },
    "distance_along": {
        "Euclidean distance (never negative)": """import math


def distance_along(start, pose):
    x0, y0, _ = start
    x, y, _ = pose
    return math.hypot(x - x0, y - y0)
""",
        "x and y swapped": """import math


def distance_along(start, pose):
    x0, y0, theta0 = start
    x, y, _ = pose
    return (y - y0) * math.cos(theta0) + (x - x0) * math.sin(theta0)
""",
        "projected on the pose's heading instead of the start's": """import math


def distance_along(start, pose):
    x0, y0, _ = start
    x, y, theta = pose
    return (x - x0) * math.cos(theta) + (y - y0) * math.sin(theta)
""",
        "signed Euclidean distance (sideways offsets count)": """import math


def distance_along(start, pose):
    x0, y0, theta0 = start
    x, y, _ = pose
    along = (x - x0) * math.cos(theta0) + (y - y0) * math.sin(theta0)
    return math.copysign(math.hypot(x - x0, y - y0), along)
""",
    },
    "AngleTracker": {
        "returns the last wrapped change instead of the total": """import math


class AngleTracker:
    def __init__(self, theta0):
        self.last = theta0

    def update(self, theta):
        change = (theta - self.last + math.pi) % (2 * math.pi) - math.pi
        self.last = theta
        return change
""",
        "theta - theta0, no wrap across 2 pi": """import math


class AngleTracker:
    def __init__(self, theta0):
        self.theta0 = theta0

    def update(self, theta):
        return theta - self.theta0
""",
        "adds unwrapped changes": """import math


class AngleTracker:
    def __init__(self, theta0):
        self.last = theta0
        self.total = 0.0

    def update(self, theta):
        self.total += theta - self.last
        self.last = theta
        return self.total
""",
        "wraps the total into [-pi, pi)": """import math


class AngleTracker:
    def __init__(self, theta0):
        self.last = theta0
        self.total = 0.0

    def update(self, theta):
        change = (theta - self.last + math.pi) % (2 * math.pi) - math.pi
        self.total = (self.total + change + math.pi) % (2 * math.pi) - math.pi
        self.last = theta
        return self.total
""",
        "never updates the last heading": """import math


class AngleTracker:
    def __init__(self, theta0):
        self.last = theta0
        self.total = 0.0

    def update(self, theta):
        self.total = (theta - self.last + math.pi) % (2 * math.pi) - math.pi
        return self.total
""",
        "state kept in the class, shared by every tracker": """import math


class AngleTracker:
    last = None
    total = 0.0

    def __init__(self, theta0):
        if AngleTracker.last is None:
            AngleTracker.last = theta0

    def update(self, theta):
        change = (theta - AngleTracker.last + math.pi) % (2 * math.pi) - math.pi
        AngleTracker.total += change
        AngleTracker.last = theta
        return AngleTracker.total
""",
    },
    "sweep_speeds": {
        "no speed too slow for the wheels": """SWEEP_SPEEDS = (0.06, 0.1, 0.2, 0.3, 0.4)
""",
        "fewer than four speeds": """SWEEP_SPEEDS = (0.03, 0.2, 0.4)
""",
        "one speed repeated": """SWEEP_SPEEDS = (0.03, 0.2, 0.2, 0.4)
""",
        "every speed too slow to move the robot": """SWEEP_SPEEDS = (0.01, 0.02, 0.025, 0.03)
""",
        "nothing fast": """SWEEP_SPEEDS = (0.02, 0.05, 0.1, 0.12)
""",
        "faster than the robot can go": """SWEEP_SPEEDS = (0.03, 0.1, 0.5, 1.0)
""",
        "centimetres per second": """SWEEP_SPEEDS = (3, 5, 10, 20, 45)
""",
        "zero as the speed too slow": """SWEEP_SPEEDS = (0.0, 0.1, 0.2, 0.4)
""",
        "backwards as the speed too slow": """SWEEP_SPEEDS = (-0.2, 0.1, 0.2, 0.4)
""",
        "one number, not a tuple": """SWEEP_SPEEDS = 0.2
""",
    },
    "error_parts": {
        "late measured the other way": [
            ("late = said_at_stop - goal", "late = goal - said_at_stop"),
        ],
        "coast measured from the start": [
            ("coast = said_at_end - said_at_stop", "coast = said_at_end"),
        ],
        "truth minus odometry": [
            (
                "wrong = said_at_end - distance_along(start, truth)",
                "wrong = distance_along(start, truth) - said_at_end",
            ),
        ],
        "straight-line distances, not along the heading": [
            (
                "said_at_stop = distance_along(start, at_stop)",
                "said_at_stop = math.dist(start[:2], at_stop[:2])",
            ),
            (
                "said_at_end = distance_along(start, at_end)",
                "said_at_end = math.dist(start[:2], at_end[:2])",
            ),
            (
                "wrong = said_at_end - distance_along(start, truth)",
                "wrong = said_at_end - math.dist(start[:2], truth[:2])",
            ),
        ],
        "centimetres": [
            ("return late, coast, wrong", "return 100 * late, 100 * coast, 100 * wrong")
        ],
    },
}
