"""Omnidirectional stereo (ODS): left/right eye panoramas from posed RGB-D views or one RGB-D panorama.

The eye cameras are :class:`~ibr.base.ray_camera.SphericalCamera` objects: every column's rays
start on the viewing circle of radius ``ipd / 2``, tangent to it, the radius fading to 0 toward
the poles (defaults 60 deg → 80 deg) so both eyes meet there without swirls. Each eye is rendered
in one pass from the views' quad meshes (:func:`panorama.stitch.stitch_rgbd`). From a single
centre capture (an equirect colour + range panorama) the panorama is first cut into six cube-face
RGB-D views; what the centre never saw (disocclusions) is filled from the background side and
reported in ``holes``.

Output layouts (:func:`pack_ods`): ``"top-bottom"`` (left eye on top: what VR players and video
sites read), ``"sbs"`` (left | right), ``"anaglyph"`` (red-cyan, for a quick look), ``"cube"``
(per-eye cubemaps).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ibr.base.ray_camera import SphericalCamera
from ibr.base.validate import check_choice, check_finite_scalar
from ibr.base.view import View
from .fill import fill_stitched

from ..convert import equirect_to_cubemap
from ..directions import FACE_NAMES
from .rgbd import Stitched, check_views, stitch_rgbd
from .rigs import cube_rig, ods_cameras

__all__ = ["ODS_LAYOUTS", "OdsPair", "check_rgbd_panorama", "ods_from_panorama", "ods_from_views", "pack_ods",
           "panorama_views"]

#: Output layouts of :func:`pack_ods`.
ODS_LAYOUTS = ("top-bottom", "sbs", "anaglyph", "cube")

#: Hole fills: "background" (depth-aware, background side) or "none".
ODS_FILLS = ("background", "none")


@dataclass(frozen=True, eq=False)
class OdsPair:
    """Left and right eye panoramas (each a :class:`Stitched`; ``holes`` = no source saw it)."""

    left: Stitched
    right: Stitched

    @property
    def eyes(self) -> tuple[Stitched, Stitched]:
        return self.left, self.right


def _check_ipd(ipd, fade_start_deg, fade_end_deg):
    ipd = check_finite_scalar("ipd", ipd)
    if not ipd > 0:
        raise ValueError(f"ipd: expected a positive interpupillary distance (scene units), got {ipd!r}")
    a = check_finite_scalar("fade_start_deg", fade_start_deg)
    b = check_finite_scalar("fade_end_deg", fade_end_deg)
    if not 0 < a < b <= 90:
        raise ValueError(f"fade_start_deg, fade_end_deg: expected 0 < start < end <= 90 (degrees of latitude), "
                         f"got {fade_start_deg!r}, {fade_end_deg!r}")
    return ipd


def ods_from_views(views, width: int, *, ipd: float = 0.064, fade_start_deg: float = 60.0,
                   fade_end_deg: float = 80.0, center=None, fill: str = "none", mesh_options: dict | None = None,
                   progress=None, **blend_options) -> OdsPair:
    """ODS eye panoramas (``width x width/2`` each) rendered from posed RGB-D views.

    Parameters
    ----------
    views : sequence of ibr.View
        Posed RGB-D views (any sizes and intrinsics).
    width : int
        Equirect width of each eye (even).
    ipd : float
        Interpupillary distance in scene units (0.064 for metres).
    fade_start_deg, fade_end_deg : float
        Latitudes between which the viewing-circle radius fades to 0 (poles agree in both eyes).
    center : 3-vector, optional
        Capture point in the world frame (default: centroid of the view centres).
    fill : {"none", "background"}
        What to do with pixels no view saw (they are reported in ``holes`` either way).
    progress : callable, optional
        ``progress(k)`` after each of the ``2 * len(views)`` eye/view renders.
    """
    views = check_views(views)
    ipd = _check_ipd(ipd, fade_start_deg, fade_end_deg)
    check_choice("fill", fill, ODS_FILLS)
    if center is None:
        center = np.mean([v.camera.position for v in views], axis=0)
    eyes = []
    for k, cam in enumerate(ods_cameras(width, ipd=ipd, fade_start_deg=fade_start_deg, fade_end_deg=fade_end_deg,
                                        center=center)):
        step = None if progress is None else (lambda i, k=k: progress(k * len(views) + i))
        eye = stitch_rgbd(views, cam, mesh_options=mesh_options, progress=step, **blend_options)
        eyes.append(fill_stitched(eye) if fill == "background" else eye)
    return OdsPair(*eyes)


def check_rgbd_panorama(color, range_map, names=("color", "range_map")) -> tuple[np.ndarray, np.ndarray]:
    """``(color, range_map)`` as arrays after checking them as one centre RGB-D panorama: an
    equirect colour (H, 2H[, C]) and a float range map of its shape, positive where finite, with at
    least one range (NaN = none). Errors name the two inputs by ``names`` (the CLI passes its
    ``--panorama COLOR`` / ``--panorama RANGE``)."""
    color = np.asarray(color)
    rng = np.asarray(range_map)
    if color.ndim not in (2, 3) or color.shape[1] != 2 * color.shape[0]:
        raise ValueError(f"{names[0]}: expected an equirect image (H, 2H[, C]), got shape {color.shape}")
    if rng.shape != color.shape[:2]:
        raise ValueError(f"{names[1]}: expected shape {color.shape[:2]} (the colour's), got {rng.shape}")
    if rng.dtype.kind != "f":
        raise TypeError(f"{names[1]}: expected a float range map, got dtype {rng.dtype}")
    with np.errstate(invalid="ignore"):
        if np.any(rng <= 0):
            raise ValueError(f"{names[1]}: expected positive ranges (NaN where there is none), got values <= 0")
    if not np.isfinite(rng).any():
        raise ValueError(f"{names[1]}: no pixel has a range (all NaN): nothing to stitch")
    return color, rng


def panorama_views(color, range_map, *, face_size: int | None = None, center=(0.0, 0.0, 0.0)) -> list[View]:
    """Six cube-face RGB-D views (90-degree pinholes at ``center``) cut from an equirect panorama.

    ``color`` (H, 2H[, C]) and ``range_map`` (H, 2H) float range along each ray (NaN = none; at
    least one range; :func:`check_rgbd_panorama`). Face size defaults to ``ceil(W / pi)`` rounded
    up to even (the equator's angular resolution at the face centres). Depth becomes planar z per
    face (:mod:`panorama.depth`).
    """
    color, rng = check_rgbd_panorama(color, range_map)
    if face_size is None:
        face_size = int(math.ceil(color.shape[1] / math.pi / 2) * 2)
    faces = equirect_to_cubemap(color, face_size, layout="dict")
    zfaces = equirect_to_cubemap(rng.astype(np.float32), face_size, layout="dict", depth=True)
    return [View(faces[name], zfaces[name], cam, f"face{name}")
            for name, cam in zip(FACE_NAMES, cube_rig(face_size, center=center))]


def ods_from_panorama(color, range_map, *, width: int | None = None, ipd: float = 0.064, fade_start_deg: float = 60.0,
                      fade_end_deg: float = 80.0, fill: str = "background", face_size: int | None = None,
                      mesh_options: dict | None = None, progress=None, **blend_options) -> OdsPair:
    """ODS eye panoramas from one centre RGB-D panorama (equirect colour + range).

    The eyes sit ``ipd / 2`` off the centre, so surfaces the centre did not see (behind near
    objects) are disoccluded: they are filled from the background side (``fill="background"``,
    default) and always reported in each eye's ``holes``. ``width`` defaults to the input's.
    A cube face without any range (a sky without depth) has nothing to render and is left out:
    its directions are holes of the eyes.
    """
    views = [v for v in panorama_views(color, range_map, face_size=face_size) if np.isfinite(v.depth).any()]
    if not views:  # a few ranges, lost in the faces' resampling
        raise ValueError("range_map: no cube face of the panorama keeps a range: nothing to stitch")
    width = np.asarray(color).shape[1] if width is None else width
    return ods_from_views(views, width, ipd=ipd, fade_start_deg=fade_start_deg, fade_end_deg=fade_end_deg,
                          center=(0.0, 0.0, 0.0), fill=fill, mesh_options=mesh_options, progress=progress,
                          **blend_options)


def pack_ods(pair: OdsPair, layout: str = "top-bottom", *, face_size: int | None = None):
    """Pack an ODS pair for a player or a file.

    ``"top-bottom"`` (2H, W) left eye on top; ``"sbs"`` (H, 2W) left | right; ``"anaglyph"``
    (H, W, 3) red from the left eye, green and blue from the right; ``"cube"`` a tuple of two
    cubemaps ``(left_faces, right_faces)`` as dicts keyed +x .. -z (``face_size`` default W/4).
    """
    from ibr.stereo.pair import anaglyph

    check_choice("layout", layout, ODS_LAYOUTS)
    if not isinstance(pair, OdsPair):
        raise TypeError(f"pair: expected an OdsPair, got {type(pair).__name__}")
    left, right = pair.left.color, pair.right.color
    if layout == "top-bottom":
        return np.concatenate([left, right], axis=0)
    if layout == "sbs":
        return np.concatenate([left, right], axis=1)
    if layout == "anaglyph":
        return anaglyph(left, right)
    if face_size is None:
        s = max(1, left.shape[1] // 4)
    elif isinstance(face_size, bool) or not isinstance(face_size, (int, np.integer)) or face_size < 1:
        raise ValueError(f"face_size: expected a positive integer, got {face_size!r}")  # 0 meant "default"
    else:
        s = int(face_size)
    return equirect_to_cubemap(left, s, layout="dict"), equirect_to_cubemap(right, s, layout="dict")


def vertical_disparity(pair_or_camera, points_world) -> np.ndarray:
    """Row difference ``v_right - v_left`` (pixels) of world points in the two eyes (NaN unseen).

    With the ODS rays of :class:`SphericalCamera` both eyes share ``r(lat)``, so a point's latitude
    is the same in both: this is 0 up to rounding everywhere (tested); the function exists to
    measure it on real outputs.
    """
    if isinstance(pair_or_camera, OdsPair):
        cams = (pair_or_camera.left.camera, pair_or_camera.right.camera)
    else:
        cams = pair_or_camera
    if not all(isinstance(c, SphericalCamera) for c in cams):
        raise TypeError("pair_or_camera: expected an OdsPair or two SphericalCameras")
    _, vl, _ = cams[0].project(points_world)
    _, vr, _ = cams[1].project(points_world)
    return vr - vl
