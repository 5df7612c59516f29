"""The ROS message and service types of the course, defined once as ``.msg``/``.srv`` text.

The text files in ``definitions/<package>/{msg,srv}/`` are the single source of truth: the
classes here, the bag module and the real-ROS path are all made from them, and their md5 sums
are those of a real Duckiebot (Duckietown's ``duckietown_msgs``, ROS's ``std_msgs`` and
``sensor_msgs``).

Use the classes by name, or import them the way rospy code does::

    from duckielib.messages import WheelEncoderStamped
    from duckielib.messages.duckietown_msgs.msg import WheelEncoderStamped
    from duckielib.messages.duckietown_msgs.srv import ChangePattern, ChangePatternRequest
"""

from __future__ import annotations

import sys
import types
from pathlib import Path
from typing import TYPE_CHECKING, Dict, List, Type

from duckielib.errors import UnknownTypeError

from .message import Message, Service, make_message_class, make_service_class
from .spec import SpecRegistry, parse_message, parse_service

__all__ = [
    "Message",
    "Service",
    "get_message_class",
    "get_service_class",
    "message_types",
    "service_types",
    "definition",
    "REGISTRY",
    # std_msgs
    "Header",
    "String",
    "Empty",
    "ColorRGBA",
    "Float32",
    "Bool",
    # sensor_msgs
    "CompressedImage",
    "Image",
    # duckietown_msgs
    "WheelEncoderStamped",
    "WheelsCmdStamped",
    "Twist2DStamped",
    "Pose2DStamped",
    "LEDPattern",
    "BoolStamped",
    "ChangePattern",
    "ChangePatternRequest",
    "ChangePatternResponse",
    "SetCustomLEDPattern",
    "SetCustomLEDPatternRequest",
    "SetCustomLEDPatternResponse",
]

_DEFINITIONS = Path(__file__).resolve().parent / "definitions"

#: Every parsed definition, with md5 sums and full texts.
REGISTRY = SpecRegistry()
_MESSAGE_CLASSES: Dict[str, Type[Message]] = {}
_SERVICE_CLASSES: Dict[str, Type[Service]] = {}


def _read_definitions() -> None:
    for package in sorted(_DEFINITIONS.iterdir()):
        for kind in ("msg", "srv"):
            for path in sorted((package / kind).glob("*." + kind)):
                text = path.read_text(encoding="utf-8")
                full_name = f"{package.name}/{path.stem}"
                if kind == "msg":
                    REGISTRY.add_message(parse_message(text, full_name))
                else:
                    REGISTRY.add_service(parse_service(text, full_name))


def get_message_class(full_name: str) -> Type[Message]:
    """The class of a message type, such as ``"duckietown_msgs/WheelEncoderStamped"``.

    Raises:
        UnknownTypeError: if the course has no such message type.
    """
    if full_name not in _MESSAGE_CLASSES:
        spec = REGISTRY.message(full_name)
        _MESSAGE_CLASSES[full_name] = make_message_class(
            spec,
            REGISTRY.md5sum(full_name),
            REGISTRY.full_text(full_name),
            get_message_class,
            "srv" if _is_service_part(full_name) else "msg",
        )
    return _MESSAGE_CLASSES[full_name]


def get_service_class(full_name: str) -> Type[Service]:
    """The class of a service type, such as ``"duckietown_msgs/ChangePattern"``.

    Raises:
        UnknownTypeError: if the course has no such service type.
    """
    if full_name not in _SERVICE_CLASSES:
        if full_name not in REGISTRY.services:
            raise UnknownTypeError(
                f"There is no service type {full_name!r}; known types are: "
                f"{', '.join(service_types())}."
            )
        spec = REGISTRY.services[full_name]
        _SERVICE_CLASSES[full_name] = make_service_class(
            full_name,
            REGISTRY.md5sum(full_name),
            get_message_class(spec.request.full_name),
            get_message_class(spec.response.full_name),
            spec.text,
        )
    return _SERVICE_CLASSES[full_name]


def message_types() -> List[str]:
    """The names of all message types (service requests and responses excluded), sorted."""
    return sorted(name for name in REGISTRY.messages if not _is_service_part(name))


def service_types() -> List[str]:
    """The names of all service types, sorted."""
    return sorted(REGISTRY.services)


def definition(full_name: str) -> str:
    """The ``.msg`` or ``.srv`` text of a type, as ``rosmsg show``/``rossrv show`` print it."""
    if full_name in REGISTRY.services:
        return REGISTRY.services[full_name].text
    return REGISTRY.message(full_name).text


def _install_modules() -> None:
    """Make ``duckielib.messages.<package>.msg`` and ``.srv`` importable, as in rospy code."""
    packages: Dict[str, types.ModuleType] = {}
    for full_name in list(REGISTRY.messages) + list(REGISTRY.services):
        package, short_name = full_name.split("/")
        kind = "srv" if full_name in REGISTRY.services or _is_service_part(full_name) else "msg"
        if package not in packages:
            packages[package] = _new_module(f"{__name__}.{package}", f"The {package} types.")
            globals()[package] = packages[package]
        parent = packages[package]
        if not hasattr(parent, kind):
            setattr(parent, kind, _new_module(f"{parent.__name__}.{kind}", f"{package} {kind}."))
        cls = (
            get_service_class(full_name)
            if full_name in REGISTRY.services
            else get_message_class(full_name)
        )
        setattr(getattr(parent, kind), short_name, cls)
        getattr(parent, kind).__all__.append(short_name)  # for ``from std_msgs.msg import *``
        globals()[short_name] = cls


def _is_service_part(full_name: str) -> bool:
    return any(
        full_name in (spec.request.full_name, spec.response.full_name)
        for spec in REGISTRY.services.values()
    )


def _new_module(name: str, doc: str) -> types.ModuleType:
    module = types.ModuleType(name, doc)
    module.__all__ = []  # type: ignore[attr-defined]
    sys.modules[name] = module
    return module


_read_definitions()
_install_modules()

if TYPE_CHECKING:
    # The classes are made at import time from the definitions (the single source of their
    # fields), so a type checker sees each one as a message class.
    def __getattr__(name: str) -> Type[Message]: ...
