"""Render quad meshes into spherical ray cameras (equirect, ODS eyes) -- exact per pixel.

The pinhole rasterizer (:mod:`ibr.render.rasterize`) maps target pixels to source pixels through
one homography per quad. A :class:`~ibr.base.ray_camera.SphericalCamera` has no single centre or
image plane, so here every covered target pixel intersects its *own* ray with the quad's plane
(known exactly from the mesh), maps the hit point into the source camera, applies the same
half-open fill rule, and z-tests by the **range** along the ray. Conservative bounds per quad
cover the +-180 deg seam and the poles (see :mod:`ibr.render._ray_kernels`). Colour is then
sampled with one ``cv2.remap``, as on the pinhole path.

Conventions: target pixel (u, v) centres at integers; depth = range from the ray's own origin
(scene units), NaN where uncovered; layer colour float32 in the source's value scale.
"""

from __future__ import annotations

import numpy as np

from ..base.ray_camera import SphericalCamera
from ..base.validate import check_choice, check_positive
from . import _ray_kernels as _k
from ._raster_kernels import bucket_bands
from .bands import run_bands
from ..base.first_run import await_kernels
from .rasterize import (_FAR, FOOTPRINTS, Layer, SourceMaps, _clamp_flags, _intrinsics, as_float_color, sample_maps,
                        source_color)

__all__ = ["rasterize_mesh_rays", "render_mesh_rays", "rasterize_mesh_rays_reference"]

_PARALLEL_QUADS = 256  # quads per piece of the setup (each sampled along its outline) on the band pool


def _check_camera(camera) -> SphericalCamera:
    if not isinstance(camera, SphericalCamera):
        raise TypeError(f"camera: expected a SphericalCamera, got {type(camera).__name__}")
    return camera


def src_from_rig(source, camera: SphericalCamera) -> tuple[np.ndarray, np.ndarray]:
    """Rotation (3, 3) and translation (3,) of ``source_cam_from_rig``."""
    m = source.cam_from_world @ camera.world_from_rig
    return np.ascontiguousarray(m[:3, :3]), np.ascontiguousarray(m[:3, 3])


def rasterize_mesh_rays(mesh, camera: SphericalCamera, *, footprint: str = "free", depth_tol: float = 0.01,
                        out: SourceMaps | None = None, _region: list | None = None) -> SourceMaps:
    """Z-buffered ray casting of ``mesh`` into a spherical camera: source coordinates and range.

    Parameters
    ----------
    mesh : QuadMesh
        Quads of one source view (``mesh.camera`` is the pinhole source camera).
    camera : SphericalCamera
        Target: mono equirect or one ODS eye.
    footprint, depth_tol
        Clamping of sample positions at quad sides, as :func:`ibr.render.rasterize_mesh`.
    out : SourceMaps, optional
        Preallocated (H, W) arrays to overwrite (``depth`` receives the range).
    _region : list, optional
        Internal (blending): when given, only the region the quads can reach is written and
        ``_region`` receives ``[v0, v1, column_mask]``; the rest of ``out`` is stale.

    Returns
    -------
    SourceMaps
        ``depth`` holds the range along each pixel's unit ray from its own origin.
    """
    _check_camera(camera)
    check_choice("footprint", footprint, FOOTPRINTS)
    depth_tol = check_positive("depth_tol", depth_tol)
    h, w = camera.shape
    if out is None:
        out = SourceMaps(np.empty((h, w), np.float32), np.empty((h, w), np.float32), np.empty((h, w), np.float32),
                         np.empty((h, w), np.bool_))
    rot, tr = src_from_rig(mesh.camera, camera)
    src_k = _intrinsics(mesh.camera)
    await_kernels("ray-setup")  # a first run: the helper may be caching the setup kernels right now
    nq = len(mesh.rects)
    plane_rig = np.empty((nq, 4), np.float64)
    bbox = np.empty((nq, 4), np.int32)
    run_bands(_k.setup_rays, nq, mesh.rects, mesh.inv_depth_planes, src_k, rot, tr, camera.sign, 0.5 * camera.ipd,
              np.radians(camera.fade_start_deg), np.radians(camera.fade_end_deg), w, h, plane_rig, bbox,
              min_rows=_PARALLEL_QUADS)
    flags = _clamp_flags(mesh, footprint, depth_tol)
    start, order = bucket_bands(bbox, h, _bands(h))
    if _region is None:
        v0, v1, colmask = 0, h - 1, np.ones(w, np.uint8)
    else:
        v0, v1, colmask = _k.region(bbox, w, h)
        _region[:] = [v0, v1, colmask]
    nbands = len(start) - 1
    run_bands(_k.raster_rays, nbands, mesh.rects, plane_rig, bbox, flags, src_k, rot, tr, _tables(camera, "rows"),
              _tables(camera, "cols"), start, order, _band_order(nbands), _FAR, v0, v1, colmask, out.depth, out.map_u,
              out.map_v, out.coverage, min_rows=1, pieces_per_thread=nbands)  # one task per piece, taken in turn
    return out


def _bands(height: int) -> int:
    """Bands of rows for the parallel raster: 8 per thread (see :func:`_band_order`)."""
    import numba

    return int(min(height, 8 * numba.get_num_threads()))


def _band_order(nbands: int) -> np.ndarray:
    """Task -> band, interleaved so that each thread's contiguous chunk of tasks spreads over the
    image (task k of ``per = nbands / T`` per thread renders band ``(k % per) * T + k // per``)."""
    import numba

    t = max(1, numba.get_num_threads())
    per = -(-nbands // t)
    order = [(k % per) * t + k // per for k in range(per * t)]
    return np.array([b for b in order if b < nbands], np.int64)


_TABLES: dict = {}


def _tables(camera: SphericalCamera, which: str) -> np.ndarray:
    """Row/column tables of a camera, cached by their defining numbers (read-only)."""
    key = (which, camera.width, camera.height, camera.sign, camera.ipd, camera.fade_start_deg, camera.fade_end_deg)
    t = _TABLES.get(key)
    if t is None:
        if len(_TABLES) > 32:
            _TABLES.clear()
        t = camera.row_tables() if which == "rows" else camera.column_tables()
        t.setflags(write=False)
        _TABLES[key] = t
    return t


def render_mesh_rays(mesh, color, camera: SphericalCamera, *, footprint: str = "free", depth_tol: float = 0.01,
                     interpolation: str = "linear") -> Layer:
    """Render a source's quad mesh into a spherical camera (colour by ``cv2.remap``).

    Returns a :class:`Layer` whose ``depth`` is the range along each pixel's ray. Example: the
    mesh of a pinhole view rendered into the mono equirect camera at the view's own centre gives
    the view's colours at the pixels its frustum covers and NaN range elsewhere.
    """
    col = source_color(mesh, color)
    maps = rasterize_mesh_rays(mesh, camera, footprint=footprint, depth_tol=depth_tol)
    sampled = sample_maps(as_float_color(col), maps.map_u, maps.map_v, interpolation=interpolation)
    return Layer(sampled, maps.depth, maps.coverage)


# ------------------------------------------------------------------------- reference
def rasterize_mesh_rays_reference(mesh, camera: SphericalCamera) -> SourceMaps:
    """Slow numpy reference of :func:`rasterize_mesh_rays` (``footprint="none"``) for tests.

    Independent geometry, in the world frame: every pixel ray (``camera.rays_world()``) is
    intersected with every quad's plane, the hit is projected with the source camera's
    :meth:`~ibr.base.camera.Camera.project`, kept inside the rect's half-open outline, in front of
    the source camera, with the ray origin on the source camera's side of the plane; nearest range
    wins. No bounds: every quad is tested against every pixel.
    """
    h, w = camera.shape
    origin, d = camera.rays_world()
    best = np.full((h, w), np.inf)
    mu = np.full((h, w), np.float32(_FAR), np.float32)
    mv = np.full((h, w), np.float32(_FAR), np.float32)
    src = mesh.camera
    rot, src_center = src.world_from_cam[:3, :3], src.position
    for q in range(len(mesh.rects)):
        a, b, c = mesh.inv_depth_planes[q]
        nrm = rot @ np.array([a * src.fx, b * src.fy, a * src.cx + b * src.cy + c])
        off = 1.0 + nrm @ src_center  # plane: nrm . X = off
        side = origin @ nrm - off
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = -side / (d @ nrm)
        pts = origin + lam[..., None] * d
        uv, zs = src.project(pts.reshape(-1, 3))
        uv = uv.reshape(h, w, 2)
        zs = zs.reshape(h, w)
        u0, v0, u1, v1 = (mesh.rects[q] - 0.5).tolist()
        with np.errstate(invalid="ignore"):
            hit = ((side < 0) & (lam > 0) & (zs > 0) & (uv[..., 0] >= u0) & (uv[..., 0] < u1)
                   & (uv[..., 1] >= v0) & (uv[..., 1] < v1) & (lam < best))
        best[hit] = lam[hit]
        mu[hit] = uv[..., 0][hit]
        mv[hit] = uv[..., 1][hit]
    cov = np.isfinite(best)
    return SourceMaps(mu, mv, np.where(cov, best, np.nan).astype(np.float32), cov)
