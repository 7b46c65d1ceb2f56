"""Supersampled rendering at depth edges (issue 11: the edge band).

A source pixel's colour is the mean over its footprint (a camera integrates; the bundled views
are 3 x 3 box-filtered), but a renderer that maps each target pixel *centre* to one source point
gives a silhouette pixel the colour of one side only: the jagged, up-to-a-pixel-off outlines
that dominate the error around depth edges (on clutter at t = 0.5, 217 of the band's 13 700
pixels hold half its squared error). With ``supersample=k`` (odd) the sources are upsampled k
x k with sub-pixel silhouettes (:func:`ibr.render.upsample.upsample_view`), the view is rendered
into the same camera at k times the resolution (:meth:`Camera.resized`: the centre subsample of
each pixel is its centre ray) and brought back with :func:`downsample_rendering`: at *edge
pixels*, whose k x k subsamples see surfaces more than ``depth_tol`` apart, the colour is the
mean of the subsamples (a box filter over the pixel, as the camera's); everywhere else it is
the centre subsample (box-filtering interiors too blurred textures: the room pair lost 1.1 dB
over all pixels). Depth, holes and filled pixels are the centre subsample's. Unlike the plain
render, a supersampled one does not give a source back exactly at its own pose: its edge pixels
take the mean of bicubic subsamples instead of the recorded mixed colour (clutter a: 821 pixels
differ, by at most 22 levels).

Measured (``python benchmarks/bench_edges.py --quick``, k = 3, t = .25/.5/.75, covered pixels):
clutter edge band 28.16 -> 31.02 dB, all covered pixels 37.07 -> 39.29 dB; room band 30.97 ->
32.21 dB, all 38.39 -> 39.92; the real motorcycle pair, left -> right, 27.55 -> 28.22 dB. The 1x
sources rendered the same way gave 29.95 / 37.96 (clutter) and 31.34 / 38.43 (room). It costs
the render at k^2 the pixels: the 512 x 512 two-source frame 8.1 -> 78 ms (9.4x; meshes cached),
and meshes of k^2 the pixels, built once per source.
"""

from __future__ import annotations

import functools

import numpy as np

from ..base.validate import check_array, check_positive

__all__ = ["SUPERSAMPLES", "check_supersample", "downsample_rendering", "edge_pixels", "supersampled_camera"]

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


def edge_pixels(depth_k: np.ndarray, known_k: np.ndarray, k: int, depth_tol: float) -> np.ndarray:
    """(H, W) bool: pixels whose k x k subsamples all have a colour (``known_k``: covered or
    filled) and see depths more than ``depth_tol`` (relative) apart, or some with a depth and
    some without (a filled hole beside a surface).

    Parameters
    ----------
    depth_k : (k H, k W) float
        Planar depth of the subsamples, NaN where none is known.
    known_k : (k H, k W) bool
        Subsamples with a colour (not an unfilled hole).
    """
    k = check_supersample(k)
    depth_tol = check_positive("depth_tol", depth_tol)
    depth_k = check_array("depth_k", depth_k, ndim=2, dtype_kind="f")
    _check_multiple(depth_k.shape, k)
    if np.shape(known_k) != np.shape(depth_k):
        raise ValueError(f"known_k: expected shape {np.shape(depth_k)} (depth_k's), got {np.shape(known_k)}")
    # k^2 strided planes of (H, W), reduced element-wise: a reduction over the axes of a
    # (H, k, W, k) view took 30x as long (150 ms at 1536 x 1536, #13)
    planes = _subsample_planes(np.asarray(depth_k), k)
    zmax = functools.reduce(np.fmax, planes)  # NaN-ignoring: NaN only where every subsample is
    zmin = functools.reduce(np.fmin, planes)
    all_finite = functools.reduce(np.logical_and, [np.isfinite(p) for p in planes])
    known = functools.reduce(np.logical_and, _subsample_planes(np.asarray(known_k, bool), k))
    with np.errstate(invalid="ignore"):
        step = zmax > zmin * (1.0 + depth_tol)  # False where every subsample is NaN
    partial = np.isfinite(zmax) & ~all_finite
    return known & (step | partial)


def _check_multiple(shape, k: int) -> None:
    if len(shape) < 2 or shape[0] % k or shape[1] % k or not shape[0] or not shape[1]:
        raise ValueError(f"supersampled arrays: expected a shape of multiples of k = {k}, got {tuple(shape)}")


def _subsample_planes(a: np.ndarray, k: int) -> list:
    """The k^2 (H, W) views ``a[i::k, j::k]`` of a (k H, k W) array: subsample (i, j) of every
    pixel."""
    return [a[i::k, j::k] for i in range(k) for j in range(k)]


def downsample_rendering(color_k, depth_k, holes_k, filled_k, k: int, depth_tol: float = 0.02):
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
    depth_tol : float
        Relative depth difference that makes a pixel an edge pixel (:func:`edge_pixels`).

    Returns
    -------
    color, depth, holes, filled : arrays of (H, W[, C])
        Colour: the subsamples' mean at edge pixels, else the centre subsample; depth, holes
        and filled: the centre subsample's.
    """
    k = check_supersample(k)
    depth_tol = check_positive("depth_tol", depth_tol)
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
    edge = edge_pixels(depth_k, ~holes_k | filled_k, k, depth_tol)
    if edge.any():
        h, w = edge.shape
        blocks = color_k.reshape(h, k, w, k, -1)
        ys, xs = np.nonzero(edge)
        mean = blocks[ys, :, xs].astype(np.float64).mean(axis=(1, 2))  # (n, C)
        if np.issubdtype(color.dtype, np.integer):
            mean = np.rint(mean)
        color.reshape(h, w, -1)[ys, xs] = mean.astype(color.dtype)
    return color, depth, holes, filled
