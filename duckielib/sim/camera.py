"""The robot's camera: 640x480 JPEG frames of the mat ahead of the robot.

The rendering is deliberately simple: a top-down view of the mat, centred on the robot's
heading and rotated with it, so the image's top is straight ahead and its bottom edge lies just
in front of the bumper. Tiles are dark grey in a checkerboard of two shades, tile borders are
light lines, walls are brown and anything beyond them is black. Frames change as the robot
moves and their JPEG size changes from frame to frame, as on the real robot.

Pillow is imported here only, and only when a frame is encoded.
"""

from __future__ import annotations

import io
import math
from typing import Tuple

import numpy as np

from duckielib.sim.world import WALL_THICKNESS, World

__all__ = ["Camera", "CAMERA_RATE_HZ", "IMAGE_WIDTH", "IMAGE_HEIGHT"]

#: Frames per second the camera produces at most.
CAMERA_RATE_HZ = 30.0

#: Image width, in pixels.
IMAGE_WIDTH = 640

#: Image height, in pixels.
IMAGE_HEIGHT = 480

_TILE_DARK = np.array([52, 52, 56], dtype=np.uint8)
_TILE_LIGHT = np.array([68, 68, 72], dtype=np.uint8)
_LINE = np.array([225, 225, 215], dtype=np.uint8)
_WALL = np.array([150, 110, 70], dtype=np.uint8)
_BEYOND = np.array([10, 10, 12], dtype=np.uint8)
_FLOOR = np.array([130, 120, 105], dtype=np.uint8)
_PALETTE = np.stack([_TILE_DARK, _TILE_LIGHT, _LINE, _WALL, _BEYOND, _FLOOR])


class Camera:
    """Renders what the robot's camera sees.

    Args:
        world: the mat to render.
        view_width_m: width of the ground seen across the image, in metres.
        near_m: distance from the axle to the ground seen at the image's bottom edge, in metres.
        line_width_m: width of the tile border lines, in metres.
        rate_hz: frames per second the camera produces at most.
    """

    def __init__(
        self,
        world: World,
        view_width_m: float = 1.2,
        near_m: float = 0.08,
        line_width_m: float = 0.02,
        rate_hz: float = CAMERA_RATE_HZ,
    ) -> None:
        self.world = world
        self.rate_hz = rate_hz
        self.line_width_m = line_width_m
        metres_per_pixel = view_width_m / IMAGE_WIDTH
        rows = np.arange(IMAGE_HEIGHT, dtype=np.float64)
        cols = np.arange(IMAGE_WIDTH, dtype=np.float64)
        # Robot-frame coordinates of each pixel's centre: forward grows upwards in the image,
        # left grows to the left.
        forward = near_m + (IMAGE_HEIGHT - 0.5 - rows) * metres_per_pixel
        left = (IMAGE_WIDTH / 2 - 0.5 - cols) * metres_per_pixel
        self._forward, self._left = np.meshgrid(forward, left, indexing="ij")
        # The same in tiles and in single precision, for rendering (a tile is a few hundred
        # pixels; float32 keeps a millionth of one): half the memory traffic of float64.
        self._forward_tiles = (self._forward / world.tile_size).astype(np.float32)
        self._left_tiles = (self._left / world.tile_size).astype(np.float32)

    def pixels_in_world(self, pose: Tuple[float, float, float]) -> Tuple[np.ndarray, np.ndarray]:
        """World coordinates (x, y) of every pixel's ground point, each shape (480, 640), in m."""
        x, y, theta = pose
        cos_t, sin_t = math.cos(theta), math.sin(theta)
        world_x = x + cos_t * self._forward - sin_t * self._left
        world_y = y + sin_t * self._forward + cos_t * self._left
        return world_x, world_y

    def palette_indices(self, pose: Tuple[float, float, float]) -> np.ndarray:
        """What each pixel seen from ``pose`` shows, as an index into the camera's palette.

        Returns:
            Shape (480, 640), dtype uint8: 0 and 1 the tiles' two shades, 2 a tile border,
            3 a wall, 4 beyond the walls, 5 the floor around a mat without walls.
        """
        world = self.world
        x, y, theta = pose
        size = world.tile_size
        cos_t, sin_t = np.float32(math.cos(theta)), np.float32(math.sin(theta))
        tiles_x = np.float32(x / size) + cos_t * self._forward_tiles - sin_t * self._left_tiles
        tiles_y = np.float32(y / size) + sin_t * self._forward_tiles + cos_t * self._left_tiles
        index = ((np.floor(tiles_x) + np.floor(tiles_y)).astype(np.int32) & 1).astype(np.uint8)
        half_line = np.float32(self.line_width_m / 2 / size)
        on_line = (np.abs(tiles_x - np.round(tiles_x)) < half_line) | (
            np.abs(tiles_y - np.round(tiles_y)) < half_line
        )
        index[on_line] = 2
        width, height = world.width / size, world.height / size
        outside = (tiles_x < 0) | (tiles_x > width) | (tiles_y < 0) | (tiles_y > height)
        if world.walls:
            wall = WALL_THICKNESS / size
            beyond = (
                (tiles_x < -wall)
                | (tiles_x > width + wall)
                | (tiles_y < -wall)
                | (tiles_y > height + wall)
            )
            index[outside] = 3
            index[beyond] = 4
        else:
            index[outside] = 5
        return index

    def render(self, pose: Tuple[float, float, float]) -> np.ndarray:
        """The image seen from ``pose`` (x, y, theta): RGB, shape (480, 640, 3), dtype uint8."""
        return _PALETTE[self.palette_indices(pose)]

    def jpeg(self, pose: Tuple[float, float, float], quality: int = 80) -> bytes:
        """The image seen from ``pose`` as JPEG bytes (what the camera node publishes).

        Pillow colours the palette image itself, faster than building the RGB array first.
        """
        from PIL import Image

        image = Image.fromarray(self.palette_indices(pose), mode="P")
        image.putpalette(_PALETTE.tobytes())
        buffer = io.BytesIO()
        image.convert("RGB").save(buffer, format="JPEG", quality=quality)
        return buffer.getvalue()

    @staticmethod
    def encode_jpeg(image: np.ndarray, quality: int = 80) -> bytes:
        """``image`` (RGB, shape (H, W, 3), uint8) as JPEG bytes."""
        from PIL import Image

        buffer = io.BytesIO()
        Image.fromarray(np.ascontiguousarray(image, dtype=np.uint8)).save(
            buffer, format="JPEG", quality=quality
        )
        return buffer.getvalue()
