"""numba kernels of the forward splat (seed 003 method 2 per pixel) behind :mod:`ibr.render.forward`.

Private, no validation. Pixel centers at integer coordinates.
"""

from __future__ import annotations

import numpy as np
from ..base.jit import njit, prange

__all__: list[str] = []

# ------------------------------------------------------------------------- forward warp
@njit(cache=True, error_model="numpy")
def project_pixels(depth, ks, r, t, kt, tu, tv, tz):
    """Per source pixel: target pixel position (tu, tv) and planar target depth tz
    (NaN where the source depth is invalid or the point is behind the target camera).
    r, t: tgt_from_src."""
    h, w = depth.shape
    fx, fy, cx, cy = ks[0], ks[1], ks[2], ks[3]
    tfx, tfy, tcx, tcy = kt[0], kt[1], kt[2], kt[3]
    for v in prange(h):
        y1 = (v - cy) / fy
        for u in range(w):
            z = depth[v, u]
            if not (z > 0.0):
                tz[v, u] = np.nan
                continue
            x = (u - cx) / fx * z
            y = y1 * z
            X = r[0, 0] * x + r[0, 1] * y + r[0, 2] * z + t[0]
            Y = r[1, 0] * x + r[1, 1] * y + r[1, 2] * z + t[1]
            Z = r[2, 0] * x + r[2, 1] * y + r[2, 2] * z + t[2]
            if not (Z > 0.0):
                tz[v, u] = np.nan
                continue
            tu[v, u] = tfx * X / Z + tcx
            tv[v, u] = tfy * Y / Z + tcy
            tz[v, u] = Z


@njit(cache=True, error_model="numpy")
def splat(tu, tv, tz, inverse, zbuf, map_u, map_v):
    """Round-to-nearest z-buffered splat (seed 003 method 2). zbuf (H, W) float64 = +inf.

    map_u/map_v receive the source coordinate to sample at each target pixel: the source pixel
    center (``inverse=False``), or the source center shifted by the splat's rounding offset
    (``inverse=True``: the source point that lands on the target pixel center, to first order
    with a unit Jacobian)."""
    h, w = tz.shape
    ht, wt = zbuf.shape
    for v in range(h):
        for u in range(w):
            z = tz[v, u]
            if not (z > 0.0):
                continue
            x = tu[v, u]
            y = tv[v, u]
            iu = int(np.floor(x + 0.5))
            iv = int(np.floor(y + 0.5))
            if iu < 0 or iv < 0 or iu >= wt or iv >= ht:
                continue
            if z < zbuf[iv, iu]:
                zbuf[iv, iu] = z
                if inverse:
                    map_u[iv, iu] = min(max(u + (iu - x), 0.0), w - 1.0)
                    map_v[iv, iu] = min(max(v + (iv - y), 0.0), h - 1.0)
                else:
                    map_u[iv, iu] = u
                    map_v[iv, iu] = v


@njit(cache=True, error_model="numpy")
def finish_splat(zbuf, map_u, map_v, depth, coverage, far_coord):
    h, w = zbuf.shape
    for v in prange(h):
        for u in range(w):
            z = zbuf[v, u]
            if z < np.inf:
                depth[v, u] = z
                coverage[v, u] = True
            else:
                depth[v, u] = np.nan
                coverage[v, u] = False
                map_u[v, u] = far_coord
                map_v[v, u] = far_coord
