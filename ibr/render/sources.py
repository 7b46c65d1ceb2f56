"""The sources of view synthesis (:mod:`ibr.render.view_synthesis`): what is derived once per
source view and cached on it (the colour as the samplers read it, the silhouettes' trust, the
quad meshes per option set, the view upsampled for ``supersample``), and each source's mesh
options for a call (the level of detail from the camera move, :func:`lod_baseline`; the partner
view a coarsely quantized source's planes are fitted to). Caches are keyed on the view object
(weakly), so they live as long as it does."""

from __future__ import annotations

import weakref

import numpy as np

from ..base.depth import depth_steps, quantization_of, set_quantization
from .composite import mixed_pixels, pack_trust, rgbt_source, source_trust, trust_channel
from .matting import rim_matte
from .sharp_sampling import upsample_cosited, upsample_rgbt
from .rasterize import as_float_color
from ..base.view import View, no_valid_depth_message

__all__ = ["lod_baseline", "source_mesh"]

#: A pixel's eight neighbours (the centre left out): dilating with it gives, per pixel, whether
#: any neighbour is set.
_RING = np.array([[1, 1, 1], [1, 0, 1], [1, 1, 1]], np.uint8)


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
        colour (:func:`~ibr.render.upsample.upsample_view`; :func:`~ibr.render.view_synthesis.warp`),
        made once per factor; its meshes are cached on it like any view's."""
        v = self._upsampled.get(k)
        if v is None:
            v = self._upsampled[k] = _with_mixed_radius(self._upsample(k), k)
        return set_quantization(v, quantization_of(self._view()))  # as the view's is now (it may have been set since)

    def _upsample(self, k: int, refined_key=None, clean_start: bool = False, partner_key=None) -> View:
        """:func:`~ibr.render.upsample.upsample_view` of the source, or with ``refined_key`` (the
        options of a mesh of this source refined against its partner, :func:`_with_partners`) of
        the source with that mesh's depth instead of its stored codes
        (:func:`~ibr.render.view_synthesis._upsampled_pair`; ``partner_key``: the partner's, whose
        quantization its codes' bins take);
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
        reads: the colour with the trust as a fourth channel (:func:`~ibr.render.composite.rgbt_source`; 255 everywhere
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


#: The mesh option (internal: added by :func:`~ibr.render.view_synthesis.iter_interpolate` and
#: :func:`~ibr.render.view_synthesis.interpolation_meshes`; not a keyword a caller would type)
#: holding a weak reference to the other source of a pair: the source's depth is coarsely
#: quantized, and its mesh's large quads are fitted to the other's colour
#: (:mod:`ibr.render.plane_refine`).
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
