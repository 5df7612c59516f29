"""Message classes that behave like the ones genpy generates for rospy.

A class is made, on first use, from a parsed ``.msg`` definition (see :mod:`.spec`). Its
instances have the definition's fields as attributes, are built from keywords or from every
field in order, start from ROS's defaults (0, 0.0, ``""``, ``False``, ``[]``, ``b""`` for byte
arrays, an empty nested message, ``Time(0)``), and carry ``_type``, ``_md5sum``,
``_full_text``, ``_has_header``, ``__slots__`` and ``_slot_types`` as genpy's do.

Two things go beyond genpy, to help students: every assignment is checked at once (a string in
a float field, or 70000 in a uint16 field, fails on the line that did it, with a sentence that
says what the field accepts), and ``print(msg)`` shows the message as ``rostopic echo`` would.

:meth:`Message.serialize` and :meth:`Message.deserialize` use ROS 1's wire format
(little-endian, ``uint32`` lengths), byte for byte what rospy sends and bags store.
"""

from __future__ import annotations

import math
import struct
from numbers import Integral, Real
from typing import Any, Callable, ClassVar, Dict, List, Tuple, Type, TypeVar, Union, cast

from duckielib.errors import MessageError
from duckielib.rostime import Duration, Time

from .codegen import (
    FLOAT32_MAX,
    FLOAT_LETTERS,
    INTEGER_LETTERS,
    integer_range,
    make_init,
    make_reader,
    make_setattr,
    make_writer,
)
from .spec import Field, MessageSpec

__all__ = ["Message", "Service", "make_message_class", "make_service_class"]

_BYTE_TYPES = ("uint8", "char")
_UINT32 = struct.Struct("<I")
_TIME = struct.Struct("<II")
_DURATION = struct.Struct("<ii")
_SHORT_ARRAY = 16
#: What packing a field with a value of the wrong type or size raises.
_WRITE_ERRORS = (struct.error, TypeError, ValueError, OverflowError, AttributeError)
_set = object.__setattr__
#: What messages are read from: bytes, or a view of a larger buffer.
_Data = Union[bytes, memoryview]
_M = TypeVar("_M", bound="Message")


class _Codec:
    """How one primitive or message type is checked, defaulted, written and read."""

    def __init__(
        self,
        describe: str,
        check: Callable[[Any], bool],
        default: Callable[[], Any],
        write: Callable[[bytearray, Any], None],
        read: Callable[[_Data, int], Tuple[Any, int]],
        message_class: Any = None,
    ) -> None:
        self.describe = describe
        self.check = check
        self.default = default
        self.write = write
        self.read = read
        self.message_class = message_class


def _is_real(value: Any) -> bool:
    kind = type(value)
    if kind is float or kind is int:  # the common case, without the slower ABC check
        return True
    return isinstance(value, Real) and not isinstance(value, bool)


def _is_bool(value: Any) -> bool:
    if isinstance(value, bool):
        return True
    if isinstance(value, Integral):
        return value in (0, 1)
    return getattr(getattr(value, "dtype", None), "kind", "") == "b"


def _integer_codec(type_name: str) -> _Codec:
    low, high = integer_range(type_name)
    packer = struct.Struct("<" + INTEGER_LETTERS[type_name])

    def check(value: Any) -> bool:
        if type(value) is int:  # the common case, without the slower ABC check
            return low <= value <= high
        return (
            isinstance(value, Integral)
            and not isinstance(value, bool)
            and low <= int(value) <= high
        )

    def write(out: bytearray, value: Any) -> None:
        out += packer.pack(value)

    def read(data: _Data, offset: int) -> Tuple[Any, int]:
        return packer.unpack_from(data, offset)[0], offset + packer.size

    return _Codec(f"an integer from {low} to {high} ({type_name})", check, int, write, read)


def _float_codec(type_name: str) -> _Codec:
    packer = struct.Struct("<" + FLOAT_LETTERS[type_name])
    limit = FLOAT32_MAX if type_name == "float32" else math.inf

    def check(value: Any) -> bool:
        return _is_real(value) and not (math.isfinite(value) and abs(value) > limit)

    def write(out: bytearray, value: Any) -> None:
        out += packer.pack(value)

    def read(data: _Data, offset: int) -> Tuple[Any, int]:
        return packer.unpack_from(data, offset)[0], offset + packer.size

    return _Codec(f"a number ({type_name})", check, float, write, read)


def _bool_codec() -> _Codec:
    def write(out: bytearray, value: Any) -> None:
        out.append(1 if value else 0)

    def read(data: _Data, offset: int) -> Tuple[Any, int]:
        return bool(data[offset]), offset + 1

    return _Codec("True or False (bool)", _is_bool, bool, write, read)


def _string_codec() -> _Codec:
    def write(out: bytearray, value: Any) -> None:
        encoded = value.encode("utf-8")
        out += _UINT32.pack(len(encoded))
        out += encoded

    def read(data: _Data, offset: int) -> Tuple[Any, int]:
        (length,) = _UINT32.unpack_from(data, offset)
        start = offset + 4
        _require(data, start + length)
        return bytes(data[start : start + length]).decode("utf-8", "replace"), start + length

    return _Codec("a str (string)", lambda value: isinstance(value, str), str, write, read)


def _time_codec(kind: Union[Type[Time], Type[Duration]]) -> _Codec:
    packer = _TIME if kind is Time else _DURATION

    def write(out: bytearray, value: Any) -> None:
        out += packer.pack(value.secs, value.nsecs)

    def read(data: _Data, offset: int) -> Tuple[Any, int]:
        secs, nsecs = packer.unpack_from(data, offset)
        return kind(secs, nsecs), offset + packer.size

    name = kind.__name__
    return _Codec(
        f"a rospy.{name} ({name.lower()})",
        lambda value: isinstance(value, kind),
        kind,
        write,
        read,
    )


def _message_codec(message_class: Type[Message]) -> _Codec:
    def write(out: bytearray, value: Any) -> None:
        value._write(out)

    def read(data: _Data, offset: int) -> Tuple[Any, int]:
        message = message_class.__new__(message_class)
        return message, message._read(data, offset)

    return _Codec(
        f"a {message_class.__name__} message ({message_class._type})",
        lambda value: isinstance(value, message_class),
        message_class,
        write,
        read,
        message_class,
    )


def _primitive_codec(type_name: str) -> _Codec:
    if type_name in INTEGER_LETTERS:
        return _integer_codec(type_name)
    if type_name in FLOAT_LETTERS:
        return _float_codec(type_name)
    if type_name == "bool":
        return _bool_codec()
    if type_name == "string":
        return _string_codec()
    return _time_codec(Time if type_name == "time" else Duration)


def _require(data: _Data, end: int) -> None:
    if end > len(data):
        raise MessageError(
            f"The serialized message is cut short: it needs {end} bytes but has {len(data)}."
        )


class _FieldCodec:
    """Checks, defaults, writes and reads one field, scalar or array."""

    def __init__(self, field: Field, element: _Codec) -> None:
        self.field = field
        self.element = element
        self.is_bytes = field.is_array and field.base_type in _BYTE_TYPES

    def default(self) -> Any:
        length = self.field.array_length
        if self.is_bytes:
            return bytes(length or 0)
        if self.field.is_array:
            return [self.element.default() for _ in range(length or 0)]
        return self.element.default()

    def accept(self, owner: str, value: Any) -> Any:
        """Return the value to store, or raise MessageError naming the field and the rule."""
        field = self.field
        if not field.is_array:
            if not self.element.check(value):
                raise self._error(owner, f"must be {self.element.describe}", value)
            return value
        if self.is_bytes and isinstance(value, (bytes, bytearray, memoryview)):
            value = bytes(value)
        elif isinstance(value, (str, bytes, bytearray)) or not hasattr(value, "__len__"):
            raise self._error(owner, f"must be a list of {self.element.describe}", value)
        else:
            items = value.tolist() if hasattr(value, "tolist") else value
            for index, item in enumerate(items):
                if not self.element.check(item):
                    raise self._error(
                        owner, f"must hold only {self.element.describe}; item {index} is", item
                    )
            if self.is_bytes:
                value = bytes(items)
        if field.array_length is not None and len(value) != field.array_length:
            raise MessageError(
                f"{owner}.{field.name} must hold exactly {field.array_length} items, "
                f"but got {len(value)}."
            )
        return value

    def _error(self, owner: str, rule: str, value: Any) -> MessageError:
        shown = repr(value)
        if len(shown) > 60:
            shown = shown[:57] + "..."
        return MessageError(
            f"{owner}.{self.field.name} {rule}, but got {shown} ({type(value).__name__})."
        )

    def write(self, out: bytearray, value: Any) -> None:
        if not self.field.is_array:
            self.element.write(out, value)
            return
        if self.field.array_length is None:
            out += _UINT32.pack(len(value))
        if self.is_bytes:
            out += value
        else:
            for item in value:
                self.element.write(out, item)

    def read(self, data: _Data, offset: int) -> Tuple[Any, int]:
        if not self.field.is_array:
            return self.element.read(data, offset)
        length = self.field.array_length
        if length is None:
            _require(data, offset + 4)
            (length,) = _UINT32.unpack_from(data, offset)
            offset += 4
        if self.is_bytes:
            _require(data, offset + length)
            return bytes(data[offset : offset + length]), offset + length
        items = []
        for _ in range(length):
            item, offset = self.element.read(data, offset)
            items.append(item)
        return items, offset


class Message:
    """Base class of every message type; behaves like ``genpy.Message``.

    Build a message from keywords (fields not named keep their defaults) or from all fields in
    order, never a mix of both::

        tick = WheelEncoderStamped(data=120, resolution=135, type=1)
        tick.data += 3
    """

    # Every message may carry the connection header it arrived with, as rospy sets it on what
    # a subscriber receives (``msg._connection_header["callerid"]``: who published it).
    __slots__ = ("_connection_header",)
    _type: ClassVar[str] = ""
    _md5sum: ClassVar[str] = ""
    _full_text: ClassVar[str] = ""
    _has_header: ClassVar[bool] = False
    _slot_types: ClassVar[List[str]] = []
    _codecs: ClassVar[Dict[str, _FieldCodec]] = {}

    def __init__(self, *args: Any, **kwds: Any) -> None:
        name = type(self).__name__
        if args and kwds:
            raise TypeError(f"{name}(...) takes either every field in order or keywords, not both.")
        if args and len(args) != len(self.__slots__):
            fields = ", ".join(self.__slots__)
            raise TypeError(
                f"{name}(...) takes all {len(self.__slots__)} fields in order ({fields}), "
                f"but got {len(args)} values; use keywords to set only some."
            )
        values = dict(zip(self.__slots__, args)) if args else kwds
        codecs = self._codecs
        for key in values:
            if key not in codecs:
                raise AttributeError(
                    f"{name} has no field {key!r}; its fields are: {', '.join(self.__slots__)}."
                )
        for key, codec in codecs.items():
            value = values.get(key)
            if value is None:
                _set(self, key, codec.default())
            else:
                _set(self, key, codec.accept(name, value))

    def __setattr__(self, key: str, value: Any) -> None:
        codec = self._codecs.get(key)
        if codec is None:
            if key == "_connection_header":
                object.__setattr__(self, key, value)
                return
            raise AttributeError(
                f"{type(self).__name__} has no field {key!r}; "
                f"its fields are: {', '.join(self.__slots__)}."
            )
        object.__setattr__(self, key, codec.accept(type(self).__name__, value))

    def _check_types(self) -> None:
        """Check every field again, including items appended to lists since they were set.

        Raises:
            MessageError: naming the first field whose value does not fit its type.
        """
        for key, codec in self._codecs.items():
            value = codec.accept(type(self).__name__, getattr(self, key))
            if not codec.field.is_primitive:
                for item in value if codec.field.is_array else [value]:
                    item._check_types()

    # -- ROS 1 wire format -----------------------------------------------------------------
    # Each message class gets its own generated ``_write(out)`` and ``_read(data, offset)``
    # (see :mod:`.codegen`); these two are for the fieldless base class.
    def _write(self, out: bytearray) -> None:
        pass

    def _read(self, data: _Data, offset: int) -> int:
        return offset

    def serialize(self, buff: Any) -> None:
        """Write the message in ROS 1's wire format to a binary stream (``buff.write``).

        Raises:
            MessageError: if a field holds a value its type cannot carry.
        """
        buff.write(self.to_bytes())

    def to_bytes(self) -> bytes:
        """The message in ROS 1's wire format, as stored in a bag.

        Raises:
            MessageError: if a field holds a value its type cannot carry.
        """
        out = bytearray()
        try:
            self._write(out)
        except _WRITE_ERRORS as error:
            self._check_types()  # says which field is wrong, and how
            raise MessageError(f"This {self._type} cannot be serialized: {error}.") from None
        return bytes(out)

    def deserialize(self: _M, data: bytes) -> _M:
        """Fill this message from ROS 1 wire-format bytes and return it (as genpy does).

        Raises:
            MessageError: if the bytes are cut short or longer than the message.
        """
        view = data if type(data) is bytes else memoryview(data)
        end = self._read(view, 0)
        if end != len(view):
            raise MessageError(
                f"The serialized {self._type} has {len(view) - end} bytes too many; "
                "is it really this type?"
            )
        return self

    @classmethod
    def from_bytes(cls: Type[_M], data: bytes) -> _M:
        """A new message read from ROS 1 wire-format bytes."""
        message = cls.__new__(cls)
        if type(data) is bytes and message._read(data, 0) == len(data):
            return message  # the common case: a whole message, read at once
        return message.deserialize(data)

    # -- Python protocol -------------------------------------------------------------------
    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(getattr(self, key) == getattr(other, key) for key in self.__slots__)

    __hash__ = None  # type: ignore[assignment]  # mutable, like genpy messages

    def __getstate__(self) -> List[Any]:
        return [getattr(self, key) for key in self.__slots__]

    def __setstate__(self, state: List[Any]) -> None:
        for key, value in zip(self.__slots__, state):
            object.__setattr__(self, key, value)

    def __repr__(self) -> str:
        inner = ", ".join(f"{key}={getattr(self, key)!r}" for key in self.__slots__)
        return f"{type(self).__name__}({inner})"

    def __str__(self) -> str:
        return "\n".join(_yaml_lines(self, 0)) if self.__slots__ else ""


def _yaml_scalar(value: Any) -> str:
    if isinstance(value, str):
        return f'"{value}"' if value else "''"
    if isinstance(value, (Time, Duration)):
        return str(value.to_nsec())
    return repr(value) if isinstance(value, float) else str(value)


def _yaml_lines(message: Message, indent: int) -> List[str]:
    """The message as ``rostopic echo`` prints it: one field a line, nested ones indented."""
    pad = "  " * indent
    lines = []
    for key, codec in message._codecs.items():
        value = getattr(message, key)
        if isinstance(value, (Time, Duration)):
            lines += [f"{pad}{key}:", f"{pad}  secs: {value.secs}", f"{pad}  nsecs: {value.nsecs}"]
        elif isinstance(value, Message):
            lines.append(f"{pad}{key}:")
            lines += _yaml_lines(value, indent + 1)
        elif codec.field.is_array and not codec.field.is_primitive:
            lines.append(f"{pad}{key}:{' []' if not value else ''}")
            for item in value:
                item_lines = _yaml_lines(item, indent + 2)
                lines.append(f"{pad}  -")
                lines += item_lines
        elif codec.field.is_array:
            items = list(value)
            if len(items) > _SHORT_ARRAY:
                shown = ", ".join(_yaml_scalar(item) for item in items[:_SHORT_ARRAY])
                lines.append(f"{pad}{key}: [{shown}, ...] ({len(items)} items)")
            else:
                lines.append(f"{pad}{key}: [{', '.join(_yaml_scalar(item) for item in items)}]")
        else:
            lines.append(f"{pad}{key}: {_yaml_scalar(value)}")
    return lines


class Service:
    """Base class of every service type; like genpy's, it only names its two message classes.

    Attributes:
        _type: ``"package/Type"``.
        _md5sum: the md5 sum rospy checks when a client connects.
        _request_class: the message class a caller sends.
        _response_class: the message class the server answers with.
    """

    _type: ClassVar[str] = ""
    _md5sum: ClassVar[str] = ""
    _request_class: ClassVar[Type[Message]] = Message
    _response_class: ClassVar[Type[Message]] = Message


def make_message_class(
    spec: MessageSpec,
    md5sum: str,
    full_text: str,
    resolve: Callable[[str], Type[Message]],
    kind: str = "msg",
) -> Type[Message]:
    """Create the class of a message type.

    Args:
        spec: the parsed definition.
        md5sum: its ROS 1 md5 sum.
        full_text: its definition with its dependencies', as rospy and bags carry it.
        resolve: returns the class of a nested message type, given ``"package/Type"``.
        kind: ``"srv"`` for the request or response of a service, else ``"msg"``.
    """
    codecs: Dict[str, _FieldCodec] = {}
    for field in spec.fields:
        element = (
            _primitive_codec(field.base_type)
            if field.is_primitive
            else _message_codec(resolve(field.base_type))
        )
        codecs[field.name] = _FieldCodec(field, element)
    namespace: Dict[str, Any] = {
        "__slots__": tuple(codecs),
        "__module__": f"duckielib.messages.{spec.package}.{kind}",
        "__doc__": f"The ROS message {spec.full_name}.\n\nDefinition::\n\n"
        + "\n".join("    " + line for line in spec.text.strip("\n").split("\n")),
        "_type": spec.full_name,
        "_md5sum": md5sum,
        "_full_text": full_text,
        "_has_header": spec.has_header,
        "_slot_types": [field.type for field in spec.fields],
        "_codecs": codecs,
    }
    for constant in spec.constants:
        namespace[constant.name] = constant.value
    namespace["_write"] = make_writer(spec.short_name, codecs)
    namespace["_read"] = make_reader(codecs)
    namespace["__init__"] = make_init(spec.short_name, codecs, Message.__init__)
    namespace["__setattr__"] = make_setattr(codecs, Message.__setattr__)
    # type() is typed as making some class; it makes a subclass of its base, Message.
    return cast(Type[Message], type(spec.short_name, (Message,), namespace))


def make_service_class(
    full_name: str,
    md5sum: str,
    request_class: Type[Message],
    response_class: Type[Message],
    text: str,
) -> Type[Service]:
    """Create the class of a service type from its request and response classes."""
    package, short_name = full_name.split("/")
    namespace: Dict[str, Any] = {
        "__module__": f"duckielib.messages.{package}.srv",
        "__doc__": f"The ROS service {full_name}.\n\nDefinition::\n\n"
        + "\n".join("    " + line for line in text.strip("\n").split("\n")),
        "_type": full_name,
        "_md5sum": md5sum,
        "_request_class": request_class,
        "_response_class": response_class,
    }
    return cast(Type[Service], type(short_name, (Service,), namespace))
