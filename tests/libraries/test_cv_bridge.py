"""cv_bridge as camera nodes use it: conversions, JPEG messages, and a node on the graph."""

from __future__ import annotations

import io
import sys

import cv2
import numpy as np
import pytest

from duckielib.libraries import cv_bridge
from duckielib.libraries.cv_bridge import CvBridge, CvBridgeError
from duckielib.messages import CompressedImage, Header, Image
from duckielib.ros import Graph, rospy
from duckielib.ros.log import ERROR
from duckielib.rostime import Time
from duckielib.sim import VirtualDuckiebot

#: Encoding -> (NumPy type, channels) of the images it names.
ENCODINGS = {
    "bgr8": (np.uint8, 3),
    "rgb8": (np.uint8, 3),
    "mono8": (np.uint8, 1),
    "bgra8": (np.uint8, 4),
    "rgba8": (np.uint8, 4),
    "mono16": (np.uint16, 1),
    "bgr16": (np.uint16, 3),
    "8UC3": (np.uint8, 3),
    "32FC1": (np.float32, 1),
}


@pytest.fixture
def bridge():
    return CvBridge()


def random_image(dtype, channels, height=6, width=7, seed=0):
    rng = np.random.default_rng(seed)
    shape = (height, width) if channels == 1 else (height, width, channels)
    if np.issubdtype(dtype, np.floating):
        return rng.normal(size=shape).astype(dtype)
    return rng.integers(0, np.iinfo(dtype).max, size=shape, endpoint=True).astype(dtype)


@pytest.mark.parametrize("encoding", ENCODINGS)
def test_each_encoding_round_trips_exactly(bridge, encoding):
    dtype, channels = ENCODINGS[encoding]
    image = random_image(dtype, channels)
    msg = bridge.cv2_to_imgmsg(image, encoding)
    assert isinstance(msg, Image)
    assert (msg.height, msg.width, msg.encoding) == (6, 7, encoding)
    assert msg.step == 7 * channels * np.dtype(dtype).itemsize
    assert len(msg.data) == 6 * msg.step
    assert msg.is_bigendian == 0
    # As published: serialized and read back.
    received = Image.from_bytes(msg.to_bytes())
    same = bridge.imgmsg_to_cv2(received)
    assert same.dtype == dtype
    assert same.shape == image.shape
    np.testing.assert_array_equal(same, image)
    assert not same.flags.writeable  # a view of the message's bytes, as on the robot
    copy = bridge.imgmsg_to_cv2(received, encoding)
    np.testing.assert_array_equal(copy, image)
    assert copy.flags.writeable


def test_passthrough_names_the_opencv_type_and_keeps_the_header(bridge):
    header = Header(seq=4, stamp=Time(12, 5), frame_id="duckiebot/camera_optical_frame")
    msg = bridge.cv2_to_imgmsg(np.zeros((2, 3, 3), np.uint8), header=header)
    assert msg.encoding == "8UC3"
    assert msg.header.stamp == Time(12, 5)
    assert msg.header.frame_id == "duckiebot/camera_optical_frame"
    assert bridge.cv2_to_imgmsg(np.zeros((2, 3), np.int16)).encoding == "16SC1"
    assert bridge.cv2_to_imgmsg(np.zeros((2, 3, 2), np.float64)).encoding == "64FC2"


def test_colour_conversions_give_opencvs_values(bridge):
    bgr = np.array([[[0, 0, 255], [0, 255, 0], [255, 0, 0], [10, 20, 30]]], np.uint8)
    msg = bridge.cv2_to_imgmsg(bgr, "bgr8")
    np.testing.assert_array_equal(bridge.imgmsg_to_cv2(msg, "rgb8"), bgr[:, :, ::-1])
    grey = bridge.imgmsg_to_cv2(msg, "mono8")
    assert grey.shape == (1, 4)
    assert grey.tolist() == [[76, 150, 29, 22]]  # 0.299 R + 0.587 G + 0.114 B, rounded
    rgba = bridge.imgmsg_to_cv2(msg, "rgba8")
    assert rgba[0, 3].tolist() == [30, 20, 10, 255]
    assert bridge.imgmsg_to_cv2(msg, "bgra8")[0, 0].tolist() == [0, 0, 255, 255]
    wide = bridge.imgmsg_to_cv2(msg, "bgr16")
    assert wide.dtype == np.uint16
    assert wide[0, 0].tolist() == [0, 0, 65535]
    assert wide[0, 3].tolist() == [2570, 5140, 7710]  # 8 bits scaled to 16: times 257
    assert bridge.imgmsg_to_cv2(msg, "mono16").tolist() == [[19532, 38550, 7453, 5654]]

    grey_msg = bridge.cv2_to_imgmsg(np.array([[0, 128, 255]], np.uint8), "mono8")
    assert bridge.imgmsg_to_cv2(grey_msg, "bgr8").tolist() == [
        [[0, 0, 0], [128, 128, 128], [255, 255, 255]]
    ]
    deep = bridge.cv2_to_imgmsg(np.array([[0, 257, 32896, 65535]], np.uint16), "mono16")
    assert bridge.imgmsg_to_cv2(deep, "mono8").tolist() == [[0, 1, 128, 255]]

    rgba_msg = bridge.cv2_to_imgmsg(np.array([[[1, 2, 3, 4]]], np.uint8), "rgba8")
    assert bridge.imgmsg_to_cv2(rgba_msg, "bgr8").tolist() == [[[3, 2, 1]]]


def test_conversions_the_real_bridge_refuses_raise_cv_bridge_error(bridge):
    generic = bridge.cv2_to_imgmsg(np.zeros((2, 2, 3), np.uint8))  # "8UC3": no colours
    with pytest.raises(CvBridgeError, match="has no colours"):
        bridge.imgmsg_to_cv2(generic, "bgr8")
    assert bridge.imgmsg_to_cv2(generic, "16UC3").dtype == np.uint16
    with pytest.raises(CvBridgeError, match="channels"):
        bridge.imgmsg_to_cv2(generic, "8UC1")
    with pytest.raises(CvBridgeError, match="needs an image of type 8UC1"):
        bridge.cv2_to_imgmsg(np.zeros((2, 2, 3), np.uint8), "mono8")
    with pytest.raises(CvBridgeError, match="needs an image of type 8UC3"):
        bridge.cv2_to_imgmsg(np.zeros((2, 2, 3), np.uint16), "bgr8")
    with pytest.raises(CvBridgeError, match="not an image encoding"):
        bridge.imgmsg_to_cv2(bridge.cv2_to_imgmsg(np.zeros((2, 2), np.uint8)), "grey")
    with pytest.raises(CvBridgeError, match="no OpenCV type"):
        bridge.cv2_to_imgmsg(np.zeros((2, 2), np.int64))
    with pytest.raises(TypeError, match="NumPy array"):
        bridge.cv2_to_imgmsg([[1, 2], [3, 4]])
    # CvBridgeError is a TypeError, as in the real bridge.
    assert issubclass(CvBridgeError, TypeError)
    short = Image(height=2, width=2, encoding="mono8", step=2, data=b"\x00\x01\x02")
    with pytest.raises(CvBridgeError, match="holds 3 bytes"):
        bridge.imgmsg_to_cv2(short)


def test_types_and_encodings_as_the_real_bridge_names_them(bridge):
    assert cv_bridge.getCvType("bgr8") == cv2.CV_8UC3
    assert bridge.encoding_to_cvtype2("mono16") == cv2.CV_16UC1
    assert bridge.encoding_to_cvtype2("32FC4") == cv2.CV_32FC4
    assert bridge.encoding_to_dtype_with_channels("rgba8") == ("uint8", 4)
    assert bridge.dtype_with_channels_to_cvtype2(np.dtype("float32"), 2) == "32FC2"
    assert bridge.cvtype2_to_dtype_with_channels(cv2.CV_16SC3) == ("int16", 3)


def test_padded_rows_and_big_endian_data_read_as_on_the_robot(bridge):
    # Rows of 3 grey pixels, each padded to 4 bytes.
    padded = Image(
        height=2, width=3, encoding="mono8", step=4, data=bytes([1, 2, 3, 0, 4, 5, 6, 0])
    )
    assert bridge.imgmsg_to_cv2(padded).tolist() == [[1, 2, 3], [4, 5, 6]]
    big = Image(
        height=1, width=2, encoding="mono16", is_bigendian=1, step=4, data=b"\x01\x02\xff\x00"
    )
    image = bridge.imgmsg_to_cv2(big)
    assert image.tolist() == [[258, 65280]]
    assert image.dtype.isnative
    assert bridge.cv2_to_imgmsg(np.array([[258]], ">u2"), "mono16").is_bigendian == 1


def test_a_jpeg_round_trip_through_compressed_image_stays_close(bridge):
    rows, columns = np.mgrid[0:48, 0:64]
    image = np.dstack([rows * 5, columns * 4, (rows + columns) * 2]).astype(np.uint8)
    msg = bridge.cv2_to_compressed_imgmsg(image)
    assert isinstance(msg, CompressedImage)
    assert msg.format == "jpg"
    assert msg.data[:2] == b"\xff\xd8"
    received = CompressedImage.from_bytes(msg.to_bytes())
    back = bridge.compressed_imgmsg_to_cv2(received)
    assert back.shape == image.shape
    assert np.abs(back.astype(int) - image).mean() < 2.0
    assert np.abs(back.astype(int) - image).max() < 16
    grey = bridge.compressed_imgmsg_to_cv2(received, "mono8")
    assert grey.shape == (48, 64)
    expected = cv2.cvtColor(back, cv2.COLOR_BGR2GRAY)
    np.testing.assert_array_equal(grey, expected)
    rgb = bridge.compressed_imgmsg_to_cv2(received, "rgb8")
    np.testing.assert_array_equal(rgb, back[:, :, ::-1])
    png = bridge.cv2_to_compressed_imgmsg(image, "png")
    assert png.format == "png"
    np.testing.assert_array_equal(bridge.compressed_imgmsg_to_cv2(png), image)


def test_compressed_data_that_does_not_decode_raises(bridge):
    with pytest.raises(CvBridgeError, match="do not decode"):
        bridge.compressed_imgmsg_to_cv2(CompressedImage(format="jpeg", data=b"not a jpeg"))
    with pytest.raises(CvBridgeError, match="do not decode"):
        bridge.compressed_imgmsg_to_cv2(CompressedImage(format="jpeg"))
    with pytest.raises(CvBridgeError, match="cannot write"):
        bridge.cv2_to_compressed_imgmsg(np.zeros((4, 4, 3), np.uint8), "nosuchformat")


def test_importing_the_package_imports_neither_cv2_nor_the_modules():
    import subprocess

    script = (
        "import sys, duckielib.libraries, duckielib.ros.modules as served\n"
        "print(sorted(served._library_modules()), 'cv2' in sys.modules,"
        " any(m.startswith('duckielib.libraries.') for m in sys.modules))"
    )
    result = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True
    )
    assert result.stdout.split() == [
        "['cv_bridge',",
        "'cv_bridge.core',",
        "'duckietown_utils',",
        "'duckietown_utils.exception_utils',",
        "'duckietown_utils.exceptions',",
        "'duckietown_utils.file_utils',",
        "'duckietown_utils.image_conversions',",
        "'duckietown_utils.jpg',",
        "'duckietown_utils.yaml_wrap',",
        "'message_filters',",
        "'rosbag',",
        "'rosbag.bag',",
        "'tf',",
        "'tf.transformations',",
        "'tf2_ros']",
        "False",
        "False",
    ]


# -- a camera node on the virtual Duckiebot ------------------------------------------------------
#: The rectangle the node draws: corners (x, y), BGR colour.
TOP_LEFT, BOTTOM_RIGHT, RED = (100, 80), (220, 160), (0, 0, 255)


def annotator(seen):
    """A camera node as students write it: decode, draw, republish raw and compressed."""
    import cv2 as opencv
    from cv_bridge import CvBridge as Bridge

    rospy.init_node("annotator")
    bridge = Bridge()
    pub = rospy.Publisher("~image", Image, queue_size=1)
    pub_compressed = rospy.Publisher("~image/compressed", CompressedImage, queue_size=1)

    def on_image(msg):
        image = bridge.compressed_imgmsg_to_cv2(msg, "bgr8")
        seen.append((msg.header.stamp, image.copy()))
        opencv.rectangle(image, TOP_LEFT, BOTTOM_RIGHT, RED, thickness=-1)
        pub.publish(bridge.cv2_to_imgmsg(image, "bgr8", header=msg.header))
        compressed = bridge.cv2_to_compressed_imgmsg(image)
        compressed.header = msg.header
        pub_compressed.publish(compressed)

    rospy.Subscriber("camera_node/image/compressed", CompressedImage, on_image, queue_size=1)
    rospy.spin()


def test_a_camera_node_draws_on_the_virtual_duckiebots_frames(monkeypatch):
    monkeypatch.setitem(sys.modules, "cv_bridge", cv_bridge)
    graph = Graph(stdout=io.StringIO(), stderr=io.StringIO())
    bot = VirtualDuckiebot(seed=3, graph=graph)
    seen, raw, compressed = [], [], []
    node = graph.host_node("viewer")
    from duckielib.ros.context import node_context

    with node_context(node):
        rospy.Subscriber("/duckiebot/annotator/image", Image, raw.append, queue_size=None)
        rospy.Subscriber(
            "/duckiebot/annotator/image/compressed", CompressedImage, compressed.append
        )
    bot.launch(annotator, seen)
    bot.run(0.2)
    bot.shutdown()
    assert [record.text for record in graph.log if record.level == ERROR] == []
    assert len(raw) >= 3
    assert len(raw) == len(seen) == len(compressed)
    bridge = CvBridge()
    (x0, y0), (x1, y1) = TOP_LEFT, BOTTOM_RIGHT
    for (stamp, original), msg, small in zip(seen, raw, compressed):
        assert msg.header.stamp == stamp
        assert (msg.width, msg.height, msg.encoding) == (640, 480, "bgr8")
        image = bridge.imgmsg_to_cv2(msg, "bgr8")
        assert (image[y0 : y1 + 1, x0 : x1 + 1] == RED).all()
        outside = np.ones(image.shape[:2], bool)
        outside[y0 : y1 + 1, x0 : x1 + 1] = False
        np.testing.assert_array_equal(image[outside], original[outside])
        assert original.std() > 5  # a real frame of the mat, not a blank image
        decoded = bridge.compressed_imgmsg_to_cv2(small)
        centre = decoded[(y0 + y1) // 2, (x0 + x1) // 2].astype(int)
        assert np.abs(centre - RED).max() < 8
        assert small.header.stamp == stamp
    stamps = [stamp.to_sec() for stamp, _ in seen]
    assert stamps == sorted(stamps)
    assert stamps[-1] - stamps[0] == pytest.approx((len(stamps) - 1) / 30, abs=1e-6)
