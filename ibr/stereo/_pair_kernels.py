"""numba kernels of seed 003's method 2 (per-pixel mapping) and the background-side hole fill.

Private: :mod:`ibr.stereo.pair` validates, allocates and calls these. Each kernel has a plain
numpy/Python reference below (``*_reference``) that the tests compare against.

Pixel convention: pixel centers at integer coordinates; a source pixel u maps to the target
position ``x(u) = u + shift(u)`` with ``shift = -fx * dx / z + dpixel`` (seed 003 method 2 with
Dz = 0, so rows are preserved exactly: v' = v).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__: list[str] = []


@njit(cache=True, nogil=True, error_model="numpy")
def scanline_warp(v0, v1, color, z, fx, dx, dpixel, max_jump_px, out_color, out_depth, out_cov, is_int=False):
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
    """
    h, w, nc = color.shape
    for v in range(v0, v1):  # rows v0 .. v1-1: ibr.render.bands.run_bands runs bands on all cores
        xs = np.empty(w)
        izs = np.empty(w)
        ok = np.zeros(w, np.bool_)
        best = np.zeros(w)  # the row's z-buffer in inverse depth (0 = empty)
        row = np.zeros((w, nc), np.float32)  # the row's colours (cache-resident; stored once at the end)
        for i in range(w):
            zi = z[v, i]
            if zi > 0:
                ok[i] = True
                iz = 1.0 / zi  # one division per pixel: the shift is -fx dx / z = -fx dx * (1 / z)
                izs[i] = iz
                xs[i] = i - fx * dx * iz + dpixel
        next_connected = -1  # i + 1 when i connects to its right neighbour (its conn_l then)
        for i in range(w):
            if not ok[i]:
                continue
            xi = xs[i]
            izi = izs[i]
            conn_l = next_connected == i
            conn_r = i + 1 < w and ok[i + 1] and abs((xs[i + 1] - (i + 1)) - (xi - i)) <= max_jump_px
            if conn_r:
                next_connected = i + 1
            if conn_r:
                xr = xs[i + 1]
                izr = izs[i + 1]
                a, b = (xi, xr) if xi <= xr else (xr, xi)
                j0 = max(int(np.ceil(a)), 0)
                j1 = min(int(np.floor(b)), w - 1)
                span = xr - xi
                inv_span = 0.0 if span == 0 or j0 > j1 else 1.0 / span  # no division without a pixel
                for j in range(j0, j1 + 1):
                    t = (j - xi) * inv_span
                    iz = izi + t * (izr - izi)
                    if iz > best[j]:
                        best[j] = iz
                        for c in range(nc):
                            ci = np.float32(color[v, i, c])
                            row[j, c] = ci + t * (np.float32(color[v, i + 1, c]) - ci)
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
        # output in branch-free loops that LLVM vectorizes (uncovered colours are the zeros of row)
        for j in range(w):
            bj = best[j]
            out_depth[v, j] = 1.0 / bj if bj > 0 else np.nan
            out_cov[v, j] = bj > 0
        flat = row.reshape(-1)
        dst = out_color[v].reshape(-1)
        if is_int:
            for k in range(w * nc):
                dst[k] = flat[k] + np.float32(0.5)  # round half up (truncation of x + 0.5 >= 0)
        else:
            for k in range(w * nc):
                dst[k] = flat[k]


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
def scanline_warp_reference(color, z, fx, dx, dpixel, max_jump_px):
    """numpy reference of :func:`scanline_warp`: per row, every candidate (segment or half
    footprint) evaluated at every target pixel center, the nearest kept. O(W^2) per row."""
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
        shift = x - np.arange(w)
        conn = valid[:-1] & valid[1:] & (np.abs(shift[1:] - shift[:-1]) <= max_jump_px)
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
            ccol = color[v, i][None, :] + t[:, None] * (color[v, i + 1] - color[v, i])[None, :]
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
