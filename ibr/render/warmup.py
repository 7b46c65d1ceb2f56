"""Compile the frame kernels in a second process on the first run (issue #13, cold start).

numba compiles each kernel the first time it is called, one after the other, on one core: a
fresh install's first ``ibr interpolate`` spent ~9 s compiling (segmentation 3.6 s, rasterizer
2.2 s, compositor 1.6 s, hole fill 1.8 s) while the second core idled. :func:`start_warmup`
starts ``python -m ibr.render.warmup``, which calls the rasterizer and then the hole fill on a
tiny scene with the argument types of a real run (uint8 colour, float32 depth, the mesh's
read-only arrays), so they land in numba's on-disk cache while the main process compiles the
segmentation (splitting, plane fit, labelling) and the compositor; when the main process
reaches them it loads them from the cache instead. ``python -m ibr.render.warmup stitch`` does the
same for ``ibr stitch`` (the ray rasterizer's setup and the N-source blend into a spherical
camera; the main process compiles the ray raster kernel itself). Nothing here
is needed for correctness: if the helper is slow or fails, the main process compiles what it needs
itself.

The helper marks each group of kernels it has cached (a file per group in a directory of this
run); :func:`await_kernels` lets the main process wait for a group the helper is still compiling
instead of compiling the same kernel a second time on the other core. Without that, the main
process reached the rasterizer 0.3 s before the helper had cached it and compiled it again (1.2 s),
then did the same with the fill (#13).
"""

from __future__ import annotations

import atexit
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

__all__ = ["await_kernels", "start_warmup", "warm_frame_kernels", "warm_stitch_kernels"]

_STARTED: list = []  # (helper process, marker directory, groups it marks, owner pid) once started
#: The kernel groups each kind of helper marks (a group of the other kind is not waited for).
GROUPS = {"frame": ("raster", "fill"), "stitch": ("ray-setup", "blend")}
_READY: set = set()  # groups this process no longer waits for
#: The longest wait for one group (s): the helper takes ~8 s in all; past this the main process
#: compiles the kernels itself (an overloaded machine, a helper stuck on its imports).
MAX_WAIT_S = 15.0


def warm_frame_kernels(marks: Path | None = None) -> None:
    """Call the rasterizer and the hole fill once on a tiny scene (types as in a real run), in
    the order the main process will need them after its own segmentation kernels; mark groups
    "raster" and "fill" in the directory ``marks`` as they land in the cache."""
    from ..base.camera import Camera
    from .fill import _fill_pullpush_inplace
    from .rasterize import rasterize_mesh

    h, w = 24, 32
    mesh = _tiny_mesh()
    moved = Camera(30.0, 30.0, (w - 1) / 2, (h - 1) / 2, w, h,
                   np.array([[1, 0, 0, 0.3], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]]))
    rasterize_mesh(mesh, moved)
    _mark(marks, "raster")
    color = np.full((h, w, 3), 128, np.uint8)
    depth = np.full((h, w), 3.0, np.float32)
    holes = np.zeros((h, w), np.bool_)
    holes[8:12, 10:20] = True
    depth[holes] = np.nan
    _fill_pullpush_inplace(color, depth, holes, axis=0)
    _mark(marks, "fill")


def _tiny_mesh():
    """A 32 x 24 source of two quads (a step from z = 2 to z = 4) with the argument types of a
    real mesh, built by hand: the plane fit and labelling are left to the main process, which
    reaches them right after its segmentation (compiling them here too made this helper the
    last to finish, #13)."""
    from ..base.camera import Camera
    from ..mesh.quad_mesh import QuadMesh

    h, w = 24, 32
    cam = Camera(30.0, 30.0, (w - 1) / 2, (h - 1) / 2, w, h)
    rects = np.array([[0, 0, w // 2, h], [w // 2, 0, w, h]], np.int32)
    planes = np.array([[0.0, 0.0, 0.5], [0.0, 0.0, 0.25]])
    qop = np.zeros((h, w), np.int32)
    qop[:, w // 2:] = 1
    return QuadMesh(cam, rects, planes, qop, {})


def warm_stitch_kernels(marks: Path | None = None) -> None:
    """The kernels ``ibr stitch`` runs after its segmentation, but one: the ray rasterizer's setup
    (setup, bucketing, region; group "ray-setup"), then the spherical accumulation and the resolve
    of the blend (group "blend"), on the tiny mesh and a small equirect ray camera. The ray raster
    kernel itself is left to the main process, which reaches it when its segmentation is done
    (compiling the whole chain here kept the main process waiting 4 s, #13): here it is skipped
    for the setup and replaced by the numpy reference for the blend."""
    from ..base.ray_camera import SphericalCamera
    from . import _ray_kernels, blend
    from .ray_raster import rasterize_mesh_rays, rasterize_mesh_rays_reference
    from .rasterize import SourceMaps

    mesh = _tiny_mesh()
    camera = SphericalCamera(64, 32)
    h, w = camera.shape
    maps = SourceMaps(*(np.empty((h, w), np.float32) for _ in range(3)), np.empty((h, w), np.bool_))
    raster_rays = _ray_kernels.raster_rays
    _ray_kernels.raster_rays = _skip
    try:
        rasterize_mesh_rays(mesh, camera, out=maps, _region=[0, -1, None])
    finally:
        _ray_kernels.raster_rays = raster_rays
    _mark(marks, "ray-setup")

    def reference_rays(mesh, camera, *, footprint, out, _region):
        ref = rasterize_mesh_rays_reference(mesh, camera)
        for name in ("depth", "map_u", "map_v", "coverage"):
            getattr(out, name)[...] = getattr(ref, name)
        _region[:] = [0, camera.shape[0] - 1, np.ones(camera.shape[1], np.uint8)]  # the types of _k.region's
        return out

    rays = blend.rasterize_mesh_rays
    blend.rasterize_mesh_rays = reference_rays
    try:
        blend.blend_sources([(mesh, np.full((24, 32, 3), 128, np.uint8))], camera)
    finally:
        blend.rasterize_mesh_rays = rays
    _mark(marks, "blend")


def _skip(*args) -> None:
    """Stands in for a kernel whose compilation is left to the main process."""


def _mark(marks: Path | None, group: str) -> None:
    if marks is not None:
        try:
            (marks / group).touch()
        except OSError:  # the main process has gone (and removed the directory): nobody waits
            pass


def await_kernels(group: str) -> None:
    """Wait until the first-run helper has cached kernel group ``group`` (:data:`GROUPS`), while it
    runs and at most :data:`MAX_WAIT_S`; at once when no helper was started
    (every run but a first one) or the group was awaited before."""
    if not _STARTED or group in _READY:
        return
    proc, marks, groups, owner = _STARTED[0]
    if group not in groups or os.getpid() != owner:  # not this helper's, or a forked child
        return
    deadline = time.monotonic() + MAX_WAIT_S
    while not (marks / group).exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.005)
    _READY.add(group)


def start_warmup(kind: str = "frame") -> None:
    """Start the helper process for ``kind`` ("frame": rasterizer and fill; "stitch": ray
    rasterizer and blend) once per process (quietly; killed at exit if still running)."""
    if _STARTED or os.environ.get("NUMBA_DISABLE_JIT") or os.environ.get("IBR_NO_WARMUP"):
        return
    marks = Path(tempfile.mkdtemp(prefix="ibr-warmup-"))
    try:
        proc = subprocess.Popen([sys.executable, "-m", "ibr.render.warmup", kind, str(marks)],
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    except OSError:
        shutil.rmtree(marks, ignore_errors=True)
        return
    _STARTED.append((proc, marks, GROUPS.get(kind, ()), os.getpid()))
    atexit.register(_stop, proc, marks, os.getpid())


def _stop(proc, marks: Path, owner: int) -> None:
    if os.getpid() != owner:  # a forked child exiting: the helper and its marks are the parent's
        return
    if proc.poll() is None:
        proc.kill()
        proc.wait()
    shutil.rmtree(marks, ignore_errors=True)


if __name__ == "__main__":
    _kind = sys.argv[1] if len(sys.argv) > 1 else "frame"
    _marks = Path(sys.argv[2]) if len(sys.argv) > 2 else None
    warm_stitch_kernels(_marks) if _kind == "stitch" else warm_frame_kernels(_marks)
