"""Stage 2, geometry to pixels: rasterize quad meshes into a target camera, composite, fill.

In: :class:`~ibr.mesh.QuadMesh` + source color, a target :class:`~ibr.base.Camera`. Out: per-source
layers (:class:`Layer`: color, depth, coverage), composited and hole-filled into a
:class:`Rendering` (color, depth, hole mask) by :func:`warp` and :func:`interpolate`.
:mod:`~ibr.render.rasterize` (per-quad exact homography + z-buffer), :mod:`~ibr.render.forward`
(per-pixel splat), :mod:`~ibr.render.composite` (two sources, depth-aware),
:mod:`~ibr.render.fill` (previous frame, background side), :mod:`~ibr.render.view_synthesis`
(the pipeline: :mod:`~ibr.render.sources` caches what each source view gives,
:mod:`~ibr.render.frame_composite` makes one frame from the sources' maps). Each module's numba
kernels sit beside it. Imports :mod:`ibr.base` and :mod:`ibr.mesh`.
"""

from __future__ import annotations

from .._lazy import lazy_exports

_EXPORTS = {
    "Layer": "rasterize",
    "SourceMaps": "rasterize",
    "rasterize_mesh": "rasterize",
    "render_mesh": "rasterize",
    "sample_maps": "rasterize",
    "forward_maps": "forward",
    "forward_warp": "forward",
    "fill_background": "fill",
    "fill_background_rows": "fill",
    "fill_horizontal_parallax": "fill",
    "fill_previous": "fill",
    "Rendering": "rendering",
    "interpolate": "view_synthesis",
    "iter_interpolate": "view_synthesis",
    "interpolation_meshes": "view_synthesis",
    "coarse_sources": "view_synthesis",
    "source_mesh": "sources",
    "warp": "view_synthesis",
    "viewpoint_weights": "composite",
    "sample_composite": "composite",
}

__getattr__, __dir__, __all__ = lazy_exports(__name__, _EXPORTS)
