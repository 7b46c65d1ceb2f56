"""Stage: the virtual canvas (seed 004) -- images, video and drawings on planes in the scene.

In: world rectangles (centre, normal, up, size in scene units) carrying an RGBA buffer
(:class:`Canvas`), content for them (an image resampled once, video frames from
``cv2.VideoCapture``, anti-aliased strokes), target cameras with the scene's depth. Out: canvas
pixels picked from screen pixels (:func:`pick_pixel`: ray, nearest canvas in front of the scene),
and renderings with the canvases composited in (:func:`composite`: one homography per canvas for
pinhole targets, alpha blending, occlusion by the scene depth). :mod:`~ibr.canvas.plane` (the
canvas and its exact world <-> pixel mapping), :mod:`~ibr.canvas.resample` (images, the seed's
power-of-two texture with corrected scale factors), :mod:`~ibr.canvas.video`,
:mod:`~ibr.canvas.strokes`, :mod:`~ibr.canvas.pick`, :mod:`~ibr.canvas.compositor` (+ its numba
kernel). Panorama targets (equirect, cubemap) are in :mod:`panorama.canvas`. Imports
:mod:`ibr.base`, :mod:`ibr.mesh` and :mod:`ibr.render`.
"""

from __future__ import annotations

from .._lazy import lazy_exports

_EXPORTS = {
    "Canvas": "plane",
    "canvas_from_image": "resample",
    "set_image": "resample",
    "power_of_two_size": "resample",
    "texture_scale": "resample",
    "VideoSource": "video",
    "frame_schedule": "video",
    "draw_stroke": "strokes",
    "stroke_from_screen": "strokes",
    "parse_color": "strokes",
    "Pick": "pick",
    "pick_pixel": "pick",
    "pick_pixels": "pick",
    "pick_ray": "pick",
    "pick_rays": "pick",
    "camera_rays": "pick",
    "composite": "compositor",
    "composite_into": "compositor",
    "composite_rays_into": "compositor",
}

__getattr__, __dir__, __all__ = lazy_exports(__name__, _EXPORTS)
