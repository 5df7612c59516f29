"""The rules an answer keeps, read from notebooks: no answer from the library, no call doing it.

Each case starts from the release filled with the reference answers (as a student who solved
everything hands it in), changes one answer or adds cells, and checks what
:func:`broken_rules` says, sentence for sentence. Nothing is run: the checker only reads.
"""

from __future__ import annotations

import functools
from typing import Any, Dict, List, Mapping, Optional, Sequence

import nbformat
import pytest

from autograder.bench import filled_notebook
from autograder.course import ROOT
from autograder.rules import FORBIDDEN, broken_rules, graded_names

NOTEBOOKS = sorted(path.name for path in (ROOT / "solutions").iterdir() if path.is_dir())
WHY = "write the computation yourself (notebook 01 says why)"
#: What notebook 03's answers say when they take the simulator's heading wrap.
HEADING_OF = f"wrap_angle uses duckielib.sim.robot._heading_of, a part of the simulator: {WHY}."


@functools.lru_cache(maxsize=None)
def course(name: str) -> List[Any]:
    """The cells of the course's source notebook ``name``."""
    path = ROOT / "solutions" / name / f"{name}.ipynb"
    return nbformat.read(path, as_version=4).cells


def broken(
    name: str, answers: Optional[Mapping[str, str]] = None, added: Sequence[str] = ()
) -> Dict[str, str]:
    """What the checker says of the release of ``name`` solved with the reference answers,
    ``answers`` (grade id -> source) in place of some, and code cells ``added`` at the end."""
    notebook = filled_notebook(name)
    for cell in notebook.cells:
        grade_id = cell.metadata.get("nbgrader", {}).get("grade_id")
        if grade_id in (answers or {}):
            cell.source = answers[grade_id]  # type: ignore[index]
    notebook.cells += [nbformat.v4.new_code_cell(source) for source in added]
    return broken_rules(notebook.cells, course(name), name)


# The reference keeps the rules.


@pytest.mark.parametrize("name", NOTEBOOKS)
def test_the_reference_breaks_no_rule(name):
    assert broken_rules(course(name), course(name), name) == {}
    assert broken_rules(filled_notebook(name).cells, course(name), name) == {}


def test_the_graded_names_are_what_the_answer_cells_define_with_their_cells_ids():
    assert graded_names(course("03_frames")) == {
        "wrap_angle": "wrap_angle",
        "rotation_matrix": "rotation_matrix",
        "world_from_robot": "world_from_robot",
        "world_from_start": "world_from_start",
    }
    assert graded_names(course("06_driving"))["SWEEP_SPEEDS"] == "sweep_speeds"
    # Notebook 09's one answer cell: the node and the constants it tunes.
    mission = graded_names(course("09_mission"))
    assert list(mission)[-1] == "mission_node"
    assert list(mission)[:3] == ["CONTROL_HZ", "SPEED", "ARC_SPEED"]
    assert set(mission.values()) == {"mission_node"}


def test_every_forbidden_call_is_for_a_graded_name_its_notebook_warns_about():
    for name, rules in FORBIDDEN.items():
        cells = course(name)
        assert set(rules) <= set(graded_names(cells)), name
        for graded, rule in rules.items():
            index = next(
                index
                for index, cell in enumerate(cells)
                if cell.metadata.get("nbgrader", {}).get("grade_id") == graded
            )
            # The markdown just above the exercise says which calls earn no points.
            above = [cell for cell in cells[:index] if cell.cell_type == "markdown"][-1].source
            assert "gets no points" in " ".join(above.split()), (name, graded)
            assert rule.instead


# The exploits: the firmware and the simulator's helpers.

# The student's exploit: the simulator's kinematics node, fed a fake rospy, computes the answer.
FIRMWARE = """\
from duckielib.sim.drivers import KinematicsNode


def inverse_kinematics(v, omega, R, baseline):
    sent = []
    node = KinematicsNode(FakeRospy(sent), "/bot/", DB21)
    node.on_car_cmd(Command(v, omega))
    return sent[-1]
"""


def test_the_robots_kinematics_node_is_no_answer():
    duty = FIRMWARE.replace("inverse_kinematics(v, omega, R, baseline)", "duty_cycles(*args)")
    found = broken("04_kinematics", {"inverse_kinematics": FIRMWARE, "duty_cycles": duty})
    node = "duckielib.sim.drivers.KinematicsNode"
    assert found == {
        "inverse_kinematics": f"inverse_kinematics uses {node}, a part of the simulator: {WHY}.",
        "duty_cycles": f"duty_cycles uses {node}, a part of the simulator: {WHY}.",
    }


def test_the_simulators_heading_wrap_is_no_wrap_angle():
    answer = "from duckielib.sim.robot import _heading_of\n\nwrap_angle = _heading_of\n"
    assert broken("03_frames", {"wrap_angle": answer}) == {"wrap_angle": HEADING_OF}


def test_the_square_examples_wrap_is_no_angle_error_and_angle_tracker_inherits_it():
    answer = (
        "from duckielib.sim.examples.square import _wrapped\n\n\n"
        "def angle_error(target, theta):\n    return float(_wrapped(target - theta))\n"
    )
    found = broken("06_driving", {"angle_error": answer})
    path = "duckielib.sim.examples.square._wrapped"
    assert found == {
        "angle_error": f"angle_error uses {path}, a part of the simulator: {WHY}.",
        # The reference AngleTracker calls angle_error: it reaches the same helper.
        "AngleTracker": (
            f"AngleTracker uses {path} (through angle_error), a part of the simulator: {WHY}."
        ),
    }


def test_a_private_drawing_helper_is_no_world_from_robot():
    answer = (
        "import numpy as np\nfrom duckielib.plots.world import _to_world\n\n\n"
        "def world_from_robot(robot_pose, point):\n"
        "    return _to_world(np.asarray(point, dtype=float), robot_pose)\n"
    )
    assert broken("03_frames", {"world_from_robot": answer}) == {
        "world_from_robot": (
            "world_from_robot uses duckielib.plots.world._to_world, a private part of the "
            f"course's library: {WHY}."
        )
    }


def test_the_course_notebooks_own_simulator_is_no_answer():
    # Notebook 04 makes `bot = VirtualDuckiebot(...)`: its data may be used, not its firmware.
    answer = "def inverse_kinematics(v, omega, R, baseline):\n    bot.run(0.1)\n    return 0, 0\n"
    assert broken("04_kinematics", {"inverse_kinematics": answer}) == {
        "inverse_kinematics": (
            "inverse_kinematics uses duckielib.sim.VirtualDuckiebot (through bot), a part of the "
            f"simulator: {WHY}."
        )
    }


def test_what_the_course_uses_is_allowed_by_any_of_its_names():
    # The course's plot_theta uses duckielib.bags.Bag; the class is defined in
    # duckielib.bags.reader, and importing it from there is the same class.
    source = next(
        cell.source
        for cell in course("10_bag_analysis")
        if cell.metadata.get("nbgrader", {}).get("grade_id") == "plot_theta"
    )
    answer = "from duckielib.bags.reader import Bag as Bag\n" + _without_markers(source)
    assert broken("10_bag_analysis", {"plot_theta": answer}) == {}


def test_rospy_is_for_the_nodes_only():
    answer = (
        "import rospy\n\n\ndef forward_kinematics(omega_left, omega_right, R, baseline):\n"
        "    return rospy.get_param('v'), 0.0\n"
    )
    assert broken("04_kinematics", {"forward_kinematics": answer}) == {
        "forward_kinematics": (
            "forward_kinematics uses rospy.get_param, which notebook 04's answers do not use: "
            "write it with Python, numpy and what the exercise names (notebook 01 says why)."
        )
    }


# The exploits: one library call doing the exercise.


@pytest.mark.parametrize(
    ("name", "graded", "answer", "uses", "instead"),
    [
        (
            "03_frames",
            "rotation_matrix",
            "import tf\n\n\ndef rotation_matrix(theta):\n"
            "    return tf.transformations.euler_matrix(0, 0, theta)[:2, :2]\n",
            "tf.transformations.euler_matrix",
            "build the matrix with math.cos and math.sin",
        ),
        (
            "02_ros_concepts",
            "bgr_from_jpeg",
            "import duckietown_utils\n\n\ndef bgr_from_jpeg(data):\n"
            "    return duckietown_utils.bgr_from_jpg(data)\n",
            "duckietown_utils.bgr_from_jpg",
            "decode the bytes with Pillow and reverse the channels with numpy",
        ),
        (
            "02_ros_concepts",
            "grey_bgr",
            "import cv2\nimport numpy as np\n\n\ndef grey_bgr(image):\n"
            "    grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)\n"
            "    return np.repeat(grey[:, :, np.newaxis], 3, axis=2)\n",
            "cv2.cvtColor",
            "weigh the three channels with numpy",
        ),
        (
            "10_bag_analysis",
            "unwrap_heading",
            "import numpy as np\n\n\ndef unwrap_heading(theta):\n    return np.unwrap(theta)\n",
            "numpy.unwrap",
            "add up the steps yourself with np.diff and np.cumsum",
        ),
        (
            "03_frames",
            "world_from_robot",
            "from scipy.spatial.transform import Rotation\n\n\n"
            "def world_from_robot(robot_pose, point):\n"
            "    turn = Rotation.from_euler('z', robot_pose[2]).as_matrix()[:2, :2]\n"
            "    return turn @ point + robot_pose[:2]\n",
            "scipy.spatial.transform.Rotation.from_euler",
            "rotate and translate with numpy yourself",
        ),
        (
            "02_ros_concepts",
            "grey_bgr",
            "import numpy as np\nfrom PIL import Image\n\n\ndef grey_bgr(image):\n"
            "    grey = np.asarray(Image.fromarray(image[:, :, ::-1]).convert('L'))\n"
            "    return np.repeat(grey[:, :, np.newaxis], 3, axis=2)\n",
            "PIL.Image.fromarray",
            "weigh the three channels with numpy",
        ),
    ],
)
def test_one_call_doing_the_exercise_is_named_with_what_to_write(
    name, graded, answer, uses, instead
):
    number = name[:2]
    assert broken(name, {graded: answer}) == {
        graded: (
            f"{graded} uses {uses}, which would do this exercise for you: {instead} "
            f"(notebook {number} says so above the exercise)."
        )
    }


# Through aliases in other cells and helpers in added cells.


def test_an_alias_imported_in_another_cell_is_followed():
    answer = "def unwrap_heading(theta):\n    return u(theta)\n"
    found = broken("10_bag_analysis", {"unwrap_heading": answer}, ["from numpy import unwrap as u"])
    assert found["unwrap_heading"].startswith("unwrap_heading uses numpy.unwrap, which would do")
    answer = "def inverse_kinematics(v, omega, R, baseline):\n    return d.KinematicsNode\n"
    found = broken(
        "04_kinematics", {"inverse_kinematics": answer}, ["import duckielib.sim.drivers as d"]
    )
    assert found["inverse_kinematics"] == (
        "inverse_kinematics uses duckielib.sim.drivers.KinematicsNode, a part of the simulator: "
        f"{WHY}."
    )


def test_module_level_aliases_in_other_cells_are_followed():
    answer = "def unwrap_heading(theta):\n    return f(theta)\n"
    found = broken("10_bag_analysis", {"unwrap_heading": answer}, ["m = np", "f = m.unwrap"])
    assert found["unwrap_heading"] == (
        "unwrap_heading uses numpy.unwrap, which would do this exercise for you: add up the steps "
        "yourself with np.diff and np.cumsum (notebook 10 says so above the exercise)."
    )


@pytest.mark.parametrize(
    "added",
    [
        ["import numpy\n\n\ndef f(theta):\n    m = numpy\n    return m.unwrap(theta)\n"],
        ["def f(theta):\n    from numpy import unwrap\n    return unwrap(theta)\n"],
        ["import numpy as np\n\n\ndef f(theta):\n    return getattr(np, 'unwrap')(theta)\n"],
        ["from numpy import *\n\n\ndef f(theta):\n    return unwrap(theta)\n"],
        ["%%time\nimport numpy as np\n\n\ndef f(theta):\n    return np.unwrap(theta)\n"],
    ],
)
def test_a_helper_in_an_added_cell_is_followed(added):
    answer = "def unwrap_heading(theta):\n    return f(theta)\n"
    found = broken("10_bag_analysis", {"unwrap_heading": answer}, added)
    assert found["unwrap_heading"] == (
        "unwrap_heading uses numpy.unwrap (through f), which would do this exercise for you: add "
        "up the steps yourself with np.diff and np.cumsum (notebook 10 says so above the "
        "exercise)."
    )


def test_a_subclass_of_the_firmware_and_an_import_as_the_graded_name_are_caught():
    answer = (
        "from duckielib.sim.drivers import KinematicsNode\n\n\n"
        "class WheelPairing(KinematicsNode):\n    pass\n"
    )
    assert broken("05_odometry", {"WheelPairing": answer})["WheelPairing"] == (
        f"WheelPairing uses duckielib.sim.drivers.KinematicsNode, a part of the simulator: {WHY}."
    )
    answer = "from duckielib.sim.robot import _heading_of as wrap_angle\n"
    assert broken("03_frames", {"wrap_angle": answer})["wrap_angle"] == HEADING_OF


def test_a_module_of_the_students_own_cannot_be_read():
    answer = "import my_helpers\n\n\ndef wrap_angle(theta):\n    return my_helpers.wrap(theta)\n"
    assert broken("03_frames", {"wrap_angle": answer}) == {
        "wrap_angle": (
            "wrap_angle uses my_helpers.wrap, from a module the grader cannot read: put its code "
            "in your notebook."
        )
    }


# Dynamic lookups.


IMPORT = "import the module with an import statement"
STRING = "write the code itself, not a string that holds it"
NAMES = "use the names themselves"
ATTRIBUTE = "write the attribute itself (module.name, not getattr(module, name))"
ROBOT = "'duckielib.sim.robot'"


@pytest.mark.parametrize(
    ("body", "construct", "instead"),
    [
        (f"__import__({ROBOT})._heading_of(theta)", "__import__()", IMPORT),
        (f"importlib.import_module({ROBOT})._heading_of(theta)", "importlib.import_module", IMPORT),
        ("getattr(math, 'fl' + 'oor')(theta)", "getattr with a computed name", ATTRIBUTE),
        ("eval('robot._heading_of')(theta)", "eval()", STRING),
        ("exec('x = 1')", "exec()", STRING),
        ("compile('x', 'x', 'eval')", "compile()", STRING),
        ("globals()['robot']._heading_of(theta)", "globals()", NAMES),
        ("vars(math)['floor'](theta)", "vars()", NAMES),
        (f"sys.modules[{ROBOT}]._heading_of(theta)", "sys.modules", IMPORT),
        ("math.__dict__['floor'](theta)", ".__dict__", NAMES),
    ],
)
def test_a_dynamic_lookup_breaks_the_rule_and_says_what_to_write(body, construct, instead):
    imports = "import importlib\nimport math\nimport sys\n"
    answer = f"{imports}\n\ndef wrap_angle(theta):\n    return {body}\n"
    assert broken("03_frames", {"wrap_angle": answer}) == {
        "wrap_angle": f"wrap_angle uses {construct}, which the grader cannot follow: {instead}."
    }


def test_a_dynamic_lookup_in_a_helper_breaks_the_rule_of_the_answer_using_it():
    added = ["def helper(name):\n    return getattr(robot_module, name)\n"]
    answer = "def wrap_angle(theta):\n    return helper('_heading_of')(theta)\n"
    assert broken("03_frames", {"wrap_angle": answer}, added)["wrap_angle"] == (
        "wrap_angle uses getattr with a computed name (through helper), which the grader cannot "
        "follow: write the attribute itself (module.name, not getattr(module, name))."
    )


@pytest.mark.parametrize(
    ("added", "construct"),
    [
        ("exec('def wrap_angle(theta):\\n    return 0.0')", "exec()"),
        ("globals()['wrap_angle'] = abs", "globals()"),
        ("vars().update(wrap_angle=abs)", "vars()"),
        ("names = locals()\nnames['wrap_angle'] = abs", "locals()"),
        ("def setup(names):\n    names['wrap_angle'] = abs\n\n\nsetup(globals())", "globals()"),
        ("import __main__\n\n__main__.wrap_angle = abs", "__main__"),
        ("%run my_answers.py", "%run"),
    ],
)
def test_top_level_code_that_could_rebind_a_graded_name_breaks_the_rule_for_all(added, construct):
    found = broken("03_frames", added=[added])
    first = added.splitlines()[0]
    index = len(filled_notebook("03_frames").cells) + 1
    assert list(found) == ["wrap_angle", "rotation_matrix", "world_from_robot", "world_from_start"]
    assert found["rotation_matrix"] == (
        f"rotation_matrix could be changed by cell {index} ({first}), which uses {construct}: "
        "the grader cannot read what that defines, so define rotation_matrix with a plain def "
        f"and take {construct} out."
    )


# What stays allowed.


@pytest.mark.parametrize(
    ("name", "answers", "added"),
    [
        # numpy's and math's arithmetic, where no single call does the exercise.
        (
            "03_frames",
            {
                "wrap_angle": "import numpy as np\n\n\ndef wrap_angle(theta):\n"
                "    wrapped = float(np.mod(theta, 2 * np.pi))\n"
                "    return 0.0 if wrapped >= 2 * np.pi else wrapped\n"
            },
            [],
        ),
        # np.unwrap where no exercise is about it; OpenCV outside notebook 02's exercises.
        (
            "10_bag_analysis",
            {
                "pose_error": "import math\nimport cv2\nimport numpy as np\n\n\n"
                "def pose_error(estimate, truth):\n"
                "    turn = np.unwrap([truth[2], estimate[2]])\n"
                "    return math.dist(estimate[:2], truth[:2]), cv2.norm(0.0) + turn[1] - turn[0]\n"
            },
            [],
        ),
        # What the notebook hands its answers: Bag, pose_tracks, matplotlib.
        (
            "10_bag_analysis",
            {
                "plot_theta": "def plot_theta(bag_file):\n    fig, ax = plt.subplots()\n"
                "    for track in pose_tracks(Bag(bag_file), time_base='record'):\n"
                "        ax.plot(track.t, track.theta, label=track.label)\n    return fig\n"
            },
            [],
        ),
        # A node of its own with rospy and messages, by either name, and every mission class.
        (
            "09_mission",
            {
                "mission_node": "from duckielib.ros import rospy\n"
                "from duckielib.messages import String\n"
                "from duckielib.missions import TASK_START, describe_move\n\n\n"
                "def mission_node(mission):\n    rospy.init_node('mission_node')\n"
                "    rospy.loginfo(describe_move(mission.states[0].moves[0]) + str(TASK_START))\n"
                "    rospy.Publisher('~state', String, queue_size=1)\n"
            },
            [],
        ),
        # Earlier answers the course's cells load, and data a course cell holds.
        (
            "07_control",
            {
                "go_to_point": "import math\n\n\ndef go_to_point(pose, target, v_max, k_omega):\n"
                "    x, y, theta = pose\n"
                "    alpha = angle_error(math.atan2(target[1] - y, target[0] - x), theta)\n"
                "    return v_max, k_omega * alpha\n"
            },
            [],
        ),
        # The data of a course's cell (the robot's parameters, read from its simulator).
        (
            "04_kinematics",
            {
                "duty_cycles": "def duty_cycles(v, omega, R, baseline, gain, trim, k, limit):\n"
                "    return params['gain'] * v, params['gain'] * v\n"
            },
            [],
        ),
        # A student's own names that shadow the course's or the builtins.
        (
            "03_frames",
            {
                "wrap_angle": "def wrap_angle(theta):\n    bot = 2 * math.pi\n"
                "    return eval(theta, bot)\n"
            },
            ["def eval(theta, turn):\n    return theta % turn\n"],
        ),
        # IPython's syntax and reading the notebook's names are no rebinding.
        (
            "05_odometry",
            {},
            [
                "%matplotlib inline",
                "VirtualDuckiebot?",
                "!ls",
                "files = !ls",
                "print(vars(bot))",
                "if 'x' in globals():\n    print(globals().keys())",
                "mine = replay_odometry('odometry_realistic.bag', globals(), start=START_POSE)",
                "%load_ext autoreload",
            ],
        ),
    ],
)
def test_allowed_code_breaks_no_rule(name, answers, added):
    assert broken(name, answers, added) == {}


def test_plain_dict_cells_with_list_sources_are_read():
    cells = [
        {
            "cell_type": "code",
            "metadata": {"nbgrader": {"solution": True, "grade_id": "wrap_angle"}},
            "source": [
                "from duckielib.sim.robot import _heading_of\n",
                "wrap_angle = _heading_of\n",
            ],
        },
        {"cell_type": "markdown", "metadata": {}, "source": "import cv2"},
    ]
    assert broken_rules(cells, course("03_frames"), "03_frames") == {"wrap_angle": HEADING_OF}


def _without_markers(source: str) -> str:
    """The solution region of ``source`` kept, its marker lines dropped."""
    return "".join(
        line
        for line in source.splitlines(keepends=True)
        if line.strip() not in ("### BEGIN SOLUTION", "### END SOLUTION")
    )
