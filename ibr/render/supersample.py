"""Supersampled rendering at depth edges (issue 11: the edge band).

A source pixel's colour is the mean over its footprint (a camera integrates; the bundled views
are 3 x 3 box-filtered), but a renderer that maps each target pixel *centre* to one source point
gives a silhouette pixel the colour of one side only: the jagged, up-to-a-pixel-off outlines
that dominate the error around depth edges (on clutter at t = 0.5, 217 of the band's 13 700
pixels hold half its squared error). With ``supersample=k`` (odd) the sources are upsampled k
x k with sub-pixel silhouettes (:func:`ibr.render.upsample.upsample_view`), the view is rendered
into the same camera at k times the resolution (:meth:`Camera.resized`: the centre subsample of
each pixel is its centre ray) and brought back with :func:`downsample_rendering`: every pixel
whose subsamples all have a colour is their mean (a box filter over the pixel, as the camera's).
Until the nineteenth session only *edge pixels* (subsamples more than 2 % apart in depth) were
boxed and the others kept their centre subsample, since boxing interiors blurred the Lanczos
textures (room -1.1 dB over all pixels); the sources' colour is now back-projected so that
each pixel's subsamples average to it (:mod:`ibr.render.superres`), and boxing every pixel
gains (clutter band 31.54 -> 31.77 dB with the back-projection). Depth, holes and filled pixels
are the centre subsample's. A source rendered at its own pose comes back within one level (the
rounding of nine subsamples; before: 821 of clutter a's pixels off by up to 22).

Measured (``python benchmarks/bench_edges.py --quick``, k = 3, t = .25/.5/.75, covered pixels):
clutter edge band 28.16 -> 31.02 dB, all covered pixels 37.07 -> 39.29 dB; room band 30.97 ->
32.21 dB, all 38.39 -> 39.92; the real motorcycle pair, left -> right, 27.55 -> 28.22 dB. The 1x
sources rendered the same way gave 29.95 / 37.96 (clutter) and 31.34 / 38.43 (room). It costs
the render at k^2 the pixels: the 512 x 512 two-source frame 8.1 -> 78 ms (9.4x; meshes cached),
and meshes of k^2 the pixels, built once per source.
"""

from __future__ import annotations

import functools

import cv2
import numpy as np

from ..base.validate import check_array

__all__ = ["SUPERSAMPLES", "check_supersample", "downsample_rendering", "supersampled_camera"]

#: Allowed factors: odd, so that each pixel's centre ray is one of its subsamples.
SUPERSAMPLES = (1, 3, 5)


def check_supersample(value) -> int:
    """``value`` as a supersampling factor: an odd integer in :data:`SUPERSAMPLES`, else a
    ValueError naming ``supersample``."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or int(value) not in SUPERSAMPLES:
        raise ValueError(f"supersample: expected one of {', '.join(map(str, SUPERSAMPLES))} (odd: the pixel "
                         f"centre is a subsample), got {value!r}")
    return int(value)


def supersampled_camera(camera, k: int):
    """``camera`` at k times its width and height (the same view; pixel-centre aware)."""
    from ..base.camera import Camera

    if not isinstance(camera, Camera):
        raise TypeError(f"camera: expected a Camera, got {type(camera).__name__}")
    k = check_supersample(k)
    return camera if k == 1 else camera.resized(camera.width * k, camera.height * k)


def _check_multiple(shape, k: int) -> None:
    if len(shape) < 2 or shape[0] % k or shape[1] % k or not shape[0] or not shape[1]:
        raise ValueError(f"supersampled arrays: expected a shape of multiples of k = {k}, got {tuple(shape)}")


def _block_means(x: np.ndarray, k: int) -> np.ndarray:
    """(H, W[, C]) float32: the k x k block means of a (k H, k W[, C]) array (OpenCV's area
    resampling, exact at an integer factor; a single channel axis is kept)."""
    x = np.asarray(x, np.float32)
    out = cv2.resize(x, (x.shape[1] // k, x.shape[0] // k), interpolation=cv2.INTER_AREA)
    return out[..., None] if out.ndim < x.ndim else out


def _subsample_planes(a: np.ndarray, k: int) -> list:
    """The k^2 (H, W) views ``a[i::k, j::k]`` of a (k H, k W) array: subsample (i, j) of every
    pixel."""
    return [a[i::k, j::k] for i in range(k) for j in range(k)]


def downsample_rendering(color_k, depth_k, holes_k, filled_k, k: int):
    """The k x k supersampled arrays of a rendering brought back to the target's resolution.

    Parameters
    ----------
    color_k : (k H, k W) or (k H, k W, C) array
        Colour of the subsamples (any dtype; integers are rounded back).
    depth_k : (k H, k W) float32
        Planar depth of the subsamples (NaN where unknown).
    holes_k, filled_k : (k H, k W) bool
        Subsamples that no source covered, and those of them the fill wrote.
    k : int
        The odd factor (:func:`check_supersample`).

    Returns
    -------
    color, depth, holes, filled : arrays of (H, W[, C])
        Colour: the subsamples' mean (a box filter, the camera's) where every subsample has a
        colour (covered or filled), else the centre subsample's; depth, holes and filled: the
        centre subsample's.
    """
    k = check_supersample(k)
    c = k // 2
    color_k = check_array("color_k", color_k, ndim=(2, 3), dtype_kind="uif")
    for name, a in (("depth_k", depth_k), ("holes_k", holes_k), ("filled_k", filled_k)):
        if np.shape(a) != color_k.shape[:2]:
            raise ValueError(f"{name}: expected shape {color_k.shape[:2]} (color_k's), got {np.shape(a)}")
    _check_multiple(color_k.shape[:2], k)
    centre = (slice(c, None, k), slice(c, None, k))
    color = np.array(color_k[centre], order="C")  # copies: the caller's arrays stay as they are
    depth = np.array(depth_k[centre], order="C")
    holes = np.array(holes_k[centre], order="C")
    filled = np.array(filled_k[centre], order="C")
    if k == 1:
        return color, depth, holes, filled
    # pixels whose subsamples all have a colour (covered or filled)
    whole = functools.reduce(np.logical_and, _subsample_planes(~np.asarray(holes_k, bool) | filled_k, k))
    # the block means by OpenCV's area resampling (exact at an integer factor; a gather of every
    # pixel's block took twice the frame); 8- and 16-bit colour directly, rounded as np.rint
    # would (a mean of k^2 = 9 or 25 integers is never half-way): 2.3 ms less per 512^2 frame
    if color.dtype in (np.uint8, np.uint16):
        mean = cv2.resize(np.asarray(color_k), (color.shape[1], color.shape[0]), interpolation=cv2.INTER_AREA)
    else:
        mean = _block_means(color_k, k)
        if np.issubdtype(color.dtype, np.integer):
            mean = np.rint(mean)
    mean = mean.astype(color.dtype, copy=False).reshape(color.shape)
    np.copyto(color, mean, where=whole.reshape(whole.shape + (1,) * (color.ndim - 2)))
    return color, depth, holes, filled
