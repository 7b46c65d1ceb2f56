"""Mesh export: a :class:`~ibr.mesh.QuadMesh` as Wavefront OBJ, binary PLY, or a PNG of its
segmentation (seed 002 plate I-A).

Every file is written atomically (:func:`ibr.io.images.atomic_path`). Texture coordinates follow
the OBJ/PLY convention (origin at the image's bottom-left): ``s = (u + 0.5) / W``,
``t = 1 - (v + 0.5) / H`` at a pixel-edge corner (u, v), pixel centers at integer coordinates.
"""

from __future__ import annotations

import os

import numpy as np

from ..mesh.quad_mesh import QuadMesh, segmentation_image
from ..base.validate import check_image_size
from .images import atomic_path

__all__ = ["write_obj", "write_ply", "write_segmentation_png"]

_FRAMES = ("cam", "world")


def _export_arrays(mesh: QuadMesh, frame: str):
    """Vertices (4K, 3), texture coords (4K, 2) and kept quad indices (K,) for export.

    Texture coordinates follow the OBJ/PLY convention (origin at the image's bottom-left):
    ``s = (u + 0.5) / W``, ``t = 1 - (v + 0.5) / H`` for a pixel-edge corner (u, v); e.g. the
    image's top-left corner (-0.5, -0.5) maps to (0, 1). Quads with a corner at 1/z <= 0 are left
    out. Each face lists its corners top-left, bottom-left, bottom-right, top-right, i.e.
    counter-clockwise as seen from the source camera, so faces point back at the camera.
    """
    if frame not in _FRAMES:
        raise ValueError(f"frame: expected one of {', '.join(map(repr, _FRAMES))}, got {frame!r}")
    corners = mesh.corners_cam  # TL, TR, BR, BL
    keep = np.flatnonzero(np.isfinite(corners).all(axis=(1, 2)))
    corners = corners[keep][:, [0, 3, 2, 1]]
    uv = mesh.corners_uv[keep][:, [0, 3, 2, 1]]
    if frame == "world":
        m = mesh.camera.world_from_cam
        corners = corners @ m[:3, :3].T + m[:3, 3]
    h, w = mesh.shape
    st = np.stack([(uv[..., 0] + 0.5) / w, 1.0 - (uv[..., 1] + 0.5) / h], -1)
    return corners.reshape(-1, 3), st.reshape(-1, 2), keep


def write_obj(mesh: QuadMesh, path, *, texture=None, frame: str = "cam") -> int:
    """Write the mesh as a Wavefront OBJ of independent textured quads; returns the quad count.

    Parameters
    ----------
    mesh : QuadMesh
    path : str or Path
        ``.obj`` file, written atomically (temporary name in the same folder, then renamed).
    texture : str, optional
        File name of the source image (relative to the OBJ, e.g. ``"color.png"``); when given, a
        material file ``<stem>.mtl`` with ``map_Kd texture`` is written next to the OBJ.
    frame : {"cam", "world"}
        Coordinates of the vertices: the source camera frame (x right, y down, z forward) or the
        world frame (through ``camera.world_from_cam``).

    Texture coordinates: ``vt = ((u + 0.5) / W, 1 - (v + 0.5) / H)`` at pixel-edge corners, so the
    image's top-left corner is (0, 1) and bottom-right (1, 0) (OBJ origin bottom-left).
    """
    if not isinstance(mesh, QuadMesh):
        raise TypeError(f"mesh: expected a QuadMesh, got {type(mesh).__name__}")
    verts, st, keep = _export_arrays(mesh, frame)
    path = str(path)
    stem = os.path.splitext(os.path.basename(path))[0]
    lines = [f"# ibr quad mesh: {len(keep)} quads, {mesh.shape[1]}x{mesh.shape[0]} source, frame={frame}\n"]
    if texture is not None:
        lines.append(f"mtllib {stem}.mtl\nusemtl source\n")
    buf = []
    buf.append("".join("v %.9g %.9g %.9g\n" % tuple(p) for p in verts))
    buf.append("".join("vt %.9g %.9g\n" % tuple(t) for t in st))
    idx = np.arange(1, 4 * len(keep) + 1).reshape(-1, 4)
    buf.append("".join("f %d/%d %d/%d %d/%d %d/%d\n" % (a, a, b, b, c, c, d, d) for a, b, c, d in idx))
    if texture is not None:
        mtl = os.path.join(os.path.dirname(path), f"{stem}.mtl")
        with atomic_path(mtl) as tmp, open(tmp, "w") as fh:
            fh.write(f"newmtl source\nKa 1 1 1\nKd 1 1 1\nillum 0\nmap_Kd {texture}\n")
    with atomic_path(path) as tmp, open(tmp, "w") as fh:
        fh.write("".join(lines))
        fh.writelines(buf)
    return len(keep)


def write_ply(mesh: QuadMesh, path, *, texture=None, frame: str = "cam") -> int:
    """Write the mesh as a binary little-endian PLY of textured quads; returns the quad count.

    Vertices carry ``x y z`` (float32, frame as in :func:`write_obj`) and per-vertex texture
    coordinates ``s t`` (same convention as :func:`write_obj`); faces are quads. ``texture`` adds a
    ``comment TextureFile <name>`` header line (MeshLab's convention). Written atomically.
    """
    if not isinstance(mesh, QuadMesh):
        raise TypeError(f"mesh: expected a QuadMesh, got {type(mesh).__name__}")
    verts, st, keep = _export_arrays(mesh, frame)
    nv, nf = len(verts), len(keep)
    header = ["ply", "format binary_little_endian 1.0", f"comment ibr quad mesh, frame={frame}"]
    if texture is not None:
        header.append(f"comment TextureFile {texture}")
    header += [
        f"element vertex {nv}",
        "property float x",
        "property float y",
        "property float z",
        "property float s",
        "property float t",
        f"element face {nf}",
        "property list uchar int vertex_indices",
        "end_header",
    ]
    vdt = np.dtype([("x", "<f4"), ("y", "<f4"), ("z", "<f4"), ("s", "<f4"), ("t", "<f4")])
    v = np.empty(nv, vdt)
    v["x"], v["y"], v["z"] = verts.T
    v["s"], v["t"] = st.T
    fdt = np.dtype([("n", "u1"), ("i", "<i4", (4,))])
    f = np.empty(nf, fdt)
    f["n"] = 4
    f["i"] = np.arange(nv, dtype=np.int32).reshape(-1, 4)
    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        fh.write(("\n".join(header) + "\n").encode("ascii"))
        fh.write(v.tobytes())
        fh.write(f.tobytes())
    return nf


def write_segmentation_png(mesh: QuadMesh, color, path, *, scale: int = 1) -> None:
    """Write :func:`segmentation_image` as an 8-bit PNG (atomically), upscaled by ``scale``
    (nearest neighbor) so that one-pixel quads stay visible."""
    import cv2

    if isinstance(scale, bool) or not isinstance(scale, (int, np.integer)) or scale < 1:
        raise ValueError(f"scale: expected an integer >= 1, got {scale!r}")
    h, w = mesh.shape
    check_image_size("scale", w * int(scale), h * int(scale), channels=3, itemsize=1)  # before allocating (#12)
    img = segmentation_image(mesh, color)
    if scale > 1:
        img = np.repeat(np.repeat(img, scale, 0), scale, 1)
    if not str(path).lower().endswith(".png"):
        raise ValueError(f"path: expected a .png file name, got {path!r}")
    with atomic_path(path) as tmp:
        if not cv2.imwrite(str(tmp), img[..., ::-1]):
            raise OSError(f"{path}: could not write the PNG")
