"""Quad meshes of an RGB-D panorama, one per cube face, packed for the web viewer (#18).

The viewer draws an RGB-D panorama as geometry instead of a sphere, so that moving the viewpoint
inside a small head box shows motion parallax. The geometry is the engine's adaptive quad mesh
(:func:`ibr.build_mesh`, seed 002 section 1.2) of each 90-degree cube-face view
(:func:`panorama.stitch.panorama_views`): a flat wall is one quad, not a million pixels.

Binary format (``mesh.bin``, little endian, version 1)::

    b"IBRQ"  uint32 version  uint32 face_size  uint32 quads[6]     (36 bytes)
    float32 planes[Q, 3]    (a, b, c) of 1/z = a*u + b*v + c, all faces in px nx py ny pz nz order
    uint16  rects[Q, 4]     [u0, v0, u1, v1] half-open pixel ranges (ibr.mesh.QuadMesh)

with ``Q = sum(quads)``: 20 bytes per quad. Face pixel (u, v) of face F (centres at integers,
``f = S/2``, ``c = (S-1)/2``) looks along ``right*(u-c)/f + down*(v-c)/f + forward``
(:mod:`panorama.directions`), so a quad corner at ``(u0 - 1/2, v0 - 1/2)`` lies at
``z * that ray`` with ``1/z`` from its plane. The page rebuilds the corners exactly so.
"""

from __future__ import annotations

import struct

import numpy as np

from ibr.base.validate import check_number
from ibr.mesh import QuadMesh, build_mesh

__all__ = ["MAGIC", "face_meshes", "pack_face_meshes", "unpack_face_meshes"]

MAGIC = b"IBRQ"
VERSION = 1
_HEADER = struct.Struct("<4sII6I")


def face_meshes(color, range_map, *, face_size: int | None = None, head_box: float = 0.1,
                max_error_px: float = 0.5) -> list[QuadMesh]:
    """Six quad meshes (px nx py ny pz nz) of an equirect RGB-D panorama.

    Parameters
    ----------
    color : (H, 2H[, C]) array
        Equirect colour (used only for its size and for the face views' checks).
    range_map : (H, 2H) float array
        Range along each pixel's ray from the panorama's centre, scene units; NaN where there is
        no depth (sky): those pixels get no quad and the viewer shows them at infinity.
    face_size : int, optional
        Face size in pixels (default as :func:`panorama.stitch.panorama_views`).
    head_box : float
        Largest distance the viewer moves from the centre, scene units: the level of detail is
        chosen so that a move of this size shows at most ``max_error_px`` of error (the mesh's
        ``baseline``).
    max_error_px : float
        Reprojection error bound in face pixels (:func:`ibr.build_mesh`).
    """
    from .stitch.ods import panorama_views

    head_box = check_number("head_box", head_box, minimum=0.0, exclusive_minimum=True)
    max_error_px = check_number("max_error_px", max_error_px, minimum=0.0, exclusive_minimum=True)
    views = panorama_views(color, range_map, face_size=face_size)
    return [build_mesh(v, max_error_px=max_error_px, baseline=head_box) for v in views]


def pack_face_meshes(meshes) -> bytes:
    """The six meshes as ``mesh.bin`` bytes (format in the module docstring)."""
    meshes = list(meshes)
    if len(meshes) != 6 or not all(isinstance(m, QuadMesh) for m in meshes):
        raise ValueError(f"meshes: expected six QuadMesh (px nx py ny pz nz), got {len(meshes)} items")
    size = meshes[0].shape[0]
    if any(m.shape != (size, size) for m in meshes):
        raise ValueError("meshes: expected six square meshes of one face size")
    if size > 65535:
        raise ValueError(f"meshes: face size {size} does not fit the format's uint16 pixel ranges")
    header = _HEADER.pack(MAGIC, VERSION, size, *(len(m) for m in meshes))
    planes = np.concatenate([m.inv_depth_planes for m in meshes]).astype("<f4")
    rects = np.concatenate([m.rects for m in meshes]).astype("<u2")
    return header + planes.tobytes() + rects.tobytes()


def unpack_face_meshes(data: bytes) -> tuple[int, list[tuple[np.ndarray, np.ndarray]]]:
    """``(face_size, [(rects (Q, 4) uint16, planes (Q, 3) float32) per face])`` of ``mesh.bin`` bytes."""
    if len(data) < _HEADER.size:
        raise ValueError(f"data: {len(data)} bytes is shorter than the {_HEADER.size}-byte header")
    magic, version, size, *counts = _HEADER.unpack_from(data)
    if magic != MAGIC or version != VERSION:
        raise ValueError(f"data: not a version-{VERSION} face-mesh file (magic {magic!r}, version {version})")
    total = sum(counts)
    if len(data) != _HEADER.size + 20 * total:
        raise ValueError(f"data: expected {_HEADER.size + 20 * total} bytes for {total} quads, got {len(data)}")
    planes = np.frombuffer(data, "<f4", 3 * total, _HEADER.size).reshape(total, 3)
    rects = np.frombuffer(data, "<u2", 4 * total, _HEADER.size + 12 * total).reshape(total, 4)
    out, start = [], 0
    for n in counts:
        out.append((rects[start:start + n], planes[start:start + n]))
        start += n
    return size, out
