"""Stage 0, the ground every stage stands on: cameras, depth encodings, RGB-D views, validation.

In: numbers and arrays (intrinsics, poses, depth buffers in any encoding). Out: :class:`Camera`
(pinhole, OpenCV frame: x right, y down, z forward; 4x4 camera-to-world poses), planar depth z
(float32, NaN invalid) from every encoding (:mod:`ibr.base.depth`), :class:`View` (color + depth +
camera). The shared argument checks (:mod:`ibr.base.validate`) raise errors that name the argument.
Imports nothing else of ``ibr``.
"""

from __future__ import annotations

from .._lazy import lazy_exports

_EXPORTS = {
    "Camera": "camera",
    "GLFrustum": "camera",
    "look_at": "camera",
    "interpolate_cameras": "camera",
    "camera_from_gl_projection": "camera",
    "gl_frustum_from_projection": "camera",
    "View": "view",
}

__getattr__, __dir__, __all__ = lazy_exports(__name__, _EXPORTS)
