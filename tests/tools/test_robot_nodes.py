"""``robot_nodes/``, the Duckietown project for the robot, and ``duckie robot prepare``.

The project's files are checked statically (no Docker, no robot): every path the image copies
exists or is written by ``prepare``, the launchers follow Duckietown's pattern and start launch
files that exist, every node a launch file names is an executable script of ``course_nodes``,
and the catkin package agrees with itself. ``prepare`` runs for real into a copy of the
project, and what it deploys must import with every laptop-only package blocked and pass the
Python 3.8 check.
"""

from __future__ import annotations

import ast
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest
from test_purity import BLOCKER, LAPTOP_ONLY, vermin_38

from duckielib.errors import DuckielibError
from duckielib.missions import MISSIONS
from duckielib.solution import SolutionError, export_solution, reference_solution_dir
from duckielib.tools.deploy import prepare, robot_module_files

ROOT = Path(__file__).resolve().parents[2]
PROJECT = ROOT / "robot_nodes"
PACKAGE = PROJECT / "packages" / "course_nodes"
LAUNCH = PACKAGE / "launch"
SCRIPTS = PACKAGE / "src"
LAUNCHERS = sorted((PROJECT / "launchers").glob("*.sh"))
LAUNCH_FILES = sorted(LAUNCH.glob("*.launch"))
#: What the project's ``prepare`` writes, relative to the project; the Dockerfile may copy it.
PREPARED = ("deploy",)
#: The laptop-only packages, less rospy: a robot has a real one.
ROBOT_BLOCKED = tuple(name for name in LAPTOP_ONLY if name != "rospy")
#: The modules the robot's nodes import from the deployed library.
DEPLOYED_MODULES = ("duckielib.nodes.mains", "duckielib.nodes.course", "duckielib.nodes.safety")


def dockerfile_instructions() -> list[tuple[str, str]]:
    """The Dockerfile's instructions as (KEYWORD, arguments), continuation lines joined."""
    text = (PROJECT / "Dockerfile").read_text()
    text = re.sub(r"\\\n", " ", text)
    instructions = []
    for line in (raw.strip() for raw in text.splitlines()):
        if line and not line.startswith("#"):
            keyword, _, arguments = line.partition(" ")
            instructions.append((keyword.upper(), arguments.strip()))
    return instructions


def copied_sources() -> list[str]:
    sources = []
    for keyword, arguments in dockerfile_instructions():
        if keyword == "COPY":
            words = [word.strip('"') for word in arguments.split()]
            sources.extend(word for word in words[:-1] if not word.startswith("--"))
    return sources


def dtproject() -> dict[str, str]:
    fields = {}
    for line in (raw.strip() for raw in (PROJECT / ".dtproject").read_text().splitlines()):
        if line and not line.startswith("#"):
            key, _, value = line.partition("=")
            fields[key.strip()] = value.strip()
    return fields


def roslaunch_line(launcher: Path) -> list[str]:
    lines = [line for line in launcher.read_text().splitlines() if "roslaunch" in line]
    assert len(lines) == 1, f"{launcher.name} should run roslaunch exactly once"
    words = lines[0].split()
    assert words[:2] == ["dt-exec", "roslaunch"], f"{launcher.name}: {lines[0]}"
    return words[2:]


# --- The Duckietown project -----------------------------------------------------------------


def test_dtproject_is_template_ros_v3():
    fields = dtproject()
    # The keys `dts devel` requires of a format-3 project.
    assert fields["TYPE"] == "template-ros"
    assert fields["TYPE_VERSION"] == "3"
    assert re.fullmatch(r"\d+\.\d+\.\d+", fields["VERSION"])


def test_project_has_the_template_files():
    for name in (
        ".dtproject",
        "Dockerfile",
        "configurations.yaml",
        "dependencies-apt.txt",
        "dependencies-py3.txt",
        "launchers/default.sh",
        ".gitignore",
    ):
        assert (PROJECT / name).is_file(), f"robot_nodes/{name} is missing"


def test_dockerfile_builds_on_dt_ros_commons_daffy():
    instructions = dockerfile_instructions()
    arguments: dict[str, str | None] = {}
    for keyword, value in instructions:
        if keyword == "ARG":  # the first ARG of a name sets its default; later ones recall it
            name, equals, default = value.partition("=")
            arguments.setdefault(name, default.strip('"') if equals else None)
    for name in ("REPO_NAME", "DESCRIPTION", "MAINTAINER", "ICON", "ARCH", "BASE_TAG"):
        assert name in arguments, f"the Dockerfile has no ARG {name}"
    assert arguments["DISTRO"] == "daffy"
    assert arguments["BASE_IMAGE"] == "dt-ros-commons"
    assert arguments["LAUNCHER"] == "default"
    assert arguments["BASE_TAG"] == "${DISTRO}-${ARCH}"
    [base] = [value for keyword, value in instructions if keyword == "FROM"]
    assert base.split()[0].endswith("/duckietown/${BASE_IMAGE}:${BASE_TAG}")
    commands = " ".join(value for keyword, value in instructions if keyword == "RUN")
    assert "dt-apt-install ${REPO_PATH}/dependencies-apt.txt" in commands
    assert "pip3 install -r ${REPO_PATH}/dependencies-py3.txt" in commands
    assert "catkin build" in commands
    assert 'dt-install-launchers "${LAUNCH_PATH}"' in commands
    assert ("CMD", '["bash", "-c", "dt-launcher-${DT_LAUNCHER}"]') in instructions
    labels = " ".join(value for keyword, value in instructions if keyword == "LABEL")
    for label in ("module.type", "architecture", "code.version.distro", "base.image"):
        assert f"org.duckietown.label.{label}=" in labels


def test_dockerfile_copies_packages_into_the_catkin_workspace():
    instructions = dockerfile_instructions()
    assert ("ARG", 'REPO_PATH="${CATKIN_WS_DIR}/src/${REPO_NAME}"') in instructions
    assert ("COPY", './packages "${REPO_PATH}/packages"') in instructions


def test_dockerfile_carries_the_course_code():
    instructions = dockerfile_instructions()
    assert ("COPY", "./deploy /code/course") in instructions
    environment = [value for keyword, value in instructions if keyword == "ENV"]
    assert "DUCKIE_SOLUTION=/code/course/solution.py" in environment
    [python_path] = [value for value in environment if value.startswith("PYTHONPATH=")]
    assert python_path.startswith("PYTHONPATH=/code/course")
    text = (PROJECT / "Dockerfile").read_text()
    assert "duckie robot prepare" in text, "the Dockerfile must say what fills ./deploy/"


def test_every_path_the_dockerfile_copies_exists_or_is_prepared():
    sources = copied_sources()
    assert sources, "the Dockerfile copies nothing"
    for source in sources:
        relative = Path(source.rstrip("."))
        if relative.parts and relative.parts[0] in PREPARED:
            continue
        assert (PROJECT / relative).exists(), f"the Dockerfile copies {source}, which is missing"


def test_dockerignore_lets_every_copied_path_into_the_build_context():
    allowed = [
        line[1:].strip().rstrip("/")
        for line in (PROJECT / ".dockerignore").read_text().splitlines()
        if line.startswith("!")
    ]
    for source in copied_sources():
        top = Path(source.rstrip(".")).parts[0]
        assert top in allowed, f".dockerignore keeps {top} out of the build context"


def test_deploy_is_git_ignored():
    lines = (PROJECT / ".gitignore").read_text().splitlines()
    assert "/deploy/" in lines


def test_dependencies_are_numpy_only():
    def packages(name):
        text = (PROJECT / name).read_text()
        return [line.strip() for line in text.splitlines() if line.strip()[:1] not in ("", "#")]

    assert packages("dependencies-py3.txt") == ["numpy"]
    assert packages("dependencies-apt.txt") == []


def test_configurations_has_a_default():
    text = (PROJECT / "configurations.yaml").read_text()
    assert re.search(r"^configurations:\s*$", text, re.MULTILINE)
    assert re.search(r"^  default:\s*$", text, re.MULTILINE)


# --- Launchers ------------------------------------------------------------------------------


def test_the_launchers_are_the_ones_documented():
    assert [path.name for path in LAUNCHERS] == [
        "d-shape.sh",
        "default.sh",
        "rotation.sh",
        "square-then-circle.sh",
        "straight.sh",
    ]


@pytest.mark.parametrize("launcher", LAUNCHERS, ids=lambda path: path.name)
def test_launcher_follows_the_duckietown_pattern(launcher):
    assert os.access(launcher, os.X_OK), f"{launcher.name} is not executable (chmod +x)"
    lines = [line.strip() for line in launcher.read_text().splitlines()]
    assert lines[0] == "#!/bin/bash"
    code = [line for line in lines if line and not line.startswith("#")]
    assert code[0] == "source /environment.sh"
    assert code[1] == "dt-launchfile-init"
    assert code[-1] == "dt-launchfile-join"
    # Between them: dt-exec lines, and shell variables they use (BAG=...).
    assert all(line.startswith("dt-exec ") or "=" in line.split()[0] for line in code[2:-1])
    assert any(line.startswith("dt-exec ") for line in code[2:-1])


@pytest.mark.parametrize("launcher", LAUNCHERS, ids=lambda path: path.name)
def test_launcher_starts_an_existing_launch_file_with_a_valid_mission(launcher):
    package, launch_file, *arguments = roslaunch_line(launcher)
    assert package == PACKAGE.name
    assert (LAUNCH / launch_file).is_file(), f"{launcher.name} starts a missing {launch_file}"
    values = dict(argument.split(":=", 1) for argument in arguments)
    assert values["veh"] == '"$VEHICLE_NAME"'
    assert values["mission"] in MISSIONS
    declared = {arg.get("name") for arg in ET.parse(LAUNCH / launch_file).iter("arg")}
    assert set(values) <= declared


def test_launchers_drive_the_documented_missions():
    missions = {
        path.stem: dict(a.split(":=", 1) for a in roslaunch_line(path)[2:]) for path in LAUNCHERS
    }
    assert missions["default"]["mission"] == "square_then_circle"
    assert missions["square-then-circle"]["mission"] == "square_then_circle"
    assert missions["d-shape"]["mission"] == "d_shape"
    assert missions["straight"]["mission"] == "straight"
    assert missions["rotation"]["mission"] == "rotation"


# --- The catkin package ---------------------------------------------------------------------


def test_package_names_agree():
    manifest = ET.parse(PACKAGE / "package.xml").getroot()
    assert manifest.get("format") == "2"
    assert manifest.findtext("name") == PACKAGE.name
    project = re.search(r"^project\((\w+)\)", (PACKAGE / "CMakeLists.txt").read_text(), re.M)
    assert project is not None
    assert project.group(1) == PACKAGE.name


def test_package_declares_what_the_nodes_use():
    manifest = ET.parse(PACKAGE / "package.xml").getroot()
    assert manifest.findtext("buildtool_depend") == "catkin"
    depends = {element.text for element in manifest.iter("exec_depend")}
    assert {"rospy", "std_msgs", "sensor_msgs", "duckietown_msgs"} <= depends


def test_cmakelists_installs_every_script():
    text = (PACKAGE / "CMakeLists.txt").read_text()
    block = re.search(r"catkin_install_python\(PROGRAMS(.*?)DESTINATION", text, re.S)
    assert block is not None, "CMakeLists.txt has no catkin_install_python(PROGRAMS ...)"
    installed = set(block.group(1).split())
    scripts = {f"src/{path.name}" for path in SCRIPTS.iterdir() if path.suffix == ".py"}
    assert installed == scripts
    assert "${CATKIN_PACKAGE_BIN_DESTINATION}" in text[block.end() :].split(")")[0]


@pytest.mark.parametrize("script", sorted(SCRIPTS.glob("*.py")), ids=lambda path: path.name)
def test_script_is_a_thin_executable(script):
    assert os.access(script, os.X_OK), f"{script.name} is not executable (chmod +x)"
    text = script.read_text()
    assert text.startswith("#!/usr/bin/env python3\n")
    tree = ast.parse(text)
    assert ast.get_docstring(tree), f"{script.name} needs a docstring"
    body = tree.body[1:]
    assert len(body) == 2, f"{script.name}: one import and the __main__ guard"
    imported, guard = body
    assert isinstance(imported, ast.ImportFrom)
    assert imported.module.startswith("duckielib.")
    assert isinstance(guard, ast.If)
    assert ast.unparse(guard.test) == "__name__ == '__main__'"
    [call] = guard.body
    assert ast.unparse(call) == f"{imported.names[0].name}()"


def test_scripts_call_the_library_mains():
    expected = {
        "odometry_node.py": ("duckielib.nodes.mains", "odometry_main"),
        "light_service_node.py": ("duckielib.nodes.mains", "light_service_main"),
        "mission_node.py": ("duckielib.nodes.mains", "mission_main"),
        "camera_republisher_node.py": ("duckielib.nodes.mains", "camera_republisher_main"),
        "virtual_duckiebot_node.py": ("duckielib.sim.ros_node", "main"),
    }
    found = {}
    for script in SCRIPTS.glob("*.py"):
        match = re.search(r"^from ([\w.]+) import (\w+)$", script.read_text(), re.M)
        assert match is not None, script.name
        found[script.name] = match.groups()
    assert found == expected


# --- Launch files ---------------------------------------------------------------------------


def test_the_launch_files_are_there():
    assert [path.name for path in LAUNCH_FILES] == [
        "course.launch",
        "simulation.launch",
        "virtual_duckiebot.launch",
    ]


@pytest.mark.parametrize("launch_file", LAUNCH_FILES, ids=lambda path: path.name)
def test_launch_file_nodes_are_executable_scripts_of_the_package(launch_file):
    root = ET.parse(launch_file).getroot()
    assert root.tag == "launch"
    for node in root.iter("node"):
        if node.get("pkg") == "rosbag":  # ROS's own recorder, installed with ROS
            assert node.get("type") == "record", f"{launch_file.name}: {node.attrib}"
            continue
        assert node.get("pkg") == PACKAGE.name, f"{launch_file.name}: {node.attrib}"
        script = SCRIPTS / node.get("type")
        assert script.is_file(), f"{launch_file.name} starts a missing {script.name}"
        assert os.access(script, os.X_OK), f"{script.name} is not executable"
        assert node.get("output") == "screen"
    for include in root.iter("include"):
        prefix = f"$(find {PACKAGE.name})/"
        assert include.get("file").startswith(prefix)
        assert (PACKAGE / include.get("file")[len(prefix) :]).is_file()


def _args(launch_file):
    return {arg.get("name"): arg.get("default") for arg in ET.parse(launch_file).iter("arg")}


def test_course_launch():
    root = ET.parse(LAUNCH / "course.launch").getroot()
    assert _args(LAUNCH / "course.launch") == {
        "veh": "$(optenv VEHICLE_NAME duckiebot)",
        "mission": "square_then_circle",
        "stop_color": "RED",
        "camera": "true",
        "bag": "",
    }
    [group] = root.findall("group")
    assert group.get("ns") == "$(arg veh)"
    nodes = {node.get("name"): node for node in group.iter("node")}
    assert {name: node.get("type") for name, node in nodes.items()} == {
        "odometry_node": "odometry_node.py",
        "light_service_node": "light_service_node.py",
        "mission_node": "mission_node.py",
        "camera_republisher_node": "camera_republisher_node.py",
        "course_recorder": "record",
    }
    assert "/$(arg veh)/odometry_node/pose" in nodes["course_recorder"].get("args")
    assert nodes["course_recorder"].get("if") == "$(eval bag != '')"
    mission = nodes["mission_node"]
    assert mission.get("required") == "true"
    params = {param.get("name"): param.get("value") for param in mission.iter("param")}
    assert params == {"mission": "$(arg mission)", "stop_color": "$(arg stop_color)"}
    assert nodes["camera_republisher_node"].get("if") == "$(arg camera)"


def test_virtual_duckiebot_launch():
    root = ET.parse(LAUNCH / "virtual_duckiebot.launch").getroot()
    defaults = {
        "veh": "duckiebot",
        "noise": "ideal",
        "seed": "0",
        "rate": "1.0",
        "mission": "square_then_circle",
        "paused": "false",
    }
    assert defaults.items() <= _args(LAUNCH / "virtual_duckiebot.launch").items()
    [sim_time] = [param for param in root.findall("param") if param.get("name") == "/use_sim_time"]
    assert sim_time.get("value") == "true"
    [node] = root.findall("node")
    assert (node.get("name"), node.get("ns")) == ("virtual_duckiebot", "$(arg veh)")
    params = {param.get("name"): param.get("value") for param in node.iter("param")}
    for name in ("noise", "seed", "rate", "mission", "paused"):
        assert params[name] == f"$(arg {name})"


def test_simulation_launch_passes_the_same_robot_and_mission_to_both():
    root = ET.parse(LAUNCH / "simulation.launch").getroot()
    included = {}
    for include in root.iter("include"):
        values = {arg.get("name"): arg.get("value") for arg in include.iter("arg")}
        included[Path(include.get("file")).name] = values
    assert set(included) == {"virtual_duckiebot.launch", "course.launch"}
    for values in included.values():
        assert values["veh"] == "$(arg veh)"
        assert values["mission"] == "$(arg mission)"
    assert included["virtual_duckiebot.launch"]["paused"] == "$(arg paused)"
    paused = [arg.get("default") for arg in root.findall("arg") if arg.get("name") == "paused"]
    assert paused == ["false"]


@pytest.mark.ros
def test_roslaunch_reads_the_launch_files():
    if shutil.which("roslaunch") is None:
        pytest.skip("Debian's ROS 1 packages are not installed; run `make ros`.")
    env = dict(os.environ, ROS_PACKAGE_PATH=str(PROJECT / "packages"), VEHICLE_NAME="bot")
    result = subprocess.run(
        ["roslaunch", "--nodes", PACKAGE.name, "simulation.launch", "camera:=false"],
        capture_output=True,
        text=True,
        env=env,
        timeout=60,
        check=False,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert result.stdout.split() == [
        "/bot/virtual_duckiebot",
        "/bot/odometry_node",
        "/bot/light_service_node",
        "/bot/mission_node",
    ]


# --- duckie robot prepare -------------------------------------------------------------------


def copy_project(folder: Path) -> Path:
    project = folder / "robot_nodes"
    shutil.copytree(PROJECT, project, ignore=shutil.ignore_patterns("deploy", "deploy.*"))
    return project


@pytest.fixture(scope="module")
def prepared(tmp_path_factory):
    """A copy of the project, prepared with the reference solution in a separate process.

    A process of its own: generating the message packages puts Debian's ROS on ``sys.path``.
    """
    project = copy_project(tmp_path_factory.mktemp("prepared"))
    result = subprocess.run(
        [
            sys.executable,
            "-c",
            f"from duckielib.tools.deploy import prepare; prepare(project={str(project)!r})",
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    return project, result.stdout


def test_prepare_writes_the_library_and_the_solution(prepared):
    project, output = prepared
    deploy = project / "deploy"
    assert (deploy / "solution.py").is_file()
    assert "def mission_node(" in (deploy / "solution.py").read_text()
    for relative in robot_module_files():
        assert (deploy / relative).read_bytes() == (ROOT / relative).read_bytes()
    for module in DEPLOYED_MODULES:
        assert (deploy / (module.replace(".", "/") + ".py")).is_file()
    assert (
        deploy / "duckielib/messages/definitions/duckietown_msgs/msg/Pose2DStamped.msg"
    ).is_file()
    assert not list(deploy.rglob("__pycache__"))
    assert not (project / "deploy.tmp").exists()
    assert not (deploy / "duckielib" / "sim").exists()
    assert "dts devel build -f -H ROBOT" in output
    assert "dts devel run -H ROBOT" in output
    for source in copied_sources():
        assert (project / source).exists(), f"after prepare, {source} is still missing"


def test_prepared_library_imports_with_laptop_packages_blocked(prepared):
    project, _ = prepared
    deploy = project / "deploy"
    script = BLOCKER.format(blocked=LAPTOP_ONLY, modules=list(DEPLOYED_MODULES)) + (
        "import os\n"
        f"deploy = {str(deploy)!r}\n"
        # On the robot, rospy is the real one; here the in-process one stands in for it.
        "class Robot(importlib.abc.MetaPathFinder):\n"
        "    def find_spec(self, name, path=None, target=None):\n"
        f"        if name.split('.')[0] in {ROBOT_BLOCKED!r}:\n"
        "            raise ImportError('blocked laptop-only package: ' + name)\n"
        "sys.meta_path[0] = Robot()\n"
        "from duckielib.solution import MISSION_PARTS, load_solution\n"
        "load_solution(os.path.join(deploy, 'solution.py'), required=MISSION_PARTS)\n"
        # A module missing from deploy/ must not be found in the repository instead.
        "stray = sorted(name for name, module in sys.modules.items()\n"
        "               if name.split('.')[0] == 'duckielib'\n"
        "               and not (getattr(module, '__file__', None) or deploy).startswith(deploy))\n"
        "assert not stray, 'imported from outside deploy/: ' + ', '.join(stray)\n"
        "print('loaded')\n"
    )
    result = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        env=dict(os.environ, PYTHONPATH=str(deploy)),
        cwd=deploy,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["ok", "loaded"]


def test_prepared_code_runs_on_python_3_8(prepared):
    project, _ = prepared
    result = vermin_38(project / "deploy")
    assert result.returncode == 0, result.stdout + result.stderr


def test_prepare_refuses_an_unfinished_solution_and_keeps_the_old_deploy(tmp_path):
    project = copy_project(tmp_path)
    old = project / "deploy" / "solution.py"
    old.parent.mkdir()
    old.write_text("# the solution deployed before\n")
    with pytest.raises(SolutionError, match=r"^Finish notebook 05_odometry: write delta_phi"):
        prepare(solution=ROOT / "course", project=project, quiet=True)
    assert [path.name for path in (project / "deploy").iterdir()] == ["solution.py"]
    assert old.read_text() == "# the solution deployed before\n"
    assert not (project / "deploy.tmp").exists()


def test_prepare_copies_a_solution_file_and_replaces_the_old_deploy(tmp_path):
    project = copy_project(tmp_path)
    stale = project / "deploy" / "stale.txt"
    stale.parent.mkdir()
    stale.write_text("from an older prepare\n")
    module = tmp_path / "mine.py"
    module.write_text(export_solution(reference_solution_dir()).source)
    result = duckie("robot", "prepare", "--solution", str(module), "--project", str(project))
    assert result.returncode == 0, result.stderr
    assert (project / "deploy" / "solution.py").read_bytes() == module.read_bytes()
    assert not stale.exists()
    assert f"a copy of {module}" in result.stdout


def test_prepare_refuses_syntax_newer_than_the_robots_python(tmp_path):
    project = copy_project(tmp_path)
    module = tmp_path / "newer.py"
    module.write_text(
        export_solution(reference_solution_dir()).source
        + "\n\ndef label(x):\n    match x:\n        case 1:\n            return 'one'\n"
    )
    with pytest.raises(SolutionError, match=r"newer than 3\.8 \(line \d+"):
        prepare(solution=module, project=project, quiet=True)
    assert not (project / "deploy").exists()


def test_prepare_refuses_a_folder_that_is_not_a_project(tmp_path):
    with pytest.raises(DuckielibError, match="is not a Duckietown project"):
        prepare(project=tmp_path, quiet=True)


# --- The command ----------------------------------------------------------------------------


def duckie(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "duckielib.tools.cli", *args],
        capture_output=True,
        text=True,
        cwd=ROOT,
        timeout=300,
        check=False,
    )


def test_cli_prepare_with_an_unfinished_course_is_one_sentence(tmp_path):
    project = copy_project(tmp_path)
    result = duckie("robot", "prepare", "--solution", "course", "--project", str(project))
    assert result.returncode == 1
    assert result.stdout == ""
    assert result.stderr.startswith("duckie: Finish notebook 05_odometry: ")
    assert result.stderr.count("\n") == 1
    assert "Traceback" not in result.stderr
    assert not (project / "deploy").exists()


def test_cli_prepare_without_a_project_is_one_sentence(tmp_path):
    result = duckie("robot", "prepare", "--project", str(tmp_path))
    assert result.returncode == 1
    assert result.stderr == (
        f"duckie: {tmp_path} is not a Duckietown project (it needs .dtproject and a "
        "Dockerfile); give the course's robot_nodes/ folder.\n"
    )
