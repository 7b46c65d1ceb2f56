"""numba kernel of :mod:`ibr.render.matting`: the foreground-rim samples of one source that a
frame re-composites over its own background.

Private: :func:`ibr.render.matting.rematte_rims` validates and calls it; its numpy reference is
``tests/test_matting.py``'s. Pixel centres at integers; planar depth, NaN where none.
"""

from __future__ import annotations

import numpy as np

from ..base.jit import njit

__all__: list[str] = []


@njit(cache=True, error_model="numpy", nogil=True)
def rim_updates(points, rot, trans, fx, fy, cx, cy, flat, alpha, toward, behind, depth, color, own_u, own_v,
                own_z, own_cov, own_w, own_h, two, other_z, other_cov, tol, min_change, out_px, out_val):
    """For each rim pixel of one source (``points`` (N, 3) world, ``flat`` its sorted flat source
    indices, ``alpha``, ``toward`` (N, 2) the neighbour (dy, dx) toward its background and
    ``behind`` (N, C) that neighbour's colour in the source), the target pixels of the 2 x 2
    around its projection (``rot``, ``trans``: target cam_from_world; intrinsics) where the
    composite (``depth``, ``color``) shows its surface (within ``tol``), the pixel toward its
    background lies farther and its colour B_t differs from ``behind`` by more than
    ``min_change`` in some channel, the source's own maps sample exactly that rim pixel there,
    and, with ``two`` sources, the other one's layer (``other_z``, ``other_cov``) does not show
    that surface. Writes their flat indices and new colours
    ``C + (1 - alpha) (B_t - behind)`` (the composite's colour with the background's change,
    float64) to ``out_px``, ``out_val`` (room for 4 N); returns how many."""
    h, w = depth.shape
    nc = color.shape[2]
    n = 0
    for i in range(points.shape[0]):
        x = rot[0, 0] * points[i, 0] + rot[0, 1] * points[i, 1] + rot[0, 2] * points[i, 2] + trans[0]
        y = rot[1, 0] * points[i, 0] + rot[1, 1] * points[i, 1] + rot[1, 2] * points[i, 2] + trans[1]
        z = rot[2, 0] * points[i, 0] + rot[2, 1] * points[i, 1] + rot[2, 2] * points[i, 2] + trans[2]
        if not (z > 0):
            continue
        u0 = np.floor(fx * x / z + cx)
        v0 = np.floor(fy * y / z + cy)
        if not (u0 >= -1 and u0 < w and v0 >= -1 and v0 < h):
            continue
        for corner in range(4):
            u = int(u0) + (corner & 1)
            v = int(v0) + (corner >> 1)
            if u < 0 or u >= w or v < 0 or v >= h:
                continue
            zt = np.float64(depth[v, u])
            if not (abs(z - zt) <= tol * zt):  # the composite shows another surface (or none)
                continue
            bu = min(max(u + toward[i, 1], 0), w - 1)
            bv = min(max(v + toward[i, 0], 0), h - 1)
            if not (depth[bv, bu] > zt * (1.0 + tol)):  # nothing behind it in that direction
                continue
            change = 0.0
            for c in range(nc):
                change = max(change, abs(np.float64(color[bv, bu, c]) - behind[i, c]))
            if not (change > min_change):
                continue
            if not _shows(own_cov, own_z, v, u, zt, tol) or _nearest(own_u, own_v, v, u, own_w, own_h) != flat[i]:
                continue  # the source's own layer samples another pixel here
            if two and _shows(other_cov, other_z, v, u, zt, tol):
                continue  # the other source sees that surface here too (and has the say at its own pose)
            a = alpha[i]
            out_px[n] = v * w + u
            for c in range(nc):
                out_val[n, c] = np.float64(color[v, u, c]) + (1.0 - a) * (np.float64(color[bv, bu, c]) - behind[i, c])
            n += 1
    return n


@njit(cache=True, error_model="numpy", inline="always")
def _shows(cov, zmap, v, u, zt, tol):
    """The layer covers target pixel (v, u) at the composite's depth ``zt``."""
    return cov[v, u] and abs(np.float64(zmap[v, u]) - zt) <= tol * zt


@njit(cache=True, error_model="numpy", inline="always")
def _nearest(map_u, map_v, v, u, ws, hs):
    """Flat index of the source pixel nearest to where target pixel (v, u) samples it (rounded
    as the composite kernels round, clamped to the source)."""
    sx = min(max(int(np.floor(np.float64(map_u[v, u]) + 0.5)), 0), ws - 1)
    sy = min(max(int(np.floor(np.float64(map_v[v, u]) + 0.5)), 0), hs - 1)
    return sy * ws + sx
