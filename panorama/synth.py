"""Exact ground truth for spherical cameras: equirect and cube-face renders of ``ibr.synth`` scenes.

Every ray goes through a pixel centre in the conventions of :mod:`panorama.directions` (e.g. a
4096-wide equirect's column 2048 looks 0.044 deg right of +z), from ``origin`` in the world
frame (x right, y down, z forward). Color may be supersampled k x k over the pixel footprint in
the pixel's own (u, v) coordinates (offsets (i + 0.5) / k - 0.5); depth is always the exact
pixel-centre value: range for equirect renders, planar z per face for cube renders.
"""

from __future__ import annotations

import numpy as np

from ibr.synth import Scene, render_rays

from .depth import face_ray_lengths, planar_from_range
from .directions import FACE_NAMES, WORLD_FROM_FACE, direction_from_equirect_pixel
from .layouts import layout_faces

__all__ = ["render_cubemap", "render_equirect"]


def _offsets(k: int):
    if isinstance(k, bool) or not isinstance(k, (int, np.integer)) or k < 1:
        raise ValueError(f"supersample: expected an integer >= 1, got {k!r}")
    o = (np.arange(k) + 0.5) / k - 0.5
    return [(du, dv) for dv in o for du in o]


def render_equirect(scene: Scene, width: int, height: int, *, origin=(0.0, 0.0, 0.0),
                    supersample: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """(color (H, W, 3) float32, range (H, W) float32, NaN on a miss) of a 2:1 equirect camera."""
    if width != 2 * height:
        raise ValueError(f"width, height: expected 2:1, got {width} x {height}")
    v, u = np.mgrid[0:height, 0:width].astype(np.float64)
    _, rng = render_rays(scene, np.asarray(origin, float), direction_from_equirect_pixel(u, v, width, height))
    acc = np.zeros((height, width, 3))
    offs = _offsets(supersample)
    for du, dv in offs:
        c, _ = render_rays(scene, np.asarray(origin, float),
                           direction_from_equirect_pixel(u + du, v + dv, width, height))
        acc += c
    return (acc / len(offs)).astype(np.float32), rng.astype(np.float32)


def render_cubemap(scene: Scene, face_size: int, *, origin=(0.0, 0.0, 0.0), supersample: int = 1,
                   layout: str = "list"):
    """(color faces, planar z faces) of six 90-degree face cameras, in ``layout``.

    Color faces are (S, S, 3) float32; depth faces (S, S) float32 planar z along each face's
    forward axis (NaN on a miss).
    """
    s = int(face_size)
    j, i = np.mgrid[0:s, 0:s].astype(np.float64)
    o = np.asarray(origin, float)
    colors, depths = [], []
    lengths = face_ray_lengths(s)
    for f in range(len(FACE_NAMES)):
        def dirs(du=0.0, dv=0.0):
            a = 2 * (i + du + 0.5) / s - 1
            b = 2 * (j + dv + 0.5) / s - 1
            d = np.stack([a, b, np.ones_like(a)], -1) @ WORLD_FROM_FACE[f].T
            return d / np.linalg.norm(d, axis=-1, keepdims=True)
        _, rng = render_rays(scene, o, dirs())
        offs = _offsets(supersample)
        acc = np.zeros((s, s, 3))
        for du, dv in offs:
            acc += render_rays(scene, o, dirs(du, dv))[0]
        colors.append((acc / len(offs)).astype(np.float32))
        depths.append(planar_from_range(rng, lengths[f]))
    return layout_faces(np.stack(colors), layout), layout_faces(np.stack(depths), layout)


def render_spherical(scene: Scene, camera, *, supersample: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """(color (H, W, 3) float32, range (H, W) float32) of a :class:`~ibr.base.ray_camera.SphericalCamera`.

    Exactly the camera's rays (mono equirect or an ODS eye, fade included): colour supersampled
    k x k over each pixel's (u, v) footprint (each sub-ray with its own origin), range from the
    ray origin at the pixel centre, NaN on a miss.
    """
    from ibr.base.ray_camera import SphericalCamera

    if not isinstance(camera, SphericalCamera):
        raise TypeError(f"camera: expected a SphericalCamera, got {type(camera).__name__}")
    h, w = camera.shape
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    o, d = camera.rays_world(u, v)
    _, rng = render_rays(scene, o.reshape(-1, 3), d.reshape(-1, 3))
    acc = np.zeros((h * w, 3))
    offs = _offsets(supersample)
    for du, dv in offs:
        o, d = camera.rays_world(u + du, v + dv)
        acc += render_rays(scene, o.reshape(-1, 3), d.reshape(-1, 3))[0]
    return (acc / len(offs)).reshape(h, w, 3).astype(np.float32), rng.reshape(h, w).astype(np.float32)
