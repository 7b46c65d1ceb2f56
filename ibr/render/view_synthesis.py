"""New views from RGB-D sources: ``ibr.warp`` (one source) and ``ibr.interpolate`` (two sources).

The pipeline of seed 002 (DESIGN.md section 2, steps 4-7): each source view gets an adaptive quad
mesh (built once and cached on the view object), the mesh is inverse-warped into the target camera
(:func:`ibr.render.render_mesh`: exact per-quad homography, z-buffer), two sources are composited
(:func:`ibr.render.composite.composite`: depth-aware blend by default, the seed's front/back order on
request) and the remaining holes are filled (previous frame in a sequence, depth-aware background
fill for a single frame). ``method="forward"`` replaces the mesh by the per-pixel splat of seed 003
(:func:`ibr.render.forward.forward_warp`) as a fast preview.

This module holds the public calls; what each source view gives (its meshes, trust, upsampled
view; the level of detail) is cached by :mod:`ibr.render.sources`, one frame is made from the
sources' maps by :mod:`ibr.render.frame_composite`, and the result is a
:class:`~ibr.render.rendering.Rendering` (re-exported here with :func:`lod_baseline` and
:func:`source_mesh`). The helpers are imported by name: patch them where they are used.

Conventions: pixel (u, v) = (column, row) with centers at integer coordinates (the image spans
[-0.5, W-0.5] x [-0.5, H-0.5]); depth is planar z in scene units, float32, NaN where unknown;
output colors keep the sources' dtype (uint8 in, uint8 out, rounded to nearest).
"""

from __future__ import annotations

from typing import Iterator, Sequence

import numpy as np

from ..base.validate import check_choice, check_finite_scalar, check_flag, check_mesh_options, check_positive
from ..base.camera import Camera, interpolate_cameras
from .composite import COMPOSITE_MODES, viewpoint_weights
from .fill import FILLS, parallax_axis
from .frame_composite import _antialias, _finish, _render
from .supersample import check_supersample, downsample_rendering, supersampled_camera
from .rasterize import FOOTPRINTS
from .rendering import Rendering
from .sources import (_PARTNER, _check_source, _lod_options, _mesh_key, _source, _with_partners, lod_baseline,
                      source_mesh)
from ..base.view import View

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
        (default, :func:`~ibr.render.sources.lod_baseline`), or 5 % of the median depth (issue 4's default).
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
    """Generator form of :func:`interpolate`: yields one :class:`~ibr.render.rendering.Rendering` per target, in order
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
    codes are coarse (:func:`~ibr.render.sources._with_partners`)."""
    opts = [_lod_options(v, cams, mesh_options, lod) for v in (view_a, view_b)]
    return _with_partners([view_a, view_b], opts)


def _upsampled_pair(view_a, view_b, mesh_options: dict, lod: str, method: str, k: int) -> tuple:
    """The two sources at k x k their resolution, their colours refined by each other
    (:meth:`~ibr.render.sources._Source.upsampled_with`). A source in coarse codes
    (:func:`~ibr.render.sources._with_partners`) is upsampled from the depth of its mesh refined
    against the other source (:mod:`ibr.render.plane_refine`), moved into its codes' bins and its
    partner's, rather than from its codes (8-bit disparity, ``supersample=3``, against the exact depth's: clutter -1.94
    -> -0.72 dB, room -1.91 -> -0.14; docs/edges.md section 3); its upsampled meshes still allow
    for the codes' quantization."""
    keys = (None, None)
    if method == "mesh":
        # the fitted meshes of the whole pair's span (one upsampled view per source and partner, whatever the frames)
        opts = _pair_mesh_options(view_a, view_b, [view_a.camera, view_b.camera], mesh_options, lod)
        keys = tuple(_mesh_key(o) if _PARTNER in o else None for o in opts)
    return (_source(view_a).upsampled_with(view_b, k, keys[0], keys[1]),
            _source(view_b).upsampled_with(view_a, k, keys[1], keys[0]))


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
