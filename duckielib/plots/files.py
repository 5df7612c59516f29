"""Writing pictures to files: figures as PNG, SVG or PDF, animations as GIF or MP4.

Every picture of the package is saved here, and each file appears whole or not at all: it is
written under a hidden temporary name in the same folder, then renamed, and the temporary file
is removed if anything fails. A reader (a browser, a grader, another process) thus never sees
half a file, and a failed write leaves nothing behind.

- :func:`save_figure`: a figure as PNG, SVG or PDF.
- :func:`save_animation`: an animation (:func:`~duckielib.plots.animate_path`,
  :func:`~duckielib.plots.animate_run`) as a GIF, with Pillow, or an MP4, with ffmpeg.
- :func:`save_gif_frames`: pictures already drawn (the run player's frames) as a GIF.

Like every module of :mod:`duckielib.plots`, the library's only package that imports
matplotlib, it runs on the laptop only.
"""

from __future__ import annotations

import contextlib
import secrets
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Sequence, Tuple, Union

import numpy as np

from duckielib.errors import DuckielibError

if TYPE_CHECKING:
    from matplotlib.animation import FuncAnimation
    from matplotlib.figure import Figure

__all__ = ["save_animation", "save_figure", "save_gif_frames"]

_FIGURE_FORMATS = (".png", ".svg", ".pdf")
ANIMATION_FORMATS = (".gif", ".mp4")


def _partial_path(path: Path) -> Path:
    """A hidden, unused name next to ``path``, with the same (lower-case) suffix."""
    token = secrets.token_hex(4)
    return path.with_name(f".{path.stem}.{token}.partial{path.suffix.lower()}")


def _write_whole(path: Path, what: str, write: Callable[[Path], None]) -> Path:
    """Call ``write`` on a temporary file next to ``path``, then rename it to ``path``.

    Args:
        path: the file to write; its folder exists.
        what: what is written ("figure", "animation"), for the error sentences.
        write: writes the picture to the path it is given.

    Returns:
        ``path``.

    Raises:
        DuckielibError: if the file cannot be written; other errors of ``write`` are raised
            as they are. Either way, no temporary file is left behind.
    """
    partial = _partial_path(path)
    try:
        write(partial)
        partial.replace(path)
    except BaseException as error:
        with contextlib.suppress(FileNotFoundError):
            partial.unlink()
        if isinstance(error, OSError):
            raise DuckielibError(
                f"Cannot save the {what} as {str(path)!r}: {error.strerror or error}; check "
                f"that you may write there."
            ) from error
        raise
    return path


def checked_path(path: Union[str, Path], what: str, formats: Tuple[str, ...]) -> Path:
    """``path`` as a Path, once its suffix is one of ``formats`` and its folder exists."""
    path = Path(path)
    if path.suffix.lower() not in formats:
        names = f"{', '.join(formats[:-1])} or {formats[-1]}"
        raise DuckielibError(
            f"Cannot save the {what} as {str(path)!r}: use a name ending in {names}."
        )
    if not path.parent.is_dir():
        raise DuckielibError(
            f"Cannot save the {what} as {str(path)!r}: the folder {str(path.parent)!r} does "
            f"not exist; create it first or choose another path."
        )
    return path


def save_figure(fig: Figure, path: Union[str, Path]) -> Path:
    """Save ``fig`` as PNG, SVG or PDF, chosen by the suffix of ``path``.

    Args:
        fig: the figure to save.
        path: the file to write, ending in .png, .svg or .pdf; its folder must exist.

    Returns:
        The path written.

    Raises:
        DuckielibError: if the suffix is none of those, the folder does not exist, or the file
            cannot be written.
    """
    path = checked_path(path, "figure", _FIGURE_FORMATS)
    suffix = path.suffix.lower()
    return _write_whole(
        path,
        "figure",
        lambda partial: fig.savefig(
            partial, format=suffix[1:], dpi=150 if suffix == ".png" else "figure"
        ),
    )


def save_animation(
    anim: FuncAnimation, path: Union[str, Path], fps: float = 15.0, dpi: float = 72.0
) -> Path:
    """Save an animation as an animated GIF (with Pillow) or an MP4 video (with ffmpeg).

    Args:
        anim: the animation, from :func:`~duckielib.plots.animate_path` or
            :func:`~duckielib.plots.animate_run`.
        path: the file to write, ending in .gif or .mp4; its folder must exist.
        fps: frames per second of the file (give the ``fps`` the animation was made with).
        dpi: resolution; both animations' figures are 6 x 6 inches (432 pixels at 72 dpi).

    Returns:
        The path written.

    Raises:
        DuckielibError: if the suffix is neither, the folder does not exist, an MP4 is asked
            for without ffmpeg installed, or the file cannot be written.
    """
    from matplotlib import animation

    path = checked_path(path, "animation", ANIMATION_FORMATS)
    writer: animation.AbstractMovieWriter
    if path.suffix.lower() == ".gif":
        writer = animation.PillowWriter(fps=round(fps))
    elif animation.writers.is_available("ffmpeg"):
        writer = animation.FFMpegWriter(fps=round(fps))
    else:
        raise DuckielibError(
            f"Cannot save the animation as {str(path)!r}: an MP4 needs ffmpeg, which is not "
            f"installed; install it (for example `apt install ffmpeg`) or save a .gif instead."
        )
    return _write_whole(
        path, "animation", lambda partial: anim.save(str(partial), writer=writer, dpi=dpi)
    )


def save_gif_frames(
    frames: Sequence[np.ndarray],
    path: Union[str, Path],
    fps: float,
    colors: Sequence[Tuple[float, float, float]] = (),
) -> Path:
    """Save RGB frames as an animated GIF that loops, with one palette for every frame.

    One palette, worked out once from the first, middle and last frames and ``colors``, makes
    the file quick to write (a few milliseconds a frame) and keeps a colour the same in every
    frame.

    Args:
        frames: the pictures, each of shape (H, W, 3), uint8, all of one size.
        path: the file to write, ending in .gif; its folder must exist.
        fps: frames per second.
        colors: colours that must be exact in the file (RGB in [0, 1]), such as the LEDs'.

    Returns:
        The path written.

    Raises:
        DuckielibError: if there is no frame, the suffix is not .gif, the folder does not
            exist, or the file cannot be written.
    """
    from PIL import Image

    path = checked_path(path, "animation", (".gif",))
    if not len(frames):
        raise DuckielibError(f"Cannot save the animation as {str(path)!r}: it has no frame.")
    sample = [frames[0], frames[len(frames) // 2], frames[-1]]
    width = sample[0].shape[1]
    for red, green, blue in colors:
        swatch = np.empty((4, width, 3), dtype=np.uint8)
        swatch[:] = np.round(np.array([red, green, blue]) * 255)
        sample.append(swatch)
    palette = Image.fromarray(np.concatenate(sample, axis=0)).quantize(
        colors=255, method=Image.Quantize.MEDIANCUT
    )
    pictures = [
        Image.fromarray(frame).quantize(palette=palette, dither=Image.Dither.NONE)
        for frame in frames
    ]
    return _write_whole(
        path,
        "animation",
        lambda partial: pictures[0].save(
            partial,
            format="GIF",
            save_all=True,
            append_images=pictures[1:],
            duration=round(1000 / fps),
            loop=0,
        ),
    )
