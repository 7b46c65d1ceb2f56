"""Depth-buffer segmentation into planar rectangles (seed 002, section 1.2).

Pipeline: planar depth z -> nonlinear depth z' (seed eq. 2, 2^24 scale) -> per-pixel planarity
measure (the seed's five-point Δ² or better ones) -> binary split into rectangles.

Methods (``method=``)
---------------------
``"paper"``     faithful seed 002: |Δ²z'| = |4z'(i,j) - z'(i,j-1) - z'(i,j+1) - z'(i-1,j) - z'(i+1,j)|
                against the threshold, and the seed's scan-from-the-sides binary split.
``"separate"``  as ``"paper"`` with max(|∂²/∂u²|, |∂²/∂v²|, |∂²/∂u∂v|) instead of the Laplacian,
                which also sees harmonic saddles (z' ∝ u² − v² has Δ² = 0 but ∂²/∂u² = 2).
``"edge"``      (default) edge-aware and error-bounded: break edges *between* pixels where a depth
                step or crease lies (one-sided stencils keep pixels on a plane next to an edge
                planar), splits along the grid line holding most break edges, and a rectangle
                is accepted only when the least-squares plane over it reproduces every pixel's z'
                within the tolerance — the same plane the mesh uses, so the bound is guaranteed.
                A break-free rectangle that fails the fit is cut at a distinct crease line if
                it has one (mean |second difference| > 5x the average line), else in the middle.

Near/far and thresholds
-----------------------
z' = 2^24 f/(f-n) (1 - n/z) is affine in 1/z, so *which* pixels are planar does not depend on the
near/far planes, but the size of a threshold in z' units does. When ``near``/``far`` are not given
they are the smallest and largest valid depth of the view (far = 2 near for a constant depth), so
that z' spans the full 24-bit range over the view, like a z-buffer with tight clip planes: a
threshold of 2^15 is then 1/512 of the view's z' range, as in the seed.

Error bound (``max_error_px``)
------------------------------
Moving the camera sideways by a baseline b shifts a pixel of depth z by f·b/z pixels, so an error
δ(1/z) in inverse depth moves it by f·b·δ(1/z) (for a forward move by b, (r)·b·δ(1/z) with r the
distance from the principal point, <= f·b·δ(1/z) for fields of view up to 90°). A plane fit whose
max |residual in 1/z| <= tol therefore keeps the reprojection error <= f·b·tol pixels:
``tol = max_error_px / (f · b)``. In z' units tol_z' = tol · 2^24 f n/(f - n). The default baseline
is 5% of the median valid depth.

Pixels: (u, v) = (column, row), centers at integers; a rect ``[u0, v0, u1, v1]`` covers columns
u0..u1-1 and rows v0..v1-1 (e.g. [0, 0, 2, 1] is pixels (0, 0) and (1, 0)).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from . import _segment_kernels as _k
from ..base.validate import check_array, check_choice, check_positive
from ..base.depth import ZPRIME_SCALE, zprime_from_z
from ..base.first_run import await_kernels

__all__ = [
    "METHODS",
    "DEFAULT_METHOD",
    "DEFAULT_MAX_ERROR_PX",
    "DEFAULT_BASELINE_FRACTION",
    "Segmentation",
    "auto_near_far",
    "break_edges",
    "delta2",
    "planarity_measure",
    "segment",
    "split_rects",
    "tolerance_from_error_px",
    "zprime",
    "zprime_per_inv_depth",
]

METHODS = ("edge", "separate", "paper")
DEFAULT_METHOD = "edge"
DEFAULT_MAX_ERROR_PX = 0.5
DEFAULT_BASELINE_FRACTION = 0.05
#: ``edge`` method: break edges where a second difference exceeds this fraction of the tolerance.
DEFAULT_BREAK_FRACTION = 1.0
#: Quantized depth: second differences up to this many codes never break an edge. The rounded
#: codes of a plane step by at most one code between neighbours and their second differences are
#: 0 or +-1 code; two codes need a pixel one code off both its neighbours (a mixed or noisy pixel,
#: or the apex of a curved surface), which now breaks: with 2.0 here the bundled clutter pair in
#: 8-bit disparity rendered 0.65 dB below its exact depth, with 1.5 0.55 dB at fewer quads (room
#: -0.19 either way, 16-bit millimetres unchanged; ``benchmarks/bench_edges.py``, section 3)...
QUANT_BREAK_CODES = 1.5
#: ... and a plane may deviate this many codes from the stored (rounded) values.
QUANT_FIT_CODES = 0.5
#: ``edge`` method: a failed fit is cut at its most bent line when that line's mean |second
#: difference| exceeds this multiple of the average line (a crease), else in the middle.
CREASE_PEAK = 5.0


# ------------------------------------------------------------------ z'


def _depth(name: str, depth) -> np.ndarray:
    z = check_array(name, depth, ndim=2, dtype_kind="fiu")
    if z.shape[0] < 1 or z.shape[1] < 1:
        raise ValueError(f"{name}: expected a non-empty (H, W) array, got shape {z.shape}")
    z = z.astype(np.float64)
    with np.errstate(invalid="ignore"):
        z[~(np.isfinite(z) & (z > 0))] = np.nan
    return z


def auto_near_far(depth) -> tuple[float, float]:
    """Near/far for z' from a view's valid depth range: (min z, max z); far = 2·near if constant.

    Raises ``ValueError`` when the depth has no valid pixel.
    """
    z = _depth("depth", depth)
    if not np.isfinite(z).any():
        raise ValueError("depth: no valid pixel (all NaN, inf or <= 0)")
    n, f = float(np.nanmin(z)), float(np.nanmax(z))
    if not f > n * (1 + 1e-9):
        f = 2.0 * n
    return n, f


def zprime(depth, *, near: float | None = None, far: float | None = None) -> tuple[np.ndarray, float, float]:
    """Seed 002 eq. 2 nonlinear depth z' = 2^24 f/(f-n) (1 - n/z), float64, NaN where invalid.

    Returns ``(zp, near, far)``; near/far default to :func:`auto_near_far`.
    """
    z = _depth("depth", depth)
    if near is None or far is None:
        n0, f0 = auto_near_far(z)
        near = n0 if near is None else near
        far = f0 if far is None else far
    near = check_positive("near", near)
    far = check_positive("far", far, allow_inf=True)
    if not far > near:
        raise ValueError(f"far: expected far > near, got near={near}, far={far}")
    return zprime_from_z(z, near=near, far=far), near, far


def zprime_per_inv_depth(near: float, far: float) -> float:
    """|dz'/d(1/z)| = 2^24 f n / (f - n) (= 2^24 n for an infinite far plane)."""
    ratio = 1.0 if np.isinf(far) else far / (far - near)
    return ZPRIME_SCALE * ratio * near


# ------------------------------------------------------------------ measures


def delta2(zp) -> np.ndarray:
    """Seed 002 Δ² buffer (signed): 4z'(i,j) - z'(i,j-1) - z'(i,j+1) - z'(i-1,j) - z'(i+1,j).

    Plain numpy. NaN at invalid pixels. An axis whose stencil leaves the image or touches an
    invalid pixel contributes 0, so a plane's border pixels read 0 too.
    """
    z = check_array("zp", zp, ndim=2, dtype_kind="f").astype(np.float64)
    pad = np.pad(z, 1, constant_values=np.nan)
    c = pad[1:-1, 1:-1]
    tu = 2 * c - pad[1:-1, :-2] - pad[1:-1, 2:]
    tv = 2 * c - pad[:-2, 1:-1] - pad[2:, 1:-1]
    out = np.nan_to_num(tu, nan=0.0) + np.nan_to_num(tv, nan=0.0)
    out[~np.isfinite(z)] = np.nan
    return out


def _laplacian_measure_reference(zp):
    d = np.abs(delta2(zp))
    d[np.isnan(d)] = np.inf
    return d


def _separate_measure_reference(zp):
    z = np.asarray(zp, np.float64)
    pad = np.pad(z, 1, constant_values=np.nan)
    c = pad[1:-1, 1:-1]
    tu = np.abs(2 * c - pad[1:-1, :-2] - pad[1:-1, 2:])
    tv = np.abs(2 * c - pad[:-2, 1:-1] - pad[2:, 1:-1])
    tm = 0.25 * np.abs(pad[2:, 2:] - pad[:-2, 2:] - pad[2:, :-2] + pad[:-2, :-2])
    out = np.nan_to_num(np.fmax(np.fmax(tu, tv), tm), nan=0.0)
    out[~np.isfinite(z)] = np.inf
    return out


def planarity_measure(zp, *, method: str = "paper") -> np.ndarray:
    """Per-pixel non-planarity of z' (>= 0, +inf at invalid pixels), numba kernel.

    ``method="paper"``: |Δ²z'| (:func:`delta2`); ``"separate"``: max(|∂²/∂u²|, |∂²/∂v²|,
    |∂²/∂u∂v|) with centered stencils, the mixed one ``(z'(u+1,v+1) - z'(u+1,v-1) - z'(u-1,v+1) +
    z'(u-1,v-1)) / 4``.
    """
    check_choice("method", method, ("paper", "separate"))
    z = np.ascontiguousarray(check_array("zp", zp, ndim=2, dtype_kind="f"), dtype=np.float64)
    return _k.laplacian_measure(z) if method == "paper" else _k.separate_measure(z)


def _edge_line_reference(z, thr):
    n = len(z)
    out = np.zeros(max(n - 1, 0), np.uint8)
    fin = np.isfinite(z)

    def state(i):  # 0 unavailable, 1 straight, 2 bent (centered stencil at i)
        if i < 1 or i > n - 2 or not (fin[i - 1] and fin[i] and fin[i + 1]):
            return 0
        return 2 if abs(z[i - 1] - 2 * z[i] + z[i + 1]) > thr else 1

    for i in range(n - 1):
        if fin[i] != fin[i + 1]:
            out[i] = 1
        elif fin[i]:
            ci, cj = state(i), state(i + 1)
            if 2 in (ci, cj) and 1 not in (ci, cj):
                out[i] = 1
            elif ci == 2 and cj == 1 and state(i - 1) == 1:
                out[i] = 1
    return out


def _break_edges_reference(zp, thr):
    z = np.asarray(zp, np.float64)
    h, w = z.shape
    hb = np.zeros((h, max(w - 1, 0)), np.uint8)
    vb = np.zeros((max(h - 1, 0), w), np.uint8)
    for v in range(h):
        hb[v] = _edge_line_reference(z[v], thr)
    for u in range(w):
        vb[:, u] = _edge_line_reference(z[:, u], thr)
    return hb, vb


def break_edges(zp, threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """Break edges between 4-neighbors of z' for the edge-aware criterion (numba kernel).

    Returns ``hb`` (H, W-1) uint8, 1 where pixels (u, v) and (u+1, v) are separated, and ``vb``
    (H-1, W) uint8 for (u, v) and (u, v+1). Along a line, pair (i, i+1) is a break when exactly one
    of them is valid; when every available centered second difference straddling it (at i and at
    i+1) exceeds ``threshold`` (a step or crease between them); or when the stencil at i is bent
    while both one-sided stencils at i are straight (a crease at i; pixel i joins the low side).
    """
    z = np.ascontiguousarray(check_array("zp", zp, ndim=2, dtype_kind="f"), dtype=np.float64)
    thr = float(threshold)
    if not thr >= 0:
        raise ValueError(f"threshold: expected a number >= 0, got {threshold!r}")
    return _k.edge_breaks(z, thr)


# ------------------------------------------------------------------ split: references


def _split_pixels_reference(bad, invalid, min_band, first_dir):
    """Plain-Python seed 002 binary split; same output order as the numba kernel."""
    bad = np.asarray(bad, bool)
    invalid = np.asarray(invalid, bool)
    h, w = bad.shape
    out = []
    stack = [(0, 0, w, h, first_dir)]
    while stack:
        u0, v0, u1, v1, d = stack.pop()
        area = (u1 - u0) * (v1 - v0)
        if invalid[v0:v1, u0:u1].all():
            continue
        if area == 1 or not bad[v0:v1, u0:u1].any():
            out.append((u0, v0, u1, v1))
            continue
        if d == 0 and u1 - u0 < 2:
            d = 1
        elif d == 1 and v1 - v0 < 2:
            d = 0
        block = bad[v0:v1, u0:u1]
        lines = block.any(axis=0) if d == 0 else block.any(axis=1)
        lo, hi = (u0, u1) if d == 0 else (v0, v1)
        first = int(np.argmax(lines))  # a bad line exists
        last = len(lines) - 1 - int(np.argmax(lines[::-1]))
        if first >= min_band:
            s = lo + first
        elif len(lines) - 1 - last >= min_band:
            s = lo + last + 1
        else:
            s = lo + (hi - lo) // 2
        if d == 0:
            stack += [(s, v0, u1, v1, 1), (u0, v0, s, v1, 1)]
        else:
            stack += [(u0, s, u1, v1, 0), (u0, v0, u1, s, 0)]
    return np.array(out, np.int32).reshape(-1, 4)


def _fit_max_residual_reference(zp, u0, v0, u1, v1):
    block = zp[v0:v1, u0:u1]
    v, u = np.mgrid[v0:v1, u0:u1].astype(np.float64)
    a = np.stack([u.ravel(), v.ravel(), np.ones(u.size)], 1)
    coef, *_ = np.linalg.lstsq(a, block.ravel(), rcond=None)
    return float(np.abs(a @ coef - block.ravel()).max())


def _crease_split_reference(zp, u0, v0, u1, v1, peak):
    """Plain-Python twin of ``_segment_kernels.crease_split`` (same summation order)."""
    w, h = u1 - u0, v1 - v0
    sv, su = max(1, h // _k.CREASE_SAMPLES), max(1, w // _k.CREASE_SAMPLES)
    nsv, nsu = len(range(v0, v1, sv)), len(range(u0, u1, su))
    cu = cv = -1
    best_u = best_v = -1.0
    if w >= 3:
        means = []
        for c in range(u0 + 1, u1 - 1):
            acc = 0.0
            for v in range(v0, v1, sv):
                acc += abs(zp[v, c - 1] - 2.0 * zp[v, c] + zp[v, c + 1])
            means.append(acc / nsv)
        tot = 0.0
        for i, m in enumerate(means):
            tot += m
            if m > best_u:
                best_u, cu = m, u0 + 1 + i
        if not best_u > peak * tot / (w - 2):
            cu = -1
    if h >= 3:
        means = []
        for r in range(v0 + 1, v1 - 1):
            acc = 0.0
            for u in range(u0, u1, su):
                acc += abs(zp[r - 1, u] - 2.0 * zp[r, u] + zp[r + 1, u])
            means.append(acc / nsu)
        tot = 0.0
        for i, m in enumerate(means):
            tot += m
            if m > best_v:
                best_v, cv = m, v0 + 1 + i
        if not best_v > peak * tot / (h - 2):
            cv = -1
    if cu >= 0 and (cv < 0 or best_u >= best_v):
        return 0, cu
    if cv >= 0:
        return 1, cv
    return (0, u0 + w // 2) if w >= h else (1, v0 + h // 2)


def _split_edges_reference(zp, invalid, hb, vb, tol, first_dir, peak):
    """Plain-Python edge-aware split; same output order as the numba kernel."""
    zp = np.asarray(zp, np.float64)
    invalid = np.asarray(invalid, bool)
    h, w = zp.shape
    out = []
    stack = [(0, 0, w, h, first_dir)]
    while stack:
        u0, v0, u1, v1, d = stack.pop()
        if invalid[v0:v1, u0:u1].all():
            continue
        cols = hb[v0:v1, u0 : u1 - 1].sum(axis=0)  # breaks across line k = u0 + 1 + index
        rows = vb[v0 : v1 - 1, u0:u1].sum(axis=1)
        if cols.sum() + rows.sum() > 0:
            if d == 0 and cols.sum() == 0:
                d = 1
            elif d == 1 and rows.sum() == 0:
                d = 0
            counts = cols if d == 0 else rows
            lo, hi = (u0, u1) if d == 0 else (v0, v1)
            ks = np.arange(lo + 1, hi)
            dist = np.abs(2 * ks - (lo + hi))
            best = counts.max()
            cand = ks[counts == best]
            s = int(cand[np.argmin(dist[counts == best])])
        else:
            area = (u1 - u0) * (v1 - v0)
            if area == 1 or _fit_max_residual_reference(zp, u0, v0, u1, v1) <= tol:
                out.append((u0, v0, u1, v1))
                continue
            d, s = _crease_split_reference(zp, u0, v0, u1, v1, peak)
        if d == 0:
            stack += [(s, v0, u1, v1, 1), (u0, v0, s, v1, 1)]
        else:
            stack += [(u0, s, u1, v1, 0), (u0, v0, u1, s, 0)]
    return np.array(out, np.int32).reshape(-1, 4)


# ------------------------------------------------------------------ split: public


def split_rects(
    zp,
    *,
    method: str = DEFAULT_METHOD,
    threshold: float,
    tolerance: float | None = None,
    break_threshold: float | None = None,
    min_band: int = 1,
    reference: bool = False,
) -> np.ndarray:
    """Binary split of a z' buffer into rects (Q, 4) int32 ``[u0, v0, u1, v1]`` (half-open).

    Parameters
    ----------
    zp : (H, W) float
        Nonlinear depth z' (:func:`zprime`), NaN where invalid, or any buffer affine in it with
        thresholds in its units (:func:`segment` passes 1/z). Invalid pixels belong to no rect.
    method : {"edge", "separate", "paper"}
        See the module docstring.
    threshold : float
        Per-pixel threshold in z' units: on |Δ²| (``paper``), on the largest separate second
        difference (``separate``), or on the second differences that mark break edges (``edge``).
    tolerance : float, optional
        ``edge`` only: max |residual| in z' units of a rect's least-squares plane (default:
        ``threshold``).
    break_threshold : float, optional
        ``edge`` only: second-difference threshold of the break edges in z' units (default:
        ``threshold``).
    min_band : int
        ``paper``/``separate``: the "large enough" scanned band of the seed, in lines (>= 1).
    reference : bool
        Use the plain-Python reference implementation (slow; for tests).

    The first split is along a vertical line (scanning columns), then directions alternate.
    """
    check_choice("method", method, METHODS)
    z = np.ascontiguousarray(check_array("zp", zp, ndim=2, dtype_kind="f"), dtype=np.float64)
    thr = float(threshold)
    if not thr >= 0:
        raise ValueError(f"threshold: expected a number >= 0 (z' units), got {threshold!r}")
    if isinstance(min_band, bool) or int(min_band) != min_band or min_band < 1:
        raise ValueError(f"min_band: expected an integer >= 1, got {min_band!r}")
    if method == "edge":
        tol = thr if tolerance is None else float(tolerance)
        if not tol >= 0:
            raise ValueError(f"tolerance: expected a number >= 0 (z' units), got {tolerance!r}")
        bthr = thr if break_threshold is None else float(break_threshold)
        if not bthr >= 0:
            raise ValueError(f"break_threshold: expected a number >= 0 (z' units), got {break_threshold!r}")
        if reference:
            invalid = (~np.isfinite(z)).astype(np.uint8)
            hb, vb = _break_edges_reference(z, bthr)
            return _split_edges_reference(z, invalid, hb, vb, tol, 0, CREASE_PEAK)
        ch, rv = _k.edge_prefix(z, bthr)
        await_kernels("segment")  # a first `ibr mesh`: the helper may be caching the split's callees
        return _k.split_edges(z, ch, rv, tol, 0, CREASE_PEAK)
    invalid = (~np.isfinite(z)).astype(np.uint8)
    if reference:
        m = _laplacian_measure_reference(z) if method == "paper" else _separate_measure_reference(z)
        return _split_pixels_reference(m >= thr, invalid, int(min_band), 0)
    m = _k.laplacian_measure(z) if method == "paper" else _k.separate_measure(z)
    bad = (m >= thr).astype(np.uint8)
    return _k.split_pixels(bad, invalid, int(min_band), 0)


def tolerance_from_error_px(max_error_px: float, *, focal_px: float, baseline: float) -> float:
    """Max |error in 1/z| (1/scene units) that keeps reprojection within ``max_error_px``.

    ``tol = max_error_px / (focal_px * baseline)``: a camera move by ``baseline`` shifts a pixel by
    ``focal_px * baseline / z``, so an error δ(1/z) moves it by ``focal_px * baseline * δ(1/z)``.
    Example: 0.5 px, f = 1000 px, b = 0.1 m -> 0.005 m^-1.
    """
    e = check_positive("max_error_px", max_error_px)
    f = check_positive("focal_px", focal_px)
    b = check_positive("baseline", baseline)
    return e / (f * b)


@dataclass(frozen=True, eq=False)
class Segmentation:
    """Result of :func:`segment`: rects plus the parameters that produced them.

    ``threshold`` and ``tolerance`` are in z' units; ``tolerance_inv_depth`` is the guaranteed
    max |plane residual| in 1/z (``edge`` method only, else None); ``seconds`` the wall time of
    1/z + measure + split. ``inv_depth`` is 1/z (NaN where invalid); :attr:`zprime` gives z'.
    """

    rects: np.ndarray
    inv_depth: np.ndarray
    near: float
    far: float
    method: str
    threshold: float
    tolerance: float | None
    tolerance_inv_depth: float | None
    max_error_px: float | None
    baseline: float | None
    seconds: float
    quantization: object = None

    @property
    def zprime(self) -> np.ndarray:
        """z' = 2^24 f/(f-n) (1 - n/z) of the segmented depth (seed eq. 2), NaN where invalid."""
        ratio = 1.0 if np.isinf(self.far) else self.far / (self.far - self.near)
        return ZPRIME_SCALE * ratio - zprime_per_inv_depth(self.near, self.far) * self.inv_depth


def segment(
    depth,
    *,
    camera=None,
    threshold: float | None = None,
    max_error_px: float | None = None,
    baseline: float | None = None,
    method: str = DEFAULT_METHOD,
    near: float | None = None,
    far: float | None = None,
    min_band: int = 1,
    break_fraction: float = DEFAULT_BREAK_FRACTION,
    quantization=None,
) -> Segmentation:
    """Segment a planar depth map into rectangles that are planar in 1/z.

    Parameters
    ----------
    depth : (H, W) array
        Planar z in scene units; NaN, inf and z <= 0 are invalid and belong to no rect.
    camera : Camera, optional
        Needed for ``max_error_px`` (its focal length in pixels).
    threshold : float, optional
        Level of detail in z' units (the seed's 2^11 .. 2^15 for 24-bit z'). Exclusive with
        ``max_error_px``.
    max_error_px : float, optional
        Max reprojection error in pixels for a camera move of ``baseline``; converted to a
        tolerance on 1/z (:func:`tolerance_from_error_px`) and then to z'. Default
        (neither given): 0.5 px.
    baseline : float, optional
        Camera displacement in scene units for ``max_error_px``; default 5% of the median depth.
    method : {"edge", "separate", "paper"}
        See the module docstring. With ``max_error_px`` the ``paper``/``separate`` methods use the
        derived tolerance as their threshold, without a guarantee.
    near, far : float, optional
        Clip planes of z'; default: the view's depth range (:func:`auto_near_far`).
    quantization : DepthQuantization, optional
        The quantization of the depth's encoding (:class:`ibr.base.depth.DepthQuantization`).
        A staircase of one-code steps on a smooth surface is a plane: second differences of
        one code (``dq``, in 1/z, taken at the nearest pixel) never break an edge (break
        threshold ``max(break, QUANT_BREAK_CODES * dq)``), and a plane is accepted within
        ``tolerance + QUANT_FIT_CODES * dq`` of the stored codes (the codes themselves are only
        known to half a step).
    """
    check_choice("method", method, METHODS)
    if threshold is not None and max_error_px is not None:
        raise ValueError("threshold, max_error_px: give at most one of them")
    z = check_array("depth", depth, ndim=2, dtype_kind="fiu")
    if z.shape[0] < 1 or z.shape[1] < 1:
        raise ValueError(f"depth: expected a non-empty (H, W) array, got shape {z.shape}")
    if z.dtype not in (np.float32, np.float64):
        z = z.astype(np.float64)
    z = np.ascontiguousarray(z)
    t0 = time.perf_counter()
    # The split runs on q = 1/z: z' = A - B q is affine in q, so every decision (second
    # differences over a threshold, plane-fit residuals, crease profiles) is the same with the
    # z' thresholds divided by B, and the fit residual is directly the 1/z error that is bounded.
    q, lo, hi, count = _k.inv_depth_range(z)
    if count == 0 and (near is None or far is None):
        raise ValueError("depth: no valid pixel (all NaN, inf or <= 0)")
    if near is None or far is None:
        if not hi > lo * (1 + 1e-9):
            hi = 2.0 * lo
        near = lo if near is None else near
        far = hi if far is None else far
    n = check_positive("near", near)
    f = check_positive("far", far, allow_inf=True)
    if not f > n:
        raise ValueError(f"far: expected far > near, got near={near}, far={far}")
    scale = zprime_per_inv_depth(n, f)
    if threshold is None:
        max_error_px = DEFAULT_MAX_ERROR_PX if max_error_px is None else max_error_px
        if camera is None:
            raise ValueError("camera: needed to convert max_error_px to a depth tolerance")
        if baseline is None:
            baseline = DEFAULT_BASELINE_FRACTION * _median_depth(z)
        tol_q = tolerance_from_error_px(max_error_px, focal_px=max(camera.fx, camera.fy), baseline=baseline)
        thr = tol_q * scale
    else:
        thr = check_positive("threshold", threshold)
    dq = _quant_step(quantization, z)
    if method == "edge":
        bf = check_positive("break_fraction", break_fraction)
        rects = split_rects(q, method=method, threshold=thr / scale,
                            tolerance=thr / scale + QUANT_FIT_CODES * dq,
                            break_threshold=max(bf * thr / scale, QUANT_BREAK_CODES * dq),
                            min_band=min_band)  # unused by the edge method, but checked as for the others
    else:
        rects = split_rects(q, method=method, threshold=max(thr / scale, QUANT_BREAK_CODES * dq), min_band=min_band)
    seconds = time.perf_counter() - t0
    tol = thr + QUANT_FIT_CODES * dq * scale if method == "edge" else None
    return Segmentation(
        rects=rects,
        inv_depth=q,
        near=n,
        far=f,
        method=method,
        threshold=thr,
        tolerance=tol,
        tolerance_inv_depth=(tol / scale) if tol is not None else None,
        max_error_px=max_error_px,
        baseline=baseline,
        seconds=seconds,
        quantization=quantization,
    )


def _quant_step(quantization, z) -> float:
    """Inverse-depth step of one code (0 without quantization)."""
    if quantization is None:
        return 0.0
    from ..base.depth import DepthQuantization

    if not isinstance(quantization, DepthQuantization):
        raise TypeError(f"quantization: expected an ibr.base.depth.DepthQuantization, got "
                        f"{type(quantization).__name__}")
    return float(quantization.max_inv_step(z))


def _median_depth(z) -> float:
    """Median of the valid depth; images over 2^16 pixels use every 4th row and column (the
    median of a smooth depth map changes by far less than the 5% baseline it feeds)."""
    sub = z[::4, ::4] if z.size > 65536 else z
    with np.errstate(invalid="ignore"):
        valid = sub[np.isfinite(sub) & (sub > 0)]
    if valid.size == 0:
        valid = z[np.isfinite(z) & (z > 0)]
    if valid.size == 0:
        raise ValueError("depth: no valid pixel to choose a default baseline from")
    return float(np.median(valid))
