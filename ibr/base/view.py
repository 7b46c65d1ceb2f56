"""An RGB-D view: color, planar depth and the camera that saw them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .validate import check_color, check_image
from .camera import Camera

__all__ = ["DEPTH_RANGE", "View", "no_valid_depth_message"]

#: Valid planar depths lie in this range (scene units). Values outside it are refused rather than
#: rendered into nonsense (1e-30 everywhere puts every point on the camera centre; 1e30 makes
#: every parallax zero); rescale such a depth (a view file's ``scale``) into the range.
DEPTH_RANGE = (1e-6, 1e9)


@dataclass(frozen=True, eq=False)
class View:
    """One RGB-D view.

    Parameters
    ----------
    color : (H, W), (H, W, 3) or (H, W, 4) array
        uint8, uint16, float32 or float64 color (any other dtype raises ``TypeError``); float
        colors are linear or display values in [0, 1].
    depth : (H, W) float32 array or None
        Planar z (along the camera's optical axis) in scene units, NaN where invalid (non-finite
        and non-positive values become NaN); valid values must lie in :data:`DEPTH_RANGE`. ``None``
        for a view that carries color and camera only (e.g. the Middlebury right image).
    camera : Camera
        Camera whose image size equals the color's.
    name : str
        Short label used in messages and file names.

    Notes
    -----
    The renderers cache what they derive from a view (its mesh, its colour layers) on the View
    object, so treat its arrays as read-only once it has been rendered: after editing colour or
    depth in place, make a new View (``View(color, depth, camera)``), or the old mesh and colours
    are used. Colour is kept as given (no copy; big-endian data is made native), depth as float32.
    """

    color: np.ndarray
    depth: np.ndarray | None
    camera: Camera
    name: str = "view"

    def __post_init__(self):
        color = check_color("color", self.color)
        if not color.dtype.isnative:  # big-endian data (a FITS or network buffer): the kernels read native
            color = color.astype(color.dtype.newbyteorder("="))
            object.__setattr__(self, "color", color)
        if color.dtype.kind == "f":
            bad = int(color.size - np.count_nonzero(np.isfinite(color)))
            if bad:  # the fill spread them over every hole
                raise ValueError(f"color: {bad} non-finite value(s) (NaN or inf); colour must be finite "
                                 "(mark missing pixels by NaN depth instead)")
        if not isinstance(self.camera, Camera):
            raise TypeError(f"camera: expected a Camera, got {type(self.camera).__name__}")
        if color.shape[:2] != self.camera.shape:
            raise ValueError(
                f"color: size {color.shape[1]}x{color.shape[0]} does not match camera size "
                f"{self.camera.width}x{self.camera.height}"
            )
        if self.depth is not None:
            depth = check_image("depth", self.depth, channels=(1,))
            if depth.dtype.kind == "b":  # True would pass for a depth of 1
                raise TypeError(f"depth: expected a float or integer depth map, got dtype {depth.dtype}")
            depth = depth.reshape(depth.shape[:2])
            if depth.shape != color.shape[:2]:
                raise ValueError(
                    f"depth: size {depth.shape[1]}x{depth.shape[0]} does not match color size "
                    f"{color.shape[1]}x{color.shape[0]}"
                )
            with np.errstate(invalid="ignore"):
                invalid = ~(np.isfinite(depth) & (depth > 0))
            if not invalid.all():  # range checked before the float32 cast, which would turn a float64
                valid = depth[~invalid]  # 1e40 into inf and 1e-50 into 0, both then NaN, silently
                lo, hi = float(valid.min()), float(valid.max())
                if lo < float(np.float32(DEPTH_RANGE[0])) or hi > float(np.float32(DEPTH_RANGE[1])):  # float32 bounds
                    raise ValueError(f"depth: valid values must lie in [{DEPTH_RANGE[0]:g}, {DEPTH_RANGE[1]:g}] "
                                     f"scene units, got {lo:.6g}..{hi:.6g} (rescale the depth, e.g. a view "
                                     "file's depth 'scale')")
            with np.errstate(over="ignore"):  # only invalid values (e.g. -1e40) can overflow
                depth = depth.astype(np.float32, copy=True)
            depth[invalid] = np.nan
            object.__setattr__(self, "depth", depth)

    @property
    def shape(self) -> tuple[int, int]:
        """Image shape ``(height, width)``."""
        return self.camera.shape

    @property
    def has_depth(self) -> bool:
        return self.depth is not None

    def require_depth(self, what: str = "this operation") -> np.ndarray:
        """Return the depth or raise a clear error naming the view."""
        if self.depth is None:
            raise ValueError(f"view {self.name!r}: {what} needs depth, but the view has none")
        return self.depth


def no_valid_depth_message(who: str, consequence: str) -> str:
    """The one wording of the error for a depth with no valid pixel, naming the view as ``who``
    (the library: ``"view: view 'room_a'"``; the CLI: the option and the file the user gave) and
    ending with ``consequence`` (its punctuation included, e.g. ``", so it cannot be a source"``)."""
    return f"{who}: the depth has no valid pixel (NaN, zero, negative or infinite everywhere){consequence}"
