"""One frame of view synthesis from its sources' maps (:mod:`ibr.render.view_synthesis`): the
sources rasterized into the target camera, composited (the 8-bit, float-layer or bicubic path,
with the silhouettes' trust), the covered pixels the fill should recolour marked (background-rim
samples beside a gap, stray samples), the edge pixels' subsamples for ``antialias``, and the
holes filled (:func:`_finish`)."""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..base.camera import Camera
from .composite import Composite, _pixels_of, composite, remap_composite, sample_composite
from .fill import _fill_background_inplace, _fill_previous_inplace, _fill_pullpush_inplace
from .matting import _full_scale, rematte_rims, rematte_subsamples
from .sharp_sampling import SHARP_SCALE
from .edge_antialias import average_edge_pixels, edge_candidates, subsample_maps, unpack_subsamples
from .rasterize import CRACK_REL, Layer, SourceMaps, _rasterize_many_into, sample_maps, scratch, scratch_maps
from .rendering import Rendering
from .sources import _RING, _mesh_key, _quantization_in, _source, source_mesh

#: An anti-aliased frame's (:mod:`ibr.render.edge_antialias`) edge test: the relative depth
#: difference that makes a step, and the colour span (of full scale) below which an edge is left
#: as it is (0: the same figures with 35 % more candidates; 64/255: clutter's band -0.14 dB).
EDGE_DEPTH_TOL = 0.02
EDGE_CONTRAST = 32 / 255

#: A pixel and its four neighbours: eroding a coverage with it keeps the pixels all of whose
#: 4-neighbours are covered.
_CROSS = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], np.uint8)


#: Map coordinates of the pixels a source does not cover, in the scratch maps of view synthesis:
#: inside the source, since every sampler here reads a pixel's maps only where it is covered.
#: Far off the source (rasterize's ``_FAR``) sent cv2.remap's 8-bit path through its per-pixel
#: border handling at every hole pixel (motorcycle, 16 % holes: remap 0.85 -> 0.31 ms a warp, #13).
_UNCOVERED_COORD = np.float32(0.0)


def _source_maps(views, camera: Camera, method: str, footprint: str, splat: str, mesh_options,
                 setups: list | None = None) -> list:
    """Where each target pixel samples each of ``views`` (``mesh_options``: one dict per view).
    Meshes are rasterized together into per-thread scratch buffers of slots "a", "b" (valid until
    the next call; internal use only), all sources' rows in one pass of the band pool.
    ``setups`` receives each mesh's quad set-up (``_rasterize_many_into``)."""
    if method == "mesh":
        return _rasterize_many_into([source_mesh(v, **o) for v, o in zip(views, mesh_options)], camera, footprint,
                                    0.01, [scratch_maps(slot, camera.shape) for slot in "ab"[:len(views)]],
                                    crack_rel=CRACK_REL, far_coord=_UNCOVERED_COORD, setups=setups)
    from .forward import forward_maps

    return [forward_maps(v.depth, v.camera, camera, splat=splat) for v in views]


def _render(views, camera, weights, *, method, footprint, splat, mesh_options, interpolation, composite_mode,
            depth_tol, dtype, silhouettes=False, rematte=False, antialias=False):
    """Render one or two sources into ``camera`` and composite them (output arrays are fresh).
    ``mesh_options``: one dict per view. ``silhouettes``: mixed silhouette pixels of each
    source get low trust where the two layers agree (:func:`~ibr.render.composite.source_trust`).
    :attr:`~ibr.render.composite.Composite.replace` marks the covered pixels the fill should recolour: background-rim
    samples beside their layer's gap and stray samples (:func:`_stray_samples`). ``rematte``
    (with ``silhouettes``, two sources): foreground-rim samples are re-composited over the
    target's background (:mod:`ibr.render.matting`). ``antialias`` (method mesh): the
    subsamples of the frame's depth-edge pixels are composited too
    (:mod:`ibr.render.edge_antialias`; with ``rematte`` it is they that are re-mixed, not the
    frame's pixels) and returned as :class:`_EdgeSubsamples` beside the composite (None
    otherwise), for :func:`_antialias` once the frame is finished."""
    mattes = None
    if rematte and silhouettes and len(views) == 2 and method == "mesh":
        # foreground rims over the target's background (not for supersampled sources, whose rims are
        # subsamples placed by their colour: clutter's band 31.06 -> 31.00 dB with it); made before
        # the frame's maps exist (1080p peak memory)
        mattes = [_source(v).rim_matte(o) for v, o in zip(views, mesh_options)]
    setups = []  # each mesh's quads set up for the camera, for the edge subsamples
    maps = _source_maps(views, camera, method, footprint, splat, mesh_options, setups)
    if not any(m.coverage.any() for m in maps):
        return None, None
    composite_options = dict(method=method, mesh_options=mesh_options, interpolation=interpolation,
                             composite_mode=composite_mode, depth_tol=depth_tol, dtype=dtype, silhouettes=silhouettes)
    comp = _composite_maps(views, maps, weights, **composite_options)
    if mattes is not None and not antialias:  # (anti-aliased: the subsamples are re-mixed instead)
        rematte_rims(comp.color, comp.depth, camera, maps, mattes, [v.depth.shape for v in views])
    stray = _stray_samples(maps, views, comp.coverage)
    if stray is not None:
        comp = Composite(comp.color, comp.depth, comp.coverage, stray if comp.replace is None else comp.replace | stray)
    edges = None
    if antialias and method == "mesh":
        edges = _edge_subsamples(views, maps, setups, camera, weights, comp, footprint, composite_options, mattes)
    return comp, edges


@dataclass(frozen=True)
class _EdgeSubsamples:
    """The composited subsamples of a frame's candidate edge pixels (``ys``, ``xs``) and which of
    them lie on their centre's quads in every source (``same``)."""

    ys: np.ndarray
    xs: np.ndarray
    sub: Composite
    same: np.ndarray


def _edge_subsamples(views, maps, setups, camera, weights, comp, footprint, composite_options,
                     mattes=None) -> _EdgeSubsamples:
    """The subsamples of the pixels of ``comp`` where a silhouette can cross, composited from
    each source's maps as the frame was (:mod:`ibr.render.edge_antialias`); not of holes nor
    of the pixels the fill recolours."""
    exclude = ~comp.coverage if comp.replace is None else ~comp.coverage | comp.replace
    ys, xs = edge_candidates(comp.depth, comp.color, depth_tol=EDGE_DEPTH_TOL,
                             contrast=EDGE_CONTRAST * _full_scale(comp.color.dtype), exclude=exclude)
    meshes = [source_mesh(v, **o) for v, o in zip(views, composite_options["mesh_options"])]
    traced = [subsample_maps(mesh, camera, m, ys, xs, footprint=footprint, far_coord=_UNCOVERED_COORD, quads=q)
              for mesh, m, q in zip(meshes, maps, setups)]
    sub = _composite_maps(views, [t[0] for t in traced], weights, slots=("edge a", "edge b"), **composite_options)
    same = functools.reduce(np.logical_and, [t[1] for t in traced])  # on the centre's quads in every source
    n = len(ys)
    if mattes is not None and n:  # foreground-rim subsamples over the target's background
        layers = [SourceMaps(*[unpack_subsamples(getattr(t[0], f), n) for f in ("map_u", "map_v", "depth", "coverage")])
                  for t in traced]
        rematte_subsamples(unpack_subsamples(sub.color, n), unpack_subsamples(sub.depth, n), layers, ys, xs,
                           comp.color, comp.depth, mattes, [v.depth.shape for v in views])
    return _EdgeSubsamples(ys, xs, Composite(*[unpack_subsamples(a, n) for a in (sub.color, sub.depth, sub.coverage)]),
                           same)


def _antialias(r: "Rendering", edges: "_EdgeSubsamples | None") -> "Rendering":
    """``r`` with its edge pixels filtered over their subsamples (in place)."""
    if edges is not None:
        color = r.color if r.color.ndim == 3 else r.color[..., None]  # (a composite's colour is (H, W, C))
        average_edge_pixels(color, r.depth, edges.ys, edges.xs, edges.sub.color, edges.sub.depth,
                            edges.sub.coverage, edges.same, EDGE_DEPTH_TOL)
    return r


def _composite_maps(views, maps, weights, *, method, mesh_options, interpolation, composite_mode, depth_tol,
                    dtype, silhouettes, slots=("a", "b")):
    """The composite of :func:`_render` from the sources' ``maps`` (by the 8-bit, the float or the
    bicubic path; ``slots``: the keys of the float path's per-source scratch layers)."""
    keys = [_mesh_key(o) if method == "mesh" else None for o in mesh_options]
    use_trust = silhouettes and len(views) == 2
    quant = [_quantization_in(o, v) for v, o in zip(views, mesh_options)]
    raw = [_source(v).raw for v in views]
    scale = SHARP_SCALE if interpolation == "sharp" else 1
    if interpolation != "cubic" and raw[0].dtype == np.uint8 and raw[0].shape[2] == 3 and np.dtype(dtype) == np.uint8:
        # 8-bit colour: cv2.remap's four-channel SIMD path samples colour + trust (of the sources
        # upsampled 2 x 2 for sharp sampling), then one pass
        got = [_source(v).rgbt(k, use_trust, scale) for v, k in zip(views, keys)]
        return remap_composite([g[0] for g in got], maps, weights, mode=composite_mode, depth_tol=depth_tol,
                               rims=[g[1] for g in got] if use_trust else None, quantization=quant,
                               source_scale=scale)
    trust = packed = None
    if use_trust:
        trust = packed = [_source(v).trust(k) for v, k in zip(views, keys)]
    if interpolation == "linear":  # fused numba pass (no layer images, no OpenCV thread pool)
        return sample_composite(raw, maps, weights, mode=composite_mode, depth_tol=depth_tol, dtype=dtype,
                                trust=trust, quantization=quant)
    colors = [_source(v).sharp_color(k) if scale != 1 else _source(v).color for v, k in zip(views, keys)]
    layers = []
    for m, c, slot in zip(maps, colors, slots):
        buf = scratch((slot, "color"), (*m.depth.shape, c.shape[2]), np.float32)
        if scale != 1:  # bilinear taps on the upsampled colour (sharp_sampling)
            sampled = sample_maps(c, m.map_u * np.float32(scale), m.map_v * np.float32(scale), out=buf)
        else:
            sampled = sample_maps(c, m.map_u, m.map_v, interpolation=interpolation, out=buf)
        layers.append(Layer(sampled, m.depth, m.coverage))
    if trust is not None:
        trust = [sample_maps(np.ascontiguousarray(t[..., :1]), m.map_u, m.map_v)[..., 0] for t, m in zip(trust, maps)]
    comp = composite(layers, weights, mode=composite_mode, depth_tol=depth_tol, dtype=dtype, trust=trust,
                     quantization=quant)
    if packed is None:
        return comp
    _keep_rims_out(comp.color, maps, raw, packed)
    replace = _rim_samples_beside_gaps(maps, [t[..., 1] < 0 for t in packed], depth_tol)
    return Composite(comp.color, comp.depth, comp.coverage, replace if replace.any() else None)


def _keep_rims_out(color, maps, sources, packed) -> None:
    """In place in the composite ``color`` (H, W, C) of the float-layer paths (bicubic, and sharp
    sampling of colour that is not 8-bit RGB): the pixels that one layer alone covers take the
    rule of the bilinear kernels (``_rim_free_store`` in ``_composite_kernels``): near that layer's
    gap, a sample whose nearest source pixel is clean while a tap lies on the background rim is
    taken again, bilinear on the source's own pixels (``sources``: (H_s, W_s, C)) with the taps
    weighted by their trust (``packed``: per source, ``pack_trust``)."""
    from . import _composite_kernels as _ck

    out = color.reshape(*color.shape[:2], -1)
    is_int = out.dtype.kind in "ui"
    maxval = float(np.iinfo(out.dtype).max) if is_int else 0.0
    for i, (m, src, k) in enumerate(zip(maps, sources, packed)):
        ys, xs = _pixels_of(m.coverage & ~maps[1 - i].coverage)
        _ck.rim_free_samples(ys, xs, src, k, m.depth, m.map_u, m.map_v, out, is_int, maxval)


def _stray_samples(maps, views, coverage) -> np.ndarray | None:
    """(H, W) bool, or None when there are none: covered target pixels none of whose eight
    neighbours is covered (a speck inside a hole) whose source pixel, in every layer covering it,
    has a valid neighbour in its source. The warp tore such a sample from its neighbours: its
    depth disagrees with theirs, as a real depth map's outliers do (the Middlebury motorcycle:
    0.11 % of the right view, dark dots of the fork scattered over the disocclusion beside it),
    so the fill recolours it as it does a background-rim sample (its depth stays). A pixel that
    is alone in its source too (every neighbour without depth) is what the source recorded, and
    stays: a source is given back unchanged at its own pose."""
    import cv2

    cov = np.ascontiguousarray(coverage).view(np.uint8)
    alone = cv2.compare(cov, cv2.dilate(cov, _RING), cv2.CMP_GT)  # covered, no covered neighbour
    # (uint8 OpenCV calls: 0.02 ms at 512 x 384, numpy took 0.3)
    ys, xs = _pixels_of(alone)
    if not ys.size:
        return None
    keep = np.zeros(ys.size, bool)
    for m, view in zip(maps, views):
        on = np.flatnonzero(m.coverage[ys, xs])
        lone = _source(view).lone
        keep[on] |= lone[m.nearest_source_pixel(ys[on], xs[on], lone.shape)]
    stray = np.zeros(coverage.shape, bool)
    stray[ys[~keep], xs[~keep]] = True
    return stray if stray.any() else None


def _rim_samples_beside_gaps(maps, rims, depth_tol: float = 0.02) -> np.ndarray:
    """(H, W) bool: target pixels that one layer alone covers with a sample whose nearest source
    pixel lies on that source's background rim (``rims``: per source, ``mixed_pixels(side="far")``),
    beside a pixel that layer does not cover, and pixels where both layers see one surface (depths
    within ``depth_tol``) through such samples, each beside its own layer's gap: what the
    bilinear kernels mark as :attr:`~ibr.render.composite.Composite.replace` (``_nearest``, ``_beside_gap`` and
    ``_rims_beside_both_gaps`` in ``_composite_kernels``), here in numpy for the float-layer
    (bicubic) path."""
    import cv2

    shape = maps[0].coverage.shape
    beside = []
    for m, r in zip(maps, rims):
        cov = np.ascontiguousarray(m.coverage).view(np.uint8)
        ys, xs = _pixels_of(cov > cv2.erode(cov, _CROSS))  # covered, a 4-neighbour not (the image's border is no gap)
        rim = np.zeros(shape, bool)
        rim[ys, xs] = r[m.nearest_source_pixel(ys, xs, r.shape)]
        beside.append(rim)
    a, b = maps
    with np.errstate(invalid="ignore"):
        same = np.abs(a.depth - b.depth) <= depth_tol * np.fmin(a.depth, b.depth)
    return (beside[0] & ~b.coverage) | (beside[1] & ~a.coverage) | (beside[0] & beside[1] & same)


def _finish(comp, camera, t, fill, previous, out_2d, axis=0) -> Rendering:
    """The :class:`Rendering` of the composite ``comp`` in ``camera`` (``t``: its interpolation
    parameter): holes filled as ``fill`` says (``previous``: the frame before, for "previous"),
    the covered pixels :attr:`~ibr.render.composite.Composite.replace` marks recoloured by the
    fill (their depth kept); ``out_2d``: single-channel colour as (H, W); ``axis``: the
    parallax axis of the fill (:func:`~ibr.render.fill.parallax_axis`)."""
    holes = ~comp.coverage
    color, depth = comp.color, comp.depth
    filled = np.zeros_like(holes)
    # background-rim samples beside their layer's gap: covered (the hole mask stays exact), but their colour
    # (foreground mixed in) is replaced by the fill's background estimate; their depth stays
    replace = comp.replace if comp.replace is not None and fill != "none" and comp.replace.any() else None
    if replace is not None and (holes | replace).all():  # no pixel left to fill from: rims stay
        replace = None
    rim_depth = depth[replace] if replace is not None else None
    if holes.any() or replace is not None:
        # seed step 7 (only hole pixels change); a previous frame of another size cannot serve
        if fill == "previous" and previous is not None and previous.depth.shape == holes.shape:
            filled = _fill_previous_inplace(color, depth, holes, replace, previous.color.reshape(color.shape),
                                            previous.depth, axis=axis)
        elif fill in ("previous", "inpaint"):  # streak-free background pull-push
            filled = _fill_pullpush_inplace(color, depth, holes if replace is None else holes | replace, axis=axis)
        elif fill == "background":  # the directional fill of issue 4 (rows and columns)
            filled = _fill_background_inplace(color, depth, holes if replace is None else holes | replace)
    if replace is not None:
        depth[replace] = rim_depth
    if out_2d:
        color = color[..., 0]
    return Rendering(color, depth, holes, filled, camera, t)
