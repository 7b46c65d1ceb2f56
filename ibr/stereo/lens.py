"""Radial lens distortion of a head-mounted display: model, exact inverse, pre-distortion (seed 001 7.3).

Model (seed 001 eq. 7.16): a point at undistorted normalized radius ``r_u`` appears at
``r_d = f(r_u) = r_u + c1 r_u^3 + c2 r_u^5`` (c1 > 0 pincushion, c1 < 0 barrel). The "k1/k2"
form ``r_d = r_u (1 + k1 r_u^2 + k2 r_u^4)`` of OpenCV/Brown is the same polynomial; it differs only
in the radius unit (OpenCV normalizes by the focal length in pixels), see
:meth:`RadialDistortion.from_k1k2`.

Inverse ``r_u = f^-1(r_d)``:

* exact, by safeguarded Newton iteration (bracketed by bisection; converges to ~1e-15);
* by a lookup table of the exact inverse with linear interpolation (seed: "computed offline and
  stored in an array");
* by the closed-form approximation of seed eq. 7.17, which prints only the correction ratio N/D;
  the usable approximation is ``r_u ~ r_d (1 - N/D)`` with
  ``N = c1 r^2 + c2 r^4 + c1^2 r^4 + c2^2 r^8 + 2 c1 c2 r^6``, ``D = 1 + 4 c1 r^2 + 6 c2 r^4``,
  ``r = r_d`` (DESIGN.md section 3). Its error grows quickly with the radius.

Normalized radius and pixel convention
--------------------------------------
Image maps normalize pixel offsets from the lens center isotropically: ``r = |(u, v) - c| / s``
with the lens center ``c`` in pixels (pixel centers at integers, so the center of a 512-wide
image is u = 255.5) and the scale ``s`` in pixels (default: half the image width, so that the
seed's canonical x in [-1, 1] spans the eye image horizontally). Example: W = H = 512, default
c = (255.5, 255.5), s = 256: pixel (511, 255.5) has r = 255.5 / 256 = 0.998.

Pre-distortion: the lens shows a display pixel at radius r at the perceived radius f(r), so the
display image must show the rendered image's content from radius f(r): output pixel at r samples
the input at f(r) (``cv2.remap``). This is "applying f^-1 to the image": content at radius rho
moves to f^-1(rho). ``inverse=True`` undoes it (samples at f^-1(r)), i.e. simulates the lens.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Sequence

import cv2
import numpy as np

from ..base.validate import (check_array, check_choice, check_color, check_finite_scalar, check_flag, check_image,
                             check_number, check_positive)

__all__ = [
    "RadialDistortion",
    "distortion_maps",
    "fit_radial",
    "predistort",
    "predistort_stereo",
]

INVERSE_METHODS = ("newton", "lut", "approx")


#: Largest lens range r_max (normalized radius, tan of the half field angle: 89.94 deg).
MAX_R = 1000.0


@dataclass(frozen=True)
class RadialDistortion:
    """Radial model ``r_d = r_u + c1 r_u^3 + c2 r_u^5`` valid for ``0 <= r_u <= r_max``.

    The model must be strictly increasing on [0, r_max] (so that it has an inverse); the
    constructor checks ``f'(r) = 1 + 3 c1 r^2 + 5 c2 r^4 > 0`` there and raises otherwise.
    """

    c1: float
    c2: float = 0.0
    r_max: float = 1.5

    def __post_init__(self):
        object.__setattr__(self, "c1", check_finite_scalar("c1", self.c1))
        object.__setattr__(self, "c2", check_finite_scalar("c2", self.c2))
        # a normalized radius (tan of the half field angle): 1000 is 89.94 deg; r_max^2 overflowed at 1e200
        object.__setattr__(self, "r_max", float(check_number("r_max", self.r_max, minimum=0, exclusive_minimum=True,
                                                             maximum=MAX_R)))
        s = np.linspace(0, self.r_max**2, 4097)
        d = 1 + 3 * self.c1 * s + 5 * self.c2 * s**2
        # the quadratic in s = r^2 has its extremum at s* = -3 c1 / (10 c2)
        if self.c2 != 0:
            s_star = -3 * self.c1 / (10 * self.c2)
            if 0 <= s_star <= self.r_max**2:
                d = np.append(d, 1 + 3 * self.c1 * s_star + 5 * self.c2 * s_star**2)
        if np.min(d) <= 0:
            raise ValueError(
                f"c1, c2: the model r + c1 r^3 + c2 r^5 with c1={self.c1}, c2={self.c2} is not "
                f"increasing on [0, r_max={self.r_max}] (no inverse); reduce r_max or the coefficients"
            )

    # ------------------------------------------------------------------ forms
    @classmethod
    def from_k1k2(cls, k1: float, k2: float = 0.0, *, focal_px: float, scale_px: float,
                  r_max: float = 1.5) -> "RadialDistortion":
        """Convert OpenCV/Brown ``x_d = x_u (1 + k1 r^2 + k2 r^4)`` in focal-length units.

        With ``r_cv = r * scale_px / focal_px`` the model in this module's radius unit has
        ``c1 = k1 (scale_px/focal_px)^2`` and ``c2 = k2 (scale_px/focal_px)^4``.
        """
        a = check_positive("scale_px", scale_px) / check_positive("focal_px", focal_px)
        return cls(check_finite_scalar("k1", k1) * a**2, check_finite_scalar("k2", k2) * a**4, r_max)

    def to_k1k2(self, *, focal_px: float, scale_px: float) -> tuple[float, float]:
        """Inverse of :meth:`from_k1k2`."""
        a = check_positive("scale_px", scale_px) / check_positive("focal_px", focal_px)
        return self.c1 / a**2, self.c2 / a**4

    @property
    def rd_max(self) -> float:
        """Largest distorted radius covered: f(r_max)."""
        return float(self.distort(self.r_max))

    # ------------------------------------------------------------------ model
    def distort(self, r_u) -> np.ndarray:
        """Eq. 7.16: ``r_d = r_u + c1 r_u^3 + c2 r_u^5`` (float64)."""
        r = np.asarray(r_u, dtype=np.float64)
        r2 = r * r
        return r * (1 + r2 * (self.c1 + self.c2 * r2))

    def derivative(self, r_u) -> np.ndarray:
        """``f'(r) = 1 + 3 c1 r^2 + 5 c2 r^4``."""
        r2 = np.asarray(r_u, dtype=np.float64) ** 2
        return 1 + r2 * (3 * self.c1 + 5 * self.c2 * r2)

    def undistort(self, r_d, *, method: str = "newton", lut_size: int = 1024) -> np.ndarray:
        """Inverse ``r_u = f^-1(r_d)``; NaN for r_d outside [0, f(r_max)].

        ``method``: ``"newton"`` (exact to ~1e-15), ``"lut"`` (table of ``lut_size`` exact samples
        over [0, f(r_max)], linear interpolation), ``"approx"`` (seed eq. 7.17 as
        ``r_d (1 - N/D)``, no range limit other than D != 0).
        """
        check_choice("method", method, INVERSE_METHODS)
        rd = np.asarray(r_d, dtype=np.float64)
        if method == "approx":
            return self.undistort_approx(rd)
        ok = (rd >= 0) & (rd <= self.rd_max * (1 + 1e-12))
        if method == "lut":
            xs, ys = self.inverse_lut(lut_size)
            return np.where(ok, np.interp(rd, xs, ys), np.nan)
        return np.where(ok, self._newton(np.where(ok, rd, 0.0)), np.nan)

    def _newton(self, rd: np.ndarray) -> np.ndarray:
        """Safeguarded Newton on [0, r_max] for f(r) = rd (vectorized)."""
        lo = np.zeros_like(rd)
        hi = np.full_like(rd, self.r_max)
        r = np.clip(rd, 0, self.r_max)  # seed: start from f with the axes swapped, r0 = r_d
        for _ in range(100):
            g = self.distort(r) - rd
            lo = np.where(g < 0, r, lo)
            hi = np.where(g > 0, r, hi)
            step = g / self.derivative(r)
            r_new = r - step
            bad = ~((r_new > lo) & (r_new < hi))
            r_new = np.where(bad, 0.5 * (lo + hi), r_new)
            done = np.all(np.abs(r_new - r) <= 1e-15 * np.maximum(1.0, np.abs(r)))
            r = r_new
            if done:
                break
        return r

    def inverse_lut(self, size: int = 1024) -> tuple[np.ndarray, np.ndarray]:
        """``(r_d samples, r_u samples)``: ``size`` uniform r_d in [0, f(r_max)] and their exact
        inverses (Newton); interpolate linearly with ``np.interp``."""
        if int(size) != size or size < 2:
            raise ValueError(f"size: expected an integer >= 2, got {size!r}")
        xs = np.linspace(0.0, self.rd_max, int(size))
        return xs, self._newton(xs)

    def undistort_approx(self, r_d) -> np.ndarray:
        """Seed eq. 7.17 completed: ``r_u ~ r_d (1 - N/D)`` (see module docstring)."""
        r = np.asarray(r_d, dtype=np.float64)
        c1, c2 = self.c1, self.c2
        r2 = r * r
        n = c1 * r2 + c2 * r2**2 + c1**2 * r2**2 + c2**2 * r2**4 + 2 * c1 * c2 * r2**3
        d = 1 + 4 * c1 * r2 + 6 * c2 * r2**2
        return r * (1 - n / d)


def fit_radial(r_u, r_d, *, r_max: float | None = None) -> RadialDistortion:
    """Least-squares c1, c2 from measured radius pairs (seed 001 7.3, first stage).

    ``r_d - r_u = c1 r_u^3 + c2 r_u^5`` is linear in (c1, c2). ``r_u``, ``r_d`` are 1-D arrays of
    normalized radii (or (N, 2) arrays of points relative to the lens center, whose norms are
    used). ``r_max`` defaults to the largest measured r_u.
    """
    ru = check_array("r_u", r_u, ndim=(1, 2), dtype_kind="fiu").astype(np.float64)
    rd = check_array("r_d", r_d, ndim=(1, 2), dtype_kind="fiu").astype(np.float64)
    if ru.shape != rd.shape:
        raise ValueError(f"r_d: expected the shape of r_u {ru.shape}, got {rd.shape}")
    if ru.ndim == 2:
        if ru.shape[1] != 2:
            raise ValueError(f"r_u: expected shape (N,) or (N, 2), got {ru.shape}")
        ru, rd = np.linalg.norm(ru, axis=1), np.linalg.norm(rd, axis=1)
    ok = np.isfinite(ru) & np.isfinite(rd)
    if ok.sum() < 2 or np.count_nonzero(ru[ok] > 0) < 2:
        raise ValueError("r_u: need at least two finite, non-zero radius pairs to fit c1, c2")
    a = np.stack([ru[ok] ** 3, ru[ok] ** 5], 1)
    (c1, c2), *_ = np.linalg.lstsq(a, rd[ok] - ru[ok], rcond=None)
    return RadialDistortion(float(c1), float(c2), float(r_max if r_max is not None else ru[ok].max()))


# ---------------------------------------------------------------------- images
def _lenses(lens) -> tuple[RadialDistortion, ...]:
    if isinstance(lens, RadialDistortion):
        return (lens,)
    if isinstance(lens, Sequence) and len(lens) == 3 and all(isinstance(x, RadialDistortion) for x in lens):
        return tuple(lens)
    raise TypeError("lens: expected a RadialDistortion or a sequence of three (per R, G, B channel "
                    f"for chromatic aberration), got {type(lens).__name__}")


def _check_center(center_px, width: int, height: int, name: str = "center_px") -> tuple[float, float]:
    """The lens centre as floats, inside the image span [-0.5, W - 0.5] x [-0.5, H - 0.5] (#12:
    a centre far outside gives an all-black picture); errors name ``name``."""
    c = check_array(name, center_px, shape=(2,), dtype_kind="fiu").astype(np.float64)
    u, v = float(c[0]), float(c[1])
    if not (np.isfinite(c).all() and -0.5 <= u <= width - 0.5 and -0.5 <= v <= height - 0.5):
        raise ValueError(f"{name}: expected a lens centre inside the image, u in [-0.5, {width - 0.5:g}] and "
                         f"v in [-0.5, {height - 0.5:g}] (pixel centres at integers), got ({u:g}, {v:g})")
    return u, v


def distortion_maps(width: int, height: int, lens: RadialDistortion, *, center_px=None,
                    scale_px: float | None = None, inverse: bool = False,
                    method: str = "newton") -> tuple[np.ndarray, np.ndarray]:
    """Cached, read-only sampling maps; see :func:`_distortion_maps` (same arguments)."""
    if not isinstance(lens, RadialDistortion):
        raise TypeError(f"lens: expected a RadialDistortion, got {type(lens).__name__}")
    width = check_number("width", width, integer=True, minimum=1)
    height = check_number("height", height, integer=True, minimum=1)
    check_flag("inverse", inverse)  # checked always, not only where it is used
    check_choice("method", method, INVERSE_METHODS)
    center = None if center_px is None else _check_center(center_px, int(width), int(height))
    scale = None if scale_px is None else check_positive("scale_px", scale_px)
    return _cached_maps(int(width), int(height), lens, center, scale, bool(inverse), method)


@lru_cache(maxsize=16)
def _cached_maps(width, height, lens, center, scale, inverse, method):
    mx, my = _distortion_maps(width, height, lens, center_px=center, scale_px=scale,
                              inverse=inverse, method=method)
    mx.setflags(write=False)
    my.setflags(write=False)
    return mx, my


def _distortion_maps(width: int, height: int, lens: RadialDistortion, *, center_px=None,
                     scale_px: float | None = None, inverse: bool = False,
                     method: str = "newton") -> tuple[np.ndarray, np.ndarray]:
    """Sampling maps ``(map_x, map_y)`` (H, W) float32 for ``cv2.remap``.

    Output pixel (u, v) at normalized radius r from ``center_px`` samples the input at radius
    f(r) (pre-distortion) or f^-1(r) (``inverse=True``, by ``method``), same direction. Pixel
    centers at integers; default center ((W-1)/2, (H-1)/2), default ``scale_px = W/2``. Pixels
    whose source radius is outside the lens range map to -1e6 (border value).
    """
    if not isinstance(lens, RadialDistortion):
        raise TypeError(f"lens: expected a RadialDistortion, got {type(lens).__name__}")
    w, h = int(width), int(height)
    if w < 1 or h < 1:
        raise ValueError(f"width, height: expected positive sizes, got {width}x{height}")
    cx, cy = ((w - 1) / 2, (h - 1) / 2) if center_px is None else (
        check_finite_scalar("center_px[0]", center_px[0]), check_finite_scalar("center_px[1]", center_px[1]))
    s = w / 2 if scale_px is None else check_positive("scale_px", scale_px)
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    dx, dy = (u - cx) / s, (v - cy) / s
    r = np.hypot(dx, dy)
    if inverse:
        r_src = lens.undistort(r, method=method)
    else:
        r_src = np.where(r <= lens.r_max, lens.distort(r), np.nan)
    with np.errstate(invalid="ignore", divide="ignore"):
        ratio = np.where(r > 0, r_src / r, 1.0)  # r -> 0: f(r)/r -> 1
    ratio = np.where(np.isfinite(r_src), ratio, np.nan)
    mx = cx + dx * ratio * s
    my = cy + dy * ratio * s
    bad = ~np.isfinite(mx)
    mx[bad] = -1e6
    my[bad] = -1e6
    return mx.astype(np.float32), my.astype(np.float32)


def _remap(img: np.ndarray, mx, my) -> np.ndarray:
    out = cv2.remap(img, mx, my, interpolation=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
    return out[..., None] if img.ndim == 3 and out.ndim == 2 else out  # OpenCV drops a single channel axis


def predistort(image, lens, *, center_px=None, scale_px: float | None = None,
               inverse: bool = False, method: str = "newton") -> np.ndarray:
    """Pre-distort (or with ``inverse=True`` undo the pre-distortion of) one eye image.

    ``lens`` is one :class:`RadialDistortion` or three (R, G, B) for chromatic aberration: each
    channel is remapped with its own coefficients so that after the lens the colors line up
    (an alpha channel follows the green lens).
    Outside the lens range the output is 0 (black). Keeps the dtype; see :func:`distortion_maps`
    for the pixel convention.
    """
    img = check_color("image", image, channels=None)  # cv2.remap has no kernel for other dtypes (#12)
    lenses = _lenses(lens)
    h, w = img.shape[:2]
    if len(lenses) == 1:
        mx, my = distortion_maps(w, h, lenses[0], center_px=center_px, scale_px=scale_px,
                                 inverse=inverse, method=method)
        return _remap(img, mx, my)
    if img.ndim != 3 or img.shape[2] < 3:
        raise ValueError(f"image: per-channel lenses need an (H, W, 3) image, got shape {img.shape}")
    out = np.empty_like(img)
    green = None
    for c, ln in enumerate(lenses):
        mx, my = distortion_maps(w, h, ln, center_px=center_px, scale_px=scale_px,
                                 inverse=inverse, method=method)
        out[..., c] = _remap(np.ascontiguousarray(img[..., c]), mx, my)
        if c == 1:
            green = mx, my
    if img.shape[2] > 3:  # alpha (and any further channel) moves with the green, reference lens
        extra = _remap(np.ascontiguousarray(img[..., 3:]), *green)
        out[..., 3:] = extra.reshape(h, w, -1)
    return out


def predistort_stereo(left, right, lens, *, centers_px=None, scale_px: float | None = None,
                      inverse: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Pre-distort a stereo pair for a head-mounted display with per-eye lens centers.

    ``centers_px = ((u_left, v_left), (u_right, v_right))`` are the lens centers in each eye
    image's own pixel coordinates (e.g. from the headset's lens separation vs. its screen
    width: a lens separation smaller than half the panel moves the left center right of the eye
    image's center and the right center left of it). Default: each image's center.
    """
    l_img = check_image("left", left)
    r_img = check_image("right", right)
    if l_img.shape != r_img.shape:
        raise ValueError(f"right: expected the left image's shape {l_img.shape}, got {r_img.shape}")
    if centers_px is None:
        cl = cr = None
    else:
        c = check_array("centers_px", centers_px, shape=(2, 2), dtype_kind="fiu")
        cl, cr = tuple(c[0]), tuple(c[1])
    return (predistort(l_img, lens, center_px=cl, scale_px=scale_px, inverse=inverse),
            predistort(r_img, lens, center_px=cr, scale_px=scale_px, inverse=inverse))
