"""numba kernels for :mod:`ibr.mesh.segment` and :mod:`ibr.mesh` (private; wrappers validate inputs).

All kernels take C-contiguous arrays; invalid depth is NaN in the float inputs. Pixel (u, v) =
(column, row) is element ``[v, u]``. Plain numpy/Python references live in :mod:`ibr.mesh.segment`
(``*_reference``) and the tests compare the two.
"""

from __future__ import annotations

import numpy as np
from ..base.jit import njit

#: Pixels sampled along each line by :func:`crease_split` (at most about this many).
CREASE_SAMPLES = 32

# ------------------------------------------------------------------ z'


@njit(cache=True)
def zprime_kernel(z, near, far, scale):
    """z' = scale f/(f-n) (1 - n/z) (seed 002 eq. 2) as float64, NaN where z is not finite or <= 0.
    ``far`` may be inf (ratio f/(f-n) = 1)."""
    h, w = z.shape
    ratio = 1.0 if np.isinf(far) else far / (far - near)
    a = scale * ratio
    b = scale * ratio * near
    zp = np.empty((h, w), np.float64)
    for v in range(h):
        for u in range(w):
            x = np.float64(z[v, u])
            zp[v, u] = a - b / x if (x > 0 and x < np.inf) else np.nan  # x > 0 is False for NaN
    return zp


@njit(cache=True)
def valid_range(z):
    """(min, max, count) of the valid (finite, > 0) values of a 2-D ``z``; (nan, nan, 0) if none."""
    h, w = z.shape
    los = np.full(h, np.inf)
    his = np.full(h, -np.inf)
    ns = np.zeros(h, np.int64)
    for v in range(h):
        lo = np.inf
        hi = -np.inf
        n = 0
        for u in range(w):
            x = np.float64(z[v, u])
            if x > 0 and x < np.inf:  # False for NaN
                n += 1
                lo = min(lo, x)
                hi = max(hi, x)
        los[v] = lo
        his[v] = hi
        ns[v] = n
    n = ns.sum()
    if n == 0:
        return np.nan, np.nan, 0
    return los.min(), his.max(), n


def inv_depth_range(z):
    """(q, zmin, zmax, count): q = 1/z as float64 (NaN where z is not finite or <= 0, or so small
    that 1/z overflows: 1e-310) and the range and count of the valid depth. (nan, nan, 0) range when nothing is valid.

    ``z`` is a C-contiguous 2-D float32 or float64 array. numpy and ``cv2.minMaxLoc``, not a
    kernel: a first run compiled one for this in 0.3 s; 2.5 ms at 1920x1080 (the kernel 1.7 ms).
    """
    import cv2

    with np.errstate(divide="ignore", over="ignore", invalid="ignore"):  # 1/1e-310 is inf
        q = np.divide(1.0, z, dtype=np.float64)
    valid = (z > 0) & (z < np.inf) & (q < np.inf)  # False for NaN; a denormal z (1/z = inf) is no depth either
    n = int(np.count_nonzero(valid))
    np.copyto(q, np.nan, where=~valid)
    if n == 0:
        return q, np.nan, np.nan, 0
    lo, hi = cv2.minMaxLoc(z, mask=valid.view(np.uint8))[:2]  # exact: the min / max element
    return q, float(lo), float(hi), n


# ------------------------------------------------------------------ per-pixel measures


@njit(cache=True)
def laplacian_measure(zp):
    """|five-point second difference| of z' (seed 002, Δ² below eq. 2); +inf at invalid pixels.

    An axis whose neighbor on either side is outside the image or invalid contributes nothing
    (its curvature cannot be measured there), so a border pixel of a plane stays planar.
    """
    h, w = zp.shape
    out = np.empty((h, w), np.float64)
    for v in range(h):
        for u in range(w):
            c = zp[v, u]
            if not np.isfinite(c):
                out[v, u] = np.inf
                continue
            s = 0.0
            if u > 0 and u < w - 1:
                a = zp[v, u - 1]
                b = zp[v, u + 1]
                if np.isfinite(a) and np.isfinite(b):
                    s += 2.0 * c - a - b
            if v > 0 and v < h - 1:
                a = zp[v - 1, u]
                b = zp[v + 1, u]
                if np.isfinite(a) and np.isfinite(b):
                    s += 2.0 * c - a - b
            out[v, u] = abs(s)
    return out


@njit(cache=True)
def separate_measure(zp):
    """max(|d2/du2|, |d2/dv2|, |d2/dudv|) of z' with centered stencils; +inf at invalid pixels.

    The mixed term is ``(z(u+1,v+1) - z(u+1,v-1) - z(u-1,v+1) + z(u-1,v-1)) / 4``. Terms whose
    stencil leaves the image or touches an invalid pixel are skipped.
    """
    h, w = zp.shape
    out = np.empty((h, w), np.float64)
    for v in range(h):
        for u in range(w):
            c = zp[v, u]
            if not np.isfinite(c):
                out[v, u] = np.inf
                continue
            m = 0.0
            if u > 0 and u < w - 1:
                a = zp[v, u - 1]
                b = zp[v, u + 1]
                if np.isfinite(a) and np.isfinite(b):
                    m = max(m, abs(2.0 * c - a - b))
            if v > 0 and v < h - 1:
                a = zp[v - 1, u]
                b = zp[v + 1, u]
                if np.isfinite(a) and np.isfinite(b):
                    m = max(m, abs(2.0 * c - a - b))
                if u > 0 and u < w - 1:
                    d = zp[v + 1, u + 1] - zp[v - 1, u + 1] - zp[v + 1, u - 1] + zp[v - 1, u - 1]
                    if np.isfinite(d):
                        m = max(m, 0.25 * abs(d))
            out[v, u] = m
    return out


@njit(cache=True, inline="always")
def _pair_break(zm2, zm1, a, b, zp2, thr):
    """Break flag between samples a (index i) and b (i + 1) of a line, given the samples at
    i - 2, i - 1, i + 2 (NaN when outside the line or invalid). See :func:`edge_breaks`.
    ``x == x`` is the NaN test (z' holds NaN, never inf, for invalid pixels)."""
    fa = a == a
    fb = b == b
    if fa != fb:
        return 1
    if not fa:
        return 0
    # state of the centered stencil: 0 unavailable, 1 straight, 2 bent
    ci = 0
    if zm1 == zm1:
        ci = 2 if abs(zm1 - 2.0 * a + b) > thr else 1
    cj = 0
    if zp2 == zp2:
        cj = 2 if abs(a - 2.0 * b + zp2) > thr else 1
    if (ci == 2 or cj == 2) and ci != 1 and cj != 1:
        return 1  # every stencil straddling the pair is bent: a step or crease between i and i+1
    if ci == 2 and cj == 1 and zm2 == zm2 and abs(zm2 - 2.0 * zm1 + a) <= thr:
        return 1  # crease exactly at i: both one-sided stencils at i are straight
    return 0


@njit(cache=True)
def edge_breaks(zp, thr):
    """Break edges between 4-neighbors for the edge-aware criterion.

    Returns ``hb`` (H, W-1) uint8 (1 = break between (u, v) and (u+1, v)) and ``vb`` (H-1, W) uint8
    (break between (u, v) and (u, v+1)). Along each line, the pair (i, i+1) is a break when one of
    them is invalid and the other valid; or when every available centered second difference
    straddling the pair (at i and at i+1) exceeds ``thr`` (a depth step or a crease between
    them); or when the stencil at i is bent but both one-sided stencils at i are straight (a crease
    exactly at i: pixel i joins the side before it). Pixels on a plane next to an edge therefore
    stay planar: their one-sided stencils are straight.
    """
    h, w = zp.shape
    nan = np.nan
    hb = np.zeros((h, max(w - 1, 0)), np.uint8)
    vb = np.zeros((max(h - 1, 0), w), np.uint8)
    for v in range(h):
        for u in range(w - 1):
            zm2 = zp[v, u - 2] if u >= 2 else nan
            zm1 = zp[v, u - 1] if u >= 1 else nan
            zp2 = zp[v, u + 2] if u + 2 < w else nan
            hb[v, u] = _pair_break(zm2, zm1, zp[v, u], zp[v, u + 1], zp2, thr)
    for v in range(h - 1):
        for u in range(w):
            zm2 = zp[v - 2, u] if v >= 2 else nan
            zm1 = zp[v - 1, u] if v >= 1 else nan
            zp2 = zp[v + 2, u] if v + 2 < h else nan
            vb[v, u] = _pair_break(zm2, zm1, zp[v, u], zp[v + 1, u], zp2, thr)
    return hb, vb


# ------------------------------------------------------------------ summed-area tables


@njit(cache=True)
def _sat(mask):
    """Summed-area table (H+1, W+1) int32 of a 0/1 array."""
    h, w = mask.shape
    s = np.zeros((h + 1, w + 1), np.int32)
    for v in range(h):
        row = 0
        for u in range(w):
            row += mask[v, u]
            s[v + 1, u + 1] = s[v, u + 1] + row
    return s


@njit(cache=True)
def _box(s, u0, v0, u1, v1):
    """Sum of the SAT's source over columns u0..u1-1, rows v0..v1-1 (0 when empty)."""
    if u1 <= u0 or v1 <= v0:
        return 0
    return s[v1, u1] - s[v0, u1] - s[v1, u0] + s[v0, u0]


@njit(cache=True)
def _colcum(mask):
    """(H+1, W) int32 prefix sums down each column: c[v, u] = sum(mask[:v, u])."""
    h, w = mask.shape
    c = np.zeros((h + 1, w), np.int32)
    for v in range(h):
        for u in range(w):
            c[v + 1, u] = c[v, u] + mask[v, u]
    return c


@njit(cache=True)
def _rowcum_t(mask):
    """(W+1, H) int32 prefix sums along each row, stored transposed: r[u, v] = sum(mask[v, :u]),
    so that consecutive rows v of one column range are contiguous in memory. Written in blocks
    of 32 columns so that the transposed writes stay in cache."""
    h, w = mask.shape
    r = np.zeros((w + 1, h), np.int32)
    carry = np.zeros(h, np.int32)
    for b0 in range(0, w, 32):
        b1 = min(b0 + 32, w)
        for v in range(h):
            acc = carry[v]
            for u in range(b0, b1):
                acc += mask[v, u]
                r[u + 1, v] = acc
            carry[v] = acc
    return r


# ------------------------------------------------------------------ binary split (paper)


@njit(cache=True, inline="always")
def _put_rect(stack, row, u0, v0, u1, v1, direction):
    stack[row, 0] = u0
    stack[row, 1] = v0
    stack[row, 2] = u1
    stack[row, 3] = v1
    stack[row, 4] = direction


@njit(cache=True, inline="always")
def _push_children(stack, top, u0, v0, u1, v1, d, split):
    """Push the two halves of rect [u0, u1) x [v0, v1) cut at ``split`` along axis ``d`` (0: at
    column u = split, 1: at row v = split), the high child first so that the low child is
    processed first; each child splits along the other axis next (the seed's alternation)."""
    if d == 0:
        _put_rect(stack, top, split, v0, u1, v1, 1)
        _put_rect(stack, top + 1, u0, v0, split, v1, 1)
    else:
        _put_rect(stack, top, u0, split, u1, v1, 0)
        _put_rect(stack, top + 1, u0, v0, u1, split, 0)


@njit(cache=True)
def split_pixels(bad, invalid, min_band, first_dir):
    """Seed 002 binary split on a per-pixel "over threshold" map (faithful mode).

    ``bad[v, u]`` = 1 where |Δ²| >= threshold or depth is invalid; ``invalid`` = 1 where depth is
    invalid. A region is kept as one rect when no pixel in it is bad or it is a single valid pixel,
    and dropped when all its pixels are invalid. Otherwise it is split alternately by a vertical
    line (direction 0: scan columns) and a horizontal line (direction 1: scan rows): scan lines
    inward from the low side until a line holds a bad pixel; if the clean band before it holds at
    least ``min_band`` lines, split just before that line; else scan from the high side likewise;
    else split in the middle. A region one line thick in the current direction uses the other.

    Returns (Q, 4) int32 rects ``[u0, v0, u1, v1]`` in depth-first order (low child first).
    """
    h, w = bad.shape
    sb = _sat(bad)
    si = _sat(invalid)
    cc = _colcum(bad)
    rc = _rowcum_t(bad)
    cap = h * w + 1
    out = np.empty((cap, 4), np.int32)
    stack = np.empty((cap + 1, 5), np.int32)
    top = 0
    stack[0, 0] = 0
    stack[0, 1] = 0
    stack[0, 2] = w
    stack[0, 3] = h
    stack[0, 4] = first_dir
    top = 1
    n = 0
    while top > 0:
        top -= 1
        u0 = stack[top, 0]
        v0 = stack[top, 1]
        u1 = stack[top, 2]
        v1 = stack[top, 3]
        d = stack[top, 4]
        area = (u1 - u0) * (v1 - v0)
        if _box(si, u0, v0, u1, v1) == area:
            continue
        if area == 1 or _box(sb, u0, v0, u1, v1) == 0:
            out[n, 0] = u0
            out[n, 1] = v0
            out[n, 2] = u1
            out[n, 3] = v1
            n += 1
            continue
        if d == 0 and u1 - u0 < 2:
            d = 1
        elif d == 1 and v1 - v0 < 2:
            d = 0
        lo = u0 if d == 0 else v0
        hi = u1 if d == 0 else v1
        split = -1
        k = lo
        while k < hi:  # scan from the low side
            cnt = (cc[v1, k] - cc[v0, k]) if d == 0 else (rc[u1, k] - rc[u0, k])
            if cnt > 0:
                break
            k += 1
        if k - lo >= min_band:
            split = k
        else:
            k = hi - 1
            while k >= lo:  # scan from the high side
                cnt = (cc[v1, k] - cc[v0, k]) if d == 0 else (rc[u1, k] - rc[u0, k])
                if cnt > 0:
                    break
                k -= 1
            if hi - 1 - k >= min_band:
                split = k + 1
            else:
                split = lo + (hi - lo) // 2
        _push_children(stack, top, u0, v0, u1, v1, d, split)
        top += 2
    return out[:n].copy()


# ------------------------------------------------------------------ plane fit


@njit(cache=True, fastmath={"reassoc"})
def _rect_moments(zp, u0, v0, u1, v1):
    """(S(z), S(z du), S(z dv)) over a full rect, du = u - uc and dv = v - vc about its center.

    The only kernel with re-associated (SIMD) sums; every plane fit of the split and of the mesh
    goes through it, so the plane the split verified is the plane the mesh stores.
    """
    uc = 0.5 * (u0 + u1 - 1)
    vc = 0.5 * (v0 + v1 - 1)
    s = 0.0
    su = 0.0
    sv = 0.0
    for v in range(v0, v1):
        row = zp[v]
        rs = 0.0
        rsu = 0.0
        for u in range(u0, u1):
            z = row[u]
            rs += z
            rsu += z * (u - uc)
        s += rs
        su += rsu
        sv += rs * (v - vc)
    return s, su, sv


@njit(cache=True, inline="always")
def _rect_plane(zp, u0, v0, u1, v1):
    """Centered least-squares plane (a, b, c, uc, vc): z ~ c + a (u - uc) + b (v - vc).

    Over a full rectangle the normal equations decouple in centered coordinates:
    ``a = S(z du) / S(du^2)``, ``b = S(z dv) / S(dv^2)``, ``c = mean(z)``; a one-pixel-thick rect
    gets a zero slope across its thickness.
    """
    w = u1 - u0
    h = v1 - v0
    s, su, sv = _rect_moments(zp, u0, v0, u1, v1)
    c = s / (w * h)
    a = su / (h * w * (w * w - 1) / 12.0) if w > 1 else 0.0
    b = sv / (w * h * (h * h - 1) / 12.0) if h > 1 else 0.0
    return a, b, c, 0.5 * (u0 + u1 - 1), 0.5 * (v0 + v1 - 1)


@njit(cache=True)
def rect_fit_max_residual(zp, u0, v0, u1, v1, limit):
    """Max |residual| of the least-squares plane of ``zp`` over a full rect (all finite).

    Stops early (returning a value > ``limit``) as soon as a residual exceeds ``limit``.
    """
    a, b, c, uc, vc = _rect_plane(zp, u0, v0, u1, v1)
    m = 0.0
    for v in range(v0, v1):
        base = c + b * (v - vc)
        for u in range(u0, u1):
            r = abs(zp[v, u] - (base + a * (u - uc)))
            if r > m:
                m = r
                if m > limit:
                    return m
    return m


@njit(cache=True)
def _row_exceeds(row, u0, u1, base, a, uc, limit):
    """Number of pixels u0..u1-1 of ``row`` whose residual against ``base + a (u - uc)`` exceeds
    ``limit`` (a branch-free count, so that the loop vectorizes)."""
    n = 0
    for u in range(u0, u1):
        n += abs(row[u] - (base + a * (u - uc))) > limit
    return n


@njit(cache=True, inline="always")
def rect_fit_within(zp, u0, v0, u1, v1, limit):
    """True when every |residual| of the least-squares plane over a full rect is <= ``limit``.

    Same plane and residuals as :func:`rect_fit_max_residual` (``<= limit`` there iff True
    here). The first and last rows are checked first (a crease or bend near the rect's edge
    shows there), then the others; the check stops at the first row holding a residual over
    ``limit``.
    """
    a, b, c, uc, vc = _rect_plane(zp, u0, v0, u1, v1)
    if _row_exceeds(zp[v0], u0, u1, c + b * (v0 - vc), a, uc, limit):
        return False
    if v1 - 1 > v0 and _row_exceeds(zp[v1 - 1], u0, u1, c + b * (v1 - 1 - vc), a, uc, limit):
        return False
    for v in range(v0 + 1, v1 - 1):
        if _row_exceeds(zp[v], u0, u1, c + b * (v - vc), a, uc, limit):
            return False
    return True


def fit_planes_inv_depth(q, rects):
    """(Q, 3) least-squares planes ``q(u, v) = a u + b v + c`` over each rect (absolute coords).

    A one-pixel rect gets a = b = 0, c = q(center); a one-pixel-thick rect gets a zero slope
    across its thickness. Rects must hold finite values only. Same fit as the split's
    (:func:`rect_fit_within`), so the tolerance the split verified holds for these planes.
    """
    out = np.empty((rects.shape[0], 3), np.float64)  # here, not in the kernel (#13)
    _fit_planes_kernel(q, rects, out)
    return out


@njit(cache=True)
def _fit_planes_kernel(q, rects, out):
    """:func:`fit_planes_inv_depth` into ``out`` (Q, 3)."""
    for i in range(rects.shape[0]):
        a, b, c, uc, vc = _rect_plane(q, rects[i, 0], rects[i, 1], rects[i, 2], rects[i, 3])
        out[i, 0] = a
        out[i, 1] = b
        out[i, 2] = c - a * uc - b * vc


def label_rects(rects, h, w):
    """(H, W) int32 index of the rect covering each pixel, -1 elsewhere, for rects that do not
    overlap (a segmentation's) inside the image.

    numpy, not a kernel (a first run compiled one in 0.3 s, #13): each rect adds its index + 1
    at its four corners of a difference array (+ at (v0, u0) and (v1, u1), - at the other two),
    whose 2-D prefix sum is that index over the rect (13 ms for 19,200 rects at 1920x1080).
    Overlapping rects give meaningless labels (:func:`rect_coverage` takes any rects); rects
    that are empty or leave the image are refused.
    """
    check_rects_inside(rects, h, w)
    return _rect_corner_sums(rects, h, w, np.arange(1, len(rects) + 1, dtype=np.int32)) - 1


def check_rects_inside(rects, h, w) -> None:
    """Refuse (ValueError naming ``rects`` and the first bad one) rects that are empty or leave
    the h x w image; a numba kernel would read or write outside the arrays."""
    r = np.asarray(rects).reshape(-1, 4)
    inside = (r[:, 0] >= 0) & (r[:, 1] >= 0) & (r[:, 2] <= w) & (r[:, 3] <= h) & (r[:, 0] < r[:, 2]) & (r[:, 1] < r[:, 3])
    if not inside.all():
        raise ValueError(f"rects: expected non-empty [u0, v0, u1, v1] inside the {w}x{h} image, "
                         f"got {r[np.argmin(inside)].tolist()}")


def rect_coverage(rects, h, w):
    """(H, W) bool: the pixels that at least one rect covers (rects may overlap; the parts outside
    the image are ignored)."""
    r = np.asarray(rects, np.int64).reshape(-1, 4)
    r = np.clip(r, 0, [w, h, w, h])
    r = r[(r[:, 2] > r[:, 0]) & (r[:, 3] > r[:, 1])]
    return _rect_corner_sums(r, h, w, np.ones(len(r), np.int32)) > 0


def _rect_corner_sums(rects, h, w, values):
    """(H, W) int32 sum of ``values[i]`` over the pixels of rect i (rects inside the image)."""
    r = np.asarray(rects, np.intp).reshape(-1, 4)
    d = np.zeros((h + 1, w + 1), np.int32)
    np.add.at(d, (r[:, 1], r[:, 0]), values)
    np.subtract.at(d, (r[:, 1], r[:, 2]), values)
    np.subtract.at(d, (r[:, 3], r[:, 0]), values)
    np.add.at(d, (r[:, 3], r[:, 2]), values)
    np.cumsum(d, axis=0, out=d)
    np.cumsum(d, axis=1, out=d)
    return d[:h, :w]


# ------------------------------------------------------------------ binary split (edge-aware)


#: Vertical break flags are buffered for this many consecutive rows, then written to the
#: transposed row prefix sums ``rv`` a cache line at a time.
_RV_BLOCK = 32


def edge_prefix(zp, thr):
    """Prefix sums of the break edges of :func:`edge_breaks`, in one fused pass over ``zp``
    (single-threaded: on a shared 2-core machine numba's parallel kernels measured slower than
    serial ones).

    Returns ``ch`` (H+1, W-1) with ``ch[v, u] = sum(hb[:v, u])`` (breaks across the vertical grid
    line between columns u and u+1, rows above v) and ``rv`` (W+1, H-1) with
    ``rv[u, v] = sum(vb[v, :u])`` (stored transposed so a scan over rows reads contiguous memory).
    Both are int16 when the image is at most 32767 pixels on each side (a count never exceeds
    the side), else int32: half the memory traffic for the split's line scans.
    """
    h, w = zp.shape
    dt = np.int16 if max(h, w) <= 32767 else np.int32
    ch = np.empty((h + 1, max(w - 1, 0)), dt)
    rv = np.empty((w + 1, max(h - 1, 0)), dt)
    ch[0] = 0  # here rather than in the kernel: zeroing loops there stopped its row loops from
    rv[0] = 0  # vectorizing (measured 1.5x slower)
    scratch = np.empty((5, w + 2), np.uint8)  # the kernel's rows of pixel codes and flags
    _edge_prefix_kernel(zp, thr, ch, rv, scratch, np.empty(w * _RV_BLOCK, np.uint8))
    return ch, rv


@njit(cache=True, inline="always")
def _stencil_state(a, c, b, thr):
    """Centered second difference a - 2c + b: 0 unavailable (a NaN sample), 1 straight, 2 bent.
    Branch-free so that the loops over a row vectorize."""
    avail = (a == a) & (c == c) & (b == b)
    bent = abs(a - 2.0 * c + b) > thr
    return np.uint8(avail) * (np.uint8(1) + np.uint8(bent))


@njit(cache=True, inline="always")
def _valid_bit(x):
    """4 where sample ``x`` is valid (not NaN), else 0: bit 2 of a pixel code."""
    return np.uint8(x == x) << np.uint8(2)


@njit(cache=True, inline="always")
def _flag(cm1, c0, c1):
    """Break flag of pair (i, i+1) from the pixel codes at i-1, i, i+1 (bits 0-1: stencil state
    0 unavailable / 1 straight / 2 bent, bit 2: sample valid). Same rule as :func:`_pair_break`
    (the one-sided stencil at i is the centered one at i-1); branch-free on uint8 only, so the
    loops vectorize."""
    s0 = c0 & 3
    s1 = c1 & 3
    fa = (c0 >> 2) & 1
    fb = (c1 >> 2) & 1
    st0 = s0 == 1
    st1 = s1 == 1
    straddle = ((s0 == 2) | (s1 == 2)) & ~st0 & ~st1  # every stencil straddling the pair is bent
    crease = (s0 == 2) & st1 & ((cm1 & 3) == 1)  # crease exactly at i
    return (fa ^ fb) | (fa & fb & np.uint8(straddle | crease))


@njit(cache=True)
def _add_row(dst, src, flags, n):
    """dst[:n] = src[:n] + flags[:n] (a separate kernel on 1-D rows: the loop vectorizes, 3x
    faster than the same sum written inline in the 2-D kernel)."""
    for u in range(n):
        dst[u] = src[u] + flags[u]


@njit(cache=True)
def _edge_prefix_kernel(zp, thr, ch, rv, scratch, vflags):
    """Fill rows 1.. of ``ch`` and ``rv`` of :func:`edge_prefix` (row 0 must be zero already):
    row by row, pixel codes (stencil state + validity), break flags, prefix sums."""
    h, w = zp.shape
    blk = _RV_BLOCK
    # scratch rows passed in (``scratch`` (5, W + 2) uint8: hc, vc0, vc1, vc2, hflags; ``vflags``
    # (W * _RV_BLOCK,) uint8): allocated in the kernel the row loops vectorized better (the edge
    # prefix 2.2 -> 2.7 ms at 1920 x 1080, the whole room mesh within noise: 13.02 / 13.03 ms),
    # but numba's np.empty overloads cost a first run 0.11 s of compiling (#13)
    hc = scratch[0]
    vc0 = scratch[1]
    vc1 = scratch[2]
    vc2 = scratch[3]
    hflags = scratch[4]
    for u in range(w + 2):
        hc[u] = 0
        vc0[u] = 0
        vc1[u] = 0
        vc2[u] = 0
    for u in range(w):
        vc1[u] = _valid_bit(zp[0, u])  # no vertical stencil at row 0
    for v in range(h):
        row = zp[v]
        hc[1] = _valid_bit(row[0])
        hc[w] = _valid_bit(row[w - 1])
        for u in range(1, w - 1):
            hc[u + 1] = _stencil_state(row[u - 1], row[u], row[u + 1], thr) | _valid_bit(row[u])
        for u in range(w - 1):
            hflags[u] = _flag(hc[u], hc[u + 1], hc[u + 2])
        _add_row(ch[v + 1], ch[v], hflags, w - 1)
        if v + 1 >= h:
            break
        nxt = zp[v + 1]
        if v + 2 < h:
            nn = zp[v + 2]
            for u in range(w):
                vc2[u] = _stencil_state(row[u], nxt[u], nn[u], thr) | _valid_bit(nxt[u])
        else:
            for u in range(w):
                vc2[u] = _valid_bit(nxt[u])
        j = v % blk
        for u in range(w):
            vflags[u * blk + j] = _flag(vc0[u], vc1[u], vc2[u])
        vc0, vc1, vc2 = vc1, vc2, vc0
        if j == blk - 1 or v == h - 2:  # row prefix sums of the buffered rows, stored transposed
            first = v - j
            nb = j + 1
            # rv[u + 1] = rv[u] + the flags of column u, with _add_row (compiled for ch already):
            # an int32 accumulator row here cost a first run its own np.empty signature and loops,
            # 2.30 -> 2.15 s compiling this kernel (median of 4, #13); same sums, same warm time
            for u in range(w):
                _add_row(rv[u + 1, first : first + nb], rv[u, first : first + nb], vflags[u * blk : u * blk + nb], nb)


@njit(cache=True, inline="always")
def _quick_reject(zp, u0, v0, u1, v1, tol):
    """True when no plane can fit the rect within ``tol`` (exact necessary condition).

    For any affine f, f(a) + f(b) = f(c) + f(d) whenever a + b = c + d; with residuals bounded by
    tol the same sums differ by at most 4 tol. Checks the corner twist and the corners against the
    middle pixels, so creases and curvature are rejected without a full pass over the rect.
    """
    ua = u0
    ub = u1 - 1
    va = v0
    vb = v1 - 1
    lim = 4.0 * tol
    if abs(zp[va, ua] + zp[vb, ub] - zp[va, ub] - zp[vb, ua]) > lim:
        return True
    um = (ua + ub) // 2
    vm = (va + vb) // 2
    un = ua + ub - um
    vn = va + vb - vm
    if abs(zp[va, ua] + zp[vb, ub] - zp[vm, um] - zp[vn, un]) > lim:
        return True
    if abs(zp[va, ub] + zp[vb, ua] - zp[vm, un] - zp[vn, um]) > lim:
        return True
    if abs(zp[va, ua] + zp[va, ub] - zp[va, um] - zp[va, un]) > lim:
        return True
    if abs(zp[vb, ua] + zp[vb, ub] - zp[vb, um] - zp[vb, un]) > lim:
        return True
    if abs(zp[va, ua] + zp[vb, ua] - zp[vm, ua] - zp[vn, ua]) > lim:
        return True
    if abs(zp[va, ub] + zp[vb, ub] - zp[vm, ub] - zp[vn, ub]) > lim:
        return True
    return False


@njit(cache=True)
def _add_abs_second_diff(acc, line, n):
    """acc[i] += |line[i-1] - 2 line[i] + line[i+1]| for i = 1..n-2 (a separate kernel on 1-D
    views, so that the loop vectorizes)."""
    for i in range(1, n - 1):
        acc[i] += abs(line[i - 1] - 2.0 * line[i] + line[i + 1])


def crease_split(zp, u0, v0, u1, v1, peak):
    """Where to split a break-free rect whose plane fit failed: ``(direction, line)``.

    Per column (direction 0) and per row (direction 1) the mean |centered second difference|
    inside the rect is computed. When the most bent line stands out — its mean exceeds ``peak``
    times the average over the lines of that direction — it is a crease too shallow to be a break
    edge, and the rect is cut there (ties: the first line). Profiles use every
    ``max(1, extent // CREASE_SAMPLES)``-th pixel along the line, so the cost per failed fit is
    O((w + h) * CREASE_SAMPLES) rather than O(w * h). Otherwise (smooth curvature, or a
    rect too thin for a stencil) the rect is cut in the middle of its longer side.
    """
    return _crease_split_kernel(zp, np.int64(u0), np.int64(v0), np.int64(u1), np.int64(v1), peak,
                                np.empty(zp.shape[1], np.float64))


@njit(cache=True, inline="always")
def _crease_split_kernel(zp, u0, v0, u1, v1, peak, col_sum):
    """:func:`crease_split` with a scratch row ``col_sum`` (W,) float64 for the column profile
    (allocated by the caller, once per split: an allocation in a kernel cost a first run
    0.1-0.2 s of compiling, #13). Written plainly: keeping line sums between the calls of one
    split, and rolling row buffers, ran the meshes 3-5 % faster but cost a first run 0.29 s of
    compiling (median of five)."""
    w = u1 - u0
    h = v1 - v0
    sv = max(1, h // CREASE_SAMPLES)  # lines are sampled: at most ~CREASE_SAMPLES per profile
    su = max(1, w // CREASE_SAMPLES)
    nsv = (h + sv - 1) // sv
    nsu = (w + su - 1) // su
    best_u = -1.0
    cu = -1
    tot_u = 0.0
    if w >= 3:
        acc = col_sum[u0:u1]
        acc[:] = 0.0
        for v in range(v0, v1, sv):
            _add_abs_second_diff(acc, zp[v, u0:u1], w)
        for c in range(u0 + 1, u1 - 1):
            m = col_sum[c] / nsv
            tot_u += m
            if m > best_u:
                best_u = m
                cu = c
        if not best_u > peak * tot_u / (w - 2):
            cu = -1
    best_v = -1.0
    cv = -1
    tot_v = 0.0
    if h >= 3:
        for r in range(v0 + 1, v1 - 1):
            s = 0.0
            for i in range(nsu):
                u = u0 + i * su
                s += abs(zp[r - 1, u] - 2.0 * zp[r, u] + zp[r + 1, u])
            m = s / nsu
            tot_v += m
            if m > best_v:
                best_v = m
                cv = r
        if not best_v > peak * tot_v / (h - 2):
            cv = -1
    if cu >= 0 and (cv < 0 or best_u >= best_v):
        return 0, cu
    if cv >= 0:
        return 1, cv
    if w >= h:
        return 0, u0 + w // 2
    return 1, v0 + h // 2


def split_edges(zp, ch, rv, tol, first_dir, peak):
    """Edge-aware, error-bounded binary split.

    ``ch``/``rv`` are the break-edge prefix sums of :func:`edge_prefix`. A region with break edges
    inside is split along the grid line that carries the most of them (ties: nearest the middle),
    in the alternating direction when that direction holds any break, else in the other one. A
    break-free region is either all invalid (dropped: an invalid/valid pair is always a break) or
    all valid; it is kept when it is one pixel or when the least-squares plane of ``zp`` over it
    has max |residual| <= ``tol``, else split at its most bent line (:func:`crease_split`).

    Returns (Q, 4) int32 rects in depth-first order (low child first).
    """
    h, w = zp.shape
    cap = h * w + 1
    out = np.empty((cap, 4), np.int32)  # buffers allocated here, not in the kernel (#13)
    stack = np.empty((cap + 1, 5), np.int32)
    n = _split_edges_kernel(zp, ch, rv, tol, int(first_dir), peak, out, stack, np.empty(w, np.float64))
    return out[:n].copy()


@njit(cache=True)
def _split_edges_kernel(zp, ch, rv, tol, first_dir, peak, out, stack, col_sum):
    """:func:`split_edges` into ``out`` (capacity H W + 1 rects, ``stack`` one more); returns the
    number of rects."""
    h, w = zp.shape
    stack[0, 0] = 0
    stack[0, 1] = 0
    stack[0, 2] = w
    stack[0, 3] = h
    stack[0, 4] = first_dir
    top = 1
    n = 0
    while top > 0:
        top -= 1
        u0 = stack[top, 0]
        v0 = stack[top, 1]
        u1 = stack[top, 2]
        v1 = stack[top, 3]
        d = stack[top, 4]
        # break counts per grid line inside the region, best line of each direction
        nh = 0
        best_h = 0
        dist_h = 1 << 30
        split_h = -1
        mid2 = u0 + u1
        for k in range(u0 + 1, u1):
            cnt = ch[v1, k - 1] - ch[v0, k - 1]
            if cnt > 0:
                nh += cnt
                dist = abs(2 * k - mid2)
                if cnt > best_h or (cnt == best_h and dist < dist_h):
                    best_h = cnt
                    dist_h = dist
                    split_h = k
        nv = 0
        best_v = 0
        dist_v = 1 << 30
        split_v = -1
        mid2 = v0 + v1
        for k in range(v0 + 1, v1):
            cnt = rv[u1, k - 1] - rv[u0, k - 1]
            if cnt > 0:
                nv += cnt
                dist = abs(2 * k - mid2)
                if cnt > best_v or (cnt == best_v and dist < dist_v):
                    best_v = cnt
                    dist_v = dist
                    split_v = k
        if nh + nv > 0:
            if d == 0 and nh == 0:
                d = 1
            elif d == 1 and nv == 0:
                d = 0
            split = split_h if d == 0 else split_v
        else:
            if not np.isfinite(zp[v0, u0]):
                continue  # break-free and invalid: the whole region is invalid
            area = (u1 - u0) * (v1 - v0)
            if area == 1 or (
                not _quick_reject(zp, u0, v0, u1, v1, tol) and rect_fit_within(zp, u0, v0, u1, v1, tol)
            ):
                out[n, 0] = u0
                out[n, 1] = v0
                out[n, 2] = u1
                out[n, 3] = v1
                n += 1
                continue
            d, split = _crease_split_kernel(zp, u0, v0, u1, v1, peak, col_sum)
        _push_children(stack, top, u0, v0, u1, v1, d, split)
        top += 2
    return n
