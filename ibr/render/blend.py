"""N-source depth-aware blending: render any number of RGB-D sources into one target camera.

Two-source compositing (:mod:`ibr.render.composite`) generalized for camera rigs (6-16 views):
each source's quad mesh is rasterized into the target (pinhole :class:`~ibr.base.camera.Camera`
or :class:`~ibr.base.ray_camera.SphericalCamera`), then added to running accumulators with a
per-pixel z-test of relative tolerance ``rel_tol`` (the nearest surface wins; samples of the same
surface within the tolerance are blended). Weights (see :mod:`ibr.render._blend_kernels`) prefer
the source that sees the surface from nearest the target ray (small angle at the surface point),
most frontally (incidence), away from its own depth edges (mixed pixels), and
fade toward each source's image border so the change of winning source leaves no seam.

Conventions: colour float32 in the sources' value scale; depth is the range along each ray for
spherical targets and planar z for pinhole targets; ``holes`` is True where no source saw the
pixel; ``winner`` the index of the highest-weight source per pixel (-1 in holes).
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Sequence

import cv2
import numpy as np

from ..base.camera import Camera
from ..base.depth import depth_steps
from ..base.ray_camera import SphericalCamera
from ..base.validate import check_choice, check_positive
from . import _blend_kernels as _k
from .rasterize import _mesh_inv_depth, as_float_color, rasterize_mesh, scratch
from .ray_raster import rasterize_mesh_rays
from .rasterize import SourceMaps
from ..base.first_run import await_kernels

__all__ = ["Blended", "blend_sources", "edge_confidence", "prefilter_sigma", "source_prior"]

#: Relative inverse-depth jump between neighbouring source pixels that counts as a depth edge.
EDGE_JUMP = 0.05
#: Distance (source pixels) from a depth edge over which the confidence ramps from low to 1.
EDGE_RAMP_PX = 2.0

_conf_cache: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()
_prior_cache: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def edge_confidence(mesh) -> np.ndarray:
    """(H, W) float32 confidence of each source pixel: ``clip(d / EDGE_RAMP_PX, 0.02, 1)`` with d
    the distance (px) to the nearest pixel on either side of a depth edge of the source
    (inverse depth jumping by more than ``EDGE_JUMP`` relative, or no depth next to depth).

    Pixels on a silhouette mix foreground and background colour in a real (or anti-aliased)
    image; with the low weight, a clean pixel of another source wins where one exists. Cached
    per mesh.
    """
    conf = _conf_cache.get(mesh)
    if conf is None:
        inv = _mesh_inv_depth(mesh)
        edge = depth_steps(inv, EDGE_JUMP)
        if edge.any():
            dist = cv2.distanceTransform((~edge).astype(np.uint8), cv2.DIST_L2, 3)
        else:
            dist = np.full(inv.shape, np.inf, np.float32)
        conf = np.clip(dist / EDGE_RAMP_PX, 0.02, 1.0).astype(np.float32)
        conf.setflags(write=False)
        _conf_cache[mesh] = conf
    return conf


#: Prefilter strength: Gaussian sigma = PREFILTER_K * sqrt(s^2 - 1) source pixels for a source
#: s times finer than the target (measured on the ``capture`` scene: best PSNR at 0.35-0.45 for
#: s = 1.1-1.6; benchmarks/bench_stitch.py).
PREFILTER_K = 0.4


def _pixels_per_radian(camera) -> float:
    """Sampling density at the image centre (pinhole) or along the equator (spherical)."""
    if isinstance(camera, SphericalCamera):
        return camera.width / (2.0 * np.pi)
    return float(np.sqrt(camera.fx * camera.fy))


def prefilter_sigma(source_camera, target_camera) -> float:
    """Gaussian sigma (source pixels) that band-limits a source to the target's sampling rate.

    A target pixel averages the scene over its own footprint; sampling a finer source at one
    point per target pixel would alias its fine texture. With ``s`` the ratio of source to target
    pixels per radian (source centre vs target centre/equator), the missing blur is about that of
    a box of ``s`` source pixels less the source's own pixel, variance ``(s^2 - 1) / 12``; the
    constant ``PREFILTER_K`` was fitted on the synthetic capture scene. 0 when ``s <= 1``.
    """
    s = _pixels_per_radian(source_camera) / _pixels_per_radian(target_camera)
    return float(PREFILTER_K * np.sqrt(max(s * s - 1.0, 0.0)))


def _prefilter(color: np.ndarray, sigma: float) -> np.ndarray:
    if sigma < 0.05:
        return color
    k = 2 * int(np.ceil(3.0 * sigma)) + 1
    return cv2.GaussianBlur(color, (k, k), sigma, borderType=cv2.BORDER_REPLICATE).reshape(color.shape)


def incidence(mesh) -> np.ndarray:
    """(H, W) float32 cosine between each source pixel's ray and its quad's plane normal (1 = seen
    head-on, 0 = grazing or no quad).

    The quad's plane in the source camera frame is ``n . X = 1`` with ``n = (a fx, b fy,
    a cx + b cy + c)`` (inverse depth ``1/z = a u + b v + c``); the pixel's point is
    ``X = z (x', y', 1)``, ``x' = (u - cx) / fx``, so ``cos = (n . X) / (|n| |X|) =
    (1/z) / (|n| sqrt(x'^2 + y'^2 + 1))``.
    """
    cam = mesh.camera
    q = mesh.quad_of_pixel
    h, w = q.shape
    v, u = np.mgrid[0:h, 0:w]
    p = mesh.inv_depth_planes[np.where(q >= 0, q, 0)]
    a, b, c = p[..., 0], p[..., 1], p[..., 2]
    n_norm = np.sqrt((a * cam.fx) ** 2 + (b * cam.fy) ** 2 + (a * cam.cx + b * cam.cy + c) ** 2)
    inv = a * u + b * v + c
    ray = np.sqrt(((u - cam.cx) / cam.fx) ** 2 + ((v - cam.cy) / cam.fy) ** 2 + 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        cos = np.where((q >= 0) & (inv > 0), inv / (n_norm * ray), 0.0)
    return np.clip(cos, 0.0, 1.0).astype(np.float32)


def source_prior(mesh) -> np.ndarray:
    """(H, W) float32 weight of each source pixel before the target is known:
    ``incidence(mesh)**2 * edge_confidence(mesh)`` (frontal, clean pixels win). Cached per mesh."""
    prior = _prior_cache.get(mesh)
    if prior is None:
        prior = (incidence(mesh) ** 2 * edge_confidence(mesh)).astype(np.float32)
        prior.setflags(write=False)
        _prior_cache[mesh] = prior
    return prior


@dataclass(frozen=True, eq=False)
class Blended:
    """Result of :func:`blend_sources`.

    Attributes
    ----------
    color : (H, W, C) float32
        Blended colour in the sources' value scale, 0 in holes.
    depth : (H, W) float32
        Range along the ray (spherical target) or planar z (pinhole target); NaN in holes.
    holes : (H, W) bool
        True where no source covered the pixel.
    winner : (H, W) int16
        Index of the source with the largest weight at each pixel, -1 in holes.
    """

    color: np.ndarray
    depth: np.ndarray
    holes: np.ndarray
    winner: np.ndarray


def _target_shape(camera) -> tuple[int, int]:
    if isinstance(camera, (Camera, SphericalCamera)):
        return camera.shape
    raise TypeError(f"camera: expected a Camera or a SphericalCamera, got {type(camera).__name__}")


def blend_sources(sources: Sequence, camera, *, rel_tol: float = 0.02, sigma_deg: float = 10.0,
                  feather_px: float = 16.0, footprint: str = "free", interpolation: str = "linear",
                  antialias: bool = True, progress=None) -> Blended:
    """Render and blend N sources into one target camera.

    Parameters
    ----------
    sources : sequence of (QuadMesh, color)
        Each source's quad mesh (``ibr.build_mesh``) and its colour image (same size as the
        mesh's camera; all sources with the same number of channels).
    camera : Camera or SphericalCamera
        The target.
    rel_tol : float
        Relative depth tolerance of the per-pixel z-test (0.02: samples within 2 % of the nearest
        depth belong to the same surface).
    sigma_deg : float
        Angular scale of the viewpoint weight ``exp(-(angle / sigma)^2)``.
    feather_px : float
        Width of the weight ramp at each source's image border, in source pixels.
    footprint : str
        Clamping of sample positions at quad sides (:func:`ibr.render.rasterize_mesh`).
    interpolation : {"linear", "cubic"}
        Colour reconstruction: bilinear, or bicubic (Keys, a = -0.75, as OpenCV's INTER_CUBIC).
    antialias : bool
        Prefilter each source finer than the target (see :func:`prefilter_sigma`) so that fine
        texture does not alias when a rig of sharp cameras makes a smaller panorama.
    progress : callable, optional
        Called as ``progress(i)`` after source i has been added.

    Returns
    -------
    Blended
    """
    shape = _target_shape(camera)
    rel_tol = check_positive("rel_tol", rel_tol)
    sigma = np.radians(check_positive("sigma_deg", sigma_deg))
    feather = check_positive("feather_px", feather_px)
    check_choice("interpolation", interpolation, ("linear", "cubic"))
    if len(sources) == 0:
        raise ValueError("sources: expected at least one (mesh, color) source, got none")
    colors = [as_float_color(c) for _, c in sources]
    if antialias:
        colors = [_prefilter(col, prefilter_sigma(mesh.camera, camera)) for (mesh, _), col in zip(sources, colors)]
    nch = {c.shape[2] for c in colors}
    if len(nch) != 1:
        raise ValueError(f"sources: every colour must have the same number of channels, got {sorted(nch)}")
    for i, ((mesh, _), col) in enumerate(zip(sources, colors)):
        if col.shape[:2] != mesh.camera.shape:
            raise ValueError(f"sources[{i}]: colour {col.shape[1]}x{col.shape[0]} does not match its mesh's "
                             f"camera {mesh.camera.width}x{mesh.camera.height}")
    h, w = shape
    c = nch.pop()
    acc = np.zeros((h, w, c), np.float32)
    acc_w = np.zeros((h, w), np.float32)
    acc_z = np.zeros((h, w), np.float32)
    front = np.full((h, w), np.inf, np.float32)
    best_w = np.zeros((h, w), np.float32)
    best_id = np.full((h, w), -1, np.int16)
    maps = SourceMaps(scratch(("blend", "u"), shape, np.float32), scratch(("blend", "v"), shape, np.float32),
                      scratch(("blend", "z"), shape, np.float32), scratch(("blend", "c"), shape, np.bool_))
    args = (rel_tol, interpolation == "cubic", 1.0 / (sigma * sigma), 1.0 / feather, acc, acc_w, acc_z, front,
            best_w, best_id)
    for i, ((mesh, _), col) in enumerate(zip(sources, colors)):
        if isinstance(camera, SphericalCamera):
            from .ray_raster import _tables

            region = [0, -1, None]
            rasterize_mesh_rays(mesh, camera, footprint=footprint, out=maps, _region=region)
            await_kernels("blend")  # a first run: the helper may be caching the blend kernels right now
            center = (camera.world_from_rig[:3, :3].T @ (mesh.camera.position - camera.world_from_rig[:3, 3]))
            _k.accumulate_spherical(col, source_prior(mesh), maps.map_u, maps.map_v, maps.depth,
                                    _tables(camera, "rows"), _tables(camera, "cols"), np.ascontiguousarray(center),
                                    *region, i, *args)
        else:
            m = rasterize_mesh(mesh, camera, footprint=footprint)
            center = (camera.cam_from_world @ np.append(mesh.camera.position, 1.0))[:3]
            _k.accumulate_pinhole(col, source_prior(mesh), m.map_u, m.map_v, m.depth, np.linalg.inv(camera.K),
                                  np.ascontiguousarray(center), i, *args)
        if progress is not None:
            progress(i)
    out = np.empty((h, w, c), np.float32)
    depth = np.empty((h, w), np.float32)
    cov = np.empty((h, w), np.bool_)
    _k.resolve(acc, acc_w, acc_z, out, depth, cov)
    best_id[~cov] = -1
    return Blended(out, depth, ~cov, best_id)
