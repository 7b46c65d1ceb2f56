"""numba kernels of the background-side hole fills behind :mod:`ibr.render.fill`.

Private, no validation. Each kernel fills in place; ``fill_rows_background`` has a numpy
reference below that the tests compare against.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

__all__: list[str] = []

@njit(cache=True, error_model="numpy")
def background_fill(color, depth, holes, rel_tol, max_dist, is_int, filled):
    """Fill hole pixels from the *farther* of their nearest non-hole neighbours (in place).

    For every hole pixel the nearest non-hole pixel is found in each of the four directions
    (left, right, up, down, at most ``max_dist`` pixels away). The farthest candidate depth z_bg
    marks the background; candidates with depth >= z_bg (1 - rel_tol) are averaged with weights
    1/distance, so disocclusions take background, never foreground, colors. ``filled`` (bool)
    marks the pixels written; holes with no candidate stay untouched."""
    h, w, nc = color.shape
    # nearest non-hole row above / below each hole pixel: row-major sweeps keeping the last
    # non-hole row of every column (cache friendly; written only at hole pixels)
    up = np.empty((h, w), np.int32)
    down = np.empty((h, w), np.int32)
    row_has = np.zeros(h, np.bool_)
    last = np.full(w, -1, np.int32)
    for v in range(h):
        for u in range(w):
            if holes[v, u]:
                up[v, u] = last[u]
                row_has[v] = True
            else:
                last[u] = v
    last[:] = -1
    for v in range(h - 1, -1, -1):
        if not row_has[v]:
            for u in range(w):
                if not holes[v, u]:
                    last[u] = v
            continue
        for u in range(w):
            if holes[v, u]:
                down[v, u] = last[u]
            else:
                last[u] = v
    # nearest non-hole column left / right, per row that has holes
    left = np.empty((h, w), np.int32)
    right = np.empty((h, w), np.int32)
    for v in range(h):
        if not row_has[v]:
            continue
        lst = -1
        for u in range(w):
            if not holes[v, u]:
                lst = u
            left[v, u] = lst
        lst = -1
        for u in range(w - 1, -1, -1):
            if not holes[v, u]:
                lst = u
            right[v, u] = lst
    cu = np.empty(4, np.int64)
    cv = np.empty(4, np.int64)
    cd = np.empty(4, np.float64)
    cz = np.empty(4, np.float64)
    for v in range(h):
        if not row_has[v]:
            continue
        for u in range(w):
            if not holes[v, u]:
                continue
            n = 0
            vi = np.int64(v)
            ui = np.int64(u)
            for k in range(4):
                if k == 0:
                    uu = np.int64(left[vi, ui])
                    vv = vi
                    dist = ui - uu
                elif k == 1:
                    uu = np.int64(right[vi, ui])
                    vv = vi
                    dist = uu - ui
                elif k == 2:
                    uu = ui
                    vv = np.int64(up[vi, ui])
                    dist = vi - vv
                else:
                    uu = ui
                    vv = np.int64(down[vi, ui])
                    dist = vv - vi
                if uu < 0 or vv < 0 or dist > max_dist:
                    continue
                z = depth[vv, uu]
                if not (z > 0.0):
                    continue
                cu[n] = uu
                cv[n] = vv
                cd[n] = dist
                cz[n] = z
                n += 1
            if n == 0:
                continue
            zbg = 0.0
            for k in range(n):
                zbg = max(zbg, cz[k])
            wsum = 0.0
            zacc = 0.0
            for k in range(n):
                if cz[k] >= zbg * (1.0 - rel_tol):
                    wsum += 1.0 / cd[k]
            for ch in range(nc):
                acc = 0.0
                for k in range(n):
                    if cz[k] >= zbg * (1.0 - rel_tol):
                        acc += color[cv[k], cu[k], ch] / cd[k]
                x = acc / wsum
                if is_int:
                    x = np.floor(x + 0.5)
                color[v, u, ch] = x
            for k in range(n):
                if cz[k] >= zbg * (1.0 - rel_tol):
                    zacc += cz[k] / cd[k]
            depth[v, u] = zacc / wsum
            filled[v, u] = True


@njit(cache=True, parallel=True)
def fill_rows_background(color, depth, cov, out_holes):
    """Fill each uncovered run of a row with the deeper of its two covered neighbours
    (the background side); a run touching the image border takes its only neighbour.
    Runs with no covered pixel in the row stay 0 / NaN. In place; marks ``out_holes``."""
    h, w, nc = color.shape
    for v in prange(h):
        j = 0
        while j < w:
            if cov[v, j]:
                j += 1
                continue
            a = j
            while j < w and not cov[v, j]:
                j += 1
            b = j  # run is [a, b)
            left = a - 1
            right = b if b < w else -1
            src = -1
            if left >= 0 and right >= 0:
                src = left if depth[v, left] >= depth[v, right] else right
            elif left >= 0:
                src = left
            elif right >= 0:
                src = right
            for k in range(a, b):
                out_holes[v, k] = True
                if src >= 0:
                    depth[v, k] = depth[v, src]
                    for c in range(nc):
                        color[v, k, c] = color[v, src, c]


# ---------------------------------------------------------------------- references
def fill_rows_background_reference(color, depth, cov):
    """numpy reference of :func:`fill_rows_background` (returns copies and the hole mask)."""
    color = color.copy()
    depth = depth.copy()
    holes = np.zeros(cov.shape, bool)
    h, w = cov.shape
    for v in range(h):
        covered = np.flatnonzero(cov[v])
        for k in np.flatnonzero(~cov[v]):
            holes[v, k] = True
            left = covered[covered < k]
            right = covered[covered > k]
            cand = []
            if left.size:
                cand.append(left[-1])
            if right.size:
                cand.append(right[0])
            if not cand:
                continue
            src = cand[0] if len(cand) == 1 or depth[v, cand[0]] >= depth[v, cand[1]] else cand[1]
            color[v, k] = color[v, src]
            depth[v, k] = depth[v, src]
    return color, depth, holes
