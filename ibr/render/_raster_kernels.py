"""numba kernels behind :mod:`ibr.render` and :mod:`ibr.render.forward` (private; no validation here).

Pixel convention: pixel (u, v) = (column, row), centers at integer coordinates, the image spans
[-0.5, W - 0.5] x [-0.5, H - 0.5]. Quad rect ``[u0, v0, u1, v1]`` covers source pixels
``u0 .. u1-1`` x ``v0 .. v1-1``; its pixel-edge outline is ``[u0-0.5, u1-0.5) x [v0-0.5, v1-0.5)``.

Quad rasterization (inverse warp, seed 002 section 2.1 with an exact homography)
---------------------------------------------------------------------------------
For a quad with source plane ``n . X_s = 1`` and the rigid map ``X_s = R X_t + T``
(``R, T`` = ``src_from_tgt``), a target pixel ``p = (u, v, 1)`` with ray ``d = Kt^-1 p`` meets the
plane at ``z_t = m / (n . R d)`` with ``m = 1 - n . T``. Hence

* ``1/z_t = g . p`` with ``g = (Kt^-T R^T n) / m``  (affine in target pixels), and
* ``X_s / z_t = (R Kt^-1 + T g^T) p``, so the source pixel is ``Hp / (Hp)_z`` with
  ``H = Ks (R Kt^-1 + T g^T)``, a 3x3 homography, and ``(Hp)_z = z_s / z_t``.

``m <= 0`` means the target camera is on the back side of the plane (back-facing or edge-on quad):
the quad is culled. A target pixel is covered when ``g.p > 0`` (in front of the target camera),
``(Hp)_z > 0`` (in front of the source camera) and the source point lies in the half-open pixel-edge
outline of the rect. The half-open test is the fill rule: it is evaluated as the sign of four linear
forms (``Hx - (u0-.5) Hz >= 0``, ``Hx - (u1-.5) Hz < 0``, same for rows), so two coplanar quads that
share an edge evaluate the *same* linear form with opposite strictness and cover every target
pixel exactly once (no crack, no double cover) -- the source-space equivalent of the top-left rule.
"""

from __future__ import annotations

import numpy as np
from ..base.jit import njit, prange

__all__: list[str] = []

# Every kernel uses error_model="numpy": a division by zero gives inf/NaN (which the kernels
# test for) instead of numba's default Python-style check and exception on every division.
# The callees are nogil like the kernels that call them: numba compiles the builtins a kernel
# uses (min, max, int) once per set of options in a process, and the first-run helper compiled
# them twice (0.07 s, #13); the fill kernels it compiles after them share the same options.

# Layout of the per-quad coefficient rows computed by setup_quads (12 float64 per quad).
_G, _HX, _HY, _HZ = 0, 3, 6, 9


@njit(cache=True, error_model="numpy", nogil=True)
def _corner_tgt(uc, vc, a, b, c, ifx, ify, cx, cy, r, t):
    """Target-frame point of the source pixel-edge corner (uc, vc) on the plane 1/z = a u + b v + c
    (ifx, ify: reciprocal source focal lengths)."""
    w = a * uc + b * vc + c
    if not (w > 0.0):
        return 0.0, 0.0, 0.0, False
    zs = 1.0 / w
    xs = (uc - cx) * ifx * zs - t[0]
    ys = (vc - cy) * ify * zs - t[1]
    zs = zs - t[2]
    # X_t = R^T (X_s - T)
    x = r[0, 0] * xs + r[1, 0] * ys + r[2, 0] * zs
    y = r[0, 1] * xs + r[1, 1] * ys + r[2, 1] * zs
    z = r[0, 2] * xs + r[1, 2] * ys + r[2, 2] * zs
    return x, y, z, True


@njit(cache=True, error_model="numpy", inline="always")
def _grow(x, y, z, kt, lim, umin, umax, vmin, vmax):
    iz = 1.0 / z
    uu = min(max(kt[0] * x * iz + kt[2], -lim), lim)
    vv = min(max(kt[1] * y * iz + kt[3], -lim), lim)
    return min(umin, uu), max(umax, uu), min(vmin, vv), max(vmax, vv)


@njit(cache=True, error_model="numpy", nogil=True)
def _clip_edge(xa, ya, za, xb, yb, zb, eps, kt, lim, umin, umax, vmin, vmax):
    """Grow the projected bounding box by edge a->b clipped to z > eps (Sutherland-Hodgman:
    the start vertex if in front, plus the crossing point with z = eps)."""
    ina = za > eps
    if ina:
        umin, umax, vmin, vmax = _grow(xa, ya, za, kt, lim, umin, umax, vmin, vmax)
    if ina != (zb > eps):
        s = (eps - za) / (zb - za)
        umin, umax, vmin, vmax = _grow(xa + s * (xb - xa), ya + s * (yb - ya), eps, kt, lim, umin, umax, vmin, vmax)
    return umin, umax, vmin, vmax


def _setup_quads(q0, q1, rects, planes, ks, r, t, kt_inv, kt, width, height, coef, bbox):
    """Per-quad homography rows and target bounding boxes.

    ks, kt: (4,) fx, fy, cx, cy of source / target; r (3,3), t (3,) src_from_tgt; kt_inv (3,3).
    Writes coef (Q, 12) = [g, Hx, Hy, Hz] rows and bbox (Q, 4) int32 [ulo, vlo, uhi, vhi]
    (inclusive pixel-center ranges; ulo > uhi marks a culled or invisible quad). Quads
    ``q0 .. q1-1`` only (:func:`ibr.render.bands.run_bands` splits them over the threads).
    """
    fx, fy, cx, cy = ks[0], ks[1], ks[2], ks[3]
    ifx, ify = 1.0 / fx, 1.0 / fy
    for q in range(q0, q1):
        a, b, c = planes[q, 0], planes[q, 1], planes[q, 2]
        n0 = a * fx
        n1 = b * fy
        n2 = a * cx + b * cy + c
        m = 1.0 - (n0 * t[0] + n1 * t[1] + n2 * t[2])
        bbox[q, 0] = 1
        bbox[q, 2] = 0
        bbox[q, 1] = 1
        bbox[q, 3] = 0
        # relative edge-on test: |n.T| and 1 are the two terms of m
        if not (m > 1e-9):
            continue
        # R^T n
        rn0 = r[0, 0] * n0 + r[1, 0] * n1 + r[2, 0] * n2
        rn1 = r[0, 1] * n0 + r[1, 1] * n1 + r[2, 1] * n2
        rn2 = r[0, 2] * n0 + r[1, 2] * n1 + r[2, 2] * n2
        # g = Kt^-T (R^T n) / m
        im = 1.0 / m
        for j in range(3):
            coef[q, _G + j] = (kt_inv[0, j] * rn0 + kt_inv[1, j] * rn1 + kt_inv[2, j] * rn2) * im
        # M = R Kt^-1 + T g^T ; H = Ks M
        for j in range(3):
            g = coef[q, _G + j]
            m0 = r[0, 0] * kt_inv[0, j] + r[0, 1] * kt_inv[1, j] + r[0, 2] * kt_inv[2, j] + t[0] * g
            m1 = r[1, 0] * kt_inv[0, j] + r[1, 1] * kt_inv[1, j] + r[1, 2] * kt_inv[2, j] + t[1] * g
            m2 = r[2, 0] * kt_inv[0, j] + r[2, 1] * kt_inv[1, j] + r[2, 2] * kt_inv[2, j] + t[2] * g
            coef[q, _HX + j] = fx * m0 + cx * m2
            coef[q, _HY + j] = fy * m1 + cy * m2
            coef[q, _HZ + j] = m2
        # --- bounding box of the quad outline projected into the target, clipped at z_t > eps
        u0 = rects[q, 0] - 0.5
        v0 = rects[q, 1] - 0.5
        u1 = rects[q, 2] - 0.5
        v1 = rects[q, 3] - 0.5
        x0, y0, z0, ok0 = _corner_tgt(u0, v0, a, b, c, ifx, ify, cx, cy, r, t)
        x1, y1, z1, ok1 = _corner_tgt(u1, v0, a, b, c, ifx, ify, cx, cy, r, t)
        x2, y2, z2, ok2 = _corner_tgt(u1, v1, a, b, c, ifx, ify, cx, cy, r, t)
        x3, y3, z3, ok3 = _corner_tgt(u0, v1, a, b, c, ifx, ify, cx, cy, r, t)
        if not (ok0 and ok1 and ok2 and ok3):
            # the plane reaches the source camera plane inside the outline: no finite corners,
            # test the whole target image (the per-pixel tests stay exact)
            umin, vmin, umax, vmax = -1.0, -1.0, float(width), float(height)
        else:
            # clip a hair in front of the target camera: 1e-7 of the corner nearest to its plane,
            # in front or behind (the part between the plane and eps projects beyond the clamp
            # anyway). Relative to the farthest corner, a ground plane whose horizon ran along the
            # quad's edge (corners at 4e8) was clipped at z = 40: its visible part, one row drawn
            zabs = np.inf
            for zc in (z0, z1, z2, z3):
                if zc != 0.0 and abs(zc) < zabs:
                    zabs = abs(zc)
            eps = 1e-7 * zabs if zabs < np.inf else 0.0
            lim = 4.0 * (width + height) + 16.0
            umin, umax, vmin, vmax = np.inf, -np.inf, np.inf, -np.inf
            umin, umax, vmin, vmax = _clip_edge(x0, y0, z0, x1, y1, z1, eps, kt, lim, umin, umax, vmin, vmax)
            umin, umax, vmin, vmax = _clip_edge(x1, y1, z1, x2, y2, z2, eps, kt, lim, umin, umax, vmin, vmax)
            umin, umax, vmin, vmax = _clip_edge(x2, y2, z2, x3, y3, z3, eps, kt, lim, umin, umax, vmin, vmax)
            umin, umax, vmin, vmax = _clip_edge(x3, y3, z3, x0, y0, z0, eps, kt, lim, umin, umax, vmin, vmax)
            if not (umin <= umax):
                continue  # entirely behind the target camera
        # inclusive pixel-center range, with a tiny margin against rounding (the exact
        # per-pixel tests decide coverage)
        ulo = max(int(np.ceil(umin - 1e-6)), 0)
        uhi = min(int(np.floor(umax + 1e-6)), width - 1)
        vlo = max(int(np.ceil(vmin - 1e-6)), 0)
        vhi = min(int(np.floor(vmax + 1e-6)), height - 1)
        bbox[q, 0] = ulo
        bbox[q, 1] = vlo
        bbox[q, 2] = uhi
        bbox[q, 3] = vhi


#: compiled serially and run in pieces by ibr.render.bands (parallel=True left numba's worker
#: threads spinning next to the rasterizer's row bands: 0.5 ms more per motorcycle warp)
setup_quads = njit(cache=True, error_model="numpy", nogil=True)(_setup_quads)


@njit(cache=True, error_model="numpy", nogil=True)
def _span(e0, e1, e2, v, strict, lo, hi, slo, shi):
    """Narrow the integer range [lo, hi] to u with e0*u + e1*v + e2 >= 0 (> 0 if strict),
    conservatively (one pixel of slack; the exact test is per pixel), and [slo, shi] to the u
    that pass for sure: at least one pixel inside the crossing x = -(e1 v + e2) / e0, where the
    form is >= |e0| (rounding of x and of the per-pixel form is ~1e-7 |e0| even at the 1e9
    clamp), so the per-pixel tests can be skipped there with the same result."""
    cst = e1 * v + e2
    if e0 > 0.0:
        x = -cst / e0
        if x == x:  # not NaN
            b = int(np.floor(max(min(x, 1e9), -1e9)))
            lo = max(lo, b - 1)
            slo = max(slo, b + 2)
        else:
            shi = slo - 1
    elif e0 < 0.0:
        x = -cst / e0
        if x == x:
            b = int(np.ceil(max(min(x, 1e9), -1e9)))
            hi = min(hi, b + 1)
            shi = min(shi, b - 2)
        else:
            shi = slo - 1
    elif e0 == 0.0:  # the form is cst at every u: all pass or none (cst = 0 or NaN: no pixel is sure)
        if cst < 0.0 or (strict and cst == 0.0):
            hi = lo - 1
        if not (cst > 0.0):
            shi = slo - 1
    else:  # e0 NaN (an overflowed quad): every exact test fails
        hi = lo - 1
        shi = slo - 1
    return lo, hi, slo, shi


def bucket_bands(bbox, height, nbands):
    """Counting sort of visible quads into horizontal bands of target rows.

    Returns (start (nbands + 1,) int64, quads (N,) int32): band k holds quads
    ``quads[start[k]:start[k+1]]`` in increasing quad order (a quad spanning several bands is
    listed in each). numpy, not a kernel: a stable sort of the (quad, band) pairs by band (radix
    sort on int16) costs 0.02-0.06 ms more per frame for 1,500-20,000 quads, and the kernel cost a
    first run 0.16-0.28 s of compiling (#13).
    """
    rows_per_band = (height + nbands - 1) // nbands
    q = np.flatnonzero((bbox[:, 0] <= bbox[:, 2]) & (bbox[:, 1] <= bbox[:, 3]))
    first = (bbox[q, 1] // rows_per_band).astype(np.intp)
    n = bbox[q, 3] // rows_per_band + 1 - first  # bands per visible quad
    ends = np.cumsum(n)
    band = np.arange(ends[-1] if len(ends) else 0) - np.repeat(ends - n - first, n)  # first, first + 1, ...
    band = band.astype(np.int16 if nbands <= 32767 else np.int32)
    quads = np.repeat(q.astype(np.int32), n)[np.argsort(band, kind="stable")]
    start = np.zeros(nbands + 1, np.int64)
    np.cumsum(np.bincount(band, minlength=nbands), out=start[1:])
    return start, quads


def _raster_quads(band0, band1, rects, coef, bbox, clamp, width, height, band_start, band_quads, far_coord,
                  crack_rel, src_qop, depth, map_u, map_v, coverage):
    """Z-buffered rasterization of quads into source-coordinate maps, one band of target rows
    per parallel task (each band owns its rows: no write races).

    depth (H, W) float32 serves as the z-buffer of 1/z_t while rasterizing and receives z_t
    (NaN where uncovered) at the end; map_u/map_v (H, W) float32 receive the source pixel
    coordinates of the nearest quad per target pixel (far_coord where uncovered); coverage (H, W)
    bool. clamp (Q, 4) uint8 flags [left, top, right, bottom]: when set, the sample position is
    clamped to the rect's outer pixel *centers* on that side so that bilinear sampling never
    reads across a depth edge. crack_rel > 0 closes one-pixel cracks along rows: an uncovered
    pixel between two covered row neighbours whose depths are within ``crack_rel`` of the nearer
    takes their mean map coordinates and the mean of their inverse depths (two neighbouring
    quads of a curved surface have different planes, so their shared edge can open by a pixel
    in another view), if the source pixel at those mean coordinates belongs to one of the two
    neighbours' quads (``src_qop``: the source mesh's quad of each pixel): behind a one-pixel pole
    the wall's two sides agree, but halfway between their samples is the pole; 0 leaves them.
    """
    nbands = band_start.shape[0] - 1
    rows_per_band = (height + nbands - 1) // nbands
    # _span's strictness as run-time booleans: the literals True / False compiled one _span each,
    # and int32 bounds a third (0.26 s each on a first run, #13)
    strict, loose = np.bool_(True), np.bool_(False)
    for band in range(band0, band1):
        r0 = band * rows_per_band
        r1 = min(height, r0 + rows_per_band)
        inv_z = depth
        for v in range(r0, r1):
            izrow = inv_z[v]
            for u in range(width):
                izrow[u] = 0.0
        for k in range(band_start[band], band_start[band + 1]):
            q = band_quads[k]
            ulo, vlo, uhi, vhi = np.int64(bbox[q, 0]), np.int64(bbox[q, 1]), np.int64(bbox[q, 2]), np.int64(bbox[q, 3])
            g0, g1, g2 = coef[q, 0], coef[q, 1], coef[q, 2]
            hx0, hx1, hx2 = coef[q, 3], coef[q, 4], coef[q, 5]
            hy0, hy1, hy2 = coef[q, 6], coef[q, 7], coef[q, 8]
            hz0, hz1, hz2 = coef[q, 9], coef[q, 10], coef[q, 11]
            eu0 = rects[q, 0] - 0.5
            ev0 = rects[q, 1] - 0.5
            eu1 = rects[q, 2] - 0.5
            ev1 = rects[q, 3] - 0.5
            # four edge forms E = Hx - e*Hz (columns) / Hy - e*Hz (rows)
            l0, l1, l2 = hx0 - eu0 * hz0, hx1 - eu0 * hz1, hx2 - eu0 * hz2  # >= 0
            rr0, rr1, rr2 = hx0 - eu1 * hz0, hx1 - eu1 * hz1, hx2 - eu1 * hz2  # < 0
            t0, t1, t2 = hy0 - ev0 * hz0, hy1 - ev0 * hz1, hy2 - ev0 * hz2  # >= 0
            b0, b1, b2 = hy0 - ev1 * hz0, hy1 - ev1 * hz1, hy2 - ev1 * hz2  # < 0
            cl = clamp[q, 0] != 0
            ct = clamp[q, 1] != 0
            cr = clamp[q, 2] != 0
            cb = clamp[q, 3] != 0
            su0 = float(rects[q, 0])
            sv0 = float(rects[q, 1])
            su1 = float(rects[q, 2] - 1)
            sv1 = float(rects[q, 3] - 1)
            for v in range(max(vlo, r0), min(vhi + 1, r1)):
                fv = float(v)
                lo, hi = ulo, uhi
                slo, shi = 1, 0  # the pixels that pass all six tests for sure (none known)
                if hi - lo > 6:  # narrow long rows analytically; tiny quads test every pixel
                    slo, shi = lo, hi
                    lo, hi, slo, shi = _span(g0, g1, g2, fv, strict, lo, hi, slo, shi)
                    lo, hi, slo, shi = _span(hz0, hz1, hz2, fv, strict, lo, hi, slo, shi)
                    lo, hi, slo, shi = _span(l0, l1, l2, fv, loose, lo, hi, slo, shi)
                    lo, hi, slo, shi = _span(-rr0, -rr1, -rr2, fv, strict, lo, hi, slo, shi)
                    lo, hi, slo, shi = _span(t0, t1, t2, fv, loose, lo, hi, slo, shi)
                    lo, hi, slo, shi = _span(-b0, -b1, -b2, fv, strict, lo, hi, slo, shi)
                    lo = max(lo, ulo)
                    hi = min(hi, uhi)
                gv = g1 * fv + g2
                xv = hx1 * fv + hx2
                yv = hy1 * fv + hy2
                zv = hz1 * fv + hz2
                lv, rv, tv, bv = l1 * fv + l2, rr1 * fv + rr2, t1 * fv + t2, b1 * fv + b2
                izrow, murow, mvrow = inv_z[v], map_u[v], map_v[v]
                for u in range(lo, hi + 1):
                    fu = float(u)
                    iz = g0 * fu + gv
                    if not (iz > izrow[u]):
                        continue
                    hz = hz0 * fu + zv
                    if u < slo or u > shi:  # near the outline: the exact tests (the fill rule)
                        if not (hz > 0.0):
                            continue
                        if not (l0 * fu + lv >= 0.0 and rr0 * fu + rv < 0.0):
                            continue
                        if not (t0 * fu + tv >= 0.0 and b0 * fu + bv < 0.0):
                            continue
                    ihz = 1.0 / hz  # one division (3 % of the kernel)
                    us = (hx0 * fu + xv) * ihz
                    vs = (hy0 * fu + yv) * ihz
                    if cl and us < su0:
                        us = su0
                    if cr and us > su1:
                        us = su1
                    if ct and vs < sv0:
                        vs = sv0
                    if cb and vs > sv1:
                        vs = sv1
                    izrow[u] = iz
                    murow[u] = us
                    mvrow[u] = vs
        for v in range(r0, r1):
            drow, crow, murow, mvrow = depth[v], coverage[v], map_u[v], map_v[v]
            for u in range(width):  # branch-free, so that it vectorizes (8 % of the kernel)
                iz = drow[u]
                cov = iz > 0.0
                drow[u] = 1.0 / iz if cov else np.float32(np.nan)
                crow[u] = cov
                murow[u] = murow[u] if cov else far_coord
                mvrow[u] = mvrow[u] if cov else far_coord
            if crack_rel > 0.0:
                _close_row_cracks(drow, crow, murow, mvrow, width, crack_rel, src_qop)


@njit(cache=True, error_model="numpy", nogil=True)
def _quad_at(qop, x, y):
    """The source mesh's quad at the nearest pixel of (x, y) (clamped to the image; -1: none)."""
    h, w = qop.shape
    return qop[min(max(int(np.floor(y + 0.5)), 0), h - 1), min(max(int(np.floor(x + 0.5)), 0), w - 1)]


@njit(cache=True, error_model="numpy", inline="always")
def _crack_between(za, zb, ua, va, ub, vb, rel, qop):
    """Whether the gap between two covered target pixels (depths za, zb; source coordinates
    (ua, va), (ub, vb)) is a crack of one surface: their depths agree within ``rel`` and the
    source pixel halfway between their samples belongs to one of their two quads (``qop``: the
    source mesh's quad of each pixel), not to a thin object in front of them. (Testing the
    halfway pixel's plane instead closed the same cracks but made the raster kernel's first
    compile 0.3 s longer, #13.)"""
    if not (abs(za - zb) <= rel * min(za, zb)):
        return False
    qm = _quad_at(qop, 0.5 * (ua + ub), 0.5 * (va + vb))
    return qm >= 0 and (qm == _quad_at(qop, 1.0 * ua, 1.0 * va) or qm == _quad_at(qop, 1.0 * ub, 1.0 * vb))


@njit(cache=True, error_model="numpy", inline="always")
def _close_row_cracks(drow, crow, murow, mvrow, width, rel, qop):
    """One-pixel cracks of one target row closed (see :func:`_raster_quads`, ``crack_rel``)."""
    for u in range(1, width - 1):
        if crow[u] or not (crow[u - 1] and crow[u + 1]):
            continue
        zl = drow[u - 1]
        zr = drow[u + 1]
        if _crack_between(zl, zr, murow[u - 1], mvrow[u - 1], murow[u + 1], mvrow[u + 1], rel, qop):
            drow[u] = 2.0 / (1.0 / zl + 1.0 / zr)
            murow[u] = 0.5 * (murow[u - 1] + murow[u + 1])
            mvrow[u] = 0.5 * (mvrow[u - 1] + mvrow[u + 1])
            crow[u] = True


#: Bands ``band0 .. band1-1`` without the GIL: :func:`ibr.render.bands.run_bands` runs bands on all
#: cores (compiled serially: a third of the parallel=True compile time, #13)
raster_quads = njit(cache=True, error_model="numpy", nogil=True)(_raster_quads)


@njit(cache=True, error_model="numpy")
def _off_plane(inv, uu, vv, a, b, c, rel_tol):
    p = a * uu + b * vv + c
    q = inv[vv, uu]
    return not (q > 0.0) or abs(q - p) > rel_tol * abs(p)


@njit(cache=True, error_model="numpy")
def clamp_flags(rects, planes, inv, rel_tol, out):
    """Per quad and side [left, top, right, bottom]: 1 when any source pixel just outside that
    side is outside the image, has no depth (``inv <= 0``), or has an inverse depth ``inv`` off
    the quad's plane by more than ``rel_tol`` (a depth edge), so bilinear sampling must not read
    across it."""
    h, w = inv.shape
    for q in prange(rects.shape[0]):
        u0, v0, u1, v1 = rects[q, 0], rects[q, 1], rects[q, 2], rects[q, 3]
        a, b, c = planes[q, 0], planes[q, 1], planes[q, 2]
        # sides: 0 left (column u0-1), 1 top (row v0-1), 2 right (column u1), 3 bottom (row v1)
        for side in range(4):
            vertical = side == 0 or side == 2
            if vertical:
                fixed = u0 - 1 if side == 0 else u1
                inside = 0 <= fixed < w
                lo, hi = v0, v1
            else:
                fixed = v0 - 1 if side == 1 else v1
                inside = 0 <= fixed < h
                lo, hi = u0, u1
            flag = 0
            if not inside:
                flag = 1
            else:
                for k in range(lo, hi):
                    uu = fixed if vertical else k
                    vv = k if vertical else fixed
                    if _off_plane(inv, uu, vv, a, b, c, rel_tol):
                        flag = 1
                        break
            out[q, side] = flag
