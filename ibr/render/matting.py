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
* per frame (:func:`rematte_rims`, a kernel over the rim pixels), each kept rim pixel is
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

from dataclasses import dataclass

import numpy as np

from ..base.camera import Camera
from .composite import mixed_pixels

__all__ = ["MAX_ALPHA", "MIN_CHANGE", "MIN_CONTRAST", "RimMatte", "rematte_rims", "rim_matte"]

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


@dataclass(frozen=True)
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


def rim_matte(color: np.ndarray, depth: np.ndarray, camera: Camera, *, quantization=None) -> RimMatte:
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
    """
    c = np.asarray(color)
    z = np.asarray(depth, np.float64)
    if c.ndim != 3 or c.shape[:2] != z.shape:
        raise ValueError(f"color: expected (H, W, C) with the depth's (H, W) = {z.shape}, got shape {c.shape}")
    if not isinstance(camera, Camera) or camera.shape != z.shape:
        raise ValueError(f"camera: expected a Camera of the depth's shape {z.shape}")
    scale = _full_scale(c.dtype)
    both = mixed_pixels(z, side="both", quantization=quantization)
    near = both & ~mixed_pixels(z, side="far", quantization=quantization)
    ys, xs = np.nonzero(near)
    h, w = z.shape
    zp = z[ys, xs]
    n, nc = ys.size, c.shape[2]
    f_sum, b_sum = np.zeros((n, nc)), np.zeros((n, nc))
    f_n, b_n = np.zeros(n), np.zeros(n)
    b_dir = np.zeros((n, 2))
    for dy, dx in _RING:
        jy, jx = ys + dy, xs + dx
        inside = (jy >= 0) & (jy < h) & (jx >= 0) & (jx < w)
        jy, jx = np.clip(jy, 0, h - 1), np.clip(jx, 0, w - 1)
        zq, cq = z[jy, jx], c[jy, jx].astype(np.float64)
        with np.errstate(invalid="ignore"):
            own = inside & (np.abs(zq - zp) <= _STEP * zp) & ~both[jy, jx]
            behind = inside & (zq > zp * (1.0 + _STEP))
        f_sum += own[:, None] * cq
        f_n += own
        b_sum += behind[:, None] * cq
        b_n += behind
        b_dir += behind[:, None] * (dy, dx)
    fg = f_sum / np.maximum(f_n, 1.0)[:, None]
    bg = b_sum / np.maximum(b_n, 1.0)[:, None]
    diff = fg - bg
    contrast2 = (diff * diff).sum(1)
    mix = c[ys, xs].astype(np.float64)
    alpha = np.clip(((mix - bg) * diff).sum(1) / np.maximum(contrast2, 1e-30), 0.0, 1.0)
    keep = (f_n > 0) & (b_n > 0) & (contrast2 >= (MIN_CONTRAST * scale) ** 2 * nc) & (alpha < MAX_ALPHA)
    ys, xs = ys[keep], xs[keep]
    points = camera.unproject(np.stack([xs, ys], -1).astype(np.float64), zp[keep])
    # the 8-neighbour nearest to the mean direction of the farther neighbours
    angle = np.arctan2(b_dir[keep, 0], b_dir[keep, 1])
    toward = np.stack([np.rint(np.sin(angle)), np.rint(np.cos(angle))], -1).astype(np.int64)
    by = np.clip(ys + toward[:, 0], 0, h - 1)
    bx = np.clip(xs + toward[:, 1], 0, w - 1)
    behind = c[by, bx].astype(np.float64)
    return RimMatte(ys.astype(np.int64) * w + xs, points, alpha[keep], toward, behind, scale)


def rematte_rims(color: np.ndarray, depth: np.ndarray, camera: Camera, layers, mattes, source_shapes,
                 *, depth_tol: float = _STEP) -> int:
    """Re-composite the target pixels that show an unmixable foreground-rim sample over the
    target's own background, in place in ``color`` (module docstring).

    Each rim pixel is projected into the target and the 2 x 2 pixels around it are tested (one
    kernel pass over the rim pixels, ``ibr.render._matting_kernels.rim_updates``): the cheap,
    selective tests first (the composite shows that surface there, its background changed), the
    maps' exact test last, so a frame costs little more than its rim pixels.

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
    from ..base.first_run import await_kernels
    from . import _matting_kernels as _k

    await_kernels("matte")  # a first run: the helper may be caching the kernel right now
    h, w = depth.shape
    if len(layers) != len(mattes) or len(mattes) != len(source_shapes) or len(mattes) not in (1, 2):
        raise ValueError("layers, mattes, source_shapes: expected one or two of each, as many of each")
    r = camera.cam_from_world
    rot, trans = np.ascontiguousarray(r[:3, :3]), np.ascontiguousarray(r[:3, 3])
    updates = []
    for own, matte in enumerate(mattes):
        if not len(matte):
            continue
        m, shape, other = layers[own], source_shapes[own], layers[-1 - own]  # (one source: itself, unused)
        out_px = np.empty(4 * len(matte), np.int64)
        out_val = np.empty((4 * len(matte), color.shape[2]))
        n = _k.rim_updates(matte.points, rot, trans, camera.fx, camera.fy, camera.cx, camera.cy, matte.flat,
                           matte.alpha, matte.toward, matte.behind, depth, color, m.map_u, m.map_v, m.depth,
                           m.coverage, shape[1], shape[0], len(layers) == 2, other.depth, other.coverage,
                           float(depth_tol), MIN_CHANGE * matte.scale, out_px, out_val)
        if n:
            updates.append((out_px[:n], out_val[:n]))
    count = 0
    for px, value in updates:  # written after every test read the composite as it was
        if np.issubdtype(color.dtype, np.integer):
            value = np.clip(np.rint(value), 0, np.iinfo(color.dtype).max)
        color[px // w, px % w] = value.astype(color.dtype)
        count += px.size
    return count
