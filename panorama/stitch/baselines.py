"""The two baselines ODS stitching is measured against (issue #20), built the way their users would.

* :func:`strip_stitch` -- **strip stitching without depth**, what a camera rig does without
  geometry (omnistereo from the captured images themselves). For the eye ray of column ``lon``
  (tangent to the viewing circle of radius r) the camera chosen is the one on the rig whose
  centre lies nearest that tangent ray: for a camera at yaw ``beta`` on a ring of radius R,
  ``beta = lon + asin(s r / R)`` -- the left eye takes each camera's strip right of its centre,
  the right eye the strip left of it. The image is then sampled along the eye ray's direction as
  if the camera sat at the rig centre (no depth: rotation only).
* :func:`slit_stitch` -- **slit stitching with our own meshes**: N narrow pinhole cameras at the
  eye positions on the viewing circle (yaw ``lon_k``, looking along it), each rendered from the
  views' quad meshes with the N-source blend, keeping each one's central strip of longitudes.
  Its error shrinks and its time grows with N; seams sit at the strip boundaries
  ``lon_k +- pi / N``. Pinhole slits cannot reach the poles: the result covers
  ``|lat| <= lat_max`` (default the fade start, where the circle radius is still ipd / 2).
"""

from __future__ import annotations

import math

import numpy as np

from ibr.base.camera import Camera
from ibr.base.ray_camera import SphericalCamera
from ibr.render.points import sample_points

from .rgbd import Stitched, check_views, stitch_rgbd

__all__ = ["slit_boundaries", "slit_stitch", "strip_stitch"]


def _check_camera(camera):
    if not isinstance(camera, SphericalCamera):
        raise TypeError(f"camera: expected a SphericalCamera, got {type(camera).__name__}")
    return camera


def strip_stitch(views, camera: SphericalCamera) -> Stitched:
    """Depth-free strip stitching of a rig's images into one eye (or mono) camera.

    Only colour is used (depth may be absent); ``depth`` of the result is NaN. Pixels whose
    direction falls outside the chosen camera's image are holes.
    """
    camera = _check_camera(camera)
    views = list(views)
    if not views:
        raise ValueError("views: expected at least one view, got none")
    h, w = camera.shape
    rig_rot = camera.world_from_rig[:3, :3]
    center = camera.world_from_rig[:3, 3]
    v, u = np.mgrid[0:h, 0:w]
    _, d_rig = camera.rays_rig(u, v)
    lon = camera.lon(u)
    sr = camera.sign * camera.radius(camera.lat(v))  # s * r(lat)
    best = np.full((h, w), np.inf)
    choice = np.full((h, w), -1, np.int32)
    for i, view in enumerate(views):
        cam = view.camera
        pos = rig_rot.T @ (cam.position - center)
        fwd = rig_rot.T @ cam.world_from_cam[:3, 2]
        radius = math.hypot(pos[0], pos[2])
        yaw = math.atan2(fwd[0], fwd[2])
        pitch = math.atan2(-fwd[1], math.hypot(fwd[0], fwd[2]))
        with np.errstate(invalid="ignore"):
            shift = np.arcsin(np.clip(sr / radius, -1, 1)) if radius > 0 else 0.0
        dyaw = (yaw - (lon + shift) + np.pi) % (2 * np.pi) - np.pi
        dpitch = pitch - np.arctan2(-d_rig[..., 1], np.hypot(d_rig[..., 0], d_rig[..., 2]))
        score = dyaw ** 2 + dpitch ** 2
        # only where the direction lands inside this camera's image
        d_cam = (d_rig @ rig_rot.T) @ cam.world_from_cam[:3, :3]
        with np.errstate(divide="ignore", invalid="ignore"):
            pu = cam.fx * d_cam[..., 0] / d_cam[..., 2] + cam.cx
            pv = cam.fy * d_cam[..., 1] / d_cam[..., 2] + cam.cy
        inside = (d_cam[..., 2] > 0) & (pu >= -0.5) & (pu <= cam.width - 0.5) & (pv >= -0.5) & (pv <= cam.height - 0.5)
        take = inside & (score < best)
        best[take] = score[take]
        choice[take] = i
    color = np.zeros((h, w, _channels(views[0].color)), np.float32)
    for i, view in enumerate(views):
        sel = choice == i
        if not sel.any():
            continue
        cam = view.camera
        d_cam = (d_rig[sel] @ rig_rot.T) @ cam.world_from_cam[:3, :3]
        pu = cam.fx * d_cam[:, 0] / d_cam[:, 2] + cam.cx
        pv = cam.fy * d_cam[:, 1] / d_cam[:, 2] + cam.cy
        color[sel] = sample_points(view.color, pu, pv)
    holes = choice < 0
    out = _to_dtype(color, views[0].color)
    return Stitched(out, np.full((h, w), np.nan, np.float32), holes, choice.astype(np.int16), camera)


def _channels(color) -> int:
    return 1 if color.ndim == 2 else color.shape[2]


def _to_dtype(color: np.ndarray, like: np.ndarray) -> np.ndarray:
    if like.dtype.kind in "ui":
        info = np.iinfo(like.dtype)
        color = np.clip(np.rint(color), info.min, info.max).astype(like.dtype)
    else:
        color = color.astype(like.dtype)
    return color[..., 0] if like.ndim == 2 else color


def slit_boundaries(n: int, width: int) -> np.ndarray:
    """Column coordinates (pixel edges) of the N slit boundaries ``lon = -pi + 2 pi k / N``."""
    return np.arange(n) * width / n - 0.5


def slit_stitch(views, camera: SphericalCamera, n: int, *, lat_max_deg: float | None = None,
                margin_px: int = 4, **blend_options) -> Stitched:
    """Mesh slit stitching: N pinhole slits on the viewing circle, central strips kept.

    Slit k looks along ``lon_k = -pi + 2 pi (k + 0.5) / N`` from ``s r right(lon_k)``, with the
    target's angular resolution at its centre (``fx = W / 2 pi``) and a vertical field reaching
    ``lat_max_deg`` (default: the fade start). Output pixels outside ``|lat| <= lat_max`` are
    holes.
    """
    camera = _check_camera(camera)
    views = check_views(views)
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 3:
        raise ValueError(f"n: expected an integer >= 3 slits, got {n!r}")
    lat_max = math.radians(camera.fade_start_deg if lat_max_deg is None else lat_max_deg)
    if not 0 < lat_max < math.radians(85):
        raise ValueError(f"lat_max_deg: expected 0 < lat_max < 85, got {lat_max_deg!r}")
    h, w = camera.shape
    f = w / (2 * math.pi)
    half_w = int(math.ceil(f * math.tan(math.pi / n))) + margin_px
    # at a strip's side edge (pi / n off its axis) the ray to lat_max meets the slit's plane
    # 1 / cos(pi / n) farther out than on the axis
    half_h = int(math.ceil(f * math.tan(lat_max) / math.cos(math.pi / n))) + margin_px
    sw, sh = 2 * half_w, 2 * half_h
    r = camera.sign * float(camera.radius(0.0))
    v, u = np.mgrid[0:h, 0:w]
    lon = camera.lon(u)
    lat = camera.lat(v)
    k_of = np.clip(np.floor((lon + np.pi) / (2 * np.pi) * n).astype(np.int64), 0, n - 1)
    color = np.zeros((h, w, _channels(views[0].color)), np.float32)
    depth = np.full((h, w), np.nan, np.float32)
    holes = np.ones((h, w), bool)
    rig = camera.world_from_rig
    band = np.abs(lat) <= lat_max
    for k in range(n):
        lon_k = -math.pi + 2 * math.pi * (k + 0.5) / n
        ry = np.array([[math.cos(lon_k), 0, math.sin(lon_k)], [0, 1, 0], [-math.sin(lon_k), 0, math.cos(lon_k)]])
        pose = np.eye(4)
        pose[:3, :3] = rig[:3, :3] @ ry
        pose[:3, 3] = rig[:3, :3] @ (r * np.array([math.cos(lon_k), 0.0, -math.sin(lon_k)])) + rig[:3, 3]
        slit = Camera(f, f, half_w - 0.5, half_h - 0.5, sw, sh, pose)
        res = stitch_rgbd(views, slit, **blend_options)
        sel = (k_of == k) & band
        d = np.stack([np.cos(lat[sel]) * np.sin(lon[sel] - lon_k), -np.sin(lat[sel]),
                      np.cos(lat[sel]) * np.cos(lon[sel] - lon_k)], -1)
        pu = f * d[:, 0] / d[:, 2] + slit.cx
        pv = f * d[:, 1] / d[:, 2] + slit.cy
        col = res.color.astype(np.float32)
        color[sel] = sample_points(col, pu, pv)
        cov = sample_points((~res.holes).astype(np.float32), pu, pv)[:, 0]
        z = sample_points(np.nan_to_num(res.depth, nan=0.0), pu, pv)[:, 0]
        depth[sel] = np.where(cov > 0.999, z * np.linalg.norm(d / d[:, 2:3], axis=1), np.nan)
        holes[sel] = cov <= 0.999
    return Stitched(_to_dtype(color, views[0].color), depth, holes, np.where(holes, -1, k_of).astype(np.int16),
                    camera)
