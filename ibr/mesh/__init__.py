"""Stage 1, depth to geometry: seed 002's segmentation and the adaptive planar quad mesh.

In: a :class:`~ibr.base.View` (or a camera and planar depth). Out: :class:`QuadMesh` -- arrays of
source-pixel rectangles, each with the plane of inverse depth ``1/z = a u + b v + c`` it lies on.
:mod:`ibr.mesh.segment` holds the nonlinear z', the second-difference buffer, break edges and the
binary split; :mod:`ibr.mesh.quad_mesh` fits the planes. Kernels sit beside them. Imports only
:mod:`ibr.base`; writing meshes to files is :mod:`ibr.io.mesh_files`.
"""

from __future__ import annotations

from .._lazy import lazy_exports

_EXPORTS = {
    "QuadMesh": "quad_mesh",
    "build_mesh": "quad_mesh",
    "fit_inv_depth_planes": "quad_mesh",
    "mesh_depth": "quad_mesh",
    "segmentation_image": "quad_mesh",
}

__getattr__, __dir__, __all__ = lazy_exports(__name__, _EXPORTS)
