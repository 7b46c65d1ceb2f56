"""Compile the frame kernels in a second process on the first run (issue #13, cold start).

numba compiles each kernel the first time it is called, one after the other, on one core: a
fresh install's first ``ibr interpolate`` spent ~9 s compiling (segmentation 3.6 s, rasterizer
2.2 s, compositor 1.6 s, hole fill 1.8 s) while the second core idled. :func:`start_warmup`
starts ``python -m ibr.render.warmup``, which calls the mesh's plane fit and labelling, the
rasterizer and then the hole fill on a tiny scene with the argument types of a real run (uint8
colour, float32 depth, the mesh's read-only arrays), so they land in numba's on-disk cache while
the main process compiles the segmentation's splitting and the compositor; when the main process
reaches them it loads them from the cache instead. ``python -m ibr.render.warmup stitch`` does the
same for ``ibr stitch`` (ray rasterizer and N-source blend into a spherical camera). Nothing here
is needed for correctness: if the helper is slow or fails, the main process compiles what it needs
itself.
"""

from __future__ import annotations

import atexit
import os
import subprocess
import sys

import numpy as np

__all__ = ["start_warmup", "warm_frame_kernels", "warm_stitch_kernels"]

_STARTED: list = []


def warm_frame_kernels() -> None:
    """Call the mesh's plane fit and labelling (the last segmentation steps), the rasterizer and
    the hole fill once on a tiny scene (types as in a real run), in the order the main process
    will need them after its own segmentation kernels."""
    from ..base.camera import Camera
    from .fill import _fill_pullpush_inplace
    from .rasterize import rasterize_mesh

    h, w = 24, 32
    mesh = _tiny_mesh()
    moved = Camera(30.0, 30.0, (w - 1) / 2, (h - 1) / 2, w, h,
                   np.array([[1, 0, 0, 0.3], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]))
    rasterize_mesh(mesh, moved)
    color = np.full((h, w, 3), 128, np.uint8)
    depth = np.full((h, w), 3.0, np.float32)
    holes = np.zeros((h, w), np.bool_)
    holes[8:12, 10:20] = True
    depth[holes] = np.nan
    _fill_pullpush_inplace(color, depth, holes, axis=0)


def _tiny_mesh():
    """A 32 x 24 source of two quads (a step from z = 2 to z = 4), the argument types of a real
    mesh (the mesh's plane fit and labelling compiled on the way)."""
    from ..base.camera import Camera
    from ..mesh._segment_kernels import fit_planes_inv_depth, label_rects
    from ..mesh.quad_mesh import QuadMesh

    h, w = 24, 32
    seg_rects = np.array([[0, 0, w, h]], np.int32)
    fit_planes_inv_depth(np.full((h, w), 0.5), seg_rects)
    label_rects(seg_rects, h, w)
    cam = Camera(30.0, 30.0, (w - 1) / 2, (h - 1) / 2, w, h)
    rects = np.array([[0, 0, w // 2, h], [w // 2, 0, w, h]], np.int32)
    planes = np.array([[0.0, 0.0, 0.5], [0.0, 0.0, 0.25]])
    qop = np.zeros((h, w), np.int32)
    qop[:, w // 2:] = 1
    return QuadMesh(cam, rects, planes, qop, {})


def warm_stitch_kernels() -> None:
    """Blend the tiny mesh into a small equirect ray camera (what ``ibr stitch`` runs after its
    segmentation): ray setup and raster, the spherical accumulation and the resolve."""
    from ..base.ray_camera import SphericalCamera
    from .blend import blend_sources

    mesh = _tiny_mesh()
    blend_sources([(mesh, np.full((24, 32, 3), 128, np.uint8))], SphericalCamera(64, 32))


def start_warmup(kind: str = "frame") -> None:
    """Start the helper process for ``kind`` ("frame": rasterizer and fill; "stitch": ray
    rasterizer and blend) once per process (quietly; killed at exit if still running)."""
    if _STARTED or os.environ.get("NUMBA_DISABLE_JIT") or os.environ.get("IBR_NO_WARMUP"):
        return
    try:
        proc = subprocess.Popen([sys.executable, "-m", "ibr.render.warmup", kind], stdin=subprocess.DEVNULL,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    except OSError:
        return
    _STARTED.append(proc)
    atexit.register(_stop, proc)


def _stop(proc) -> None:
    if proc.poll() is None:
        proc.kill()
        proc.wait()


if __name__ == "__main__":
    warm_stitch_kernels() if sys.argv[1:] == ["stitch"] else warm_frame_kernels()
