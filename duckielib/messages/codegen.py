"""Generated readers and writers of the ROS 1 wire format, one pair per message type.

genpy writes a ``serialize`` and a ``deserialize`` method for every message type, packing runs
of fixed-size fields with a single ``struct`` call; this module does the same when a class is
made, from the codecs of :mod:`.message`. For ``WheelEncoderStamped`` the writer is three lines::

    out += _s0.pack(self.header.seq, self.header.stamp.secs, self.header.stamp.nsecs)
    _text = self.header.frame_id.encode("utf-8"); out += _U32.pack(len(_text)); out += _text
    out += _s1.pack(self.data, self.resolution, self.type)

Nested messages (not arrays of them) are flattened into their parent's runs. Arrays go through
their field codec, which checks every item first (items appended to a list were never checked).
Scalar fields need no check here: every assignment was checked when it was made.
"""

from __future__ import annotations

import struct
from typing import TYPE_CHECKING, Any, Callable, Dict, List, Mapping, Tuple, Type, Union

from duckielib.errors import MessageError
from duckielib.rostime import NS_PER_S, Duration, Time

if TYPE_CHECKING:
    from typing import Protocol

    from .spec import Field

    class _ElementCodec(Protocol):
        @property
        def message_class(self) -> Any: ...  # the nested message's class, for a message field

    class FieldCodec(Protocol):
        """What the generated code asks of a field's codec (``message._FieldCodec``)."""

        @property
        def field(self) -> Field: ...

        @property
        def element(self) -> _ElementCodec: ...

        def default(self) -> Any: ...

        def accept(self, owner: str, value: Any) -> Any: ...

        def write(self, out: bytearray, value: Any) -> None: ...

        def read(self, data: Union[bytes, memoryview], offset: int) -> Tuple[Any, int]: ...

    #: The field codecs of a message type, by field name in definition order.
    Codecs = Mapping[str, FieldCodec]

__all__ = [
    "FLOAT32_MAX",
    "FLOAT_LETTERS",
    "INTEGER_LETTERS",
    "integer_range",
    "make_init",
    "make_reader",
    "make_writer",
]

#: The ``struct`` letter of each fixed-size primitive type (little-endian, as ROS 1 sends).
INTEGER_LETTERS = {
    "int8": "b",
    "byte": "b",
    "uint8": "B",
    "char": "B",
    "int16": "h",
    "uint16": "H",
    "int32": "i",
    "uint32": "I",
    "int64": "q",
    "uint64": "Q",
}
FLOAT_LETTERS = {"float32": "f", "float64": "d"}
_FIXED = {**INTEGER_LETTERS, **FLOAT_LETTERS, "bool": "?"}
#: The largest finite float32.
FLOAT32_MAX = 3.4028234663852886e38


def integer_range(type_name: str) -> Tuple[int, int]:
    """The smallest and largest value of an integer type (``"uint16"`` -> (0, 65535))."""
    letter = INTEGER_LETTERS[type_name]
    bits = struct.calcsize(letter) * 8
    if letter.isupper():
        return 0, 2**bits - 1
    return -(2 ** (bits - 1)), 2 ** (bits - 1) - 1


_UINT32 = struct.Struct("<I")


def _time(kind: Union[Type[Time], Type[Duration]], secs: int, nsecs: int) -> Union[Time, Duration]:
    """A Time or Duration from unpacked fields, normalised only when it needs to be."""
    if 0 <= nsecs < NS_PER_S:
        value = object.__new__(kind)
        value.secs = secs
        value.nsecs = nsecs
        return value
    return kind(secs, nsecs)


def _leaves(codecs: Codecs, path: Tuple[str, ...]) -> List[Tuple[str, Tuple[str, ...], Any]]:
    """The fields of a message in wire order, nested messages opened up.

    Each item is ``(kind, path, detail)``: ``fixed`` (detail: struct letter), ``time``
    (detail: Time or Duration), ``string``, ``array`` (detail: the field codec), and ``begin``
    and ``end`` around a nested message's own fields (detail: its class).
    """
    found: List[Tuple[str, Tuple[str, ...], Any]] = []
    for key, codec in codecs.items():
        field = codec.field
        where = (*path, key)
        if field.is_array:
            found.append(("array", where, codec))
        elif not field.is_primitive:
            nested = codec.element.message_class
            found.append(("begin", where, nested))
            found += _leaves(nested._codecs, where)
            found.append(("end", where, nested))
        elif field.base_type == "string":
            found.append(("string", where, None))
        elif field.base_type in ("time", "duration"):
            found.append(("time", where, Time if field.base_type == "time" else Duration))
        else:
            found.append(("fixed", where, _FIXED[field.base_type]))
    return found


def _owner(name: str, codecs: Codecs, path: Tuple[str, ...]) -> str:
    """The name of the message type that holds the field at ``path``.

    Args:
        name: the name of the outermost message type.
        codecs: its field codecs.
        path: the field names from the outermost message down to the field.
    """
    for key in path[:-1]:
        nested = codecs[key].element.message_class
        name, codecs = nested.__name__, nested._codecs
    return name


def _compile(source: str, name: str, namespace: Dict[str, Any]) -> Callable[..., Any]:
    exec(compile(source, f"<generated {name}>", "exec"), namespace)
    return namespace[name]


def make_writer(name: str, codecs: Codecs) -> Callable[[Any, bytearray], None]:
    """``_write(self, out)``: append the message's wire format to ``out``.

    Args:
        name: the message type's class name, for error messages.
        codecs: its field codecs.
    """
    namespace: Dict[str, Any] = {"_U32": _UINT32}
    lines: List[str] = []
    run: Tuple[List[str], List[str]] = ([], [])

    def flush() -> None:
        letters, values = run
        if letters:
            packer_name = f"_s{len(namespace)}"
            namespace[packer_name] = struct.Struct("<" + "".join(letters))
            lines.append(f"    out += {packer_name}.pack({', '.join(values)})")
            letters.clear()
            values.clear()

    for kind, path, detail in _leaves(codecs, ()):
        value = "self." + ".".join(path)
        if kind == "fixed":
            run[0].append(detail)
            run[1].append(value)
        elif kind == "time":
            run[0].append("II" if detail is Time else "ii")
            run[1].extend([f"{value}.secs", f"{value}.nsecs"])
        elif kind == "string":
            flush()
            lines.append(f"    _text = {value}.encode('utf-8')")
            lines.append("    out += _U32.pack(len(_text))")
            lines.append("    out += _text")
        elif kind == "array":
            flush()
            codec_name = f"_c{len(namespace)}"
            namespace[codec_name] = detail
            owner = _owner(name, codecs, path)
            lines.append(f"    {codec_name}.write(out, {codec_name}.accept({owner!r}, {value}))")
    flush()
    source = "def _write(self, out):\n" + ("\n".join(lines) or "    pass") + "\n"
    return _compile(source, "_write", namespace)


def make_reader(codecs: Codecs) -> Callable[[Any, Union[bytes, memoryview], int], int]:
    """``_read(self, data, offset)``: fill the message from ``data``; return the end offset.

    Args:
        codecs: the message type's field codecs.
    """
    source = _ReaderSource()
    for kind, path, detail in _leaves(codecs, ()):
        source.add(kind, path[-1], detail)
    return _compile(source.text(), "_read", source.namespace)


class _ReaderSource:
    """The source of a ``_read`` function, written one field at a time."""

    def __init__(self) -> None:
        self.namespace: Dict[str, Any] = {
            "_U32": _UINT32,
            "_time": _time,
            "_set": object.__setattr__,
            "_new": object.__new__,
            "_Time": Time,
            "_Duration": Duration,
            "_cut": _cut_short,
            "_error": struct.error,
        }
        self.lines: List[str] = []
        self.letters: List[str] = []  # the struct letters of the run being read
        self.targets: List[str] = []  # the variables they are unpacked into
        self.finish: List[str] = []  # statements that build Time values after the run
        self.fields: List[List[Tuple[str, str]]] = [[]]  # (field, variable) of open messages
        self.count = 0

    def _name(self, prefix: str, value: Any = None) -> str:
        name = f"{prefix}{len(self.namespace) + self.count}"
        self.count += 1
        if value is not None:
            self.namespace[name] = value
        return name

    def _flush(self) -> None:
        if self.letters:
            packer = struct.Struct("<" + "".join(self.letters))
            name = self._name("_s", packer)
            self.lines.append(f"    {', '.join(self.targets)}, = {name}.unpack_from(data, offset)")
            self.lines.append(f"    offset += {packer.size}")
            self.lines.extend(self.finish)
            self.letters, self.targets, self.finish = [], [], []

    def add(self, kind: str, key: str, detail: Any) -> None:
        """Read one item of :func:`_leaves`."""
        if kind == "begin":
            self.fields.append([])
            return
        if kind == "end":
            self._flush()
            name = self._name("_v")
            class_name = self._name("_class", detail)
            self.lines.append(f"    {name} = _new({class_name})")
            self.lines += [
                f"    _set({name}, {field!r}, {value})" for field, value in self.fields.pop()
            ]
            self.fields[-1].append((key, name))
            return
        name = self._name("_v")
        self.fields[-1].append((key, name))
        if kind == "fixed":
            self.letters.append(detail)
            self.targets.append(name)
        elif kind == "time":
            self.letters.append("II" if detail is Time else "ii")
            self.targets += [f"{name}_s", f"{name}_n"]
            kind_name = "_Time" if detail is Time else "_Duration"
            self.finish.append(f"    {name} = _time({kind_name}, {name}_s, {name}_n)")
        elif kind == "string":
            self._flush()
            self.lines += _read_string(name)
        elif kind == "array":
            self._flush()
            codec_name = self._name("_c", detail)
            self.lines.append(f"    {name}, offset = {codec_name}.read(data, offset)")

    def text(self) -> str:
        """The whole function."""
        self._flush()
        lines = self.lines + [f"    _set(self, {key!r}, {value})" for key, value in self.fields[0]]
        body = "\n".join("    " + line for line in lines) or "        pass"
        return (
            "def _read(self, data, offset):\n"
            "    try:\n"
            f"{body}\n"
            "    except _error:\n"
            "        _cut(data, None, self)\n"
            "    return offset\n"
        )


_SCALAR_DEFAULTS = {"string": "''", "bool": "False", "float32": "0.0", "float64": "0.0"}


def _fast_test(base_type: str, value: str) -> str:
    """A quick test that ``value`` is plainly fine for a field, or ``""`` if there is none.

    Values that fail it are not wrong yet: they go to the field codec, which decides.
    """
    if base_type == "string":
        return f"type({value}) is str"
    if base_type == "float64":
        return f"type({value}) is float"
    if base_type == "float32":
        return f"type({value}) is float and -_F32 <= {value} <= _F32"
    if base_type not in INTEGER_LETTERS:
        return ""
    low, high = integer_range(base_type)
    return f"type({value}) is int and {low} <= {value} <= {high}"


def make_init(name: str, codecs: Codecs, generic: Callable[..., None]) -> Callable[..., None]:
    """``__init__(self, **fields)``, checking each given field and defaulting the others.

    Calls with positional values or unknown keywords go to ``generic``, which explains them.

    Args:
        name: the message type's class name, for error messages.
        codecs: its field codecs.
        generic: the checking ``__init__`` of the base class.
    """
    namespace: Dict[str, Any] = {
        "_set": object.__setattr__,
        "_generic": generic,
        "_fields": frozenset(codecs),
        "_F32": FLOAT32_MAX,
        "_name": name,
        "_Time": Time,
        "_Duration": Duration,
    }
    lines = [
        "def __init__(self, *args, **kwds):",
        "    if args or not kwds.keys() <= _fields:",
        "        return _generic(self, *args, **kwds)",
        "    get = kwds.get",
    ]
    for number, (key, codec) in enumerate(codecs.items()):
        field = codec.field
        namespace[f"_accept{number}"] = codec.accept
        test = ""
        if field.is_array or not field.is_primitive:
            default = f"_default{number}()"
            namespace[f"_default{number}"] = codec.default
        elif field.base_type in ("time", "duration"):
            default = "_Time(0, 0)" if field.base_type == "time" else "_Duration(0, 0)"
        else:
            default = _SCALAR_DEFAULTS.get(field.base_type, "0")
            test = _fast_test(field.base_type, "value")
        lines += [
            f"    value = get({key!r})",
            "    if value is None:",
            f"        value = {default}",
            f"    elif not ({test}):" if test else "    else:",
            f"        value = _accept{number}(_name, value)",
            f"    _set(self, {key!r}, value)",
        ]
    return _compile("\n".join(lines) + "\n", "__init__", namespace)


def make_setattr(codecs: Codecs, generic: Callable[..., None]) -> Callable[..., None]:
    """``__setattr__(self, key, value)``: store plainly fine values at once, as ``__init__``.

    Other values and unknown names go to ``generic``, which checks them or explains.

    Args:
        codecs: the message type's field codecs.
        generic: the checking ``__setattr__`` of the base class.
    """
    namespace: Dict[str, Any] = {
        "_set": object.__setattr__,
        "_generic": generic,
        "_F32": FLOAT32_MAX,
        "_Time": Time,
        "_Duration": Duration,
    }
    lines = ["def __setattr__(self, key, value):"]
    for number, (key, codec) in enumerate(codecs.items()):
        field = codec.field
        if field.is_array:
            test = ""
        elif not field.is_primitive:
            namespace[f"_class{number}"] = codec.element.message_class
            test = f"isinstance(value, _class{number})"
        elif field.base_type == "time":
            test = "isinstance(value, _Time)"
        elif field.base_type == "duration":
            test = "isinstance(value, _Duration)"
        else:
            test = _fast_test(field.base_type, "value")
        if test:
            lines += [
                f"    if key == {key!r} and {test}:",
                f"        return _set(self, {key!r}, value)",
            ]
    lines.append("    _generic(self, key, value)")
    return _compile("\n".join(lines) + "\n", "__setattr__", namespace)


def _read_string(name: str) -> List[str]:
    """Lines that read a string into ``name``: its length, then its UTF-8 bytes."""
    return [
        "    (_length,) = _U32.unpack_from(data, offset)",
        "    _end = offset + 4 + _length",
        "    if _end > len(data):",
        "        _cut(data, _end)",
        f"    {name} = bytes(data[offset + 4 : _end]).decode('utf-8', 'replace')",
        "    offset = _end",
    ]


def _cut_short(data: Union[bytes, memoryview], end: Any, message: Any = None) -> None:
    """Raise the error for bytes that end before the message does."""
    what = f"serialized {message._type}" if message is not None else "serialized message"
    needs = f": it needs {end} bytes but has {len(data)}" if end is not None else ""
    raise MessageError(f"The {what} is cut short{needs}.")
