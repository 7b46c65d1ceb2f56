"""numba kernel behind :func:`panorama.maps.perspective_map` (private; no validation here).

Builds the remap coordinates of a pinhole view directly per pixel (ray, rotation, then the
equirect or cube-face pixel), the same float64 formulas as :mod:`panorama.directions`
(``lonlat_from_direction``, ``face_pixel_from_direction``), without the (H, W, 3) arrays of the
numpy path: a new view direction every frame costs one pass instead of ~10 array passes.
"""

from __future__ import annotations

import math

import numpy as np
from ibr.base.jit import njit, prange

__all__: list[str] = []


def _atan_coefficients(degree: int = 10) -> np.ndarray:
    """``atan(x) = x P(x^2)`` on [0, 1]: least-squares polynomial P (increasing powers); max
    error 2.8e-10 rad at degree 10 (4e-7 of an equirect pixel at 4096 wide), several times cheaper
    than the libm ``atan2`` that dominated the map build."""
    t = 0.5 + 0.5 * np.cos(np.linspace(0.0, np.pi, 4001))[:-1]  # (0, 1], Chebyshev-spaced
    return np.polynomial.polynomial.polyfit(t, np.arctan(np.sqrt(t)) / np.sqrt(t), degree)


ATAN_POLY = _atan_coefficients(7)


@njit(cache=True, error_model="numpy", inline="always", fastmath={"arcp", "contract", "nsz"})
def _atan2(y, x, c0, c1, c2, c3, c4, c5, c6, c7):
    """atan2 through :data:`ATAN_POLY` (same quadrants as math.atan2 except the sign of -0);
    the polynomial in Estrin's form (short dependency chains)."""
    ay, ax = abs(y), abs(x)
    if ay > ax:
        r = ax / ay
    elif ax > 0.0:
        r = ay / ax
    else:
        return 0.0
    t = r * r
    t2 = t * t
    p = (c0 + c1 * t) + t2 * (c2 + c3 * t) + t2 * t2 * ((c4 + c5 * t) + t2 * (c6 + c7 * t))
    a = r * p
    if ay > ax:
        a = 0.5 * math.pi - a
    if x < 0.0:
        a = math.pi - a
    return -a if y < 0.0 else a


@njit(cache=True, error_model="numpy", parallel=True, fastmath={"arcp", "contract", "nsz"})
def perspective_map(rot, fx, fy, cx, cy, cube, src_h, src_w, axis_of, sign_of, poly, out_x, out_y):
    """out_x/out_y (H, W) float32: source coordinates of view pixel (u, v) (centres at integers).

    rot: world_from_view (3, 3). cube: padded-atlas coordinates of :mod:`panorama.maps` (face f
    pixel (i, j) at (i + 1, j + 1 + f (S + 2)), S = src_h); else equirect (u, v), unpadded.
    """
    h, w = out_x.shape
    s = float(src_h)
    ifx = 1.0 / fx
    c0, c1, c2, c3, c4, c5, c6, c7 = poly[0], poly[1], poly[2], poly[3], poly[4], poly[5], poly[6], poly[7]
    for v in prange(h):
        ry = (v - cy) / fy
        for u in range(w):
            rx = (u - cx) * ifx
            dx = rot[0, 0] * rx + rot[0, 1] * ry + rot[0, 2]
            dy = rot[1, 0] * rx + rot[1, 1] * ry + rot[1, 2]
            dz = rot[2, 0] * rx + rot[2, 1] * ry + rot[2, 2]
            if cube:
                ax, ay, az = abs(dx), abs(dy), abs(dz)
                k = 0  # dominant axis, ties to the lower one (numpy argmax)
                if ay > ax:
                    k = 1
                if az > max(ax, ay):
                    k = 2
                comp = dx if k == 0 else (dy if k == 1 else dz)
                face = 2 * k + (1 if comp < 0 else 0)
                inv = 1.0 / abs(comp)
                ka, kb = axis_of[0, face], axis_of[1, face]
                da = dx if ka == 0 else (dy if ka == 1 else dz)
                db = dx if kb == 0 else (dy if kb == 1 else dz)
                a = da * (sign_of[0, face] * inv)
                b = db * (sign_of[1, face] * inv)
                out_x[v, u] = (a + 1) * 0.5 * s - 0.5 + 1.0
                out_y[v, u] = (b + 1) * 0.5 * s - 0.5 + 1.0 + face * (s + 2.0)
            else:
                lon = _atan2(dx, dz, c0, c1, c2, c3, c4, c5, c6, c7)
                lat = _atan2(-dy, math.sqrt(dx * dx + dz * dz), c0, c1, c2, c3, c4, c5, c6, c7)
                out_x[v, u] = (lon / (2 * math.pi) + 0.5) * src_w - 0.5
                out_y[v, u] = (0.5 - lat / math.pi) * src_h - 0.5
