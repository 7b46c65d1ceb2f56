"""Colour of the k x k upsampled sources made consistent with their pixels, and sharpened by the
partner source (issue 11; iterative back-projection, Irani & Peleg 1991).

A source pixel's colour is the mean of the scene over its footprint (a camera integrates; the
bundled views are 3 x 3 box-filtered), so the k x k subsamples of a source upsampled for
:mod:`ibr.render.supersample` should average to the pixel. A Lanczos reading does not: it is
a smooth curve through the pixel means, lower in contrast than the scene, and a box filter over
it blurs once more. Two steps mend this:

* :func:`back_project` (every upsampled source, :func:`~ibr.render.upsample.upsample_view`):
  the residual ``S - box(X)`` of each pixel spread bilinearly over the subsamples and added, a
  few times, then once spread evenly (nearest), so that every pixel's k x k mean is its colour
  again (within rounding): a source rendered at its own pose gives itself back;
* :func:`super_resolve_pair` (the two sources of an interpolation): the same iteration with
  each source also explaining the other's pixels: the partner's k x k subsamples are mapped
  through their depth into this source's upsampled image (bilinear; those this source does not
  see keep the partner's own colour), their k x k mean compared with the partner's pixel, and
  that residual mapped back and averaged with the own one (:data:`PARTNER_WEIGHT`) wherever
  both sources see the same surface (depths within :data:`SAME_SURFACE_REL`); a partner's
  mixed pixel whose depth shows one surface only explains this source within
  :data:`UNSPLIT_RESIDUAL` (else it would draw the surface its depth misses into this one).
  The two cameras see each surface at other sub-pixel phases and, next to a silhouette, the
  background a mixed pixel hides at other distances from the outline, so the partner tells
  what one view's mean cannot: finer texture and unmixed colours on both sides of silhouettes.

Since the sources are then box-consistent, the supersampled renderer box-filters every pixel,
not only the edge pixels (:func:`~ibr.render.supersample.downsample_rendering`).

Twentieth session: each iteration's step is longer (:data:`PAIR_STEP`, over-relaxed) and, at
the subsamples of the source's depth-edge pixels and a little around them, adds a total-variation
step (:data:`EDGE_TV_WEIGHT`): a mixed pixel holds two surfaces, each flat up to its silhouette,
where the back-projection leaves a ramp. With the upsampled sources' depth-edge subsamples
started from their own surface (:func:`~ibr.render.upsample.upsample_view`) the band went
clutter 32.27 -> 32.53, room 33.21 -> 33.44 dB (all covered 40.63 -> 40.92, 41.79 -> 42.10);
:data:`UNSPLIT_RESIDUAL` went from 24/255 to 20/255 with them.

Measured (``python benchmarks/bench_edges.py --quick``, ``supersample=3``, t = .25/.5/.75,
covered pixels; edge band / all covered, dB): clutter 31.54 / 39.59 -> 31.77 band with the own
back-projection and the box over every pixel -> 32.17 / 40.47 with the partner's (eight
iterations; 32.03 with only the partner's pixels this source sees whole); room 32.37 / 40.07 ->
32.45 -> 33.07 / 41.49 (32.93); with the upsampled pair's widened trust
(:meth:`~ibr.render.sources._Source.silhouettes`) and twelve iterations 32.27 /
40.63 and 33.21 / 41.79; the motorcycle pair's one source 28.29 -> 28.30 (28.28 with the
twentieth session's start). Before the
partial and unsplit pixels more iterations lost at the silhouettes (20: clutter band 31.93,
room 32.68 with all covered 42.11), so they stop at :data:`PAIR_ITERATIONS`; clamping the
partner's residual (to 6 or 16 levels, against misregistration) changed nothing but lowered
room at 6; a partial pixel's residual scaled by
the share this source sees: +0.01 dB.
"""

from __future__ import annotations

import functools

import cv2
import numpy as np

from ..base.depth import quantization_of
from ..base.validate import check_array, check_number, check_positive
from ..base.view import View
from .supersample import _subsample_planes, _block_means, check_supersample

__all__ = ["BACK_PROJECTIONS", "PAIR_ITERATIONS", "PARTNER_WEIGHT", "back_project", "super_resolve_pair"]

#: Bilinear back-projection steps of a single source (then one even step). 1, 3 and 8 gave the
#: same band (clutter 31.76 / 31.77 / 31.76 dB without the partner; 60 ms per source at 3).
BACK_PROJECTIONS = 1
#: Iterations of the two-source back-projection. 8 / 12 / 16 (with the unsplit rule and the
#: upsampled pair's widened trust): band clutter 32.23 / 32.27 / 32.28, room 33.15 / 33.21 /
#: 33.23 dB, room's covered off-band pixels over 48/255 5, 5, 0 / 5, 2, 0 / 5, 1, 0, the ghost
#: line beside clutter's left pole 4.0 / 4.6 / 5.3 levels; about 40 ms each at 512 x 384.
PAIR_ITERATIONS = 12
#: Step length of each iteration (over-relaxation: 1 is the plain back-projection; 2 is the edge
#: of stability, 3 diverges). 1 / 1.6 (with the edge total variation): band clutter 32.47 /
#: 32.52, room 33.41 / 33.50 dB, all covered 40.82 / 40.90 and 41.81 / 42.11; 24 iterations of
#: step 1 took room to 33.52 / 42.21 at twice the time, 48 to 33.57 / 42.32.
PAIR_STEP = 1.6
#: Weight of the partner's residual against the source's own (1).
PARTNER_WEIGHT = 0.5
#: Total-variation step (share of the colour's range per iteration, :meth:`_EdgeZone.tv_descent`) at the
#: subsamples of the source's depth-edge pixels and within :data:`EDGE_TV_RADIUS` pixels of them:
#: the two surfaces a mixed pixel holds are flat on either side of its silhouette, not a ramp.
#: 0 / 0.5 / 1 / 2 (radius 1, step 1): clutter's band 32.41 / 32.48 / 32.50 / 32.47, room's 33.35
#: / 33.40 / 33.40 / 33.34 dB; over the whole image (2, 4 levels' epsilon) it flattened room's
#: textures (all covered 41.79 -> 41.10).
EDGE_TV_WEIGHT = 1.0 / 255.0
#: Pixels around the depth-edge pixels the total variation reaches (0 / 1 / 2, step 1: clutter
#: 32.44 / 32.50 / 32.51 dB, room 33.34 / 33.40 / 33.41; 2 / 4 with 24 iterations: 32.52 / 32.54,
#: 33.52 / 33.55).
EDGE_TV_RADIUS = 2
#: Colour difference (share of the range) below which the total variation is quadratic.
EDGE_TV_EPSILON = 4.0 / 255.0
#: Relative depth difference within which a subsample and the partner's depth at its image are
#: one surface (the blend's tolerance).
SAME_SURFACE_REL = 0.02
#: A partner's depth-edge pixel whose subsamples all lie on one surface (its silhouette not
#: split inside it) may mix in a surface its depth does not show (a pole's dark limb beside a
#: face, clutter): its residual is left out where it exceeds this share of the colour's range
#: (20/255), so it does not draw that surface into this source. 16 / 24 / 40 / none: clutter's
#: band 32.17 / 32.17 / 32.16 / 32.16, room's 32.98 / 33.06 / 33.10 / 33.12, the line beside
#: clutter's left pole (t = 0.75, mean error of its worst column) 6.0 / 7.0 / 13.0 / 12.9
#: levels (7.2 before the partner's colour). With the longer steps (:data:`PAIR_STEP`) the
#: line came back (24: 5.7 levels): 16 / 20 / 24 now give room 33.41 / 33.44 / 33.50 dB
#: (clutter 32.52-32.53) and the line 3.0 / 3.7 / 5.7.
UNSPLIT_RESIDUAL = 20.0 / 255.0


def back_project(color_k: np.ndarray, color: np.ndarray, k: int, iterations: int | None = None,
                 limits: tuple[float, float] | None = None) -> np.ndarray:
    """(k H, k W, C) float32: ``color_k`` corrected until each pixel's k x k mean is ``color``.

    Parameters
    ----------
    color_k : (k H, k W, C) array
        An upsampled reading of ``color`` (e.g. Lanczos-4), in ``color``'s levels.
    color : (H, W, C) array
        The source pixels (box means of their footprints).
    k : int
        Upsampling factor.
    iterations : int, optional
        Bilinear steps before the final even one (default :data:`BACK_PROJECTIONS`).
    limits : (low, high), optional
        The colour's range (an integer dtype's): the subsamples are kept inside it, and what
        clipping takes from a pixel's mean goes to its other subsamples (:func:`_consistent`).
    """
    iterations = BACK_PROJECTIONS if iterations is None else _check_iterations(iterations)
    k = check_supersample(k)
    if limits is not None and not (np.ndim(limits) == 1 and len(limits) == 2 and limits[0] < limits[1]):
        raise ValueError(f"limits: expected (low, high) with low < high, got {limits!r}")
    s = check_array("color", color, ndim=3, dtype_kind="uif").astype(np.float32)
    x = check_array("color_k", color_k, shape=(s.shape[0] * k, s.shape[1] * k, s.shape[2]),
                    dtype_kind="uif").astype(np.float32)
    for _ in range(iterations):
        x = x + _spread(s - _block_means(x, k), k, cv2.INTER_LINEAR)
    return _consistent(x, s, k, limits)


def super_resolve_pair(sources: tuple[View, View], upsampled: tuple[View, View], k: int,
                       iterations: int | None = None, weight: float | None = None) -> tuple:
    """The two upsampled sources' colours refined by each other (module docstring).

    Parameters
    ----------
    sources : (View, View)
        The sources at their own resolution (their colours are the observations).
    upsampled : (View, View)
        The same at k x k (:func:`~ibr.render.upsample.upsample_view`): cameras, depth (NaN
        where unknown) and the starting colour.
    k : int
        Upsampling factor.
    iterations, weight : optional
        Default :data:`PAIR_ITERATIONS`, :data:`PARTNER_WEIGHT`.

    Returns
    -------
    (color_a, color_b) : arrays of the upsampled colours' shape and dtype
    """
    iterations = PAIR_ITERATIONS if iterations is None else _check_iterations(iterations)
    weight = PARTNER_WEIGHT if weight is None else check_positive("weight", weight)
    k = check_supersample(k)
    _check_views(sources, upsampled, k)
    obs = [_channels(s.color).astype(np.float32) for s in sources]
    x = [_channels(u.color).astype(np.float32) for u in upsampled]
    channels = x[0].shape[2]
    edges = [_depth_edge_pixels(u, k) for u in upsampled]  # (edge pixels, subsample planes): the links' and zones'
    links = [_Link(upsampled[i], upsampled[1 - i], k, weight, channels, _unsplit_edge_pixels(*edges[i]))
             for i in (0, 1)]  # i's subsamples in the other
    limits = _colour_limits(upsampled[0].color.dtype)
    scale = limits[1] if limits else 1.0
    unsplit_limit = np.float32(UNSPLIT_RESIDUAL * scale)
    zones = [_EdgeZone(u, k, edge) for u, (edge, _) in zip(upsampled, edges)]
    length = np.float32(PAIR_STEP)
    tv_weight, tv_eps = np.float32(EDGE_TV_WEIGHT * scale) * length, np.float32(EDGE_TV_EPSILON * scale)
    for _ in range(iterations):
        steps = [_pair_step(xi, obs[i], x[1 - i], obs[1 - i], links[i], links[1 - i], k, unsplit_limit, length)
                 for i, xi in enumerate(x)]
        for xi, step, zone in zip(x, steps, zones):
            step.reshape(-1, channels)[zone.at] += tv_weight * zone.tv_descent(xi, tv_eps)  # (unique indices)
            xi += step
    return tuple(_as_colour(_consistent(xi, o, k, limits), u.color.dtype, u.color.shape)
                 for xi, o, u in zip(x, obs, upsampled))


def _check_iterations(iterations) -> int:
    return check_number("iterations", iterations, integer=True, minimum=0)


def _check_views(sources, upsampled, k: int) -> None:
    for name, pair in (("sources", sources), ("upsampled", upsampled)):
        if not isinstance(pair, (tuple, list)) or len(pair) != 2 or not all(isinstance(v, View) for v in pair):
            raise TypeError(f"{name}: expected two Views, got {type(pair).__name__}")
    for i, (src, up) in enumerate(zip(sources, upsampled)):
        if up.depth is None:
            raise ValueError(f"upsampled[{i}]: expected a View with depth")
        h, w = src.shape
        if up.shape != (h * k, w * k) or np.shape(up.color)[2:] != np.shape(src.color)[2:]:
            raise ValueError(f"upsampled[{i}]: expected {w * k}x{h * k} with sources[{i}]'s channels "
                             f"(k = {k}), got {up.camera.width}x{up.camera.height}")


class _Link:
    """Where one upsampled source's subsamples fall in the other's upsampled image, which of them
    the other does not see (``hidden``: its depth there not within :data:`SAME_SURFACE_REL`), and
    the shares of the own and the other's residual in their steps (the other's ``weight`` where
    it sees them); ``unsplit_edge``: ``this``'s :func:`_unsplit_edge_pixels`."""

    def __init__(self, this: View, other: View, k: int, weight: float, channels: int, unsplit_edge: np.ndarray):
        h, w = this.depth.shape
        mu, mv, z = _pixels_in(this, other)
        z_other = cv2.remap(np.asarray(other.depth, np.float32), mu, mv, cv2.INTER_NEAREST,
                            borderMode=cv2.BORDER_CONSTANT, borderValue=np.nan)
        with np.errstate(invalid="ignore"):
            seen = (np.abs(z_other - z) <= SAME_SURFACE_REL * z).astype(np.float32)  # (k H, k W)
        self.maps = cv2.convertMaps(mu, mv, cv2.CV_16SC2)  # fixed point: remaps twice as fast
        self.pixel_seen = (_block_means(seen, k) > 0).reshape(h // k, w // k, 1)  # seen in part
        self.unsplit_edge = unsplit_edge[..., None]
        # per channel: numpy's products broadcast over a channel axis of 1 take 3x as long
        seen = np.repeat(seen[..., None] > 0, channels, axis=2)  # bool: a quarter of the memory
        self.hidden = ~seen
        self.own_share = np.where(seen, np.float32(1.0 / (1.0 + weight)), np.float32(1.0))  # the other's: 1 - own

    def sample(self, image: np.ndarray) -> np.ndarray:
        """``image`` (the other's upsampled grid) read at this source's subsamples."""
        return _remap(image, self.maps)


def _pair_step(x, obs, x_other, obs_other, link, link_other, k, unsplit_limit, length):
    """The step of one source: its own residual and, where the other sees it, the other's,
    weighted (:class:`_Link`), times ``length`` (:data:`PAIR_STEP`). The other's pixels as this
    source explains them: their subsamples this source sees read in its image, the others the
    other's own (a pixel the other sees beside a silhouette that hides part of it from this
    source still tells)."""
    explained = link_other.sample(x)
    np.copyto(explained, x_other, where=link_other.hidden)  # (one pass; a product with the mask took three)
    residual = obs_other - _block_means(explained, k)
    residual *= link_other.pixel_seen
    residual *= ~(link_other.unsplit_edge & (_largest_channel(np.abs(residual)) > unsplit_limit))
    residual *= length  # (on the pixels: a ninth of the work on the subsamples)
    back = link.sample(_spread(residual, k, cv2.INTER_LINEAR))
    own = _spread((obs - _block_means(x, k)) * length, k, cv2.INTER_LINEAR)
    own -= back  # own * share + back * (1 - share), in place (frame-sized arrays at 3x: 1080p memory)
    own *= link.own_share
    own += back
    return own


def _largest_channel(a: np.ndarray) -> np.ndarray:
    """(H, W, 1): the largest of ``a``'s channels (numpy's max over a last axis of 3 took 40x as
    long as the elementwise maxima of its channel planes)."""
    return functools.reduce(np.maximum, [a[..., c] for c in range(a.shape[2])])[..., None]


class _EdgeZone:
    """The subsamples of an upsampled view's depth-edge pixels (:func:`_depth_edge_pixels`) and
    of the pixels within :data:`EDGE_TV_RADIUS` of them (flat indices into its (k H, k W) grid),
    with their neighbours' (replicated at the border), for :meth:`tv_descent`; ``edge``: the
    depth-edge pixels if already known."""

    def __init__(self, view: View, k: int, edge: np.ndarray | None = None):
        r = 2 * EDGE_TV_RADIUS + 1
        edge = _depth_edge_pixels(view, k)[0] if edge is None else edge
        zone = cv2.dilate(edge.view(np.uint8), np.ones((r, r), np.uint8))
        ys, xs = np.nonzero(np.repeat(np.repeat(zone, k, 0), k, 1))
        h, w = view.depth.shape
        up, down = np.maximum(ys - 1, 0) * w, np.minimum(ys + 1, h - 1) * w
        left, right = np.maximum(xs - 1, 0), np.minimum(xs + 1, w - 1)
        row = ys * w
        self.at = row + xs
        self._neighbours = (row + right, down + xs, row + left, up + xs, down + left, up + right)

    def tv_descent(self, x: np.ndarray, eps) -> np.ndarray:
        """(n, C): the descent direction of the total variation of ``x`` ((k H, k W, C); each
        channel, forward differences smoothed by ``eps``), ``div(grad x / sqrt(|grad x|^2 +
        eps^2))``, at the zone's subsamples."""
        flat = x.reshape(-1, x.shape[-1])
        c = np.take(flat, self.at, axis=0)  # (3x faster than flat[self.at])
        right, down, left, up, down_left, up_right = (np.take(flat, i, axis=0) for i in self._neighbours)
        e2 = eps * eps

        def unit(gx, gy, g):  # g / |(gx, gy)|_eps
            return g / np.sqrt(gx * gx + gy * gy + e2)

        gx, gy = right - c, down - c
        return (unit(gx, gy, gx) - unit(c - left, down_left - left, c - left)
                + unit(gx, gy, gy) - unit(up_right - up, c - up, c - up))


def _depth_edge_pixels(view: View, k: int):
    """The (H, W) bool depth-edge pixels (:func:`~ibr.render.upsample.depth_edge_pixels` of the
    centre subsamples) of a view upsampled k x k, and its k k subsample planes."""
    from .upsample import depth_edge_pixels

    planes = _subsample_planes(np.asarray(view.depth, np.float32), k)
    return depth_edge_pixels(planes[len(planes) // 2], quantization=quantization_of(view)), planes


def _unsplit_edge_pixels(edge: np.ndarray, planes: list) -> np.ndarray:
    """(H, W) bool: the depth-edge pixels of an upsampled view (``edge``, ``planes``:
    :func:`_depth_edge_pixels`) whose k x k subsamples all lie within :data:`SAME_SURFACE_REL`
    of each other."""
    with np.errstate(invalid="ignore"):
        one_surface = np.fmax.reduce(planes) <= np.fmin.reduce(planes) * (1 + SAME_SURFACE_REL)
    return edge & one_surface


def _pixels_in(this: View, other: View):
    """(map_u, map_v, z): where each pixel of ``this`` lands in ``other`` (float32 pixel
    coordinates; far outside where its depth is unknown or it lies behind ``other``) and its
    planar depth there."""
    h, w = this.depth.shape
    cam = this.camera
    z = np.asarray(this.depth, np.float32)
    x = ((np.arange(w, dtype=np.float32) - np.float32(cam.cx)) / np.float32(cam.fx))[None, :] * z
    y = ((np.arange(h, dtype=np.float32) - np.float32(cam.cy)) / np.float32(cam.fy))[:, None] * z
    m = (other.camera.cam_from_world @ cam.world_from_cam).astype(np.float32)  # this camera -> other's
    px, py, pz = (m[i, 0] * x + m[i, 1] * y + m[i, 2] * z + m[i, 3] for i in range(3))
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(pz > 0, np.float32(1.0) / pz, np.nan)
        mu = np.nan_to_num(np.float32(other.camera.fx) * px * inv + np.float32(other.camera.cx), nan=-1e6)
        mv = np.nan_to_num(np.float32(other.camera.fy) * py * inv + np.float32(other.camera.cy), nan=-1e6)
    return mu.astype(np.float32), mv.astype(np.float32), pz


def _spread(r: np.ndarray, k: int, interpolation: int) -> np.ndarray:
    """``r`` upsampled k x k (pixel centres aligned)."""
    return _channels(cv2.resize(r, (r.shape[1] * k, r.shape[0] * k), interpolation=interpolation), r)


def _remap(image: np.ndarray, maps) -> np.ndarray:
    out = cv2.remap(image, maps[0], maps[1], cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return out if out.ndim == image.ndim else out[..., None]


def _channels(a: np.ndarray, like: np.ndarray | None = None) -> np.ndarray:
    """``a`` with a channel axis (OpenCV drops a single one)."""
    a = np.asarray(a)
    return a[..., None] if a.ndim == 2 and (like is None or like.ndim == 3) else a


def _consistent(x: np.ndarray, s: np.ndarray, k: int, limits) -> np.ndarray:
    """``x`` with each pixel's residual ``s - box(x)`` spread evenly over its k x k subsamples;
    within ``limits``, what clipping then takes from a pixel's mean goes to its subsamples in
    proportion to their room to the limit it moves away from (exact where ``s`` lies within
    ``limits``)."""
    x = x + _spread(s - _block_means(x, k), k, cv2.INTER_NEAREST)
    if limits is None:
        return x
    np.clip(x, *limits, out=x)
    r = s - _block_means(x, k)
    ys, xs = np.nonzero(_largest_channel(np.abs(r))[..., 0] > 1e-4)  # the pixels clipping moved (few)
    if ys.size:
        h, w, c = s.shape
        blocks = x.reshape(h, k, w, k, c)
        b = blocks[ys, :, xs]  # (n, k, k, C)
        rb = r[ys, xs][:, None, None, :]
        room = np.where(rb > 0, limits[1] - b, b - limits[0])
        total = room.mean(axis=(1, 2), keepdims=True)
        with np.errstate(divide="ignore", invalid="ignore"):
            step = np.where(total > 0, rb * room / total, 0.0)
        blocks[ys, :, xs] = np.clip(b + step, *limits)
    return x


def _colour_limits(dtype) -> tuple[float, float] | None:
    """(0, the largest value) of an integer colour dtype; None for floats (unbounded)."""
    return (0.0, float(np.iinfo(dtype).max)) if np.issubdtype(dtype, np.integer) else None


def _as_colour(x: np.ndarray, dtype, shape) -> np.ndarray:
    """``x`` as a colour array of ``dtype`` and ``shape`` (integers rounded and clipped to their
    range)."""
    if np.issubdtype(dtype, np.integer):
        x = np.clip(np.rint(x), 0, np.iinfo(dtype).max)
    return x.astype(dtype).reshape(shape)
