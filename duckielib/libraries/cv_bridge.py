"""cv_bridge: camera messages to OpenCV images (NumPy arrays) and back, as on a Duckiebot.

Use it exactly as ROS's ``cv_bridge``::

    from cv_bridge import CvBridge

    bridge = CvBridge()
    image = bridge.compressed_imgmsg_to_cv2(msg, "bgr8")   # the camera's JPEG, as BGR pixels
    cv2.rectangle(image, (10, 10), (50, 50), (0, 0, 255), 2)
    pub.publish(bridge.cv2_to_imgmsg(image, "bgr8"))

Encodings are ROS's names: ``bgr8``, ``rgb8``, ``mono8``, ``bgra8``, ``rgba8``, their 16-bit
twins (``mono16``, ``bgr16``...), Bayer patterns, ``yuv422``, and OpenCV's generic types
(``8UC3``, ``32FC1``...), which carry no colours. Conversions follow the real bridge: between
colour encodings only (a generic ``8UC3`` image does not become ``bgr8``), 8-bit values scaled
to 16 bits and back, and a failure raises :class:`CvBridgeError`.

Differences from the real one, on purpose: it runs with NumPy 2; an ``Image`` whose rows are
padded (``step`` larger than a row) is read row by row; a ``CompressedImage`` converted to
another encoding is read as what it decodes to (grey, BGR or BGRA) rather than always as BGR;
data that does not decode, or a format OpenCV cannot write, raises :class:`CvBridgeError`.
As on the robot, ``imgmsg_to_cv2(msg)`` with ``"passthrough"`` returns a read-only view of the
message's bytes: ask for an encoding (or ``.copy()`` it) to draw on the image.

Laptop side; never deployed (the robot has the real cv_bridge).
"""

from __future__ import annotations

import re
import sys
from typing import Any, Dict, List, Optional, Tuple

import numpy as np

from duckielib.messages import get_message_class

__all__ = ["CvBridge", "CvBridgeError", "getCvType"]

PASSTHROUGH = "passthrough"

#: OpenCV's depth names, their NumPy types, OpenCV's depth codes and bits per value.
_DEPTHS: Dict[str, Tuple[str, int, int]] = {
    "8U": ("uint8", 0, 8),
    "8S": ("int8", 1, 8),
    "16U": ("uint16", 2, 16),
    "16S": ("int16", 3, 16),
    "32S": ("int32", 4, 32),
    "32F": ("float32", 5, 32),
    "64F": ("float64", 6, 64),
}
_DEPTH_OF_DTYPE = {dtype: depth for depth, (dtype, _, _) in _DEPTHS.items()}
_DEPTH_OF_CODE = {code: depth for depth, (_, code, _) in _DEPTHS.items()}
_GENERIC = re.compile(r"(8U|8S|16U|16S|32S|32F|64F)(?:C([0-9]+))?")

# Colour families: what the channels mean, whatever the depth.
GRAY, RGB, BGR, RGBA, BGRA, YUV422 = "gray", "rgb", "bgr", "rgba", "bgra", "yuv422"
BAYER_RGGB, BAYER_BGGR, BAYER_GBRG, BAYER_GRBG = "rggb", "bggr", "gbrg", "grbg"

#: ROS's colour encodings: their family, OpenCV depth and channels.
_COLOR: Dict[str, Tuple[str, str, int]] = {
    "mono8": (GRAY, "8U", 1),
    "mono16": (GRAY, "16U", 1),
    "bgr8": (BGR, "8U", 3),
    "rgb8": (RGB, "8U", 3),
    "bgr16": (BGR, "16U", 3),
    "rgb16": (RGB, "16U", 3),
    "bgra8": (BGRA, "8U", 4),
    "rgba8": (RGBA, "8U", 4),
    "bgra16": (BGRA, "16U", 4),
    "rgba16": (RGBA, "16U", 4),
    "yuv422": (YUV422, "8U", 2),
    **{
        f"bayer_{pattern}{bits}": (pattern, f"{bits}U", 1)
        for pattern in (BAYER_RGGB, BAYER_BGGR, BAYER_GBRG, BAYER_GRBG)
        for bits in (8, 16)
    },
}

#: The OpenCV conversion (a ``cv2`` constant's name) from one colour family to another.
_CODES: Dict[Tuple[str, str], str] = {
    **{
        (source, target): f"COLOR_{source.upper()}2{target.upper()}"
        for source in (GRAY, RGB, BGR, RGBA, BGRA)
        for target in (GRAY, RGB, BGR, RGBA, BGRA)
        if source != target
    },
    **{
        (YUV422, target): f"COLOR_YUV2{target.upper()}_UYVY"
        for target in (GRAY, RGB, BGR, RGBA, BGRA)
    },
    # OpenCV names a Bayer pattern by the second row's first two pixels.
    **{
        (pattern, target): f"COLOR_Bayer{opencv}2{target.upper()}"
        for pattern, opencv in (
            (BAYER_RGGB, "BG"),
            (BAYER_BGGR, "RG"),
            (BAYER_GBRG, "GR"),
            (BAYER_GRBG, "GB"),
        )
        for target in (GRAY, RGB, BGR)
    },
}
#: Families an image may keep while changing only its depth (``mono8`` to ``mono16``...).
_SAME_FAMILY_OK = (GRAY, RGB, BGR, RGBA, BGRA, YUV422)
#: A step that changes the depth only (scaling 8 to 16 bits and back).
_DEPTH_STEP = ""


class CvBridgeError(TypeError):
    """An image or message cannot be converted (the message says why)."""


def _parse(encoding: str) -> Tuple[str, int]:
    """An encoding's OpenCV depth name and channel count.

    Raises:
        CvBridgeError: for an encoding ROS does not know.
    """
    if encoding in _COLOR:
        _, depth, channels = _COLOR[encoding]
        return depth, channels
    match = _GENERIC.fullmatch(encoding) if isinstance(encoding, str) else None
    if match is None:
        known = ", ".join(sorted(name for name in _COLOR if not name.startswith("bayer")))
        raise CvBridgeError(
            f"{encoding!r} is not an image encoding: use one of {known}, a Bayer pattern, "
            "or an OpenCV type such as 8UC3."
        )
    return match.group(1), int(match.group(2) or 1)


def _bits(encoding: str) -> int:
    return _DEPTHS[_parse(encoding)[0]][2]


def getCvType(encoding: str) -> int:  # noqa: N802 - the real module's name
    """OpenCV's type number of an encoding (``bgr8`` is ``CV_8UC3``, 16).

    Raises:
        CvBridgeError: for an encoding ROS does not know.
    """
    depth, channels = _parse(encoding)
    return _DEPTHS[depth][1] + ((channels - 1) << 3)


def _conversion(source: str, target: str) -> List[str]:
    """The steps from one encoding to another: ``cv2`` colour codes and depth changes.

    Raises:
        CvBridgeError: if the real bridge refuses the conversion too.
    """
    source_channels, target_channels = _parse(source)[1], _parse(target)[1]
    source_family = _COLOR[source][0] if source in _COLOR else None
    target_family = _COLOR[target][0] if target in _COLOR else None
    if source_family is None or target_family is None:
        if source_family is None and target_family is not None:
            raise CvBridgeError(
                f"An image of type {source} has no colours, so it cannot become {target}: "
                f"publish it with a colour encoding (for example cv2_to_imgmsg(image, 'bgr8'))."
            )
        if source_channels != target_channels:
            raise CvBridgeError(
                f"{source} has {source_channels} channels and {target} has {target_channels}: "
                "without colours, only the depth of an image can change."
            )
        return [_DEPTH_STEP]
    if source_family == target_family and source_family in _SAME_FAMILY_OK:
        return [_DEPTH_STEP]
    code = _CODES.get((source_family, target_family))
    if code is None:
        raise CvBridgeError(f"cv_bridge cannot convert an image from {source} to {target}.")
    if _bits(source) != _bits(target):
        return [code, _DEPTH_STEP]
    return [code]


def _change_depth(image: np.ndarray, source: str, target: str) -> np.ndarray:
    """``image`` with the target encoding's depth, scaled between 8 and 16 bits as OpenCV."""
    source_bits, target_bits = _bits(source), _bits(target)
    dtype = np.dtype(_DEPTHS[_parse(target)[0]][0])
    scale = 1.0
    if (source_bits, target_bits) == (8, 16):
        scale = 65535.0 / 255.0
    elif (source_bits, target_bits) == (16, 8):
        scale = 255.0 / 65535.0
    values = image.astype(np.float64) * scale if scale != 1.0 else image
    if dtype.kind == "f":
        return np.asarray(values, dtype=dtype)
    limits = np.iinfo(dtype)
    # OpenCV rounds to the nearest value (halves to even) and saturates.
    return np.clip(np.rint(values), limits.min, limits.max).astype(dtype)


def _convert(image: np.ndarray, source: str, target: str) -> np.ndarray:
    """A new image: ``image`` (in ``source``) in the ``target`` encoding."""
    if target == source:
        _parse(source)
        return image.copy()
    import cv2

    steps = _conversion(source, target)
    for step in steps:
        if step == _DEPTH_STEP:
            image = _change_depth(image, source, target)
        else:
            try:
                image = cv2.cvtColor(image, getattr(cv2, step))
            except cv2.error as error:
                raise CvBridgeError(
                    f"OpenCV cannot convert this image from {source} to {target}: "
                    f"{str(error).strip().splitlines()[-1]}"
                ) from None
    return image


def _require_array(cvim: Any, what: str) -> np.ndarray:
    if not isinstance(cvim, np.ndarray):
        raise TypeError(f"{what} takes an image as a NumPy array, not {type(cvim).__name__}.")
    return cvim


def _decoded_encoding(image: np.ndarray) -> str:
    """The encoding of an image as ``cv2.imdecode`` gives it: grey, BGR or BGRA."""
    channels = 1 if image.ndim == 2 else image.shape[2]
    names = {1: "mono", 3: "bgr", 4: "bgra"}
    if image.dtype in (np.uint8, np.uint16) and channels in names:
        return f"{names[channels]}{8 * image.dtype.itemsize}"
    return f"{_DEPTH_OF_DTYPE[image.dtype.name]}C{channels}"


class CvBridge:
    """Converts between ``sensor_msgs/Image`` or ``CompressedImage`` and OpenCV images.

    OpenCV images are NumPy arrays of shape (height, width, channels), or (height, width) for a
    single channel; OpenCV's colour images are BGR.

    Raises:
        ImportError: if OpenCV (``cv2``) is not installed.
    """

    def __init__(self) -> None:
        try:
            import cv2  # noqa: F401 - OpenCV does the colour conversions and compression
        except ImportError:
            raise ImportError(
                "cv_bridge needs OpenCV: install it with `pip install opencv-python-headless`."
            ) from None

    # Types, as the real bridge names them.

    def encoding_to_cvtype2(self, encoding: str) -> int:
        """OpenCV's type number of an encoding (``bgr8``: ``cv2.CV_8UC3``)."""
        return getCvType(encoding)

    def encoding_to_dtype_with_channels(self, encoding: str) -> Tuple[str, int]:
        """The NumPy type and channel count of an encoding (``bgr8``: ``("uint8", 3)``)."""
        depth, channels = _parse(encoding)
        return _DEPTHS[depth][0], channels

    def dtype_with_channels_to_cvtype2(self, dtype: Any, n_channels: int) -> str:
        """OpenCV's type name of a NumPy type with channels (``uint8``, 3: ``"8UC3"``)."""
        name = np.dtype(dtype).name
        if name not in _DEPTH_OF_DTYPE:
            raise CvBridgeError(
                f"Images of {name} values have no OpenCV type: use uint8, int8, uint16, "
                "int16, int32, float32 or float64."
            )
        return f"{_DEPTH_OF_DTYPE[name]}C{n_channels}"

    def cvtype2_to_dtype_with_channels(self, cvtype: int) -> Tuple[str, int]:
        """The NumPy type and channel count of OpenCV's type number (16: ``("uint8", 3)``)."""
        depth = _DEPTH_OF_CODE[cvtype & 7]
        return _DEPTHS[depth][0], (cvtype >> 3) + 1

    # Images.

    def imgmsg_to_cv2(self, img_msg: Any, desired_encoding: str = PASSTHROUGH) -> np.ndarray:
        """An ``Image`` message as an OpenCV image.

        Args:
            img_msg: a ``sensor_msgs/Image``.
            desired_encoding: the encoding to convert to, or ``"passthrough"`` for the
                message's own: then the array is a read-only view of the message's bytes.

        Raises:
            CvBridgeError: if the encoding is unknown, the data does not fit the size, or the
                conversion is impossible.
        """
        dtype_name, channels = self.encoding_to_dtype_with_channels(img_msg.encoding)
        dtype = np.dtype(dtype_name).newbyteorder(">" if img_msg.is_bigendian else "<")
        height, width, step = int(img_msg.height), int(img_msg.width), int(img_msg.step)
        row = width * channels * dtype.itemsize
        data = img_msg.data
        if isinstance(data, (list, tuple)):
            data = bytes(data)
        if step < row:
            raise CvBridgeError(
                f"This {img_msg.encoding} image's step ({step} bytes) is shorter than one row "
                f"of {width} pixels ({row} bytes)."
            )
        if len(data) < height * step:
            raise CvBridgeError(
                f"This image holds {len(data)} bytes of data, but {height} rows of {step} bytes "
                f"need {height * step}."
            )
        shape: Tuple[int, ...] = (height, width)
        strides: Tuple[int, ...] = (step, channels * dtype.itemsize)
        if channels > 1:
            shape += (channels,)
            strides += (dtype.itemsize,)
        image = np.ndarray(shape=shape, dtype=dtype, buffer=data, strides=strides)
        if not dtype.isnative:
            image = image.astype(dtype.newbyteorder("="))
        if desired_encoding == PASSTHROUGH:
            return image
        return _convert(image, img_msg.encoding, desired_encoding)

    def cv2_to_imgmsg(
        self, cvim: np.ndarray, encoding: str = PASSTHROUGH, header: Optional[Any] = None
    ) -> Any:
        """An OpenCV image as an ``Image`` message.

        Args:
            cvim: the image.
            encoding: what its channels are (``"bgr8"``...); it must fit the array's type and
                channels. ``"passthrough"`` names the array's OpenCV type (``"8UC3"``).
            header: the message's header (for example the camera message's, to keep its
                stamp).

        Raises:
            TypeError: if ``cvim`` is not a NumPy array.
            CvBridgeError: if the encoding does not fit the image.
        """
        image = _require_array(cvim, "cv2_to_imgmsg()")
        if image.ndim not in (2, 3):
            raise CvBridgeError(
                f"An image has 2 dimensions (grey) or 3 (colour), not {image.ndim}: "
                f"this array's shape is {image.shape}."
            )
        channels = 1 if image.ndim == 2 else image.shape[2]
        cv_type = self.dtype_with_channels_to_cvtype2(image.dtype, channels)
        if encoding != PASSTHROUGH:
            depth, wanted = _parse(encoding)
            if f"{depth}C{wanted}" != cv_type:
                raise CvBridgeError(
                    f"The encoding {encoding} needs an image of type {depth}C{wanted}, but this "
                    f"one is {cv_type} ({image.dtype.name}, {channels} channels)."
                )
        msg: Any = get_message_class("sensor_msgs/Image")()
        if header is not None:
            msg.header = header
        msg.height, msg.width = image.shape[0], image.shape[1]
        msg.encoding = cv_type if encoding == PASSTHROUGH else encoding
        order = image.dtype.byteorder
        msg.is_bigendian = int(order == ">" or (order == "=" and sys.byteorder == "big"))
        msg.data = image.tobytes()
        row = image.shape[1] * channels * image.dtype.itemsize
        msg.step = len(msg.data) // msg.height if msg.height else row
        return msg

    # Compressed images.

    def compressed_imgmsg_to_cv2(
        self, cmprs_img_msg: Any, desired_encoding: str = PASSTHROUGH
    ) -> np.ndarray:
        """A ``CompressedImage`` message (JPEG, PNG...) as an OpenCV image.

        Args:
            cmprs_img_msg: a ``sensor_msgs/CompressedImage``.
            desired_encoding: the encoding to convert to, or ``"passthrough"`` for the image
                as it decodes (BGR for a colour JPEG, 2 dimensions for a grey one).

        Raises:
            CvBridgeError: if the data does not decode or the conversion is impossible.
        """
        import cv2

        data = np.frombuffer(bytes(cmprs_img_msg.data), dtype=np.uint8)
        image = cv2.imdecode(data, cv2.IMREAD_UNCHANGED) if data.size else None
        if image is None:
            raise CvBridgeError(
                f"The {len(data)} bytes of this CompressedImage (format "
                f"{cmprs_img_msg.format!r}) do not decode as an image."
            )
        if desired_encoding == PASSTHROUGH:
            return image
        return _convert(image, _decoded_encoding(image), desired_encoding)

    def cv2_to_compressed_imgmsg(self, cvim: np.ndarray, dst_format: str = "jpg") -> Any:
        """An OpenCV image as a ``CompressedImage`` message.

        Args:
            cvim: the image (BGR, BGRA or grey).
            dst_format: the file format OpenCV writes: ``"jpg"``, ``"png"``, ``"bmp"``...;
                the message's ``format`` says it.

        Raises:
            TypeError: if ``cvim`` is not a NumPy array.
            CvBridgeError: if OpenCV cannot write the image in that format.
        """
        import cv2

        image = _require_array(cvim, "cv2_to_compressed_imgmsg()")
        try:
            ok, encoded = cv2.imencode("." + dst_format, image)
        except cv2.error:
            ok = False
        if not ok:
            raise CvBridgeError(
                f"OpenCV cannot write this {image.dtype.name} image of shape {image.shape} as "
                f"{dst_format!r}: use 'jpg' or 'png' for a BGR, BGRA or grey uint8 image."
            )
        msg: Any = get_message_class("sensor_msgs/CompressedImage")()
        msg.format = dst_format
        msg.data = encoded.tobytes()
        return msg


#: ``cv_bridge.core``: the real package's module for the same names.
core = sys.modules[__name__]
