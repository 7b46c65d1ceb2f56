"""Hole filling after compositing (seed 002 section 2.2, step 2, and a single-frame fill).

* ``fill_previous``: in an animated transition the holes left after two-source compositing take
  the previous output frame ("painter's algorithm" over the last frame), which avoids flicker.
  Only hole pixels are written.
* ``fill_background``: for a single frame, a depth-aware fill. Disocclusions open *behind*
  foreground objects, so each hole pixel takes the farther (background) of its nearest covered
  neighbours along the row and the column, never the foreground; the filled depth is the
  background's.
* ``fill_background_rows``: the same rule along rows only, for horizontal-only parallax (stereo
  pairs, seed 003): each run of uncovered pixels takes the deeper of its two row neighbours.

Both return new arrays and a ``filled`` mask; nothing is invented silently (the interpolation
result carries ``holes`` and ``filled``). Pixel convention: (u, v) = (column, row), centers at
integers.
"""

from __future__ import annotations

import numpy as np

from . import _fill_kernels as _k
from ..base.validate import check_array, check_image, check_positive

__all__ = ["FILLS", "fill_background", "fill_background_rows", "fill_previous"]

#: Fill modes accepted by :func:`ibr.interpolate` and ``ibr interpolate --fill``.
FILLS = ("previous", "inpaint", "none")


def _check(color, depth, holes):
    color = np.asarray(color)
    depth = np.asarray(depth)
    holes = np.asarray(holes)
    if color.ndim != 3:
        raise ValueError(f"color: expected (H, W, C), got shape {color.shape}")
    if depth.shape != color.shape[:2]:
        raise ValueError(f"depth: expected shape {color.shape[:2]}, got {depth.shape}")
    if holes.shape != color.shape[:2] or holes.dtype != np.bool_:
        raise ValueError(f"holes: expected a bool array of shape {color.shape[:2]}, got {holes.dtype} {holes.shape}")
    return color, depth, holes


def fill_previous(color, depth, holes, previous_color, previous_depth=None):
    """Copy the previous frame into the hole pixels (seed 002 step 7).

    Parameters
    ----------
    color : (H, W, C) array
    depth : (H, W) float32
    holes : (H, W) bool
        Pixels to fill.
    previous_color : (H, W, C) array
        Previous output frame (same shape and dtype as ``color``).
    previous_depth : (H, W) float32, optional
        Its depth; filled pixels get NaN depth when omitted.

    Returns
    -------
    color, depth, filled
        New arrays; ``filled`` equals ``holes``. Pixels outside ``holes`` are bit-identical to the
        input.
    """
    color, depth, holes = _check(color, depth, holes)
    prev = np.asarray(previous_color)
    if prev.shape != color.shape:
        raise ValueError(f"previous_color: expected shape {color.shape}, got {prev.shape}")
    out = color.copy()
    out[holes] = prev[holes]
    z = depth.astype(np.float32, copy=True)
    if previous_depth is None:
        z[holes] = np.nan
    else:
        pz = np.asarray(previous_depth)
        if pz.shape != depth.shape:
            raise ValueError(f"previous_depth: expected shape {depth.shape}, got {pz.shape}")
        z[holes] = pz[holes]
    return out, z, holes.copy()


def fill_background(color, depth, holes, *, depth_tol: float = 0.05, max_dist: int | None = None):
    """Depth-aware single-frame fill that propagates background, not foreground.

    Each hole pixel looks for the nearest non-hole pixel left, right, up and down (at most
    ``max_dist`` pixels away). The farthest of those depths ``z_bg`` marks the background; the
    candidates with depth ``>= z_bg (1 - depth_tol)`` are averaged with weights 1/distance.

    Parameters
    ----------
    color : (H, W, C) array (any dtype; integer results are rounded)
    depth : (H, W) float32 planar depth, NaN where unknown
    holes : (H, W) bool
    depth_tol : float
        Relative depth band counted as background.
    max_dist : int, optional
        Search radius in pixels (default: unlimited).

    Returns
    -------
    color, depth, filled
        New arrays. ``filled`` marks the hole pixels that got a value; holes without any
        candidate (e.g. a whole empty row and column) stay as they were.
    """
    color, depth, holes = _check(color, depth, holes)
    out = np.ascontiguousarray(color).copy()
    z = np.ascontiguousarray(depth, dtype=np.float32).copy()
    return out, z, _fill_background_inplace(out, z, holes, depth_tol=depth_tol, max_dist=max_dist)


def _fill_background_inplace(color, depth, holes, *, depth_tol: float = 0.05, max_dist=None) -> np.ndarray:
    """:func:`fill_background` writing into ``color`` (C-contiguous (H, W, C)) and ``depth``
    (C-contiguous float32); returns ``filled``. Internal: callers own both arrays."""
    depth_tol = check_positive("depth_tol", depth_tol)
    max_dist = np.iinfo(np.int64).max if max_dist is None else int(check_positive("max_dist", max_dist))
    filled = np.zeros(holes.shape, np.bool_)
    if holes.any():
        _k.background_fill(color, depth, np.ascontiguousarray(holes), depth_tol, max_dist,
                           color.dtype.kind in "ui", filled)
    return filled


def fill_background_rows(color, depth, coverage) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fill uncovered pixels row by row from the background side.

    Each run of uncovered pixels takes the color and depth of the deeper of its two covered row
    neighbours (a disocclusion opens behind a foreground edge, so the background is what the
    hidden area most likely continues); runs at the image border take their only neighbour.
    Returns copies ``(color float32 (H, W, C), depth float32, holes bool)``.
    """
    col = check_image("color", color)
    col = np.ascontiguousarray((col[..., None] if col.ndim == 2 else col).astype(np.float32, copy=True))
    d = check_array("depth", depth, shape=col.shape[:2], dtype_kind="f").astype(np.float32, copy=True)
    cov = check_array("coverage", coverage, shape=col.shape[:2], dtype_kind="b")
    d[~cov] = np.nan
    holes = np.zeros(cov.shape, np.bool_)
    _k.fill_rows_background(col, d, np.ascontiguousarray(cov), holes)
    return col, d, holes
