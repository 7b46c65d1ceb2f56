"""Depth encodings and their exact conversions to planar z.

Inside the engine depth is **planar z**: the coordinate along the optical axis (camera +z) in
scene units, float32, NaN where there is no depth. Every other encoding is converted at the edge
by the functions here. Each ``z_from_*`` function returns NaN for invalid input (NaN, inf,
zero or negative depth, values outside the encoding's range); :func:`valid_mask` gives the mask.

Encodings (n, f = near and far plane distances, planar)
-------------------------------------------------------
range          r = z * |ray|, ``|ray| = sqrt(1 + ((u - cx)/fx)^2 + ((v - cy)/fy)^2)``
disparity      d = B * fx / z - doffs  <=>  z = B * fx / (d + doffs)   (Middlebury, pixels)
window z       w = f / (f - n) * (1 - n / z), in [0, 1] (OpenGL with glDepthRange(0, 1), D3D)
               exact inverse z = n * f / (f - w * (f - n))   (DESIGN.md: seed 003's printed
               inverse Z'(f - n)/f + n is wrong)
fixed point    q = round(w * (2^bits - 1)), bits in {16, 24, 32}; seed 002 eq. 2 uses the scale
               2^24 * w (see :func:`zprime_from_z`).
reversed z     w_rev = 1 - w (finite far), or n / z (infinite far plane)

Quantization step of a fixed-point buffer at depth z (one code step):
``dz = z^2 * (f - n) / (n * f * (2^bits - 1))`` to first order; see :func:`zbuffer_step`.

Quantization of every encoding (:class:`DepthQuantization`)
------------------------------------------------------------
Stored depth is often quantized: integer disparities (8-bit maps), millimetre codes (16-bit
sensor PNGs), the codes of a 16/24-bit z-buffer. In inverse depth q = 1/z every one of them has a
step of the form ``dq(q) = c0 + c2 q^2``:

* disparity with step s (pixels): q = (d + doffs) / (B f)  ->  ``c0 = s / (B f)``
* window / fixed-point z-buffer codes (bits b): q = (1 - w (f - n) / f) / n  ->
  ``c0 = (f - n) / (n f (2^b - 1))``
* planar z (or range) stored in codes of ``scale`` scene units: dz = scale  ->  ``c2 = scale``
  (dq = dz / z^2 to first order; range codes are at most this coarse in z)

:func:`zbuffer_step`, :func:`disparity_step` and :func:`code_step` give the step in z.
"""

from __future__ import annotations

import numpy as np

from .validate import check_array, check_finite_scalar, check_near_far as _near_far, check_positive

__all__ = [
    "DepthQuantization",
    "code_step",
    "depth_steps",
    "disparity_step",
    "quantization_of",
    "set_quantization",
    "disparity_from_z",
    "fixed_from_z",
    "range_from_z",
    "sanitize_depth",
    "valid_mask",
    "window_from_z",
    "reversed_from_z",
    "z_from_disparity",
    "z_from_fixed",
    "z_from_range",
    "z_from_reversed",
    "z_from_window",
    "z_from_zprime",
    "zbuffer_step",
    "zprime_from_z",
    "ZPRIME_SCALE",
]

#: Scale of the seed 002 nonlinear depth z' (eq. 2): z' = 2^24 * w.
ZPRIME_SCALE = float(2**24)


def _float(name: str, a) -> np.ndarray:
    return check_array(name, a, dtype_kind="fiub").astype(np.float64)


def valid_mask(z) -> np.ndarray:
    """Boolean mask of usable planar depth: finite and > 0."""
    z = np.asarray(z)
    with np.errstate(invalid="ignore"):
        return np.isfinite(z) & (z > 0)


def depth_steps(inv_depth, rel: float) -> np.ndarray:
    """(H, W) bool: both pixels of every pair of 4-neighbours across a depth discontinuity.

    Parameters
    ----------
    inv_depth : (H, W) array
        Inverse depth 1/z; NaN, infinite, 0 or negative where there is no depth.
    rel : float
        A step: the two inverse depths differ by more than ``rel`` times the larger (the
        nearer surface's), or one pixel has depth and the other has none. Two pixels without
        depth are no step.
    """
    q = np.asarray(inv_depth)
    if q.ndim != 2 or q.dtype.kind not in "fiu":
        raise ValueError(f"inv_depth: expected an (H, W) array of numbers, got {q.dtype} {q.shape}")
    if not (isinstance(rel, (int, float, np.floating)) and np.isfinite(rel) and rel > 0):
        raise ValueError(f"rel: expected a positive finite number, got {rel!r}")
    with np.errstate(invalid="ignore"):
        valid = np.isfinite(q) & (q > 0)
    out = np.zeros(q.shape, bool)
    for axis in (0, 1):
        head = (slice(None, -1), slice(None)) if axis == 0 else (slice(None), slice(None, -1))
        tail = (slice(1, None), slice(None)) if axis == 0 else (slice(None), slice(1, None))
        a, b, va, vb = q[head], q[tail], valid[head], valid[tail]
        with np.errstate(invalid="ignore"):
            step = (va != vb) | (va & vb & (np.abs(a - b) > rel * np.maximum(a, b)))
        out[head] |= step
        out[tail] |= step
    return out


def _depth32(z) -> np.ndarray:
    """float32 depth (or range) with NaN wherever it is not a finite positive float32: the cast
    turns 1e39 into inf and 1e-46 into 0, which would pass for depth."""
    with np.errstate(over="ignore"):
        out = np.asarray(z, dtype=np.float64).astype(np.float32)
    with np.errstate(invalid="ignore"):
        out[~(np.isfinite(out) & (out > 0))] = np.nan
    return out


def sanitize_depth(z, *, near: float | None = None, far: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Planar depth as float32 with every invalid value set to NaN, plus the validity mask.

    Invalid: NaN, +-inf, z <= 0, and (when given) z < near or z > far.

    Returns
    -------
    z : float32 array, same shape
    valid : bool array
    """
    z64 = _float("z", z)
    valid = valid_mask(z64)
    with np.errstate(invalid="ignore"):
        if near is not None:
            valid &= z64 >= check_positive("near", near)
        if far is not None:
            valid &= z64 <= check_positive("far", far, allow_inf=True)
    out = _depth32(np.where(valid, z64, np.nan))
    return out, valid & np.isfinite(out)  # values the float32 cast overflowed (1e39) or flushed (1e-46)


def _ray_norm(camera, shape) -> np.ndarray:
    if tuple(shape[-2:]) != (camera.height, camera.width):
        raise ValueError(
            f"depth: shape {tuple(shape)} does not match camera size {camera.height}x{camera.width}"
        )
    return np.linalg.norm(camera.rays_cam(), axis=-1)


def range_from_z(z, camera) -> np.ndarray:
    """Range (Euclidean distance from the camera center along the pixel ray) from planar z.

    ``z`` has shape (H, W) matching ``camera``. For a pixel at the principal point range = z;
    at the corner of a 90-degree square camera (|x| = |y| = 1 in normalized coords) range = sqrt(3) z.
    """
    z = _float("z", z)
    z = np.where(valid_mask(z), z, np.nan)
    return _depth32(z * _ray_norm(camera, z.shape))


def z_from_range(r, camera) -> np.ndarray:
    """Planar z from range along the ray; inverse of :func:`range_from_z`. Invalid -> NaN."""
    r = _float("range", r)
    r = np.where(valid_mask(r), r, np.nan)
    return _depth32(r / _ray_norm(camera, r.shape))


def z_from_disparity(d, *, baseline: float, focal_px: float, doffs: float = 0.0) -> np.ndarray:
    """Planar z = baseline * focal_px / (d + doffs) (Middlebury convention).

    ``d`` in pixels; z in the units of ``baseline``. Pixels with d + doffs <= 0 or non-finite d
    become NaN. Example: motorcycle (quarter size) f = 994.978 px, B = 193.001 mm,
    doffs = 31.086: d = 100 gives z = 1464.9 mm.
    """
    d = _float("disparity", d)
    b = check_positive("baseline", baseline)
    f = check_positive("focal_px", focal_px)
    off = check_finite_scalar("doffs", doffs)
    den = d + off
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(np.isfinite(den) & (den > 0), b * f / den, np.nan)
    return _depth32(z)


def disparity_from_z(z, *, baseline: float, focal_px: float, doffs: float = 0.0) -> np.ndarray:
    """Disparity d = baseline * focal_px / z - doffs; inverse of :func:`z_from_disparity`."""
    z = _float("z", z)
    b = check_positive("baseline", baseline)
    f = check_positive("focal_px", focal_px)
    off = check_finite_scalar("doffs", doffs)
    with np.errstate(divide="ignore", invalid="ignore"):
        d = np.where(valid_mask(z), b * f / z - off, np.nan)
    return d.astype(np.float32)


def window_from_z(z, *, near: float, far: float) -> np.ndarray:
    """Window-space depth w = f / (f - n) * (1 - n / z) in [0, 1] (float64).

    w = 0 at the near plane and 1 at the far plane (tends to 1 as z -> inf for far = inf).
    Invalid z -> NaN. Values outside [n, f] are returned unclipped (w < 0 or w > 1).
    """
    n, f = _near_far(near, far)
    z = _float("z", z)
    ratio = 1.0 if np.isinf(f) else f / (f - n)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(valid_mask(z), ratio * (1 - n / z), np.nan)


def z_from_window(w, *, near: float, far: float) -> np.ndarray:
    """Planar z from window depth: z = n f / (f - w (f - n)) (exact inverse; float32).

    w outside [0, 1], NaN or inf -> NaN. w = 1 (the cleared far plane) is the far plane itself;
    use :func:`sanitize_depth` with ``far`` slightly below it to treat cleared pixels as empty.
    For far = inf, z = n / (1 - w) and w = 1 -> NaN.
    """
    n, f = _near_far(near, far)
    w = _float("w", w)
    ok = np.isfinite(w) & (w >= 0) & (w <= 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        if np.isinf(f):
            z = n / (1 - w)
            ok &= w < 1
        else:
            z = n * f / (f - w * (f - n))
    return _depth32(np.where(ok, z, np.nan))


def reversed_from_z(z, *, near: float, far: float) -> np.ndarray:
    """Reversed-z window depth: 1 - w for finite far, n / z for an infinite far plane."""
    n, f = _near_far(near, far)
    if np.isinf(f):
        z = _float("z", z)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(valid_mask(z), n / z, np.nan)
    return 1.0 - window_from_z(z, near=n, far=f)


def z_from_reversed(w_rev, *, near: float, far: float) -> np.ndarray:
    """Planar z from reversed-z depth; inverse of :func:`reversed_from_z`. 0 (far/cleared) -> NaN
    for an infinite far plane, the far plane otherwise."""
    n, f = _near_far(near, far)
    w_rev = _float("w_rev", w_rev)
    if np.isinf(f):
        with np.errstate(divide="ignore", invalid="ignore"):
            ok = np.isfinite(w_rev) & (w_rev > 0) & (w_rev <= 1)
            return _depth32(np.where(ok, n / w_rev, np.nan))
    return z_from_window(1.0 - w_rev, near=n, far=f)


def _check_bits(bits) -> int:
    if bits not in (16, 24, 32):
        raise ValueError(f"bits: expected 16, 24 or 32, got {bits!r}")
    return int(bits)


def fixed_from_z(z, *, near: float, far: float, bits: int = 24) -> np.ndarray:
    """Fixed-point z-buffer codes q = round(w * (2^bits - 1)) as uint16 (16 bits) or uint32.

    Depth outside [near, far] is clamped to the nearest end code, as a GPU depth test would
    store it; invalid depth (NaN, <= 0) is stored as the far code (a cleared buffer).
    """
    bits = _check_bits(bits)
    n, f = _near_far(near, far)
    if np.isinf(f):
        raise ValueError("far: a fixed-point z-buffer needs a finite far plane")
    w = window_from_z(z, near=n, far=f)
    top = 2**bits - 1
    q = np.rint(np.clip(np.nan_to_num(w, nan=1.0), 0.0, 1.0) * top)
    return q.astype(np.uint16 if bits == 16 else np.uint32)


def z_from_fixed(q, *, near: float, far: float, bits: int = 24, far_is_empty: bool = True) -> np.ndarray:
    """Planar z from fixed-point z-buffer codes; the far code is empty (NaN) by default."""
    bits = _check_bits(bits)
    q = check_array("q", q, dtype_kind="iu")
    top = 2**bits - 1
    if q.size and (q.min() < 0 or q.max() > top):
        raise ValueError(f"q: codes must lie in [0, {top}] for {bits} bits, got [{q.min()}, {q.max()}]")
    z = z_from_window(q.astype(np.float64) / top, near=near, far=far)
    if far_is_empty:
        z[q == top] = np.nan
    return z


def zbuffer_step(z, *, near: float, far: float, bits: int) -> np.ndarray:
    """Depth change (scene units) of one code step of a fixed-point z-buffer at depth z.

    Exact: the distance from z to the depth of the next code, ``z(w + 1/(2^bits - 1)) - z(w)``;
    to first order ``z^2 (f - n) / (n f (2^bits - 1))``. NaN where the next code is past far.
    Example (n = 0.1, f = 100, 16 bits): 1.52e-4 at z = 1 and 1.53e-2 at z = 10.
    """
    bits = _check_bits(bits)
    n, f = _near_far(near, far)
    w = window_from_z(z, near=n, far=f)
    w_next = w + 1.0 / (2**bits - 1)
    # The far plane itself (w = 1) is the last code; allow for rounding of w computed from z.
    has_next = w_next <= 1 + 1e-9
    w_next = np.minimum(w_next, 1.0)
    def z_of(wv):  # the exact inverse in float64, also for an infinite far plane (n / (1 - w))
        return n / (1 - wv) if np.isinf(f) else n * f / (f - wv * (f - n))

    with np.errstate(divide="ignore", invalid="ignore"):
        z0 = z_of(w)
        z1 = np.where(has_next, z_of(w_next), np.nan)
    return z1 - z0


def zprime_from_z(z, *, near: float, far: float, scale: float = ZPRIME_SCALE) -> np.ndarray:
    """Seed 002 eq. 2: z' = 2^24 * f / (f - n) * (1 - n / z) (float64, unquantized).

    z' is affine in 1/z, hence affine in pixel coordinates over any plane. NaN for invalid z.
    """
    return scale * window_from_z(z, near=near, far=far)


def z_from_zprime(zp, *, near: float, far: float, scale: float = ZPRIME_SCALE) -> np.ndarray:
    """Inverse of :func:`zprime_from_z` (float32 planar z)."""
    return z_from_window(_float("zp", zp) / scale, near=near, far=far)


# ----------------------------------------------------------------------------- quantization
def disparity_step(z, *, baseline: float, focal_px: float, doffs: float = 0.0, step: float = 1.0) -> np.ndarray:
    """Depth change (scene units) of one disparity code of ``step`` pixels at depth z.

    Exact: ``z(d - step) - z(d)`` with ``d = B f / z - doffs`` (the next code *farther* away);
    to first order ``z^2 step / (B f)``. NaN where the farther code has d + doffs <= 0.
    Example: B = 0.24, f = 443.4 px, integer disparities: 0.0095 at z = 1, 0.24 at z = 5.
    """
    b = check_positive("baseline", baseline)
    f = check_positive("focal_px", focal_px)
    s = check_positive("step", step)
    z = _float("z", z)
    with np.errstate(divide="ignore", invalid="ignore"):
        den = b * f / z - s
        far = np.where(valid_mask(z) & (den > 0), b * f / den, np.nan)
    return far - z


def code_step(z, *, scale: float) -> np.ndarray:
    """Depth change of one code of a depth stored as integers of ``scale`` scene units (e.g.
    a 16-bit PNG in millimetres: scale = 0.001 m): ``scale`` at every valid z, NaN elsewhere."""
    sc = check_positive("scale", scale)
    z = _float("z", z)
    return np.where(valid_mask(z), sc, np.nan)


class DepthQuantization:
    """Quantization step of a depth encoding as a function of depth.

    The step in inverse depth q = 1/z is ``dq(q) = c0 + c2 q^2`` (module docstring): ``c0`` for
    encodings uniform in 1/z (disparity, z-buffer codes), ``c2`` for encodings uniform in z
    (millimetre codes). Build one with :meth:`disparity`, :meth:`zbuffer`, :meth:`codes`,
    or :meth:`from_encoding` (a view file's encoding and parameters). Immutable and hashable
    (meshes are cached per quantization).

    Examples
    --------
    >>> q = DepthQuantization.disparity(baseline=0.24, focal_px=443.4)   # integer disparities
    >>> round(float(q.step(2.0)), 4)                                        # scene units at z = 2
    0.0376
    """

    __slots__ = ("c0", "c2")

    def __init__(self, c0: float = 0.0, c2: float = 0.0):
        for name, v in (("c0", c0), ("c2", c2)):
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating)) or not np.isfinite(v) or v < 0:
                raise ValueError(f"{name}: expected a finite number >= 0, got {v!r}")
        object.__setattr__(self, "c0", float(c0))
        object.__setattr__(self, "c2", float(c2))

    def __setattr__(self, name, value):
        raise AttributeError("DepthQuantization is immutable")

    def __eq__(self, other) -> bool:
        return isinstance(other, DepthQuantization) and (self.c0, self.c2) == (other.c0, other.c2)

    def __hash__(self) -> int:
        return hash((DepthQuantization, self.c0, self.c2))

    def __lt__(self, other) -> bool:  # sortable, so option dicts holding one can be sorted
        return (self.c0, self.c2) < (other.c0, other.c2)

    def __repr__(self) -> str:
        return f"DepthQuantization(c0={self.c0:.6g}, c2={self.c2:.6g})"

    def describe(self) -> str:
        """The step in words: ``"depth codes of 0.05 scene units"`` (:meth:`codes`),
        ``"codes of 0.0012 in 1/z"`` (disparity, z-buffer), both joined, or ``"no steps"``."""
        parts = ([f"depth codes of {self.c2:g} scene units"] if self.c2 else []) + (
            [f"codes of {self.c0:.4g} in 1/z"] if self.c0 else [])
        return " and ".join(parts) or "no steps"

    # -------------------------------------------------------------- constructors
    @classmethod
    def disparity(cls, *, baseline: float, focal_px: float, step: float = 1.0) -> "DepthQuantization":
        """Disparity stored in codes of ``step`` pixels (``scale`` of a view file)."""
        return cls(c0=check_positive("step", step) / (check_positive("baseline", baseline)
                                                       * check_positive("focal_px", focal_px)))

    @classmethod
    def zbuffer(cls, *, near: float, far: float, bits: int) -> "DepthQuantization":
        """Window depth in ``bits``-bit codes (fixed16/fixed24; float32 window depth is as coarse
        as 24 bits)."""
        bits = _check_bits(bits)
        n, f = _near_far(near, far)
        ratio = 1.0 if np.isinf(f) else (f - n) / f
        return cls(c0=ratio / (n * (2**bits - 1)))

    @classmethod
    def codes(cls, scale: float) -> "DepthQuantization":
        """Planar depth (or range) stored as integers of ``scale`` scene units."""
        return cls(c2=check_positive("scale", scale))

    @classmethod
    def from_encoding(cls, encoding: str, params: dict, *, integer: bool) -> "DepthQuantization | None":
        """The quantization implied by a view file's depth ``encoding`` and its ``params``
        (``integer``: the stored file holds integer codes, e.g. a 16-bit PNG). For ``z``,
        ``range`` and ``disparity`` a ``step`` parameter (stored units per code, before
        ``scale``) overrides the default of one code; float files without a ``step`` are taken
        as unquantized (None). Float32 window, reversed and z' depth are as coarse as 24-bit
        codes."""
        step = params.get("step")
        scale = params.get("scale", 1.0)
        if encoding in ("fixed16", "fixed24"):
            return cls.zbuffer(near=params["near"], far=params["far"], bits=16 if encoding == "fixed16" else 24)
        if encoding in ("window", "reversed", "zprime"):  # float32 window depth: as coarse as 24 bits
            return cls.zbuffer(near=params["near"], far=params["far"], bits=24)
        if step is None and not integer:
            return None
        units = (1.0 if step is None else float(step)) * scale
        if encoding == "disparity":
            return cls.disparity(baseline=params["baseline"], focal_px=params["focal_px"], step=units)
        return cls.codes(units)  # "z", "range"

    # -------------------------------------------------------------- steps
    def inv_step(self, q):
        """Step in inverse depth (1/scene units) at inverse depth ``q``."""
        q = np.asarray(q, np.float64)
        return self.c0 + self.c2 * q * q

    def step(self, z):
        """Step in planar depth (scene units) at depth ``z``, to first order: ``dq z^2``."""
        z = np.asarray(z, np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            return self.c0 * z * z + self.c2

    def max_inv_step(self, depth) -> float:
        """Largest inverse-depth step over the valid pixels of ``depth`` (at the nearest one)."""
        if self.c2 == 0:
            return self.c0
        z = np.asarray(depth)
        with np.errstate(invalid="ignore"):
            v = z[np.isfinite(z) & (z > 0)]
        return self.c0 + (self.c2 / float(v.min()) ** 2 if v.size else 0.0)


import weakref as _weakref

_quantization_of: "_weakref.WeakKeyDictionary" = _weakref.WeakKeyDictionary()


def set_quantization(view, quantization: "DepthQuantization | None"):
    """Record the quantization of ``view``'s depth (what :func:`ibr.io.load_view` does for a
    view file's encoding); :func:`ibr.build_mesh` uses it when not given ``quantization=``.
    Returns ``view``."""
    if quantization is not None and not isinstance(quantization, DepthQuantization):
        raise TypeError(f"quantization: expected a DepthQuantization or None, got {type(quantization).__name__}")
    if quantization is None:
        _quantization_of.pop(view, None)
    else:
        _quantization_of[view] = quantization
    return view


def quantization_of(view) -> "DepthQuantization | None":
    """The quantization recorded for ``view`` (:func:`set_quantization`), or None."""
    try:
        return _quantization_of.get(view)
    except TypeError:
        return None
