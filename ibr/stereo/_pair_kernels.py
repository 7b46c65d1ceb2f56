"""numba kernels of seed 003's method 2 (per-pixel mapping) and the background-side hole fill.

Private: :mod:`ibr.stereo.pair` validates, allocates and calls these. Each kernel has a plain
numpy/Python reference below (``*_reference``) that the tests compare against.

Pixel convention: pixel centers at integer coordinates; a source pixel u maps to the target
position ``x(u) = u + shift(u)`` with ``shift = -fx * dx / z + dpixel`` (seed 003 method 2 with
Dz = 0, so rows are preserved exactly: v' = v).
"""

from __future__ import annotations

import numpy as np
from ..base.jit import njit

__all__: list[str] = []

#: A depth step for sharp sampling's taps: inverse depths of row neighbours more than this apart,
#: relative to the nearer one (the 2 % of :func:`ibr.render.sources._sharp_edges`).
STEP_REL = 0.02


@njit(cache=True, nogil=True, error_model="numpy", inline="always")
def _half_segment(a, half, b):
    """A segment's colour at pixel i (``a``), and its rises to the half-way sample and from there
    to pixel i + 1 (``b``), in float32."""
    ca = np.float32(a)
    hc = np.float32(half)
    return ca, hc - ca, np.float32(b) - hc


@njit(cache=True, nogil=True, error_model="numpy")
def resolve_half_way(v0, v1, color, z, half, is_int):
    """Make Lanczos-3 half-way samples safe for sharp sampling, rows v0 .. v1-1, in place.

    ``half`` (H, W, C), ``color``'s dtype: on entry the plain Lanczos-3 sample half-way between
    pixels i and i + 1 of each row (:func:`ibr.render.sharp_sampling.half_way_columns` with
    ``clamp=False``, taps i - 2 .. i + 3, the border repeated); on return clamped to the range of
    its two pixels, or their mean (``is_int``: rounded half up) where a tap lies across a depth
    step (row neighbours whose inverse depths differ by more than :data:`STEP_REL` of the nearer,
    or a pixel with depth beside one without, ``z`` (H, W) <= 0 or NaN): the odd columns of
    :func:`~ibr.render.sharp_sampling.upsample_cosited` with
    :func:`~ibr.base.depth.depth_steps`' steps along rows, done once per view for both eyes.
    """
    h, w, nc = color.shape
    at = np.empty(w, np.int64)  # the row's depth steps: between pixels m and m + 1
    for v in range(v0, v1):
        # clamp to the two pixels, as one flat loop over the row (vectorized: 3x the per-pixel loop)
        src = color[v].reshape(-1)
        dst = half[v].reshape(-1)
        for q in range((w - 1) * nc):
            a = src[q]
            b = src[q + nc]
            dst[q] = min(max(dst[q], min(a, b)), max(a, b))
        for c in range(nc):  # past the last pixel the border repeats: the pixel itself
            half[v, w - 1, c] = color[v, w - 1, c]
        n = 0
        zp = z[v, 0]
        valid_p = zp > 0  # False for NaN
        for m in range(w - 1):
            zi = z[v, m + 1]
            valid = zi > 0
            # |1/a - 1/b| > r max(1/a, 1/b)  <=>  |a - b| > r max(a, b): no division
            if valid != valid_p or (valid and abs(zi - zp) > STEP_REL * max(zi, zp)):
                at[n] = m
                n += 1
            zp = zi
            valid_p = valid
        # half-way samples i whose taps i - 2 .. i + 3 hold a step m, m + 1: i in m - 2 .. m + 2
        for k in range(n):
            for i in range(max(at[k] - 2, 0), min(at[k] + 3, w - 1)):
                for c in range(nc):
                    if is_int:
                        half[v, i, c] = (np.int64(color[v, i, c]) + np.int64(color[v, i + 1, c]) + 1) >> 1
                    else:
                        half[v, i, c] = np.float32(0.5) * (np.float32(color[v, i, c]) + np.float32(color[v, i + 1, c]))


@njit(cache=True, nogil=True, error_model="numpy")
def scanline_warp(v0, v1, color, z, fx, dx, dpixel, max_jump_px, out_color, out_depth, out_cov, is_int=False,
                  half=None):
    """Row-preserving forward mapping with linear interpolation between connected neighbors.

    color (H, W, C) any dtype (read as is: uint8 sources move 4x less memory than a float32
    copy), z (H, W) float32 (NaN invalid); outputs (any contents, every row is initialised
    here): out_color (H, W, C) -- float32, or with ``is_int`` an integer array that receives the
    value rounded half up (a convex combination of source values: never out of range) -- 0 where
    uncovered, out_depth (H, W) float32 (NaN where uncovered), out_cov (H, W) bool. Colours are
    interpolated in float32 whatever the dtype.

    Neighbors i, i+1 (both valid) are connected when their shifts differ by at most
    ``max_jump_px`` (a larger jump is a depth edge: disocclusion, left as a hole). A connected
    segment covers the target pixel centers j with x_i <= j <= x_{i+1}; inverse depth and color
    are interpolated linearly in x (exact for inverse depth on planes). A pixel's outer half
    footprint [x - 0.5, x] / [x, x + 0.5] on an unconnected side takes its own color and depth.
    Z-buffer: nearest wins (kept per row in inverse depth, so no division per candidate pixel;
    each source pixel's position and inverse depth are computed once per row).

    ``half`` (H, W, C), same dtype as ``color``, optional: sharp sampling. ``half[v, i]`` is
    the colour half-way between pixels i and i + 1 (:func:`resolve_half_way`), and a segment's
    colour runs linearly from pixel i to it and on to pixel i + 1 (a row of the 2x co-sited
    upsampling of :mod:`ibr.render.sharp_sampling` sampled linearly) instead of straight from
    i to i + 1 (which averages the two half-way: a blur).
    """
    h, w, nc = color.shape
    sharp = half is not None
    if half is None:  # numba prunes the branch the argument's type rules out
        hv = color
    else:
        hv = half
    xs = np.empty(w)
    izs = np.empty(w)  # inverse depth, -1 where invalid
    best = np.empty(w)  # the row's z-buffer in inverse depth (0 = empty)
    row = np.empty((w, nc), np.float32)  # the row's colours (cache-resident; stored once at the end)
    seg = np.empty((3, nc), np.float32)  # sharp: a segment's colours at i, i + 1/2 and i + 1
    rgb = nc == 3  # the common case, with the channel loop written out (1.5x faster than a loop over nc)
    k = fx * dx
    for v in range(v0, v1):  # rows v0 .. v1-1: ibr.render.bands.run_bands runs bands on all cores
        best[:] = 0.0
        row[:] = 0.0
        for i in range(w):
            zi = z[v, i]
            if zi > 0:
                iz = 1.0 / zi  # one division per pixel: the shift is -fx dx / z = -fx dx * (1 / z)
                xs[i] = i - k * iz + dpixel
            else:
                iz = -1.0
                xs[i] = 0.0
            izs[i] = iz
        conn_l = False  # pixel i connects to its left neighbour (carried from i - 1)
        for i in range(w):
            izi = izs[i]
            if izi < 0:
                conn_l = False
                continue
            xi = xs[i]
            conn_r = False
            if i + 1 < w:
                izr = izs[i + 1]
                xr = xs[i + 1]
                conn_r = izr >= 0 and abs((xr - xi) - 1.0) <= max_jump_px
            if conn_r:
                a, b = (xi, xr) if xi <= xr else (xr, xi)
                j0 = max(int(np.ceil(a)), 0)
                j1 = min(int(np.floor(b)), w - 1)
                if j0 <= j1:  # no division without a pixel centre
                    inv_span = 0.0 if xr == xi else 1.0 / (xr - xi)
                    diz = izr - izi
                    if sharp and rgb:
                        c0, e0, f0 = _half_segment(color[v, i, 0], hv[v, i, 0], color[v, i + 1, 0])
                        c1, e1, f1 = _half_segment(color[v, i, 1], hv[v, i, 1], color[v, i + 1, 1])
                        c2, e2, f2 = _half_segment(color[v, i, 2], hv[v, i, 2], color[v, i + 1, 2])
                        for j in range(j0, j1 + 1):
                            t = (j - xi) * inv_span
                            iz = izi + t * diz
                            if iz > best[j]:
                                best[j] = iz
                                tf = np.float32(2.0 * t)  # pixel i -> half-way, then half-way -> i + 1
                                if tf < 1.0:
                                    row[j, 0] = c0 + tf * e0
                                    row[j, 1] = c1 + tf * e1
                                    row[j, 2] = c2 + tf * e2
                                else:
                                    tf -= np.float32(1.0)
                                    row[j, 0] = c0 + e0 + tf * f0
                                    row[j, 1] = c1 + e1 + tf * f1
                                    row[j, 2] = c2 + e2 + tf * f2
                    elif sharp:
                        for c in range(nc):
                            seg[0, c], seg[1, c], seg[2, c] = _half_segment(color[v, i, c], hv[v, i, c],
                                                                          color[v, i + 1, c])
                        for j in range(j0, j1 + 1):
                            t = (j - xi) * inv_span
                            iz = izi + t * diz
                            if iz > best[j]:
                                best[j] = iz
                                tf = np.float32(2.0 * t)
                                if tf < 1.0:
                                    for c in range(nc):
                                        row[j, c] = seg[0, c] + tf * seg[1, c]
                                else:
                                    tf -= np.float32(1.0)
                                    for c in range(nc):
                                        row[j, c] = seg[0, c] + seg[1, c] + tf * seg[2, c]
                    elif rgb:
                        c0 = np.float32(color[v, i, 0])
                        c1 = np.float32(color[v, i, 1])
                        c2 = np.float32(color[v, i, 2])
                        d0 = np.float32(color[v, i + 1, 0]) - c0
                        d1 = np.float32(color[v, i + 1, 1]) - c1
                        d2 = np.float32(color[v, i + 1, 2]) - c2
                        for j in range(j0, j1 + 1):
                            t = (j - xi) * inv_span
                            iz = izi + t * diz
                            if iz > best[j]:
                                best[j] = iz
                                tf = np.float32(t)  # colours in float32 (within 2e-5 of float64 at 255)
                                row[j, 0] = c0 + tf * d0
                                row[j, 1] = c1 + tf * d1
                                row[j, 2] = c2 + tf * d2
                    else:
                        for j in range(j0, j1 + 1):
                            t = (j - xi) * inv_span
                            iz = izi + t * diz
                            if iz > best[j]:
                                best[j] = iz
                                for c in range(nc):
                                    ci = np.float32(color[v, i, c])
                                    row[j, c] = ci + t * (np.float32(color[v, i + 1, c]) - ci)
            if not (conn_l and conn_r):
                # half footprints on unconnected sides: [x - 0.5, x] and [x, x + 0.5)
                for side in range(2):
                    if (side == 0 and conn_l) or (side == 1 and conn_r):
                        continue
                    if side == 0:
                        j0 = max(int(np.ceil(xi - 0.5)), 0)
                        j1 = min(int(np.floor(xi)), w - 1)
                    else:
                        j0 = max(int(np.ceil(xi)), 0)
                        j1 = min(int(np.ceil(xi + 0.5)) - 1, w - 1)
                    for j in range(j0, j1 + 1):
                        if izi > best[j]:
                            best[j] = izi
                            for c in range(nc):
                                row[j, c] = color[v, i, c]
            conn_l = conn_r
        # output in branch-free loops that LLVM vectorizes (uncovered colours are the zeros of row)
        for j in range(w):
            bj = best[j]
            out_depth[v, j] = 1.0 / bj if bj > 0 else np.nan
            out_cov[v, j] = bj > 0
        flat = row.reshape(-1)
        dst = out_color[v].reshape(-1)
        if is_int:
            for q in range(w * nc):
                dst[q] = flat[q] + np.float32(0.5)  # round half up (truncation of x + 0.5 >= 0)
        else:
            for q in range(w * nc):
                dst[q] = flat[q]


@njit(cache=True)
def point_splat(color, z, fx, fy, cx, cy, dx, dz, dpixel, out_color, out_depth, out_cov):
    """Seed 003 method 2 literally: each pixel copied to the rounded target position
    ``u' = fx (X - dx)/(Z - dz) + cx + dpixel``, ``v' = fy Y/(Z - dz) + cy``, z-buffered."""
    h, w, nc = color.shape
    for v in range(h):
        for u in range(w):
            zz = z[v, u]
            if not (zz > 0):
                continue
            x = (u - cx) / fx * zz
            y = (v - cy) / fy * zz
            zt = zz - dz
            if zt <= 0:
                continue
            ut = fx * (x - dx) / zt + cx + dpixel
            vt = fy * y / zt + cy
            j = int(np.floor(ut + 0.5))
            k = int(np.floor(vt + 0.5))
            if 0 <= j < w and 0 <= k < h and zt < out_depth[k, j]:
                out_depth[k, j] = zt
                out_cov[k, j] = True
                for c in range(nc):
                    out_color[k, j, c] = color[v, u, c]


# ---------------------------------------------------------------------- references
def scanline_warp_reference(color, z, fx, dx, dpixel, max_jump_px, half=None):
    """numpy reference of :func:`scanline_warp`: per row, every candidate (segment or half
    footprint) evaluated at every target pixel center, the nearest kept. O(W^2) per row.
    ``half``: the resolved half-way samples of sharp sampling (:func:`resolve_half_way`)."""
    h, w, nc = color.shape
    out_c = np.zeros((h, w, nc), np.float32)
    out_z = np.full((h, w), np.inf, np.float32)
    cov = np.zeros((h, w), bool)
    j = np.arange(w, dtype=np.float64)
    for v in range(h):
        zr = z[v].astype(np.float64)
        valid = zr > 0
        with np.errstate(invalid="ignore", divide="ignore"):
            x = np.arange(w) - fx * dx / zr + dpixel
        conn = valid[:-1] & valid[1:] & (np.abs((x[1:] - x[:-1]) - 1.0) <= max_jump_px)  # shifts' difference
        best = np.full(w, np.inf)
        col = np.zeros((w, nc))
        for i in range(w - 1):
            if not conn[i]:
                continue
            a, b = sorted((x[i], x[i + 1]))
            inside = (j >= a) & (j <= b)
            span = x[i + 1] - x[i]
            t = np.zeros(w) if span == 0 else (j - x[i]) / span
            zz = 1.0 / (1 / zr[i] + t * (1 / zr[i + 1] - 1 / zr[i]))
            if half is None:
                ccol = color[v, i][None, :] + t[:, None] * (color[v, i + 1] - color[v, i])[None, :]
            else:  # pixel i -> the half-way sample -> pixel i + 1
                ci, hi, cn = (np.asarray(x, np.float64)[None, :] for x in (color[v, i], half[v, i], color[v, i + 1]))
                t2 = 2.0 * t[:, None]
                ccol = np.where(t2 < 1.0, ci + t2 * (hi - ci), hi + (t2 - 1.0) * (cn - hi))
            upd = inside & (zz < best)
            best[upd] = zz[upd]
            col[upd] = ccol[upd]
        for i in range(w):
            if not valid[i]:
                continue
            cl = i > 0 and conn[i - 1]
            cr = i < w - 1 and conn[i]
            m = np.zeros(w, bool)
            if not cl:
                m |= (j >= x[i] - 0.5) & (j <= x[i])
            if not cr:
                m |= (j >= x[i]) & (j < x[i] + 0.5)
            upd = m & (zr[i] < best)
            best[upd] = zr[i]
            col[upd] = color[v, i]
        hit = np.isfinite(best)
        out_z[v, hit] = best[hit]
        out_c[v, hit] = col[hit]
        cov[v] = hit
    return out_c, out_z, cov
