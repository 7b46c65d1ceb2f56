"""Two-source compositing of rendered layers (seed 002 section 2.2, step 1).

Two source views rendered into the same intermediate camera leave complementary holes. The seed
orders them by the distance of the new viewpoint to each source: the nearer source's layer is the
foreground, the other only fills its holes (``mode="front"``). The default ``mode="blend"`` is
depth-aware: where both layers see the same surface (planar depths within ``depth_tol``, relative)
their colors are mixed with weights from the viewpoint distances (``w_a = d_b / (d_a + d_b)``),
which removes the seam where the foreground layer ends and averages view-dependent differences;
where the depths disagree the nearer surface wins (a z-test), so an object one source missed still
occludes what is behind it. Measured on the bundled pairs (``benchmarks/bench_render.py``) the
blend is the better of the two (README, section render).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from . import _composite_kernels as _k
from .bands import run_bands
from ..base.validate import check_choice, check_positive
from ..base.camera import Camera
from .rasterize import Layer, scratch

__all__ = ["COMPOSITE_MODES", "Composite", "composite", "mixed_pixels", "pack_trust", "remap_composite", "rgbt_source",
           "rim_beside_holes", "sample_composite", "source_trust", "trust_channel", "viewpoint_weights"]

#: Relative step in inverse depth between 4-neighbours that marks a depth discontinuity (and
#: that is also ``STEP_RATIO`` times larger than the neighbouring differences on the line).
STEP_REL = 0.02
STEP_RATIO = 3.0
#: Trust of a mixed silhouette pixel in the blend (clean pixels: 1).
MIXED_TRUST = 0.03
#: Codes of the depth encoding's quantization step added to the blend's depth tolerance (two
#: sources' planes fitted to integer codes may each be half a code off; #11)
QUANT_BLEND_CODES = 1.5
#: Codes of the depth encoding's quantization step that a step between 4-neighbours must exceed
#: to count as a silhouette (:func:`mixed_pixels` with ``quantization``): neighbouring planes
#: fitted to integer codes of one smooth surface may differ by up to about a code (#11).
QUANT_STEP_CODES = 1.5

_NO_TRUST = np.ones((1, 1, 2), np.float32)
_NO_TRUST_2D = np.ones((1, 1), np.float32)
_NO_RIM = np.zeros((1, 1), np.bool_)

#: Compositing modes: depth-aware blend (default) and the seed's front/back order.
COMPOSITE_MODES = ("blend", "front")


@dataclass(frozen=True, eq=False)
class Composite:
    """Result of :func:`composite`: ``color`` (H, W, C) in the requested dtype, ``depth`` (H, W)
    float32 planar z (NaN where no layer covers), ``coverage`` (H, W) bool; ``replace`` (H, W)
    bool or None: covered pixels whose colour a hole fill should replace (background-rim samples
    beside a hole or the other layer, :func:`rim_beside_holes`)."""

    color: np.ndarray
    depth: np.ndarray
    coverage: np.ndarray
    replace: np.ndarray | None = None


#: Pixels per strip in :func:`mixed_pixels` (bounds its temporary arrays to a few MB)
_STRIP_PIXELS = 1 << 18


def _quant_tolerance(quantization) -> tuple[float, float]:
    """(quant0, quant2) of the composite kernels' agreement test for ``quantization`` (a
    :class:`~ibr.base.depth.DepthQuantization`, a sequence of them or None per source: the
    coarsest wins): ``QUANT_BLEND_CODES`` times its c0 and c2."""
    from ..base.depth import DepthQuantization

    qs = quantization if isinstance(quantization, (list, tuple)) else [quantization]
    c0 = c2 = 0.0
    for i, q in enumerate(qs):
        if q is None:
            continue
        if not isinstance(q, DepthQuantization):
            raise TypeError(f"quantization: expected an ibr.base.depth.DepthQuantization (or one per source), got "
                            f"{type(q).__name__}")
        c0, c2 = max(c0, q.c0), max(c2, q.c2)
    return QUANT_BLEND_CODES * c0, QUANT_BLEND_CODES * c2


def _layer_order(weights, n: int) -> tuple[int, int, float, float]:
    """``weights`` of ``n`` (1 or 2) layers, checked and normalized, as ``(a, b, wa, wb)``: the
    index and weight of the layer with the larger weight first (the nearer source, which the
    kernels call layer a), then the other; one layer: ``(0, 0, 1.0, 0.0)``."""
    w = np.asarray(weights, dtype=np.float64).reshape(-1)
    if w.shape != (n,) or not np.all(np.isfinite(w)) or np.any(w < 0) or w.sum() <= 0:
        raise ValueError(f"weights: expected {n} non-negative finite weights with a positive sum, got {weights!r}")
    if n == 1:
        return 0, 0, 1.0, 0.0
    w = w / w.sum()
    a, b = (0, 1) if w[0] >= w[1] else (1, 0)
    return a, b, float(w[a]), float(w[b])


def _sources_and_maps(sources, maps) -> tuple[list, list]:
    """``sources`` and ``maps`` as lists of one or two each, the same number."""
    sources, maps = list(sources), list(maps)
    if not 1 <= len(sources) <= 2 or len(maps) != len(sources):
        raise ValueError(f"sources, maps: expected 1 or 2 of each, got {len(sources)} and {len(maps)}")
    return sources, maps


def _steps(q: np.ndarray, axis: int, rel: float, ratio: float, quantization=None) -> np.ndarray:
    """Depth discontinuities between neighbours along ``axis`` of inverse depth ``q`` (NaN
    invalid): a valid/invalid pair, or ``|dq| > rel * min(q)`` and ``> ratio`` times the
    smaller of the two neighbouring differences on the line (a step, not a steep plane; the
    smaller, so that both edges of a one-pixel-wide object count), and, for quantized depth,
    more than :data:`QUANT_STEP_CODES` codes of the encoding (``quantization``)."""
    d = np.diff(q, axis=axis)
    ad = np.abs(d)
    pad = [(0, 0), (0, 0)]
    pad[axis] = (1, 1)
    p = np.pad(np.where(np.isnan(ad), np.inf, ad), pad, constant_values=np.inf)  # missing: no evidence
    sl = [slice(None), slice(None)]
    sl[axis] = slice(None, -2)
    left = p[tuple(sl)]
    sl[axis] = slice(2, None)
    right = p[tuple(sl)]
    n = q.shape[axis]
    q0, q1 = np.take(q, np.arange(n - 1), axis=axis), np.take(q, np.arange(1, n), axis=axis)
    with np.errstate(invalid="ignore"):
        step = (ad > rel * np.fmin(q0, q1)) & (ad > ratio * np.minimum(left, right))
        if quantization is not None:
            step &= ad > QUANT_STEP_CODES * quantization.inv_step(np.fmax(q0, q1))
    return step | (np.isnan(q0) != np.isnan(q1))


def mixed_pixels(depth, *, rel: float = STEP_REL, ratio: float = STEP_RATIO, side: str = "both",
                 quantization=None) -> np.ndarray:
    """(H, W) bool: pixels on either side of a depth discontinuity of a source (silhouettes).

    A camera integrates each pixel over its area, so a pixel whose 4-neighbour lies across a
    depth step (see :data:`STEP_REL`, :data:`STEP_RATIO`; the edge of valid depth counts)
    holds a mixture of foreground and background colour while its depth is one of the two. Such
    pixels are marked on *both* sides of the step (``side="both"``), or only the farther pixel
    of each step between two valid depths (``side="far"``: the background rim, whose colour
    carries the foreground's). Invalid pixels are never marked. With ``quantization`` (the
    :class:`~ibr.base.depth.DepthQuantization` of the depth's encoding) a step must also exceed
    :data:`QUANT_STEP_CODES` codes: the staircase of a smooth surface is no silhouette.
    """
    if side not in ("both", "far"):
        raise ValueError(f"side: expected 'both' or 'far', got {side!r}")
    z = np.asarray(depth, np.float64)
    if z.ndim != 2:
        raise ValueError(f"depth: expected (H, W), got shape {z.shape}")
    with np.errstate(divide="ignore", invalid="ignore"):
        q = np.where(np.isfinite(z) & (z > 0), 1.0 / z, np.nan)
    out = np.zeros(q.shape, bool)
    h, w = q.shape
    # steps along a row depend on that row only (along a column, on that column): strips of
    # rows (columns) keep numpy's temporaries small (a 1080p frame peaked 130 MB higher, #13)
    rows = max(1, _STRIP_PIXELS // max(w, 1))
    for r0 in range(0, h, rows) if w > 1 else ():
        _mark(out[r0:r0 + rows], q[r0:r0 + rows], 1, rel, ratio, side, quantization)
    cols = max(1, _STRIP_PIXELS // max(h, 1))
    for c0 in range(0, w, cols) if h > 1 else ():
        _mark(out[:, c0:c0 + cols], q[:, c0:c0 + cols], 0, rel, ratio, side, quantization)
    return out & ~np.isnan(q)


def _mark(out: np.ndarray, q: np.ndarray, axis: int, rel: float, ratio: float, side: str, quantization) -> None:
    """Mark in ``out`` the pixels of the steps of ``q`` along ``axis`` (see mixed_pixels)."""
    step = _steps(q, axis, rel, ratio, quantization)
    first = (slice(None, -1), slice(None)) if axis == 0 else (slice(None), slice(None, -1))
    second = (slice(1, None), slice(None)) if axis == 0 else (slice(None), slice(1, None))
    if side == "both":
        out[first] |= step
        out[second] |= step
        return
    with np.errstate(invalid="ignore"):
        first_far = q[first] < q[second]  # smaller inverse depth: the farther pixel (NaN: False)
        second_far = q[second] < q[first]
    out[first] |= step & first_far
    out[second] |= step & second_far


def source_trust(depth=None, *, mixed_trust: float = MIXED_TRUST, quantization=None, mixed=None) -> np.ndarray:
    """(H, W) float32 trust of each source pixel's colour: ``mixed_trust`` on the mixed pixels
    of :func:`mixed_pixels` (with the depth's ``quantization``, if any; or ``mixed``, those
    pixels already found, instead of ``depth``), 1 elsewhere. Sampled bilinearly with the colour, it scales the blend
    weights where two sources see the same surface, so a clean pixel of the other source wins
    over a silhouette pixel that carries the other surface's colour (the ghost outline)."""
    if (depth is None) == (mixed is None):
        raise ValueError("depth, mixed: give exactly one (the depth, or its mixed pixels)")
    if mixed is None:
        mixed = mixed_pixels(depth, quantization=quantization)
    t = np.ones(np.shape(mixed), np.float32)
    t[np.asarray(mixed, bool)] = np.float32(mixed_trust)
    return t


def pack_trust(trust, rim=None) -> np.ndarray:
    """(H, W, 2) float32: the trust map and, per pixel, the minimum over the 2x2 block that
    starts there (the taps of a bilinear sample whose floor is that pixel; clamped at the
    border), so the sampler skips the interpolation where all four taps are clean. On the
    background rim ``rim`` (:func:`mixed_pixels` with ``side="far"``; default none) the block
    minimum is stored as ``-1 - minimum`` (negative: the sampler reads the flag from its sign,
    and ``< 1`` still sends it to the interpolation; one map less per source, #13)."""
    t = np.ascontiguousarray(trust, np.float32)
    m = t.copy()
    m[:, :-1] = np.minimum(m[:, :-1], t[:, 1:])
    m[:-1] = np.minimum(m[:-1], m[1:])
    if rim is not None:
        r = np.asarray(rim, bool)
        m[r] = -1.0 - m[r]
    return np.ascontiguousarray(np.stack([t, m], -1))


def rim_beside_holes(coverage, rim) -> np.ndarray:
    """(H, W) bool: the pixels of ``rim`` that have a 4-neighbour ``coverage`` leaves out.

    ``rim`` marks pixels that only one source covers with a sample from its background rim
    (:func:`mixed_pixels` with ``side="far"``): its colour mixes in the foreground beside it in
    that source. Where the target still shows that foreground next to it (the source's layer
    covers every neighbour, e.g. at the source's own pose) the mixture is right; where that
    source's layer ends beside the pixel (a disocclusion opened between the two surfaces: a hole,
    or pixels only the other source sees) it is a dark or bright outline left on the background,
    and the hole fill should replace its colour (:attr:`Composite.replace`). ``coverage`` is
    therefore the coverage of the rim samples' own layer (one call per layer), or, for a single
    source, of the target.
    """
    out = np.zeros(rim.shape, bool)
    ys, xs = np.nonzero(rim)  # few pixels: test their four neighbours only
    if ys.size == 0:
        return out
    h, w = rim.shape
    beside = np.zeros(ys.size, bool)
    for dy, dx in ((-1, 0), (1, 0), (0, -1), (0, 1)):
        y, x = ys + dy, xs + dx
        inside = (y >= 0) & (y < h) & (x >= 0) & (x < w)
        beside[inside] |= ~coverage[y[inside], x[inside]]
    out[ys[beside], xs[beside]] = True
    return out


def viewpoint_weights(camera: Camera, sources) -> np.ndarray:
    """Blend weights of source cameras for a target ``camera`` from viewpoint distances.

    Two sources at distances ``d_a``, ``d_b`` from the target's center get ``w_a = d_b / (d_a + d_b)``
    and ``w_b = d_a / (d_a + d_b)`` (inverse-distance weights; for a camera interpolated at
    parameter t on the segment between them, ``w_a = 1 - t``). When all centers coincide (pure
    rotation), the rotation angle between the optical axes replaces the distance. A source at
    the target's exact pose gets weight 1.
    """
    sources = list(sources)
    d = np.array([np.linalg.norm(camera.position - s.position) for s in sources])
    if not np.any(d > 1e-12 * max(1.0, float(np.abs(camera.position).max()))):
        z = camera.world_from_cam[:3, 2]
        d = np.array([np.arccos(np.clip(z @ s.world_from_cam[:3, 2], -1, 1)) for s in sources])
    if np.any(d == 0):
        w = (d == 0).astype(np.float64)
    else:
        w = 1.0 / d
    return w / w.sum()


def composite(
    layers,
    weights,
    *,
    mode: str = "blend",
    depth_tol: float = 0.02,
    dtype=np.float32,
    trust=None,
    quantization=None,
) -> Composite:
    """Combine one or two layers rendered into the same camera.

    Parameters
    ----------
    layers : sequence of Layer
        One or two layers of equal size and channel count.
    weights : sequence of float
        Non-negative weight per layer (e.g. :func:`viewpoint_weights`); normalized here. The
        layer with the larger weight is the nearer source (the foreground for ``mode="front"``).
    mode : {"blend", "front"}
        Depth-aware blend (default) or the seed's order (nearer source in front, the other only
        in its holes).
    depth_tol : float
        Relative planar-depth tolerance under which two layers see the same surface
        (``|z_a - z_b| <= depth_tol * min(z_a, z_b)``).
    dtype : numpy dtype
        Output color dtype. Integer outputs are rounded to nearest and clipped to the dtype's
        range (layers hold colors in the source's value scale, see :class:`ibr.render.Layer`).
    trust : sequence of (H, W) float arrays, optional
        Per layer, the trust of each target pixel's colour (e.g. :func:`source_trust` sampled
        like the colour); where the layers agree, the blend weights are scaled by it.
    quantization : DepthQuantization or sequence of them, optional
        The sources' depth quantization (:class:`ibr.base.depth.DepthQuantization`, e.g. integer
        disparities): layers within ``QUANT_BLEND_CODES`` codes of each other (in inverse depth)
        also count as one surface, so planes fitted to coarse codes still blend.
    """
    check_choice("mode", mode, COMPOSITE_MODES)
    depth_tol = check_positive("depth_tol", depth_tol)
    layers = list(layers)
    if not 1 <= len(layers) <= 2:
        raise ValueError(f"layers: expected 1 or 2 layers, got {len(layers)}")
    for i, layer in enumerate(layers):
        if not isinstance(layer, Layer):
            raise TypeError(f"layers[{i}]: expected a Layer, got {type(layer).__name__}")
        if layer.color.shape != layers[0].color.shape:
            raise ValueError(
                f"layers[{i}]: color shape {layer.color.shape} differs from layers[0]'s {layers[0].color.shape}"
            )
    ia, ib, wa, wb = _layer_order(weights, len(layers))
    dtype = np.dtype(dtype)
    is_int = dtype.kind in "ui"
    maxval = float(np.iinfo(dtype).max) if is_int else 0.0
    h, wd, c = layers[0].color.shape
    out = np.empty((h, wd, c), dtype)
    depth = np.empty((h, wd), np.float32)
    coverage = np.empty((h, wd), np.bool_)
    a, b = layers[ia], layers[ib]
    ka = kb = _NO_TRUST_2D
    use_trust = trust is not None and len(layers) == 2
    if use_trust:
        k = [np.ascontiguousarray(t, np.float32) for t in trust]
        if len(k) != 2 or any(t.shape != (h, wd) for t in k):
            raise ValueError(f"trust: expected 2 arrays of shape {(h, wd)}, got {[t.shape for t in k]}")
        ka, kb = k[ia], k[ib]
    _k.composite2(a.color, a.depth, b.color, b.depth, wa, wb, mode == "blend", depth_tol,
                  *_quant_tolerance(quantization),
                  is_int, maxval, out, depth, coverage, use_trust, ka, kb)
    return Composite(out, depth, coverage)


def sample_composite(
    sources,
    maps,
    weights,
    *,
    mode: str = "blend",
    depth_tol: float = 0.02,
    dtype=np.float32,
    trust=None,
    quantization=None,
) -> Composite:
    """Sample and composite in one pass: :func:`composite` of the layers that bilinear sampling of
    ``sources`` at ``maps`` would give, without materializing the layer colors.

    Parameters
    ----------
    sources : sequence of (H_s, W_s, C) arrays
        Source colors (one or two, same channel count and dtype; uint8, uint16 or float). Values
        are interpolated in float32 in the sources' own value scale.
    maps : sequence of SourceMaps
        Per layer: source coordinates (pixel centers at integers: 3.0 is column 3, 3.5 the mean of
        columns 3 and 4), target depth (NaN uncovered); all of the target size.
    weights, mode, depth_tol, dtype, quantization
        As in :func:`composite`.
    trust : sequence of (H_s, W_s) float32 arrays, optional
        Per source, :func:`source_trust` (source pixel grid; or its :func:`pack_trust`, which
        callers rendering many frames can cache); sampled with the colour's bilinear taps, it
        scales the blend weights where the layers agree.

    Notes
    -----
    Sampling is exact bilinear in float32 (``cv2.remap`` rounds positions to 1/32 px); taps
    beyond the image border repeat the border pixel. Equivalent to ``composite`` of
    ``Layer(sample_maps(...))`` layers up to that rounding, and cheaper: one parallel pass, no
    OpenCV thread pool competing with numba's.
    """
    check_choice("mode", mode, COMPOSITE_MODES)
    depth_tol = check_positive("depth_tol", depth_tol)
    sources, maps = _sources_and_maps(sources, maps)
    a, b, wa, wb = _layer_order(weights, len(sources))
    single = len(sources) == 1
    for i, s in enumerate(sources):
        if s.ndim != 3 or s.shape[2] != sources[0].shape[2] or s.dtype != sources[0].dtype:
            raise ValueError(f"sources[{i}]: expected (H, W, C) with C = {sources[0].shape[2]} and dtype "
                             f"{sources[0].dtype}, got {s.dtype} {s.shape}")
    dtype = np.dtype(dtype)
    is_int = dtype.kind in "ui"
    maxval = float(np.iinfo(dtype).max) if is_int else 0.0
    h, wd = maps[0].depth.shape
    out = np.empty((h, wd, sources[0].shape[2]), dtype)
    depth = np.empty((h, wd), np.float32)
    coverage = np.empty((h, wd), np.bool_)
    ma, mb = maps[a], maps[b]
    ka = kb = _NO_TRUST
    use_trust = trust is not None and not single
    if use_trust:
        k = [np.asarray(t, np.float32) for t in trust]
        if len(k) != 2 or any(t.shape[:2] != s.shape[:2] for t, s in zip(k, sources)):
            raise ValueError("trust: expected one (H_s, W_s) array per source, of the source's size")
        k = [t if t.ndim == 3 and t.shape[2] == 2 else pack_trust(t) for t in k]
        ka, kb = k[a], k[b]
    rim = np.empty(depth.shape, np.bool_)
    run_bands(_k.sample_composite2, out.shape[0], sources[a], ma.map_u, ma.map_v, ma.depth, sources[b], mb.map_u,
              mb.map_v, mb.depth, single, wa, wb, mode == "blend", depth_tol, *_quant_tolerance(quantization), is_int,
              maxval, out, depth, coverage, use_trust, ka, kb, rim)
    return Composite(out, depth, coverage, rim if use_trust and not single and rim.any() else None)


#: Pixels sampled at a time by :func:`remap_composite`: chunks of whole rows, per thread and source
#: a (rows, W, 4) work array of 0.5 MB (64 rows at 1920 wide, where whole layer images took 8.3 MB
#: each; 166 rows of the 741-wide motorcycle: 64 rows there cost 2-3 % more per warp).
CHUNK_PIXELS = 64 * 1920


def _chunk_rows(width: int) -> int:
    """Rows per chunk of :func:`remap_composite` for an image ``width`` pixels wide."""
    return max(16, CHUNK_PIXELS // max(int(width), 1))


def _remap_rows(src, m, r0: int, r1: int, dst, scale: int, work) -> None:
    """``cv2.remap`` of rows ``r0 .. r1-1`` of maps ``m`` from ``src`` into ``dst``; with
    ``scale`` 2 the source is upsampled 2 x 2 and the rows' map coordinates are doubled into
    ``work`` (two per-thread (rows, W) float32 arrays; exact in float32)."""
    mu, mv = m.map_u[r0:r1], m.map_v[r0:r1]
    if scale != 1:
        su, sv = work[0][:r1 - r0], work[1][:r1 - r0]
        mu, mv = np.multiply(mu, np.float32(scale), out=su), np.multiply(mv, np.float32(scale), out=sv)
    cv2.remap(src, mu, mv, cv2.INTER_LINEAR, dst=dst, borderMode=cv2.BORDER_REPLICATE)


def rgbt_source(color, trust=None) -> np.ndarray:
    """(H, W, 4) uint8: an 8-bit three-channel ``color`` and, as its fourth channel, ``trust``
    (:func:`source_trust`, in [0, 1]) in steps of 1/255 (255 where ``trust`` is None): the source
    layout of :func:`remap_composite`, which callers rendering many frames cache."""
    c = np.asarray(color)
    if c.ndim != 3 or c.shape[2] != 3 or c.dtype != np.uint8:
        raise ValueError(f"color: expected (H, W, 3) uint8, got {c.dtype} {c.shape}")
    out = np.empty((*c.shape[:2], 4), np.uint8)
    out[..., :3] = c
    out[..., 3] = 255 if trust is None else trust_channel(trust, c.shape[:2])
    return out


def trust_channel(trust, shape) -> np.ndarray:
    """(H, W) uint8: ``trust`` (in [0, 1], clipped) in steps of 1/255, rounded; ``shape`` (H, W)
    is checked."""
    t = np.asarray(trust, np.float32)
    if t.shape != tuple(shape):
        raise ValueError(f"trust: expected shape {tuple(shape)}, got {t.shape}")
    scaled = np.clip(t, 0.0, 1.0)  # one temporary (peak memory at 1080p, #13)
    scaled *= 255.0
    return np.rint(scaled, out=scaled).astype(np.uint8)


def remap_composite(sources, maps, weights, *, mode: str = "blend", depth_tol: float = 0.02, rims=None,
                    quantization=None, source_scale: int = 1) -> Composite:
    """:func:`sample_composite` for 8-bit colour: each source is sampled by ``cv2.remap`` (its
    SIMD path for four 8-bit channels), then the layers are composited, band by band of rows on
    the :mod:`~ibr.render.bands` pool, each band in chunks of whole rows (:data:`CHUNK_PIXELS`) sampled into
    per-thread work arrays and composited while still in cache (no frame-sized layer images).

    Parameters
    ----------
    sources : sequence of (H_s, W_s, 4) uint8
        One or two :func:`rgbt_source` arrays: colour and trust, sampled together (the trust with
        the colour's bilinear weights, as :func:`sample_composite` does).
    maps, weights, mode, depth_tol, quantization
        As in :func:`sample_composite`.
    rims : sequence of (H_s, W_s) bool, optional
        Per source, its background rim (:func:`mixed_pixels` with ``side="far"``); with two
        sources, the trust scales the blend and :attr:`Composite.replace` marks the rim samples
        beside a pixel their layer does not cover (as ``sample_composite`` with ``trust``). None: the trust channel is unused.
    source_scale : {1, 2}
        2: each source is its image upsampled 2 x 2 co-sited
        (:func:`~ibr.render.sharp_sampling.upsample_cosited`, shape (2 H_s, 2 W_s, 4)) while
        ``maps`` and ``rims`` stay in the image's own coordinates (each chunk's map rows are
        doubled into work arrays for ``cv2.remap``).

    Notes
    -----
    OpenCV's 8-bit bilinear remap quantizes the fractional position to 1/32 pixel (INTER_BITS = 5)
    and rounds each layer to 8 bits before the blend; taps beyond the border repeat the border
    pixel, as in ``sample_composite``. The result differs from the exact float32 sampler by at
    most a few levels at sharp edges (``tests/test_composite.py`` bounds it), at 1920 x 1080 in
    a quarter of its time (``ibr bench speed``).
    """
    check_choice("mode", mode, COMPOSITE_MODES)
    depth_tol = check_positive("depth_tol", depth_tol)
    sources, maps = _sources_and_maps(sources, maps)
    for i, s in enumerate(sources):
        if s.ndim != 3 or s.shape[2] != 4 or s.dtype != np.uint8:
            raise ValueError(f"sources[{i}]: expected (H, W, 4) uint8 (rgbt_source), got {s.dtype} {s.shape}")
    if source_scale not in (1, 2) or isinstance(source_scale, bool):
        raise ValueError(f"source_scale: expected 1 or 2, got {source_scale!r}")
    a, b, wa, wb = _layer_order(weights, len(sources))
    single = len(sources) == 1
    h, wd = maps[0].depth.shape
    use_trust = rims is not None and not single
    ra = rb = _NO_RIM
    if use_trust:
        r = [np.asarray(x, np.bool_) for x in rims]
        if len(r) != 2 or any(tuple(source_scale * n for n in x.shape) != s.shape[:2] for x, s in zip(r, sources)):
            raise ValueError("rims: expected one (H_s, W_s) bool array per source, of the source's size"
                             + (" (its image's, before the 2 x 2 upsampling)" if source_scale == 2 else ""))
        ra, rb = r[a], r[b]
    out = np.empty((h, wd, 3), np.uint8)
    depth = np.empty((h, wd), np.float32)
    coverage = np.empty((h, wd), np.bool_)
    rim = np.empty((h, wd), np.bool_)
    ma, mb = maps[a], maps[b]
    quant0, quant2 = _quant_tolerance(quantization)

    rows = _chunk_rows(wd)

    def band(v0, v1):  # sample chunks of this band's rows, each composited while still in cache
        chunks = [scratch(("rgbt-chunk", i), (rows, wd, 4), np.uint8) for i in range(len(sources))]
        work = [scratch(("map-chunk", axis), (rows, wd), np.float32) for axis in "uv"] if source_scale != 1 else None
        for r0 in range(v0, v1, rows):
            r1 = min(r0 + rows, v1)
            for src, m, dst in zip(sources, maps, chunks):
                _remap_rows(src, m, r0, r1, dst[:r1 - r0], source_scale, work)
            _k.composite_rgbt(r0, r1, chunks[a], ma.depth, chunks[b], mb.depth, single, wa, wb, mode == "blend",
                              depth_tol, quant0, quant2, out, depth, coverage, use_trust, ra, ma.map_u, ma.map_v, rb,
                              mb.map_u, mb.map_v, rim, r0, sources[a], sources[b], source_scale)

    run_bands(band, h)
    return Composite(out, depth, coverage, rim if use_trust and rim.any() else None)


def _pixels_of(mask) -> tuple[np.ndarray, np.ndarray]:
    """(rows, columns) of the set pixels of a 2-D bool or uint8 ``mask``, row by row as
    ``np.nonzero`` lists them: ``cv2.findNonZero``, 0.1 ms at 741 x 500 where np.nonzero took 0.73."""
    found = cv2.findNonZero(np.ascontiguousarray(mask).view(np.uint8))  # (N, 2) or (N, 1, 2) (x, y), or None
    if found is None:
        return np.empty(0, np.intp), np.empty(0, np.intp)
    xs, ys = found.reshape(-1, 2).T
    return ys, xs
