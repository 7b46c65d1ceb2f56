"""Hole fill for stitched panoramas: thin disocclusions from the background side, large unseen
regions (a ring rig's polar caps) smoothly.

A stitched eye or panorama has two kinds of holes. Disocclusions beside objects are a few pixels
wide and open along the parallax (rows of an equirect); the directional background fill of
issue 4 (:func:`ibr.render.fill.fill_background`) fills them best (20-21 dB on the hole pixels of
the ODS benchmark, against 14.7-16.6 dB for the pull-push of ``ibr interpolate``, docs/stitch.md).
Regions no camera saw (the zenith and nadir of a ring of cameras, 41.5 % of each ODS eye of the
8-camera ring) are tens to hundreds of pixels from any seen pixel; copying rows or columns into
them draws tall streaks. There the fill blends, with the distance to the nearest seen pixel, into
a smooth normalized pyramid of the seen colours (no depth: nothing behind a cap is known).
Measured on the ring's ODS eyes at 1024 wide: hole pixels 23.8 -> 25.6 dB, no streaks.

Pixel convention: (u, v) = (column, row) of the equirect (or any image), centres at integers. The
equirect's left and right edges are not joined (as in ``fill_background``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["CAP_PX_PER_WIDTH", "fill_panorama"]

#: Hole pixels farther than ``cap_px`` from any seen pixel blend into the smooth fill, fully at
#: twice that distance; ``cap_px`` defaults to this share of the image width (8 px at 1024 wide,
#: 32 at the default 4096), at least 4. Disocclusions of the ODS benchmark reach 4.2 px at 1024
#: wide and are unchanged; on the ring's caps 4 / 8 / 16 px gave 25.7 / 25.6 / 25.3 dB.
CAP_PX_PER_WIDTH = 1.0 / 128


def fill_panorama(color, depth, holes, *, cap_px: float | None = None):
    """Fill the holes of a stitched panorama (or one ODS eye).

    Parameters
    ----------
    color : (H, W, C) array, any dtype (integers are rounded back)
    depth : (H, W) float32 range or depth of the seen pixels (NaN where unknown)
    holes : (H, W) bool, the pixels no view saw
    cap_px : float, optional
        Distance (pixels) from the nearest seen pixel beyond which a hole pixel starts to blend
        into the smooth fill (fully at ``2 cap_px``); default ``max(4, W * CAP_PX_PER_WIDTH)``.

    Returns
    -------
    color, depth, filled
        New arrays (as :func:`ibr.render.fill.fill_background`): holes take the background side's
        colour, blended far from any seen pixel into the smooth fill; the depth is the directional
        fill's; every other pixel is bit-identical.
    """
    import cv2

    from ibr.base.validate import check_positive
    from ibr.render.fill import fill_background

    out, z, filled = fill_background(color, depth, holes)
    h, w = out.shape[:2]
    cap = max(4.0, w * CAP_PX_PER_WIDTH) if cap_px is None else check_positive("cap_px", cap_px)
    holes = np.asarray(holes)
    if not holes.any() or holes.all():
        return out, z, filled
    dist = cv2.distanceTransform(holes.astype(np.uint8), cv2.DIST_L2, 5)
    far = dist > cap
    if not far.any():
        return out, z, filled
    smooth = _smooth_fill(np.asarray(color, np.float32).reshape(h, w, -1), holes)
    t = np.clip((dist[far] - cap) / cap, 0.0, 1.0)[:, None]
    blend = (1.0 - t) * out.reshape(h, w, -1)[far].astype(np.float32) + t * smooth[far]
    if out.dtype.kind in "ui":
        info = np.iinfo(out.dtype)
        blend = np.clip(np.rint(blend), info.min, info.max)
    out.reshape(h, w, -1)[far] = blend.astype(out.dtype)
    return out, z, filled


def _smooth_fill(color: np.ndarray, holes: np.ndarray) -> np.ndarray:
    """(H, W, C) float32: the seen colours spread smoothly over the holes by a normalized pyramid
    (``cv2.pyrDown`` of weighted colour and weight; on the way up each level keeps its own
    normalized colour where its weight is high and takes the coarser level's elsewhere)."""
    import cv2

    weight = (~holes).astype(np.float32)
    levels = []
    s, wt = color * weight[..., None], weight
    while min(s.shape[:2]) > 2:
        levels.append((s, wt))
        s, wt = cv2.pyrDown(s), cv2.pyrDown(wt)
        if s.ndim == 2:  # OpenCV drops a single channel
            s = s[..., None]
    val = s / np.maximum(wt, 1e-6)[..., None]
    for s, wt in reversed(levels):
        up = cv2.pyrUp(val, dstsize=(s.shape[1], s.shape[0]))
        if up.ndim == 2:
            up = up[..., None]
        own = np.clip(4.0 * wt, 0.0, 1.0)[..., None]
        val = own * (s / np.maximum(wt, 1e-6)[..., None]) + (1.0 - own) * up
    return val
