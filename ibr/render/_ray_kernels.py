"""numba kernels behind :mod:`ibr.render.ray_raster` (private; no validation here).

Target: a :class:`~ibr.base.ray_camera.SphericalCamera` given as tables -- per row
``[sin lat, cos lat, s*r(lat)]``, per column ``[sin lon, cos lon]`` -- so pixel (u, v) has the rig
frame ray ``o = s r (cos lon, 0, -sin lon)``, ``d = (cos lat sin lon, -sin lat, cos lat cos lon)``.

Per quad, in the rig frame, the source plane is ``n . X = off`` (from the source camera's
``n_cam . X_s = 1`` and ``X_s = R X + T``: ``n = R^T n_cam``, ``off = 1 - n_cam . T``); the source
camera lies on the side ``n . X < off``. A pixel's ray meets the plane at
``t = (off - n . o) / (n . d)``; the hit is kept when the ray origin is on the source camera's side
(front-facing), ``t > 0``, the hit is in front of the source camera and its source pixel lies in
the rect's half-open pixel-edge outline (the same fill rule as the pinhole rasterizer), and ``t``
beats the z-buffer (range along the unit ray).

Conservative bounds: each quad's outline is sampled along its four edges (spacing <= 3 px of angle
at the equator's scale), projected with the camera's inverse, unwrapped across the +-180 deg seam and padded;
quads over a pole (the vertical ray from the rig centre hits them) span all columns up to that
pole's row.
"""

from __future__ import annotations

import math

import numpy as np
from ..base.jit import njit

__all__: list[str] = []

_NARROW_MIN = 8  # bounds narrower than this many columns skip the per-row arc narrowing
_PAD = 1.0  # pixels of slack around the sampled outline (the curve's sagitta between samples <= 3 px apart)


@njit(cache=True, error_model="numpy", inline="always")
def _radius(lat_abs, r0, fa, fb):
    if lat_abs <= fa:
        return r0
    if lat_abs >= fb:
        return 0.0
    return r0 * 0.5 * (1.0 + math.cos(math.pi * (lat_abs - fa) / (fb - fa)))


@njit(cache=True, error_model="numpy", inline="always")
def _radius_slope(lat, r0, fa, fb):
    x = (abs(lat) - fa) / (fb - fa)
    if x <= 0.0 or x >= 1.0:
        return 0.0
    s = -r0 * 0.5 * math.pi * math.sin(math.pi * x) / (fb - fa)
    return s if lat > 0 else -s


@njit(cache=True, error_model="numpy", inline="always")
def _project(x, y, z, sign, r0, fa, fb, width, height):
    """(u, v, ok) of a rig-frame point (see SphericalCamera.project: bracketed Newton on lat)."""
    rho = math.hypot(x, z)
    alpha = math.atan2(x, z)
    lat = math.atan2(-y, rho)
    r = 0.0
    if sign != 0:
        lo, hi = -0.5 * math.pi, 0.5 * math.pi
        for _ in range(16):
            r = _radius(abs(lat), r0, fa, fb)
            s2 = max(rho * rho - r * r, 1e-300)
            sq = math.sqrt(s2)
            g = lat - math.atan2(-y, sq)
            if g < 0.0:
                lo = lat
            elif g > 0.0:
                hi = lat
            else:
                break
            dg = 1.0 + y * r * _radius_slope(lat, r0, fa, fb) / (sq * (s2 + y * y))
            step = lat - g / dg
            lat = step if lo < step < hi else 0.5 * (lo + hi)
        r = _radius(abs(lat), r0, fa, fb)
        if rho <= r:
            return 0.0, 0.0, False
        lon = alpha - math.asin(sign * r / rho)
    else:
        lon = alpha
    u = (lon / (2.0 * math.pi) + 0.5) * width - 0.5
    v = (0.5 - lat / math.pi) * height - 0.5
    return u, v, True


@njit(cache=True, error_model="numpy", inline="always")
def _src_pixel(x, y, z, rot, tr, fx, fy, cx, cy):
    xs = rot[0, 0] * x + rot[0, 1] * y + rot[0, 2] * z + tr[0]
    ys = rot[1, 0] * x + rot[1, 1] * y + rot[1, 2] * z + tr[1]
    zs = rot[2, 0] * x + rot[2, 1] * y + rot[2, 2] * z + tr[2]
    if not (zs > 0.0):
        return 0.0, 0.0, False
    return fx * xs / zs + cx, fy * ys / zs + cy, True


@njit(cache=True, error_model="numpy", inline="always")
def _pole_inside(nx, ny, nz, off, dy, rect, rot, tr, fx, fy, cx, cy):
    """Does the vertical ray from the rig centre toward dy (-1 up, +1 down) hit the quad?"""
    if not (off > 0.0):  # rig centre not on the source side of the plane
        return False
    nd = ny * dy
    if not (nd > 0.0):
        return False
    t = off / nd
    us, vs, ok = _src_pixel(0.0, t * dy, 0.0, rot, tr, fx, fy, cx, cy)
    return ok and rect[0] - 0.5 <= us < rect[2] - 0.5 and rect[1] - 0.5 <= vs < rect[3] - 0.5


@njit(cache=True, error_model="numpy", inline="always")
def _rig_point(uu, vv, iv, rot, tr, fx, fy, cx, cy):
    """Rig-frame point of source pixel (uu, vv) at inverse depth iv: ``R^T (X_s - T)``."""
    dx = (uu - cx) / fx / iv - tr[0]
    dy = (vv - cy) / fy / iv - tr[1]
    dz = 1.0 / iv - tr[2]
    return (rot[0, 0] * dx + rot[1, 0] * dy + rot[2, 0] * dz,
            rot[0, 1] * dx + rot[1, 1] * dy + rot[2, 1] * dz,
            rot[0, 2] * dx + rot[1, 2] * dy + rot[2, 2] * dz)


def _setup_rays(q0, q1, rects, planes, src_k, rot, tr, sign, r0, fa, fb, width, height, plane_rig, bbox):
    """Per quad: rig-frame plane ``[nx, ny, nz, off]`` and target bounds [ulo, vlo, uhi, vhi]
    (ulo/uhi may lie outside [0, W): columns wrap modulo W). Empty quads get ulo > uhi. Quads
    ``q0 .. q1-1`` only (:func:`ibr.render.bands.run_bands` splits them over the threads)."""
    fx, fy, cx, cy = src_k[0], src_k[1], src_k[2], src_k[3]
    for q in range(q0, q1):
        a, b, c = planes[q, 0], planes[q, 1], planes[q, 2]
        ncx, ncy, ncz = a * fx, b * fy, a * cx + b * cy + c  # n_cam: n_cam . X_s = 1
        # n = R^T n_cam, off = 1 - n_cam . T
        nx = rot[0, 0] * ncx + rot[1, 0] * ncy + rot[2, 0] * ncz
        ny = rot[0, 1] * ncx + rot[1, 1] * ncy + rot[2, 1] * ncz
        nz = rot[0, 2] * ncx + rot[1, 2] * ncy + rot[2, 2] * ncz
        off = 1.0 - (ncx * tr[0] + ncy * tr[1] + ncz * tr[2])
        plane_rig[q, 0] = nx
        plane_rig[q, 1] = ny
        plane_rig[q, 2] = nz
        plane_rig[q, 3] = off
        if not (off + math.hypot(nx, nz) * abs(r0) > 0.0):  # every ray origin behind the plane
            bbox[q, 0], bbox[q, 1], bbox[q, 2], bbox[q, 3] = 1, 0, 0, -1
            continue
        u0, v0, u1, v1 = rects[q, 0] - 0.5, rects[q, 1] - 0.5, rects[q, 2] - 0.5, rects[q, 3] - 0.5
        cu = (u0, u1, u1, u0, u0)
        cv = (v0, v0, v1, v1, v0)
        umin, umax, vmin, vmax = 1e30, -1e30, 1e30, -1e30
        prev_u = 0.0
        first = True
        full = False
        for e in range(4):
            # corner points (rig frame) of this edge; source camera: X_s = p * z, p = ((u-cx)/fx, ...)
            ua, va, ub, vb = cu[e], cv[e], cu[e + 1], cv[e + 1]
            ia = a * ua + b * va + c
            ib = a * ub + b * vb + c
            if not (ia > 0.0 and ib > 0.0):
                full = True
                break
            # angle-based sample count: endpoints as seen from the rig centre
            ax, ay, az = _rig_point(ua, va, ia, rot, tr, fx, fy, cx, cy)
            bx, by, bz = _rig_point(ub, vb, ib, rot, tr, fx, fy, cx, cy)
            la = math.sqrt(ax * ax + ay * ay + az * az)
            lb = math.sqrt(bx * bx + by * by + bz * bz)
            cosang = (ax * bx + ay * by + az * bz) / max(la * lb, 1e-300)
            ang = math.acos(min(1.0, max(-1.0, cosang)))
            n = int(min(4096.0, ang * width / (2.0 * math.pi) / 3.0)) + 1
            for i in range(n):
                s = i / n
                # the edge is straight in the source image and on the plane: interpolate in
                # source pixel coordinates, then unproject with the plane's inverse depth
                uu = ua + s * (ub - ua)
                vv = va + s * (vb - va)
                iv = a * uu + b * vv + c
                px, py, pz = _rig_point(uu, vv, iv, rot, tr, fx, fy, cx, cy)
                pu, pv, ok = _project(px, py, pz, sign, r0, fa, fb, width, height)
                if not ok:
                    full = True
                    break
                if first:
                    first = False
                else:  # unwrap across the seam relative to the previous sample
                    pu += width * round((prev_u - pu) / width)
                prev_u = pu
                umin = min(umin, pu)
                umax = max(umax, pu)
                vmin = min(vmin, pv)
                vmax = max(vmax, pv)
            if full:
                break
        if full:
            bbox[q, 0], bbox[q, 1], bbox[q, 2], bbox[q, 3] = 0, 0, width - 1, height - 1
            continue
        up = _pole_inside(nx, ny, nz, off, -1.0, rects[q], rot, tr, fx, fy, cx, cy)
        down = _pole_inside(nx, ny, nz, off, 1.0, rects[q], rot, tr, fx, fy, cx, cy)
        if up:
            vmin = -0.5
        if down:
            vmax = height - 0.5
        ulo = int(math.ceil(umin - _PAD))  # pixel centres (integers) within the padded outline
        uhi = int(math.floor(umax + _PAD))
        if up or down or uhi - ulo + 1 >= width:
            ulo, uhi = 0, width - 1
        vlo = max(0, int(math.ceil(vmin - _PAD)))
        vhi = min(height - 1, int(math.floor(vmax + _PAD)))
        bbox[q, 0], bbox[q, 1], bbox[q, 2], bbox[q, 3] = ulo, vlo, uhi, vhi


#: compiled serially without the GIL and run in pieces by ibr.render.bands (parallel=True took
#: 5.7 s to compile on a first ``ibr stitch``, #13)
setup_rays = njit(cache=True, error_model="numpy", nogil=True)(_setup_rays)


def region(bbox, width, height):
    """Rows [v0, v1] and a column mask (W,) uint8 holding every quad's bounds (columns wrap).

    Pixels outside the region are covered by no quad: the raster and blend kernels skip them.
    v0 > v1 when no quad is visible. (The mask is allocated here: an allocation inside the kernel
    cost a first ``ibr stitch`` 0.2 s of compiling, #13.)
    """
    cols = np.zeros(width, np.uint8)
    v0, v1 = _region(bbox, height, cols)
    return v0, v1, cols


@njit(cache=True, error_model="numpy")
def _region(bbox, height, cols):
    """:func:`region`'s rows; marks the columns in ``cols`` (zeroed)."""
    width = cols.shape[0]
    v0, v1 = np.int64(height), np.int64(-1)
    for q in range(bbox.shape[0]):
        lo, top, hi, bottom = np.int64(bbox[q, 0]), np.int64(bbox[q, 1]), np.int64(bbox[q, 2]), np.int64(bbox[q, 3])
        if lo > hi or top > bottom:
            continue
        v0 = top if top < v0 else v0
        v1 = bottom if bottom > v1 else v1
        if hi - lo + 1 >= width:
            for u in range(width):
                cols[u] = 1
        else:
            for uw in range(lo, hi + 1):
                cols[uw % width] = 1
    return v0, v1


@njit(cache=True, error_model="numpy", inline="always")
def _arc(rad, centre, ly, slat, clat, lo, hi, mid):
    """Narrow [lo, hi] (unwrapped longitudes, hi - lo < pi) to where ``l . d(lon) >= 0`` on a row
    of latitude lat: ``l . d = clat R cos(lon - lon0) + C`` with ``R = |(lx, lz)|``,
    ``lon0 = atan2(lx, lz)`` (row-independent: ``clat > 0`` at every pixel centre), ``C = -slat ly``.
    The failing set is the arc ``|lon - centre| < pi - h``, ``centre = lon0 + pi``,
    ``h = acos(-C / (clat R))``; each of its copies (every 2 pi) that covers an end of [lo, hi] cuts
    it there; a copy strictly inside would split it in two, and is left to the per-pixel test."""
    r = clat * rad
    c = -slat * ly
    if r < 1e-300:
        return (lo, hi) if c >= 0.0 else (1.0, -1.0)
    k = -c / r
    if k <= -1.0:
        return lo, hi
    if k > 1.0:
        return 1.0, -1.0
    half = math.pi - math.acos(k)  # half-width of the failing arc
    centre += 2.0 * math.pi * round((mid - centre) / (2.0 * math.pi))
    for shift in (-2.0 * math.pi, 0.0, 2.0 * math.pi):
        clo = centre + shift - half
        chi = centre + shift + half
        if clo <= lo and chi >= hi:
            return 1.0, -1.0
        if clo <= lo < chi:
            lo = chi
        elif clo < hi <= chi:
            hi = clo
    return lo, hi


@njit(cache=True, error_model="numpy", inline="always")
def _row_span(forms, slat, clat, ulo, uhi, width):
    """Columns [a, b] of a row whose rays start at the rig centre that can hit the quad: the
    intersection of the six arcs of ``forms`` (6, 5) ``[lx, ly, lz, |(lx, lz)|, atan2(lx, lz) + pi]``
    (4 rect sides, z_s > 0, n . d > 0), widened by one pixel each way (the exact per-pixel test
    decides)."""
    scale = 2.0 * math.pi / width
    lo = ((ulo + 0.5) - 0.5 * width) * scale - scale
    hi = ((uhi + 0.5) - 0.5 * width) * scale + scale
    mid = 0.5 * (lo + hi)
    for i in range(6):
        lo, hi = _arc(forms[i, 3], forms[i, 4], forms[i, 1], slat, clat, lo, hi, mid)
        if lo > hi:
            return 1, 0
    a = int(math.floor((lo / (2.0 * math.pi) + 0.5) * width - 0.5)) - 1
    b = int(math.ceil((hi / (2.0 * math.pi) + 0.5) * width - 0.5)) + 1
    return max(a, ulo), min(b, uhi)


@njit(cache=True, error_model="numpy", inline="always")
def _clamp(us, vs, cl, ct, cr, cb, su0, sv0, su1, sv1):
    """Clamp a sample position to the rect's outer pixel centres on the flagged sides."""
    if cl and us < su0:
        us = su0
    if cr and us > su1:
        us = su1
    if ct and vs < sv0:
        vs = sv0
    if cb and vs > sv1:
        vs = sv1
    return us, vs


def _raster_rays(t0, t1, rects, plane_rig, bbox, clamp, src_k, rot, tr, rows, cols, band_start, band_quads,
                 band_order, far_coord, v0, v1, colmask, rng, map_u, map_v, coverage):
    """Z-buffered ray casting of quads into a spherical camera, one band of rows per task.

    rng (H, W) float32 receives the range along each pixel's unit ray from its own origin (NaN
    uncovered); map_u/map_v the source pixel coordinates (far_coord uncovered); coverage bool.
    clamp (Q, 4) uint8 [left, top, right, bottom]: clamp the sample position to the rect's outer
    pixel centres on that side (as the pinhole rasterizer).
    """
    height, width = rng.shape
    fx, fy, cx, cy = src_k[0], src_k[1], src_k[2], src_k[3]
    nbands = band_start.shape[0] - 1
    rows_per_band = (height + nbands - 1) // nbands
    for task in range(t0, t1):  # tasks t0 .. t1-1 (ibr.render.bands.run_bands hands them out)
        band = band_order[task]
        r0 = band * rows_per_band
        r1 = min(height, r0 + rows_per_band)
        m = np.empty((3, 3))
        forms = np.empty((6, 5))
        for v in range(max(r0, v0), min(r1, v1 + 1)):
            for u in range(width):
                if colmask[u]:
                    rng[v, u] = np.inf
        for k in range(band_start[band], band_start[band + 1]):
            q = band_quads[k]
            nx, ny, nz, off = plane_rig[q, 0], plane_rig[q, 1], plane_rig[q, 2], plane_rig[q, 3]
            eu0, ev0 = rects[q, 0] - 0.5, rects[q, 1] - 0.5
            eu1, ev1 = rects[q, 2] - 0.5, rects[q, 3] - 0.5
            su0, sv0 = float(rects[q, 0]), float(rects[q, 1])
            su1, sv1 = float(rects[q, 2] - 1), float(rects[q, 3] - 1)
            cl, ct, cr, cb = clamp[q, 0] != 0, clamp[q, 1] != 0, clamp[q, 2] != 0, clamp[q, 3] != 0
            ulo, uhi = bbox[q, 0], bbox[q, 2]
            # Rows whose rays start at the rig centre (mono; ODS beyond the fade): every test is a
            # linear form in d, l . d >= 0 with l = M^T e, M = R + T n^T / off (the hit X = off d /
            # (n . d) maps to X_s ~ M d), so the row's columns narrow to an arc analytically.
            narrow = off > 0.0 and uhi - ulo < width // 2
            if narrow:
                for i in range(3):
                    for j in range(3):
                        m[i, j] = rot[i, j] + tr[i] * plane_rig[q, j] / off
                for j in range(3):
                    forms[0, j] = fx * m[0, j] + (cx - eu0) * m[2, j]
                    forms[1, j] = -(fx * m[0, j] + (cx - eu1) * m[2, j])
                    forms[2, j] = fy * m[1, j] + (cy - ev0) * m[2, j]
                    forms[3, j] = -(fy * m[1, j] + (cy - ev1) * m[2, j])
                    forms[4, j] = m[2, j]
                    forms[5, j] = plane_rig[q, j]
                for i in range(6):
                    forms[i, 3] = math.hypot(forms[i, 0], forms[i, 2])
                    forms[i, 4] = math.atan2(forms[i, 0], forms[i, 2]) + math.pi
            for v in range(max(bbox[q, 1], r0), min(bbox[q, 3] + 1, r1)):
                slat, clat, sr = rows[v, 0], rows[v, 1], rows[v, 2]
                a, b = ulo, uhi
                if narrow and sr == 0.0:
                    if uhi - ulo > _NARROW_MIN:  # narrow long rows analytically; short ones test every pixel
                        a, b = _row_span(forms, slat, clat, ulo, uhi, width)
                    # rays from the rig centre: X_s = (off / n.d) M d, so the source pixel is the
                    # projection of M d (a homography of the direction), t = off / n.d
                    k0x, k0y, k0z = -slat * m[0, 1], -slat * m[1, 1], -slat * m[2, 1]
                    kn = -slat * ny
                    for uw in range(a, b + 1):
                        u = uw if uw < width else uw - width
                        if u < 0:
                            u += width
                        sx, sz = clat * cols[u, 0], clat * cols[u, 1]
                        nd = nx * sx + nz * sz + kn
                        if not (nd > 0.0 and off < rng[v, u] * nd):  # t = off / nd beats the z-buffer
                            continue
                        zs = m[2, 0] * sx + m[2, 2] * sz + k0z
                        if not (zs > 0.0):
                            continue
                        xs = m[0, 0] * sx + m[0, 2] * sz + k0x
                        ys = m[1, 0] * sx + m[1, 2] * sz + k0y
                        iz = 1.0 / zs
                        us = fx * xs * iz + cx
                        vs = fy * ys * iz + cy
                        if not (us >= eu0 and us < eu1 and vs >= ev0 and vs < ev1):
                            continue
                        t = off / nd
                        if not (t < rng[v, u]):  # the exact test (the product above may round)
                            continue
                        us, vs = _clamp(us, vs, cl, ct, cr, cb, su0, sv0, su1, sv1)
                        rng[v, u] = t
                        map_u[v, u] = us
                        map_v[v, u] = vs
                    continue
                for uw in range(a, b + 1):
                    u = uw if uw < width else uw - width
                    if u < 0:
                        u += width
                    slon, clon = cols[u, 0], cols[u, 1]
                    ox, oz = sr * clon, -sr * slon
                    side = nx * ox + nz * oz - off
                    if not (side < 0.0):
                        continue  # ray origin behind the plane: back-facing
                    dx, dy, dz = clat * slon, -slat, clat * clon
                    nd = nx * dx + ny * dy + nz * dz
                    if not (nd > 0.0):
                        continue
                    t = -side / nd
                    if not (t < rng[v, u]):
                        continue
                    px, py, pz = ox + t * dx, t * dy, oz + t * dz
                    xs = rot[0, 0] * px + rot[0, 1] * py + rot[0, 2] * pz + tr[0]
                    ys = rot[1, 0] * px + rot[1, 1] * py + rot[1, 2] * pz + tr[1]
                    zs = rot[2, 0] * px + rot[2, 1] * py + rot[2, 2] * pz + tr[2]
                    if not (zs > 0.0):
                        continue
                    us = fx * xs / zs + cx
                    vs = fy * ys / zs + cy
                    if not (us >= eu0 and us < eu1 and vs >= ev0 and vs < ev1):
                        continue
                    us, vs = _clamp(us, vs, cl, ct, cr, cb, su0, sv0, su1, sv1)
                    rng[v, u] = t
                    map_u[v, u] = us
                    map_v[v, u] = vs
        for v in range(max(r0, v0), min(r1, v1 + 1)):
            for u in range(width):
                if not colmask[u]:
                    continue
                if rng[v, u] < np.inf:
                    coverage[v, u] = True
                else:
                    rng[v, u] = np.nan
                    coverage[v, u] = False
                    map_u[v, u] = far_coord
                    map_v[v, u] = far_coord


#: serial without the GIL, tasks handed out by ibr.render.bands (parallel=True: 6.0 s to compile)
raster_rays = njit(cache=True, error_model="numpy", nogil=True)(_raster_rays)
