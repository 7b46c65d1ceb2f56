"""Stage 3, views for two eyes and head-mounted displays.

In: a :class:`~ibr.base.View` (or a color frame, its z-buffer and its OpenGL projection). Out: left
and right eye images (packed side-by-side, top-bottom, anaglyph ...), lens pre-distorted frames,
time-warped frames. :mod:`~ibr.stereo.stereo_camera` is seed 000's off-axis stereo camera and
comfort limits, :mod:`~ibr.stereo.pair` seed 003's pair synthesis, :mod:`~ibr.stereo.lens` seed
001's radial distortion and :mod:`~ibr.stereo.timewarp` its post-rendering warp. Imports
:mod:`ibr.base`, :mod:`ibr.mesh` and :mod:`ibr.render`.
"""

from __future__ import annotations

from .._lazy import lazy_exports

_EXPORTS = {
    "ComfortReport": "stereo_camera",
    "StereoCamera": "stereo_camera",
    "auto_stereo": "stereo_camera",
    "comfort": "stereo_camera",
    "interaxial_for_parallax": "stereo_camera",
    "max_interaxial": "stereo_camera",
    "max_interaxial_for_range": "stereo_camera",
    "parallax_angle_deg": "stereo_camera",
    "parallax_px": "stereo_camera",
    "parallax_scene": "stereo_camera",
    "stereo_pair": "pair",
    "stereo_pair_from_zbuffer": "pair",
    "pack_stereo": "pair",
    "anaglyph": "pair",
    "dubois_anaglyph": "pair",
    "stereo_cameras": "pair",
    "RadialDistortion": "lens",
    "distortion_maps": "lens",
    "fit_radial": "lens",
    "predistort": "lens",
    "predistort_stereo": "lens",
    "TimewarpFrame": "timewarp",
    "UpconvertResult": "timewarp",
    "guard_band_camera": "timewarp",
    "rotation_homography": "timewarp",
    "upconvert": "timewarp",
    "warp_rotation": "timewarp",
}

__getattr__, __dir__, __all__ = lazy_exports(__name__, _EXPORTS)
