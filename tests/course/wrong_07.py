"""Deliberately wrong solutions of notebook 07_control, one dict entry per mistake.

Each value is the full source of a replacement for the graded cell named by the key; the test
cell ``test_<grade_id>`` must lose marks with it.
"""

_PID_HEAD = """import math


class PID:
    def __init__(self, kp, ki, kd, limit):
        self.kp, self.ki, self.kd, self.limit = kp, ki, kd, limit
        self.reset()
"""

_RESET = """
    def reset(self):
        self.integral = 0.0
        self.previous = None
"""

_UPDATE = """
    def update(self, error, dt):
        derivative = 0.0 if self.previous is None else (error - self.previous) / dt
        self.previous = error
        integral = self.integral + error * dt
        output = self.kp * error + self.ki * integral + self.kd * derivative
        if abs(output) > self.limit:
            output = math.copysign(self.limit, output)
            if output * error > 0:
                integral = self.integral
        self.integral = integral
        return output
"""

_GO_TO_POINT = """import math


def go_to_point(pose, target, v_max, k_omega):
    x, y, theta = pose
    dx, dy = target[0] - x, target[1] - y
    distance = math.hypot(dx, dy)
{alpha}
{v}
    return v, k_omega * alpha
"""
_WRAPPED = "    alpha = (math.atan2(dy, dx) - theta + math.pi) % (2 * math.pi) - math.pi"
_FORWARD_ONLY = "    v = min(v_max, 2.0 * distance) * max(0.0, math.cos(alpha))"

WRONG = {
    "PID": {
        "integral without dt": _PID_HEAD
        + _RESET
        + _UPDATE.replace("self.integral + error * dt", "self.integral + error"),
        "derivative kick: previous error taken as 0 at the first update": _PID_HEAD
        + _RESET.replace("self.previous = None", "self.previous = 0.0")
        + _UPDATE.replace("0.0 if self.previous is None else ", ""),
        "no output limit": _PID_HEAD
        + _RESET
        + """
    def update(self, error, dt):
        derivative = 0.0 if self.previous is None else (error - self.previous) / dt
        self.previous = error
        self.integral += error * dt
        return self.kp * error + self.ki * self.integral + self.kd * derivative
""",
        "output limit without anti-windup": _PID_HEAD
        + _RESET
        + """
    def update(self, error, dt):
        derivative = 0.0 if self.previous is None else (error - self.previous) / dt
        self.previous = error
        self.integral += error * dt
        output = self.kp * error + self.ki * self.integral + self.kd * derivative
        return max(-self.limit, min(self.limit, output))
""",
        "reset does not clear anything": """import math


class PID:
    def __init__(self, kp, ki, kd, limit):
        self.kp, self.ki, self.kd, self.limit = kp, ki, kd, limit
        self.integral = 0.0
        self.previous = None

    def reset(self):
        pass
"""
        + _UPDATE,
        "reset clears the integral but not the previous error": _PID_HEAD
        + """
    def reset(self):
        self.integral = 0.0
        if not hasattr(self, "previous"):
            self.previous = None
"""
        + _UPDATE,
        "derivative not divided by dt": _PID_HEAD
        + _RESET
        + _UPDATE.replace("(error - self.previous) / dt", "(error - self.previous)"),
        "state shared by every controller (class attributes)": """import math


class PID:
    integral = 0.0
    previous = None

    def __init__(self, kp, ki, kd, limit):
        self.kp, self.ki, self.kd, self.limit = kp, ki, kd, limit

    def reset(self):
        PID.integral = 0.0
        PID.previous = None

    def update(self, error, dt):
        derivative = 0.0 if PID.previous is None else (error - PID.previous) / dt
        PID.previous = error
        integral = PID.integral + error * dt
        output = self.kp * error + self.ki * integral + self.kd * derivative
        if abs(output) > self.limit:
            output = math.copysign(self.limit, output)
            if output * error > 0:
                integral = PID.integral
        PID.integral = integral
        return output
""",
    },
    "go_to_point": {
        "raw bearing error, not wrapped": _GO_TO_POINT.format(
            alpha="    alpha = math.atan2(dy, dx) - theta", v=_FORWARD_ONLY
        ),
        "drives backwards to targets behind": _GO_TO_POINT.format(
            alpha=_WRAPPED, v="    v = min(v_max, 2.0 * distance) * math.cos(alpha)"
        ),
        "ignores v_max": _GO_TO_POINT.format(
            alpha=_WRAPPED, v="    v = 2.0 * distance * max(0.0, math.cos(alpha))"
        ),
        "never slows down near the target": _GO_TO_POINT.format(
            alpha=_WRAPPED, v="    v = v_max * max(0.0, math.cos(alpha))"
        ),
        "bearing error with the sign reversed": _GO_TO_POINT.format(
            alpha="    alpha = (theta - math.atan2(dy, dx) + math.pi) % (2 * math.pi) - math.pi",
            v=_FORWARD_ONLY,
        ),
        "bearing error wrapped into [0, 2 pi)": _GO_TO_POINT.format(
            alpha="    alpha = (math.atan2(dy, dx) - theta) % (2 * math.pi)", v=_FORWARD_ONLY
        ),
    },
}
