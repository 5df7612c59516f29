"""Whole Duckietown projects run unchanged by ``duckie run``, from any working folder.

``projects/square_project`` is written in the students' layout (Duckietown's template): two
catkin packages under ``packages/``, one with a Python package under ``include/`` (installed
by its ``setup.py``, as ``catkin_python_setup`` does), the other with its own ``msg/`` and
``srv/`` and the node that answers the service; launch files with arguments, a group in the
robot's namespace, an include with arguments, parameters chosen by ``if``/``unless``, a
``rosparam`` file and a remapping; launchers that ``roslaunch`` and ``rosrun``; and, in
``extras.launch``, what students' nodes do on a robot: record to ``/data/bags`` with rosbag's
API, time a controller with ``time.time()``, show the camera with ``cv2.imshow``.
"""

from __future__ import annotations

import json
import math
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np
import pytest

from duckielib.bags import Bag, pose_tracks
from duckielib.plots import ImageView
from duckielib.ros import uninstall_modules
from duckielib.tools.cli import main
from duckielib.tools.deploy import GENERATED, prepare
from duckielib.tools.deploy import PROJECT as ROBOT_PROJECT
from duckielib.tools.project import ProjectError, Workspace, launched_nodes, run_project
from duckielib.tools.project.image import image_environment

PROJECT = Path(__file__).resolve().parent / "projects" / "square_project"


@pytest.fixture(autouse=True)
def clean_imports(monkeypatch):
    monkeypatch.setenv("VEHICLE_NAME", "duckiebot")
    before = set(sys.modules)
    yield
    uninstall_modules()
    for name in set(sys.modules) - before:
        if name.split(".")[0] in ("rospy", "duckietown_msgs", "motion_msgs", "motion_control"):
            del sys.modules[name]


def travelled(bag_path):
    """How far the robot really drove in a run (m), from its bag's true poses."""
    (truth,) = [t for t in pose_tracks(Bag(bag_path), "record") if "ground_truth" in t.label]
    return math.hypot(truth.x[-1] - truth.x[0], truth.y[-1] - truth.y[0])


@pytest.mark.parametrize(
    "where", [".", "packages", "packages/motion_control", "packages/motion_msgs/src", "elsewhere"]
)
def test_the_project_runs_unchanged_from_any_working_folder(where, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path if where == "elsewhere" else PROJECT / where)
    run = run_project(PROJECT, out=tmp_path / "run", seconds=20)
    # The launcher roslaunches square.launch with side:=0.6; the launch file's group puts both
    # nodes under the robot, its include starts the side server with that side, and the
    # driver reads its speed (unless fast) and its gains (rosparam) and asks the server.
    assert run.nodes == {
        "/duckiebot/side_server": "running, stopped when the run ended",
        "/duckiebot/square_driver": "ended (required: the run ended with it)",
    }
    log = (tmp_path / "run" / "log.txt").read_text()
    assert "[/duckiebot/side_server]: side of a square asked" in log
    assert "[/duckiebot/square_driver]: drove 0.60 m at 0.2 m/s" in log
    # Its own message type recorded, its remapped commands driven by the robot: 0.6 m.
    assert run.topics["/duckiebot/square_driver/progress"] >= 25
    assert run.topics["/duckiebot/car_cmd_switch_node/cmd"] >= 25
    assert "/duckiebot/car_cmd" not in run.topics
    assert travelled(run.files["bag"]) == pytest.approx(0.6, abs=0.03)
    assert 3.0 < run.simulated < 3.6  # the run ended with the required node
    summary = json.loads(run.files["summary"].read_text())
    assert summary["nodes"] == run.nodes
    assert not any(name.endswith("image/compressed") for name in summary["topics"])
    # The project's packages were importable only during the run.
    assert "motion_msgs" not in sys.modules
    assert not any("square_project" in path for path in sys.path)


def test_a_launch_file_a_node_script_and_another_launcher_run_too(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    launch = PROJECT / "packages/motion_control/launch/square.launch"
    run = run_project(launch, out=tmp_path / "launch", seconds=20)
    assert travelled(run.files["bag"]) == pytest.approx(0.5, abs=0.03)  # the default side
    # rosrun of the server alone: it serves until the run's time is up.
    run = run_project(PROJECT, launcher="side-server", out=tmp_path / "server", seconds=2)
    assert run.nodes == {"/side_server": "still running after 2 s, stopped"}
    script = PROJECT / "packages/motion_msgs/src/side_server.py"
    assert launched_nodes(script)[1].nodes[0].script == script


def test_what_the_launch_files_say_is_read_as_roslaunch_reads_it(monkeypatch):
    workspace, launched = launched_nodes(PROJECT)
    assert sorted(workspace.packages) == ["motion_control", "motion_msgs"]
    assert workspace.find("motion_msgs") == PROJECT / "packages/motion_msgs"
    server, driver = launched.nodes
    assert (server.name, server.namespace, server.params) == (
        "side_server",
        "/duckiebot",
        {"side": 0.6},  # type="double", from the include's argument
    )
    # $(eval ...): Python on the arguments (strings), by name or with arg().
    assert driver.params == {
        "speed": 0.2,
        "long_side": True,
        "gains": {"k_omega": 2.0, "settle": 0.3},
    }
    assert driver.remap == {"car_cmd": "car_cmd_switch_node/cmd"}
    assert driver.required
    assert driver.where.endswith("square.launch, line 11")
    # $(env VEHICLE_NAME) and the arguments given on the launcher's line.
    monkeypatch.setenv("VEHICLE_NAME", "ente")
    _, launched = launched_nodes(PROJECT)
    assert {node.namespace for node in launched.nodes} == {"/ente"}


def test_a_project_that_cannot_run_is_said_with_its_file_and_line(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ProjectError, match=r"no launcher 'nope'; its launchers are: default, "):
        launched_nodes(PROJECT, launcher="nope")
    with pytest.raises(ProjectError, match=r"not inside a Duckietown project"):
        Workspace.around(tmp_path)
    broken = tmp_path / "broken"
    shutil.copytree(PROJECT, broken)
    launch = broken / "packages/motion_control/launch/square.launch"
    launch.write_text(launch.read_text().replace('output="screen"', 'output="screen'))
    with pytest.raises(ProjectError, match=r"square\.launch does not parse, line 11: "):
        launched_nodes(broken)
    launch.write_text(launch.read_text().replace('output="screen', 'output="screen"'))
    launch.write_text(launch.read_text().replace("$(arg side)", "$(arg sides)"))
    with pytest.raises(ProjectError, match=r"square\.launch, line 8 uses \$\(arg sides\)"):
        launched_nodes(broken)
    launch.write_text(launch.read_text().replace("$(arg sides)", "$(arg side)"))
    # A node that fails is said with its file and line; the others run on, as in roslaunch
    # (here the failing node is required, so the run ends with it).
    node = broken / "packages/motion_control/src/square_node.py"
    node.write_text(node.read_text().replace("import Progress", "import Progres"))
    run = run_project(broken, out=tmp_path / "run")
    (failure,) = run.failures
    assert failure.startswith(
        "The node square_driver stopped with ImportError at "
        "packages/motion_control/src/square_node.py, line 7: cannot import name 'Progres'"
    )
    assert run.nodes == {
        "/duckiebot/side_server": "running, stopped when the run ended",
        "/duckiebot/square_driver": "failed (its traceback is in log.txt)",
    }
    assert (tmp_path / "run" / "run.bag").is_file()  # closed whole, wheels stopped
    node.write_text(
        node.read_text().replace("import Progres\n", "import Progress\nimport tag_finder\n")
    )
    (broken / "dependencies-py3.txt").write_text("numpy\ntag-finder>=3.1  # the robot's\n")
    (failure,) = run_project(broken, out=tmp_path / "run2").failures
    assert failure.endswith(
        "No module named 'tag_finder'. The project lists tag-finder>=3.1 in "
        "dependencies-py3.txt, which dts devel build installs on the robot: install it here "
        "too, with '.venv/bin/pip install tag-finder>=3.1'."
    )
    node.write_text(node.read_text().replace("import tag_finder", "import image_geometry"))
    (broken / "dependencies-apt.txt").write_text("ros-noetic-image-geometry\n")
    (failure,) = run_project(broken, out=tmp_path / "run3").failures
    assert (
        "No module named 'image_geometry'. The project installs it on the robot from "
        "dependencies-apt.txt (ros-noetic-image-geometry), a ROS package the virtual "
        "Duckiebot does not serve" in failure
    )
    launcher = broken / "launchers/default.sh"
    launcher.write_text(launcher.read_text() + "dt-exec make everything\n")
    with pytest.raises(ProjectError, match=r"default\.sh, line 13 runs 'make'"):
        launched_nodes(broken)
    launcher.write_text(
        launcher.read_text().replace(
            "dt-exec make everything", "dt-exec roslaunch motion_control square.launch file"
        )
    )
    with pytest.raises(
        ProjectError,
        match=r"default\.sh, line 13: roslaunch takes its arguments as name:=value after the "
        r"package and the launch file, and 'file' is none",
    ):
        launched_nodes(broken)
    elsewhere = broken / "packages/motion_control/launch/elsewhere.launch"
    elsewhere.write_text('<launch>\n  <node pkg="move_robot" type="go.py" name="go"/>\n</launch>\n')
    with pytest.raises(
        ProjectError,
        match=r"elsewhere\.launch starts no node of the project\. .*elsewhere\.launch, line 2: "
        r"node go\.py of package move_robot is not in this project",
    ):
        launched_nodes(elsewhere)
    basic = tmp_path / "basic"
    (basic / "packages" / "my_code").mkdir(parents=True)
    (basic / "launchers").mkdir()
    (basic / ".dtproject").write_text("TYPE=template-basic\nTYPE_VERSION=2\n")
    with pytest.raises(ProjectError, match=r"is a Duckietown template-basic project"):
        launched_nodes(basic)


def test_duckie_run_prints_the_nodes_and_what_they_published(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", str(PROJECT), "--out", "out", "--seconds", "20"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("ran 2 node(s) for 3.")
    assert "  /duckiebot/square_driver/progress  " in out
    assert out.rstrip().endswith("wrote run.bag, log.txt, summary.json in out")
    assert main(["run", str(PROJECT), "-L", "nope"]) == 1
    assert "has no launcher 'nope'" in capsys.readouterr().err


def test_nodes_find_the_robots_data_its_clock_and_a_window(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    run = run_project(PROJECT, launcher="extras", out=tmp_path / "run", seconds=10)
    assert set(run.nodes.values()) == {"ended"}
    log = (tmp_path / "run" / "log.txt").read_text()
    # /data/bags/ticks.bag and /data/logs/ticks.txt land in the run's folder, whole.
    ticks = Bag(tmp_path / "run" / "data" / "bags" / "ticks.bag")
    assert ticks.topics["left_ticks"].count == 60  # 2 s at 30 Hz
    assert (tmp_path / "run" / "data" / "logs" / "ticks.txt").read_text() == "60 ticks\n"
    assert "[/duckiebot/tick_recorder]: recorded 60 ticks" in log
    # The host's name in node code is the robot's, as in its container; the laptop keeps its own.
    assert "[/duckiebot/tick_recorder]: recording on duckiebot (uname says duckiebot)" in log
    assert socket.gethostname() == os.uname()[1] != "duckiebot"
    assert not Path("/data/bags/ticks.bag").exists()
    # time.time() and perf_counter() in the node read the simulated clock: dt is the rate's.
    assert "[/duckiebot/heading_pid]: mean dt 0.100 s over 20 steps, 2.00 s in all" in log
    # cv2's window: the latest frame saved, said once.
    frame = cv2.imread(str(tmp_path / "run" / "windows" / "camera.png"))
    assert frame.shape == (480, 640, 3)
    assert "[/duckiebot/camera_viewer]: showed 5 frames, 0 AprilTags in them" in log
    assert run.notes == [
        "cv2.imshow shows no window here: each window's latest frame is saved in "
        f"{tmp_path / 'run' / 'windows'}, and all its frames are in run.bag on "
        "/cv2_windows/NAME/compressed."
    ]
    # ... and every frame in the bag, where a notebook's image view plays the window.
    shown = Bag(tmp_path / "run" / "run.bag").read("/cv2_windows/camera/compressed")
    assert len(shown) == run.topics["/cv2_windows/camera/compressed"] == 5
    assert cv2.imdecode(np.frombuffer(shown[0].message.data, np.uint8), 1).shape == (480, 640, 3)
    assert [item.time for item in shown] == sorted(item.time for item in shown)
    player = ImageView.from_bag(tmp_path / "run" / "run.bag")  # the window, not the camera
    caption = player.children[0].children[2].value
    assert caption.startswith("/cv2_windows/camera/compressed: frame 1 of 5, t = 0.03 s")
    assert "the nodes wrote 2 file(s) to the robot's /data" in run.text()
    # Outside the run, the wall clock, open() and cv2 are as they were.
    assert abs(time.time() - time.mktime(time.localtime())) < 2
    assert not hasattr(open, "__wrapped__")
    assert not hasattr(os.stat, "__wrapped__")
    assert cv2.imshow.__module__ in (None, "cv2")


def test_launcher_arguments_reach_an_undeclared_arg_and_shell_lines_are_read(tmp_path):
    # As roslaunch does: arguments given on the command line are there for $(arg ...) of the
    # launch file named, declared or not. A launcher's `if ... fi` around a roscore is shell.
    copy = tmp_path / "copy"
    shutil.copytree(PROJECT, copy)
    launcher = copy / "launchers/default.sh"
    launcher.write_text(
        launcher.read_text()
        .replace("side:=0.6", "side:=0.6 laps:=3 &")
        .replace(
            "# launching app\n",
            '# launching app\nif [[ -z "${VEHICLE_NAME}" ]]; then\n  roscore &\n  sleep 5\nfi\n',
        )
    )
    launch = copy / "packages/motion_control/launch/square.launch"
    launch.write_text(
        launch.read_text().replace(
            '<param name="speed" value="0.2"',
            '<param name="laps" value="$(arg laps)"/>\n      <param name="speed" value="0.2"',
        )
    )
    _, launched = launched_nodes(copy)
    assert launched.nodes[1].params["laps"] == 3


DRIVE_FOREVER = """\
#!/usr/bin/env python3
import os
import rospy
from duckietown_msgs.msg import WheelsCmdStamped

rospy.init_node("drive_forever")
topic = "/%s/wheels_driver_node/wheels_cmd" % os.environ["VEHICLE_NAME"]
pub = rospy.Publisher(topic, WheelsCmdStamped, queue_size=1)
rate = rospy.Rate(10)
while not rospy.is_shutdown():
    pub.publish(WheelsCmdStamped(vel_left=0.3, vel_right=0.3))
    rate.sleep()
"""


def small_project(root, package, scripts, launchers=()):
    """A project with one catkin package of node scripts, and launchers, written here."""
    folder = root / "packages" / package
    (folder / "src").mkdir(parents=True)
    (folder / "package.xml").write_text(
        f'<?xml version="1.0"?>\n<package format="2"><name>{package}</name><version>0.1.0'
        "</version><description>nodes</description><maintainer email='a@b.c'>a</maintainer>"
        "<license>MIT</license><buildtool_depend>catkin</buildtool_depend></package>\n"
    )
    for name, text in scripts.items():
        (folder / "src" / name).write_text(text)
    (root / "launchers").mkdir()
    for name, text in dict(launchers).items():
        (root / "launchers" / name).write_text(text)
    return folder


def test_ctrl_c_stops_a_run_with_its_wheels_at_zero_and_its_files_whole(tmp_path):
    package = small_project(tmp_path / "project", "driver", {"drive_forever.py": DRIVE_FOREVER})
    script = package / "src" / "drive_forever.py"
    out = tmp_path / "run"
    command = [sys.executable, "-m", "duckielib.tools.cli", "run", str(script)]
    process = subprocess.Popen(
        [*command, "--seconds", "1e6", "--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    recording = out / "run.bag.active"
    deadline = time.monotonic() + 60
    while not (recording.exists() and recording.stat().st_size > 200_000):
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "the run never started recording"
        time.sleep(0.1)
    process.send_signal(signal.SIGINT)
    stdout, stderr = process.communicate(timeout=60)
    assert process.returncode == 130, stderr
    assert stderr.strip() == "duckie: interrupted."
    assert "stopped by Ctrl-C:" in stdout.splitlines()[0]
    assert "/drive_forever  running, stopped by Ctrl-C" in stdout
    assert "the wheels were stopped: duty cycles 0, 0 at the end" in stdout
    summary = json.loads((out / "summary.json").read_text())
    assert summary["interrupted"] is True
    assert summary["wheels_at_end"] == [0.0, 0.0]
    assert not recording.exists()
    bag = Bag(out / "run.bag")
    commands = bag.read("/duckiebot/wheels_driver_node/wheels_cmd")
    assert len(commands) == summary["topics"]["/duckiebot/wheels_driver_node/wheels_cmd"] > 100
    assert commands[-1].message.vel_left == pytest.approx(0.3)
    assert bag.check() is None


DOCKERFILE = """\
ARG REPO_NAME="demo"
ARG REPO_PATH="${CATKIN_WS_DIR}/src/${REPO_NAME}"
FROM duckietown/dt-ros-commons:daffy-arm64v8
ENV DT_MODULE_TYPE="${REPO_NAME}"
ENV DT_REPO_PATH="${REPO_PATH}"
COPY ./config /code/config
COPY ./deploy/. /code/course
# the library and the model, where the nodes find them
ENV PYTHONPATH=/code/course${PYTHONPATH:+:${PYTHONPATH}}
ENV GAINS=/code/config/gains.yaml \\
    MODE=fast
ENV MODEL /code/course/model.onnx
ENV ROS_SHARE=/opt/ros/noetic/share
"""


def test_the_dockerfiles_env_is_set_with_the_image_paths_turned_into_the_projects(tmp_path):
    (tmp_path / "Dockerfile").write_text(DOCKERFILE)
    (tmp_path / "config").mkdir()
    (tmp_path / "config" / "gains.yaml").write_text("k: 1\n")
    (tmp_path / "deploy").mkdir()
    image = image_environment(tmp_path)
    assert image.variables == {
        "DT_MODULE_TYPE": "demo",
        "GAINS": str(tmp_path / "config" / "gains.yaml"),
        "MODE": "fast",
        "MODEL": str(tmp_path / "deploy" / "model.onnx"),
    }  # DT_REPO_PATH (the base image's variable) and /opt/ros (not the project's) are left out
    assert image.python_path == [tmp_path / "deploy"]
    assert image.notes == [
        "the Dockerfile sets MODEL=/code/course/model.onnx, the project's deploy/model.onnx in "
        "the image, which does not exist yet."
    ]
    with image.applied():
        assert os.environ["GAINS"] == str(tmp_path / "config" / "gains.yaml")
        assert sys.path[-1] == str(tmp_path / "deploy")
    assert "GAINS" not in os.environ
    assert str(tmp_path / "deploy") not in sys.path


def test_the_courses_own_robot_project_runs_as_its_image_runs_it(tmp_path):
    # robot_nodes/ as a student has it after `duckie robot prepare`: its nodes find the
    # solution through the Dockerfile's DUCKIE_SOLUTION, and take the virtual robot's rospy.
    project = tmp_path / "robot_nodes"
    shutil.copytree(ROBOT_PROJECT, project, ignore=shutil.ignore_patterns(*GENERATED))
    unprepared = run_project(project, launcher="straight", out=tmp_path / "unprepared")
    assert unprepared.failures[0] == (
        "The node odometry_node exited with status 1 at "
        "packages/course_nodes/src/odometry_node.py, line 17 (it said why above)."
    )
    assert unprepared.notes[-1] == (
        "the Dockerfile sets DUCKIE_SOLUTION=/code/course/solution.py, the project's "
        "deploy/solution.py in the image, which does not exist yet."
    )
    prepare(project=project, quiet=True)
    run = run_project(project, launcher="straight", seconds=60, out=tmp_path / "run")
    assert run.nodes["/duckiebot/mission_node"] == "ended (required: the run ended with it)"
    states = [m.message.data for m in Bag(run.files["bag"]).read("/duckiebot/mission_node/state")]
    assert states[0] == "wait"
    assert states[-1] == "done"
    (truth,) = [
        t for t in pose_tracks(Bag(run.files["bag"]), "record") if "ground_truth" in t.label
    ]
    farthest = max(math.hypot(x - truth.x[0], y - truth.y[0]) for x, y in zip(truth.x, truth.y))
    assert farthest == pytest.approx(1.25, abs=0.05)  # the task: 1.25 m out, then back
    assert "DUCKIE_SOLUTION" not in os.environ


CHORES = {
    "count_up.py": """\
import os
import sys
import rospy
from std_msgs.msg import Int32

rospy.init_node("count_up")
rospy.loginfo("side %s, %s", sys.argv[1], os.environ["GREETING"])
pub = rospy.Publisher("count", Int32, queue_size=10)
rate = rospy.Rate(10)
for n in range(30):
    pub.publish(n)
    rate.sleep()
""",
    "cable_check.py": """\
import rospy

rospy.init_node("cable_check")
rospy.sleep(1.0)
raise RuntimeError("the left cable is loose")
""",
    "after_check.py": """\
import rospy

rospy.init_node("after_check")
rospy.loginfo("started at %.1f s", rospy.get_time())
with open("after_check.txt", "w") as out:  # relative: the container's working folder
    out.write("checked")
""",
}

CHORES_LAUNCHER = """\
#!/bin/bash
source /environment.sh
dt-launchfile-init
SIDE=${SQUARE_SIDE:-0.5}
export GREETING="hello from ${VEHICLE_NAME}"
dt-exec rosrun chores count_up.py $SIDE
rosrun chores cable_check.py
rosrun chores after_check.py
dt-launchfile-join
"""


def test_launcher_lines_run_as_bash_runs_them_and_a_failed_node_leaves_the_others(
    tmp_path, capsys, monkeypatch
):
    monkeypatch.chdir(tmp_path)
    # ${VAR:-default}, a variable of the launcher and one it exports; dt-exec runs in the
    # background, a plain line in the foreground: the next line waits for it. A node that
    # fails is said with its file and line, and the others run on, as under roslaunch.
    project = tmp_path / "chores"
    small_project(project, "chores", CHORES, {"default.sh": CHORES_LAUNCHER})
    run = run_project(project, out=tmp_path / "run", seconds=10)
    assert run.failures == [
        "The node cable_check stopped with RuntimeError at "
        "packages/chores/src/cable_check.py, line 5: the left cable is loose."
    ]
    assert run.nodes == {
        "/count_up": "ended",
        "/cable_check": "failed (its traceback is in log.txt)",
        "/after_check": "ended",
    }
    assert run.topics["/count"] == 30
    assert run.simulated == pytest.approx(3.0)  # 30 messages at 10 Hz, the last sleep included
    log = (tmp_path / "run" / "log.txt").read_text()
    assert "[/count_up]: side 0.5, hello from duckiebot" in log
    assert "[/after_check]: started at 1.0 s" in log
    assert (tmp_path / "run" / "after_check.txt").read_text() == "checked"
    assert not Path("after_check.txt").exists()
    assert "GREETING" not in os.environ
    assert "SIDE" not in os.environ
    # The command prints the run, then the failure, and exits with 1.
    assert main(["run", str(project), "--out", str(tmp_path / "run2")]) == 1
    out, err = capsys.readouterr()
    assert "failed: The node cable_check stopped with RuntimeError" in out
    assert err.strip() == f"duckie: {run.failures[0]}"


HELPERS = {
    "ask.py": """\
import rospy
from std_srvs.srv import Trigger

rospy.init_node("ask")
rospy.wait_for_service("/answer")
rospy.loginfo("answer: %s", rospy.ServiceProxy("/answer", Trigger)().message)
""",
    "answer.py": """\
import rospy
from std_srvs.srv import Trigger, TriggerResponse

rospy.init_node("answer")
rospy.Service("/answer", Trigger, lambda request: TriggerResponse(True, "forty-two"))
rospy.spin()
""",
}


def test_two_launchers_run_together_and_a_node_left_waiting_says_for_what(tmp_path):
    # On a robot, two `dts devel run -L ...` containers share the robot: one node waits for
    # a service the other launcher's node offers.
    project = tmp_path / "helpers"
    small_project(
        project,
        "helpers",
        HELPERS,
        {
            "asker.sh": "#!/bin/bash\ndt-exec rosrun helpers ask.py\n",
            "answerer.sh": "#!/bin/bash\ndt-exec rosrun helpers answer.py\n",
        },
    )
    alone = run_project(project, launcher="asker", out=tmp_path / "alone", seconds=5)
    assert alone.nodes == {"/ask": "still waiting for service /answer since 0.0 s, stopped"}
    both = run_project(project, launcher=["answerer", "asker"], out=tmp_path / "both", seconds=5)
    assert both.nodes == {
        "/answer": "still running after 5 s, stopped",
        "/ask": "ended",
    }
    assert "[/ask]: answer: forty-two" in (tmp_path / "both" / "log.txt").read_text()
