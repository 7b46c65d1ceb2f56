"""Capture rigs and target cameras for stitching: cube-face and ring rigs, equirect and ODS eyes.

Conventions of :mod:`panorama.directions`: rig frame x right, y down, z forward; yaw (longitude)
0 looks at +z and grows toward +x. A rig's ``center`` is its capture point in the world frame.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ibr.base.camera import Camera
from ibr.base.validate import check_finite_scalar, check_image_size, check_keys
from ibr.base.ray_camera import SphericalCamera
from ibr.io.view_files import json_format

from ..directions import WORLD_FROM_FACE

__all__ = ["RigFile", "cube_rig", "equirect_camera", "is_rig_file", "ods_cameras", "read_rig", "ring_rig"]


def _center(center) -> np.ndarray:
    """A rig's capture point as a float64 3-vector, or an error naming ``center``."""
    try:
        c = np.asarray(center, dtype=np.float64)
    except (TypeError, ValueError):
        raise TypeError(f"center: expected a finite 3-vector, got {center!r}") from None
    if c.shape != (3,):
        raise ValueError(f"center: expected a finite 3-vector, got shape {c.shape}")
    if not np.all(np.isfinite(c)):
        raise ValueError(f"center: expected a finite 3-vector, got {center!r}")
    return c


def _translation(center) -> np.ndarray:
    m = np.eye(4)
    m[:3, 3] = _center(center)
    return m


def _check_width(width) -> int:
    """An equirect width: even, >= 2, and within the image ceilings for float32 RGB (a stitch
    holds several such arrays: 32768 wide exhausted 24 GB)."""
    if isinstance(width, bool) or not isinstance(width, (int, np.integer)) or width < 2 or width % 2:
        raise ValueError(f"width: expected an even integer >= 2, got {width!r}")
    check_image_size("width", int(width), int(width) // 2, channels=3, itemsize=4)
    return int(width)


def equirect_camera(width: int, *, center=(0.0, 0.0, 0.0)) -> SphericalCamera:
    """Mono equirect camera of ``width x width/2`` pixels at ``center`` (world frame)."""
    width = _check_width(width)
    return SphericalCamera(int(width), int(width) // 2, "mono", world_from_rig=_translation(center))


def ods_cameras(width: int, *, ipd: float = 0.064, fade_start_deg: float = 60.0, fade_end_deg: float = 80.0,
                center=(0.0, 0.0, 0.0)) -> tuple[SphericalCamera, SphericalCamera]:
    """(left, right) omnidirectional-stereo eye cameras (see :mod:`ibr.base.ray_camera`)."""
    width = _check_width(width)
    pose = _translation(center)
    return tuple(SphericalCamera(int(width), int(width) // 2, eye, ipd, fade_start_deg, fade_end_deg, pose)
                 for eye in ("left", "right"))


def cube_rig(face_size: int, *, center=(0.0, 0.0, 0.0)) -> list[Camera]:
    """Six 90-degree pinhole cameras at ``center``, faces in the order +x -x +y -y +z -z."""
    if isinstance(face_size, bool) or not isinstance(face_size, (int, np.integer)) or face_size < 1:
        raise ValueError(f"face_size: expected a positive integer, got {face_size!r}")
    s = int(face_size)
    cams = []
    for rot in WORLD_FROM_FACE:
        pose = _translation(center)
        pose[:3, :3] = rot
        cams.append(Camera(s / 2.0, s / 2.0, (s - 1) / 2.0, (s - 1) / 2.0, s, s, pose))
    return cams


def ring_rig(n: int, *, radius: float = 0.1, width: int = 640, height: int = 480, hfov_deg: float = 90.0,
             vfov_deg: float | None = None, center=(0.0, 0.0, 0.0), pitches_deg=(0.0,)) -> list[Camera]:
    """``n`` outward-facing pinhole cameras on a horizontal ring (a camera rig), per pitch.

    Camera k sits at ``center + radius * (sin yaw_k, 0, cos yaw_k)`` with ``yaw_k = 360 k / n``
    degrees and looks outward at that yaw, tilted by each of ``pitches_deg`` (positive up).
    ``vfov_deg`` (optional) sets fy independently (default: square pixels).
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n: expected a positive integer, got {n!r}")
    radius = check_finite_scalar("radius", radius)
    if radius < 0:
        raise ValueError(f"radius: expected a finite distance >= 0, got {radius!r}")
    if vfov_deg is not None and not 0 < check_finite_scalar("vfov_deg", vfov_deg) < 180:
        raise ValueError(f"vfov_deg: expected 0 < fov < 180, got {vfov_deg!r}")
    pitches_deg = [check_finite_scalar(f"pitches_deg[{i}]", x) for i, x in enumerate(np.atleast_1d(pitches_deg))]
    c = _center(center)
    cams = []
    for pitch in pitches_deg:
        for k in range(int(n)):
            yaw = 2 * math.pi * k / n
            p = math.radians(pitch)
            ry = np.array([[math.cos(yaw), 0, math.sin(yaw)], [0, 1, 0], [-math.sin(yaw), 0, math.cos(yaw)]])
            rx = np.array([[1, 0, 0], [0, math.cos(p), -math.sin(p)], [0, math.sin(p), math.cos(p)]])
            pose = np.eye(4)
            pose[:3, :3] = ry @ rx
            pose[:3, 3] = c + radius * np.array([math.sin(yaw), 0.0, math.cos(yaw)])
            cam = Camera.from_fov(width, height, hfov_deg=hfov_deg, world_from_cam=pose)
            if vfov_deg is not None:
                fy = height / (2 * math.tan(math.radians(vfov_deg) / 2))
                cam = Camera(cam.fx, fy, cam.cx, cam.cy, width, height, pose)
            cams.append(cam)
    return cams


# ----------------------------------------------------------------------------- rig files
#: File name of a rig inside its folder (``ibr stitch FOLDER`` reads FOLDER/rig.json).
RIG_FILE_NAME = "rig.json"


@dataclass(frozen=True)
class RigFile:
    """A rig file (``"format": "ibr-rig"``, written by ``samples/generate_rig.py``): the view
    files of one capture (absolute paths), its capture point in the world frame, and its centre
    panorama's colour and range files when it has one."""

    views: tuple[Path, ...]
    center: np.ndarray
    panorama: tuple[Path, Path] | None = None


def is_rig_file(path) -> bool:
    """Whether ``path`` is a rig: a file named :data:`RIG_FILE_NAME`, a folder holding one, or a
    JSON file of format "ibr-rig" (a broken rig.json is still a rig: :func:`read_rig` names its
    error, it is not taken for something else)."""
    p = Path(path)
    if p.is_dir():
        return (p / RIG_FILE_NAME).is_file()
    if p.name == RIG_FILE_NAME:
        return True
    return p.suffix.lower() == ".json" and json_format(p) == "ibr-rig"


def read_rig(path) -> RigFile:
    """Read a rig file (or the :data:`RIG_FILE_NAME` of a folder). Keys: ``format`` ("ibr-rig"),
    ``version`` (1), ``views`` (view files, relative to the rig file's folder or absolute; at
    least one), ``center`` (optional 3-vector, default the origin), ``scene`` (optional name),
    ``panorama`` (optional ``{"color", "range", "width"}``). Unknown keys are refused with the
    nearest valid name (docs/files.md)."""
    p = Path(path)
    if p.is_dir():
        p = p / RIG_FILE_NAME
    where = f"rig file {p}"
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise FileNotFoundError(f"{where}: not found") from None
    except ValueError as exc:
        raise ValueError(f"{where}: not valid JSON ({exc})") from None
    check_keys(where, doc, ("format", "version", "scene", "center", "views", "panorama"),
               required=("format", "version", "views"))
    if doc["format"] != "ibr-rig" or doc["version"] != 1:
        raise ValueError(f"{where}: expected format 'ibr-rig' version 1, got {doc['format']!r} {doc['version']!r}")
    views = doc["views"]
    if not isinstance(views, list) or not views or not all(isinstance(v, str) and v.strip() for v in views):
        raise ValueError(f"{where}: 'views' must be a non-empty list of view file names")
    paths = tuple(p.parent / v for v in views)  # read only: relative to the rig file, or absolute
    try:
        center = _center(doc.get("center", (0.0, 0.0, 0.0)))
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None
    pano = doc.get("panorama")
    if pano is not None:
        check_keys(f"{where}: 'panorama'", pano, ("color", "range", "width"), required=("color", "range"))
        if not all(isinstance(pano[k], str) and pano[k].strip() for k in ("color", "range")):
            raise ValueError(f"{where}: 'panorama': 'color' and 'range' must be file names")
        pano = tuple(p.parent / pano[k] for k in ("color", "range"))
    return RigFile(paths, center, pano)
