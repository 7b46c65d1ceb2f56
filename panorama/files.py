"""Panorama files: one equirect or cubemap image, or a folder of six face files.

File layouts are the single-image layouts of :mod:`panorama.layouts` (``horizon``, ``vstrip``,
``dice``) plus ``files``: a folder holding ``px.<ext> nx py ny pz nz`` (faces +x -x +y -y +z -z
in the canonical orientation of :mod:`panorama.directions`; +y is the floor). Pixel data go
through ``ibr.io`` (8/16-bit PNG, JPEG, TIFF, float EXR), written atomically.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ibr.io import read_image, write_image

from .convert import detect_layout
from .directions import FACE_FILE_NAMES
from .layouts import canonical_layout, pack_faces, unpack_faces

__all__ = ["FACE_EXTS", "FILE_LAYOUTS", "find_face_files", "read_panorama", "write_cubemap"]

FILE_LAYOUTS = ("horizon", "vstrip", "dice", "files")
#: Extensions of face files (read and written).
FACE_EXTS = (".png", ".exr", ".tif", ".tiff", ".jpg", ".jpeg", ".pfm")
_EXTS = FACE_EXTS


def find_face_files(folder) -> list[Path]:
    """The six face files ``px.* .. nz.*`` of ``folder`` in FACE_NAMES order."""
    folder = Path(folder)
    present = {p.name.lower(): p for p in folder.iterdir() if p.is_file()} if folder.is_dir() else {}
    out = []
    for name in FACE_FILE_NAMES:  # any case of the extension (px.PNG as written with --ext .PNG)
        hits = [present[f"{name}{ext}"] for ext in _EXTS if f"{name}{ext}" in present]
        if not hits:
            raise FileNotFoundError(
                f"{folder}: no face file {name}.<ext> (a face folder holds "
                f"{', '.join(FACE_FILE_NAMES)} with one of {', '.join(_EXTS)})")
        out.append(hits[0])
    return out


def read_panorama(path, *, layout: str | None = None):
    """Read an equirect image, a cubemap image or a face folder; return ``(pano, layout)``.

    ``layout`` None detects it: a folder is ``'list'`` (faces read from ``px.* .. nz.*``), an image
    is classified by :func:`panorama.detect_layout` (2:1 equirect, 6:1 horizon, 1:6 vstrip,
    4:3 dice whose unused cells are empty). Raises FileNotFoundError for a missing path and ValueError
    for an unreadable file or an image of no recognisable layout (a 4:3 photo).
    """
    path = Path(path)
    if not path.exists():
        raise FileNotFoundError(f"pano: file or folder not found: {path}")
    if path.is_dir():
        faces = [read_image(p, what=f"face {p.name}") for p in find_face_files(path)]
        unpack_faces(faces, "list")  # checks square faces of equal shape and dtype
        return faces, "list"
    img = read_image(path, what="pano")
    if layout in (None, "auto"):
        return img, detect_layout(img)
    if layout == "equirect":
        return img, "equirect"
    layout = canonical_layout(layout)
    unpack_faces(img, layout)  # checks the shape now, with a clear message
    return img, layout


def write_cubemap(path, cube, *, layout: str, face_layout: str = "list", ext: str = ".png") -> list[Path]:
    """Write ``cube`` (given in ``face_layout``) as a file in ``layout`` or a folder of faces.

    For ``layout='files'`` ``path`` is a folder (created if missing) and faces are written as
    ``px<ext>`` ...; otherwise ``path`` is one image whose extension chooses the format.
    Returns the written paths.
    """
    faces = unpack_faces(cube, face_layout)
    if layout == "files":
        folder = Path(path)
        folder.mkdir(parents=True, exist_ok=True)
        paths = [folder / f"{name}{ext}" for name in FACE_FILE_NAMES]
        for p, face in zip(paths, faces):
            write_image(p, np.ascontiguousarray(face))
        return paths
    layout = canonical_layout(layout)
    if layout in ("list", "dict"):
        raise ValueError(f"layout: {layout!r} is an in-memory layout; for files choose one of "
                         f"{', '.join(FILE_LAYOUTS)}")
    write_image(path, pack_faces(faces, layout))
    return [Path(path)]
