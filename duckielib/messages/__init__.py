"""The ROS message and service types of a Duckiebot, defined once as ``.msg``/``.srv`` text.

The text files in ``definitions/<package>/{msg,srv}/`` are the single source of truth: the
classes here, the bag module and the real-ROS path are all made from them, and their md5 sums
are those of a real Duckiebot. They cover Duckietown's ``duckietown_msgs`` (daffy) and ROS's
``std_msgs``, ``geometry_msgs``, ``sensor_msgs``, ``nav_msgs``, ``std_srvs``, ``tf2_msgs``,
``rosgraph_msgs`` and ``actionlib_msgs`` (Noetic).

Import a type the way rospy code does, or, for the course's own types, by its short name::

    from duckielib.messages.geometry_msgs.msg import Twist
    from duckielib.messages.duckietown_msgs.srv import ChangePattern, ChangePatternRequest
    from duckielib.messages import WheelEncoderStamped

Short names at the top level are the course's types only (``Header``, ``Image``, ``Empty`` are
``std_msgs/Header``, ``sensor_msgs/Image`` and ``std_msgs/Empty``); every other type is reached
through its package, so a type of one package never hides a type of another.

A class is made the first time it is used, so importing this module stays quick.
"""

from __future__ import annotations

import sys
import threading
import types
from pathlib import Path
from typing import Any, Callable, Dict, List, Set, Type, Union, cast

from duckielib.errors import MessageDefinitionError

from .message import Message, Service, make_message_class, make_service_class
from .spec import MessageSpec, ServiceSpec, SpecRegistry, parse_message, parse_service

__all__ = [
    "Message",
    "Service",
    "add_package",
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

#: The type behind each short name of this module (std_srvs' SetBool is here as it always was,
#: though not exported with ``*``).
_TOP_LEVEL: Dict[str, str] = {
    **{name: f"std_msgs/{name}" for name in ("Header", "String", "Empty", "ColorRGBA")},
    **{name: f"std_msgs/{name}" for name in ("Float32", "Bool")},
    **{name: f"sensor_msgs/{name}" for name in ("CompressedImage", "Image")},
    **{
        name: f"duckietown_msgs/{name}"
        for name in (
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
        )
    },
    **{name: f"std_srvs/{name}" for name in ("SetBool", "SetBoolRequest", "SetBoolResponse")},
}

#: Every parsed definition, with md5 sums and full texts.
REGISTRY = SpecRegistry()
_MESSAGE_CLASSES: Dict[str, Type[Message]] = {}
_SERVICE_CLASSES: Dict[str, Type[Service]] = {}
#: The service each request and response message belongs to.
_PART_OF: Dict[str, str] = {}
#: The folder each package was read from.
_FOLDERS: Dict[str, Path] = {}
#: The types each ``<package>.msg``/``.srv`` module offers: module name -> short name -> type.
_MODULE_TYPES: Dict[str, Dict[str, str]] = {}
#: Making a class makes those of its fields first, and threads may ask for one at once.
_LOCK = threading.RLock()

_Spec = Union[MessageSpec, ServiceSpec]


def _read_package(package: str, folder: Path) -> List[_Spec]:
    """Parse the ``msg/*.msg`` and ``srv/*.srv`` files of one package folder."""
    specs: List[_Spec] = []
    for kind in ("msg", "srv"):
        for path in sorted((folder / kind).glob("*." + kind)):
            text = path.read_text(encoding="utf-8")
            full_name = f"{package}/{path.stem}"
            specs.append(
                parse_message(text, full_name) if kind == "msg" else parse_service(text, full_name)
            )
    return specs


def _register(specs: List[_Spec]) -> None:
    for spec in specs:
        if isinstance(spec, ServiceSpec):
            REGISTRY.add_service(spec)
            _PART_OF[spec.request.full_name] = spec.full_name
            _PART_OF[spec.response.full_name] = spec.full_name
        else:
            REGISTRY.add_message(spec)


def _read_definitions() -> None:
    for folder in sorted(_DEFINITIONS.iterdir()):
        if folder.is_dir():
            _register(_read_package(folder.name, folder))
            _FOLDERS[folder.name] = folder


def get_message_class(full_name: str) -> Type[Message]:
    """The class of a message type, such as ``"duckietown_msgs/WheelEncoderStamped"``.

    Raises:
        UnknownTypeError: if there is no such message type.
    """
    found = _MESSAGE_CLASSES.get(full_name)
    if found is not None:
        return found
    with _LOCK:
        if full_name not in _MESSAGE_CLASSES:
            spec = REGISTRY.message(full_name)
            _MESSAGE_CLASSES[full_name] = make_message_class(
                spec,
                REGISTRY.md5sum(full_name),
                REGISTRY.full_text(full_name),
                get_message_class,
                "srv" if full_name in _PART_OF else "msg",
            )
        return _MESSAGE_CLASSES[full_name]


def get_service_class(full_name: str) -> Type[Service]:
    """The class of a service type, such as ``"duckietown_msgs/ChangePattern"``.

    Raises:
        UnknownTypeError: if there is no such service type.
    """
    found = _SERVICE_CLASSES.get(full_name)
    if found is not None:
        return found
    with _LOCK:
        if full_name not in _SERVICE_CLASSES:
            spec = REGISTRY.service(full_name)
            _SERVICE_CLASSES[full_name] = make_service_class(
                full_name,
                REGISTRY.md5sum(full_name),
                get_message_class(spec.request.full_name),
                get_message_class(spec.response.full_name),
                spec.text,
            )
        return _SERVICE_CLASSES[full_name]


def _class_of(full_name: str) -> Union[Type[Message], Type[Service]]:
    if full_name in REGISTRY.services:
        return get_service_class(full_name)
    return get_message_class(full_name)


def message_types() -> List[str]:
    """The names of all message types (service requests and responses excluded), sorted."""
    return sorted(name for name in REGISTRY.messages if name not in _PART_OF)


def service_types() -> List[str]:
    """The names of all service types, sorted."""
    return sorted(REGISTRY.services)


def definition(full_name: str) -> str:
    """The ``.msg`` or ``.srv`` text of a type, as ``rosmsg show``/``rossrv show`` print it."""
    if full_name in REGISTRY.services:
        return REGISTRY.services[full_name].text
    return REGISTRY.message(full_name).text


def _module_getattr(module: types.ModuleType) -> Callable[[str], Any]:
    """A module's ``__getattr__`` that makes a type's class on first use, then keeps it."""

    def getattr_(name: str) -> Any:
        full_name = _MODULE_TYPES[module.__name__].get(name)
        if full_name is None:
            raise AttributeError(f"module {module.__name__!r} has no attribute {name!r}")
        found = _class_of(full_name)
        setattr(module, name, found)
        return found

    return getattr_


def _module_dir(module: types.ModuleType) -> Callable[[], List[str]]:
    def dir_() -> List[str]:
        return sorted(set(vars(module)) | set(_MODULE_TYPES[module.__name__]))

    return dir_


def _module(name: str, doc: str) -> types.ModuleType:
    """The module ``name``, made (and put in ``sys.modules``) if it does not exist yet."""
    module = sys.modules.get(name)
    if module is None:
        module = types.ModuleType(name, doc)
        module.__all__ = []  # type: ignore[attr-defined]  # for ``from std_msgs.msg import *``
        sys.modules[name] = module
    return module


def _install_modules(full_names: List[str]) -> None:
    """Make ``duckielib.messages.<package>.msg`` and ``.srv`` offer these types."""
    for full_name in full_names:
        package, short_name = full_name.split("/")
        kind = "srv" if full_name in REGISTRY.services or full_name in _PART_OF else "msg"
        parent = _module(f"{__name__}.{package}", f"The {package} types.")
        globals()[package] = parent
        module_name = f"{parent.__name__}.{kind}"
        module = _module(module_name, f"The {package} {kind} types.")
        if module_name not in _MODULE_TYPES:
            setattr(parent, kind, module)
            _MODULE_TYPES[module_name] = {}
            module.__getattr__ = _module_getattr(module)  # type: ignore[method-assign]
            module.__dir__ = _module_dir(module)  # type: ignore[method-assign]
        _MODULE_TYPES[module_name][short_name] = full_name
        module.__all__.append(short_name)


def add_package(package: str, folder: Union[str, Path]) -> types.ModuleType:
    """Add the types of a package of your own, from its ``msg/*.msg`` and ``srv/*.srv`` files.

    Its fields may use the types of the package itself and of every package already known.
    Afterwards ``duckielib.messages.<package>.msg`` (and ``.srv``) offer the new types. Adding
    the same folder again changes nothing.

    Args:
        package: the package's name, such as ``"my_msgs"``.
        folder: the package's folder, the one holding ``msg/`` and ``srv/``.

    Returns:
        The module ``duckielib.messages.<package>``.

    Raises:
        MessageDefinitionError: if the name is not a package name or is taken by other
            definitions, a line of a definition is invalid, or a field's type is not known.
    """
    folder = Path(folder).resolve()
    with _LOCK:
        if package in _FOLDERS and _FOLDERS[package] == folder:
            return cast(types.ModuleType, globals()[package])
        if package in _FOLDERS:
            # A copy of the same package (the project cloned again, run from another folder)
            # defines the same types: nothing to add.
            if _same_definitions(_read_package(package, folder)):
                return cast(types.ModuleType, globals()[package])
            raise MessageDefinitionError(
                f"The package {package} is defined already (in {_FOLDERS[package]}), with "
                "other definitions: give yours another name, or restart the kernel to use "
                "the new ones."
            )
        if not package.isidentifier() or package in globals():
            raise MessageDefinitionError(
                f"{package!r} cannot be a package name here; give yours another name."
            )
        specs = _read_package(package, folder)
        if not specs:
            raise MessageDefinitionError(f"There are no .msg or .srv files in {folder}.")
        parts = [part for spec in specs for part in _messages_of(spec)]
        known = set(REGISTRY.messages) | {part.full_name for part in parts}
        for part in parts:
            _check_known(part, known)
        _register(specs)
        _FOLDERS[package] = folder
        _install_modules(_names_of(specs))
        return cast(types.ModuleType, globals()[package])


def _same_definitions(specs: List[_Spec]) -> bool:
    """Whether every one of ``specs`` is registered already, with the same text."""
    parts = [part for spec in specs for part in _messages_of(spec)]
    return bool(parts) and all(
        part.full_name in REGISTRY.messages and REGISTRY.messages[part.full_name].text == part.text
        for part in parts
    )


def _messages_of(spec: _Spec) -> List[MessageSpec]:
    return [spec.request, spec.response] if isinstance(spec, ServiceSpec) else [spec]


def _check_known(spec: MessageSpec, known: Set[str]) -> None:
    for field in spec.fields:
        if not field.is_primitive and field.base_type not in known:
            raise MessageDefinitionError(
                f"The field {field.name!r} of {spec.full_name} has the type "
                f"{field.base_type!r}, which is not a known message type."
            )


def _names_of(specs: List[_Spec]) -> List[str]:
    names: List[str] = []
    for spec in specs:
        if isinstance(spec, ServiceSpec):
            names += [spec.request.full_name, spec.response.full_name]
        names.append(spec.full_name)
    return names


def __getattr__(name: str) -> Type[Message]:
    # The course's short names (see _TOP_LEVEL), each class made on first use. Typed as a
    # message class: its fields come from the definitions, which a type checker cannot read.
    full_name = _TOP_LEVEL.get(name)
    if full_name is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    found = _class_of(full_name)
    globals()[name] = found
    return cast(Type[Message], found)


def __dir__() -> List[str]:
    return sorted(set(globals()) | set(_TOP_LEVEL))


def _all_names() -> List[str]:
    return list(REGISTRY.messages) + list(REGISTRY.services)


_read_definitions()
_install_modules(_all_names())
