"""Variables in a launcher's lines and a Dockerfile's values, replaced as bash replaces them.

``$NAME``, ``${NAME}``, and the forms with a default or an alternative that launchers use
(``${PARKING_STALL:-1}``, ``${PYTHONPATH:+:${PYTHONPATH}}``): ``:-`` and ``-`` (a default),
``:=`` and ``=`` (a default, also assigned), ``:+`` and ``+`` (an alternative). With a colon
the variable counts as unset when it is empty, as in bash.

Laptop side; never deployed.
"""

from __future__ import annotations

import re
from typing import Dict, List, Optional

__all__ = ["Unresolved", "expand"]


class Unresolved(Exception):
    """A variable that is not set, where the caller wants to know (a base image's own)."""


_REFERENCE = re.compile(r"(\w*)(:?[-+=])?(.*)", re.S)


def expand(value: str, known: Dict[str, str], missing: Optional[str] = None) -> str:
    """``value`` with its variables replaced from ``known``.

    Args:
        value: the text.
        known: the variables set; ``:=`` assigns into it.
        missing: what an unset variable gives (bash gives ""); None raises instead.

    Raises:
        Unresolved: for an unset variable, when ``missing`` is None.
    """
    out: List[str] = []
    index = 0
    while index < len(value):
        if value.startswith("${", index):
            depth, end = 1, index + 2
            while end < len(value) and depth:
                depth += {"{": 1, "}": -1}.get(value[end], 0)
                end += 1
            out.append(_reference(value[index + 2 : end - 1], known, missing))
            index = end
        elif value[index] == "$" and (match := re.match(r"[A-Za-z_]\w*", value[index + 1 :])):
            out.append(_reference(match[0], known, missing))
            index += 1 + len(match[0])
        else:
            out.append(value[index])
            index += 1
    return "".join(out)


def _reference(inner: str, known: Dict[str, str], missing: Optional[str]) -> str:
    """What ``${inner}`` stands for."""
    name, operator, word = _REFERENCE.fullmatch(inner).groups()  # type: ignore[union-attr]
    is_set = name in known and (known[name] != "" or not (operator or "").startswith(":"))
    if operator in (":+", "+"):
        return expand(word, known, missing) if is_set else ""
    if operator in (":-", "-", ":=", "="):
        if is_set:
            return known[name]
        default = expand(word, known, missing)
        if operator.endswith("="):
            known[name] = default
        return default
    if word or name not in known:
        if missing is None:
            raise Unresolved(name)
        return missing
    return known[name]
