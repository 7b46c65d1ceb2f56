"""Picking: a screen pixel -> a ray -> the nearest canvas hit in front of the scene -> canvas pixel.

Seed 004 (section 2.2) casts a ray from the clicked screen point V "perpendicular to the screen"
(an orthographic view along -z) and asks the collision detection for the hit P on the plane;
P is then mapped to the canvas. Here the ray is the true viewing ray of the pixel (pinhole:
through the pixel centre convention of DESIGN.md section 4; panoramas build their rays in
:mod:`panorama.canvas`), every canvas is intersected exactly (:meth:`Canvas.intersect`) and the
scene's own depth takes part: a canvas hit farther than the scene surface seen at that pixel is
hidden, so it cannot be picked. A click that hits no canvas returns ``None`` (a defined no-op).

Round trip: canvas pixel -> world point -> camera pixel (:meth:`Camera.project`) -> pick gives the
canvas pixel back to ~1e-9 px (float64 throughout).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..base.camera import Camera
from ..base.validate import check_array, check_image
from .plane import Canvas

__all__ = ["Pick", "camera_rays", "pick_pixel", "pick_pixels", "pick_ray", "pick_rays"]


@dataclass(frozen=True)
class Pick:
    """The nearest canvas under a ray.

    Attributes
    ----------
    index : int
        Index of the canvas in the sequence given.
    canvas : Canvas
    xy : (2,) float64
        Canvas pixel hit (column, row; centres at integers).
    point : (3,) float64
        World point hit.
    distance : float
        Ray parameter of the hit (distance along a unit ray).
    """

    index: int
    canvas: Canvas
    xy: np.ndarray
    point: np.ndarray
    distance: float


def _canvas_list(canvases) -> list[Canvas]:
    items = [canvases] if isinstance(canvases, Canvas) else list(canvases)
    for i, c in enumerate(items):
        if not isinstance(c, Canvas):
            raise TypeError(f"canvases[{i}]: expected a Canvas, got {type(c).__name__}")
    return items


def pick_rays(canvases, origins, dirs, *, scene_distance=None, depth_tol: float = 1e-3):
    """Vectorized picking of N rays.

    Parameters
    ----------
    canvases : Canvas or sequence of Canvas
    origins : (3,) or (N, 3) array
    dirs : (N, 3) array
        Ray directions (world frame); normalized here.
    scene_distance : (N,) array, optional
        Distance along each unit ray to the scene surface (NaN or inf: nothing there); canvas hits
        farther than ``scene_distance * (1 + depth_tol)`` are hidden.

    Returns
    -------
    index : (N,) int
        Nearest visible canvas, -1 where none is hit.
    xy : (N, 2) float64
        Canvas pixel of the hit (NaN where index is -1).
    distance : (N,) float64
        Distance along the unit ray (inf where index is -1).
    """
    items = _canvas_list(canvases)
    d = check_array("dirs", dirs, shape=(None, 3), dtype_kind="fiu").astype(np.float64)
    norms = np.linalg.norm(d, axis=1)
    if not np.all(np.isfinite(norms) & (norms > 0)):
        raise ValueError("dirs: expected finite non-zero directions")
    d = d / norms[:, None]
    o = check_array("origins", origins, ndim=(1, 2), dtype_kind="fiu").astype(np.float64)
    if o.shape != (3,) and o.shape != d.shape:
        raise ValueError(f"origins: expected shape (3,) or {d.shape}, got {o.shape}")
    if not np.all(np.isfinite(o)):
        raise ValueError("origins: expected finite coordinates")
    n = len(d)
    best = np.full(n, np.inf)
    index = np.full(n, -1, np.int64)
    xy = np.full((n, 2), np.nan)
    limit = np.full(n, np.inf)
    if scene_distance is not None:
        s = np.asarray(scene_distance, dtype=np.float64).reshape(-1)
        if s.shape != (n,):
            raise ValueError(f"scene_distance: expected shape ({n},), got {s.shape}")
        limit = np.where(np.isfinite(s) & (s > 0), s * (1.0 + depth_tol), np.inf)
    for i, c in enumerate(items):
        t, q = c.intersect(o, d)
        better = (t < best) & (t <= limit)
        best[better] = t[better]
        index[better] = i
        xy[better] = q[better]
    return index, xy, best


def pick_ray(canvases, origin, direction, *, scene_distance: float | None = None,
             depth_tol: float = 1e-3) -> Pick | None:
    """The nearest canvas hit by one ray, or ``None`` when the ray hits no visible canvas."""
    items = _canvas_list(canvases)
    o = check_array("origin", origin, shape=(3,), dtype_kind="fiu").astype(np.float64)
    d = check_array("direction", direction, shape=(3,), dtype_kind="fiu").astype(np.float64)
    s = None if scene_distance is None else np.array([float(scene_distance)])
    index, xy, dist = pick_rays(items, o, d[None], scene_distance=s, depth_tol=depth_tol)
    if index[0] < 0:
        return None
    unit = d / np.linalg.norm(d)
    return Pick(int(index[0]), items[index[0]], xy[0], o + dist[0] * unit, float(dist[0]))


def camera_rays(camera: Camera, uv) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(origin (3,), unit world directions (N, 3), z-to-range factors (N,)) of pixels ``uv`` (N, 2).

    Pixel centres at integer coordinates: the ray of (u, v) is ``R ((u - cx)/fx, (v - cy)/fy, 1)``;
    the factor ``|((u - cx)/fx, (v - cy)/fy, 1)|`` turns planar depth into distance along the ray.
    """
    if not isinstance(camera, Camera):
        raise TypeError(f"camera: expected a Camera, got {type(camera).__name__}")
    q = check_array("uv", uv, dtype_kind="fiu").astype(np.float64).reshape(-1, 2)
    if not np.all(np.isfinite(q)):
        raise ValueError("uv: expected finite pixel coordinates")
    rays = np.stack([(q[:, 0] - camera.cx) / camera.fx, (q[:, 1] - camera.cy) / camera.fy, np.ones(len(q))], -1)
    length = np.linalg.norm(rays, axis=1)
    d = (rays / length[:, None]) @ camera.world_from_cam[:3, :3].T
    return camera.position, d, length


def _depth_at(depth, camera: Camera, q: np.ndarray) -> np.ndarray:
    """Planar depth at the nearest pixel of each (u, v), NaN outside the image."""
    z = check_image("depth", depth, channels=(1,))
    z = z.reshape(z.shape[:2])
    if z.shape != camera.shape:
        raise ValueError(f"depth: size {z.shape[1]}x{z.shape[0]} does not match the camera's "
                         f"{camera.width}x{camera.height}")
    iu = np.floor(q[:, 0] + 0.5).astype(np.int64)
    iv = np.floor(q[:, 1] + 0.5).astype(np.int64)
    inside = (iu >= 0) & (iu < camera.width) & (iv >= 0) & (iv < camera.height)
    out = np.full(len(q), np.nan)
    out[inside] = z[iv[inside], iu[inside]]
    return out


def pick_pixels(camera: Camera, uv, canvases, *, depth=None, depth_tol: float = 1e-3):
    """:func:`pick_rays` for pixels ``uv`` (N, 2) of a pinhole ``camera``; ``depth`` is the scene's
    planar z in that camera (nearest pixel is used). Returns ``(index, xy, distance)``."""
    q = check_array("uv", uv, dtype_kind="fiu")
    if q.ndim != 2 or q.shape[1] != 2:
        raise ValueError(f"uv: expected (N, 2) pixel positions (u, v), got shape {q.shape}")
    o, d, length = camera_rays(camera, uv)
    q = q.astype(np.float64)
    scene = None if depth is None else _depth_at(depth, camera, q) * length
    return pick_rays(canvases, o, d, scene_distance=scene, depth_tol=depth_tol)


def pick_pixel(camera: Camera, u: float, v: float, canvases, *, depth=None, depth_tol: float = 1e-3) -> Pick | None:
    """The canvas under pixel (u, v) of ``camera`` (centres at integers), or ``None``.

    ``depth`` (H, W) is the scene's planar z in ``camera``: a canvas behind the surface seen at
    that pixel is not hit. A click outside every canvas (or outside the image) returns ``None``.
    """
    items = _canvas_list(canvases)
    index, xy, dist = pick_pixels(camera, [[u, v]], items, depth=depth, depth_tol=depth_tol)
    if index[0] < 0:
        return None
    o, d, _ = camera_rays(camera, [[u, v]])
    return Pick(int(index[0]), items[index[0]], xy[0], o + dist[0] * d[0], float(dist[0]))
