"""panorama.photo: photos without depth -> equirect photospheres (seed 001, section 7.5).

In: overlapping photos taken from one spot (arrays; any sizes), optionally masks, known focal
lengths or known cameras. Out: an equirect of a chosen width placed in longitude/latitude by the
project's conventions (:mod:`panorama.directions`) with a coverage mask, the estimated cameras
as :class:`ibr.Camera` objects and a report naming every photo that was dropped and why.

* :func:`stitch_photos` -- the whole pipeline on OpenCV's ``cv2.detail`` parts
  (:mod:`.features`, :mod:`.estimate`, :mod:`.compose`, :mod:`.report`).
* :func:`compose_equirect` -- the known-pose path: exact float-map re-projection, OpenCV exposure
  compensation, seams and multi-band blending; takes per-photo masks.
* :mod:`.testdata` -- photo sets cut out of an equirect at known rotations (exact truth).
"""

from .compose import Composite, compose_equirect
from .report import DROP_REASONS, ImageReport, StitchReport
from .stitch import StitchResult, coverage_extent, native_width, stitch_photos

__all__ = ["DROP_REASONS", "Composite", "ImageReport", "StitchReport", "StitchResult", "compose_equirect",
           "coverage_extent", "native_width", "stitch_photos"]
