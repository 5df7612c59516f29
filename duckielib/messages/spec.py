"""Parse ROS 1 ``.msg`` and ``.srv`` text, and compute md5 sums and full definitions.

This follows ROS 1's own rules (genmsg), so that a type defined here has the md5 sum a real
robot checks before it talks to us, and the definition text that bags embed:

- comments (``#`` to the end of the line) and blank lines are ignored;
- ``Header`` means ``std_msgs/Header``; a bare type name means a type of the same package;
- the md5 text lists constants first (``type NAME=value``), then fields, each complex field's
  type replaced by that type's md5 sum (array brackets dropped); the md5 of a service hashes
  the request text followed by the response text;
- the full text is the type's own text, then each dependency (depth first, no repeats) after a
  line of 80 ``=`` and a line ``MSG: package/Type``.
"""

from __future__ import annotations

import difflib
import hashlib
import re
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Tuple, Union

from duckielib.errors import MessageDefinitionError, UnknownTypeError

__all__ = [
    "PRIMITIVE_TYPES",
    "Constant",
    "Field",
    "MessageSpec",
    "ServiceSpec",
    "SpecRegistry",
    "parse_message",
    "parse_service",
]

#: Types that are not messages, with the deprecated aliases ``byte`` (int8) and ``char`` (uint8).
PRIMITIVE_TYPES = frozenset(
    [
        "bool",
        "int8",
        "uint8",
        "int16",
        "uint16",
        "int32",
        "uint32",
        "int64",
        "uint64",
        "float32",
        "float64",
        "string",
        "time",
        "duration",
        "byte",
        "char",
    ]
)
_CONSTANT_TYPES = PRIMITIVE_TYPES - {"time", "duration"}
_HEADER = "std_msgs/Header"
_TYPE_PATTERN = re.compile(r"^([A-Za-z][A-Za-z0-9_]*/)?[A-Za-z][A-Za-z0-9_]*(\[[0-9]*\])?$")
_NAME_PATTERN = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")
_SERVICE_SEPARATOR = "---"


@dataclass(frozen=True)
class Constant:
    """A constant of a message, such as ``uint8 ENCODER_TYPE_INCREMENTAL=1``."""

    type: str
    name: str
    value: Union[bool, int, float, str]
    value_text: str


@dataclass(frozen=True)
class Field:
    """A field of a message.

    Attributes:
        name: the attribute name, for example ``"resolution"``.
        type: the type as ROS writes it, packages resolved: ``"uint16"``, ``"int8[]"``,
            ``"std_msgs/ColorRGBA[]"``, ``"float64[9]"``.
        base_type: the element type without brackets: ``"std_msgs/ColorRGBA"``.
        is_array: whether the field holds a sequence.
        array_length: the length of a fixed-size array, None for a variable one or a scalar.
    """

    name: str
    type: str
    base_type: str
    is_array: bool
    array_length: Optional[int]

    @property
    def is_primitive(self) -> bool:
        """True when the element type is a primitive, not a message."""
        return self.base_type in PRIMITIVE_TYPES


@dataclass(frozen=True)
class MessageSpec:
    """What a ``.msg`` text defines: its fields and constants, and the text itself."""

    full_name: str
    text: str
    fields: Tuple[Field, ...]
    constants: Tuple[Constant, ...]

    @property
    def package(self) -> str:
        """The package part of the name: ``duckietown_msgs``."""
        return self.full_name.split("/")[0]

    @property
    def short_name(self) -> str:
        """The type part of the name: ``WheelEncoderStamped``."""
        return self.full_name.split("/")[1]

    @property
    def dependencies(self) -> List[str]:
        """The message types of its fields, in field order, without repeats."""
        found: List[str] = []
        for item in self.fields:
            if not item.is_primitive and item.base_type not in found:
                found.append(item.base_type)
        return found

    @property
    def has_header(self) -> bool:
        """True when the first field is a ``std_msgs/Header`` named ``header``."""
        return bool(self.fields) and (self.fields[0].type, self.fields[0].name) == (
            _HEADER,
            "header",
        )


@dataclass(frozen=True)
class ServiceSpec:
    """What a ``.srv`` text defines: a request and a response message."""

    full_name: str
    text: str
    request: MessageSpec
    response: MessageSpec


def _fail(full_name: str, line_number: int, line: str, reason: str) -> MessageDefinitionError:
    return MessageDefinitionError(
        f"Line {line_number} of the definition of {full_name} ({line.strip()!r}) {reason}."
    )


def _resolve_type(type_text: str, package: str) -> Tuple[str, str, bool, Optional[int]]:
    """Split a field type into (resolved type, base type, is_array, fixed length)."""
    base, bracket, rest = type_text.partition("[")
    is_array = bool(bracket)
    length = int(rest[:-1]) if is_array and rest[:-1] else None
    if base == "Header":
        base = _HEADER
    elif base not in PRIMITIVE_TYPES and "/" not in base:
        base = f"{package}/{base}"
    suffix = f"[{length}]" if length is not None else ("[]" if is_array else "")
    return base + suffix, base, is_array, length


def _parse_constant_value(type_name: str, text: str) -> Union[bool, int, float, str]:
    if type_name == "string":
        return text
    if type_name == "bool":
        return text.strip() not in ("0", "false", "False")
    if type_name.startswith("float"):
        return float(text)
    return int(text, 0)


def parse_message(text: str, full_name: str) -> MessageSpec:
    """Parse the text of a ``.msg`` file.

    Args:
        text: the file's content.
        full_name: the type's name, ``"package/Type"``.

    Returns:
        The parsed specification.

    Raises:
        MessageDefinitionError: if a line is not a valid field or constant declaration.
    """
    package = full_name.split("/", maxsplit=1)[0]
    fields: List[Field] = []
    constants: List[Constant] = []
    names = set()
    for number, line in enumerate(text.split("\n"), start=1):
        clean = line.split("#", 1)[0].strip()
        if not clean:
            continue
        if "=" in clean:
            type_name, _, rest = line.strip().partition(" ")
            if type_name not in _CONSTANT_TYPES:
                raise _fail(full_name, number, line, f"declares a constant of type {type_name!r}")
            name, _, value_text = rest.partition("=")
            if type_name != "string":
                value_text = value_text.split("#", 1)[0]
            name, value_text = name.strip(), value_text.strip()
            try:
                value = _parse_constant_value(type_name, value_text)
            except ValueError:
                raise _fail(
                    full_name, number, line, "has a value that does not fit its type"
                ) from None
            constants.append(Constant(type_name, name, value, value_text))
            continue
        parts = clean.split()
        if len(parts) != 2:
            raise _fail(full_name, number, line, "should read 'type name'")
        type_text, name = parts
        if not _TYPE_PATTERN.match(type_text):
            raise _fail(full_name, number, line, f"has an invalid type {type_text!r}")
        if not _NAME_PATTERN.match(name):
            raise _fail(full_name, number, line, f"has an invalid field name {name!r}")
        if name in names:
            raise _fail(full_name, number, line, f"repeats the field name {name!r}")
        names.add(name)
        resolved, base, is_array, length = _resolve_type(type_text, package)
        fields.append(Field(name, resolved, base, is_array, length))
    return MessageSpec(full_name, text, tuple(fields), tuple(constants))


def parse_service(text: str, full_name: str) -> ServiceSpec:
    """Parse the text of a ``.srv`` file: request fields, a ``---`` line, response fields.

    The request and response are named ``package/TypeRequest`` and ``package/TypeResponse``.
    """
    request_lines: List[str] = []
    response_lines: List[str] = []
    target = request_lines
    for line in text.split("\n"):
        if line.startswith(_SERVICE_SEPARATOR):
            target = response_lines
        else:
            target.append(line)
    if target is request_lines:
        raise MessageDefinitionError(
            f"The definition of {full_name} has no '---' line between request and response."
        )
    request = parse_message("\n".join(request_lines) + "\n", f"{full_name}Request")
    response = parse_message("\n".join(response_lines) + "\n", f"{full_name}Response")
    return ServiceSpec(full_name, text, request, response)


def _unknown(kind: str, full_name: str, known: Dict[str, Any]) -> UnknownTypeError:
    """The error for a type name not in ``known``, naming the types it may have meant."""
    package, _, short_name = full_name.rpartition("/")
    same_package = {
        name.rpartition("/")[2]: name for name in known if name.startswith(package + "/")
    }
    alike = [name for name in known if name.rpartition("/")[2] == short_name]
    alike += [same_package[name] for name in difflib.get_close_matches(short_name, same_package)]
    if alike:
        hint = "did you mean " + " or ".join(repr(name) for name in dict.fromkeys(alike)) + "?"
    elif same_package:
        hint = f"the {package} types are: {', '.join(sorted(same_package))}."
    else:
        packages = sorted({name.partition("/")[0] for name in known})
        hint = f"the packages are: {', '.join(packages)}."
    return UnknownTypeError(f"There is no {kind} type {full_name!r}; {hint}")


@dataclass
class SpecRegistry:
    """Parsed message and service definitions, with md5 sums and full texts computed on demand."""

    messages: Dict[str, MessageSpec] = field(default_factory=dict)
    services: Dict[str, ServiceSpec] = field(default_factory=dict)
    _md5: Dict[str, str] = field(default_factory=dict, repr=False)

    def add_message(self, spec: MessageSpec) -> None:
        """Register a message definition."""
        self.messages[spec.full_name] = spec

    def add_service(self, spec: ServiceSpec) -> None:
        """Register a service definition, and its request and response messages."""
        self.services[spec.full_name] = spec
        self.add_message(spec.request)
        self.add_message(spec.response)

    def message(self, full_name: str) -> MessageSpec:
        """The definition of a message type.

        Raises:
            UnknownTypeError: if the type is not registered.
        """
        try:
            return self.messages[full_name]
        except KeyError:
            raise _unknown("message", full_name, self.messages) from None

    def service(self, full_name: str) -> ServiceSpec:
        """The definition of a service type.

        Raises:
            UnknownTypeError: if the type is not registered.
        """
        try:
            return self.services[full_name]
        except KeyError:
            raise _unknown("service", full_name, self.services) from None

    def md5_text(self, full_name: str) -> str:
        """The text whose md5 is the message's md5 sum (see the module docstring)."""
        spec = self.message(full_name)
        lines = [f"{c.type} {c.name}={c.value_text}" for c in spec.constants]
        for item in spec.fields:
            if item.is_primitive:
                lines.append(f"{item.type} {item.name}")
            else:
                lines.append(f"{self.md5sum(item.base_type)} {item.name}")
        return "\n".join(lines)

    def md5sum(self, full_name: str) -> str:
        """The ROS 1 md5 sum of a message or service type, as 32 hex digits."""
        if full_name not in self._md5:
            if full_name in self.services:
                service = self.services[full_name]
                text = self.md5_text(service.request.full_name) + self.md5_text(
                    service.response.full_name
                )
            else:
                text = self.md5_text(full_name)
            self._md5[full_name] = hashlib.md5(text.encode()).hexdigest()
        return self._md5[full_name]

    def all_dependencies(self, full_name: str) -> List[str]:
        """Every message type a message contains, depth first, without repeats."""
        found: List[str] = []
        for dependency in self.message(full_name).dependencies:
            for name in [dependency, *self.all_dependencies(dependency)]:
                if name not in found:
                    found.append(name)
        return found

    def full_text(self, full_name: str) -> str:
        """The definition with those of all its dependencies, as rospy and bags carry it."""
        parts = [self.message(full_name).text]
        for dependency in self.all_dependencies(full_name):
            parts.append("=" * 80 + "\nMSG: " + dependency + "\n" + self.message(dependency).text)
        return "\n".join(parts)
