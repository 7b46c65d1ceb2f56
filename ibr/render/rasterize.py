"""Inverse-warp renderer: rasterize a planar quad mesh into a target pinhole camera.

Seed 002 section 2.1 ("inverse warping") maps every quad of a source view into the new view and
texture-maps the source rectangle onto it. The seed used affine texture mapping, which drifts on
large, near quads; here each covered target pixel is mapped to its source pixel through the quad's
exact 3x3 homography (a planar quad maps by a homography), its depth comes exactly from the quad's
plane, and a z-buffer keeps the nearest quad. The kernel writes *source coordinates* and depth; one
``cv2.remap`` then samples the color bilinearly (DESIGN.md section 6: cheaper than sampling in the
kernel).

Conventions
-----------
* Pixel (u, v) = (column, row), centers at integer coordinates; the image spans
  [-0.5, W - 0.5] x [-0.5, H - 0.5]. A target pixel (3, 4) is covered by a quad when the ray
  through the *center* (3.0, 4.0) hits the quad; a quad with rect [2, 3, 6, 4] owns the half-open
  source area [1.5, 5.5) x [2.5, 3.5) (the fill rule: shared edges belong to exactly one quad).
* Depth is planar z in the target camera (scene units), float32, NaN where uncovered.
* Layer colors are float32 in the source's value scale (0..255 for uint8 sources, 0..65535 for
  uint16, unchanged for float sources).
"""

from __future__ import annotations

import threading
import weakref
from dataclasses import dataclass

import cv2
import numpy as np

from . import _raster_kernels as _k
from .bands import run_bands
from ..base.first_run import await_kernels
from ..base.validate import check_choice, check_image, check_positive
from ..base.camera import Camera

__all__ = ["FOOTPRINTS", "INTERPOLATIONS", "Layer", "SourceMaps", "rasterize_mesh", "render_mesh", "sample_maps"]

#: Sample-footprint modes of :func:`render_mesh` ("free" measured best, see README section render).
FOOTPRINTS = ("free", "surface", "quad", "none")

#: One-pixel cracks along a row of a source's rendering (view synthesis:
#: ``_rasterize_many_into(..., crack_rel=CRACK_REL)``), between two pixels within this relative
#: depth of each other, are closed before compositing (two neighbouring quads of a curved surface
#: have different planes, so their shared edge opens by a pixel in another view; where the other
#: source sees the background there it showed through, e.g. a jagged orange line along clutter's
#: dark sphere at t = 0.5, #11). Measured (bench_edges, after the fill): clutter all pixels
#: 36.82 -> 36.84 dB, band 28.27 -> 28.31; room unchanged. Closing the cracks along columns too
#: (a second pass on a snapshot of the coverage) added room's band +0.04 dB for 0.2 ms more on
#: the motorcycle's warp (6 %): not kept. 0.05 cost room's band 0.02 dB, 0.01 left a third of
#: the cracks open.
CRACK_REL = 0.02

#: Color reconstruction filters of :func:`sample_maps`.
INTERPOLATIONS = {"linear": cv2.INTER_LINEAR, "cubic": cv2.INTER_CUBIC}

# Work sizes below which a serial kernel beats waking the second thread.
_PARALLEL_PIXELS = 64 * 64

# A source coordinate far outside every image: remap's constant border returns 0 there.
_FAR = np.float32(-1.0e6)


@dataclass(frozen=True, eq=False)
class Layer:
    """One source rendered into a target camera.

    Attributes
    ----------
    color : (H, W, C) float32
        Sampled color in the source's value scale; 0 where uncovered.
    depth : (H, W) float32
        Planar z in the target camera (scene units), NaN where uncovered.
    coverage : (H, W) bool
        True where some quad (or splat) covered the pixel center.
    """

    color: np.ndarray
    depth: np.ndarray
    coverage: np.ndarray

    def __post_init__(self):
        c = np.asarray(self.color)
        if c.ndim == 2:
            object.__setattr__(self, "color", c[..., None])
        if self.depth.shape != self.coverage.shape or self.color.shape[:2] != self.depth.shape:
            raise ValueError(
                f"Layer: color {self.color.shape}, depth {self.depth.shape} and coverage "
                f"{self.coverage.shape} must share (H, W)"
            )

    @property
    def shape(self) -> tuple[int, int]:
        return self.depth.shape


@dataclass(frozen=True, eq=False)
class SourceMaps:
    """Where each target pixel samples its source (the geometry half of a render).

    ``map_u``, ``map_v`` (H, W) float32 source pixel coordinates (centers at integers; a far
    negative value where uncovered), ``depth`` (H, W) float32 target planar z (NaN uncovered),
    ``coverage`` (H, W) bool.
    """

    map_u: np.ndarray
    map_v: np.ndarray
    depth: np.ndarray
    coverage: np.ndarray

    def nearest_source_pixel(self, ys, xs, shape) -> tuple[np.ndarray, np.ndarray]:
        """(rows, columns) of the source pixel nearest to where target pixels (ys, xs) sample
        the source, clamped to its ``shape`` (H_s, W_s); rounded as the composite kernels round
        (``_nearest``): x + 0.5 in float64 (in float32 it rounds up from just below 0.5)."""
        h, w = shape
        u = np.clip(np.floor(self.map_u[ys, xs].astype(np.float64) + 0.5), 0, w - 1).astype(np.intp)
        v = np.clip(np.floor(self.map_v[ys, xs].astype(np.float64) + 0.5), 0, h - 1).astype(np.intp)
        return v, u


def _intrinsics(cam: Camera) -> np.ndarray:
    return np.array([cam.fx, cam.fy, cam.cx, cam.cy], dtype=np.float64)


def src_from_tgt(source: Camera, target: Camera) -> tuple[np.ndarray, np.ndarray]:
    """Rotation (3, 3) and translation (3,) of ``cam_src_from_cam_tgt``."""
    m = source.cam_from_world @ target.world_from_cam
    return np.ascontiguousarray(m[:3, :3]), np.ascontiguousarray(m[:3, 3])


def _nbands(height: int) -> int:
    import numba

    return int(min(height, max(1, 4 * numba.get_num_threads())))


# Per-mesh caches (keyed on the mesh object, dropped with it).
_clamp_cache: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _mesh_inv_depth(mesh) -> np.ndarray:
    """(H, W) float64 inverse depth of each source pixel from its quad's plane, 0 where none."""
    q = mesh.quad_of_pixel
    h, w = q.shape
    v, u = np.mgrid[0:h, 0:w]
    p = mesh.inv_depth_planes
    qi = np.where(q >= 0, q, 0)
    inv = p[qi, 0] * u + p[qi, 1] * v + p[qi, 2]
    inv[q < 0] = 0.0
    return inv


# the source-quad argument of the raster kernel when no crack is closed: read-only like a mesh's
# own, so that the kernel has one signature either way
_NO_QOP = np.full((1, 1), -1, np.int32)
_NO_QOP.setflags(write=False)


def _clamp_flags(mesh, footprint: str, depth_tol: float) -> np.ndarray:
    nq = len(mesh.rects)
    if footprint == "none":
        return np.zeros((nq, 4), np.uint8)
    if footprint == "free":  # clamp only at the image border (nothing to read beyond it)
        r = mesh.rects
        h, w = mesh.camera.shape
        return np.stack([r[:, 0] == 0, r[:, 1] == 0, r[:, 2] == w, r[:, 3] == h], -1).astype(np.uint8)
    if footprint == "quad":
        return np.ones((nq, 4), np.uint8)
    per_mesh = _clamp_cache.setdefault(mesh, {})
    flags = per_mesh.get(depth_tol)
    if flags is None:
        flags = np.empty((nq, 4), np.uint8)
        if nq:
            _k.clamp_flags(mesh.rects, mesh.inv_depth_planes, _mesh_inv_depth(mesh), depth_tol, flags)
        flags.setflags(write=False)
        per_mesh[depth_tol] = flags
    return flags


def rasterize_mesh(mesh, camera: Camera, *, footprint: str = "free", depth_tol: float = 0.01) -> SourceMaps:
    """Z-buffered rasterization of ``mesh`` into ``camera``: source coordinates and depth.

    Parameters
    ----------
    mesh : QuadMesh
        Quads of one source view (``mesh.camera`` is the source camera).
    camera : Camera
        Target camera (any size and intrinsics).
    footprint : {"free", "surface", "quad", "none"}
        Where bilinear sampling may read outside a quad's own source pixels (``"none"``: the raw
        geometric source coordinates, no clamping at all). ``"free"``
        (default) clamps sample positions only at the image border. ``"surface"`` also clamps to
        the quad's outer pixel centers on sides that face a depth edge (a neighbour off the quad's
        plane by more than ``depth_tol`` in relative inverse depth, or no depth), so colors never
        bleed across depth edges yet stay smooth across quad seams on one surface; ``"quad"``
        clamps on every side. On anti-aliased sources (the bundled renders, the Middlebury
        photographs) the edge pixels are already mixtures, and ``"free"`` scores 0.1-0.6 dB
        higher than ``"surface"`` (benchmarks/bench_render.py), hence the default.
    depth_tol : float
        Relative inverse-depth tolerance of the ``"surface"`` edge test.

    Returns
    -------
    SourceMaps
    """
    if not isinstance(camera, Camera):
        raise TypeError(f"camera: expected a Camera, got {type(camera).__name__}")
    h, w = camera.height, camera.width
    out = SourceMaps(np.empty((h, w), np.float32), np.empty((h, w), np.float32), np.empty((h, w), np.float32),
                     np.empty((h, w), np.bool_))
    return _rasterize_into(mesh, camera, footprint, depth_tol, out)


def _rasterize_into(mesh, camera: Camera, footprint: str, depth_tol: float, out: SourceMaps) -> SourceMaps:
    """:func:`rasterize_mesh` writing into preallocated (H, W) arrays ``out`` (all overwritten)."""
    return _rasterize_many_into([mesh], camera, footprint, depth_tol, [out])[0]


def _rasterize_many_into(meshes, camera: Camera, footprint: str, depth_tol: float, outs,
                         crack_rel: float = 0.0, far_coord: np.float32 = _FAR, setups: list | None = None) -> list:
    """:func:`_rasterize_into` for several meshes into the same camera, their bands of rows run
    in one pass of the band pool (one dispatch, and the pieces of all meshes balance out).
    ``crack_rel`` > 0: one-pixel cracks along rows between same-surface pixels are closed
    (``_raster_kernels.raster_quads``; view synthesis, not the exact coverage of
    :func:`rasterize_mesh`). ``far_coord`` (float32): the map coordinates of uncovered pixels
    (:data:`_FAR`, off the source, unless the caller reads only covered pixels' maps).
    ``setups``: a list that receives each mesh's (quad coefficients, clamp flags) for ``camera``
    (:func:`ibr.render.edge_antialias.subsample_maps` traces more rays through them)."""
    check_choice("footprint", footprint, FOOTPRINTS)
    depth_tol = check_positive("depth_tol", depth_tol)
    if not isinstance(camera, Camera):
        raise TypeError(f"camera: expected a Camera, got {type(camera).__name__}")
    h, w = camera.height, camera.width
    kt = _intrinsics(camera)
    kt_inv = np.linalg.inv(camera.K)
    await_kernels("raster")  # a first run: the helper may be caching the raster kernels right now
    jobs = []  # per mesh: (first band, bands, kernel arguments after the band range)
    first = 0
    for mesh, out in zip(meshes, outs):
        coef, bbox, flags = quad_setup(mesh, camera, footprint, depth_tol, kt=kt, kt_inv=kt_inv)
        if setups is not None:
            setups.append((coef, flags))
        start, order = _k.bucket_bands(bbox, h, _nbands(h))
        qop = mesh.quad_of_pixel if crack_rel > 0 else _NO_QOP
        jobs.append((first, len(start) - 1, (mesh.rects, coef, bbox, flags, w, h, start, order, far_coord,
                                             float(crack_rel), qop, out.depth, out.map_u, out.map_v,
                                             out.coverage)))
        first += len(start) - 1

    def bands(b0, b1):  # bands b0 .. b1-1 of all meshes, numbered one after the other
        for off, n, args in jobs:
            lo, hi = max(b0 - off, 0), min(b1 - off, n)
            if lo < hi:
                _k.raster_quads(lo, hi, *args)

    run_bands(bands, first, min_rows=1 if h * w >= _PARALLEL_PIXELS else first,
              pieces_per_thread=4 * len(jobs))  # quads crowd some bands: balance them
    return outs


def quad_setup(mesh, camera: Camera, footprint: str, depth_tol: float, *, kt=None, kt_inv=None):
    """Each quad of ``mesh`` set up for ``camera`` (``_raster_kernels.setup_quads``): (Q, 12)
    coefficient rows ``[g, Hx, Hy, Hz]``, (Q, 4) int32 target bounding boxes and (Q, 4) uint8
    clamp flags of ``footprint``. ``kt``, ``kt_inv``: the camera's intrinsics vector and
    inverse K, if at hand (internal; arguments are not checked here)."""
    r, t = src_from_tgt(mesh.camera, camera)
    nq = len(mesh.rects)
    coef = np.empty((nq, 12), np.float64)
    bbox = np.empty((nq, 4), np.int32)
    run_bands(_k.setup_quads, nq, mesh.rects, mesh.inv_depth_planes, _intrinsics(mesh.camera), r, t,
              np.linalg.inv(camera.K) if kt_inv is None else kt_inv, _intrinsics(camera) if kt is None else kt,
              camera.width, camera.height, coef, bbox, min_rows=4096)  # quads: a piece per thread from 8192 quads on
    return coef, bbox, _clamp_flags(mesh, footprint, depth_tol)


_scratch_local = threading.local()


def scratch(key, shape, dtype) -> np.ndarray:
    """A reusable per-thread work array (contents undefined) for internal, short-lived results.

    Reusing the pages avoids the page faults of a fresh multi-megabyte allocation per frame
    (several ms at 1920x1080). Never hand a scratch array to a caller. One array is kept per key
    and dtype, of the last shape asked for: a supersampled render's k^2-sized arrays are freed
    by the next plain one instead of being held for the life of the process.
    """
    store = getattr(_scratch_local, "arrays", None)
    if store is None:
        store = _scratch_local.arrays = {}
    k = (key, np.dtype(dtype).str)
    a = store.get(k)
    if a is None or a.shape != tuple(shape):
        store.pop(k, None)  # free the old pages before the new allocation
        a = store[k] = np.empty(shape, dtype)
    return a


def scratch_maps(key, shape) -> SourceMaps:
    """Reusable :class:`SourceMaps` buffers for ``key`` (see :func:`scratch`)."""
    return SourceMaps(scratch((key, "u"), shape, np.float32), scratch((key, "v"), shape, np.float32),
                      scratch((key, "z"), shape, np.float32), scratch((key, "c"), shape, np.bool_))


def as_float_color(color) -> np.ndarray:
    """(H, W, C) float32 view or copy of ``color`` in its own value scale (no rescaling)."""
    c = np.asarray(color)
    if c.ndim == 2:
        c = c[..., None]
    if c.dtype != np.float32:
        c = c.astype(np.float32)
    return np.ascontiguousarray(c)


def sample_maps(color_f32: np.ndarray, map_u: np.ndarray, map_v: np.ndarray, *, interpolation: str = "linear",
                out: np.ndarray | None = None) -> np.ndarray:
    """``cv2.remap`` of a float32 (H, W, C) image at source coordinates (centers at integers:
    map value 3.0 reads pixel column 3 exactly, 3.5 averages columns 3 and 4 bilinearly).

    ``interpolation`` is ``"linear"`` (bilinear, default) or ``"cubic"`` (bicubic: +0.5 to
    +1.7 dB on the bundled pairs, about 5x the sampling time). Outside the image (beyond half a
    pixel past the border centres) the result is 0; the bicubic taps that reach past the border
    of a position inside read the border pixel (with 0 there a uniform 200 came out up to 243
    along the border). OpenCV quantizes the fractional position to 1/32 pixel (INTER_BITS = 5),
    exact at integer positions.
    """
    check_choice("interpolation", interpolation, INTERPOLATIONS)
    c = color_f32.shape[2]
    if c > 4:
        raise ValueError(f"color: at most 4 channels, got {c}")
    cubic = interpolation == "cubic"
    border = cv2.BORDER_REPLICATE if cubic else cv2.BORDER_CONSTANT
    if out is not None:
        dst = out[..., 0] if c == 1 else out
        cv2.remap(color_f32, map_u, map_v, INTERPOLATIONS[interpolation], dst=dst, borderMode=border, borderValue=0)
        res = out
    else:
        res = cv2.remap(color_f32, map_u, map_v, INTERPOLATIONS[interpolation], borderMode=border, borderValue=0)
        res = res[..., None] if res.ndim == 2 else res
    if cubic:  # replicated taps serve positions inside; outside (uncovered: _FAR) stays 0
        h, w = color_f32.shape[:2]
        outside = (map_u < -0.5) | (map_u > w - 0.5) | (map_v < -0.5) | (map_v > h - 0.5)
        np.copyto(res, np.float32(0), where=outside[..., None])
    return res


def source_color(mesh, color) -> np.ndarray:
    """``color`` checked as the image of ``mesh``'s source camera (1-4 channels, same size)."""
    col = check_image("color", color, channels=(1, 2, 3, 4))
    if col.shape[:2] != mesh.camera.shape:
        raise ValueError(
            f"color: size {col.shape[1]}x{col.shape[0]} does not match the mesh's source camera "
            f"{mesh.camera.width}x{mesh.camera.height}"
        )
    return col


def render_mesh(
    mesh, color, camera: Camera, *, footprint: str = "free", depth_tol: float = 0.01, interpolation: str = "linear"
) -> Layer:
    """Render a source's quad mesh into a target camera (inverse warp with a z-buffer).

    Every target pixel center is traced to the nearest quad by the quad's exact homography
    (``ibr.render._raster_kernels`` derives it: ``1/z_t = g.p``, source pixel ``Hp / (Hp)_z``), so planar
    surfaces show no texture drift and the depth is the plane's, exactly. Quads whose plane faces
    away from the target camera are culled; quads crossing the target camera plane are cut there
    (only hits in front of both cameras count), never smeared.

    Parameters
    ----------
    mesh : QuadMesh
        Source quads (``ibr.build_mesh``); ``mesh.camera`` is the source camera.
    color : (H, W, C) or (H, W) array
        Source color, same size as ``mesh.camera``; uint8, uint16 or float.
    camera : Camera
        Target camera.
    footprint, depth_tol
        See :func:`rasterize_mesh`.
    interpolation : {"linear", "cubic"}
        Color reconstruction filter (:func:`sample_maps`).

    Returns
    -------
    Layer
        float32 color (source value scale), target planar depth (NaN uncovered), coverage.

    Examples
    --------
    A pixel center (u, v) = (10.0, 20.0) of the target samples the source at ``Hp/(Hp)_z``; with
    the identity warp that is exactly (10.0, 20.0), so ``render_mesh(mesh, c, mesh.camera)``
    returns ``c`` on every pixel that has a quad.
    """
    col = source_color(mesh, color)
    maps = rasterize_mesh(mesh, camera, footprint=footprint, depth_tol=depth_tol)
    sampled = sample_maps(as_float_color(col), maps.map_u, maps.map_v, interpolation=interpolation)
    return Layer(sampled, maps.depth, maps.coverage)


# ------------------------------------------------------------------------- reference
def rasterize_mesh_reference(mesh, camera: Camera) -> SourceMaps:
    """Slow numpy reference of :func:`rasterize_mesh` (``footprint="none"``) for tests.

    Independent geometry: each quad's plane ``n . X_src = 1`` is moved to the *world* frame,
    every target pixel ray is intersected with it there, the hit is projected into the source
    camera with :meth:`Camera.project` and kept if it falls in the rect's half-open pixel-edge
    outline, lies in front of both cameras, and the target camera is on the front side of the
    plane (the side of the source camera). Nearest hit wins.
    """
    h, w = camera.shape
    origin, _ = camera.rays_world()
    d = camera.rays_cam() @ camera.world_from_cam[:3, :3].T  # z_t = 1 scaled, world frame
    best = np.full((h, w), np.inf)
    mu = np.full((h, w), np.float32(_FAR), np.float32)
    mv = np.full((h, w), np.float32(_FAR), np.float32)
    src = mesh.camera
    rot, src_center = src.world_from_cam[:3, :3], src.position
    for q in range(len(mesh.rects)):
        a, b, c = mesh.inv_depth_planes[q]
        n_cam = np.array([a * src.fx, b * src.fy, a * src.cx + b * src.cy + c])
        nrm = rot @ n_cam  # plane: nrm . (X - C_src) = 1
        off = 1.0 + nrm @ src_center
        if not (nrm @ origin - off < 0):
            continue  # target on the back side (or in the plane): back-facing / edge-on
        denom = d @ nrm
        with np.errstate(divide="ignore", invalid="ignore"):
            lam = (off - nrm @ origin) / denom  # = z_t because d has z_t = 1
        pts = origin + lam[..., None] * d
        uv, zs = src.project(pts.reshape(-1, 3))
        uv = uv.reshape(h, w, 2)
        zs = zs.reshape(h, w)
        u0, v0, u1, v1 = (mesh.rects[q] - 0.5).tolist()
        with np.errstate(invalid="ignore"):
            hit = (
                (lam > 0) & (zs > 0)
                & (uv[..., 0] >= u0) & (uv[..., 0] < u1)
                & (uv[..., 1] >= v0) & (uv[..., 1] < v1)
                & (lam < best)
            )
        best[hit] = lam[hit]
        mu[hit] = uv[..., 0][hit]
        mv[hit] = uv[..., 1][hit]
    cov = np.isfinite(best)
    depth = np.where(cov, best, np.nan).astype(np.float32)
    return SourceMaps(mu, mv, depth, cov)
