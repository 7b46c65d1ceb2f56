"""Synthetic scenes with exact ground truth: analytic primitives, textures and a ray caster.

In: a scene name (or primitives) and cameras -- pinhole, or any rays (origins, directions).
Out: :class:`~ibr.base.View` renders whose depth is exact at every pixel center, so warps can be
scored against the truth. :mod:`~ibr.synth.scene` (ray caster, shading),
:mod:`~ibr.synth.primitives`, :mod:`~ibr.synth.textures`, :mod:`~ibr.synth.scenes` (the named
scenes and their camera pairs), :mod:`~ibr.synth.paths` (camera paths: key frames and
exact in-between frames of a sequence). Imports only :mod:`ibr.base`.
"""

from __future__ import annotations

from .._lazy import lazy_exports

_EXPORTS = {
    "Hit": "scene",
    "Scene": "scene",
    "render": "scene",
    "render_rays": "scene",
    "Box": "primitives",
    "Rect": "primitives",
    "Sphere": "primitives",
    "rotation": "primitives",
    "ImageTexture": "textures",
    "TEXTURE_NAMES": "textures",
    "checker_texture": "textures",
    "image_texture": "textures",
    "SCENES": "scenes",
    "make_scene": "scenes",
    "scene_cameras": "scenes",
    "staircase": "scenes",
    "SyntheticSequence": "paths",
    "camera_path": "paths",
    "path_frame_cameras": "paths",
    "render_path": "paths",
    "synthetic_sequence": "paths",
}

__getattr__, __dir__, __all__ = lazy_exports(__name__, _EXPORTS)
