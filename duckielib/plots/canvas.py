"""What the package's pictures share: a figure that shows itself in a notebook, and the tiles.

- :class:`NotebookFigure`: a matplotlib figure made without pyplot (so it works headless and
  from the ``duckie`` command) that a notebook still shows as a picture.
- :func:`draw_tile_grid`: the mat's tiles, :data:`duckielib.config.TILE_SIZE` metres apart.
  It is the only code that draws them: the pose-track plots (:mod:`~duckielib.plots.paths`)
  draw them as a light grid on white, the simulator's world (:mod:`~duckielib.plots.world`)
  as the mat looks, dark squares with light borders.
- :func:`tile_span`: the whole tiles that cover some positions.

Like every module of :mod:`duckielib.plots`, the library's only package that imports
matplotlib, it runs on the laptop only.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Sequence, Tuple

import numpy as np
from matplotlib.collections import LineCollection
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from duckielib.config import TILE_SIZE

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["draw_tile_grid"]

#: The gid of the tile borders, to find them among an axes' collections.
TILE_GRID_GID = "tile-grid"

#: How the borders look: (colour, line width in points) on white and on the mat.
_BORDERS = {False: ("#d0d0d0", 1.0), True: ("#e8e8dc", 1.5)}
#: The mat's tiles, alternating like a checkerboard.
_TILE_COLORS = ("#3a3a3e", "#48484d")


class NotebookFigure(Figure):
    """A figure that shows itself in a notebook as a picture.

    Jupyter draws pyplot's figures once pyplot's backend has started; a figure made without
    pyplot would otherwise be shown as the text ``<Figure size ...>`` until some cell has used
    pyplot.
    """

    def _repr_png_(self) -> bytes:
        from io import BytesIO

        buffer = BytesIO()
        self.savefig(buffer, format="png", bbox_inches="tight")
        return buffer.getvalue()


def tile_span(values: np.ndarray, tile_size: float = TILE_SIZE) -> Tuple[float, float]:
    """The smallest run of whole tiles, in metres, that covers ``values`` (at least one tile).

    Args:
        values: positions along one axis, in metres, any shape; NaNs are left out.
        tile_size: side of a tile, in metres.

    Returns:
        (low, high), both multiples of ``tile_size``; (0, tile_size) when nothing is finite.
    """
    values = np.asarray(values, dtype=float)
    finite = values[np.isfinite(values)]
    if finite.size == 0:
        return 0.0, tile_size
    low = math.floor(float(finite.min()) / tile_size)
    high = math.ceil(float(finite.max()) / tile_size)
    if high <= low:
        high = low + 1
    return low * tile_size, high * tile_size


def draw_tile_grid(
    ax: Axes,
    x_span: Sequence[float],
    y_span: Sequence[float],
    on_mat: bool = False,
    tile_size: float = TILE_SIZE,
) -> LineCollection:
    """Draw the borders of the mat's tiles under everything else, without moving the view.

    Args:
        ax: the axes to draw on.
        x_span: (low, high) in metres along x, multiples of ``tile_size`` (see
            :func:`tile_span`).
        y_span: (low, high) in metres along y, likewise.
        on_mat: draw the tiles as the mat looks, dark squares with light borders, rather than
            as a light grey grid on the figure's white.
        tile_size: side of a tile, in metres.

    Returns:
        The borders: one collection of straight lines, whose gid is :data:`TILE_GRID_GID`.
    """
    x_low, x_high = (float(value) for value in x_span)
    y_low, y_high = (float(value) for value in y_span)
    columns = round((x_high - x_low) / tile_size)
    rows = round((y_high - y_low) / tile_size)
    if on_mat:
        first = round(x_low / tile_size) + round(y_low / tile_size)
        for i in range(columns):
            for j in range(rows):
                ax.add_patch(
                    Rectangle(
                        (x_low + i * tile_size, y_low + j * tile_size),
                        tile_size,
                        tile_size,
                        facecolor=_TILE_COLORS[(first + i + j) % 2],
                        edgecolor="none",
                        zorder=0,
                    )
                )
    segments = [
        [(x_low + i * tile_size, y_low), (x_low + i * tile_size, y_high)]
        for i in range(columns + 1)
    ]
    segments += [
        [(x_low, y_low + j * tile_size), (x_high, y_low + j * tile_size)] for j in range(rows + 1)
    ]
    color, width = _BORDERS[on_mat]
    borders = LineCollection(
        segments, colors=color, linewidths=width, zorder=0.5, gid=TILE_GRID_GID
    )
    ax.add_collection(borders, autolim=False)
    return borders
