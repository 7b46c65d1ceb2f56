"""What happened to every photo: used or dropped, and why (OpenCV drops images silently).

One :class:`ImageReport` per input photo, in input order, and a :class:`StitchReport` holding them
with a fixed-width text table (:meth:`StitchReport.table`) for the command line.

Reasons a photo is dropped (``ImageReport.reason``)
---------------------------------------------------
``duplicate``        its best match maps it onto an earlier photo with the identity (same view);
                     the earlier photo is kept.
``little_overlap``   it matches another photo, but too weakly to be placed (confidence below the
                     threshold, or its only matches disagree with the rest of the panorama).
``no_match``         no photo shares enough consistent features with it: another scene, or no
                     overlap at all.
``separate_group``   it matches other photos, but their group is not connected to the largest
                     group (two panoramas were mixed).
``no_features``      too few features were found in it (blank, blurred, too small; fewer than
                     ``stitch.MIN_FEATURES``); it is left out before matching.
``failed``           the camera estimate for it failed (bundle adjustment diverged).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["DROP_REASONS", "ImageReport", "StitchReport"]

DROP_REASONS = ("duplicate", "little_overlap", "no_match", "separate_group", "no_features", "failed")


@dataclass
class ImageReport:
    """Fate of one input photo.

    Attributes
    ----------
    index : int
        Position in the input list.
    name : str
        File name or ``"image <index>"``.
    used : bool
        True if the photo is part of the stitched panorama.
    reason : str
        ``""`` when used, else one of :data:`DROP_REASONS`.
    detail : str
        Human-readable numbers behind the decision (best partner, inliers, confidence).
    features : int
        Number of features found (at the registration resolution).
    focal_px : float
        Estimated focal length in pixels of the full-resolution photo (NaN if dropped).
    yaw_deg, pitch_deg, roll_deg : float
        Estimated orientation in the panorama's frame (``panorama.world_from_view`` convention:
        yaw = longitude of the optical axis, pitch = its latitude, roll clockwise); NaN if dropped.
    gain : float
        Exposure gain applied to the photo (1 = unchanged; NaN if dropped).
    """

    index: int
    name: str
    used: bool = False
    reason: str = ""
    detail: str = ""
    features: int = 0
    focal_px: float = float("nan")
    yaw_deg: float = float("nan")
    pitch_deg: float = float("nan")
    roll_deg: float = float("nan")
    gain: float = float("nan")

    def drop(self, reason: str, detail: str) -> None:
        """Mark the photo as dropped for ``reason`` (one of :data:`DROP_REASONS`)."""
        if reason not in DROP_REASONS:
            raise ValueError(f"reason: expected one of {', '.join(DROP_REASONS)}, got {reason!r}")
        self.used, self.reason, self.detail = False, reason, detail


@dataclass
class StitchReport:
    """Every photo's fate plus the panorama-wide numbers.

    Attributes
    ----------
    images : list of ImageReport
        One per input photo, in input order.
    covered_fraction : float
        Fraction of the output equirect's pixels covered by at least one photo.
    lon_range_deg, lat_range_deg : (float, float)
        Longitude and latitude extent of the covered part (degrees; longitude may wrap, then
        ``lon_range_deg = (-180, 180)``).
    seconds : dict
        Wall time per stage (features, matching, cameras, compositing).
    notes : list of str
        Pairs rejected as inconsistent, the reference photo and other decisions.
    """

    images: list[ImageReport] = field(default_factory=list)
    covered_fraction: float = float("nan")
    lon_range_deg: tuple[float, float] = (float("nan"), float("nan"))
    lat_range_deg: tuple[float, float] = (float("nan"), float("nan"))
    seconds: dict = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    @property
    def used(self) -> list[int]:
        """Indices of the photos in the panorama."""
        return [r.index for r in self.images if r.used]

    @property
    def dropped(self) -> dict[int, str]:
        """``{index: reason}`` of the photos left out."""
        return {r.index: r.reason for r in self.images if not r.used}

    def table(self) -> str:
        """Fixed-width text table: one row per photo, then the coverage line."""
        rows = [("#", "photo", "status", "feat", "focal", "yaw", "pitch", "roll", "gain", "detail")]
        for r in self.images:
            def num(x, fmt):
                return "-" if not np.isfinite(x) else format(x, fmt)
            rows.append((str(r.index), r.name, "used" if r.used else f"DROPPED ({r.reason})",
                         str(r.features), num(r.focal_px, ".1f"), num(r.yaw_deg, ".2f"),
                         num(r.pitch_deg, ".2f"), num(r.roll_deg, ".2f"), num(r.gain, ".3f"), r.detail))
        widths = [max(len(row[k]) for row in rows) for k in range(len(rows[0]) - 1)]
        lines = ["  ".join(c.ljust(w) for c, w in zip(row[:-1], widths)) + "  " + row[-1] for row in rows]
        n_used = len(self.used)
        if np.isfinite(self.covered_fraction):
            lines.append(f"{n_used} of {len(self.images)} photos used; covered {100 * self.covered_fraction:.1f}% "
                         f"of the sphere (lon {self.lon_range_deg[0]:.1f}..{self.lon_range_deg[1]:.1f} deg, "
                         f"lat {self.lat_range_deg[0]:.1f}..{self.lat_range_deg[1]:.1f} deg)")
        else:
            lines.append(f"{n_used} of {len(self.images)} photos placed; no panorama")
        lines += [f"note: {n}" for n in self.notes]
        return "\n".join(line.rstrip() for line in lines)
