"""Scores of a rendered sequence: PSNR against exact frames, and temporal stability (flicker).

**Flicker** is the mean absolute change between consecutive output frames over the pixels where
nothing should change (*static regions*): ``F_k = mean over static p of |c_k(p) - c_(k-1)(p)|``
(colors in [0, 1], mean over channels), and the sequence's figure is the mean of ``F_k`` over all
consecutive pairs. A perfect renderer scores the flicker of the true video (zero when the static
mask is exact); hole fills that change from frame to frame add to it. Two ways to find static
pixels:

* :func:`static_masks_from_truth`: pixels whose ground-truth color changes by at most ``tol``
  (the definition, usable when exact frames exist: synthetic sequences);
* :func:`static_masks_from_motion`: pixels whose surface point (the frame's depth, its camera)
  projects into the previous frame's camera less than ``max_px`` pixels away (a static scene seen
  by a camera that barely moves there; usable on any sequence with depth).

Pixel convention: (u, v) = (column, row), centers at integer coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from ..base.camera import Camera
from ..base.validate import check_finite_scalar, check_image, check_positive

__all__ = [
    "FlickerReport",
    "as_unit_float",
    "frame_change",
    "flicker",
    "psnr",
    "summarize_flicker",
    "static_mask_from_motion",
    "static_mask_from_truth",
    "static_masks_from_motion",
    "static_masks_from_truth",
]


#: Colour dtypes the scores accept (any other integer type has no known white level).
UNIT_DTYPES = ("uint8", "uint16", "float16", "float32", "float64")


def as_unit_float(color, name: str = "color") -> np.ndarray:
    """Color as float32 in [0, 1] (uint8 / 255, uint16 / 65535, floats as they are), (H, W, C).

    Other dtypes (int32, int64, bool ...) are refused naming ``name``: their raw codes are not
    [0, 1] colours (an int64 0..255 image scored -48 dB against itself plus 255)."""
    c = check_image(name, np.asarray(color))
    if c.dtype.name not in UNIT_DTYPES:
        raise TypeError(f"{name}: expected a colour dtype {', '.join(UNIT_DTYPES)}, got {c.dtype}")
    if c.dtype == np.uint8:
        c = c.astype(np.float32) / 255
    elif c.dtype == np.uint16:
        c = c.astype(np.float32) / 65535
    else:
        c = c.astype(np.float32, copy=False)
    return c[..., None] if c.ndim == 2 else c


def psnr(color, truth) -> float:
    """PSNR in dB of ``color`` against ``truth`` over all pixels (peak 1 after :func:`as_unit_float`)."""
    a, b = as_unit_float(color, "color"), as_unit_float(truth, "truth")
    if a.shape != b.shape:
        raise ValueError(f"color: shape {a.shape} differs from the truth's {b.shape}")
    mse = float(np.mean((a.astype(np.float64) - b) ** 2))
    return float("inf") if mse == 0 else float(10 * np.log10(1.0 / mse))


@dataclass(frozen=True)
class FlickerReport:
    """Result of :func:`flicker`.

    Attributes
    ----------
    mean : float
        Mean over consecutive pairs of the mean absolute change in static pixels ([0, 1] color
        units; multiply by 255 for 8-bit levels). NaN when no pixel is static.
    per_pair : tuple of float
        ``F_k`` for k = 1 .. n - 1 (NaN where the pair has no static pixel).
    static_fraction : float
        Mean share of pixels counted as static.
    """

    mean: float
    per_pair: tuple
    static_fraction: float


def frame_change(previous, current, static) -> float:
    """``F_k``: mean absolute change from ``previous`` to ``current`` over the ``static`` pixels
    ([0, 1] color units, mean over channels); NaN when no pixel is static."""
    a, b = as_unit_float(previous, "previous"), as_unit_float(current, "current")
    m = np.asarray(static)
    if m.dtype != np.bool_:  # 0.2 or 2 would silently count as static
        raise TypeError(f"static: expected a boolean mask, got dtype {m.dtype}")
    if a.shape != b.shape:
        raise ValueError(f"current: shape {b.shape} differs from previous {a.shape}")
    if m.shape != b.shape[:2]:
        raise ValueError(f"static: expected shape {b.shape[:2]}, got {m.shape}")
    return float(np.abs(b[m] - a[m]).mean()) if m.any() else float("nan")


def summarize_flicker(per_pair, static_fractions) -> FlickerReport:
    """:class:`FlickerReport` from per-pair changes (NaN = no static pixel) and static shares."""
    arr = np.array(list(per_pair), float)
    mean = float(np.nanmean(arr)) if np.isfinite(arr).any() else float("nan")
    shares = list(static_fractions)
    return FlickerReport(mean, tuple(float(v) for v in arr), float(np.mean(shares)) if shares else 0.0)


def flicker(frames: Sequence, static: Sequence) -> FlickerReport:
    """Temporal flicker of a sequence of colors (module docstring).

    Parameters
    ----------
    frames : sequence of (H, W, C) or (H, W) arrays
        Output colors in order (any dtype :func:`as_unit_float` accepts).
    static : sequence of (H, W) bool
        ``static[k - 1]`` marks the static pixels of the pair (frame k - 1, frame k); n - 1 masks.
    """
    frames = list(frames)
    static = list(static)
    if not frames:
        raise ValueError("frames: expected at least one frame, got none")
    if len(static) != len(frames) - 1:
        raise ValueError(f"static: expected {len(frames) - 1} masks (one per consecutive pair), got {len(static)}")
    vals = [frame_change(frames[k - 1], frames[k], static[k - 1]) for k in range(1, len(frames))]
    return summarize_flicker(vals, [float(np.asarray(m, bool).mean()) for m in static])


def static_mask_from_truth(previous, current, *, tol: float = 1.0 / 255) -> np.ndarray:
    """Pixels whose every ground-truth channel changes by at most ``tol`` ([0, 1] units) between
    two consecutive exact frames."""
    tol = check_finite_scalar("tol", tol)
    if tol < 0:
        raise ValueError(f"tol: expected a tolerance >= 0 ([0, 1] colour units), got {tol!r}")
    a, b = as_unit_float(previous, "previous"), as_unit_float(current, "current")
    if a.shape != b.shape:  # (H, W, 3) against (H, W, 1) broadcast silently
        raise ValueError(f"current: shape {b.shape} differs from previous {a.shape}")
    return np.all(np.abs(b - a) <= tol + 1e-7, axis=-1)


def static_masks_from_truth(truth: Sequence, *, tol: float = 1.0 / 255) -> list[np.ndarray]:
    """:func:`static_mask_from_truth` of every consecutive pair of ground-truth colors."""
    truth = list(truth)
    return [static_mask_from_truth(truth[k - 1], truth[k], tol=tol) for k in range(1, len(truth))]


def static_mask_from_motion(depth, camera: Camera, previous_camera: Camera, *, max_px: float = 0.5) -> np.ndarray:
    """Pixels of a frame (``depth`` in ``camera``) whose surface point projects into
    ``previous_camera`` less than ``max_px`` pixels from the same pixel (static scene assumed;
    pixels without depth are not static)."""
    max_px = check_positive("max_px", max_px)  # NaN or <= 0 marked nothing static, silently
    for name, cam in (("camera", camera), ("previous_camera", previous_camera)):
        if not isinstance(cam, Camera):
            raise TypeError(f"{name}: expected an ibr Camera, got {type(cam).__name__}")
    z = np.asarray(depth, np.float64)
    if z.shape != camera.shape:
        raise ValueError(f"depth: expected shape {camera.shape}, got {z.shape}")
    u, v = camera.pixel_grid()
    ok = np.isfinite(z)
    pts = camera.unproject(np.stack([u[ok], v[ok]], -1), z[ok])
    uv, _ = previous_camera.project(pts)
    moved = np.hypot(uv[:, 0] - u[ok], uv[:, 1] - v[ok])
    m = np.zeros(z.shape, bool)
    m[ok] = moved < max_px  # NaN (behind the previous camera) compares False
    return m


def static_masks_from_motion(depths: Sequence, cameras: Sequence[Camera], *, max_px: float = 0.5) -> list[np.ndarray]:
    """:func:`static_mask_from_motion` of every consecutive pair (frame k against camera k - 1)."""
    depths, cameras = list(depths), list(cameras)
    if len(depths) != len(cameras):
        raise ValueError(f"cameras: expected {len(depths)} cameras (one per depth map), got {len(cameras)}")
    return [static_mask_from_motion(depths[k], cameras[k], cameras[k - 1], max_px=max_px)
            for k in range(1, len(depths))]
