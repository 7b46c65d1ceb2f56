"""numba kernel behind :mod:`ibr.render.edge_antialias` (private; no validation here).

Conventions as in :mod:`ibr.render._raster_kernels`: pixel (u, v) = (column, row), centres at
integers; a quad's coefficient row ``[g, Hx, Hy, Hz]`` (``setup_quads``) gives ``1/z_t = g.p``
and the source position ``(Hx.p, Hy.p) / Hz.p`` of the target point ``p = (u, v, 1)``; the
quad owns the half-open source outline ``[u0 - .5, u1 - .5) x [v0 - .5, v1 - .5)``.
"""

from __future__ import annotations

import numpy as np

from ..base.jit import njit

__all__: list[str] = []


def _subsample_quads(i0, i1, xs, ys, offsets, map_u, map_v, coverage, qop, rects, coef, clamp, far_coord,
                     out_u, out_v, out_z, out_c, out_same):
    """Source coordinates and depth of the subsamples ``(xs[i] + offsets[s, 0], ys[i] +
    offsets[s, 1])`` of target pixels ``i0 .. i1-1``, z-buffered over the quads that cover the
    pixel or one of its eight neighbours at their centres (``map_u``, ``map_v``, ``coverage``:
    the source's rasterized maps; ``qop``: the source mesh's quad of each source pixel). Writes
    ``out_*[s, i]`` (m, n); ``far_coord`` and NaN depth where no quad covers a subsample;
    ``out_same``: the subsample lies on the quad of the pixel's centre (or both are uncovered)."""
    h, w = coverage.shape
    hs, ws = qop.shape
    m = offsets.shape[0]
    cand = np.empty(9, np.int64)
    best = np.empty(m, np.float64)
    won = np.empty(m, np.int64)  # the quad each subsample found
    in_centre = np.empty(m, np.bool_)  # inside the outline of the centre's quad
    for i in range(i0, i1):
        x, y = xs[i], ys[i]
        centre = -1
        if coverage[y, x]:
            centre = qop[min(max(int(np.floor(map_v[y, x] + 0.5)), 0), hs - 1),
                         min(max(int(np.floor(map_u[y, x] + 0.5)), 0), ws - 1)]
        nc = 0
        for yy in range(max(y - 1, 0), min(y + 2, h)):
            for xx in range(max(x - 1, 0), min(x + 2, w)):
                if not coverage[yy, xx]:
                    continue
                su = min(max(int(np.floor(map_u[yy, xx] + 0.5)), 0), ws - 1)
                sv = min(max(int(np.floor(map_v[yy, xx] + 0.5)), 0), hs - 1)
                q = qop[sv, su]
                new = q >= 0
                for j in range(nc):
                    if cand[j] == q:
                        new = False
                if new:
                    cand[nc] = q
                    nc += 1
        for s in range(m):
            best[s] = 0.0
            won[s] = -1
            in_centre[s] = False
            out_u[s, i] = far_coord
            out_v[s, i] = far_coord
        for j in range(nc):
            q = cand[j]
            g0, g1, g2 = coef[q, 0], coef[q, 1], coef[q, 2]
            x0, x1, x2 = coef[q, 3], coef[q, 4], coef[q, 5]
            y0, y1, y2 = coef[q, 6], coef[q, 7], coef[q, 8]
            z0, z1, z2 = coef[q, 9], coef[q, 10], coef[q, 11]
            eu0, ev0, eu1, ev1 = rects[q, 0] - 0.5, rects[q, 1] - 0.5, rects[q, 2] - 0.5, rects[q, 3] - 0.5
            for s in range(m):
                fu = x + offsets[s, 0]
                fv = y + offsets[s, 1]
                iz = g0 * fu + g1 * fv + g2
                if not (iz > best[s]) and q != centre:
                    continue
                hz = z0 * fu + z1 * fv + z2
                if not (hz > 0.0):
                    continue
                hx = x0 * fu + x1 * fv + x2
                hy = y0 * fu + y1 * fv + y2
                if not (hx - eu0 * hz >= 0.0 and hx - eu1 * hz < 0.0 and hy - ev0 * hz >= 0.0 and hy - ev1 * hz < 0.0):
                    continue
                if q == centre:
                    in_centre[s] = True  # inside the centre quad's outline, whatever its plane says there
                    if not (iz > best[s]):
                        continue
                us = hx / hz
                vs = hy / hz
                if clamp[q, 0] != 0 and us < eu0 + 0.5:
                    us = eu0 + 0.5
                if clamp[q, 2] != 0 and us > eu1 - 0.5:
                    us = eu1 - 0.5
                if clamp[q, 1] != 0 and vs < ev0 + 0.5:
                    vs = ev0 + 0.5
                if clamp[q, 3] != 0 and vs > ev1 - 0.5:
                    vs = ev1 - 0.5
                best[s] = iz
                won[s] = q
                out_u[s, i] = us
                out_v[s, i] = vs
        for s in range(m):
            b = best[s]
            out_c[s, i] = b > 0.0
            out_z[s, i] = 1.0 / b if b > 0.0 else np.nan
            # on the centre's quad; or uncovered inside its outline (a plane fitted exactly to two
            # pixels across a step reaches 1/z <= 0 within its own pixel): as the centre, no edge
            out_same[s, i] = won[s] == centre or (b <= 0.0 and in_centre[s])


#: Candidates ``i0 .. i1-1`` without the GIL (:func:`ibr.render.bands.run_bands` splits them
#: over the threads)
subsample_quads = njit(cache=True, error_model="numpy", nogil=True)(_subsample_quads)


#: Weight of an edge pixel's centre in its mean (each subsample counts once): a tent rather than a
#: box over the pixel. Measured (bench_edges, clutter / room edge band, dB): 1: 29.87 / 31.28,
#: 2: 29.90 / 31.34, 3: 29.84 / 31.35, 4: 29.74 / 31.34.
CENTRE_WEIGHT = 2.0


@njit(cache=True, error_model="numpy", nogil=True)
def average_edges(color, depth, ys, xs, sub_color, sub_depth, sub_coverage, sub_same, rel, rounded, edge):
    """Filter the edge pixels among ``ys, xs`` (covered) over their subsamples in place (see
    :func:`ibr.render.edge_antialias.average_edge_pixels`; ``sub_same``: subsamples on the
    centre's own quads, left out of the edge test; ``rounded``: integer colour); sets
    ``edge[i]`` for the pixels changed."""
    nch = color.shape[2]
    m = sub_depth.shape[0]
    vals = np.empty(m + 1, np.float64)
    acc = np.empty(nch, np.float64)
    norm = 1.0 / (m + CENTRE_WEIGHT)
    for i in range(ys.shape[0]):
        y, x = ys[i], xs[i]
        vals[0] = 1.0 / depth[y, x]
        nf = 1
        e = False
        uncovered = 0
        for s in range(m):
            if not sub_coverage[s, i]:
                uncovered += 1
            if sub_same[s, i]:
                continue
            if sub_coverage[s, i]:
                vals[nf] = 1.0 / sub_depth[s, i]
                nf += 1
            else:
                e = True  # covered and uncovered subsamples
        for j in range(1, nf):  # insertion sort of at most m + 1 values
            v = vals[j]
            k = j - 1
            while k >= 0 and vals[k] > v:
                vals[k + 1] = vals[k]
                k -= 1
            vals[k + 1] = v
        for j in range(1, nf):
            if vals[j] > vals[j - 1] * (1.0 + rel):
                e = True
        edge[i] = e
        if not e:
            continue
        for c in range(nch):  # the pixel itself: its centre, and each uncovered subsample
            acc[c] = color[y, x, c] * (CENTRE_WEIGHT + uncovered)
        for s in range(m):
            if sub_coverage[s, i]:
                for c in range(nch):
                    acc[c] += sub_color[s, i, c]
        for c in range(nch):  # each pixel reads only its own colour: written in place at once
            v = acc[c] * norm
            color[y, x, c] = np.floor(v + 0.5) if rounded else v
