"""Type checking: mypy passes on the library and the grader.

mypy runs with the settings of ``[tool.mypy]`` in pyproject.toml. The course's message classes
are made at import time from their ``.msg`` and ``.srv`` files, the one home of their fields;
mypy sees each as a message class (``Type[Message]``).
"""

from __future__ import annotations

import subprocess
import sys

from duckielib.config import PROJECT_ROOT


def test_mypy_finds_no_errors_in_duckielib_and_autograder():
    result = subprocess.run(
        [sys.executable, "-m", "mypy", "duckielib", "autograder"],
        cwd=PROJECT_ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    output = result.stdout + result.stderr
    assert result.returncode == 0, f"mypy found errors:\n{output}"
    assert "Success: no issues found" in output


def test_mypy_reports_a_type_error(tmp_path):
    wrong = tmp_path / "wrong.py"
    wrong.write_text("def heading() -> float:\n    return 'north'\n")
    result = subprocess.run(
        [sys.executable, "-m", "mypy", "--no-incremental", str(wrong)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert result.returncode == 1, result.stdout + result.stderr
    assert "Incompatible return value type" in result.stdout
