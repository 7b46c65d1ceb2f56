"""numba kernel for :mod:`ibr.mesh.code_bins` (private; the wrapper validates inputs).

Pixel (u, v) = (column, row) is element ``[v, u]``; rects are ``(x0, y0, x1, y1)``, ends
exclusive. Inverse depth ``q`` is NaN where a pixel has no depth; ``step`` is the encoding's
code size in inverse depth at each pixel's stored value.
"""

from __future__ import annotations

import numpy as np

from ..base.jit import njit

_N = 6  # quadratic surface q = a u + b v + c + d u^2 + e u v + f v^2 (centred u, v)


@njit(cache=True)
def _terms(du, dv, out):
    out[0] = du
    out[1] = dv
    out[2] = 1.0
    out[3] = du * du
    out[4] = du * dv
    out[5] = dv * dv


@njit(cache=True)
def _solve_ridge(a, b, n, ridge):
    """Solve (a + ridge (diag(a) + max(diag) I)) x = b for the symmetric positive semi-definite
    n x n ``a`` by Cholesky (the tiny ridge keeps degenerate directions, e.g. curvature across a
    one-pixel line, at zero). Returns x, or NaNs if the system is empty or not positive
    definite."""
    m = np.zeros((n, n))
    big = 0.0
    for i in range(n):
        big = max(big, a[i, i])
    x = np.full(n, np.nan)
    if big <= 0.0:
        return x
    for i in range(n):
        for j in range(n):
            m[i, j] = a[i, j]
        m[i, i] += ridge * (a[i, i] + big) + 1e-300
    ll = np.zeros((n, n))
    for i in range(n):
        for j in range(i + 1):
            s = m[i, j]
            for k in range(j):
                s -= ll[i, k] * ll[j, k]
            if i == j:
                if s <= 0.0:
                    return x
                ll[i, i] = np.sqrt(s)
            else:
                ll[i, j] = s / ll[j, j]
    y = np.zeros(n)
    for i in range(n):
        s = b[i]
        for k in range(i):
            s -= ll[i, k] * y[k]
        y[i] = s / ll[i, i]
    for i in range(n - 1, -1, -1):
        s = y[i]
        for k in range(i + 1, n):
            s -= ll[k, i] * x[k]
        x[i] = s / ll[i, i]
    return x


@njit(cache=True)
def _region(q, step, x0, y0, x1, y1, grow, span):
    """The window of the rect grown by ``grow`` px (clipped to the image) and a mask of its
    pixels reached from the rect in at most ``grow`` 4-connected steps, each between valid
    neighbours at most ``span`` codes apart (the same surface)."""
    h, w = q.shape
    wx0, wy0, wx1, wy1 = max(x0 - grow, 0), max(y0 - grow, 0), min(x1 + grow, w), min(y1 + grow, h)
    ww, wh = wx1 - wx0, wy1 - wy0
    dist = np.full((wh, ww), -1, np.int64)
    queue = np.empty((wh * ww, 2), np.int64)
    head, tail = 0, 0
    for v in range(y0, y1):
        for u in range(x0, x1):
            if np.isfinite(q[v, u]):
                dist[v - wy0, u - wx0] = 0
                queue[tail, 0], queue[tail, 1] = v, u
                tail += 1
    while head < tail:
        v, u = queue[head, 0], queue[head, 1]
        head += 1
        d = dist[v - wy0, u - wx0]
        if d >= grow:
            continue
        for k in range(4):
            nv = v + (1 if k == 0 else -1 if k == 1 else 0)
            nu = u + (1 if k == 2 else -1 if k == 3 else 0)
            if nv < wy0 or nv >= wy1 or nu < wx0 or nu >= wx1 or dist[nv - wy0, nu - wx0] >= 0:
                continue
            if not np.isfinite(q[nv, nu]) or abs(q[nv, nu] - q[v, u]) > span * step[v, u]:
                continue
            dist[nv - wy0, nu - wx0] = d + 1
            queue[tail, 0], queue[tail, 1] = nv, nu
            tail += 1
    return wx0, wy0, dist >= 0


@njit(cache=True)
def _sample(reach, max_pixels):
    """(row, column) in the window of its reached pixels, or of a random share of about
    ``max_pixels`` of them when there are more (random, not every k-th: a regular grid's phase
    biases a fit)."""
    wh, ww = reach.shape
    count = 0
    for j in range(wh):
        for i in range(ww):
            count += reach[j, i]
    share = min(1.0, max_pixels / max(count, 1))
    out = np.empty((count, 2), np.int64)
    k = 0
    for j in range(wh):
        for i in range(ww):
            if reach[j, i] and (share >= 1.0 or np.random.random() < share):
                out[k, 0], out[k, 1] = j, i
                k += 1
    return out[:k]


@njit(cache=True)
def _surface_in_bins(us, vs, qs, steps, inside, iterations, reject_after, reject_codes, ridge):
    """Coefficients (6,) of the quadratic surface through the bins of the pixels at scaled,
    centred (us, vs) with stored inverse depth ``qs`` and code sizes ``steps``, by alternating
    projections (module :mod:`ibr.mesh.code_bins`); pixels not ``inside`` the quad may be left
    out as another surface. NaNs if the system is empty."""
    m = len(us)
    weight = 1.0 / steps**2  # least squares in codes
    target = qs.copy()
    t = np.zeros(_N)
    coef = np.full(_N, np.nan)
    for it in range(iterations):
        a = np.zeros((_N, _N))
        b = np.zeros(_N)
        for k in range(m):
            if weight[k] == 0.0:
                continue
            _terms(us[k], vs[k], t)
            for r in range(_N):
                b[r] += weight[k] * t[r] * target[k]
                for c in range(r + 1):
                    a[r, c] += weight[k] * t[r] * t[c]
        for r in range(_N):
            for c in range(r + 1, _N):
                a[r, c] = a[c, r]
        coef = _solve_ridge(a, b, _N, ridge)
        if not np.isfinite(coef[0]) or it == iterations - 1:
            break
        # the surface projected into each pixel's bin (half a code either side of its code)
        for k in range(m):
            if weight[k] == 0.0:
                continue
            _terms(us[k], vs[k], t)
            r_codes = (_dot(coef, t) - qs[k]) / steps[k]
            if it >= reject_after and not inside[k] and abs(r_codes) > 0.5 + reject_codes:
                weight[k] = 0.0  # another surface (a crease, a neighbour at the same depth)
            else:
                target[k] = qs[k] + min(max(r_codes, -0.5), 0.5) * steps[k]
    return coef


@njit(cache=True)
def _dot(coef, t):
    s = 0.0
    for r in range(_N):
        s += coef[r] * t[r]
    return s


@njit(cache=True)
def _plane_of_surface(coef, q, step, x0, y0, x1, y1, uc, vc, scale, accept_codes):
    """The least-squares plane ``q = a u + b v + c`` (uncentred pixel coordinates) of the surface
    over the rect (closed form: over a full rect in centred coordinates the normal equations are
    diagonal), whether the surface lies within ``accept_codes`` of every valid own pixel's bin,
    and the largest distance (inverse depth) between the plane and the surface at those pixels."""
    t = np.zeros(_N)
    s_m = s_mu = s_mv = s_uu = s_vv = 0.0
    ok = True
    for v in range(y0, y1):
        for u in range(x0, x1):
            du, dv = u - uc, v - vc
            _terms(du / scale, dv / scale, t)
            model = _dot(coef, t)
            if np.isfinite(q[v, u]) and abs(model - q[v, u]) > (0.5 + accept_codes) * step[v, u]:
                ok = False
            s_m += model
            s_mu += model * du
            s_mv += model * dv
            s_uu += du * du
            s_vv += dv * dv
    a_u = s_mu / s_uu if s_uu > 0 else 0.0
    a_v = s_mv / s_vv if s_vv > 0 else 0.0
    c = s_m / ((x1 - x0) * (y1 - y0))
    gap = 0.0
    for v in range(y0, y1):
        for u in range(x0, x1):
            if np.isfinite(q[v, u]):
                du, dv = u - uc, v - vc
                _terms(du / scale, dv / scale, t)
                gap = max(gap, abs(_dot(coef, t) - (a_u * du + a_v * dv + c)))
    return np.array([a_u, a_v, c - a_u * uc - a_v * vc]), ok, gap


@njit(cache=True)
def fit_in_code_bins(q, step, rects, seeds, grow, span, iterations, reject_after, reject_codes,
                     accept_codes, ridge, max_pixels):
    """Planes ``q = a u + b v + c`` (uncentred pixel coordinates) for the ``rects``, NaN rows where
    no plane was accepted, and for each the largest distance between its plane and its surface at
    its pixels with depth (inverse depth; NaN where none). Each rect's random share is drawn from
    its own ``seeds`` entry, so its plane does not depend on which other rects are fitted. See
    :func:`ibr.mesh.code_bins.fit_planes_in_code_bins`."""
    out = np.full((len(rects), 3), np.nan)
    gaps = np.full(len(rects), np.nan)
    for n in range(len(rects)):
        np.random.seed(seeds[n])
        x0, y0, x1, y1 = rects[n, 0], rects[n, 1], rects[n, 2], rects[n, 3]
        wx0, wy0, reach = _region(q, step, x0, y0, x1, y1, grow, span)
        uc, vc = 0.5 * (x0 + x1 - 1), 0.5 * (y0 + y1 - 1)
        scale = 0.5 * max(reach.shape[0], reach.shape[1])  # coordinates of order one: a well-conditioned system
        pix = _sample(reach, max_pixels)
        m = len(pix)
        us, vs, qs, steps = np.empty(m), np.empty(m), np.empty(m), np.empty(m)
        inside = np.empty(m, np.bool_)
        for k in range(m):
            v, u = wy0 + pix[k, 0], wx0 + pix[k, 1]
            us[k], vs[k] = (u - uc) / scale, (v - vc) / scale
            qs[k], steps[k] = q[v, u], step[v, u]
            inside[k] = x0 <= u < x1 and y0 <= v < y1
        coef = _surface_in_bins(us, vs, qs, steps, inside, iterations, reject_after, reject_codes, ridge)
        if not np.isfinite(coef[0]):
            continue
        plane, ok, gap = _plane_of_surface(coef, q, step, x0, y0, x1, y1, uc, vc, scale, accept_codes)
        if ok:
            out[n], gaps[n] = plane, gap
    return out, gaps
