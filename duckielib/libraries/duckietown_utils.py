"""duckietown_utils: the helpers Duckietown nodes import most, on the laptop.

A Duckiebot's image ships Duckietown's ``duckietown_utils``, a large library of which nodes
use a few helpers: the robot's name, reading and writing YAML files, turning camera messages
and JPEG bytes into images, and Duckietown's exceptions. Those are here, with the same names
and arguments::

    import duckietown_utils as dtu

    veh = dtu.get_current_robot_name()           # "duckiebot" on the virtual Duckiebot
    image = dtu.rgb_from_ros(msg)                 # a CompressedImage or Image, as RGB pixels
    config = dtu.yaml_load_file("config.yaml")

Asking for any other name of the real library raises an ``AttributeError`` that says what is
here, rather than a bare "has no attribute".

Laptop side; never deployed (the robot has the real library).
"""

from __future__ import annotations

import logging
import os
import socket
import sys
from pathlib import Path
from typing import Any, Optional

import numpy as np

#: Modules of Duckietown's library that nodes import helpers from (``duckietown_utils.jpg``):
#: this module stands for each (their names are registered in ``pyproject.toml`` too).
DUCKIETOWN_UTILS_MODULES = (
    "jpg",
    "yaml_wrap",
    "image_conversions",
    "file_utils",
    "exceptions",
    "exception_utils",
)

__all__ = [
    "DTBadData",
    "DTConfigException",
    "DTException",
    "DTUserError",
    "ThisIsNotADuckiebot",
    "bgr_from_imgmsg",
    "bgr_from_jpg",
    "bgr_from_rgb",
    "d8_compressed_image_from_cv_image",
    "d8n_make_sure_dir_exists",
    "get_current_robot_name",
    "get_duckiefleet_root",
    "image_cv_from_jpg",
    "jpg_from_bgr",
    "logger",
    "rgb_from_bgr",
    "rgb_from_imgmsg",
    "rgb_from_jpg",
    "rgb_from_ros",
    "yaml_dump",
    "yaml_load",
    "yaml_load_file",
    "yaml_write_to_file",
]

#: The library's logger, as nodes use it (``dtu.logger.info(...)``).
logger = logging.getLogger("duckietown_utils")


class DTException(Exception):
    """The base of Duckietown's errors."""


class DTUserError(DTException):
    """Something the user must fix (a file, a setting)."""


class DTConfigException(DTUserError):
    """The configuration (environment variables or YAML files) is wrong or missing."""


class DTBadData(DTException):
    """Data that cannot be read (a file, an image)."""


class ThisIsNotADuckiebot(DTUserError):
    """Asked for the robot's name where there is none."""


# -- the robot -----------------------------------------------------------------------------------
def get_current_robot_name() -> str:
    """The robot's name: ``VEHICLE_NAME``, as on a Duckiebot, or else the machine's name."""
    name = os.environ.get("VEHICLE_NAME")
    return name if name else socket.gethostname()


def get_duckiefleet_root() -> str:
    """The folder of the fleet's configuration, from the ``DUCKIEFLEET_ROOT`` variable.

    Raises:
        DTConfigException: if the variable is not set or names no folder.
    """
    root = os.environ.get("DUCKIEFLEET_ROOT")
    if not root:
        raise DTConfigException(
            "DUCKIEFLEET_ROOT is not set: set it to the folder of your fleet's configuration "
            "(the one holding calibrations/)."
        )
    if not Path(root).is_dir():
        raise DTConfigException(f"DUCKIEFLEET_ROOT names {root}, which is not a folder.")
    return root


# -- files ---------------------------------------------------------------------------------------
def d8n_make_sure_dir_exists(filename: str) -> None:
    """Create the folder that will hold ``filename``, if it does not exist yet."""
    folder = Path(filename).parent
    folder.mkdir(parents=True, exist_ok=True)


def yaml_load(text: str) -> Any:
    """The data a YAML text holds.

    Raises:
        DTBadData: if the text is not valid YAML.
    """
    import yaml

    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as error:
        raise DTBadData(f"This is not valid YAML: {error}") from None


def yaml_dump(data: Any) -> str:
    """``data`` as YAML text, keys in the order given."""
    import yaml

    return yaml.safe_dump(data, default_flow_style=False, sort_keys=False)


def yaml_load_file(filename: str, plain_yaml: bool = False) -> Any:
    """The data of a YAML file.

    Args:
        filename: the file.
        plain_yaml: accepted for the real library's sake; files are always read as plain YAML.

    Raises:
        DTConfigException: if the file does not exist.
        DTBadData: if it is not valid YAML.
    """
    path = Path(filename)
    if not path.is_file():
        raise DTConfigException(f"There is no file {filename} to read.")
    try:
        return yaml_load(path.read_text(encoding="utf-8"))
    except DTBadData as error:
        raise DTBadData(f"{filename}: {error}") from None


def yaml_write_to_file(ob: Any, filename: str) -> None:
    """Write ``ob`` to a YAML file, creating its folder; a reader never sees half a file."""
    d8n_make_sure_dir_exists(filename)
    path = Path(filename)
    partial = path.with_name(path.name + ".partial")
    partial.write_text(yaml_dump(ob), encoding="utf-8")
    partial.replace(path)


# -- images --------------------------------------------------------------------------------------
def _bridge() -> Any:
    from duckielib.libraries.cv_bridge import CvBridge

    return CvBridge()


def bgr_from_jpg(data: bytes) -> np.ndarray:
    """The BGR pixels (height x width x 3, uint8) of JPEG (or PNG) bytes.

    Raises:
        DTBadData: if the bytes are not an image OpenCV can decode.
    """
    import cv2

    buffer = np.frombuffer(bytes(data), dtype=np.uint8)
    image = cv2.imdecode(buffer, cv2.IMREAD_COLOR) if buffer.size else None
    if image is None:
        raise DTBadData(f"Could not decode these {len(data)} bytes as an image.")
    return image


image_cv_from_jpg = bgr_from_jpg


def rgb_from_jpg(data: bytes) -> np.ndarray:
    """The RGB pixels of JPEG bytes."""
    return rgb_from_bgr(bgr_from_jpg(data))


def jpg_from_bgr(bgr: np.ndarray) -> bytes:
    """JPEG bytes of BGR pixels."""
    import cv2

    ok, encoded = cv2.imencode(".jpg", np.ascontiguousarray(bgr))
    if not ok:
        raise DTBadData("OpenCV could not encode this image as JPEG.")
    return encoded.tobytes()


def bgr_from_rgb(rgb: np.ndarray) -> np.ndarray:
    """The same pixels with red and blue swapped (RGB to BGR)."""
    return np.ascontiguousarray(rgb[..., ::-1])


rgb_from_bgr = bgr_from_rgb


def rgb_from_imgmsg(msg: Any) -> np.ndarray:
    """The RGB pixels of a ``sensor_msgs/Image``."""
    return _bridge().imgmsg_to_cv2(msg, "rgb8")


def bgr_from_imgmsg(msg: Any) -> np.ndarray:
    """The BGR pixels of a ``sensor_msgs/Image``."""
    return _bridge().imgmsg_to_cv2(msg, "bgr8")


def rgb_from_ros(msg: Any) -> np.ndarray:
    """The RGB pixels of a camera message: a ``CompressedImage`` or an ``Image``."""
    if hasattr(msg, "format"):
        return rgb_from_jpg(msg.data)
    return rgb_from_imgmsg(msg)


def d8_compressed_image_from_cv_image(
    image_cv: np.ndarray, same_timestamp_as: Optional[Any] = None
) -> Any:
    """A ``CompressedImage`` (JPEG) of BGR pixels, stamped like ``same_timestamp_as``."""
    from duckielib.messages import CompressedImage

    msg: Any = CompressedImage(format="jpeg", data=jpg_from_bgr(image_cv))
    if same_timestamp_as is not None:
        msg.header.stamp = same_timestamp_as.header.stamp
    return msg


def __getattr__(name: str) -> Any:
    if name.startswith("__"):
        raise AttributeError(name)
    if name in DUCKIETOWN_UTILS_MODULES:  # duckietown_utils.jpg is this module
        return sys.modules[__name__]
    raise AttributeError(
        f"duckietown_utils.{name} is not on the virtual Duckiebot: only the helpers nodes use "
        f"most are here ({', '.join(__all__)}). Copy what you need from it into your node."
    )
