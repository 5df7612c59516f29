"""The robot-deployed modules stay pure: Python 3.8, standard library and numpy only.

Which modules those are is a rule about folders: all of ``duckielib/`` but its laptop packages
(``duckielib.tools.deploy.LAPTOP_PACKAGES``), the very files ``duckie robot prepare`` deploys.
"""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from duckielib.tools.deploy import LAPTOP_PACKAGES, robot_module_files

ROOT = Path(__file__).resolve().parents[1]
LAPTOP_ONLY = (
    "pymunk",
    "rosbags",
    "matplotlib",
    "rospy",
    "PIL",
    "ipywidgets",
    "nbgrader",
    "jupyterlab",
    "greenlet",
    "foxglove",
    "mcap",
)


def robot_modules() -> list[Path]:
    """The robot-deployed Python files, relative to the repository."""
    return [path for path in robot_module_files() if path.suffix == ".py"]


def robot_module_names() -> list[str]:
    names = []
    for file in robot_modules():
        parts = file.with_suffix("").parts
        names.append(".".join(parts[:-1] if parts[-1] == "__init__" else parts))
    return names


def tool(name: str) -> str:
    found = shutil.which(name, path=str(Path(sys.executable).parent))
    if found is None:
        pytest.fail(f"{name} is not installed in the environment; run `make test` to install it.")
    return found


def vermin_38(*paths: Path) -> subprocess.CompletedProcess:
    """vermin's verdict on whether ``paths`` run on Python 3.8 (return code 0: they do)."""
    return subprocess.run(
        [
            tool("vermin"),
            "--target=3.8-",
            "--violations",
            "--no-tips",
            "--no-parse-comments",
            "--eval-annotations",
            *[str(path) for path in paths],
        ],
        capture_output=True,
        text=True,
        check=False,
    )


def test_the_folders_say_where_code_runs():
    library = ROOT / "duckielib"
    laptop = sorted(path.name for path in library.iterdir() if path.name in LAPTOP_PACKAGES)
    assert laptop == sorted(LAPTOP_PACKAGES), "a laptop package is missing"
    assert laptop == ["bags", "lab", "libraries", "plots", "sim", "tools"]
    deployed = {path.parts[1] for path in robot_modules()}
    assert not deployed & set(LAPTOP_PACKAGES)
    # The robot gets the pure core and its packages: the messages, the in-process rospy,
    # the nodes and the solution's loader.
    assert {"messages", "ros", "nodes", "solution", "odometry.py", "missions.py"} <= deployed


def test_robot_modules_run_on_python_3_8():
    result = vermin_38(*[ROOT / entry for entry in robot_modules()])
    assert result.returncode == 0, result.stdout + result.stderr


def test_vermin_catches_newer_syntax(tmp_path):
    newer = tmp_path / "newer.py"
    newer.write_text("def f(x):\n    match x:\n        case 1:\n            return 1\n")
    result = subprocess.run(
        [tool("vermin"), "--target=3.8-", "--violations", "--no-tips", str(newer)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode != 0


BLOCKER = """
import importlib.abc, sys
class Block(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in {blocked!r}:
            raise ImportError("blocked laptop-only package: " + name)
        return None
sys.meta_path.insert(0, Block())
import importlib
for name in {modules!r}:
    importlib.import_module(name)
print("ok")
"""


def test_robot_modules_import_with_laptop_packages_blocked():
    script = BLOCKER.format(blocked=LAPTOP_ONLY, modules=robot_module_names())
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=False
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "ok"


def test_without_greenlet_the_graph_runs_launched_nodes_in_threads():
    script = BLOCKER.format(blocked=LAPTOP_ONLY, modules=["duckielib.ros"]) + (
        "from duckielib.ros import Graph, rospy\n"
        "graph = Graph(echo_logs=False)\n"
        "ticks = []\n"
        "def ticker():\n"
        "    rospy.init_node('ticker')\n"
        "    while not rospy.is_shutdown():\n"
        "        ticks.append(rospy.get_time())\n"
        "        rospy.sleep(0.5)\n"
        "graph.launch(ticker)\n"
        "graph.run(1.2)\n"
        "graph.shutdown()\n"
        "print(graph.threads, ticks, all(actor.finished for actor in graph._actors))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=False
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split("\n")[-2] == "True [0.0, 0.5, 1.0] True"


def test_import_duckielib_loads_nothing_heavy():
    script = (
        "import sys, duckielib\n"
        f"print(sorted(m for m in sys.modules if m.split('.')[0] in {(*LAPTOP_ONLY, 'numpy')!r}))"
    )
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip() == "[]"


def _imported_at_load(path: Path) -> set[str]:
    """The packages a module imports when it is loaded: not in functions, not for types."""
    import ast

    found: set[str] = set()
    waiting: list[ast.AST] = list(ast.parse(path.read_text(), str(path)).body)
    while waiting:
        node = waiting.pop()
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)):
            continue
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            waiting += node.orelse
            continue
        if isinstance(node, ast.Import):
            found.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module.split(".")[0])
        waiting += ast.iter_child_nodes(node)
    return found - {"__future__"}


def test_the_load_time_imports_leave_out_functions_and_types(tmp_path):
    module = tmp_path / "probe.py"
    module.write_text(
        "from __future__ import annotations\n"
        "import json, numpy.linalg\n"
        "from typing import TYPE_CHECKING\n"
        "if TYPE_CHECKING:\n    import pandas\nelse:\n    import scipy\n"
        "try:\n    import yaml\nexcept ImportError:\n    pass\n"
        "class Kept:\n    import zmq\n    def later(self):\n        import nbformat\n"
        "def lazy():\n    import matplotlib\n"
        "from . import sibling\n"
    )
    assert _imported_at_load(module) == {"json", "numpy", "typing", "scipy", "yaml", "zmq"}


#: What runs inside the grader's sandbox: its server's package, and the calls' kernel side.
INSIDE_THE_SANDBOX = ROOT / "autograder" / "sandbox" / "inside"


def test_code_inside_the_sandbox_imports_only_the_standard_library_at_load():
    # The server forks the kernel zygote before anything else is imported, and the guard and
    # the calls run in the student's kernel: at load, the standard library and each other only.
    files = [*sorted(INSIDE_THE_SANDBOX.glob("*.py")), ROOT / "autograder" / "calls.py"]
    outside = {
        f"{path.relative_to(ROOT).as_posix()} imports {package}"
        for path in files
        for package in _imported_at_load(path)
        if package not in sys.stdlib_module_names | {"inside"}  # the package, by its own name
    }
    assert outside == set()
    # And as the sandbox loads them (the package named `inside`): nothing else comes along.
    script = (
        "import sys\n"
        f"sys.path[0] = {str(INSIDE_THE_SANDBOX.parent)!r}\n"
        "before = set(sys.modules)\n"
        "import inside.serve, inside.seam, inside.guard, inside.wire\n"
        "print(sorted(name for name in set(sys.modules) - before\n"
        "             if name.split('.')[0] not in sys.stdlib_module_names | {'inside'}))\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True, timeout=60
    )
    assert result.stdout.strip() == "[]"
    loaded = {path.stem for path in INSIDE_THE_SANDBOX.glob("*.py")} - {"__init__", "__main__"}
    assert loaded == {"serve", "seam", "guard", "wire", "notebook", "zygote", "processes"}


def test_ruff_lint_is_clean():
    result = subprocess.run(
        [tool("ruff"), "check", "--no-cache", str(ROOT)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr


def test_ruff_format_is_clean():
    result = subprocess.run(
        [tool("ruff"), "format", "--check", "--no-cache", str(ROOT)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr


#: Edges stay at the edges (DESIGN.md, principle 5): each heavy package, the only places
#: in duckielib that may import it.
EDGES = {
    "pymunk": ("duckielib/sim/",),
    # io.py reads and writes ROS 1 bags through rosbags (and its seam); convert.py hands the
    # other formats (ROS 2 bags, CDR) to rosbags' public converter.
    "rosbags": (
        "duckielib/bags/seam.py",
        "duckielib/bags/reader.py",
        "duckielib/bags/writer.py",
        "duckielib/bags/convert.py",
    ),
    "matplotlib": ("duckielib/plots/", "duckielib/sim/examples/"),
    "foxglove": ("duckielib/sim/live.py",),
}


def _imported_packages(path: Path) -> set[str]:
    import ast

    found = set()
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            found.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module.split(".")[0])
    return found


def test_heavy_packages_are_imported_only_at_their_edge():
    misplaced = []
    for path in sorted((ROOT / "duckielib").rglob("*.py")):
        relative = path.relative_to(ROOT).as_posix()
        for package in _imported_packages(path) & set(EDGES):
            if not relative.startswith(EDGES[package]):
                misplaced.append(f"{relative} imports {package}")
    assert misplaced == []


def test_the_library_students_receive_never_reaches_the_grader():
    # The instructors' commands and benchmark join `duckie` through entry points (pyproject):
    # no module of duckielib imports autograder, nor names it for importlib.
    reaching = []
    for path in sorted((ROOT / "duckielib").rglob("*.py")):
        if "autograder" in _imported_packages(path) or '"autograder.' in path.read_text():
            reaching.append(path.relative_to(ROOT).as_posix())
    assert reaching == []


def test_the_instructors_commands_join_duckie_through_entry_points():
    from importlib.metadata import entry_points

    from duckielib.tools.bench import benchmarks

    (commands,) = entry_points(group="duckie.commands")
    assert commands.value == "autograder.commands:add_commands"
    assert benchmarks()["grade"][0] == "autograder.bench"
    result = subprocess.run(
        [tool("duckie"), "--help"], capture_output=True, text=True, check=True, timeout=60
    )
    for command in ("release", "grade", "formgrade", "feedback"):
        assert f"    {command} " in result.stdout or f"    {command}\n" in result.stdout


def test_no_modules_import_each_other():
    from import_graph import graph

    found = graph()
    assert found.circles() == []
    # Counting lazy imports and those for type hints too: every arrow points one way.
    assert found.circles(every=True) == []


def test_no_robot_module_reaches_a_laptop_package_in_any_way():
    # Not at load, not lazily, not for types, not by a name handed to importlib: the laptop's
    # libraries (cv_bridge, rosbag...) register in the entry point group the robot's code
    # reads (pyproject.toml), so the arrow points from the laptop to the robot.
    from import_graph import graph, robot_to_laptop

    assert robot_to_laptop(graph()) == []


def test_the_import_graph_sees_a_module_named_for_importlib():
    import ast

    from import_graph import _named_module

    calls = [
        'importlib.import_module("duckielib.libraries")',
        'import_module("duckielib.libraries.tf")',
        '__import__("duckielib.bags")',
        "importlib.import_module(name)",  # not a constant: nothing to follow
        'print("duckielib.bags")',
    ]
    found = [_named_module(ast.parse(call, mode="eval").body) for call in calls]
    assert found == ["duckielib.libraries", "duckielib.libraries.tf", "duckielib.bags", None, None]


def test_every_long_module_and_function_says_why():
    # The house's limits: a module over 600 lines or a function over 80 says at its top why
    # (where and how: tests/import_graph.py's docstring).
    from import_graph import graph, without_reason

    modules, functions = without_reason(graph())
    assert modules == []
    assert functions == []


def test_the_import_graph_reads_a_reason_only_where_it_belongs():
    import ast

    from import_graph import reason

    def module(source: str) -> str | None:
        return reason(source.splitlines(), ast.parse(source), 600)

    def function(source: str) -> str | None:
        return reason(source.splitlines(), ast.parse(source).body[-1], 80)

    assert module('"""Doc."""\n\n# Over 600 lines: one idea.\n\nimport os\n') == "one idea."
    assert module("# Over 600 lines: one idea,\n# said twice.\nimport os\n") == (
        "one idea, said twice."
    )
    assert module('"""Doc."""\n# Over 600 lines: no full stop\nimport os\n') is None
    assert module('"""Doc."""\nimport os\n# Over 600 lines: too late.\n') is None
    assert module('"""Doc."""\n# Over 80 lines: the wrong limit.\nimport os\n') is None
    body = '    """Doc.\n\n    More.\n    """\n    # Over 80 lines: one loop.\n    return 1\n'
    assert function(f"@decorated\ndef f(\n    a,\n):\n{body}") == "one loop."
    assert function("def f():\n    # Over 80 lines: one loop,\n    # for speed.\n    pass\n") == (
        "one loop, for speed."
    )
    assert function('def f():\n    """Doc."""\n    x = 1\n    # Over 80 lines: late.\n') is None
    assert function('# Over 80 lines: above.\ndef f():\n    """Doc."""\n') is None
    assert function('def f():\n    """Doc."""\n    # Over 80 lines: .\n    pass\n') is None


def test_the_served_libraries_are_the_ones_pyproject_registers():
    from importlib.metadata import entry_points

    from duckielib.libraries.duckietown_utils import DUCKIETOWN_UTILS_MODULES

    registered = {
        entry.name: entry.value for entry in entry_points(group="duckielib.ros_libraries")
    }
    libraries = sorted(
        path.stem for path in (ROOT / "duckielib" / "libraries").glob("*.py") if path.stem[0] != "_"
    )
    assert sorted({value.split(":")[0].rpartition(".")[2] for value in registered.values()}) == (
        libraries
    )
    assert {name for name in registered if name.startswith("duckietown_utils.")} == {
        f"duckietown_utils.{name}" for name in DUCKIETOWN_UTILS_MODULES
    }
