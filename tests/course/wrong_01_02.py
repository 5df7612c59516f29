"""Deliberately wrong solutions for notebooks 01 and 02, by graded cell.

Each entry replaces a graded cell's source in the released notebook; the test cell named
``test_<grade_id>`` must then score less than its points.
"""

WRONG = {
    "wheel_circumference": {
        "forgot the 2 (pi R)": """import math


def wheel_circumference(R):
    return math.pi * R
""",
        "area-like 2 pi R squared": """import math


def wheel_circumference(R):
    return 2.0 * math.pi * R * R
""",
        "pi rounded to 3.14": """def wheel_circumference(R):
    return 2.0 * 3.14 * R
""",
        "diameter instead of circumference": """def wheel_circumference(R):
    return 2.0 * R
""",
    },
    "robot_topic": {
        "hard-coded duckiebot": """import os


def robot_topic(relative_name):
    return "/duckiebot/" + relative_name
""",
        "missing leading slash": """import os


def robot_topic(relative_name):
    return os.environ["VEHICLE_NAME"] + "/" + relative_name
""",
        "name read once when the cell runs": """import os

VEHICLE = os.environ.get("VEHICLE_NAME", "duckiebot")


def robot_topic(relative_name):
    return f"/{VEHICLE}/{relative_name}"
""",
        "falls back to duckiebot when VEHICLE_NAME is unset": """import os


def robot_topic(relative_name):
    return f"/{os.environ.get('VEHICLE_NAME', 'duckiebot')}/{relative_name}"
""",
        "missing slash between name and topic": """import os


def robot_topic(relative_name):
    return f"/{os.environ['VEHICLE_NAME']}{relative_name}"
""",
    },
    "move_topic": {
        "relative name, without the robot's namespace": """def move_topic():
    return "car_cmd_switch_node/cmd"
""",
        "robot name hard-coded": """def move_topic():
    return "/duckiebot/car_cmd_switch_node/cmd"
""",
        "the report of what the wheels did": """def move_topic():
    return robot_topic("wheels_driver_node/wheels_cmd_executed")
""",
        "the kinematics node's velocity report": """def move_topic():
    return robot_topic("kinematics_node/velocity")
""",
        "the emergency stop": """def move_topic():
    return robot_topic("wheels_driver_node/emergency_stop")
""",
        "cmd_vel, a name from other robots": """def move_topic():
    return robot_topic("cmd_vel")
""",
        "the node's name instead of its topic": """def move_topic():
    return robot_topic("car_cmd_switch_node")
""",
        "name built once when the cell runs": """import os

NAME = f"/{os.environ.get('VEHICLE_NAME', 'duckiebot')}/joy_mapper_node/car_cmd"


def move_topic():
    return NAME
""",
    },
    "bgr_from_jpeg": {
        "RGB order (channels not reversed)": """import io

import numpy as np
from PIL import Image


def bgr_from_jpeg(data):
    return np.asarray(Image.open(io.BytesIO(data)).convert("RGB"), dtype=np.uint8)
""",
        "float array instead of uint8": """import io

import numpy as np
from PIL import Image


def bgr_from_jpeg(data):
    rgb = np.asarray(Image.open(io.BytesIO(data)).convert("RGB"), dtype=np.float64)
    return rgb[:, :, ::-1]
""",
        "rows and columns swapped": """import io

import numpy as np
from PIL import Image


def bgr_from_jpeg(data):
    rgb = np.asarray(Image.open(io.BytesIO(data)).convert("RGB"), dtype=np.uint8)
    return np.ascontiguousarray(rgb[:, :, ::-1].transpose(1, 0, 2))
""",
        "green and blue swapped instead of red and blue": """import io

import numpy as np
from PIL import Image


def bgr_from_jpeg(data):
    rgb = np.asarray(Image.open(io.BytesIO(data)).convert("RGB"), dtype=np.uint8)
    return np.ascontiguousarray(rgb[:, :, [0, 2, 1]])
""",
    },
    "grey_bgr": {
        "plain mean of the channels": """import numpy as np


def grey_bgr(image):
    mean = np.rint(image.astype(np.float64).mean(axis=2)).astype(np.uint8)
    return np.repeat(mean[:, :, np.newaxis], 3, axis=2)
""",
        "weights applied in BGR order as if RGB": """import numpy as np


def grey_bgr(image):
    first, second, third = (image[:, :, c].astype(np.float64) for c in range(3))
    luma = np.rint(0.299 * first + 0.587 * second + 0.114 * third).astype(np.uint8)
    return np.repeat(luma[:, :, np.newaxis], 3, axis=2)
""",
        "single channel returned": """import numpy as np


def grey_bgr(image):
    blue, green, red = (image[:, :, c].astype(np.float64) for c in range(3))
    return np.rint(0.299 * red + 0.587 * green + 0.114 * blue).astype(np.uint8)
""",
        "changes the input in place": """import numpy as np


def grey_bgr(image):
    blue, green, red = (image[:, :, c].astype(np.float64) for c in range(3))
    luma = np.rint(0.299 * red + 0.587 * green + 0.114 * blue).astype(np.uint8)
    image[:, :, 0] = luma
    image[:, :, 1] = luma
    image[:, :, 2] = luma
    return image
""",
    },
}
