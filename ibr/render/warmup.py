"""Compile the frame kernels in a second process on the first run (issue #13, cold start).

numba compiles each kernel the first time it is called, one after the other, on one core: a fresh
install's first ``ibr interpolate`` spent ~9 s compiling (segmentation 3.6 s, rasterizer 2.2 s,
compositor 1.6 s, hole fill 1.8 s) while the second core idled.
:func:`ibr.base.first_run.start_helper` starts ``python -m ibr.render.warmup``, which calls the
rasterizer and then the hole fill (its directional pass and pull-push) on a tiny scene with the
argument types of a real run (uint8 colour, float32 depth, the mesh's read-only arrays), at LLVM
-O2 (:data:`ibr.base.first_run.HELPER_OPT`), so they land in numba's on-disk cache while the main
process compiles the segmentation's edge prefix, split and plane fit and the compositor (the directional pass moved here from the
main process: median first run 12.95 -> 12.70 s, three runs each on the 2-core machine);
when the main process reaches them it loads them from the cache instead. ``python -m
ibr.render.warmup stitch`` (``stitch-ods``) does the same for ``ibr stitch`` (the ray rasterizer's
setup, the plane fit, the N-source blend's accumulation into a spherical camera and the mono (ODS)
panorama's hole fill; the main process compiles the ray raster kernel and the resolve itself),
``... mesh`` for ``ibr mesh`` (the split's callees that are functions of their own and the
plane fit). Nothing
here is needed for correctness: if the helper is slow or fails, the main process compiles what it
needs itself.

The helper marks each group of kernels it has cached (a file per group in a directory of this run,
:mod:`ibr.base.first_run`); ``await_kernels`` lets the main process wait for a group the helper is
still compiling instead of compiling the same kernel a second time on the other core. Without that,
the main process reached the rasterizer 0.3 s before the helper had cached it and compiled it again
(1.2 s), then did the same with the fill (#13).
"""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path

import numpy as np

from ..base.first_run import mark as _mark

__all__ = ["warm_frame_kernels", "warm_mesh_kernels", "warm_stitch_kernels"]


def warm_frame_kernels(marks: Path | None = None) -> None:
    """Call the rasterizer and the hole fill once on a tiny scene (types as in a real run), in
    the order the main process will need them after its own segmentation kernels and plane fit
    (the rasterizer with its crack closing is the longest compile of the first run: the main
    process, waiting for it, compiles the plane fit itself); mark groups "raster" and "fill" (the
    directional fill and the pull-push) in the directory ``marks`` as they land in the cache.
    :func:`ibr.base.first_run.start_helper` runs this process with LLVM at -O2
    (:data:`ibr.base.first_run.HELPER_OPT`)."""
    from ..base.camera import Camera
    from . import fill
    from .rasterize import CRACK_REL, _rasterize_many_into, scratch_maps

    h, w = 24, 32
    mesh = _tiny_mesh()
    moved = Camera(30.0, 30.0, (w - 1) / 2, (h - 1) / 2, w, h,
                   np.array([[1, 0, 0, 0.3], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]))
    # as view synthesis rasterizes: with its crack closing
    _rasterize_many_into([mesh], moved, "free", 0.01, [scratch_maps("warm", moved.shape)], crack_rel=CRACK_REL)
    _mark(marks, "raster")
    color = np.full((h, w, 3), 128, np.uint8)
    depth = np.full((h, w), 3.0, np.float32)
    holes = np.zeros((h, w), np.bool_)
    holes[8:12, 10:20] = True
    depth[holes] = np.nan
    fill._fill_pullpush_inplace(color, depth, holes, axis=0)
    _mark(marks, "fill")


def _tiny_mesh():
    """A 32 x 24 source of two quads (a step from z = 2 to z = 4) with the argument types of a
    real mesh, built by hand (no plane fit: the main process compiles it after its
    segmentation, #13)."""
    from ..base.camera import Camera
    from ..mesh.quad_mesh import QuadMesh

    h, w = 24, 32
    cam = Camera(30.0, 30.0, (w - 1) / 2, (h - 1) / 2, w, h)
    rects = np.array([[0, 0, w // 2, h], [w // 2, 0, w, h]], np.int32)
    planes = np.array([[0.0, 0.0, 0.5], [0.0, 0.0, 0.25]])
    qop = np.zeros((h, w), np.int32)
    qop[:, w // 2:] = 1
    return QuadMesh(cam, rects, planes, qop, {})


def warm_stitch_kernels(marks: Path | None = None, eye_fill: str = "any") -> None:
    """The kernels ``ibr stitch`` runs after its segmentation, but two: the ray rasterizer's
    setup (setup and region; group "ray-setup"), the mesh's plane fit ("plane-fit"), the
    blend's spherical accumulation ("blend") and the panorama's hole fill ("background-fill" for
    a mono panorama, ``eye_fill="any"``; "row-fill" for ODS eyes, ``"rows"``), on the tiny mesh
    and a small equirect ray camera. The ray raster kernel and the blend's resolve are left to the
    main process, which reaches the raster when its segmentation is done and the resolve while
    this process compiles the fill (#13: the main process compiled the fill last, 0.9 s alone on
    one core): here they are skipped for the setup and the blend, and the rays come from the
    numpy reference."""
    from ..base.ray_camera import SphericalCamera
    from ..mesh import _segment_kernels as k
    from . import _blend_kernels, _ray_kernels, blend, fill
    from .ray_raster import rasterize_mesh_rays, rasterize_mesh_rays_reference
    from .rasterize import SourceMaps

    mesh = _tiny_mesh()
    camera = SphericalCamera(64, 32)
    h, w = camera.shape
    maps = SourceMaps(*(np.empty((h, w), np.float32) for _ in range(3)), np.empty((h, w), np.bool_))
    with _replaced(_ray_kernels, "raster_rays", _skip):
        rasterize_mesh_rays(mesh, camera, out=maps, _region=[0, -1, None])
    _mark(marks, "ray-setup")
    k.fit_planes_inv_depth(np.ones((24, 32)), np.array([[0, 0, 32, 24]], np.int32))
    _mark(marks, "plane-fit")

    def reference_rays(mesh, camera, *, footprint, out, _region):
        ref = rasterize_mesh_rays_reference(mesh, camera)
        for name in ("depth", "map_u", "map_v", "coverage"):
            getattr(out, name)[...] = getattr(ref, name)
        _region[:] = [0, camera.shape[0] - 1, np.ones(camera.shape[1], np.uint8)]  # the types of _k.region's
        return out

    with _replaced(blend, "rasterize_mesh_rays", reference_rays), _replaced(_blend_kernels, "resolve", _skip):
        blend.blend_sources([(mesh, np.full((24, 32, 3), 128, np.uint8))], camera)
    _mark(marks, "blend")
    color = np.full((h, w, 3), 128, np.uint8)  # the stitched panorama's 8-bit colour
    depth = np.full((h, w), 3.0, np.float32)
    seen = np.ones((h, w), np.bool_)
    seen[8:12, 10:20] = False
    depth[~seen] = np.nan
    if eye_fill == "rows":
        fill.fill_horizontal_parallax(color, depth, seen)
        _mark(marks, "row-fill")
    else:
        fill.fill_background(color, depth, ~seen)
        _mark(marks, "background-fill")


def warm_mesh_kernels(marks: Path | None = None) -> None:
    """For ``ibr mesh``: the kernels the segmentation's split calls as functions of their own (the
    plane fit's moments, the plane test's row check, the crease split's line profile; the plane
    test, the quick reject and the crease split themselves are inlined into the split) and the
    plane fit, called directly on a small z' image with the argument types of a real run (int32
    rect bounds, as popped from the split's stack; float64 z'), groups "segment" and
    "plane-fit". The main process compiles the edge prefix and the split meanwhile."""
    from ..mesh import _segment_kernels as k

    h, w = 48, 64
    zp = np.linspace(0.0, 1.0, h * w).reshape(h, w)
    u0, v0, u1, v1 = np.int32(0), np.int32(0), np.int32(w), np.int32(h)
    k._rect_moments(zp, u0, v0, u1, v1)
    k._row_exceeds(zp[v0], u0, u1, 0.5, 0.0, 31.5, 0.1)
    k._add_abs_second_diff(np.zeros(w)[u0:u1], zp[v0, u0:u1], np.int64(w))
    _mark(marks, "segment")  # the split can start; the plane fit is needed only after it
    k.fit_planes_inv_depth(zp, np.array([[0, 0, w, h]], np.int32))
    _mark(marks, "plane-fit")


def _skip(*args) -> None:
    """Stands in for a kernel whose compilation is left to the main process."""


@contextlib.contextmanager
def _replaced(module, name: str, value):
    """``module.name`` is ``value`` inside the block (this helper process only)."""
    original = getattr(module, name)
    setattr(module, name, value)
    try:
        yield
    finally:
        setattr(module, name, original)


if __name__ == "__main__":
    _kind = sys.argv[1] if len(sys.argv) > 1 else "frame"
    _marks = Path(sys.argv[2]) if len(sys.argv) > 2 else None
    if _kind in ("stitch", "stitch-ods"):
        warm_stitch_kernels(_marks, "rows" if _kind == "stitch-ods" else "any")
    else:
        {"mesh": warm_mesh_kernels}.get(_kind, warm_frame_kernels)(_marks)
