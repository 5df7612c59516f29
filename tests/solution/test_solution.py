"""The student contract: exporting tagged cells into a solution, checking and loading it."""

from __future__ import annotations

import linecache
import math
import os
import subprocess
import sys

import nbformat
import pytest
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

from duckielib.odometry import Odometry
from duckielib.solution import (
    CONTRACT,
    SolutionError,
    check_saved,
    export_solution,
    load_solution,
)

DELTA_PHI = '''import math

def delta_phi(ticks, prev_ticks, resolution):
    """The change of wheel angle."""
    return 2 * math.pi * (ticks - prev_ticks) / resolution, ticks

print(delta_phi(10, 0, 135))  # exploring: not exported
'''

ESTIMATE_POSE = """TWO_PI = 2 * math.pi

def estimate_pose(R, baseline, x_prev, y_prev, theta_prev, delta_phi_left, delta_phi_right):
    d_left, d_right = R * delta_phi_left, R * delta_phi_right
    d = (d_left + d_right) / 2
    theta = (theta_prev + (d_right - d_left) / baseline) % TWO_PI
    return x_prev + d * math.cos(theta_prev), y_prev + d * math.sin(theta_prev), theta
"""

PAIRING = """class WheelPairing:
    def __init__(self, resolution=135):
        self.resolution = resolution
        self.prev = {}
        self.change = {"left": 0.0, "right": 0.0}

    def add(self, wheel, ticks):
        if wheel in self.prev:
            change, self.prev[wheel] = delta_phi(ticks, self.prev[wheel], self.resolution)
            self.change[wheel] += change
        else:
            self.prev[wheel] = ticks
        self.reported = getattr(self, "reported", set()) | {wheel}
        if len(self.reported) < 2:
            return None
        pair, self.reported = (self.change["left"], self.change["right"]), set()
        self.change = {"left": 0.0, "right": 0.0}
        return pair
"""

UNWRITTEN = '''def delta_phi(ticks, prev_ticks, resolution):
    """The change of wheel angle."""
    # YOUR CODE HERE
    raise NotImplementedError()
'''


def code(source, export=True):
    cell = new_code_cell(source)
    if export:
        cell.metadata["tags"] = ["export"]
    return cell


def write_notebook(path, cells):
    path.parent.mkdir(parents=True, exist_ok=True)
    notebook = new_notebook(cells=[new_markdown_cell("# A notebook"), *cells])
    nbformat.write(notebook, path)
    return path


def odometry_course(folder, pairing=PAIRING, delta=DELTA_PHI):
    write_notebook(
        folder / "05_odometry" / "05_odometry.ipynb",
        [
            code("import numpy as np\nbot = None", export=False),
            code(delta),
            code(ESTIMATE_POSE),
            code("assert delta_phi(1, 0, 135)[1] == 1", export=False),
            code(pairing),
        ],
    )
    return folder


def test_export_keeps_definitions_and_drops_exploration(tmp_path):
    export = export_solution(odometry_course(tmp_path / "course"))
    assert export.notebooks == ["05_odometry/05_odometry.ipynb"]
    assert "def delta_phi(ticks, prev_ticks, resolution):" in export.source
    assert "TWO_PI = 2 * math.pi" in export.source
    assert "print(delta_phi" not in export.source, "top-level calls stay in the notebook"
    assert "bot = None" not in export.source, "untagged cells are not exported"
    assert export.found == dict.fromkeys(export.found, "05_odometry/05_odometry.ipynb")
    assert set(export.found) == {"delta_phi", "estimate_pose", "WheelPairing"}
    assert export.missing == [name for name in CONTRACT if name not in export.found]
    report = export.report()
    assert report.startswith(f"3 of {len(CONTRACT)} graded parts exported.")
    assert "Finish notebook 03_frames: define wrap_angle, rotation_matrix," in report
    assert not export.complete
    compile(export.source, "solution.py", "exec")


@pytest.mark.timeout(30)
def test_a_fifo_named_like_a_notebook_is_passed_over_not_waited_on(tmp_path):
    folder = odometry_course(tmp_path / "course")
    os.mkfifo(folder / "05_odometry" / "zz_scratch.ipynb")
    export = export_solution(folder)
    assert export.notebooks == ["05_odometry/05_odometry.ipynb"]


def test_unwritten_functions_and_classes_are_reported(tmp_path):
    released_class = '''class WheelPairing:
    """Pairs readings."""
    # YOUR CODE HERE
    raise NotImplementedError()
'''
    folder = odometry_course(tmp_path / "course", pairing=released_class, delta=UNWRITTEN)
    export = export_solution(folder)
    assert export.unfinished == ["delta_phi", "WheelPairing"]
    assert "Finish notebook 05_odometry: write delta_phi, WheelPairing." in (export.report())
    with pytest.raises(SolutionError, match=r"Finish notebook 05_odometry: write delta_phi, Whe"):
        load_solution(folder)  # unfinished parts are named before anything runs
    with pytest.raises(SolutionError, match="fails to import"):
        load_solution(folder, required=())  # the released class body raises when defined


def test_parameters_that_differ_from_the_contract_are_named(tmp_path):
    wrong = DELTA_PHI.replace("(ticks, prev_ticks, resolution):", "(ticks, previous, res):")
    export = export_solution(odometry_course(tmp_path / "course", delta=wrong))
    assert export.problems == [
        "In notebook 05_odometry/05_odometry.ipynb, delta_phi takes (ticks, previous, res); "
        "the course's version takes (ticks, prev_ticks, resolution)."
    ]
    with pytest.raises(SolutionError, match=r"delta_phi takes \(ticks, previous, res\)"):
        load_solution(tmp_path / "course")


def test_a_syntax_error_names_the_notebook_and_line(tmp_path):
    folder = odometry_course(tmp_path / "course", delta="def delta_phi(ticks,:\n    pass\n")
    with pytest.raises(SolutionError, match=r"05_odometry.ipynb, exported cell 1 .*line 1"):
        export_solution(folder)


def test_folders_without_notebooks_and_missing_paths(tmp_path):
    with pytest.raises(SolutionError, match="holds no notebook"):
        export_solution(tmp_path)
    with pytest.raises(SolutionError, match="There is no folder"):
        export_solution(tmp_path / "nope")
    with pytest.raises(SolutionError, match="There is no solution file or folder"):
        load_solution(tmp_path / "nope.py")
    notebook = write_notebook(tmp_path / "one.ipynb", [code(DELTA_PHI)])
    with pytest.raises(SolutionError, match="give the folder that holds your notebooks"):
        load_solution(notebook)


def test_a_folder_loads_as_a_solution_that_drives_odometry(tmp_path):
    solution = load_solution(odometry_course(tmp_path / "course"))
    assert solution.delta_phi(135, 0, 135) == (pytest.approx(2 * math.pi), 135)
    odometry = Odometry(solution, start=(0.0, 0.0, 0.0))
    assert odometry.add("left", 1000) is None
    assert odometry.add("right", -50) == (0.0, 0.0, 0.0)
    assert odometry.add("left", 1135) is None
    x, y, theta = odometry.add("right", 85)
    assert x == pytest.approx(2 * math.pi * 0.0318)
    assert (y, theta) == (pytest.approx(0.0), pytest.approx(0.0))


def test_missing_required_parts_name_the_notebook(tmp_path):
    folder = tmp_path / "course"
    write_notebook(folder / "05_odometry" / "05_odometry.ipynb", [code(DELTA_PHI)])
    with pytest.raises(
        SolutionError, match=r"Finish notebook 05_odometry: .* has no estimate_pose"
    ):
        load_solution(folder)
    module = tmp_path / "mine.py"
    module.write_text(DELTA_PHI + ESTIMATE_POSE.replace("math.pi", "3.14159"))
    with pytest.raises(SolutionError, match="no class WheelPairing"):
        load_solution(module)
    broken = tmp_path / "broken.py"
    broken.write_text("import no_such_module_here\n")
    with pytest.raises(SolutionError, match="fails to import: ModuleNotFoundError"):
        load_solution(broken)


def test_failures_inside_a_solution_name_the_call_and_notebook(tmp_path):
    folder = odometry_course(tmp_path / "course", delta=DELTA_PHI.replace("2 * math.pi", "oops"))
    odometry = Odometry(load_solution(folder))
    odometry.add("left", 0)
    odometry.add("right", 0)
    with pytest.raises(SolutionError, match=r"WheelPairing.add\('left', 3\), from notebook"):
        odometry.add("left", 3)


def run_duckie(*args):
    return subprocess.run(
        [sys.executable, "-m", "duckielib.tools.cli", *map(str, args)],
        capture_output=True,
        text=True,
        check=False,
    )


def test_duckie_export_writes_the_module_and_reports(tmp_path):
    folder = odometry_course(tmp_path / "course")
    output = tmp_path / "mine.py"
    result = run_duckie("export", folder, "-o", output)
    assert result.returncode == 0, result.stderr
    assert f"3 of {len(CONTRACT)} graded parts exported." in result.stdout
    assert "Finish notebook 04_kinematics: define forward_kinematics," in result.stdout
    assert output.read_text() == export_solution(folder).source
    assert load_solution(output).estimate_pose(0.03, 0.1, 0, 0, 0, 0, 0) == (0.0, 0.0, 0.0)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (("export", "nowhere", "-o", "x.py"), "There is no folder nowhere"),
        (("export", ".", "-o", "x.txt"), "must end in .py"),
        (("export", ".", "-o", "no/such/dir/x.py"), "There is no folder no/such/dir"),
    ],
)
def test_duckie_export_errors_are_one_line(tmp_path, args, message):
    odometry_course(tmp_path)
    result = subprocess.run(
        [sys.executable, "-m", "duckielib.tools.cli", *args],
        capture_output=True,
        text=True,
        check=False,
        cwd=tmp_path,
    )
    assert result.returncode == 1
    assert message in result.stderr
    assert "Traceback" not in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1
    assert not list(tmp_path.glob("*.py*"))


def test_the_library_defines_no_graded_part():
    import importlib
    import pkgutil

    import duckielib

    offenders = []
    for module_info in pkgutil.walk_packages(duckielib.__path__, "duckielib."):
        if ".examples." in module_info.name or module_info.name.endswith("__main__"):
            continue
        module = importlib.import_module(module_info.name)
        offenders += [f"{module_info.name}.{name}" for name in CONTRACT if hasattr(module, name)]
    assert offenders == [], "students receive duckielib: it must not hold their answers"


def test_a_broken_later_notebook_does_not_keep_earlier_parts_from_loading(tmp_path):
    folder = odometry_course(tmp_path / "course")
    write_notebook(
        folder / "09_mission" / "09_mission.ipynb",
        [code("def mission_node(mission):\n    while True\n")],
    )
    with pytest.raises(SolutionError, match=r"In notebook 09_mission/09_mission.ipynb, exported"):
        export_solution(folder)
    module = load_solution(folder)  # the odometry parts of 05 still load
    assert module.delta_phi(135, 0, 135)[0] == pytest.approx(2 * math.pi)
    with pytest.raises(SolutionError, match="exported cell 1 is not valid Python"):
        load_solution(folder, required=["mission_node"])


def defined_in_a_cell(text, name, label="<cell 4>"):
    """``name`` as a notebook cell of ``text`` defines it (IPython keeps a cell's lines)."""
    linecache.cache[label] = (len(text), None, text.splitlines(True), label)
    namespace = {"math": math}
    exec(compile(text, label, "exec"), namespace)
    return namespace[name]


def test_check_saved_accepts_the_saved_part_and_names_an_unsaved_edit(tmp_path):
    solution = load_solution(odometry_course(tmp_path / "course"))
    # Formatting and comments do not count.
    saved = defined_in_a_cell(
        DELTA_PHI.replace("return 2", "# the angle\n    return  2"), "delta_phi"
    )
    check_saved(solution, saved)
    edited = defined_in_a_cell(DELTA_PHI.replace("2 * math.pi", "math.pi"), "delta_phi", "<c5>")
    with pytest.raises(SolutionError) as error:
        check_saved(solution, edited)
    assert str(error.value) == (
        "delta_phi in this notebook differs from the one saved in notebook 05_odometry: save "
        "the notebook (Ctrl+S) and run this cell again. Tests, duckie mission and the robot all "
        "run your saved notebooks."
    )
    # Parts the solution lacks, names outside the contract and code without source are left.
    check_saved(solution, edited.__class__, print, lambda ticks: ticks)


def test_an_unfinished_part_in_an_exported_module_stops_the_load(tmp_path):
    module = tmp_path / "mine.py"
    module.write_text(export_solution(odometry_course(tmp_path / "c", delta=UNWRITTEN)).source)
    with pytest.raises(SolutionError, match=r"^Finish notebook 05_odometry: write delta_phi \("):
        load_solution(module)
    assert load_solution(module, required=["estimate_pose"]).estimate_pose
