"""Files at the edge: images, depth maps, view files, mesh export, the Middlebury sample pair.

In: paths. Out: arrays, :class:`~ibr.base.View` objects -- and back. Every write is atomic
(:func:`atomic_path`: temporary name in the destination folder, renamed when complete).
:mod:`~ibr.io.images` (OpenImageIO; PFM with numpy), :mod:`~ibr.io.view_files` (the JSON view
file and its depth encodings), :mod:`~ibr.io.mesh_files` (OBJ, PLY, segmentation PNG),
:mod:`~ibr.io.middlebury` (the motorcycle pair as views), :mod:`~ibr.io.outputs` (one output plan
per command: outputs checked before work, staged, renamed together). The algorithm stages never import
``ibr.io``: they take arrays.
"""

from __future__ import annotations

from .._lazy import lazy_exports

_EXPORTS = {
    "atomic_path": "images",
    "read_depth": "images",
    "read_image": "images",
    "read_pfm": "images",
    "write_depth": "images",
    "write_image": "images",
    "write_pfm": "images",
    "DEPTH_ENCODINGS": "view_files",
    "VIEW_FORMAT": "view_files",
    "VIEW_VERSION": "view_files",
    "load_camera": "view_files",
    "load_view": "view_files",
    "save_view": "view_files",
    "view_to_dict": "view_files",
    "write_obj": "mesh_files",
    "OutputPlan": "outputs",
    "write_ply": "mesh_files",
    "write_segmentation_png": "mesh_files",
}

__getattr__, __dir__, __all__ = lazy_exports(__name__, _EXPORTS)
