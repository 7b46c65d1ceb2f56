"""Sources upsampled k x k with sub-pixel silhouettes, for supersampled rendering (issue 11).

A depth buffer holds one depth per pixel, the one of its centre ray, so a silhouette in it is a
staircase of whole pixels: up to half a pixel off the true outline, which only the colour of the
mixed pixels knows (a camera integrates over the pixel). Rendering a supersampled target from
such a source places the staircase exactly, and it stays a staircase. :func:`upsample_view`
gives :mod:`ibr.render.supersample` a source at k times the resolution in which

* colour is Lanczos-4 (a sharper reconstruction than the renderer's bilinear taps; bicubic
  until the seventeenth session: ``supersample=3`` over all covered pixels clutter 39.31 ->
  39.40, room 39.92 -> 40.07 dB, the motorcycle 28.22 -> 28.25, grazing 43.56 either way; edge
  band clutter 31.06 -> 31.11, room 32.21 -> 32.23, grazing 35.16 -> 35.07), back-projected so
  that each pixel's subsamples average to its colour (:func:`~ibr.render.superres.back_project`,
  nineteenth session; an interpolation's two sources then refine each other's,
  :func:`~ibr.render.superres.super_resolve_pair`); at the depth-edge pixels' subsamples it
  starts from the bilinear taps on their own surface instead (:func:`_within_surfaces`,
  twentieth session), once the silhouettes below are placed; for a pair (``clean_start``) from
  those that are no depth-edge pixels themselves where there is one, and an edge pixel the
  silhouette does not cross holds the other surface's share next to the step
  (:func:`_share_beside_the_step`; twenty-first session);
* depth is interpolated in 1/z (affine on planes) within each surface, and replicated where a
  pixel's neighbours lie on another surface;
* at every depth-edge pixel (a 4-neighbour more than 2 % nearer or farther) the k x k
  subsamples are split between the nearer and the farther surface of its 3 x 3 neighbourhood
  (its neighbours on either side of the midpoint of their inverse depths; the pixel itself on
  the nearer one if it also continues it, :func:`_continues_nearer_surface`):

  - by a straight edge whose normal points from the nearer pixels' centroid to the farther
    ones', placed so that the nearer side covers the pixel's foreground coverage read from its
    colour, ``alpha = (C - B).(F - B) / |F - B|^2`` with F, B the mean colours of the
    neighbourhood's clean nearer and farther pixels (boundary matting); the centre subsample
    keeps the side its depth says;
  - where F and B are too alike to tell (:data:`MIN_CONTRAST`; 71 % of clutter's edge
    pixels), along the depth's staircase smoothed (:func:`_staircase_sides`);
  - each subsample takes its side's plane: the inverse depth of the side's neighbour nearest
    to it, extrapolated with that neighbour's within-surface 1/z gradient, kept only within
    2 % of the side's own depth.

  Eighteenth session (``supersample=3``'s edge band, clutter / room): the planes instead of the
  neighbourhood's nearest or farthest depth replicated (up to 2 % off, a pixel of parallax at
  3 m) 31.11 -> 31.35 / 32.23 -> 32.32 dB (motorcycle, all covered pixels, 28.25 -> 28.23);
  the sides by the midpoint and the continued surface instead of within 2 % of the nearest or
  farthest (a sphere's receding limb pixel was on neither side and never split) -> 31.41 /
  32.36 (28.22); the smoothed staircase instead of no split where the colours cannot tell ->
  **31.54 / 32.37** (28.29).

Measured (``python benchmarks/bench_edges.py --quick``, ``supersample=3``, t = .25/.5/.75,
covered pixels), 1x sources -> these: clutter edge band 29.95 -> 31.02 dB, all pixels 37.96 ->
39.29 dB; room 31.34 -> 32.21 / 38.43 -> 39.92 dB. With the scene's exact 3x depth instead of
this estimate the clutter band would reach 32.4 dB: the estimate puts 90.9 % of clutter's edge
subsamples on the right surface (replicated depth: 88.7 %; room 89.1 against 87.4 %).
"""

from __future__ import annotations

import cv2
import numpy as np

from ..base.depth import quantization_of, set_quantization
from ..base.validate import check_array, check_flag, check_positive
from ..base.view import View

__all__ = ["MIN_CONTRAST", "depth_edge_pixels", "upsample_view"]

#: Relative depth difference between 4-neighbours that makes both depth-edge pixels.
EDGE_REL = 0.02
#: Smallest foreground-background colour difference (RMS over channels, in 1/255 of the colour's
#: full scale) at which a mixed pixel's coverage is read from its colour.
MIN_CONTRAST = 60.0 / 255.0
#: Standard deviation (source px) of the Gaussian that smooths the depth's staircase where a
#: silhouette's colours cannot tell its coverage (:func:`_staircase_sides`).
STAIRCASE_SIGMA = 1.0
_NEIGHBOURS = [(dy, dx) for dy in (-1, 0, 1) for dx in (-1, 0, 1)]
_OFFSETS = np.array(_NEIGHBOURS).T  # (2, 9): dy, dx of each neighbour


def depth_edge_pixels(depth: np.ndarray, rel: float = EDGE_REL, quantization=None) -> np.ndarray:
    """(H, W) bool: valid pixels with a 4-neighbour whose planar depth differs by more than
    ``rel`` of the nearer one (both pixels of every such pair) and, for quantized depth
    (a :class:`~ibr.base.depth.DepthQuantization`), by more than
    :data:`~ibr.render.composite.QUANT_STEP_CODES` codes: the staircase of a smooth surface in
    coarse codes is no silhouette."""
    from ..base.depth import DepthQuantization

    z = check_array("depth", depth, ndim=2, dtype_kind="f").astype(np.float64)
    rel = check_positive("rel", rel)
    if quantization is not None and not isinstance(quantization, DepthQuantization):
        raise TypeError(f"quantization: expected a DepthQuantization or None, got {type(quantization).__name__}")
    edge = np.zeros(z.shape, bool)
    with np.errstate(invalid="ignore", divide="ignore"):
        dh = np.abs(z[:, 1:] - z[:, :-1]) > rel * np.fmin(z[:, 1:], z[:, :-1])
        dv = np.abs(z[1:] - z[:-1]) > rel * np.fmin(z[1:], z[:-1])
        if quantization is not None:
            from .composite import QUANT_STEP_CODES

            q = 1.0 / z
            dh &= np.abs(q[:, 1:] - q[:, :-1]) > QUANT_STEP_CODES * quantization.inv_step(np.fmax(q[:, 1:], q[:, :-1]))
            dv &= np.abs(q[1:] - q[:-1]) > QUANT_STEP_CODES * quantization.inv_step(np.fmax(q[1:], q[:-1]))
    edge[:, 1:] |= dh
    edge[:, :-1] |= dh
    edge[1:] |= dv
    edge[:-1] |= dv
    return edge & np.isfinite(z)


def upsample_view(view: View, k: int, *, clean_start: bool = False) -> View:
    """``view`` at k times its width and height (same camera view, :meth:`Camera.resized`), with
    back-projected Lanczos-4 colour, depth interpolated in 1/z within surfaces and silhouettes
    placed inside the depth-edge pixels by their colours (module docstring). ``k`` = 1 returns
    ``view``. The depth's quantization (:func:`~ibr.base.depth.quantization_of`) carries over.
    ``clean_start``: the depth-edge pixels' subsamples start from the taps on their surface that
    are no depth-edge pixels where there is one (:func:`_within_surfaces`), for a colour that a
    partner source then refines (:func:`~ibr.render.superres.super_resolve_pair`)."""
    from .supersample import check_supersample

    k = check_supersample(k)
    clean_start = check_flag("clean_start", clean_start)
    if not isinstance(view, View) or view.depth is None:
        raise ValueError("view: expected a View with depth")
    if k == 1:
        return view
    h, w = view.depth.shape
    camera = view.camera.resized(w * k, h * k)
    depth = _smooth_depth(view.depth, k)
    q = quantization_of(view)
    edge = _place_silhouettes(depth, view.depth, _unit_color(view.color), k, q)
    color = _consistent_colour(view.color, k, view.depth, depth, edge, clean_start)
    return set_quantization(View(color, depth, camera, view.name), q)


def _consistent_colour(color: np.ndarray, k: int, depth: np.ndarray, depth_k: np.ndarray,
                       edge: np.ndarray, clean_start: bool = False) -> np.ndarray:
    """``color`` at k x k: Lanczos-4, at the depth-edge pixels' subsamples (``edge``) from their
    own surface only (:func:`_within_surfaces`; with ``clean_start`` its clean taps first, and
    :func:`_share_beside_the_step`), then back-projected until each pixel's k x k mean is its
    colour (:func:`~ibr.render.superres.back_project`), in ``color``'s dtype and layout."""
    from .superres import _as_colour, _colour_limits, back_project

    c = np.asarray(color)
    h, w = c.shape[:2]
    cf = c.reshape(h, w, -1).astype(np.float32)
    limits = _colour_limits(c.dtype)
    start = cv2.resize(cf, (w * k, h * k), interpolation=cv2.INTER_LANCZOS4).reshape(h * k, w * k, -1)
    py, px = np.nonzero(edge)
    if py.size:
        values, from_clean = _within_surfaces(cf, depth, depth_k, edge if clean_start else None, k, py, px)
        if clean_start:
            _share_beside_the_step(values, from_clean, cf, depth, depth_k, edge, k, py, px, limits)
        _set_subsamples(start, py, px, k, values)
    up = back_project(start, cf, k, limits=limits)
    return _as_colour(up, c.dtype, (h * k, w * k) + c.shape[2:])


def _within_surfaces(color, depth, depth_k, edge, k, py, px):
    """(values, from_clean): (n, k k, C) float32, the colour at the k x k subsamples of the
    depth-edge pixels ``(py, px)`` from the bilinear taps (pixel centres at ``(i + 0.5) / k -
    0.5``) on the subsample's own surface only (the tap pixel's ``depth`` within :data:`EDGE_REL`
    of the subsample's ``depth_k``), renormalized; the pixel's own colour where no tap is. With
    the depth-edge pixels ``edge`` (else None), from the taps on the surface that are none of
    them (mixed colours) where there is one: ``from_clean``, (n, k k) bool, marks those. Lanczos-4 across a silhouette mixes the other surface into a
    depth-edge pixel's subsamples (a dark limb into the face behind); this start instead (then
    back-projected; twentieth session, ``supersample=3``'s edge band) clutter 32.27 -> 32.40 dB,
    room 33.21 -> 33.35 (over the edge pixels and their neighbours 32.38 / 33.34; the taps of a
    masked Keys cubic 32.13 / 32.98, of Lanczos-2 32.38 / 33.31, of a Gaussian 32.39 / 33.35).
    Twenty-first session, the clean taps first (28 % of room's edge subsamples have one): room
    33.44 -> 33.57 dB, clutter 32.53 either way (without the pixel's own colour only: 33.53; clean
    taps of a tent 1.5 / 2 px wide: 33.50 / 33.49; Lanczos-4 whose other taps take this start:
    33.57, over the edge pixels' neighbours too 33.59 and clutter 32.51). Only for a pair: a lone
    source's mixed pixel has no partner to say which of its subsamples hold the other surface, and
    the back-projection darkens them all (a stereo pair's eyes, ``supersample=3``, against ray
    traced ones: room 42.02 -> 41.84 dB, clutter 38.73 -> 38.30; clutter's off-band pixels of a
    lone warp 14, 26 -> 24, 44 beside the disocclusions)."""
    h, w = depth.shape
    z = np.asarray(depth, np.float32)
    levels = 1 if edge is None else 2  # (the clean taps,) all taps on the surface: the first that has one
    out = np.empty((py.size, k * k, color.shape[2]), np.float32)
    from_clean = np.zeros((py.size, k * k), bool)
    for idx in range(k * k):
        iy, ix = divmod(idx, k)
        cy, cx = py + (iy + 0.5) / k - 0.5, px + (ix + 0.5) / k - 0.5
        y0, x0 = np.floor(cy).astype(np.intp), np.floor(cx).astype(np.intp)
        fy, fx = (cy - y0).astype(np.float32), (cx - x0).astype(np.float32)
        zs = depth_k[py * k + iy, px * k + ix]
        acc = np.zeros((levels, py.size, color.shape[2]), np.float32)
        total = np.zeros((levels, py.size), np.float32)
        for jy, wy in ((y0, 1 - fy), (y0 + 1, fy)):
            for jx, wx in ((x0, 1 - fx), (x0 + 1, fx)):
                jy_, jx_ = np.clip(jy, 0, h - 1), np.clip(jx, 0, w - 1)
                with np.errstate(invalid="ignore"):
                    same = np.abs(z[jy_, jx_] - zs) <= EDGE_REL * zs
                for j, use in enumerate([same] if edge is None else [same & ~edge[jy_, jx_], same]):
                    wgt = wy * wx * use
                    acc[j] += wgt[:, None] * color[jy_, jx_]
                    total[j] += wgt
        value = color[py, px]
        for j in reversed(range(levels)):
            own = total[j] > 1e-6
            value = np.where(own[:, None], acc[j] / np.where(own, total[j], 1)[:, None], value)
        out[:, idx] = value
        from_clean[:, idx] = edge is not None and (total[0] > 1e-6)
    return out, from_clean


def _share_beside_the_step(values, from_clean, color, depth, depth_k, edge, k, py, px, limits) -> None:
    """A pair's start (``values``, (n, k k, C), in place) at the depth-edge pixels ``(py, px)``
    whose k x k subsamples all lie on their own surface (the silhouette kept outside them, e.g.
    where the colours are too alike to read a coverage), with clean 3 x 3 neighbours on that
    surface and others off it: the subsamples without a clean tap (``from_clean``) take the clean
    neighbours' mean colour, and what the pixel's colour holds beyond the others goes to the
    subsamples next to the step (the row or column toward the neighbours off the surface along
    the edge normal), where the other surface mixed into it lies; skipped where that leaves
    ``limits``. Spread over a background pixel, a foreground's share stayed on the background
    when a disocclusion opened beside it, one subsample of which the rim replacement reaches (a
    dark line beside clutter's left pole under ``supersample=3``). Twenty-first session,
    ``supersample=3``: on the farther side of steps only, band room 33.57 -> 33.63 dB, clutter
    32.53 -> 32.51 (all covered 40.92 -> 40.87, covered off-band pixels over 48 before the fill
    0, 4, 7 -> 16, 4, 9, none after it), after the fill 40.15 -> 40.17 and 42.07 -> 42.08 dB,
    clutter's pixels more than 16 levels off 988 / 1203 / 1105 -> 982 / 1187 / 1090, the line
    16 -> 8 of them (the other subsamples at the clean neighbours' mean: 33.62 / 32.51, the line
    9); on both sides **33.65 / 32.55** (40.90 all covered), after the fill 40.20 and 42.09,
    965 / 1172 / 1081 pixels more than 16 levels off, the line 8."""
    zp = np.asarray(depth, np.float32)[py, px]
    subsample_z = _subsamples_of(depth_k, py, px, k)
    zs, cs, clean = _neighbourhoods(np.asarray(depth, np.float32), color, edge, py, px)
    with np.errstate(invalid="ignore"):  # (NaN outside the image: neither)
        own_surface = (np.abs(subsample_z - zp[:, None]) <= EDGE_REL * zp[:, None]).all(axis=1)
        own = np.abs(zs - zp[:, None]) <= EDGE_REL * zp[:, None]
        off = np.isfinite(zs) & ~own
    clean &= own
    count = clean.sum(axis=1)
    acc = (cs * clean[..., None]).sum(axis=1)
    ny, nx = _normal(off, own)
    sy, sx = _subsample_offsets(k)
    toward_step = -(ny[:, None] * sy[None] + nx[:, None] * sx[None])  # (n, k k)
    beside = toward_step >= toward_step.max(axis=1, keepdims=True) - 1e-6
    others = np.where(from_clean[..., None], values, (acc / np.maximum(count, 1)[:, None])[:, None, :])
    rest = np.where(beside[..., None], 0, others).sum(axis=1)
    share = (k * k * color[py, px] - rest) / beside.sum(axis=1)[:, None]
    use = own_surface & off.any(axis=1) & (count > 0) & ((ny != 0) | (nx != 0))
    if limits is not None:
        use &= ((share >= limits[0]) & (share <= limits[1])).all(axis=1)
    values[use] = np.where(beside[use][..., None], share[use][:, None, :], others[use])


def _unit_color(color: np.ndarray) -> np.ndarray:
    """(H, W, C) float64 colour in [0, 1] of its dtype's scale, without an alpha channel (the
    coverage is read from the colour channels)."""
    c = np.asarray(color)
    scale = float(np.iinfo(c.dtype).max) if np.issubdtype(c.dtype, np.integer) else 1.0
    c = c.astype(np.float64) / scale
    c = c if c.ndim == 3 else c[..., None]
    return c[..., :3] if c.shape[2] == 4 else c


def _smooth_depth(depth: np.ndarray, k: int) -> np.ndarray:
    """(k H, k W) float32: 1/z bilinear where it stays within :data:`EDGE_REL` of the pixel's own
    depth (one surface), the pixel's depth replicated elsewhere (edges, NaN neighbours)."""
    h, w = depth.shape
    z = np.asarray(depth, np.float32)
    rep = np.repeat(np.repeat(z, k, 0), k, 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = cv2.resize(1.0 / z, (w * k, h * k), interpolation=cv2.INTER_LINEAR)
        smooth = 1.0 / inv
        same = np.abs(smooth - rep) <= EDGE_REL * rep  # False where either is NaN
    return np.where(same, smooth, rep).astype(np.float32)


def _place_silhouettes(depth_k: np.ndarray, depth: np.ndarray, color: np.ndarray, k: int, quantization) -> np.ndarray:
    """Split the subsamples of every depth-edge pixel (:func:`depth_edge_pixels`) between its
    neighbourhood's nearer and farther surface (module docstring), in place in ``depth_k``;
    returns the (H, W) bool depth-edge pixels."""
    z = np.asarray(depth, np.float64)
    edge = depth_edge_pixels(z, quantization=quantization)
    py, px = np.nonzero(edge)
    if py.size == 0:
        return edge
    zs, cs, clean = _neighbourhoods(z, color, edge, py, px)
    zmin, zmax = np.nanmin(zs, 1), np.nanmax(zs, 1)
    # the neighbours' sides split at the midpoint of the neighbourhood's inverse depths
    with np.errstate(divide="ignore", invalid="ignore"):
        mid = 0.5 * (1.0 / zmin + 1.0 / zmax)
        near = 1.0 / zs > mid[:, None]
        far = 1.0 / zs <= mid[:, None]  # NaN (outside the image, invalid): neither
    alpha, tell = _colour_coverage(color[py, px], cs, near, far, clean)
    zp = z[py, px]
    with np.errstate(divide="ignore"):
        q = 1.0 / z  # NaN where the depth is NaN
    planes = _neighbour_planes(q, py, px)
    own_near = _continues_nearer_surface(zp, zmin, mid, near, planes)
    sy, sx = _subsample_offsets(k)
    is_near = _straight_edge_sides(alpha, own_near, near, far, sy, sx)
    # where the colours cannot tell, the silhouette follows the depth's staircase smoothed
    is_near[~tell] = _staircase_sides(q, py[~tell], px[~tell], mid[~tell], own_near[~tell], sy, sx)
    # each side's extrapolated plane, trusted within EDGE_REL of the side's own pixel depth
    # (the pixel's own on its side, the neighbourhood's extreme on the other)
    q_near = _within(_side_plane_at(planes, near, sy, sx), np.where(own_near, 1.0 / zp, 1.0 / zmin)[:, None])
    q_far = _within(_side_plane_at(planes, far, sy, sx), np.where(own_near, 1.0 / zmax, 1.0 / zp)[:, None])
    _set_subsamples(depth_k, py, px, k, 1.0 / np.where(is_near, q_near, q_far))
    return edge


def _subsample_offsets(k: int):
    """(sy, sx), each (k k,): the subsamples' offsets from their pixel's centre (px), row-major."""
    sub = (np.arange(k) + 0.5) / k - 0.5
    return tuple(a.ravel() for a in np.meshgrid(sub, sub, indexing="ij"))


def _subsamples_of(image_k: np.ndarray, py, px, k: int) -> np.ndarray:
    """(n, k k, ...): the k x k subsamples (row-major) of the pixels ``(py, px)`` of the upsampled
    ``image_k`` (the inverse of :func:`_set_subsamples`)."""
    return np.stack([image_k[py * k + iy, px * k + ix] for iy in range(k) for ix in range(k)], axis=1)


def _set_subsamples(image_k: np.ndarray, py, px, k: int, values: np.ndarray) -> None:
    """Write ``values`` ((n, k k, ...), row-major subsamples) into the k x k subsamples of the
    pixels ``(py, px)`` of the upsampled ``image_k``, in place."""
    for idx in range(k * k):
        iy, ix = divmod(idx, k)
        image_k[py * k + iy, px * k + ix] = values[:, idx]


def _straight_edge_sides(alpha, own_near, near, far, sy, sx):
    """(n, s) bool: the subsamples at offsets ``(sy, sx)`` (px, from the pixel centre) on the
    nearer side of the straight edge n.x = d (n: :func:`_normal`) whose nearer side covers
    ``alpha`` of the pixel, a linear ramp over the pixel's extent along n (exact for an edge
    along a row or column); the centre subsample (n.x = 0) keeps the pixel's own side."""
    ny, nx = _normal(near, far)
    offset = (alpha - 0.5) * (np.abs(ny) + np.abs(nx))
    offset = np.where(own_near, np.maximum(offset, 1e-9), np.minimum(offset, 0.0))
    return ny[:, None] * sy[None] + nx[:, None] * sx[None] < offset[:, None]


def _continues_nearer_surface(zp, zmin, mid, near, planes):
    """(n,) bool: the edge pixels (depth ``zp``) that belong to their neighbourhood's nearer
    surface: on its side of the midpoint ``mid`` of the inverse depths, and within
    :data:`EDGE_REL` of the nearest depth ``zmin`` or of the plane of their nearest nearer
    neighbour extrapolated to their centre (a sphere's limb pixel receding more than that from
    its inward neighbour). A depth between the surfaces that continues neither, as real depth
    maps hold at silhouettes, stays on the farther side: the midpoint alone put the
    motorcycle's ``supersample=3`` render 28.29 -> 28.15 dB over all covered pixels (clutter's
    band 31.54 -> 31.60); within 2 % of ``zmin`` only, as until the eighteenth session, put
    clutter's band 31.54 -> 31.27 (room 32.37 -> 32.35, motorcycle 28.29)."""
    others = near.copy()
    others[:, 4] = False
    q_plane = _side_plane_at(planes, others, np.zeros(1), np.zeros(1))[:, 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        q = 1.0 / zp
        continues = (zp <= zmin * (1 + EDGE_REL)) | (np.abs(q - q_plane) <= EDGE_REL * q_plane)
        return (q > mid) & continues


def _staircase_sides(q, py, px, mid, own_near, sy, sx):
    """(n, s) bool: whether the subsamples at offsets ``(sy, sx)`` (px, from the pixel centre)
    of the edge pixels ``(py, px)`` lie on the nearer surface, by the share of nearer pixels
    (inverse depth ``q`` above ``mid``) in the pixel's 5 x 5 neighbourhood weighted by a Gaussian of
    :data:`STAIRCASE_SIGMA` px around the subsample; a tie keeps the pixel's own side. The
    depth's whole-pixel staircase, smoothed: a slanted or curved silhouette is cut inside the
    pixels it crosses instead of along their edges (module docstring; with the sides by the
    midpoint alone sigma 0.7 / 1 / 1.2 / 1.6 gave clutter's band 31.60 / 31.60 / 31.63 / 31.54,
    room's 32.38 / 32.37 / 32.34 / 32.31)."""
    h, w = q.shape
    num = np.zeros((py.size, sy.size))
    den = np.zeros((py.size, sy.size))
    for dy in range(-2, 3):
        for dx in range(-2, 3):
            jy, jx = py + dy, px + dx
            inside = (jy >= 0) & (jy < h) & (jx >= 0) & (jx < w)
            qj = q[np.clip(jy, 0, h - 1), np.clip(jx, 0, w - 1)]
            valid = inside & np.isfinite(qj)
            g = np.exp(-((sy - dy) ** 2 + (sx - dx) ** 2) / (2 * STAIRCASE_SIGMA**2))[None]
            num += g * (valid & (qj > mid))[:, None]
            den += g * valid[:, None]
    share = num / np.maximum(den, 1e-300)
    return np.where(np.abs(share - 0.5) < 1e-9, own_near[:, None], share > 0.5)


def _within(q, q_side):
    """``q`` where it lies within :data:`EDGE_REL` of ``q_side`` (broadcast), ``q_side`` elsewhere."""
    with np.errstate(invalid="ignore"):
        ok = np.abs(q - q_side) <= EDGE_REL * q_side
    return np.where(ok, q, q_side)


def _neighbour_planes(q, py, px):
    """(q, gy, gx), each (n, 9): the inverse depth (of the image ``q``) of the 3 x 3 neighbours
    of the edge pixels ``(py, px)`` (row-major, clamped at the image border) and its
    within-surface gradient (:func:`_surface_gradient`, px^-1): the 1/z plane each neighbour's
    surface has there."""
    h, w = q.shape
    gy, gx = _surface_gradient(q)
    jy = np.clip(py[:, None] + _OFFSETS[0], 0, h - 1)
    jx = np.clip(px[:, None] + _OFFSETS[1], 0, w - 1)
    return q[jy, jx], gy[jy, jx], gx[jy, jx]


def _side_plane_at(planes, side, sy, sx):
    """(n, s) inverse depth at the subsample offsets ``(sy, sx)`` (px, from the pixel centre) of
    the plane of the ``side`` neighbour ((n, 9) mask) nearest to each subsample. Subsample
    depths replicated from the neighbourhood instead put clutter's edge band 0.24 dB lower under
    ``supersample=3`` (room 0.09)."""
    q, gy, gx = (a[:, None] for a in planes)  # (n, 1, 9)
    dy = sy[:, None] - _OFFSETS[0]  # (s, 9): subsample offset from each neighbour's centre
    dx = sx[:, None] - _OFFSETS[1]
    at = q + gy * dy + gx * dx  # (n, s, 9)
    j = np.argmin(np.where(side[:, None], np.hypot(dy, dx)[None], np.inf), axis=2)
    return np.take_along_axis(at, j[..., None], axis=2)[..., 0]


def _surface_gradient(q: np.ndarray):
    """(d/dy, d/dx) of the inverse depth ``q`` per pixel in px^-1, from the neighbours on its
    own surface (within :data:`EDGE_REL`): central where both are, one-sided where one is, 0
    where none (or NaN)."""

    def along_x(a):
        d = a[:, 1:] - a[:, :-1]
        with np.errstate(invalid="ignore"):
            d = np.where(np.abs(d) <= EDGE_REL * np.fmin(a[:, 1:], a[:, :-1]), d, np.nan)
        ahead = np.pad(d, ((0, 0), (0, 1)), constant_values=np.nan)
        behind = np.pad(d, ((0, 0), (1, 0)), constant_values=np.nan)
        with np.errstate(invalid="ignore"):
            grad = np.where(np.isnan(ahead), behind, np.where(np.isnan(behind), ahead, 0.5 * (ahead + behind)))
        return np.nan_to_num(grad, nan=0.0)

    return along_x(q.T).T, along_x(q)


def _neighbourhoods(z, color, edge, py, px):
    """Per edge pixel, its 3 x 3 neighbourhood (row-major, centre at 4): depths (NaN outside the
    image), colours, and which neighbours are clean (inside the image, not edge pixels)."""
    h, w = z.shape
    n = py.size
    zs = np.full((n, 9), np.nan)
    cs = np.zeros((n, 9, color.shape[2]))
    clean = np.zeros((n, 9), bool)
    for i, (dy, dx) in enumerate(_NEIGHBOURS):
        jy, jx = py + dy, px + dx
        ok = (jy >= 0) & (jy < h) & (jx >= 0) & (jx < w)
        jy, jx = np.clip(jy, 0, h - 1), np.clip(jx, 0, w - 1)
        zs[:, i] = np.where(ok, z[jy, jx], np.nan)
        cs[:, i] = color[jy, jx]
        clean[:, i] = ok & ~edge[jy, jx]
    return zs, cs, clean


def _colour_coverage(c, cs, near, far, clean):
    """(alpha, tell), each (n,): the foreground coverage ``(C - B).(F - B) / |F - B|^2`` of the
    edge pixels' colours ``c`` in [0, 1] (F, B: :func:`_mean_color` of the nearer and farther
    side), and whether F and B differ enough to read it (:data:`MIN_CONTRAST`)."""
    fg, bg = _mean_color(cs, near, clean), _mean_color(cs, far, clean)
    diff = fg - bg
    contrast2 = (diff * diff).sum(1)
    alpha = np.clip(((c - bg) * diff).sum(1) / np.maximum(contrast2, 1e-12), 0.0, 1.0)
    return alpha, contrast2 >= MIN_CONTRAST**2 * c.shape[1]


def _mean_color(cs, side, clean):
    """Mean colour of the clean pixels of ``side`` (all of ``side`` where none is clean)."""
    use = side & clean
    use = np.where(use.any(1)[:, None], use, side)
    wgt = use.astype(np.float64)
    return (cs * wgt[..., None]).sum(1) / np.maximum(wgt.sum(1), 1.0)[:, None]


def _normal(near, far):
    """Unit edge normal per pixel (y, x), from its nearer neighbours' centroid toward its
    farther ones' (0, 0 where they coincide)."""
    oy, ox = _OFFSETS.astype(np.float64)

    def centroid(sel):
        wgt = sel.astype(np.float64)
        s = np.maximum(wgt.sum(1), 1.0)
        return (wgt * oy).sum(1) / s, (wgt * ox).sum(1) / s

    y0, x0 = centroid(near)
    y1, x1 = centroid(far)
    ny, nx = y1 - y0, x1 - x0
    norm = np.hypot(ny, nx)
    norm = np.where(norm > 0, norm, 1.0)
    return ny / norm, nx / norm
