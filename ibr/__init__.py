"""ibr: image-based rendering from RGB-D views.

Depth buffers become adaptive planar quad meshes (seed 002), meshes are inverse-warped into new
viewpoints, two sources fill each other's holes. Conventions are in DESIGN.md section 4 and the
README: camera frame x right / y down / z forward, pixel centers at integer coordinates, planar
depth in scene units with NaN where invalid.

Public names are imported lazily so that ``import ibr`` stays fast.
"""

from __future__ import annotations

import importlib

__version__ = "0.1.0"

_EXPORTS = {
    # camera.py
    "Camera": "camera",
    "look_at": "camera",
    "interpolate_cameras": "camera",
    "camera_from_gl_projection": "camera",
    "gl_frustum_from_projection": "camera",
    # view.py
    "View": "view",
    # io.py
    "load_view": "io",
    "save_view": "io",
    "read_image": "io",
    "write_image": "io",
    "read_depth": "io",
    "write_depth": "io",
    # mesh.py / segment.py
    "build_mesh": "mesh",
    "QuadMesh": "mesh",
    # view_synthesis.py
    "warp": "view_synthesis",
    "interpolate": "view_synthesis",
    "Rendering": "view_synthesis",
}

__all__ = sorted(_EXPORTS) + ["__version__"]


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'ibr' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__():
    return __all__
