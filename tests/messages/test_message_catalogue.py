"""Every type of the message catalogue against the real ones: md5 sums, fields, imports.

The standard packages (std_msgs, geometry_msgs, sensor_msgs, nav_msgs, std_srvs, tf2_msgs,
rosgraph_msgs, actionlib_msgs) are compared with Debian's genpy classes, read in a Python of
their own so that nothing of Debian's ROS stays in this process. duckietown_msgs, which Debian
does not ship, is compared with the md5 sums of its daffy release.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from duckielib import messages

#: Where Debian installs genpy and the message packages (``make ros``).
DEBIAN_DIST_PACKAGES = "/usr/lib/python3/dist-packages"
#: The Debian package of each ROS package.
DEBIAN_PACKAGES = {
    "std_msgs": "python3-std-msgs",
    "geometry_msgs": "python3-geometry-msgs",
    "sensor_msgs": "python3-sensor-msgs",
    "nav_msgs": "python3-nav-msgs",
    "std_srvs": "python3-std-srvs",
    "tf2_msgs": "python3-tf2-msgs",
    "rosgraph_msgs": "python3-rosgraph-msgs",
    "actionlib_msgs": "python3-actionlib-msgs",
}
STANDARD = sorted(
    name
    for name in messages.message_types() + messages.service_types()
    if name.partition("/")[0] in DEBIAN_PACKAGES
)

# duckietown_msgs of Duckietown's dt-ros-commons, branch daffy (the types its CMakeLists.txt
# builds), md5 sums as genmsg computes them; the interface spec lists eight of them.
DUCKIETOWN_MESSAGE_MD5 = {
    "AntiInstagramThresholds": "bcde9d2f8b33a444d7909aaaa7563290",
    "AprilTagDetection": "a831190390fbef881c141df7b86598db",
    "AprilTagDetectionArray": "21f977fd1654c0bf67532acd641c3d4d",
    "AprilTagsWithInfos": "77712a218c71ce85b76155ff87db1adb",
    "BoolStamped": "542e22b190dc8e6eb476d50dda88feb7",
    "ButtonEvent": "99a2e60dbe7b111394ec13b630081819",
    "CarControl": "a5bdd39ba7df1e21f0742b74ac614c71",
    "CoordinationClearance": "863863237538fdb5f0d38c0c62b294db",
    "CoordinationSignal": "3caa78ed5f7d2e4ac24db630f8ee77a8",
    "DiagnosticsCodeProfiling": "2f919bc6b39855368e96c3df59f3187f",
    "DiagnosticsCodeProfilingArray": "57dca0d37f20880e0dee9358611e6e75",
    "DiagnosticsRosLink": "53a9a85eb8565abb4ba439662041c3aa",
    "DiagnosticsRosLinkArray": "429f5aa0771b8b09d6913175d25517ec",
    "DiagnosticsRosNode": "d51c0fa0a1d1899eebe4bf3476ab3439",
    "DiagnosticsRosParameterArray": "3cce38c64acfe087a9363ff4d78b53a5",
    "DiagnosticsRosTopic": "c3a6c5501489fa1a1f348c31cffc641a",
    "DiagnosticsRosTopicArray": "75d6b38d91572d9e365e9ae3cf66db75",
    "DisplayFragment": "b47577c93ca4c0ee8514639ef90c78dc",
    "DroneControl": "b386c6e2e9626467134582335c7f632f",
    "DroneMode": "b59b67ae59d5510222e083f7dcf98328",
    "DuckiebotLED": "d1a05ea07d5c98d935c3a53fe6500186",
    "EncoderStamped": "bceed13d0df81fff9a99f0c6a78e8f33",
    "EpisodeStart": "d9c9ddf1cb6334de0336392fe315bfa9",
    "FSMState": "3c94938238cecfe40fdf747aae8abbaa",
    "IntersectionPose": "2876ebb9c81385581c8f35481e72e0a9",
    "IntersectionPoseImg": "9be288b28225c76ee9ce1052704524b8",
    "IntersectionPoseImgDebug": "0027b9b3f880873af8e49663f8172f1a",
    "KinematicsParameters": "cbca57679564ab84ca723072e3bf6226",
    "KinematicsWeights": "6904a09d2a677bf07bc600ffaa092ae8",
    "LEDDetection": "d1ac8691d7a30e838dc372a724aee94b",
    "LEDDetectionArray": "a95456786a73967a5a29fdbf726c022c",
    "LEDDetectionDebugInfo": "be212adc91f6527a99fc828df2018200",
    "LEDInterpreter": "100d6a2c19dff0c3d52b5c327f7ecae9",
    "LEDPattern": "47c8633688bbd1c94b1e15be083240b6",
    "LanePose": "382fe0e0d5dea7350bfa93535592e68a",
    "LightSensor": "7d3098cdc59f2c0a8f7c461ef10ca781",
    "LineFollowerStamped": "296fc5d7868bac377ab0a7300283e5f4",
    "MaintenanceState": "076259ec4d51665ce2a0b26c9055f2df",
    "NodeParameter": "871c14dc09d7cdeffeca9173f51f84f9",
    "ObstacleImageDetection": "e532bfbd15e6046dab5e4261999811a9",
    "ObstacleImageDetectionList": "bb443595d23936bacf0f853c0dbaa48c",
    "ObstacleProjectedDetection": "cb503445da742d4aa1f69f0b72163c00",
    "ObstacleProjectedDetectionList": "11b067403fefa6151edc8b44e25edac3",
    "ObstacleType": "9ebfbd5f069d46cb29c52358b5e953fb",
    "ParamTuner": "53c42bf2be1bd4386da34eca6088702d",
    "Pixel": "f06a7e8dd345ffb826d71a489782114b",
    "Pose2DStamped": "013fad68aad141d90a055e21fb791e63",
    "Rect": "4a7147213b29db1bb19b0427bbb901ac",
    "Rects": "f5b74b2b15b5d4d2f299389f9f4ca7f8",
    "SceneSegments": "2aa3c1097b948038841bf28c11cf95cb",
    "Segment": "63449fcee6301e43c25adab0c5e5d117",
    "SegmentList": "1cefc32a4bc9039bf09d40c6c13beace",
    "SignalsDetection": "7a3bb73ea77191f1c0ddd7e196f27c75",
    "SignalsDetectionETHZ17": "c1b7d3a54f028811e1c3b2366af85c0a",
    "SourceTargetNodes": "f05fda47731d8da1f80e3a499a42edf9",
    "StopLineReading": "735fe9e9ff1e4d7460bbf69ab2720ae0",
    "TagInfo": "d194db19dc43ddeaa93486d02f120934",
    "ThetaDotSample": "047a1392fc183282d6b1904203840832",
    "Trajectory": "4a5c4bf7a2bfb37b947e3dfa585ede51",
    "TurnIDandType": "999e690d54f4de1ab02b7e874091d0ff",
    "Twist2DStamped": "3fc0942a3082e78d7ded4a58ea1e2d0c",
    "Vector2D": "ff8d7d66dd3e4b731ef14a45d38888b6",
    "VehicleCorners": "f601f02846ab710f0645608b8ce77e71",
    "VehiclePose": "69c01ed5e84e0f58f795e563d073900d",
    "Vsample": "636e6e791af118be8338c8ab7fbd00e7",
    "WheelEncoderStamped": "141b74ec2cc3bde8c38b5e3bdb694d12",
    "WheelsCmd": "95189a38cb8112e26fa8ced2d5359a0c",
    "WheelsCmdDBV2Stamped": "7da28061cc173091cc0253decf17895d",
    "WheelsCmdStamped": "edbf8d24194d839b1982a6a991b552c6",
}
DUCKIETOWN_SERVICE_MD5 = {
    "ChangePattern": "678f2d65b1bda577ab0910fd9c7414ba",
    "GetVariable": "685a8058475bb3a593fd8f9319066e6a",
    "IMUstatus": "508fbfdea8b0319f1b2a5826eac9a6e6",
    "LFstatus": "b59a0adbfa1b994feb973fdc4fcbe6db",
    "NodeGetParamsList": "6d0f5ba1e047603a0b1306ec478bb3e5",
    "NodeRequestParamsUpdate": "e8496433f08c35370e7779defca9aa19",
    "SensorsStatus": "d8dd1fcbd833d76004def4493c2acff3",
    "SetCustomLEDPattern": "80c491edc501f8f5b2f80aaecfd31b21",
    "SetFSMState": "af6d3a99f0fbeb66d3248fa4b3e675fb",
    "SetValue": "0aca93dcf6d857f0e5a0dc6be1eaa9fb",
    "SetVariable": "b9596f8691f82d6cddb450d38ac5e5af",
    "ToFstatus": "123f458c8760917a4db65e882cc7f43c",
}

#: Run in a Python of its own: a description of every type of Debian's message packages.
_DEBIAN_SCRIPT = """
import importlib, importlib.util, json, sys
sys.path.append(sys.argv[1])
found, missing = {}, []

def describe(cls):
    constants = {
        key: value
        for key, value in vars(cls).items()
        if not key.startswith("_") and isinstance(value, (int, float, str))
    }
    buffer = __import__("io").BytesIO()
    cls().serialize(buffer)
    return {
        "md5": cls._md5sum,
        "slots": list(cls.__slots__),
        "slot_types": list(cls._slot_types),
        "has_header": cls._has_header,
        "constants": constants,
        "default_bytes": buffer.getvalue().hex(),
    }

for package in sys.argv[2:]:
    if importlib.util.find_spec(package) is None:
        missing.append(package)
        continue
    for kind in ("msg", "srv"):
        try:
            module = importlib.import_module(package + "." + kind)
        except ImportError:
            continue
        for name in dir(module):
            cls = getattr(module, name)
            if not isinstance(cls, type) or getattr(cls, "__module__", "").split(".")[0] != package:
                continue
            if hasattr(cls, "_request_class"):
                found[cls._type] = {
                    "md5": cls._md5sum,
                    "request": describe(cls._request_class),
                    "response": describe(cls._response_class),
                }
            elif hasattr(cls, "_slot_types") and kind == "msg":
                found[cls._type] = describe(cls)
print(json.dumps({"types": found, "missing": missing}))
"""


@pytest.fixture(scope="module")
def debian():
    """Debian's message types by name, and the packages not installed; skips without genpy."""
    if not Path(DEBIAN_DIST_PACKAGES, "genpy").is_dir():
        pytest.skip("Debian's ROS 1 packages are not installed; run `make ros`.")
    result = subprocess.run(
        [sys.executable, "-c", _DEBIAN_SCRIPT, DEBIAN_DIST_PACKAGES, *DEBIAN_PACKAGES],
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(result.stdout)


def _real(debian, name):
    package = name.partition("/")[0]
    if package in debian["missing"]:
        pytest.skip(f"{package} is not installed; install {DEBIAN_PACKAGES[package]}.")
    assert name in debian["types"], f"Debian's {package} has no type {name}"
    return debian["types"][name]


def _assert_same_message(ours, real):
    assert ours._md5sum == real["md5"]
    assert list(ours.__slots__) == real["slots"]
    assert ours._slot_types == real["slot_types"]
    assert ours._has_header == real["has_header"]
    constants = {c.name: c.value for c in messages.REGISTRY.message(ours._type).constants}
    assert constants == real["constants"]
    assert ours().to_bytes().hex() == real["default_bytes"]


@pytest.mark.ros
@pytest.mark.parametrize("name", STANDARD)
def test_standard_type_equals_debian_s(debian, name):
    real = _real(debian, name)
    if name in messages.REGISTRY.services:
        service = messages.get_service_class(name)
        assert service._md5sum == real["md5"]
        _assert_same_message(service._request_class, real["request"])
        _assert_same_message(service._response_class, real["response"])
    else:
        _assert_same_message(messages.get_message_class(name), real)


@pytest.mark.ros
@pytest.mark.parametrize("package", sorted(DEBIAN_PACKAGES))
def test_every_type_of_debian_s_packages_is_defined(debian, package):
    if package in debian["missing"]:
        pytest.skip(f"{package} is not installed; install {DEBIAN_PACKAGES[package]}.")
    real = sorted(name for name in debian["types"] if name.startswith(package + "/"))
    assert real == [name for name in STANDARD if name.startswith(package + "/")]


@pytest.mark.parametrize(("name", "md5"), sorted(DUCKIETOWN_MESSAGE_MD5.items()))
def test_duckietown_message_md5(name, md5):
    assert messages.get_message_class(f"duckietown_msgs/{name}")._md5sum == md5


@pytest.mark.parametrize(("name", "md5"), sorted(DUCKIETOWN_SERVICE_MD5.items()))
def test_duckietown_service_md5(name, md5):
    assert messages.get_service_class(f"duckietown_msgs/{name}")._md5sum == md5


def test_every_duckietown_type_of_daffy_is_defined():
    ours = [name for name in messages.message_types() if name.startswith("duckietown_msgs/")]
    assert ours == [f"duckietown_msgs/{name}" for name in sorted(DUCKIETOWN_MESSAGE_MD5)]
    ours = [name for name in messages.service_types() if name.startswith("duckietown_msgs/")]
    assert ours == [f"duckietown_msgs/{name}" for name in sorted(DUCKIETOWN_SERVICE_MD5)]


@pytest.mark.parametrize("name", messages.service_types())
def test_every_service_round_trips_its_request_and_response(name):
    service = messages.get_service_class(name)
    for part in (service._request_class, service._response_class):
        assert part.from_bytes(part().to_bytes()) == part()
        assert part.__module__.endswith(".srv")


def run_python(script: str) -> str:
    """Run ``script`` in a fresh Python; its stdout."""
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=False
    )
    assert result.returncode == 0, result.stderr
    return result.stdout


def test_robot_code_imports_every_package():
    out = run_python(
        "import duckielib.ros\n"
        "from std_msgs.msg import *\n"
        "print(' '.join(sorted(n for n, v in dict(globals()).items() if hasattr(v, '_type'))))\n"
        "from geometry_msgs.msg import Twist, Pose, PoseStamped, TransformStamped\n"
        "from nav_msgs.msg import Odometry\n"
        "from std_srvs.srv import Trigger, TriggerResponse, Empty\n"
        "from duckietown_msgs.msg import EpisodeStart\n"
        "from duckietown_msgs.srv import SetFSMState\n"
        "from sensor_msgs.msg import Imu, CameraInfo\n"
        "from tf2_msgs.msg import TFMessage\n"
        "from rosgraph_msgs.msg import Clock, Log\n"
        "print(Twist._type, Odometry._type, Empty._type, TriggerResponse._type,\n"
        "      EpisodeStart._type)\n"
        "print(Odometry().pose.pose.orientation.w, TriggerResponse(success=True).success)\n"
    )
    star, types, values = out.strip().split("\n")
    std_msgs = [name for name in messages.message_types() if name.startswith("std_msgs/")]
    assert star.split() == sorted(name.partition("/")[2] for name in std_msgs)
    assert types.split() == [
        "geometry_msgs/Twist",
        "nav_msgs/Odometry",
        "std_srvs/Empty",
        "std_srvs/TriggerResponse",
        "duckietown_msgs/EpisodeStart",
    ]
    assert values.split() == ["0.0", "True"]


def test_short_names_keep_the_course_s_types():
    assert messages.Header._type == "std_msgs/Header"
    assert messages.Empty._type == "std_msgs/Empty"
    assert messages.Image._type == "sensor_msgs/Image"
    assert messages.String._type == "std_msgs/String"
    for name in messages.__all__:
        found = getattr(messages, name)
        if isinstance(found, type) and found not in (messages.Message, messages.Service):
            assert found._type.rpartition("/")[2] == name
            assert found._type.partition("/")[0] in ("std_msgs", "sensor_msgs", "duckietown_msgs")
    assert not hasattr(messages, "Twist")
    assert not hasattr(messages, "Odometry")
    assert "Header" in dir(messages)


def test_classes_are_made_on_first_use_only():
    out = run_python(
        "from duckielib import messages\n"
        "print(len(messages._MESSAGE_CLASSES), len(messages.REGISTRY.messages) > 200)\n"
        "from duckielib.messages.geometry_msgs.msg import PoseStamped\n"
        "print(sorted(messages._MESSAGE_CLASSES))\n"
    )
    assert out.split("\n")[:2] == [
        "0 True",
        "['geometry_msgs/Point', 'geometry_msgs/Pose', 'geometry_msgs/PoseStamped', "
        "'geometry_msgs/Quaternion', 'std_msgs/Header']",
    ]


def test_threads_asking_at_once_get_the_same_class():
    out = run_python(
        "import threading\n"
        "from duckielib import messages\n"
        "found = []\n"
        "start = threading.Barrier(8)\n"
        "def ask():\n"
        "    start.wait()\n"
        "    found.append(messages.get_message_class('sensor_msgs/MultiDOFJointState'))\n"
        "threads = [threading.Thread(target=ask) for _ in range(8)]\n"
        "[thread.start() for thread in threads]\n"
        "[thread.join() for thread in threads]\n"
        "print(len(found), len(set(map(id, found))))\n"
    )
    assert out.split() == ["8", "1"]
