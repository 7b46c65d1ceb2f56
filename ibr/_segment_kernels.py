"""numba kernels for :mod:`ibr.segment` and :mod:`ibr.mesh` (private; wrappers validate inputs).

All kernels take C-contiguous arrays; invalid depth is NaN in the float inputs. Pixel (u, v) =
(column, row) is element ``[v, u]``. Plain numpy/Python references live in :mod:`ibr.segment`
(``*_reference``) and the tests compare the two.
"""

from __future__ import annotations

import numpy as np
from numba import njit

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


@njit(cache=True)
def inv_depth_range(z):
    """(q, zmin, zmax, count): q = 1/z as float64 (NaN where z is not finite or <= 0) and the
    range and count of the valid depth, in one pass. (nan, nan, 0) range when nothing is valid."""
    h, w = z.shape
    q = np.empty((h, w), np.float64)
    lo = np.inf
    hi = -np.inf
    n = 0
    for v in range(h):
        for u in range(w):
            x = np.float64(z[v, u])
            if x > 0 and x < np.inf:  # False for NaN
                q[v, u] = 1.0 / x
                n += 1
                lo = min(lo, x)
                hi = max(hi, x)
            else:
                q[v, u] = np.nan
    if n == 0:
        return q, np.nan, np.nan, 0
    return q, lo, hi, n


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
        # push the high child first so that the low child is processed first
        if d == 0:
            stack[top, 0] = split
            stack[top, 1] = v0
            stack[top, 2] = u1
            stack[top, 3] = v1
            stack[top, 4] = 1
            stack[top + 1, 0] = u0
            stack[top + 1, 1] = v0
            stack[top + 1, 2] = split
            stack[top + 1, 3] = v1
            stack[top + 1, 4] = 1
        else:
            stack[top, 0] = u0
            stack[top, 1] = split
            stack[top, 2] = u1
            stack[top, 3] = v1
            stack[top, 4] = 0
            stack[top + 1, 0] = u0
            stack[top + 1, 1] = v0
            stack[top + 1, 2] = u1
            stack[top + 1, 3] = split
            stack[top + 1, 4] = 0
        top += 2
    return out[:n].copy()


# ------------------------------------------------------------------ plane fit


@njit(cache=True)
def rect_fit_max_residual(zp, u0, v0, u1, v1, limit):
    """Max |residual| of the least-squares plane of ``zp`` over a full rect (all finite).

    Over a full rectangle the normal equations decouple in centered coordinates:
    ``a = S(z du) / S(du^2)``, ``b = S(z dv) / S(dv^2)``, ``c = mean(z)``. Stops early (returning
    a value > ``limit``) as soon as a residual exceeds ``limit``.
    """
    w = u1 - u0
    h = v1 - v0
    uc = 0.5 * (u0 + u1 - 1)
    vc = 0.5 * (v0 + v1 - 1)
    s = 0.0
    su = 0.0
    sv = 0.0
    for v in range(v0, v1):
        dv = v - vc
        for u in range(u0, u1):
            z = zp[v, u]
            s += z
            su += z * (u - uc)
            sv += z * dv
    n = w * h
    c = s / n
    suu = h * w * (w * w - 1) / 12.0
    svv = w * h * (h * h - 1) / 12.0
    a = su / suu if w > 1 else 0.0
    b = sv / svv if h > 1 else 0.0
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
def fit_planes_inv_depth(q, rects):
    """(Q, 3) least-squares planes ``q(u, v) = a u + b v + c`` over each rect (absolute coords).

    A one-pixel rect gets a = b = 0, c = q(center); a one-pixel-thick rect gets a zero slope
    across its thickness. Rects must hold finite values only.
    """
    nq = rects.shape[0]
    out = np.empty((nq, 3), np.float64)
    for i in range(nq):
        u0 = rects[i, 0]
        v0 = rects[i, 1]
        u1 = rects[i, 2]
        v1 = rects[i, 3]
        w = u1 - u0
        h = v1 - v0
        uc = 0.5 * (u0 + u1 - 1)
        vc = 0.5 * (v0 + v1 - 1)
        s = 0.0
        su = 0.0
        sv = 0.0
        for v in range(v0, v1):
            dv = v - vc
            for u in range(u0, u1):
                z = q[v, u]
                s += z
                su += z * (u - uc)
                sv += z * dv
        c = s / (w * h)
        a = su / (h * w * (w * w - 1) / 12.0) if w > 1 else 0.0
        b = sv / (w * h * (h * h - 1) / 12.0) if h > 1 else 0.0
        out[i, 0] = a
        out[i, 1] = b
        out[i, 2] = c - a * uc - b * vc
    return out


@njit(cache=True)
def label_rects(rects, h, w):
    """(H, W) int32 index of the rect covering each pixel, -1 elsewhere."""
    lab = np.full((h, w), -1, np.int32)
    for i in range(rects.shape[0]):
        for v in range(rects[i, 1], rects[i, 3]):
            for u in range(rects[i, 0], rects[i, 2]):
                lab[v, u] = i
    return lab


# ------------------------------------------------------------------ binary split (edge-aware)


def edge_prefix(zp, thr):
    """Prefix sums of the break edges of :func:`edge_breaks` (single-threaded: on a shared
    2-core machine numba's parallel kernels measured slower than serial ones).

    Returns ``ch`` (H+1, W-1) int32 with ``ch[v, u] = sum(hb[:v, u])`` (breaks across the vertical
    grid line between columns u and u+1, rows above v) and ``rv`` (W+1, H-1) int32 with
    ``rv[u, v] = sum(vb[v, :u])`` (stored transposed so a scan over rows reads contiguous memory).
    """
    return _colcum_breaks(zp, thr), _rowcum_t(_vertical_breaks(zp, thr))


@njit(cache=True, inline="always")
def _stencil_state(a, c, b, thr):
    """Centered second difference a - 2c + b: 0 unavailable (a NaN sample), 1 straight, 2 bent."""
    if a == a and c == c and b == b:
        return 2 if abs(a - 2.0 * c + b) > thr else 1
    return 0


@njit(cache=True, inline="always")
def _flag(sm1, s0, s1, fa, fb):
    """Break flag of pair (i, i+1) from the stencil states at i-1, i, i+1 and the validity of
    samples i and i+1 (same rule as :func:`_pair_break`: the one-sided stencil at i is the
    centered one at i-1)."""
    if fa != fb:
        return 1
    if not fa:
        return 0
    if (s0 == 2 or s1 == 2) and s0 != 1 and s1 != 1:
        return 1
    if s0 == 2 and s1 == 1 and sm1 == 1:
        return 1
    return 0


@njit(cache=True)
def _colcum_breaks(zp, thr):
    """Column prefix sums (H+1, W-1) of the horizontal-neighbor break flags, in one pass."""
    h, w = zp.shape
    ch = np.empty((h + 1, max(w - 1, 0)), np.int32)
    st = np.zeros(w + 1, np.int8)  # st[u] = state at u; st[w] stays 0
    for u in range(w - 1):
        ch[0, u] = 0
    for v in range(h):
        for u in range(1, w - 1):
            st[u] = _stencil_state(zp[v, u - 1], zp[v, u], zp[v, u + 1], thr)
        prev = 0
        for u in range(w - 1):
            a = zp[v, u]
            b = zp[v, u + 1]
            ch[v + 1, u] = ch[v, u] + _flag(prev, st[u], st[u + 1], a == a, b == b)
            prev = st[u]
    return ch


@njit(cache=True)
def _vertical_breaks(zp, thr):
    """(H-1, W) uint8 vertical-neighbor break flags (``vb`` of :func:`edge_breaks`)."""
    h, w = zp.shape
    vb = np.empty((max(h - 1, 0), w), np.uint8)
    if h < 2:
        return vb
    s_prev = np.zeros(w, np.int8)  # states at row v - 1
    s_cur = np.zeros(w, np.int8)  # row v (0 for v = 0)
    s_next = np.zeros(w, np.int8)  # row v + 1
    for v in range(h - 1):
        if v + 2 < h:
            for u in range(w):
                s_next[u] = _stencil_state(zp[v, u], zp[v + 1, u], zp[v + 2, u], thr)
        else:
            s_next[:] = 0
        for u in range(w):
            a = zp[v, u]
            b = zp[v + 1, u]
            vb[v, u] = _flag(s_prev[u], s_cur[u], s_next[u], a == a, b == b)
        s_prev, s_cur, s_next = s_cur, s_next, s_prev
    return vb


@njit(cache=True)
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
        acc = np.zeros(w, np.float64)
        for v in range(v0, v1, sv):
            for c in range(u0 + 1, u1 - 1):
                acc[c - u0] += abs(zp[v, c - 1] - 2.0 * zp[v, c] + zp[v, c + 1])
        for c in range(u0 + 1, u1 - 1):
            m = acc[c - u0] / nsv
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
        acc = np.zeros(h, np.float64)
        for r in range(v0 + 1, v1 - 1):
            s = 0.0
            for u in range(u0, u1, su):
                s += abs(zp[r - 1, u] - 2.0 * zp[r, u] + zp[r + 1, u])
            acc[r - v0] = s
        for r in range(v0 + 1, v1 - 1):
            m = acc[r - v0] / nsu
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


@njit(cache=True)
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
    out = np.empty((cap, 4), np.int32)
    stack = np.empty((cap + 1, 5), np.int32)
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
                not _quick_reject(zp, u0, v0, u1, v1, tol)
                and rect_fit_max_residual(zp, u0, v0, u1, v1, tol) <= tol
            ):
                out[n, 0] = u0
                out[n, 1] = v0
                out[n, 2] = u1
                out[n, 3] = v1
                n += 1
                continue
            d, split = crease_split(zp, u0, v0, u1, v1, peak)
        if d == 0:
            stack[top, 0] = split
            stack[top, 1] = v0
            stack[top, 2] = u1
            stack[top, 3] = v1
            stack[top, 4] = 1
            stack[top + 1, 0] = u0
            stack[top + 1, 1] = v0
            stack[top + 1, 2] = split
            stack[top + 1, 3] = v1
            stack[top + 1, 4] = 1
        else:
            stack[top, 0] = u0
            stack[top, 1] = split
            stack[top, 2] = u1
            stack[top, 3] = v1
            stack[top, 4] = 0
            stack[top + 1, 0] = u0
            stack[top + 1, 1] = v0
            stack[top + 1, 2] = u1
            stack[top + 1, 3] = split
            stack[top + 1, 4] = 0
        top += 2
    return out[:n].copy()
