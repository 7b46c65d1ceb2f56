"""New views from RGB-D sources: ``ibr.warp`` (one source) and ``ibr.interpolate`` (two sources).

The pipeline of seed 002 (DESIGN.md section 2, steps 4-7): each source view gets an adaptive quad
mesh (built once and cached on the view object), the mesh is inverse-warped into the target camera
(:func:`ibr.render.render_mesh`: exact per-quad homography, z-buffer), two sources are composited
(:func:`ibr.render.composite.composite`: depth-aware blend by default, the seed's front/back order on
request) and the remaining holes are filled (previous frame in a sequence, depth-aware background
fill for a single frame). ``method="forward"`` replaces the mesh by the per-pixel splat of seed 003
(:func:`ibr.render.forward.forward_warp`) as a fast preview.

Conventions: pixel (u, v) = (column, row) with centers at integer coordinates (the image spans
[-0.5, W-0.5] x [-0.5, H-0.5]); depth is planar z in scene units, float32, NaN where unknown;
output colors keep the sources' dtype (uint8 in, uint8 out, rounded to nearest).
"""

from __future__ import annotations

import functools
import weakref
from dataclasses import dataclass
from typing import Iterator, Sequence

import numpy as np

from ..base.validate import check_choice, check_finite_scalar, check_flag, check_mesh_options, check_positive
from ..base.camera import Camera, interpolate_cameras
from ..base.depth import depth_steps, quantization_of, set_quantization
from .composite import (COMPOSITE_MODES, Composite, _pixels_of, composite, mixed_pixels, pack_trust, remap_composite,
                        rgbt_source, sample_composite, source_trust, trust_channel,
                        viewpoint_weights)
from .fill import FILLS, _fill_background_inplace, _fill_previous_inplace, _fill_pullpush_inplace, parallax_axis
from .matting import _full_scale, rematte_rims, rematte_subsamples, rim_matte
from .sharp_sampling import SHARP_SCALE, upsample_cosited, upsample_rgbt
from .edge_antialias import average_edge_pixels, edge_candidates, subsample_maps, unpack_subsamples
from .supersample import check_supersample, downsample_rendering, supersampled_camera
from .rasterize import (CRACK_REL, FOOTPRINTS, Layer, SourceMaps, _rasterize_many_into, as_float_color,
                        sample_maps, scratch, scratch_maps)
from ..base.view import View, no_valid_depth_message

__all__ = [
    "INTERPOLATIONS",
    "check_antialias",
    "coarse_sources",
    "METHODS",
    "Rendering",
    "interpolate",
    "interpolation_meshes",
    "iter_interpolate",
    "lod_baseline",
    "source_mesh",
    "warp",
]

#: Rendering methods: quad-mesh inverse warp (default) or per-pixel forward splat.
METHODS = ("mesh", "forward")

#: Level-of-detail sources: the camera move of the call (default) or 5 % of the median depth.
LODS = ("move", "depth")

#: Colour reconstruction: bilinear taps on each source upsampled 2 x 2 once (default,
#: :mod:`ibr.render.sharp_sampling`), plain bilinear, or bicubic (float layers, slower).
INTERPOLATIONS = ("sharp", "linear", "cubic")


@dataclass(frozen=True, eq=False)
class Rendering:
    """A rendered view and what is known about each pixel.

    Attributes
    ----------
    color : (H, W, C) or (H, W) array
        Same dtype and channel layout as the source color.
    depth : (H, W) float32
        Planar z in ``camera`` (scene units); NaN where nothing is known (unfilled holes; filled
        pixels carry the depth of what filled them).
    holes : (H, W) bool
        Pixels that no source covered (before filling): every value there is invented.
    filled : (H, W) bool
        Pixels whose colour the fill wrote (previous frame or background fill): the holes it
        filled and covered pixels sampled from a source's background rim (their colour mixed in
        the foreground) beside a hole or the other source's pixels
        (:attr:`~ibr.render.composite.Composite.replace`).
    camera : Camera
        The target camera.
    t : float or None
        Interpolation parameter (0 = first source, 1 = second) when the camera came from one.
    """

    color: np.ndarray
    depth: np.ndarray
    holes: np.ndarray
    filled: np.ndarray
    camera: Camera
    t: float | None = None

    @property
    def unfilled(self) -> np.ndarray:
        """(H, W) bool: holes still empty after filling (color 0, depth NaN)."""
        return self.holes & ~self.filled

    @property
    def hole_fraction(self) -> float:
        """Share of pixels no source covered (before filling)."""
        return float(self.holes.mean())

    def to_view(self, name: str = "rendering") -> View:
        """The rendering as a :class:`~ibr.base.view.View` (e.g. for :func:`ibr.save_view`)."""
        return View(self.color, self.depth, self.camera, name)


#: An anti-aliased frame's (:mod:`ibr.render.edge_antialias`) edge test: the relative depth
#: difference that makes a step, and the colour span (of full scale) below which an edge is left
#: as it is (0: the same figures with 35 % more candidates; 64/255: clutter's band -0.14 dB).
EDGE_DEPTH_TOL = 0.02
EDGE_CONTRAST = 32 / 255

#: A pixel's eight neighbours (the centre left out): dilating with it gives, per pixel, whether
#: any neighbour is set.
_RING = np.array([[1, 1, 1], [1, 0, 1], [1, 1, 1]], np.uint8)
#: A pixel and its four neighbours: eroding a coverage with it keeps the pixels all of whose
#: 4-neighbours are covered.
_CROSS = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], np.uint8)


# ------------------------------------------------------------------------- source cache
class _Source:
    """Per-view cache: the color as the numba sampler reads it, a float32 copy for ``cv2.remap``
    (made on first use), and the meshes by option set."""

    def __init__(self, view: View):
        self.raw = np.ascontiguousarray(view.color if view.color.ndim == 3 else view.color[..., None])
        self._color = None
        self._depth = view.depth
        self.meshes: dict = {}
        self._trust: dict = {}
        self.median_depth = None
        self.any_valid = None  # some finite depth (_check_source)
        self._view = weakref.ref(view)
        self._upsampled: dict = {}
        self._lone = None
        #: an upsampled source's mixed pixels span its 1x pixel: its k x k subsamples, not only the
        #: one beside the step (:meth:`silhouettes`; :func:`_with_mixed_radius`)
        self.mixed_radius = 0

    @property
    def lone(self) -> np.ndarray:
        """(H, W) bool: pixels with depth none of whose eight neighbours has depth (made once)."""
        if self._lone is None:
            import cv2

            valid = np.ascontiguousarray(self._depth > 0).view(np.uint8)  # NaN where a view has no depth
            self._lone = (valid > cv2.dilate(valid, _RING))
            self._lone.setflags(write=False)
        return self._lone

    def drop_dead_partners(self) -> None:
        """Forget the meshes fitted to a partner view that no longer exists, and what was derived
        from them: their keys hold its dead weak reference, so nothing can ask for them again."""
        for cache in (self.meshes, self._trust, self._upsampled):
            for key in [k for k in cache if _holds_dead_ref(k)]:
                del cache[key]

    def upsampled(self, k: int) -> View:
        """The source alone at k x k its resolution with sub-pixel silhouettes and back-projected
        colour (:func:`~ibr.render.upsample.upsample_view`; :func:`warp`), made once per factor;
        its meshes are cached on it like any view's."""
        v = self._upsampled.get(k)
        if v is None:
            v = self._upsampled[k] = _with_mixed_radius(self._upsample(k), k)
        return set_quantization(v, quantization_of(self._view()))  # as the view's is now (it may have been set since)

    def _upsample(self, k: int, refined_key=None, clean_start: bool = False, partner_key=None) -> View:
        """:func:`~ibr.render.upsample.upsample_view` of the source, or with ``refined_key`` (the
        options of a mesh of this source refined against its partner, :func:`_with_partners`) of
        the source with that mesh's depth instead of its stored codes (:func:`_upsampled_pair`;
        ``partner_key``: the partner's, whose quantization its codes' bins take);
        ``clean_start`` for a colour its partner refines."""
        from .upsample import upsample_view

        view = self._view()
        if refined_key is None:
            source = view
        else:
            options = dict(refined_key)
            partner = options[_PARTNER]()
            source = _with_mesh_depth(view, source_mesh(view, **options), partner,
                                      _quantization_in(dict(partner_key or ()), partner))
        return upsample_view(source, k, clean_start=clean_start)

    def upsampled_with(self, partner: View, k: int, refined_key=None, partner_key=None) -> View:
        """The source at k x k as :meth:`_upsample`, its colour refined together with
        ``partner``'s (:func:`~ibr.render.superres.super_resolve_pair`); made once per pair and
        factor (the partner's is cached on it, and both are dropped with either view)."""
        from .superres import super_resolve_pair

        view, other = self._view(), _source(partner)
        self.drop_dead_partners()  # a few keys: the views refined with a partner gone go at once
        other.drop_dead_partners()
        key, key_other = (k, refined_key, weakref.ref(partner), partner_key), (k, partner_key, self._view, refined_key)
        if key not in self._upsampled or key_other not in other._upsampled:
            ups = (self._upsample(k, refined_key, True, partner_key),
                   other._upsample(k, partner_key, True, refined_key))
            colours = super_resolve_pair((view, partner), ups, k)
            refined = [_with_mixed_radius(View(c, u.depth, u.camera, u.name), k) for c, u in zip(colours, ups)]
            self._upsampled[key], other._upsampled[key_other] = refined
        return set_quantization(self._upsampled[key], quantization_of(view))

    def trust(self, mesh_key) -> np.ndarray:
        """(H, W, 2) float32 :func:`~ibr.render.composite.source_trust` of the source (mixed
        silhouette pixels low) with its 2x2 block minimum, negative on the background rim (``pack_trust``), from the depth of its mesh for ``mesh_key`` (planes: quantized
        depth codes are no steps) or, for ``None`` (forward splat), from the raw depth."""
        t = self._trust.get(mesh_key)
        if t is None:
            mixed, far = self.silhouettes(mesh_key)
            t = self._trust[mesh_key] = pack_trust(source_trust(mixed=mixed), far)
            t.setflags(write=False)
            self._trust.pop(("silhouettes", mesh_key), None)  # in the packed trust now (as in :meth:`rgbt`)
        return t

    def silhouettes(self, mesh_key) -> tuple[np.ndarray, np.ndarray]:
        """(H, W) bool :func:`~ibr.render.composite.mixed_pixels` of the depth of its mesh for
        ``mesh_key`` (or the raw depth for ``None``), on both sides of each step and on its far
        side, made once: the trust, the background rims and the rim mattes all read them. An
        upsampled source's (:attr:`mixed_radius`) are widened to cover its 1x mixed pixels, whose
        colour all its k x k subsamples carry (nineteenth session, ``supersample=3``: band
        clutter 32.17 -> 32.23, room 33.07 -> 33.15 dB; the line beside clutter's left pole 7.0 ->
        4.0 levels)."""
        got = self._trust.get(("silhouettes", mesh_key))
        if got is None:
            depth, quant = self._source_depth(mesh_key), self._quantization(mesh_key)
            got = (_widened(mixed_pixels(depth, quantization=quant), self.mixed_radius),
                   mixed_pixels(depth, side="far", quantization=quant))
            for x in got:
                x.setflags(write=False)
            self._trust[("silhouettes", mesh_key)] = got
        return got

    def rgbt(self, mesh_key, silhouettes: bool, scale: int = 1):
        """For an 8-bit three-channel source, what :func:`~ibr.render.composite.remap_composite`
        reads: the colour with the trust as a fourth channel (:func:`rgbt_source`; 255 everywhere
        without ``silhouettes``), upsampled ``scale`` x ``scale`` for sharp sampling
        (:func:`~ibr.render.sharp_sampling.upsample_cosited`; only that one is kept), and the
        background rim (None without ``silhouettes``), cached like :meth:`trust`."""
        key = ("rgbt", mesh_key if silhouettes or scale != 1 else "plain", silhouettes, scale)
        got = self._trust.get(key)
        if got is None:
            depth = self._source_depth(mesh_key) if silhouettes or scale != 1 else None
            mixed, rims = self.silhouettes(mesh_key) if silhouettes else (None, None)
            trust = trust_channel(source_trust(mixed=mixed), depth.shape) if silhouettes else 255
            self._trust.pop(("silhouettes", mesh_key), None)  # kept here (the rims) or no longer needed
            del mixed  # (1080p peak memory: two frame-sized masks less while the frame is composited)
            if scale == 1:
                color = rgbt_source(self.raw)
                color[..., 3] = trust
            else:  # built at 2 x 2 directly, each frame-sized temporary freed when done (1080p peak memory)
                edges = _sharp_edges(depth)
                del depth
                color = upsample_rgbt(self.raw, np.broadcast_to(np.uint8(trust), self.raw.shape[:2]), edges)
            got = (color, rims)
            for x in got:
                if x is not None:
                    x.setflags(write=False)
            self._trust[key] = got
        return got

    def rim_matte(self, mesh_options: dict):
        """:func:`~ibr.render.matting.rim_matte` of the source, from the depth of its mesh for
        ``mesh_options`` (built if need be; cached like :meth:`trust`)."""
        mesh_key = _mesh_key(mesh_options)
        m = self._trust.get(("matte", mesh_key))
        if m is None:
            view = self._view()
            source_mesh(view, **mesh_options)  # (cached) the matte reads its mesh's depth
            m = self._trust[("matte", mesh_key)] = rim_matte(self.raw, self._source_depth(mesh_key), view.camera,
                                                             silhouettes=self.silhouettes(mesh_key))
        return m

    def _source_depth(self, mesh_key):
        """The depth of the mesh for ``mesh_key`` (planes: quantized depth codes are no steps) or,
        for ``None`` (forward splat), the raw depth."""
        return self._depth if mesh_key is None else self.meshes[mesh_key].depth()

    def _quantization(self, mesh_key):
        """The depth quantization the mesh for ``mesh_key`` was built with (None: exact depth,
        or the forward splat's raw depth)."""
        return None if mesh_key is None else self.meshes[mesh_key].info.get("quantization")

    @property
    def color(self) -> np.ndarray:
        """(H, W, C) float32 in the source's value scale."""
        if self._color is None:
            self._color = as_float_color(self.raw)
            self._color.setflags(write=False)
        return self._color

    def sharp_color(self, mesh_key) -> np.ndarray:
        """:attr:`color` upsampled 2 x 2 co-sited for sharp sampling, no tap across the depth
        edges of the mesh for ``mesh_key`` (made once per key)."""
        key = ("sharp", mesh_key)
        c = self._trust.get(key)
        if c is None:
            c = self._trust[key] = upsample_cosited(self.color, _sharp_edges(self._source_depth(mesh_key)))
            c.setflags(write=False)
        return c


_sources: "weakref.WeakKeyDictionary[View, _Source]" = weakref.WeakKeyDictionary()


def _sharp_edges(depth) -> np.ndarray:
    """The pixels of a source no Lanczos tap of sharp sampling reaches across: both sides of
    every step of more than 2 % in 1/z, and the edge of valid depth
    (:func:`~ibr.base.depth.depth_steps`)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return depth_steps(1.0 / np.asarray(depth, np.float32), 0.02)


def _source(view: View) -> _Source:
    src = _sources.get(view)
    if src is None:
        src = _sources[view] = _Source(view)
    return src


def source_mesh(view: View, **mesh_options):
    """The quad mesh of a source view, built once per view object and option set, then reused.

    ``mesh_options`` go to :func:`ibr.build_mesh` (e.g. ``threshold=``, ``max_error_px=``). The
    cache holds the mesh for as long as the view object lives (keyed on the object, not its
    content: mutating a view's arrays in place is not detected).
    """
    _check_source(view, "view")
    src = _source(view)
    key = _mesh_key(mesh_options)
    mesh = src.meshes.get(key)
    if mesh is None:
        partner = mesh_options.get(_PARTNER)
        if partner is not None:  # the mesh without a partner, its large quads fitted to the partner's colour
            own = {k: v for k, v in mesh_options.items() if k != _PARTNER}
            other = partner()
            if other is None:  # the partner is gone: nothing to fit to (and nothing cached under its key)
                return source_mesh(view, **own)
            from .plane_refine import refine_planes

            src.drop_dead_partners()
            mesh = refine_planes(source_mesh(view, **own), view, other)
        else:
            from ..mesh import build_mesh

            mesh = build_mesh(view, **mesh_options)
        src.meshes[key] = mesh
    return mesh


#: The mesh option (internal: added by :func:`iter_interpolate` and :func:`interpolation_meshes`;
#: not a keyword a caller would type) holding a weak reference to the other source of a pair:
#: the source's depth is coarsely quantized, and its mesh's large quads are fitted to the other's
#: colour (:mod:`ibr.render.plane_refine`).
_PARTNER = "partner view (internal)"


def _with_mixed_radius(view: View, k: int) -> View:
    """``view``, a source upsampled k x k, with its mixed pixels to be widened by k - 1
    subsamples (:attr:`_Source.mixed_radius`)."""
    _source(view).mixed_radius = k - 1
    return view


def _widened(mask: np.ndarray, radius: int) -> np.ndarray:
    """``mask`` dilated by a (2 radius + 1)^2 square (itself for 0)."""
    if not radius:
        return mask
    import cv2

    return cv2.dilate(mask.view(np.uint8), np.ones((2 * radius + 1,) * 2, np.uint8)).view(bool)


def _holds_dead_ref(key) -> bool:
    """Whether a cache key (nested tuples) holds a weak reference whose view no longer exists."""
    if isinstance(key, weakref.ReferenceType):
        return key() is None
    return isinstance(key, tuple) and any(_holds_dead_ref(k) for k in key)


def _quantization_in(mesh_options: dict, view: View):
    """The quantization of ``view``'s depth: the one ``mesh_options`` give, else the one
    recorded on the view (:func:`~ibr.base.depth.quantization_of`), or None."""
    quant = mesh_options.get("quantization")
    return quant if quant is not None else quantization_of(view)


def _with_partners(views, opts) -> list[dict]:
    """Each source's mesh options, plus :data:`_PARTNER` (the other source) where its depth's
    quantization is coarse over the pair's baseline (:func:`~ibr.render.plane_refine.is_coarse`,
    at the source's median depth)."""
    from .plane_refine import is_coarse

    out = []
    for view, o, other in zip(views, opts, views[::-1]):
        quant = _quantization_in(o, view)
        baseline = float(np.linalg.norm(view.camera.position - other.camera.position))
        coarse = is_coarse(quant, _median_depth_of(view), baseline, view.camera.fx)
        out.append({**o, _PARTNER: weakref.ref(other)} if coarse else o)
    return out


#: Levels of detail from the camera move are cached on a grid of baselines 2^(k/2) (scene
#: units): a call reuses the mesh of the next larger level, at most sqrt(2) finer than needed.
_LOD_STEPS_PER_OCTAVE = 2
#: The move-derived baseline never drops below this share of the source's median depth (issue
#: 4's fixed default). A smaller move would allow coarser planes for the image, but the output
#: depth would then drift by more than the 2 % under which the blend sees one surface (room,
#: t = 0.5 at the move's 0.12: 99th-percentile depth error 2.1 %, -0.14 dB), and a pure
#: rotation has no parallax at all.
_MIN_BASELINE_FRACTION = 0.05


def _mesh_key(mesh_options: dict) -> tuple:
    return tuple(sorted(mesh_options.items()))


def lod_baseline(view: View, cameras) -> float:
    """The baseline (scene units) for the error bound of ``view``'s mesh when it is rendered
    into ``cameras``: the largest distance from the source camera centre to a target centre
    (for an interpolation, the span of the frames on the source's side), rounded up to the
    level grid (``2^(k/2)``) so that nearby calls share one cached mesh, and at least 5 % of
    the median depth (issue 4's default; see :data:`_MIN_BASELINE_FRACTION`). Parallax is ``f * b / z`` pixels for a move ``b``, so a mesh whose planes
    are within ``max_error_px / (f b)`` in 1/z is within ``max_error_px`` in every target."""
    c = view.camera.position
    b = max(float(np.linalg.norm(cam.position - c)) for cam in cameras)
    floor = _MIN_BASELINE_FRACTION * _median_depth_of(view)
    if not b > floor:
        return floor
    k = np.ceil(_LOD_STEPS_PER_OCTAVE * np.log2(b))
    return float(2.0 ** (k / _LOD_STEPS_PER_OCTAVE))


def _lod_options(view: View, cameras, mesh_options: dict, lod: str) -> dict:
    """``mesh_options`` plus the move-derived baseline, unless the caller fixed the level of
    detail (``threshold`` or ``baseline``) or asked for the old default (``lod="depth"``), and
    the quantization recorded on the view unless the options give one (so that it is part of
    the meshes' cache key: a quantization set on the view later builds new meshes)."""
    recorded = quantization_of(view)
    if mesh_options.get("quantization") is None and recorded is not None:
        mesh_options = {**mesh_options, "quantization": recorded}
    if lod == "depth" or "threshold" in mesh_options or "baseline" in mesh_options:
        return mesh_options
    b = lod_baseline(view, cameras)
    if b == _MIN_BASELINE_FRACTION * _median_depth_of(view):  # the default mesh (same cache key)
        return mesh_options
    return {**mesh_options, "baseline": b}


def _median_depth_of(view: View) -> float:
    """The median depth of a source (the default baseline's reference), computed once per view."""
    src = _source(view)
    if src.median_depth is None:
        from ..mesh.segment import _median_depth

        src.median_depth = _median_depth(view.depth)
    return src.median_depth


def _check_source(view, name: str, method: str = "mesh") -> None:
    if not isinstance(view, View):
        raise TypeError(f"{name}: expected an ibr View, got {type(view).__name__}")
    if view.depth is None:
        raise ValueError(
            f"{name}: view {view.name!r} has no depth, so it cannot be a source "
            "(a view without depth can only give a target camera)"
        )
    if method != "mesh":  # beside another source the forward splat draws nothing from it (holes)
        return
    src = _source(view)
    if src.any_valid is None:  # once per view
        src.any_valid = bool(np.isfinite(view.depth).any())
    if not src.any_valid:
        raise ValueError(no_valid_depth_message(f"{name}: view {view.name!r}", ", so it cannot be a source"))


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
    :attr:`Composite.replace` marks the covered pixels the fill should recolour: background-rim
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
    bilinear kernels mark as :attr:`Composite.replace` (``_nearest``, ``_beside_gap`` and
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


def check_antialias(antialias, method: str) -> bool:
    """``antialias`` as a bool; True only with the mesh method (the subsamples trace its quads)."""
    antialias = check_flag("antialias", antialias)
    if antialias and method != "mesh":
        raise ValueError(f"antialias: the edge subsamples trace the quad mesh, so it needs method='mesh' (--method "
                         f"mesh on the command line), got method={method!r}")
    return antialias


def _check_target(camera, name="camera") -> Camera:
    if isinstance(camera, View):
        return camera.camera
    if not isinstance(camera, Camera):
        raise TypeError(f"{name}: expected a Camera (or a View whose camera to use), got {type(camera).__name__}")
    return camera


def _at_resolution(r: Rendering, camera: Camera, k: int) -> Rendering:
    """``r``, rendered into ``camera`` supersampled k times (:mod:`ibr.render.supersample`),
    brought back to ``camera``: box-filtered colour wherever every subsample has one."""
    if k == 1:
        return r
    color, depth, holes, filled = downsample_rendering(r.color, r.depth, r.holes, r.filled, k)
    return Rendering(color, depth, holes, filled, camera, r.t)


def _at_supersampling(interpolation: str, k: int) -> str:
    """The colour reconstruction a k x k supersampled render uses: its sources are already
    upsampled k x k (bicubic colour, :mod:`ibr.render.upsample`), so "sharp" samples them
    bilinearly instead of upsampling them once more (4 k^2 the source's memory)."""
    return "linear" if k > 1 and interpolation == "sharp" else interpolation


def _nothing_seen(camera: Camera, names, t) -> ValueError:
    where = f"target camera at t={t:g}" if t is not None else "target camera"
    return ValueError(
        f"{where} sees nothing of source view(s) {', '.join(map(repr, names))}: no surface of theirs "
        f"covers a pixel centre of it ({camera!r}); is it looking away, placed behind them, or so wide "
        f"(a field of view near 180 degrees) that they fall between its pixel centres?"
    )


# ------------------------------------------------------------------------- public calls
def warp(
    view: View,
    camera: Camera,
    *,
    method: str = "mesh",
    fill: str = "inpaint",
    footprint: str = "free",
    interpolation: str = "sharp",
    splat: str = "inverse",
    mesh_options: dict | None = None,
    lod: str = "move",
    supersample: int = 1,
    antialias: bool = False,
) -> Rendering:
    """Render one RGB-D view from another camera.

    Parameters
    ----------
    view : View
        Source with depth (``view.depth`` not None).
    camera : Camera or View
        Target camera (any size and intrinsics); a View stands for its camera, so a view without
        depth (e.g. the Middlebury right image) is a valid target.
    method : {"mesh", "forward"}
        Quad-mesh inverse warp (default, exact on planes) or per-pixel forward splat (preview).
    fill : {"inpaint", "background", "none", "previous"}
        Hole filling: streak-free background pull-push (default,
        :func:`ibr.render.fill.fill_pullpush`), the directional background fill of rows and
        columns (``"background"``), or none. ``"previous"`` has no previous frame here and
        behaves like ``"inpaint"``.
    footprint : {"free", "surface", "quad"}
        Sample-footprint clamping of the mesh renderer (:func:`ibr.render.rasterize_mesh`).
    interpolation : {"sharp", "linear", "cubic"}
        Color reconstruction: bilinear taps on the source upsampled 2 x 2 once by Lanczos-3,
        co-sited (default; :mod:`ibr.render.sharp_sampling`: about bicubic's sharpness at 1.1x
        the bilinear frame, 4x the source's colour memory), plain bilinear (softer where
        pixels fall between source pixels), or bicubic (float layers, about 3x the frame).
        With ``supersample`` > 1 the upsampled source is sampled bilinearly for "sharp".
    splat : {"inverse", "nearest"}
        Splat mode of ``method="forward"`` (:func:`ibr.render.forward.forward_warp`).
    mesh_options : dict, optional
        Options of :func:`ibr.build_mesh` (level of detail, ``quantization``); the mesh is
        cached per view and option set.
    lod : {"move", "depth"}
        Where the error bound's baseline comes from when ``mesh_options`` fixes neither
        ``baseline`` nor ``threshold``: the actual move from the source to ``camera``
        (default, :func:`lod_baseline`), or 5 % of the median depth (issue 4's default).
    supersample : {1, 3, 5}
        Upsample the source k x k with its silhouettes placed inside the mixed pixels and its
        colour back-projected (:mod:`ibr.render.upsample`), render k x k subsamples per pixel
        and box-filter them (:mod:`ibr.render.supersample`): anti-aliased, sub-pixel
        silhouettes, about k^2 the time (and a mesh of k^2 the pixels, once per source). 1: off
        (default).
    antialias : bool
        Anti-aliased silhouettes: each covered pixel at a depth edge is the mean of its centre
        (twice) and four diagonal subsamples (:mod:`ibr.render.edge_antialias`): about 1.5x the
        frame and a first run ~1 s longer (its kernels compile), so an option, the cheap middle
        between the default and ``supersample=3``. Not with ``supersample`` > 1, which
        subsamples every pixel. False: off (default).

    Returns
    -------
    Rendering
        ``color`` (source dtype), ``depth``, ``holes`` (not covered by the source), ``filled``.

    Raises
    ------
    ValueError
        Source without depth; a camera that sees nothing of the source; bad option values.
    """
    check_choice("method", method, METHODS)
    check_choice("fill", fill, FILLS)
    check_choice("footprint", footprint, FOOTPRINTS)
    check_choice("interpolation", interpolation, INTERPOLATIONS)
    check_choice("lod", lod, LODS)
    from .forward import SPLATS

    check_choice("splat", splat, SPLATS)  # checked for the mesh method too, where it is unused
    k = check_supersample(supersample)
    antialias = check_antialias(antialias, method)
    interpolation = _at_supersampling(interpolation, k)
    _check_source(view, "view")  # one source: without any valid depth nothing can be drawn, either method
    camera = _check_target(camera)
    mesh_options = check_mesh_options(mesh_options)
    view = _source(view).upsampled(k) if k > 1 else view
    opts = _lod_options(view, [camera], mesh_options, lod) if method == "mesh" else {}
    cam_k = supersampled_camera(camera, k)
    comp, edges = _render([view], cam_k, [1.0], method=method, footprint=footprint, splat=splat,
                          mesh_options=[opts], interpolation=interpolation, composite_mode="blend",
                          depth_tol=0.02, dtype=view.color.dtype, antialias=antialias and k == 1)
    if comp is None:
        raise _nothing_seen(camera, [view.name], None)
    r = _finish(comp, cam_k, None, fill, None, view.color.ndim == 2, parallax_axis(camera, [view.camera]))
    return _at_resolution(_antialias(r, edges), camera, k)


def _targets(view_a: View, view_b: View, t) -> tuple[list[Camera], list[float | None], bool]:
    """Target cameras, their t values and whether a single result was asked for."""
    single = isinstance(t, (Camera, View)) or np.ndim(t) == 0
    items = [t] if single else list(t)
    if not items:
        raise ValueError("t: expected a number, a camera or a non-empty list of them, got an empty list")
    cams, ts = [], []
    for i, item in enumerate(items):
        name = "t" if single else f"t[{i}]"
        if isinstance(item, (Camera, View)):
            cams.append(_check_target(item, name))
            ts.append(None)
        else:
            tv = check_finite_scalar(name, item)
            cams.append(interpolate_cameras(view_a.camera, view_b.camera, tv))
            ts.append(tv)
    return cams, ts, single


def iter_interpolate(
    view_a: View,
    view_b: View,
    t,
    *,
    method: str = "mesh",
    composite_mode: str = "blend",
    fill: str = "previous",
    depth_tol: float = 0.02,
    footprint: str = "free",
    interpolation: str = "sharp",
    splat: str = "inverse",
    mesh_options: dict | None = None,
    lod: str = "move",
    silhouettes: bool = True,
    supersample: int = 1,
    antialias: bool = False,
) -> Iterator[Rendering]:
    """Generator form of :func:`interpolate`: yields one :class:`Rendering` per target, in order
    (the previous-frame fill uses the frame yielded before). Every argument is checked when it is
    called, before the first frame is asked for."""
    check_choice("method", method, METHODS)
    check_choice("composite_mode", composite_mode, COMPOSITE_MODES)
    check_choice("fill", fill, FILLS)
    check_choice("footprint", footprint, FOOTPRINTS)
    check_choice("interpolation", interpolation, INTERPOLATIONS)
    check_choice("lod", lod, LODS)
    from .forward import SPLATS

    check_choice("splat", splat, SPLATS)
    check_flag("silhouettes", silhouettes)
    antialias = check_antialias(antialias, method)
    depth_tol = check_positive("depth_tol", depth_tol)
    k = check_supersample(supersample)
    interpolation = _at_supersampling(interpolation, k)
    _check_pair(view_a, view_b, method)
    cams, ts, _ = _targets(view_a, view_b, t)
    base = check_mesh_options(mesh_options)
    if k > 1:  # the sources at k x k their resolution, sub-pixel silhouettes (ibr.render.upsample)
        view_a, view_b = _upsampled_pair(view_a, view_b, base, lod, method, k)
        opts = [_lod_options(v, cams, base, lod) for v in (view_a, view_b)] if method == "mesh" else [{}, {}]
    else:
        opts = _pair_mesh_options(view_a, view_b, cams, base, lod) if method == "mesh" else [{}, {}]
    return _frames(view_a, view_b, cams, ts, k, opts, method=method, footprint=footprint, splat=splat,
                   interpolation=interpolation, composite_mode=composite_mode, depth_tol=depth_tol,
                   silhouettes=silhouettes, fill=fill, antialias=antialias)


def _check_pair(view_a, view_b, method: str = "mesh") -> None:
    """The two sources of an interpolation: views with depth of one size, colour dtype and layout."""
    _check_source(view_a, "view_a", method)
    _check_source(view_b, "view_b", method)
    if view_a.shape != view_b.shape:
        raise ValueError(
            f"view_b: size {view_b.camera.width}x{view_b.camera.height} differs from view_a's "
            f"{view_a.camera.width}x{view_a.camera.height}; both sources must have the same size"
        )
    if view_a.color.dtype != view_b.color.dtype or view_a.color.shape != view_b.color.shape:
        raise ValueError(
            f"view_b: color {view_b.color.dtype} {view_b.color.shape} differs from view_a's "
            f"{view_a.color.dtype} {view_a.color.shape}; convert both to one dtype and layout"
        )


def _pair_mesh_options(view_a, view_b, cams, mesh_options: dict, lod: str) -> list[dict]:
    """Each source's mesh options for rendering ``cams``: the level of detail from the span of
    the whole call (one mesh per source for every frame) and the other source where the depth's
    codes are coarse (:func:`_with_partners`)."""
    opts = [_lod_options(v, cams, mesh_options, lod) for v in (view_a, view_b)]
    return _with_partners([view_a, view_b], opts)


def _upsampled_pair(view_a, view_b, mesh_options: dict, lod: str, method: str, k: int) -> tuple:
    """The two sources at k x k their resolution, their colours refined by each other
    (:meth:`_Source.upsampled_with`). A source in coarse codes (:func:`_with_partners`) is
    upsampled from the depth of its mesh refined against the other source
    (:mod:`ibr.render.plane_refine`), moved into its codes' bins and its partner's, rather than
    from its codes (8-bit disparity, ``supersample=3``, against the exact depth's: clutter -1.94
    -> -0.72 dB, room -1.91 -> -0.14; docs/edges.md section 3); its upsampled meshes still allow
    for the codes' quantization."""
    keys = (None, None)
    if method == "mesh":
        # the fitted meshes of the whole pair's span (one upsampled view per source and partner, whatever the frames)
        opts = _pair_mesh_options(view_a, view_b, [view_a.camera, view_b.camera], mesh_options, lod)
        keys = tuple(_mesh_key(o) if _PARTNER in o else None for o in opts)
    return (_source(view_a).upsampled_with(view_b, k, keys[0], keys[1]),
            _source(view_b).upsampled_with(view_a, k, keys[1], keys[0]))


def _with_mesh_depth(view: View, mesh, partner: View | None = None, partner_quantization=None) -> View:
    """``view`` with the depth of ``mesh``'s planes where its stored depth is valid (the stored
    depth kept where a plane gives none), moved into the bins of its codes where the mesh has a
    quantization (:func:`~ibr.mesh.code_bins.depth_in_code_bins`), and of ``partner``'s codes
    where ``partner_quantization`` is given (:func:`~ibr.mesh.code_bins.partner_code_bins`)."""
    from ..mesh.code_bins import depth_in_code_bins, partner_code_bins
    from ..mesh.quad_mesh import mesh_depth

    with np.errstate(invalid="ignore"):
        planes = mesh_depth(mesh)
        quant = mesh.info.get("quantization")
        if quant is not None:
            bounds = None
            if partner is not None and partner_quantization is not None:
                bounds = partner_code_bins(view.camera, planes, partner, partner_quantization)
            planes = depth_in_code_bins(planes, view.depth, quant, also_within=bounds)
        valid = np.isfinite(view.depth) & (view.depth > 0)
        depth = np.where(valid & np.isfinite(planes) & (planes > 0), planes, view.depth).astype(np.float32)
    return View(view.color, depth, view.camera, view.name)


def coarse_sources(view_a: View, view_b: View, *, mesh_options: dict | None = None) -> tuple[bool, bool]:
    """Whether each source's depth is stored in codes coarse over the pair's baseline (one code
    moves a point at the source's median depth by :data:`ibr.render.plane_refine.COARSE_PX` or
    more: the quantization of ``mesh_options`` or the one :func:`ibr.io.load_view` recorded);
    :func:`interpolate` fits such a source's planes to the other's colour and the codes' bins
    (:mod:`ibr.render.plane_refine`). ``view_a``, ``view_b`` and ``mesh_options`` as in
    :func:`interpolate`."""
    _check_pair(view_a, view_b)
    opts = check_mesh_options(mesh_options)
    return tuple(_PARTNER in o for o in _with_partners([view_a, view_b], [opts, opts]))


def interpolation_meshes(view_a: View, view_b: View, t, *, mesh_options: dict | None = None,
                         lod: str = "move") -> tuple:
    """The quad meshes of both sources that :func:`interpolate` renders ``t`` with (method
    ``"mesh"``, no supersampling), built now and cached for it, so that a caller can time them
    apart from the frames.

    Parameters
    ----------
    view_a, view_b, t, mesh_options, lod
        As in :func:`interpolate`.

    Returns
    -------
    (QuadMesh, QuadMesh)
        Where a source's depth is coarsely quantized (:mod:`ibr.render.plane_refine`), its mesh
        has its large quads fitted to the other source's colour and the others placed inside the
        bins of their codes, split where one plane does not follow them (:mod:`ibr.mesh.code_bins`);
        ``mesh.info["refined_quads"]``, ``mesh.info["bin_fitted_quads"]`` and
        ``mesh.info["bin_split_quads"]`` count the quads of the segmentation so treated.
    """
    check_choice("lod", lod, LODS)
    _check_pair(view_a, view_b)
    cams, _, _ = _targets(view_a, view_b, t)
    opts = _pair_mesh_options(view_a, view_b, cams, check_mesh_options(mesh_options), lod)
    return tuple(source_mesh(v, **o) for v, o in zip((view_a, view_b), opts))


def _frames(view_a, view_b, cams, ts, k, opts, *, method, footprint, splat, interpolation, composite_mode,
            depth_tol, silhouettes, fill, antialias) -> Iterator[Rendering]:
    """The frames of :func:`iter_interpolate` (its arguments checked)."""
    previous = None  # the previous frame as rendered (supersampled when k > 1), for fill="previous"
    for cam, tv in zip(cams, ts):
        w = viewpoint_weights(cam, [view_a.camera, view_b.camera])
        cam_k = supersampled_camera(cam, k)
        comp, edges = _render([view_a, view_b], cam_k, w, method=method, footprint=footprint, splat=splat,
                              mesh_options=opts, interpolation=interpolation, composite_mode=composite_mode,
                              depth_tol=depth_tol, dtype=view_a.color.dtype, silhouettes=silhouettes,
                              rematte=k == 1, antialias=antialias and k == 1)
        if comp is None:
            raise _nothing_seen(cam, [view_a.name, view_b.name], tv)
        previous = _antialias(_finish(comp, cam_k, tv, fill, previous, view_a.color.ndim == 2,
                                      parallax_axis(cam, [view_a.camera, view_b.camera])), edges)
        yield _at_resolution(previous, cam, k)


def interpolate(
    view_a: View,
    view_b: View,
    t: "float | Camera | Sequence[float | Camera]",
    *,
    method: str = "mesh",
    composite_mode: str = "blend",
    fill: str = "previous",
    depth_tol: float = 0.02,
    footprint: str = "free",
    interpolation: str = "sharp",
    splat: str = "inverse",
    mesh_options: dict | None = None,
    lod: str = "move",
    silhouettes: bool = True,
    supersample: int = 1,
    antialias: bool = False,
) -> "Rendering | list[Rendering]":
    """Views between two RGB-D sources (seed 002: inverse warping + two-source hole filling).

    Parameters
    ----------
    view_a, view_b : View
        Sources with depth, same size and color dtype.
    t : float, Camera, or a list of them
        Where to render: a float is a pose between the sources (``interpolate_cameras``: slerp
        of the rotation, lerp of position and intrinsics; 0 = ``view_a``, 1 = ``view_b``, values
        outside [0, 1] extrapolate); a Camera (or a View, for its camera) is used as given. A
        list renders a sequence.
    method : {"mesh", "forward"}
        Quad-mesh inverse warp (default) or per-pixel forward splat (preview).
    composite_mode : {"blend", "front"}
        Depth-aware blend of the two layers (default) or the seed's order (the source nearer to
        the new viewpoint in front, the other fills its holes).
    fill : {"previous", "inpaint", "background", "none"}
        Holes left after compositing: the previous output frame where it showed background
        there (default; seed step 7 with a depth test, :data:`ibr.render.fill.PREVIOUS_MIN_DEPTH`;
        elsewhere, and in the first frame, the background pull-push), the background pull-push
        for every frame (``"inpaint"``), issue 4's directional background fill, or nothing.
    depth_tol : float
        Relative depth tolerance under which both layers see the same surface.
    footprint, interpolation, splat, mesh_options, lod
        See :func:`warp`. Meshes are built once per source view and level of detail and reused
        for every frame (and by later calls with the same view objects); with ``lod="move"``
        the baseline is the largest distance from each source to the frames of the call.
    silhouettes : bool
        Give the mixed pixels on both sides of every depth discontinuity of a source low weight
        where both sources see the same surface (default), so the clean pixel of the other
        source wins (no ghost outlines), and re-mix a foreground rim that only one source sees
        with the background the target sees behind it (:mod:`ibr.render.matting`; not with
        ``supersample``; with ``antialias`` in its subsamples); ``False`` is issue 4's plain
        viewpoint blend.
    supersample : {1, 3, 5}
        As in :func:`warp`: sources upsampled with sub-pixel silhouettes, their colours refined
        by each other (:mod:`ibr.render.superres`, once per pair: about 1 s at 512 x 384), k x k
        subsamples per pixel box-filtered; about k^2 the frame time (the fill and the
        previous-frame fill run on the subsamples). 1: off (default).
    antialias : bool
        As in :func:`warp`: depth-edge pixels the mean of their centre and four subsamples
        (default False). The foreground rims of :mod:`ibr.render.matting` are then re-mixed in
        the subsamples (:func:`~ibr.render.matting.rematte_subsamples`) rather than in the frame's
        pixels (that lowered clutter's edge band, 29.90 -> 29.77 dB; in the subsamples 29.99).

    Returns
    -------
    Rendering or list of Rendering
        A single result for a scalar ``t`` or a single camera, else one per entry.

    Raises
    ------
    ValueError
        A source without depth, sources of different sizes or dtypes, a non-finite ``t``, a
        target camera that sees nothing of either source, bad option values.

    Examples
    --------
    >>> mid = ibr.interpolate(a, b, 0.5)                       # doctest: +SKIP
    >>> frames = ibr.interpolate(a, b, [0.25, 0.5, 0.75])       # doctest: +SKIP
    >>> mid.color.dtype == a.color.dtype, mid.holes.mean()      # doctest: +SKIP
    """
    frames = list(
        iter_interpolate(
            view_a, view_b, t, method=method, composite_mode=composite_mode, fill=fill, depth_tol=depth_tol,
            footprint=footprint, interpolation=interpolation, splat=splat, mesh_options=mesh_options, lod=lod,
            silhouettes=silhouettes, supersample=supersample, antialias=antialias,
        )
    )
    single = isinstance(t, (Camera, View)) or np.ndim(t) == 0
    return frames[0] if single else frames
