"""Foreground rim samples re-composited over the target's own background (issue 11: ghost outlines).

A camera integrates each pixel over its area, so the pixel on the foreground side of a silhouette
holds ``C = alpha F + (1 - alpha) B_s``: its foreground colour F mixed with the background B_s
that the *source* saw beside it. Drawn at the foreground's depth into a new view, where parallax
has put another background B_t beside the silhouette, that mix is a light or dark outline along
the foreground (clutter at t = 0.5: a grey column along the dark sphere's right edge, the wall's
colour in the rim, over the navy box the target sees there). Where the other source sees that
surface, the silhouette-aware compositor already blends in its samples; where only one source
sees it, this module swaps the background in the mix (boundary matting, in the spirit of
two-layer representations), ``C' = C + (1 - alpha) (B_t - B_s)``:

* once per source (:func:`rim_matte`), every foreground-rim pixel (the nearer pixel of a depth
  step, :func:`~ibr.render.composite.mixed_pixels`) with clean neighbours on both sides gets
  ``alpha = (C - B).(F - B) / |F - B|^2`` from the mean colours F, B of its 3 x 3 neighbours on
  its own surface (not themselves on a silhouette) and on the farther one; kept where F and B
  differ enough to read alpha (:data:`MIN_CONTRAST`) and alpha < :data:`MAX_ALPHA`, with the
  neighbour toward the background and its colour B_s;
* per frame (:func:`rematte_rims`), each kept rim pixel is
  projected into the target; a target pixel of the 2 x 2 around it whose composite shows that
  sample (its layer covers it at the composite's depth and samples that very source pixel, and
  the other source does not see that surface there) and whose pixel toward the background lies
  farther, with a colour B_t that differs from B_s by more than :data:`MIN_CHANGE` in some
  channel, gets the new mix. At a source's own pose B_t is B_s: the source comes back unchanged.

The work is proportional to the number of rim pixels, not to the frame. Conventions: colours in
the source's value scale (8-bit 0..255, 16-bit 0..65535, float as is); pixel centres at integers.

Measured (``python benchmarks/bench_edges.py --quick``): see docs/edges.md ("Foreground rims over a
new background").
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..base.camera import Camera
from .composite import mixed_pixels

__all__ = ["MAX_ALPHA", "MIN_CHANGE", "MIN_CONTRAST", "RimMatte", "rematte_rims", "rematte_subsamples", "rim_matte"]

#: Smallest RMS difference (fraction of the colour's full scale) between a rim pixel's foreground
#: and background colours at which its alpha is read from its colour.
MIN_CONTRAST = 30.0 / 255.0
#: Rim pixels whose alpha is at least this are foreground enough to be left as they are.
MAX_ALPHA = 0.95
#: Smallest change of the background (fraction of full scale, largest channel) behind a rim
#: sample, from the source's to the target's, at which the sample is re-composited (smaller
#: changes are within the estimates' own error: 40/255 lost on room, 80/255 gains on clutter).
MIN_CHANGE = 80.0 / 255.0
#: Relative depth difference of a step (as the silhouettes of :mod:`ibr.render.composite`).
_STEP = 0.02
_RING = [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1) if (dy, dx) != (0, 0)]


@dataclass(frozen=True, eq=False)
class RimMatte:
    """A source's foreground-rim pixels that can be unmixed (:func:`rim_matte`).

    ``flat`` (N,) int64 sorted flat pixel indices (row-major); ``points`` (N, 3) float64 their
    world points; ``alpha`` (N,) foreground share; ``toward`` (N, 2) int64 the neighbour (dy, dx)
    nearest to the direction of the background, and ``behind`` (N, C) float64 that neighbour's
    colour (the background the source saw beside the rim), in the colour's value scale;
    ``scale`` the colour's full scale.
    """

    flat: np.ndarray
    points: np.ndarray
    alpha: np.ndarray
    toward: np.ndarray
    behind: np.ndarray
    scale: float

    def __len__(self) -> int:
        return int(self.flat.size)


def _full_scale(dtype) -> float:
    return float(np.iinfo(dtype).max) if np.issubdtype(dtype, np.integer) else 1.0


def rim_matte(color: np.ndarray, depth: np.ndarray, camera: Camera, *, quantization=None,
              silhouettes=None) -> RimMatte:
    """The unmixable foreground-rim pixels of a source (module docstring).

    Parameters
    ----------
    color : (H, W, C) array
        The source's colour (uint8, uint16 or float; an alpha channel is carried like colour).
    depth : (H, W) float
        Its planar depth (NaN where none), e.g. its mesh's depth (quantized codes are no steps).
    camera : Camera
        Its camera (the rim pixels' world points).
    quantization : DepthQuantization, optional
        The depth's encoding (:func:`~ibr.render.composite.mixed_pixels`).
    silhouettes : (both, far) of (H, W) bool, optional
        :func:`~ibr.render.composite.mixed_pixels` of ``depth`` on both sides of each step and on
        its far side, if already found (then ``quantization`` is not used).
    """
    c = np.asarray(color)
    z = np.asarray(depth, np.float64)
    if c.ndim != 3 or c.shape[:2] != z.shape:
        raise ValueError(f"color: expected (H, W, C) with the depth's (H, W) = {z.shape}, got shape {c.shape}")
    if not isinstance(camera, Camera) or camera.shape != z.shape:
        raise ValueError(f"camera: expected a Camera of the depth's shape {z.shape}")
    scale = _full_scale(c.dtype)
    if silhouettes is None:
        silhouettes = (mixed_pixels(z, quantization=quantization), mixed_pixels(z, side="far", quantization=quantization))
    both, far = (np.asarray(m, bool) for m in silhouettes)
    if both.shape != z.shape or far.shape != z.shape:
        raise ValueError(f"silhouettes: expected two (H, W) masks of the depth's shape {z.shape}")
    ys, xs = np.nonzero(both & ~far)  # the near side
    fg, bg, toward = _side_means(c, z, both, ys, xs)
    diff = fg - bg
    contrast2 = (diff * diff).sum(1)
    alpha = np.clip(((c[ys, xs] - bg) * diff).sum(1) / np.maximum(contrast2, 1e-30), 0.0, 1.0)
    keep = ~np.isnan(contrast2) & (contrast2 >= (MIN_CONTRAST * scale) ** 2 * c.shape[2]) & (alpha < MAX_ALPHA)
    ys, xs, toward = ys[keep], xs[keep], toward[keep]
    h, w = z.shape
    points = camera.unproject(np.stack([xs, ys], -1).astype(np.float64), z[ys, xs])
    by = np.clip(ys + toward[:, 0], 0, h - 1)
    bx = np.clip(xs + toward[:, 1], 0, w - 1)
    behind = c[by, bx].astype(np.float64)
    return RimMatte(ys.astype(np.int64) * w + xs, points, alpha[keep], toward, behind, scale)


def _side_means(c, z, both, ys, xs):
    """Per rim pixel (ys, xs): the mean colours (N, C) of its 3 x 3 neighbours on its own surface
    (within :data:`_STEP`, not on a silhouette themselves) and on a farther one (NaN where it has
    none), and the 8-neighbour (dy, dx) nearest to the mean direction of the farther ones."""
    h, w = z.shape
    zp = z[ys, xs]
    n, nc = ys.size, c.shape[2]
    sums = {"own": np.zeros((n, nc)), "behind": np.zeros((n, nc))}
    counts = {"own": np.zeros(n), "behind": np.zeros(n)}
    direction = np.zeros((n, 2))
    for dy, dx in _RING:
        jy, jx = ys + dy, xs + dx
        inside = (jy >= 0) & (jy < h) & (jx >= 0) & (jx < w)
        jy, jx = np.clip(jy, 0, h - 1), np.clip(jx, 0, w - 1)
        zq, cq = z[jy, jx], c[jy, jx].astype(np.float64)
        with np.errstate(invalid="ignore"):
            sides = {"own": inside & (np.abs(zq - zp) <= _STEP * zp) & ~both[jy, jx],
                     "behind": inside & (zq > zp * (1.0 + _STEP))}
        for side, m in sides.items():
            sums[side] += m[:, None] * cq
            counts[side] += m
        direction += sides["behind"][:, None] * (dy, dx)
    with np.errstate(invalid="ignore", divide="ignore"):
        fg, bg = (sums[s] / counts[s][:, None] for s in ("own", "behind"))
    angle = np.arctan2(direction[:, 0], direction[:, 1])
    toward = np.stack([np.rint(np.sin(angle)), np.rint(np.cos(angle))], -1).astype(np.int64)
    return fg, bg, toward


def rematte_rims(color: np.ndarray, depth: np.ndarray, camera: Camera, layers, mattes, source_shapes,
                 *, depth_tol: float = _STEP) -> int:
    """Re-composite the target pixels that show an unmixable foreground-rim sample over the
    target's own background, in place in ``color`` (module docstring).

    The rim pixels of all sources are projected into the target together and the 2 x 2 pixels
    around each tested, the cheap and selective tests first (the composite shows that surface
    there and another one behind it, whose colour changed), the maps' exact test last: a frame
    costs a few dozen array operations on the rim pixels (numpy; a numba kernel ran 4x faster
    but its compile added 0.58 s to a first ``ibr interpolate``, issue 13's cold start).

    Parameters
    ----------
    color : (H, W, C) array
        The composite's colour, any dtype (integers rounded and clipped).
    depth : (H, W) float
        The composite's planar depth (NaN where uncovered).
    camera : Camera
        The target camera.
    layers : sequence of maps
        Per source, where each target pixel samples it: ``map_u``, ``map_v`` (source pixel
        coordinates), ``depth`` and ``coverage`` (H, W) (:class:`~ibr.render.rasterize.SourceMaps`).
    mattes : sequence of RimMatte
        Per source, :func:`rim_matte`.
    source_shapes : sequence of (H_s, W_s)
        Per source, its image shape.

    Returns
    -------
    int
        The number of pixels re-composited.
    """
    if len(layers) != len(mattes) or len(mattes) != len(source_shapes) or len(mattes) not in (1, 2):
        raise ValueError("layers, mattes, source_shapes: expected one or two of each, as many of each")
    if np.ndim(depth) != 2 or np.ndim(color) != 3 or np.shape(color)[:2] != np.shape(depth):
        raise ValueError(f"color, depth: expected (H, W, C) and (H, W) of one size, got shapes {np.shape(color)} "
                         f"and {np.shape(depth)}")
    if not isinstance(camera, Camera) or camera.shape != np.shape(depth):
        raise ValueError(f"camera: expected a Camera of the depth's shape {np.shape(depth)}")
    if any(not isinstance(m, RimMatte) for m in mattes):
        raise TypeError("mattes: expected RimMatte objects (rim_matte)")
    rims = _joined(tuple(mattes))
    h, w = depth.shape
    k, px, b_t = _candidates(rims, color, depth, camera, depth_tol)
    if not k.size:  # the common case: no rim sample drawn over a new background
        return 0
    keep = _shown_alone(rims, k, px, layers, source_shapes, depth, depth_tol)
    px, k = px[keep], k[keep]
    flat = color.reshape(h * w, -1)
    flat[px] = _remixed(flat[px], rims.alpha[k], b_t[keep] - rims.behind[k])  # after every test read the composite
    return int(px.size)


def _remixed(colors: np.ndarray, alpha: np.ndarray, change: np.ndarray) -> np.ndarray:
    """``colors`` (N, C) with the background in their mix swapped: ``C + (1 - alpha) (B_t - B_s)``
    (``change`` = B_t - B_s), in their dtype (integers rounded and clipped)."""
    value = colors.astype(np.float64) + (1.0 - alpha)[:, None] * change
    if np.issubdtype(colors.dtype, np.integer):
        value = np.clip(np.rint(value), 0, np.iinfo(colors.dtype).max)
    return value.astype(colors.dtype)


def _background_changed(change: np.ndarray, scale: float) -> np.ndarray:
    """(N,) bool: B_t - B_s (``change``, (N, C)) over :data:`MIN_CHANGE` of full ``scale`` in some channel."""
    return np.abs(change).max(1) > MIN_CHANGE * scale


def _candidates(rims, color, depth, camera: Camera, tol: float):
    """The target pixels (flat ``px``) of the 2 x 2 around each rim pixel's projection (``k``:
    which) where the composite shows that surface and, toward the background, a farther one
    whose colour ``b_t`` (N, C) float64 differs from the source's by more than :data:`MIN_CHANGE`."""
    h, w = depth.shape
    zf = depth.reshape(-1)
    r = camera.cam_from_world
    p = rims.points
    x, y, z = (r[i, 0] * p[:, 0] + r[i, 1] * p[:, 1] + r[i, 2] * p[:, 2] + r[i, 3] for i in range(3))
    with np.errstate(invalid="ignore", divide="ignore"):
        u0 = np.floor(camera.fx * x / z + camera.cx)
        v0 = np.floor(camera.fy * y / z + camera.cy)
        near = np.flatnonzero((u0 >= -1) & (u0 < w) & (v0 >= -1) & (v0 < h) & (z > 0))
    u0, v0 = u0[near].astype(np.int64), v0[near].astype(np.int64)
    xs = (u0[:, None] + (0, 1, 0, 1)).ravel()
    ys = (v0[:, None] + (0, 0, 1, 1)).ravel()
    k = np.repeat(near, 4)
    inside = (xs >= 0) & (xs < w) & (ys >= 0) & (ys < h)
    k, ys, xs = k[inside], ys[inside], xs[inside]
    px = ys * w + xs
    zt = np.take(zf, px).astype(np.float64)
    pb = (np.clip(ys + np.take(rims.toward[:, 0], k), 0, h - 1) * w
          + np.clip(xs + np.take(rims.toward[:, 1], k), 0, w - 1))
    with np.errstate(invalid="ignore"):  # the composite shows this surface here and another behind it
        keep = (np.abs(np.take(z, k) - zt) <= tol * zt) & (np.take(zf, pb) > zt * (1.0 + tol))
    k, px, pb = k[keep], px[keep], pb[keep]
    b_t = np.take(color.reshape(h * w, -1), pb, axis=0).astype(np.float64)
    keep = _background_changed(b_t - np.take(rims.behind, k, axis=0), rims.scale)
    return k[keep], px[keep], b_t[keep]


def _shown_alone(rims, k, px, layers, source_shapes, depth, tol) -> np.ndarray:
    """Whether each candidate's own layer samples exactly its rim pixel at the composite's depth
    and (two sources) the other layer does not show that surface there."""
    w = depth.shape[1]
    zt = np.take(depth.reshape(-1), px).astype(np.float64)
    own = rims.source[k]
    shows = [_shows(m, px, zt, tol) for m in layers]
    keep = np.where(own == 0, shows[0], shows[-1])
    for j, (maps, shape) in enumerate(zip(layers, source_shapes)):
        mine = keep & (own == j)
        sy, sx = maps.nearest_source_pixel(px[mine] // w, px[mine] % w, shape)
        keep[mine] = sy * shape[1] + sx == rims.flat[k[mine]]
    if len(layers) == 2:  # the other source sees that surface here too: the compositor blends it in
        keep &= ~np.where(own == 0, shows[1], shows[0])
    return keep


@dataclass(frozen=True, eq=False)
class _Rims:
    """The rim pixels of one or two sources in one set of arrays (``source``: whose)."""

    points: np.ndarray
    flat: np.ndarray
    alpha: np.ndarray
    toward: np.ndarray
    behind: np.ndarray
    source: np.ndarray
    scale: float


@functools.lru_cache(maxsize=8)
def _joined(mattes: tuple) -> _Rims:
    """:class:`_Rims` of ``mattes`` (cached per pair of mattes: each frame of an interpolation
    reuses it)."""
    def cat(name):
        return np.concatenate([getattr(m, name) for m in mattes])

    source = np.concatenate([np.full(len(m), i, np.int8) for i, m in enumerate(mattes)])
    return _Rims(cat("points"), cat("flat"), cat("alpha"), cat("toward"), cat("behind"), source, mattes[0].scale)


def _shows(maps, px, zt, tol) -> np.ndarray:
    """Whether a layer covers target pixels ``px`` (flat) at the composite's depth ``zt``."""
    with np.errstate(invalid="ignore"):
        return np.take(maps.coverage.reshape(-1), px) & (np.abs(np.take(maps.depth.reshape(-1), px) - zt) <= tol * zt)


def rematte_subsamples(sub_color: np.ndarray, sub_depth: np.ndarray, sub_layers, ys, xs, color: np.ndarray,
                       depth: np.ndarray, mattes, source_shapes, *, depth_tol: float = _STEP) -> int:
    """:func:`rematte_rims` for the edge subsamples of :mod:`ibr.render.edge_antialias`, in place.

    A subsample shown by one source alone (its layer covers it at the composite's depth, the
    other layer does not) whose nearest source pixel is a kept rim pixel gets
    ``+ (1 - alpha) (B_t - B_s)``, B_t the frame's colour at its pixel's neighbour toward the
    background, where that neighbour lies farther and B_t differs from B_s by more than
    :data:`MIN_CHANGE` in some channel.

    Parameters
    ----------
    sub_color : (m, n, C) array
        The composited subsamples' colour (changed in place).
    sub_depth : (m, n) float
        Their composited planar depth (NaN where uncovered).
    sub_layers : sequence of SourceMaps
        Per source, the subsamples' own maps, (m, n) arrays (their nearest source pixel is
        :meth:`~ibr.render.rasterize.SourceMaps.nearest_source_pixel`'s).
    ys, xs : (n,) int
        The target pixels the subsamples belong to.
    color, depth : (H, W, C), (H, W) arrays
        The frame's composite (B_t is read there).
    mattes, source_shapes
        As in :func:`rematte_rims`.

    Returns
    -------
    int
        The number of subsamples re-mixed.
    """
    m, n = np.shape(sub_depth)
    if np.shape(sub_color)[:2] != (m, n) or len(sub_layers) != len(mattes) or len(mattes) not in (1, 2):
        raise ValueError("sub_color, sub_depth, sub_layers, mattes: expected (m, n, C) and (m, n) subsamples and one "
                         "layer and one matte per source")
    if any(not isinstance(mt, RimMatte) for mt in mattes):
        raise TypeError("mattes: expected RimMatte objects (rim_matte)")
    h, w = np.shape(depth)
    zc_all = np.asarray(sub_depth, np.float64).reshape(-1)
    with np.errstate(invalid="ignore"):  # which source shows each subsample's surface
        shows = [np.asarray(L.coverage).reshape(-1) & (np.abs(np.asarray(L.depth, np.float64).reshape(-1) - zc_all)
                                                       <= depth_tol * zc_all) for L in sub_layers]
    count = 0
    for j, (layer, matte, shape) in enumerate(zip(sub_layers, mattes, source_shapes)):
        if not len(matte):
            continue
        # shown by this source alone (where the other shows it too, the compositor blended it in) ...
        idx = np.flatnonzero(shows[j] & ~shows[1 - j] if len(sub_layers) == 2 else shows[j])
        # ... from one of its kept rim pixels
        k = _rim_index(matte, shape)[layer.nearest_source_pixel(idx // n, idx % n, shape)]
        idx, k = idx[k >= 0], k[k >= 0]
        zc = zc_all[idx]
        i = idx % n
        ty = np.clip(np.asarray(ys)[i] + matte.toward[k, 0], 0, h - 1)
        tx = np.clip(np.asarray(xs)[i] + matte.toward[k, 1], 0, w - 1)
        with np.errstate(invalid="ignore"):
            farther = depth[ty, tx] > zc * (1.0 + depth_tol)
        change = color[ty, tx].astype(np.float64) - matte.behind[k]
        keep = farther & _background_changed(change, matte.scale)
        idx, k, change = idx[keep], k[keep], change[keep]
        flat_color = sub_color.reshape(m * n, -1)
        flat_color[idx] = _remixed(flat_color[idx], matte.alpha[k], change)
        count += int(idx.size)
    return count


@functools.lru_cache(maxsize=8)
def _rim_index(matte: RimMatte, shape) -> np.ndarray:
    """(H_s, W_s) int64: each source pixel's index in ``matte``, -1 where it is no kept rim
    pixel (made once per matte)."""
    index = np.full(int(shape[0]) * int(shape[1]), -1, np.int64)
    index[matte.flat] = np.arange(len(matte))
    index = index.reshape(shape)
    index.setflags(write=False)
    return index
