"""The result of view synthesis: a rendered view and what is known about each pixel (colour,
depth, the holes no source covered, the pixels the fill wrote), in the target camera's
conventions (pixel centres at integer coordinates, planar z, NaN where nothing is known)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..base.camera import Camera
from ..base.view import View

__all__ = ["Rendering"]


@dataclass(frozen=True, eq=False)
class Rendering:
    """A rendered view and what is known about each pixel.

    Attributes
    ----------
    color : (H, W, C) or (H, W) array
        Same dtype and channel layout as the source color.
    depth : (H, W) float32
        Planar z in ``camera`` (scene units); NaN where nothing is known (unfilled holes; filled
        pixels carry the depth of what filled them).
    holes : (H, W) bool
        Pixels that no source covered (before filling): every value there is invented.
    filled : (H, W) bool
        Pixels whose colour the fill wrote (previous frame or background fill): the holes it
        filled and covered pixels sampled from a source's background rim (their colour mixed in
        the foreground) beside a hole or the other source's pixels
        (:attr:`~ibr.render.composite.Composite.replace`).
    camera : Camera
        The target camera.
    t : float or None
        Interpolation parameter (0 = first source, 1 = second) when the camera came from one.
    """

    color: np.ndarray
    depth: np.ndarray
    holes: np.ndarray
    filled: np.ndarray
    camera: Camera
    t: float | None = None

    @property
    def unfilled(self) -> np.ndarray:
        """(H, W) bool: holes still empty after filling (color 0, depth NaN)."""
        return self.holes & ~self.filled

    @property
    def hole_fraction(self) -> float:
        """Share of pixels no source covered (before filling)."""
        return float(self.holes.mean())

    def to_view(self, name: str = "rendering") -> View:
        """The rendering as a :class:`~ibr.base.view.View` (e.g. for :func:`ibr.save_view`)."""
        return View(self.color, self.depth, self.camera, name)
