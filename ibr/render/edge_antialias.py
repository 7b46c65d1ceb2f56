"""Anti-aliased silhouettes from subsamples of the depth-edge pixels only (``antialias=True``, #11).

A camera integrates each pixel over its area, so the truth's silhouette pixels mix the surfaces
on both sides of an edge; a renderer that traces each target pixel's *centre* gives such a pixel
the colour of one side only, a whole-pixel staircase. ``supersample=3`` renders every pixel 3 x 3
(at 9x the frame's time); here only the covered pixels with a neighbour on another surface or
uncovered, and colours that differ, are subsampled (:func:`edge_candidates`). For each of them
and each source the four diagonal subsample rays (:data:`SUBSAMPLE_OFFSETS`) are traced through
the quads that cover the pixel or one of its eight neighbours at their centres
(:func:`subsample_maps`; a quad that covers none of those nine centres is missed, as the frame
misses it), the subsamples are composited as the frame's pixels are (trust, blend, z-test), and
a pixel whose subsamples lie on two surfaces, or are partly uncovered, takes the mean of them
and its own colour (counted twice: a tent over the pixel) (:func:`average_edge_pixels`). View
synthesis re-mixes the foreground-rim subsamples that one source alone shows over the target's
background (:func:`~ibr.render.matting.rematte_subsamples`) before they are averaged.

At a source's own pose every subsample lies in its pixel's own quad, so a source comes back
unchanged. Measured (``python benchmarks/bench_edges.py --quick``, t = .25/.5/.75, covered
pixels): clutter's edge band 28.47 -> 29.99 dB, room's 30.98 -> 31.34; the real motorcycle warp
27.57 -> 27.93 dB; the 512 x 512 frame 1.5-1.65x (docs/edges.md).

Conventions: pixel (u, v) = (column, row), centres at integers; depth is planar z in the target
camera, NaN where uncovered; subsample s of candidate i is entry [s, i] of the (m, n) arrays.
"""

from __future__ import annotations

import functools

import cv2
import numpy as np

from . import _edge_kernels as _k
from .composite import _pixels_of
from .rasterize import SourceMaps, quad_setup
from .bands import run_bands
from ..base.camera import Camera
from ..base.validate import check_array, check_finite_scalar, check_positive

__all__ = ["SUBSAMPLE_OFFSETS", "average_edge_pixels", "edge_candidates", "subsample_maps", "unpack_subsamples"]

#: (du, dv) of the subsamples beside each edge pixel's centre: the four diagonal subsamples of
#: its 3 x 3 grid (with the centre, a quincunx). Measured (bench_edges, t = .25/.5/.75, edge band
#: of clutter / room): all eight off-centre subsamples 29.81 / 31.34 dB at twice the work, these
#: four 29.77 / 31.28, the four on the axes 29.58 / 31.35, the diagonals at 1/4 or 3/8 px 29.49 /
#: 29.69 on clutter.
SUBSAMPLE_OFFSETS = np.array([[-1, -1], [1, -1], [-1, 1], [1, 1]], np.float64) / 3
_RING = np.ones((3, 3), np.uint8)  # a pixel and its eight neighbours
_NO_Z = 1e30  # depth of uncovered pixels in edge_candidates: beyond every real depth, finite times (1 + tol)


def edge_candidates(depth: np.ndarray, color: np.ndarray, *, depth_tol: float = 0.02,
                    contrast: float = 0.0, exclude: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(rows, columns) of the target pixels where a silhouette can cross: their 3 x 3
    neighbourhood sees planar depths more than ``depth_tol`` (relative) apart or is partly
    uncovered, and its colours span at least ``contrast`` in some channel (an edge between
    like colours looks the same anti-aliased or not). ``exclude``: (H, W) bool pixels to
    leave out (e.g. those the fill recolours)."""
    depth = check_array("depth", depth, ndim=2, dtype_kind="f")
    color = _check_color(color, depth.shape)
    depth_tol = check_positive("depth_tol", depth_tol)
    contrast = check_finite_scalar("contrast", contrast)
    if exclude is not None and (np.shape(exclude) != depth.shape or np.asarray(exclude).dtype != np.bool_):
        raise ValueError(f"exclude: expected a bool array of the depth's shape {depth.shape}")
    z = np.array(depth, np.float32)  # NaN where uncovered: far beyond every depth instead
    cv2.patchNaNs(z, _NO_Z)
    zmax = cv2.dilate(z, _RING)
    zmin = cv2.erode(z, _RING)
    zmin *= np.float32(1.0 + depth_tol)
    mask = cv2.compare(zmax, zmin, cv2.CMP_GT)  # a step, or covered and uncovered pixels
    if contrast > 0:
        c = color if color.ndim == 3 else color[..., None]
        span = cv2.subtract(cv2.dilate(c, _RING), cv2.erode(c, _RING))
        span = functools.reduce(cv2.max, cv2.split(span)) if span.ndim == 3 else span  # numpy's max(-1): 40x
        mask &= cv2.compare(span, float(contrast), cv2.CMP_GE)
    if exclude is not None:
        mask[exclude] = 0
    return _pixels_of(mask)


def subsample_maps(mesh, camera: Camera, maps: SourceMaps, ys, xs, *, footprint: str = "free",
                   far_coord=np.float32(0.0), quads=None) -> tuple[SourceMaps, np.ndarray]:
    """Where the :data:`SUBSAMPLE_OFFSETS` subsamples of target pixels (``ys``, ``xs``) sample
    the source of ``mesh``, from the source's rasterized ``maps`` in ``camera`` (the frame's;
    quads are looked for among those covering the pixel or a neighbour at its centre).

    Returns the maps and ``same``, (m, n) bool: the subsample lies on the quad of its pixel's
    centre (or neither is covered). The maps are an image of subsamples, rows of ``camera``'s
    width (so that it is composited like a frame, in the frame's work arrays): entry ``s n + i``
    in row-major order is subsample s of pixel i, the rest is padding (uncovered);
    :func:`unpack_subsamples` gives the (m, n) view. Uncovered subsamples have NaN depth and
    ``far_coord`` map coordinates. ``quads``: the (coefficients, clamp flags) of the
    rasterizer's set-up of ``mesh`` for ``camera``, if at hand."""
    from ..mesh.quad_mesh import QuadMesh

    if not isinstance(mesh, QuadMesh):
        raise TypeError(f"mesh: expected a QuadMesh, got {type(mesh).__name__}")
    if not isinstance(camera, Camera):
        raise TypeError(f"camera: expected a Camera, got {type(camera).__name__}")
    if not isinstance(maps, SourceMaps) or maps.coverage.shape != camera.shape:
        raise ValueError(f"maps: expected the SourceMaps of the mesh rasterized into the camera ({camera.shape})")
    ys, xs = _check_pixels(ys, xs, camera.shape)
    n, m, w = len(ys), len(SUBSAMPLE_OFFSETS), camera.width
    size = -(-max(m * n, 1) // w) * w
    flat = [np.empty(size, np.float32), np.empty(size, np.float32), np.full(size, np.nan, np.float32),
            np.zeros(size, np.bool_)]
    flat[0][m * n:] = flat[1][m * n:] = far_coord
    same = np.ones((m, n), np.bool_)
    if n:
        if quads is None:
            coef, _, flags = quad_setup(mesh, camera, footprint, 0.01)
        else:
            coef, flags = quads
        run_bands(_k.subsample_quads, n, xs, ys, SUBSAMPLE_OFFSETS, maps.map_u, maps.map_v, maps.coverage,
                  mesh.quad_of_pixel, mesh.rects, coef, flags, np.float32(far_coord),
                  *[a[:m * n].reshape(m, n) for a in flat], same, min_rows=1024)
    return SourceMaps(*[a.reshape(-1, w) for a in flat]), same


def unpack_subsamples(a: np.ndarray, n: int) -> np.ndarray:
    """The (m, n[, C]) view of an image of subsamples (:func:`subsample_maps`; or of their
    composite) of n pixels."""
    m = len(SUBSAMPLE_OFFSETS)
    return a.reshape(-1, *a.shape[2:])[:m * n].reshape(m, n, *a.shape[2:])


def average_edge_pixels(color: np.ndarray, depth: np.ndarray, ys, xs, sub_color: np.ndarray, sub_depth: np.ndarray,
                        sub_coverage: np.ndarray, sub_same: np.ndarray | None = None, depth_tol: float = 0.02) -> int:
    """Filter the edge pixels among (``ys``, ``xs``) over their subsamples in place and return how
    many there were.

    Parameters
    ----------
    color, depth : (H, W, C), (H, W) arrays
        The finished frame: each pixel's centre subsample.
    ys, xs : (n,) int
        Covered candidate pixels (:func:`edge_candidates`).
    sub_color, sub_depth, sub_coverage : (m, n, C), (m, n), (m, n) arrays
        Their composited :data:`SUBSAMPLE_OFFSETS` subsamples (as :func:`subsample_maps` lays them out).
    sub_same : (m, n) bool array, optional
        Subsamples on the quads of their pixel's centre in every source (``subsample_maps``'
        ``same``): one surface with the centre whatever its slope, left out of the edge test
        (a steep plane's depth changes by several % within a pixel; a source then comes back
        unchanged at its own pose). None: none is.
    depth_tol : float
        An edge pixel has subsamples on two surfaces (sorted by inverse depth, two neighbours more
        than ``depth_tol`` apart: a step, not the slope of a grazing plane) or uncovered ones. It
        takes the weighted mean of its centre (twice, ``_edge_kernels.CENTRE_WEIGHT``) and
        subsamples, an uncovered subsample standing for the pixel itself (not for the hole's
        fill: the same frame with or without a fill).
    """
    depth = check_array("depth", depth, ndim=2, dtype_kind="f")
    if not isinstance(color, np.ndarray) or color.ndim != 3 or color.shape[:2] != depth.shape:
        raise ValueError(f"color: expected an (H, W, C) array of the depth's size {depth.shape}")
    ys, xs = _check_pixels(ys, xs, depth.shape)
    m, n = len(SUBSAMPLE_OFFSETS), len(ys)
    if (np.shape(sub_depth), np.shape(sub_coverage), np.shape(sub_color)) != ((m, n), (m, n), (m, n, color.shape[2])):
        raise ValueError(f"sub_color, sub_depth, sub_coverage: expected shapes {(m, n, color.shape[2])}, {(m, n)}, "
                         f"{(m, n)} (the subsamples of the {n} pixels), got {np.shape(sub_color)}, "
                         f"{np.shape(sub_depth)}, {np.shape(sub_coverage)}")
    if sub_same is None:
        sub_same = np.zeros((m, n), np.bool_)
    elif np.shape(sub_same) != (m, n):
        raise ValueError(f"sub_same: expected shape {(m, n)}, got {np.shape(sub_same)}")
    depth_tol = check_positive("depth_tol", depth_tol)
    edge = np.zeros(n, np.bool_)
    if n:
        _k.average_edges(color, depth, ys, xs, sub_color, sub_depth, sub_coverage,
                         np.ascontiguousarray(sub_same, np.bool_), float(depth_tol),
                         np.issubdtype(color.dtype, np.integer), edge)
    return int(edge.sum())


def _check_color(color, shape) -> np.ndarray:
    c = check_array("color", color, ndim=(2, 3), dtype_kind="uif")
    if c.shape[:2] != shape:
        raise ValueError(f"color: expected the depth's size {shape}, got {c.shape[:2]}")
    return c


def _check_pixels(ys, xs, shape) -> tuple[np.ndarray, np.ndarray]:
    """``ys``, ``xs`` as int64 arrays of pixels inside an image of ``shape`` (refused by name)."""
    ys, xs = (check_array(name, v, ndim=1, dtype_kind="iu") for name, v in (("ys", ys), ("xs", xs)))
    if ys.shape != xs.shape:
        raise ValueError(f"ys, xs: expected one row and one column per pixel, got {ys.size} and {xs.size}")
    h, w = shape
    if ys.size and (ys.min() < 0 or ys.max() >= h or xs.min() < 0 or xs.max() >= w):
        raise ValueError(f"ys, xs: expected pixels inside the {w}x{h} image")
    return np.ascontiguousarray(ys, np.int64), np.ascontiguousarray(xs, np.int64)
