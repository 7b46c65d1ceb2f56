"""panorama: spherical images (equirectangular, cubemaps, perspective views) built on ``ibr``.

Conventions are written once in :mod:`panorama.directions` (longitude 0 = +z, growing toward +x,
latitude positive up = -y; faces +x -x +y -y +z -z with +y the floor) and
:mod:`panorama.layouts` (dict, list, horizon, vstrip, dice; folders of six files in
:mod:`panorama.files`).
"""

from .convert import cubemap_to_equirect, detect_layout, equirect_to_cubemap, perspective
from .directions import FACE_FILE_NAMES, FACE_NAMES, WORLD_FROM_FACE, world_from_view
from .layouts import LAYOUTS, pack_faces, unpack_faces
from .photo import stitch_photos

__all__ = [
    "FACE_FILE_NAMES",
    "FACE_NAMES",
    "LAYOUTS",
    "WORLD_FROM_FACE",
    "cubemap_to_equirect",
    "detect_layout",
    "equirect_to_cubemap",
    "pack_faces",
    "perspective",
    "stitch_photos",
    "unpack_faces",
    "world_from_view",
]
