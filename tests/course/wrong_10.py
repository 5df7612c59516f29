"""Deliberately wrong solutions of notebook 10_bag_analysis, one dict entry per mistake.

Each value is the full source of a replacement for the graded cell named by the key; the test
cell ``test_<grade_id>`` must lose marks with it.
"""

WRONG = {
    "unwrap_heading": {
        "unwrap without handling negative jumps": """import numpy as np


def unwrap_heading(theta):
    theta = np.asarray(theta, dtype=float)
    steps = np.diff(theta)
    steps = np.where(steps > np.pi, steps - 2 * np.pi, steps)
    return theta[0] + np.concatenate(([0.0], np.cumsum(steps)))
""",
        "unwrap without handling positive jumps": """import numpy as np


def unwrap_heading(theta):
    theta = np.asarray(theta, dtype=float)
    steps = np.diff(theta)
    steps = np.where(steps < -np.pi, steps + 2 * np.pi, steps)
    return theta[0] + np.concatenate(([0.0], np.cumsum(steps)))
""",
        "returns the raw theta": """import numpy as np


def unwrap_heading(theta):
    return np.asarray(theta, dtype=float)
""",
        "starts at 0 instead of theta[0]": """import numpy as np


def unwrap_heading(theta):
    theta = np.asarray(theta, dtype=float)
    turns = (np.diff(theta) + np.pi) % (2 * np.pi) - np.pi
    return np.concatenate(([0.0], np.cumsum(turns)))
""",
        "wraps each step but forgets to add them up": """import numpy as np


def unwrap_heading(theta):
    theta = np.asarray(theta, dtype=float)
    turns = (np.diff(theta) + np.pi) % (2 * np.pi) - np.pi
    return theta[0] + np.concatenate(([0.0], turns))
""",
        "one wrap fixed, the following samples not shifted": """import numpy as np


def unwrap_heading(theta):
    theta = np.asarray(theta, dtype=float).copy()
    for index in range(1, len(theta)):
        step = theta[index] - theta[index - 1]
        if step > np.pi:
            theta[index] -= 2 * np.pi
        elif step < -np.pi:
            theta[index] += 2 * np.pi
    return theta
""",
    },
    "pose_error": {
        "heading not wrapped": """import math


def pose_error(estimate, truth):
    x, y, theta = estimate
    x_true, y_true, theta_true = truth
    return math.hypot(x - x_true, y - y_true), theta - theta_true
""",
        "distance using only x": """import math


def pose_error(estimate, truth):
    x, y, theta = estimate
    x_true, y_true, theta_true = truth
    heading = (theta - theta_true + math.pi) % (2 * math.pi) - math.pi
    return abs(x - x_true), heading
""",
        "heading difference the wrong way round (truth - estimate)": """import math


def pose_error(estimate, truth):
    x, y, theta = estimate
    x_true, y_true, theta_true = truth
    heading = (theta_true - theta + math.pi) % (2 * math.pi) - math.pi
    return math.hypot(x - x_true, y - y_true), heading
""",
        "absolute heading difference": """import math


def pose_error(estimate, truth):
    x, y, theta = estimate
    x_true, y_true, theta_true = truth
    heading = abs((theta - theta_true + math.pi) % (2 * math.pi) - math.pi)
    return math.hypot(x - x_true, y - y_true), heading
""",
        "heading wrapped into [0, 2 pi) instead of [-pi, pi)": """import math


def pose_error(estimate, truth):
    x, y, theta = estimate
    x_true, y_true, theta_true = truth
    return math.hypot(x - x_true, y - y_true), (theta - theta_true) % (2 * math.pi)
""",
        "squared distance": """import math


def pose_error(estimate, truth):
    x, y, theta = estimate
    x_true, y_true, theta_true = truth
    heading = (theta - theta_true + math.pi) % (2 * math.pi) - math.pi
    return (x - x_true) ** 2 + (y - y_true) ** 2, heading
""",
    },
    "state_spans": {
        "including 'done' as a state": """def state_spans(times, names, end):
    spans = []
    for index, (start, name) in enumerate(zip(times, names)):
        stop = times[index + 1] if index + 1 < len(times) else end
        spans.append((name, float(start), float(stop)))
    return spans
""",
        "each span ending at its own start": """def state_spans(times, names, end):
    spans = []
    for start, name in zip(times, names):
        if name == "done":
            break
        spans.append((name, float(start), float(start)))
    return spans
""",
        "the last state always ends at the end of the recording": """def state_spans(times, names, end):
    spans = []
    for index, (start, name) in enumerate(zip(times, names)):
        if name == "done":
            break
        later = [t for t, n in zip(times[index + 1 :], names[index + 1 :]) if n != "done"]
        stop = later[0] if later else end
        spans.append((name, float(start), float(stop)))
    return spans
""",
        "the last state dropped": """def state_spans(times, names, end):
    spans = []
    for index in range(len(times) - 1):
        if names[index] == "done":
            break
        spans.append((names[index], float(times[index]), float(times[index + 1])))
    return spans
""",
        "one span per state name, repeats merged": """def state_spans(times, names, end):
    spans = []
    seen = set()
    for index, (start, name) in enumerate(zip(times, names)):
        if name == "done":
            break
        stop = times[index + 1] if index + 1 < len(times) else end
        if name in seen:
            continue
        seen.add(name)
        spans.append((name, float(start), float(stop)))
    return spans
""",
    },
    "plot_theta": {
        "ignores the bag it is given": [
            ("bag = Bag(bag_file)", "bag = Bag(sample_bag('square_then_circle_realistic'))"),
        ],
        "plots x instead of theta": [("track.t - t0, track.theta,", "track.t - t0, track.x,")],
        "times not counted from the bag's start": [
            ("ax.plot(track.t - t0, track.theta,", "ax.plot(track.t + 1.0, track.theta,")
        ],
        "no axis labels": [
            ('    ax.set_xlabel("t (s)")\n', ""),
            ('    ax.set_ylabel("θ (rad)")\n', ""),
        ],
    },
}
