"""duckietown_utils' helpers as nodes use them: the robot's name, YAML files, images."""

from __future__ import annotations

import importlib

import cv2
import numpy as np
import pytest

from duckielib.libraries import duckietown_utils as dtu
from duckielib.messages import CompressedImage, Header, Image
from duckielib.ros.modules import modules_installed
from duckielib.rostime import Time


def test_it_is_served_by_name_where_no_real_one_is_installed():
    with modules_installed():
        module = importlib.import_module("duckietown_utils")
        assert module.get_current_robot_name is dtu.get_current_robot_name


def test_the_robots_name_is_vehicle_name_or_the_machines(monkeypatch):
    monkeypatch.setenv("VEHICLE_NAME", "ente")
    assert dtu.get_current_robot_name() == "ente"
    monkeypatch.delenv("VEHICLE_NAME")
    import socket

    assert dtu.get_current_robot_name() == socket.gethostname()


def test_the_fleet_root_must_be_set_and_be_a_folder(monkeypatch, tmp_path):
    monkeypatch.delenv("DUCKIEFLEET_ROOT", raising=False)
    with pytest.raises(dtu.DTConfigException, match="DUCKIEFLEET_ROOT is not set"):
        dtu.get_duckiefleet_root()
    monkeypatch.setenv("DUCKIEFLEET_ROOT", str(tmp_path / "nowhere"))
    with pytest.raises(dtu.DTConfigException, match="not a folder"):
        dtu.get_duckiefleet_root()
    monkeypatch.setenv("DUCKIEFLEET_ROOT", str(tmp_path))
    assert dtu.get_duckiefleet_root() == str(tmp_path)


def test_yaml_files_round_trip_and_bad_ones_say_so(tmp_path):
    data = {"gain": 1.0, "trim": -0.02, "baseline": 0.1, "radius": 0.0318, "k": 27.0}
    target = tmp_path / "calibrations" / "kinematics" / "ente.yaml"
    dtu.yaml_write_to_file(data, str(target))
    assert list(target.parent.iterdir()) == [target]  # no partial file left behind
    assert dtu.yaml_load_file(str(target)) == data
    assert target.read_text().splitlines()[0] == "gain: 1.0"  # in the order given
    with pytest.raises(dtu.DTConfigException, match="no file"):
        dtu.yaml_load_file(str(tmp_path / "missing.yaml"))
    broken = tmp_path / "broken.yaml"
    broken.write_text("gain: [1.0\n")
    with pytest.raises(dtu.DTBadData, match=r"broken\.yaml: This is not valid YAML"):
        dtu.yaml_load_file(str(broken))


def picture():
    image = np.zeros((48, 64, 3), np.uint8)
    image[:, :32] = (255, 0, 0)  # blue on the left, in BGR
    image[:, 32:] = (0, 0, 255)  # red on the right
    return image


def test_camera_messages_and_jpeg_bytes_become_pixels():
    bgr = picture()
    jpeg = dtu.jpg_from_bgr(bgr)
    assert jpeg[:2] == b"\xff\xd8"
    decoded = dtu.bgr_from_jpg(jpeg)
    assert decoded.shape == (48, 64, 3)
    # JPEG blurs the seam between the halves; away from it the colours survive.
    assert np.abs(decoded[:, :24].astype(int) - bgr[:, :24]).max() < 8
    assert np.abs(decoded[:, 40:].astype(int) - bgr[:, 40:]).max() < 8
    compressed = dtu.d8_compressed_image_from_cv_image(
        bgr, same_timestamp_as=CompressedImage(header=Header(stamp=Time(7, 5)))
    )
    assert compressed.format == "jpeg"
    assert compressed.header.stamp == Time(7, 5)
    rgb = dtu.rgb_from_ros(compressed)
    assert rgb[24, 10, 2] > 200  # blue, now in the third channel
    assert rgb[24, 10, 0] < 40
    raw = Image(height=48, width=64, encoding="bgr8", step=64 * 3, data=bgr.tobytes())
    assert np.array_equal(dtu.rgb_from_ros(raw), cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))
    assert np.array_equal(dtu.bgr_from_imgmsg(raw), bgr)
    assert np.array_equal(dtu.bgr_from_rgb(dtu.rgb_from_bgr(bgr)), bgr)
    with pytest.raises(dtu.DTBadData, match="Could not decode these 5 bytes"):
        dtu.bgr_from_jpg(b"hello")


def test_a_name_of_the_real_library_that_is_not_here_says_what_is():
    with pytest.raises(AttributeError, match=r"duckietown_utils\.load_map is not on the virtual"):
        dtu.load_map  # noqa: B018
    from_import = "from duckietown_utils import load_homography"
    with modules_installed(), pytest.raises(ImportError, match="load_homography"):
        exec(from_import, {})
