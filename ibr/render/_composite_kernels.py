"""numba kernels of two-layer compositing and the fused sampler behind :mod:`ibr.render.composite`.

Private, no validation. Pixel centers at integer coordinates; bilinear taps are clamped to the
border pixels.
"""

from __future__ import annotations

import numpy as np
from ..base.jit import njit, prange

__all__: list[str] = []

# ------------------------------------------------------------------------- compositing
@njit(cache=True, error_model="numpy", inline="always")
def _store(out, v, u, ch, x, is_int, maxval):
    if is_int:  # round half up and clip: truncation of x + 0.5 clipped to [0, maxval + 0.5)
        out[v, u, ch] = min(max(x + 0.5, 0.0), maxval)
    else:
        out[v, u, ch] = x


@njit(cache=True, error_model="numpy", inline="always")
def _agree(a, b, rel_tol, quant0, quant2):
    """Whether two layer depths a, b are one surface: within ``rel_tol`` of the nearer, plus the
    depth encoding's quantization (``quant0 a b + quant2``: |1/a - 1/b| within k codes of the
    inverse-depth step c0 + c2 / z^2 of :class:`ibr.base.depth.DepthQuantization`, quant0 = k c0,
    quant2 = k c2; zero without quantization)."""
    return abs(a - b) <= rel_tol * min(a, b) + quant0 * a * b + quant2


@njit(cache=True, error_model="numpy", inline="always")
def _layer_depths(za_row, zb_row, u, single):
    """(a, has_a, b, has_b): the two layers' depths at pixel u of a target row and whether each
    covers it (``single``: only layer a exists; b is then meaningless). Written without a NaN
    default for b or a short-circuit ``and``: that form made the callers 1.6x slower."""
    a = za_row[u]
    b = za_row[u] if single else zb_row[u]
    has_b = b > 0.0
    if single:
        has_b = False
    return a, a > 0.0, b, has_b


#: Added to trust^4 in the blend weights: samples whose trust is below about its fourth root
#: (0.13) count as equally mixed and keep the viewpoint weights. 1e-3 (0.18) let a sample 85 %
#: on mixed pixels and 15 % on a clean one lose to one wholly mixed (clutter t = 0.75, (190, 148):
#: the pole's grey 52 levels off, the last covered pixel off the edge band over 48/255; 3e-4:
#: none, the band -0.01 / -0.02 dB on clutter / room; 1e-5 and below: -0.05 to -0.1 dB).
TRUST_FLOOR = 3e-4


@njit(cache=True, error_model="numpy", inline="always")
def _trust_weights(wa, wb, ka, kb):
    """Blend weights of two agreeing layers scaled by the fourth power of their trust (1 clean,
    ~0 a mixed silhouette pixel, bilinear in between); a small floor keeps the viewpoint weights
    when both are mixed (:data:`TRUST_FLOOR`)."""
    ka = ka * ka
    kb = kb * kb
    xa = wa * (ka * ka + TRUST_FLOOR)  # trust^4: a sample half on a mixed pixel is half contaminated,
    xb = wb * (kb * kb + TRUST_FLOOR)  # so it should lose clearly, not by a factor of two
    s = xa + xb
    return xa / s, xb / s


@njit(cache=True, error_model="numpy", parallel=True)
def composite2(ca, za, cb, zb, wa, wb, blend, rel_tol, quant0, quant2, is_int, maxval, out, depth, coverage, use_trust,
               ka, kb):
    """Two-layer composite (seed 002 section 2.2 step (1) and the depth-aware blend).

    ca, cb (H, W, C) float32 colors, za, zb (H, W) float32 depths (NaN uncovered), wa >= wb the
    viewpoint weights (layer a is the nearer source). blend=False: a in front, b fills a's holes.
    blend=True: where both cover and the depths agree (:func:`_agree`) the colors and depths
    are mixed with weights wa, wb (scaled by the per-pixel trust ka, kb when ``use_trust``);
    elsewhere the nearer surface wins. ``out`` may be an integer array (values rounded and
    clipped to [0, maxval])."""
    h, w, nc = ca.shape
    for v in prange(h):
        for u in range(w):
            a = za[v, u]
            b = zb[v, u]
            has_a = a > 0.0
            has_b = b > 0.0
            if has_a and has_b:
                if blend and _agree(a, b, rel_tol, quant0, quant2):
                    xa, xb = wa, wb
                    if use_trust:
                        xa, xb = _trust_weights(wa, wb, ka[v, u], kb[v, u])
                    for ch in range(nc):
                        _store(out, v, u, ch, xa * ca[v, u, ch] + xb * cb[v, u, ch], is_int, maxval)
                    depth[v, u] = xa * a + xb * b
                elif (not blend) or a <= b or wb == 0.0:  # a source of weight 0 only fills holes
                    for ch in range(nc):
                        _store(out, v, u, ch, ca[v, u, ch], is_int, maxval)
                    depth[v, u] = a
                else:
                    for ch in range(nc):
                        _store(out, v, u, ch, cb[v, u, ch], is_int, maxval)
                    depth[v, u] = b
                coverage[v, u] = True
            elif has_a:
                for ch in range(nc):
                    _store(out, v, u, ch, ca[v, u, ch], is_int, maxval)
                depth[v, u] = a
                coverage[v, u] = True
            elif has_b:
                for ch in range(nc):
                    _store(out, v, u, ch, cb[v, u, ch], is_int, maxval)
                depth[v, u] = b
                coverage[v, u] = True
            else:
                for ch in range(nc):
                    out[v, u, ch] = 0
                depth[v, u] = np.nan
                coverage[v, u] = False


# ------------------------------------------------------------------------- hole filling



@njit(cache=True, error_model="numpy", inline="always")
def _taps(src, x, y):
    """Bilinear taps of src (H, W, C) at pixel coordinates (x, y) (centers at integers); taps
    outside the image are clamped to the border pixels."""
    return _taps_in(src.shape[0], src.shape[1], x, y)


@njit(cache=True, error_model="numpy", inline="always")
def _taps_in(h, w, x, y):
    """:func:`_taps` of an h x w image: (x0, x1, y0, y1, ax, ay)."""
    fx0 = np.floor(x)
    fy0 = np.floor(y)
    ix = int(fx0)
    iy = int(fy0)
    return (min(max(ix, 0), w - 1), min(max(ix + 1, 0), w - 1), min(max(iy, 0), h - 1),
            min(max(iy + 1, 0), h - 1), np.float32(x - fx0), np.float32(y - fy0))


@njit(cache=True, error_model="numpy", inline="always")
def _lerp(src, x0, x1, y0, y1, ax, ay, ch):
    """Bilinear interpolation in float32 (integer sources are converted exactly per tap)."""
    p00 = np.float32(src[y0, x0, ch])
    p01 = np.float32(src[y0, x1, ch])
    p10 = np.float32(src[y1, x0, ch])
    p11 = np.float32(src[y1, x1, ch])
    top = p00 + ax * (p01 - p00)
    bot = p10 + ax * (p11 - p10)
    return top + ay * (bot - top)


@njit(cache=True, error_model="numpy", inline="always")
def _sample_store(src, x, y, out, v, u, is_int, maxval):
    x0, x1, y0, y1, ax, ay = _taps(src, x, y)
    for ch in range(out.shape[2]):
        _store(out, v, u, ch, _lerp(src, x0, x1, y0, y1, ax, ay, ch), is_int, maxval)


@njit(cache=True, error_model="numpy", inline="always")
def _lerp1(src, x0, x1, y0, y1, ax, ay):
    """Bilinear interpolation of channel 0 of an (H, W, 2) float32 trust map (channel 1: the
    minimum over the 2x2 block starting at each pixel, read first to skip clean blocks)."""
    top = src[y0, x0, 0] + ax * (src[y0, x1, 0] - src[y0, x0, 0])
    bot = src[y1, x0, 0] + ax * (src[y1, x1, 0] - src[y1, x0, 0])
    return top + ay * (bot - top)


@njit(cache=True, error_model="numpy", inline="always")
def _on_rim(k, x, y):
    """Whether the nearest source pixel of the sample at (x, y) is on the background rim (a
    negative block minimum in channel 1 of a packed trust map, ``composite.pack_trust``)."""
    x0, x1, y0, y1, ax, ay = _taps(k, x, y)
    return k[y1 if ay >= 0.5 else y0, x1 if ax >= 0.5 else x0, 1] < 0.0


@njit(cache=True, error_model="numpy", inline="always")
def _beside_gap(z, v, u):
    """Whether a 4-neighbour of target pixel (v, u) is not covered by the layer of depths ``z``
    (a hole, or a pixel only the other layer covers: either way that layer's surface ends there,
    a disocclusion of its source opens beside the pixel)."""
    h, w = z.shape
    for dv, du in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        y, x = v + dv, u + du
        if 0 <= y < h and 0 <= x < w and not (z[y, x] > 0.0):
            return True
    return False


#: A one-layer sample within this many pixels (4-connected) of its layer's gap does not take
#: colour from its source's background rim (:func:`_rim_free_store`, :func:`_rim_free_resample`).
RIM_FREE_GAP_PX = 2


@njit(cache=True, error_model="numpy", inline="always")
def _near_gap(z, v, u, r):
    """Whether a pixel up to ``r`` pixels from target pixel (v, u) along a row or column is not
    covered by the layer of depths ``z`` (``_beside_gap`` for ``r`` = 1)."""
    h, w = z.shape
    for d in range(1, r + 1):
        for dv, du in ((-d, 0), (d, 0), (0, -d), (0, d)):
            y, x = v + dv, u + du
            if 0 <= y < h and 0 <= x < w and not (z[y, x] > 0.0):
                return True
    return False


@njit(cache=True, error_model="numpy", inline="always")
def _trust_weighted(ax, ay, t00, t01, t10, t11):
    """Bilinear weights of taps (y0, x0), (y0, x1), (y1, x0), (y1, x1) scaled by their trust."""
    return (np.float32((1 - ax) * (1 - ay) * t00), np.float32(ax * (1 - ay) * t01), np.float32((1 - ax) * ay * t10),
            np.float32(ax * ay * t11))


@njit(cache=True, error_model="numpy", inline="always")
def _tap_mean(src, x0, x1, y0, y1, w, ch):
    """Channel ``ch`` of src over taps (y0, x0), (y0, x1), (y1, x0), (y1, x1), weighted by the
    four weights ``w`` (their sum need not be 1; it must not be 0)."""
    return ((w[0] * np.float32(src[y0, x0, ch]) + w[1] * np.float32(src[y0, x1, ch]) + w[2] * np.float32(src[y1, x0, ch])
             + w[3] * np.float32(src[y1, x1, ch])) / (w[0] + w[1] + w[2] + w[3]))


@njit(cache=True, error_model="numpy", inline="always")
def _rim_free_store(src, k, z, x, y, out, v, u, is_int, maxval):
    """Store the sample of src at (x, y) with its taps weighted by their trust (channel 0 of the
    packed trust map ``k``) and return True, where it is a clean source pixel's sample (the
    nearest tap clean) reaching into the background rim (a tap with the rim's negative flag in
    channel 1) within :data:`RIM_FREE_GAP_PX` of its layer's gap (depths ``z``). There the rim's
    colour mixes in a foreground that has moved away (a disocclusion that the other source
    does not see either): the bilinear sample drew a second, fainter rim line beside the one
    the fill recolours (issue 11, clutter t = 0.75, beside the left pole). False elsewhere
    (nothing stored)."""
    x0, x1, y0, y1, ax, ay = _taps(src, x, y)
    if k[y0, x0, 1] >= 1.0 or k[y1 if ay >= 0.5 else y0, x1 if ax >= 0.5 else x0, 0] < 1.0:
        return False  # four clean taps (their block minimum), or the nearest one mixed
    if not (k[y0, x0, 1] < 0.0 or k[y0, x1, 1] < 0.0 or k[y1, x0, 1] < 0.0 or k[y1, x1, 1] < 0.0):
        return False
    if not _near_gap(z, v, u, RIM_FREE_GAP_PX):
        return False
    w = _trust_weighted(ax, ay, k[y0, x0, 0], k[y0, x1, 0], k[y1, x0, 0], k[y1, x1, 0])
    for ch in range(out.shape[2]):
        _store(out, v, u, ch, _tap_mean(src, x0, x1, y0, y1, w, ch), is_int, maxval)
    return True


@njit(cache=True, error_model="numpy", nogil=True)
def rim_free_samples(ys, xs, src, k, z, map_u, map_v, out, is_int, maxval):
    """:func:`_rim_free_store` at the target pixels ``(ys, xs)`` that one layer alone covers
    (its depths ``z``, its maps ``map_u``, ``map_v`` into ``src`` with the packed trust ``k``):
    the float-layer paths' composite ``out`` (H, W, C) mended in place where it applies."""
    for i in range(ys.size):
        v, u = ys[i], xs[i]
        _rim_free_store(src, k, z, map_u[v, u], map_v[v, u], out, v, u, is_int, maxval)


@njit(cache=True, error_model="numpy", inline="always")
def _rim_free_resample(orow, u, src, rims, z, v, x, y, scale):
    """:func:`_rim_free_store` for the 8-bit path: ``src`` an (H_s, W_s, 4) colour + trust source
    (upsampled ``scale`` x ``scale`` co-sited: its image pixel (i, j) is at (scale i, scale j)),
    ``rims`` its (H_s, W_s) background rim; taps on the image's own pixels; into ``orow[u]``."""
    i0, i1, j0, j1, ax, ay = _taps_in(src.shape[0] // scale, src.shape[1] // scale, x, y)
    if src[(j1 if ay >= 0.5 else j0) * scale, (i1 if ax >= 0.5 else i0) * scale, 3] < 255:
        return
    if not (rims[j0, i0] or rims[j0, i1] or rims[j1, i0] or rims[j1, i1]) or not _near_gap(z, v, u, RIM_FREE_GAP_PX):
        return
    x0, x1, y0, y1 = i0 * scale, i1 * scale, j0 * scale, j1 * scale
    w = _trust_weighted(ax, ay, np.float32(src[y0, x0, 3]), np.float32(src[y0, x1, 3]), np.float32(src[y1, x0, 3]),
                        np.float32(src[y1, x1, 3]))
    for ch in range(3):
        orow[u, ch] = np.uint8(min(_tap_mean(src, x0, x1, y0, y1, w, ch) + np.float32(0.5), np.float32(255.0)))


@njit(cache=True, error_model="numpy", inline="always")
def _rims_beside_both_gaps(on_rim_a, on_rim_b, za, zb, v, u):
    """Whether two agreeing samples are both on their sources' background rims (``on_rim_a``,
    ``on_rim_b``), each beside its own layer's gap: neither source shows the surface's own colour
    there (a dot between two disocclusions, clutter t = 0.75 at (74-75, 230)), so the fill
    recolours it as it does a lone rim sample beside its gap."""
    return on_rim_a and on_rim_b and _beside_gap(za, v, u) and _beside_gap(zb, v, u)


@njit(cache=True, error_model="numpy", nogil=True)
def sample_composite2(v0, v1, sa, ua, va, za, sb, ub, vb, zb, single, wa, wb, blend, rel_tol, quant0, quant2, is_int,
                      maxval, out, depth, coverage, use_trust, ka, kb, rim):
    """Fused bilinear sampling + two-layer composite (see composite2): layer colors are sampled
    (in float32) from the sources sa, sb (any dtype: uint8 sources are read as is, 4x less memory
    traffic than a float32 copy, with identical results) at the maps (ua, va), (ub, vb) only where they are used, so
    no layer color image is ever written. ``single``: only layer a exists. ``use_trust``: the
    agreeing blend weights are scaled by the source-space trust maps ka, kb ((H_s, W_s, 2):
    trust and its 2x2 block minimum, negative on the background rim, see ``composite.pack_trust``), sampled
    with the same bilinear taps where a block holds a mixed pixel. ``rim`` (H, W) bool receives,
    where only one layer covers a pixel, whether its nearest source pixel is on that source's
    background rim and a 4-neighbour is not covered by that layer (the rule of
    ``composite.rim_beside_holes``: the fill recolours it; ``use_trust`` only, with two layers);
    near that gap, a clean pixel's sample keeps the rim's colour out (:func:`_rim_free_store`).
    Rows ``v0 .. v1-1`` only (serial, without the GIL: :func:`ibr.render.bands.run_bands` runs
    row bands on all cores)."""
    w, nc = out.shape[1], out.shape[2]
    for v in range(v0, v1):
        zar, zbr = za[v], zb[v]
        for u in range(w):
            rim[v, u] = False
            a, has_a, b, has_b = _layer_depths(zar, zbr, u, single)
            if has_a and has_b:
                if blend and _agree(a, b, rel_tol, quant0, quant2):
                    p0, p1, p2, p3, pax, pay = _taps(sa, ua[v, u], va[v, u])
                    q0, q1, q2, q3, qax, qay = _taps(sb, ub[v, u], vb[v, u])
                    xa, xb = wa, wb
                    if use_trust and (ka[p2, p0, 1] < 1.0 or kb[q2, q0, 1] < 1.0):  # a mixed tap near
                        xa, xb = _trust_weights(wa, wb, _lerp1(ka, p0, p1, p2, p3, pax, pay),
                                                _lerp1(kb, q0, q1, q2, q3, qax, qay))
                        rim[v, u] = _rims_beside_both_gaps(_on_rim(ka, ua[v, u], va[v, u]), _on_rim(kb, ub[v, u], vb[v, u]),
                                                           za, zb, v, u)
                    for ch in range(nc):
                        x = xa * _lerp(sa, p0, p1, p2, p3, pax, pay, ch) + xb * _lerp(sb, q0, q1, q2, q3, qax, qay, ch)
                        _store(out, v, u, ch, x, is_int, maxval)
                    depth[v, u] = xa * a + xb * b
                elif (not blend) or a <= b or wb == 0.0:  # a source of weight 0 only fills holes
                    _sample_store(sa, ua[v, u], va[v, u], out, v, u, is_int, maxval)
                    depth[v, u] = a
                else:
                    _sample_store(sb, ub[v, u], vb[v, u], out, v, u, is_int, maxval)
                    depth[v, u] = b
                coverage[v, u] = True
            elif has_a:
                if not (use_trust and _rim_free_store(sa, ka, za, ua[v, u], va[v, u], out, v, u, is_int, maxval)):
                    _sample_store(sa, ua[v, u], va[v, u], out, v, u, is_int, maxval)
                depth[v, u] = a
                coverage[v, u] = True
                rim[v, u] = use_trust and _on_rim(ka, ua[v, u], va[v, u]) and _beside_gap(za, v, u)
            elif has_b:
                if not (use_trust and _rim_free_store(sb, kb, zb, ub[v, u], vb[v, u], out, v, u, is_int, maxval)):
                    _sample_store(sb, ub[v, u], vb[v, u], out, v, u, is_int, maxval)
                depth[v, u] = b
                coverage[v, u] = True
                rim[v, u] = use_trust and _on_rim(kb, ub[v, u], vb[v, u]) and _beside_gap(zb, v, u)
            else:
                for ch in range(nc):
                    out[v, u, ch] = 0
                depth[v, u] = np.nan
                coverage[v, u] = False


@njit(cache=True, error_model="numpy", nogil=True)
def composite_rgbt(v0, v1, la, za, lb, zb, single, wa, wb, blend, rel_tol, quant0, quant2, out, depth, coverage, use_trust,
                   ra, ua, va, rb, ub, vb, rim, row0, sa, sb, scale):
    """Two-layer composite of 8-bit layers that ``cv2.remap`` sampled from colour + trust sources
    ((H, W, 4) uint8: three colour channels, then the trust in 1/255, see
    ``composite.rgbt_source``); the rule of :func:`sample_composite2` with the trust read from
    channel 3. ``ra``, ``rb`` (H_s, W_s) bool: each source's background rim, looked up at the
    nearest source pixel of the maps (ua, va), (ub, vb) where only one layer covers a pixel and a
    4-neighbour is not covered by that layer (``use_trust`` only); near that gap, a clean pixel's
    sample is taken again from ``sa`` or ``sb`` (the sources, upsampled ``scale`` x ``scale``)
    without the rim's colour (:func:`_rim_free_resample`). ``out`` (H, W, 3) uint8. Rows ``v0 .. v1-1``;
    ``la``, ``lb`` hold rows ``row0 ..`` only (a chunk of rows sampled just before)."""
    w = out.shape[1]
    for v in range(v0, v1):
        # row views: with 2-D indexing in the pixel loop (numba cannot tell the arrays apart, so
        # every store reloads the 3-D strides) the kernel took 1.5x the time
        lar, lbr, orow = la[v - row0], lb[v - row0], out[v]
        zar, zbr, drow, crow, rrow = za[v], zb[v], depth[v], coverage[v], rim[v]
        for u in range(w):
            rrow[u] = False
            a, has_a, b, has_b = _layer_depths(zar, zbr, u, single)
            if has_a and has_b and blend and _agree(a, b, rel_tol, quant0, quant2):
                xa, xb = wa, wb
                ta = lar[u, 3]
                tb = lbr[u, 3]
                if use_trust and (ta < 255 or tb < 255):  # a mixed source pixel among the taps
                    xa, xb = _trust_weights(wa, wb, np.float32(ta) * np.float32(1 / 255),
                                            np.float32(tb) * np.float32(1 / 255))
                ia = np.int32(xa * 65536.0 + 0.5)  # weights in 1/65536: integer blend, rounded
                ib = np.int32(65536) - ia  # (float to 8-bit conversions cost twice as much)
                o0 = (ia * np.int32(lar[u, 0]) + ib * np.int32(lbr[u, 0]) + 32768) >> 16
                o1 = (ia * np.int32(lar[u, 1]) + ib * np.int32(lbr[u, 1]) + 32768) >> 16
                o2 = (ia * np.int32(lar[u, 2]) + ib * np.int32(lbr[u, 2]) + 32768) >> 16
                orow[u, 0] = o0
                orow[u, 1] = o1
                orow[u, 2] = o2
                drow[u] = xa * a + xb * b
                crow[u] = True
                if use_trust and ta < 255 and tb < 255:
                    rrow[u] = _rims_beside_both_gaps(_nearest(ra, ua[v, u], va[v, u]), _nearest(rb, ub[v, u], vb[v, u]),
                                                     za, zb, v, u)
            elif has_a or has_b:
                # one layer, or two surfaces: layer a when it is the only one, the nearer one, or
                # (front order, not ``blend``) the first; no arrays are rebound per pixel (numba
                # counts references on each rebinding: a one-source warp, where every pixel comes
                # here, ran 2x slower)
                if has_a and (not has_b or not blend or a <= b or wb == 0.0):
                    _copy3(orow, lar, u)
                    drow[u] = a
                else:
                    _copy3(orow, lbr, u)
                    drow[u] = b
                crow[u] = True
                if use_trust and not (has_a and has_b):  # one layer: is it a rim beside its gap?
                    on_rim = _nearest(ra, ua[v, u], va[v, u]) if has_a else _nearest(rb, ub[v, u], vb[v, u])
                    rrow[u] = on_rim and _beside_gap(za if has_a else zb, v, u)
                    if (lar[u, 3] if has_a else lbr[u, 3]) < 255:  # a mixed tap: the rim's colour kept out?
                        if has_a:
                            _rim_free_resample(orow, u, sa, ra, za, v, ua[v, u], va[v, u], scale)
                        else:
                            _rim_free_resample(orow, u, sb, rb, zb, v, ub[v, u], vb[v, u], scale)
            else:
                orow[u, 0] = 0
                orow[u, 1] = 0
                orow[u, 2] = 0
                drow[u] = np.nan
                crow[u] = False


@njit(cache=True, error_model="numpy", inline="always")
def _copy3(dst, src, u):
    """dst[u, :3] = src[u, :3] (a row of an RGB and of an RGBT layer)."""
    dst[u, 0] = src[u, 0]
    dst[u, 1] = src[u, 1]
    dst[u, 2] = src[u, 2]


@njit(cache=True, error_model="numpy", inline="always")
def _nearest(flags, x, y):
    """flags (H, W) bool at the nearest pixel of (x, y) (clamped to the image; the pixel
    :func:`_on_rim` reads)."""
    h, w = flags.shape
    return flags[min(max(int(np.floor(y + 0.5)), 0), h - 1), min(max(int(np.floor(x + 0.5)), 0), w - 1)]
