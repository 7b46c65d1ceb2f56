"""ibr: image-based rendering from RGB-D views.

Depth buffers become adaptive planar quad meshes (seed 002), meshes are inverse-warped into new
viewpoints, two sources fill each other's holes. Conventions are in DESIGN.md section 4 and the
README: camera frame x right / y down / z forward, pixel centers at integer coordinates, planar
depth in scene units with NaN where invalid.

The stages live in subpackages (``docs/architecture.md``): :mod:`ibr.base` (cameras, depth
encodings, views), :mod:`ibr.mesh` (segmentation, quad meshes), :mod:`ibr.render` (rasterizer,
compositing, fill, view synthesis), :mod:`ibr.stereo` (stereo camera, pairs, lens, time-warp),
:mod:`ibr.synth` (synthetic scenes) and :mod:`ibr.io` (files). Public names are imported lazily
so that ``import ibr`` stays fast.
"""

from __future__ import annotations

import os as _os

from ._lazy import lazy_exports

# numba's OpenMP threads spin for a while after each parallel kernel; with as many threads as
# cores they take the CPU from OpenCV's threads and from ibr's band pool working next (cv2.remap
# 1.4x slower right after the panorama's parallel map kernel, #13). Waiting passively puts them
# to sleep instead (waking them costs microseconds per kernel). Read by libgomp when numba
# first loads it, which is after this import unless the program ran a parallel numba kernel
# before importing ibr (then the setting has no effect: README); a user's own setting wins.
_os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

__version__ = "0.1.0"

_EXPORTS = {
    "Camera": "base.camera",
    "look_at": "base.camera",
    "interpolate_cameras": "base.camera",
    "camera_from_gl_projection": "base.camera",
    "gl_frustum_from_projection": "base.camera",
    "View": "base.view",
    "load_view": "io.view_files",
    "save_view": "io.view_files",
    "read_image": "io.images",
    "write_image": "io.images",
    "read_depth": "io.images",
    "write_depth": "io.images",
    "build_mesh": "mesh.quad_mesh",
    "QuadMesh": "mesh.quad_mesh",
    "warp": "render.view_synthesis",
    "interpolate": "render.view_synthesis",
    "iter_interpolate": "render.view_synthesis",
    "Rendering": "render.rendering",
    # Modules that were top-level before the stage layout (#9): ``ibr.base.depth``, ``ibr.stereo.lens`` ...
    # keep working as attributes.
    "camera": "base.camera.",
    "depth": "base.depth.",
    "view": "base.view.",
    "middlebury": "io.middlebury.",
    "segment": "mesh.segment.",
    "composite": "render.composite.",
    "fill": "render.fill.",
    "forward": "render.forward.",
    "view_synthesis": "render.view_synthesis.",
    "stereo_pair": "stereo.pair.",
    "lens": "stereo.lens.",
    "timewarp": "stereo.timewarp.",
}

__getattr__, __dir__, _names = lazy_exports(__name__, _EXPORTS)
__all__ = _names + ["__version__"]
