"""autograder: the instructor's side of the course.

It will hold the nbgrader configuration and the class grading pipeline (sandboxed, parallel
autograding with a driving score and feedback). Students never receive this package.
"""

from __future__ import annotations

__all__: list[str] = []
