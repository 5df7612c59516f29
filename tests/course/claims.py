"""The notebooks' claims: sentences that say what a figure or a printout shows, and their checks.

A notebook's text tells the student what to see in a figure or a table ("the trim straightens
the robot", "the count goes up while the robot rolls back"). Each such sentence is a claim, and
the simulator can drift away from it (a refit robot, a new seed). Every claim is listed here
with the words that make it and the numbers that back it: the notebook prints them, and the
claim holds when the printed numbers satisfy it. The gates in ``test_course_run_all.py`` check
every claim on the runs they already make (the source notebooks and the release filled with
the reference answers), so a change to the text, the cells or the simulator that breaks a
claim fails there, naming the sentence and the numbers.

To add a claim: make the cell that draws the figure print the numbers the sentence is about
(students read them too), then list the claim in ``CLAIMS`` under its notebook.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Callable, Dict, List, Mapping, Optional

__all__ = ["CLAIMS", "Claim", "check_claim", "markdown_text"]


@dataclass(frozen=True)
class Claim:
    """A sentence of a notebook about its own figures or printouts, and the numbers behind it.

    Attributes:
        says: words of the notebook's markdown that make the claim, as written (spaces and
            line breaks may differ).
        printed: a regular expression with named groups, searched in everything the notebook's
            code cells printed; each group is read as a number.
        holds: called with the groups' numbers as keyword arguments; true when the claim holds.
        meaning: the claim in a few words, for the failure message.
    """

    says: str
    printed: str
    holds: Callable[..., bool]
    meaning: str


def _words(text: str) -> str:
    return " ".join(text.split())


def markdown_text(notebook: Mapping[str, object]) -> str:
    """All the markdown of a notebook, its spaces and line breaks made single spaces."""
    cells = notebook.get("cells", [])
    parts = []
    for cell in cells:  # type: ignore[attr-defined]
        if cell.get("cell_type") == "markdown":
            text = cell.get("source", "")
            parts.append("".join(text) if isinstance(text, list) else text)
    return _words("\n".join(parts))


def check_claim(claim: Claim, markdown: str, printed: str) -> Optional[str]:
    """Why ``claim`` does not hold in a notebook's text and printouts, or None when it holds."""
    if _words(claim.says) not in _words(markdown):
        return f"the text no longer says {claim.says!r}: update or remove its claim"
    found = re.search(claim.printed, printed)
    if found is None:
        return f"nothing printed matches {claim.printed!r}, the numbers behind {claim.says!r}"
    numbers = {name: float(value) for name, value in found.groupdict().items()}
    if not claim.holds(**numbers):
        shown = ", ".join(f"{name} = {value:g}" for name, value in numbers.items())
        return f"{claim.says!r} ({claim.meaning}) does not hold: {shown}"
    return None


#: Every notebook's claims, by notebook name.
CLAIMS: Dict[str, List[Claim]] = {}
