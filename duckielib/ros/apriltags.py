"""Free Duckietown's AprilTag detector in the order its C library needs, wherever it is imported.

``dt_apriltags`` 3.1.7 (the latest on PyPI) frees a ``Detector``'s tag families before the
detector, whose own clean-up then reads the families it was given: memory already freed.
Nothing goes wrong at that moment; the heap is damaged, and the process dies later, anywhere,
of a "double free", an abort or a segmentation fault. A student's node that makes a detector
would crash the notebook's kernel or ``duckie run`` seconds or minutes after the detector went
away. The fix (free the detector first, as the C library's own example does) is merged in
Duckietown's repository, in its pull request 26, but not released.

Importing :mod:`duckielib.ros` places :class:`AprilTagsFix` on ``sys.meta_path``, just
before Python's own path finder (finders placed earlier keep their turn): when
``dt_apriltags`` is imported (by a node, a notebook, a test), its ``Detector`` gets a clean-up
that frees in the right order. The library itself is not changed on disk.
"""

from __future__ import annotations

import importlib.abc
import importlib.machinery
import sys
import types
from typing import Any, Optional, Sequence

__all__ = ["AprilTagsFix", "fix_detector", "fix_loaded"]

#: The module that defines ``Detector``.
MODULE = "dt_apriltags.apriltags"


def _free(detector: Any) -> None:
    """Free a detector, then its tag families: the C library's order."""
    pointer = getattr(detector, "tag_detector_ptr", None)
    if pointer is None:
        return
    detector.tag_detector_ptr = None  # once only, even if called again
    libc = detector.libc
    libc.apriltag_detector_destroy.restype = None
    libc.apriltag_detector_destroy(pointer)
    for family, created in detector.tag_families.items():
        destroy = getattr(libc, family + "_destroy")
        destroy.restype = None
        destroy(created)
    detector.tag_families = {}


def fix_detector(module: types.ModuleType) -> None:
    """Give ``module.Detector`` (of ``dt_apriltags.apriltags``) the clean-up in the right order."""
    detector = getattr(module, "Detector", None)
    if detector is not None and not getattr(detector, "_duckielib_fixed", False):
        detector.__del__ = _free
        detector._duckielib_fixed = True


class _Fixing(importlib.abc.Loader):
    """The real loader of ``dt_apriltags.apriltags``, followed by :func:`fix_detector`."""

    def __init__(self, loader: importlib.abc.Loader) -> None:
        self.loader = loader

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> Optional[types.ModuleType]:
        return self.loader.create_module(spec)

    def exec_module(self, module: types.ModuleType) -> None:
        self.loader.exec_module(module)
        fix_detector(module)

    def __getattr__(self, name: str) -> Any:  # get_filename, get_resource_reader...
        return getattr(self.loader, name)


class AprilTagsFix(importlib.abc.MetaPathFinder):
    """Finds ``dt_apriltags.apriltags`` as Python would, and fixes its ``Detector`` on loading."""

    def find_spec(
        self,
        fullname: str,
        path: Optional[Sequence[str]] = None,
        target: Optional[types.ModuleType] = None,
    ) -> Optional[importlib.machinery.ModuleSpec]:
        """The real spec of :data:`MODULE`, with a loader that fixes it; None for other names."""
        if fullname != MODULE:
            return None
        for finder in sys.meta_path:
            if finder is self or not hasattr(finder, "find_spec"):
                continue
            spec = finder.find_spec(fullname, path, target)
            if spec is not None:
                if spec.loader is not None:
                    spec.loader = _Fixing(spec.loader)
                return spec
        return None


def fix_loaded() -> None:
    """Fix ``Detector`` if ``dt_apriltags`` was imported before :class:`AprilTagsFix` was placed."""
    loaded = sys.modules.get(MODULE)
    if loaded is not None:
        fix_detector(loaded)
