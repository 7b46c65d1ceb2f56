"""RGB-D stitching: posed RGB-D views → one panorama (mono equirect, cubemap, or any ray camera).

Each view becomes its adaptive quad mesh (seed 002, :func:`ibr.build_mesh`, cached per view);
every mesh is rendered exactly into the target (:mod:`ibr.render.ray_raster` for spherical
cameras, the pinhole rasterizer for cube faces) and the N layers are blended depth-aware
(:func:`ibr.render.blend.blend_sources`). Colour keeps the views' dtype; depth is the range
along each ray for equirect/ODS targets (:mod:`panorama.depth`) and planar z per cube face.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ibr.base.camera import Camera
from ibr.base.validate import check_mesh_options
from ibr.base.ray_camera import SphericalCamera
from ibr.base.view import View
from ibr.render.blend import blend_sources
from ibr.render.sources import source_mesh

from ..directions import FACE_NAMES
from .rigs import cube_rig

__all__ = ["Stitched", "check_views", "stitch_rgbd", "stitch_rgbd_cubemap"]


@dataclass(frozen=True, eq=False)
class Stitched:
    """A stitched panorama.

    Attributes
    ----------
    color : (H, W, C) array in the views' dtype (0 in holes)
    depth : (H, W) float32, range along each ray (spherical) or planar z (pinhole), NaN in holes
    holes : (H, W) bool, True where no view saw the pixel
    winner : (H, W) int16, index of the view with the largest blending weight (-1 in holes)
    camera : the target camera (SphericalCamera or Camera)
    """

    color: np.ndarray
    depth: np.ndarray
    holes: np.ndarray
    winner: np.ndarray
    camera: object


def check_views(views) -> list[View]:
    """The views as a list, each with depth; a clear error otherwise."""
    if isinstance(views, View):
        views = [views]
    if views is None or isinstance(views, (str, bytes)) or not hasattr(views, "__iter__"):
        raise TypeError(f"views: expected a sequence of ibr Views, got {type(views).__name__}")
    views = list(views)
    if not views:
        raise ValueError("views: expected at least one RGB-D view, got none")
    channels = set()
    for i, v in enumerate(views):
        if not isinstance(v, View):
            raise TypeError(f"views[{i}]: expected an ibr View, got {type(v).__name__}")
        if v.depth is None:
            raise ValueError(f"views[{i}] ({v.name!r}): has no depth; stitching needs RGB-D views")
        if not np.isfinite(v.depth).any():
            raise ValueError(f"views[{i}] ({v.name!r}): depth has no valid (finite, positive) value")
        channels.add(1 if v.color.ndim == 2 else v.color.shape[2])
    if len(channels) > 1:
        raise ValueError(f"views: every view needs the same number of colour channels, got {sorted(channels)}")
    _check_no_duplicates(views)
    return views


def _check_no_duplicates(views) -> None:
    """Refuse a view given twice (the same object, or the same camera with the same colour and
    depth): it would move the default centre and double that view's blend weight."""
    seen: dict = {}
    for i, v in enumerate(views):
        c = v.camera
        key = (c.width, c.height, c.fx, c.fy, c.cx, c.cy, c.world_from_cam.tobytes())
        for j in seen.get(key, []):
            w = views[j]
            if w is v or (np.array_equal(w.color, v.color) and np.array_equal(w.depth, v.depth, equal_nan=True)):
                raise ValueError(f"views[{i}] ({v.name!r}): the same view as views[{j}] ({w.name!r}); give each view once")
        seen.setdefault(key, []).append(i)


def _to_dtype(color: np.ndarray, dtype) -> np.ndarray:
    dtype = np.dtype(dtype)
    if dtype.kind in "ui":
        info = np.iinfo(dtype)
        return np.clip(np.rint(color), info.min, info.max).astype(dtype)
    return color.astype(dtype, copy=False)


def _render(views: Sequence[View], camera, mesh_options: dict, blend_options: dict, progress) -> Stitched:
    sources = [(source_mesh(v, **mesh_options), v.color) for v in views]
    res = blend_sources(sources, camera, progress=progress, **blend_options)
    color = _to_dtype(res.color, views[0].color.dtype)
    if views[0].color.ndim == 2:
        color = color[..., 0]
    return Stitched(color, res.depth, res.holes, res.winner, camera)


def stitch_rgbd(views, camera, *, mesh_options: dict | None = None, progress=None, **blend_options) -> Stitched:
    """Stitch posed RGB-D views into one panorama seen by ``camera``.

    Parameters
    ----------
    views : sequence of ibr.View
        Posed RGB-D views (pinhole cameras with ``world_from_cam``; any sizes and intrinsics).
    camera : SphericalCamera, Camera or int
        Target: a mono equirect or ODS eye (:func:`panorama.stitch.equirect_camera`,
        :func:`panorama.stitch.ods_cameras`), a pinhole camera, or an int width for a mono equirect
        at the centroid of the views' centres.
    mesh_options : dict, optional
        Passed to :func:`ibr.build_mesh` (e.g. ``max_error_px``).
    progress : callable, optional
        ``progress(i)`` after each view.
    **blend_options
        ``rel_tol``, ``sigma_deg``, ``feather_px``, ``footprint`` of
        :func:`ibr.render.blend.blend_sources`.

    Returns
    -------
    Stitched

    Examples
    --------
    >>> from panorama.stitch import cube_rig, equirect_camera, stitch_rgbd   # doctest: +SKIP
    >>> pano = stitch_rgbd(views, equirect_camera(4096))                    # doctest: +SKIP
    >>> pano.color.shape, pano.depth.dtype                                  # doctest: +SKIP
    ((2048, 4096, 3), dtype('float32'))
    """
    views = check_views(views)
    if isinstance(camera, (int, np.integer)) and not isinstance(camera, bool):
        from .rigs import equirect_camera

        if camera < 2 or camera % 2:
            raise ValueError(f"camera: an int is the width of a mono equirect, even and >= 2; got {int(camera)}")
        camera = equirect_camera(int(camera), center=np.mean([v.camera.position for v in views], axis=0))
    if not isinstance(camera, (SphericalCamera, Camera)):
        raise TypeError(f"camera: expected a SphericalCamera, a Camera or an int width, got {type(camera).__name__}")
    _check_keywords("blend_options", blend_options, blend_sources, skip=("progress",))
    return _render(views, camera, check_mesh_options(mesh_options), blend_options, progress)


def _check_keywords(name: str, options: dict, function, skip=()) -> None:
    """Refuse keys of ``options`` that are not keyword-only parameters of ``function`` (besides
    ``skip``), naming the nearest valid one (TypeError, as Python's own message would be)."""
    import inspect

    from ibr.base.validate import nearest_name

    valid = [n for n, p in inspect.signature(function).parameters.items() if p.kind == p.KEYWORD_ONLY and n not in skip]
    for key in options:
        if key not in valid:
            near = nearest_name(key, valid)
            raise TypeError(f"{name}: unknown option {key!r}{f' (did you mean {near!r}?)' if near else ''}; "
                            f"expected {', '.join(valid)}")


def stitch_rgbd_cubemap(views, face_size: int, *, center=None, mesh_options: dict | None = None,
                        **blend_options) -> tuple[dict, dict, dict]:
    """Mono cubemap from posed RGB-D views: ``(color faces, planar-z faces, hole faces)``.

    Each face is a 90-degree pinhole camera at ``center`` (default: centroid of the view centres)
    rendered directly from the meshes (the fast pinhole path); dicts keyed by
    ``FACE_NAMES`` (+x -x +y -y +z -z), the ``dict`` layout of :mod:`panorama.layouts`.
    """
    views = check_views(views)
    if center is None:
        center = np.mean([v.camera.position for v in views], axis=0)
    color, depth, holes = {}, {}, {}
    for name, cam in zip(FACE_NAMES, cube_rig(face_size, center=center)):
        r = stitch_rgbd(views, cam, mesh_options=mesh_options, **blend_options)
        color[name], depth[name], holes[name] = r.color, r.depth, r.holes
    return color, depth, holes
