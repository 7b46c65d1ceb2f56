"""numba kernel behind :func:`ibr.canvas.composite_into`: blend one canvas into a pinhole target.

Private, no validation. Pixel centres at integer coordinates, in the target and in the canvas.
The texture has already been sampled at every pixel of the target box (``cv2.warpPerspective``
of the premultiplied canvas through the exact homography); this pass adds what depends on the
target: which pixels the rectangle covers (anti-aliased), occlusion by the scene depth, and the
"over" blend. It needs no division: ``1/z``, the coverage distances and the depth test are all
affine in the target pixel (u, v).
"""

from __future__ import annotations

import numpy as np
from ..base.jit import njit, prange

__all__: list[str] = []


@njit(cache=True, error_model="numpy", inline="always")
def _clamp01(x):
    return min(max(x, 0.0), 1.0)


@njit(cache=True, error_model="numpy", inline="always")
def _interval(a, c, bound, lo, hi):
    """Narrow [lo, hi] to the u where ``a u + c >= bound``."""
    if a > 0.0:
        lo = max(lo, (bound - c) / a)
    elif a < 0.0:
        hi = min(hi, (bound - c) / a)
    elif c < bound:
        hi = lo - 1.0
    return lo, hi


@njit(cache=True, error_model="numpy", parallel=True)
def blend_samples(out, depth, use_depth, write_depth, samp, samp_scale, v0, u0, inv_z, lines, tol, out_scale,
                  is_int, maxval, antialias, direct):
    """Blend premultiplied samples ``samp`` (h, w, k) over ``out[v0:v0+h, u0:u0+w]`` (H, W, nc).

    ``samp[..., k-1]`` is alpha, ``samp[..., :k-1]`` the premultiplied colour (k - 1 = nc, or 1
    for a gray sample into nc = 1); an output channel 3 (RGBA targets) blends the alpha itself.
    ``inv_z = (a, b, c)``: ``1/z = a u + b v + c`` of the canvas plane (<= 0: behind the camera).
    ``lines`` (4, 3): the canvas edges as target-image lines scaled so that ``lines[k] . (u, v, 1)``
    is the signed distance in target pixels (positive inside, where 1/z > 0). Coverage is the
    product of ``clamp(1/2 + d_k)`` with ``antialias``, else 1 where every ``d_k >= 0`` (the
    right and bottom edges exclusive). Occlusion: hidden where ``depth > 0`` and
    ``z > depth (1 + tol)``, i.e. ``1 > (1/z) depth (1 + tol)``. ``write_depth`` stores z where the
    blended alpha reaches 1/2.

    Each row visits only the u where the coverage can be positive (an interval: the quad is
    convex); where it is 1 (every d_k >= 1/2) an opaque sample is copied as it is when ``direct``
    (samples and output share dtype and channels), which is the whole interior of a video frame.
    """
    h, w, k = samp.shape
    nc = out.shape[2]
    na = k - 1
    za, zb, zc = inv_z[0], inv_z[1], inv_z[2]
    zscale = 1.0 + tol
    outer = -0.5 if antialias else 0.0
    inner = 0.5 if antialias else 0.0
    amax = 1.0 / samp_scale
    for j in prange(h):
        v = v0 + j
        lo, hi = float(u0), float(u0 + w - 1)
        lo, hi = _interval(za, zb * v + zc, 1e-300, lo, hi)
        ilo, ihi = lo, hi
        for q in range(4):
            c = lines[q, 1] * v + lines[q, 2]
            lo, hi = _interval(lines[q, 0], c, outer, lo, hi)
            ilo, ihi = _interval(lines[q, 0], c, inner, ilo, ihi)
        if hi < lo:
            continue
        ua = max(u0, int(np.ceil(lo)))
        ub = min(u0 + w - 1, int(np.floor(hi)))
        ia = int(np.ceil(ilo)) + 1  # one pixel of margin against rounding at the interval ends
        ib = int(np.floor(ihi)) - 1
        for u in range(ua, ub + 1):
            i = u - u0
            iz = za * u + zb * v + zc
            if not (iz > 0.0):
                continue
            if use_depth:
                zs = depth[v, u]
                if zs > 0.0 and 1.0 > iz * zs * zscale:
                    continue
            a_raw = samp[j, i, na]
            if ia <= u <= ib:
                cov = 1.0
                if direct and a_raw >= amax:
                    for ch in range(nc):
                        out[v, u, ch] = samp[j, i, ch]
                    if write_depth:
                        depth[v, u] = 1.0 / iz
                    continue
            else:
                d0 = lines[0, 0] * u + lines[0, 1] * v + lines[0, 2]
                d1 = lines[1, 0] * u + lines[1, 1] * v + lines[1, 2]
                d2 = lines[2, 0] * u + lines[2, 1] * v + lines[2, 2]
                d3 = lines[3, 0] * u + lines[3, 1] * v + lines[3, 2]
                if antialias:
                    cov = _clamp01(0.5 + d0) * _clamp01(0.5 + d1) * _clamp01(0.5 + d2) * _clamp01(0.5 + d3)
                else:
                    cov = 1.0 if (d0 >= 0.0 and d1 > 0.0 and d2 >= 0.0 and d3 > 0.0) else 0.0
                if cov <= 0.0:
                    continue
            alpha = a_raw * samp_scale * cov
            if alpha <= 0.0:
                continue
            keep = 1.0 - alpha
            s = samp_scale * cov * out_scale
            for ch in range(nc):
                if ch < na:
                    p = samp[j, i, ch] * s
                elif ch == 3:
                    p = alpha * out_scale
                else:  # a gray sample into several colour channels
                    p = samp[j, i, 0] * s
                val = p + out[v, u, ch] * keep
                if is_int:
                    out[v, u, ch] = min(max(val + 0.5, 0.0), maxval)
                else:
                    out[v, u, ch] = val
            if write_depth and alpha >= 0.5:
                depth[v, u] = 1.0 / iz
