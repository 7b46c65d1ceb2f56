"""Stereo pairs over a sequence: one interaxial and zero-parallax distance for every frame.

Choosing e and f per frame (``ibr.stereo.auto_stereo`` on each depth map) makes the depth
impression breathe as objects enter and leave the view -- a temporal artifact of its own. Over a
sequence the pair is chosen once, from the depth percentiles of all frames pooled
(:func:`sequence_stereo_params`, seed 000's comfort limit on the parallax visual angle), and every
frame is rendered with it (:func:`stereo_sequence`, seed 003 method 1 or 2).
"""

from __future__ import annotations

from typing import Iterable, Iterator

import numpy as np

from ..base.view import View
from ..stereo.pair import StereoPair, check_stereo_interpolation, check_stereo_supersample, stereo_pair
from ..stereo.stereo_camera import DEFAULT_MAX_ANGLE_DEG, auto_stereo

__all__ = ["pool_depths", "sequence_stereo_params", "stereo_sequence"]


def sequence_stereo_params(depths: Iterable, *, max_angle_deg: float = DEFAULT_MAX_ANGLE_DEG,
                           stride: int = 4, mode: str = "balanced") -> tuple[float, float]:
    """``(e, f)`` for a whole sequence: :func:`ibr.stereo.auto_stereo` on the pooled depths.

    Parameters
    ----------
    depths : iterable of (H, W) float arrays
        Planar depth of each frame (scene units, NaN invalid); consumed once.
    max_angle_deg : float
        Parallax visual-angle limit (seed 000, eq. 12 with the limit as a parameter).
    stride : int
        Every ``stride``-th pixel of every ``stride``-th row is pooled (:func:`pool_depths`).
    mode : {"balanced", "seed"}
        As in :func:`ibr.stereo.auto_stereo`.
    """
    z = pool_depths(depths, stride=stride)
    return auto_stereo(z, max_angle_deg=max_angle_deg, mode=mode)


def stereo_sequence(views: Iterable[View], *, e: float, f: float, source: str = "center",
                    method: str = "pixel", mesh_options: dict | None = None,
                    supersample: int = 1, interpolation: str = "linear") -> Iterator[StereoPair]:
    """Yield :func:`ibr.stereo.stereo_pair` of every view with the same ``e``, ``f`` and options
    (``supersample``: with ``method="mesh"``; ``interpolation``: with ``method="pixel"``; see there).

    ``views`` is consumed lazily (one view alive at a time). Disocclusions are filled per row
    from the background side and smoothed across rows, as for single frames; the pair's ``left_holes``/``right_holes``
    report them.
    """
    check_stereo_supersample(supersample, method)  # at the first frame asked for, before any view is read
    check_stereo_interpolation(interpolation, method)
    for view in views:
        yield stereo_pair(view, e=e, f=f, source=source, method=method, mesh_options=mesh_options,
                          supersample=supersample, interpolation=interpolation)


def pool_depths(depths: Iterable, *, stride: int = 4) -> np.ndarray:
    """The valid (finite, positive) depths of a sequence, pooled over its frames: every
    ``stride``-th pixel of every ``stride``-th row (memory stays small for long sequences; the
    percentiles do not need every pixel), or, for a frame whose valid pixels that grid misses
    (sparse depth, valid on every other row and column), every ``stride``²-th valid pixel. Raises
    naming ``depths`` when no frame has a valid depth."""
    if isinstance(stride, bool) or not isinstance(stride, (int, np.integer)) or stride < 1:
        raise ValueError(f"stride: expected an integer >= 1, got {stride!r}")
    pooled = []
    for i, d in enumerate(depths):
        d = np.asarray(d, np.float32)
        if d.ndim != 2:
            raise ValueError(f"depths[{i}]: expected an (H, W) depth map, got shape {d.shape}")
        s = d[::stride, ::stride].ravel()
        s = s[np.isfinite(s) & (s > 0)]
        pooled.append(s if s.size else d[np.isfinite(d) & (d > 0)][::stride * stride])
    if not pooled:
        raise ValueError("depths: expected at least one depth map, got none")
    z = np.concatenate(pooled)
    if z.size == 0:
        raise ValueError("depths: no valid (finite, positive) depth in any frame")
    return z
