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

import weakref
from dataclasses import dataclass
from typing import Iterator, Sequence

import numpy as np

from ..base.validate import check_choice, check_finite_scalar, check_positive
from ..base.camera import Camera, interpolate_cameras
from .composite import COMPOSITE_MODES, composite, sample_composite, viewpoint_weights
from .fill import FILLS, _fill_background_inplace
from .rasterize import FOOTPRINTS, INTERPOLATIONS, Layer, _rasterize_into, as_float_color, sample_maps, scratch, scratch_maps
from ..base.view import View

__all__ = [
    "METHODS",
    "Rendering",
    "interpolate",
    "iter_interpolate",
    "source_mesh",
    "warp",
]

#: Rendering methods: quad-mesh inverse warp (default) or per-pixel forward splat.
METHODS = ("mesh", "forward")


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
        The subset of ``holes`` that the fill wrote (previous frame or background fill).
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


# ------------------------------------------------------------------------- source cache
class _Source:
    """Per-view cache: the color as the numba sampler reads it, a float32 copy for ``cv2.remap``
    (made on first use), and the meshes by option set."""

    def __init__(self, view: View):
        self.raw = np.ascontiguousarray(view.color if view.color.ndim == 3 else view.color[..., None])
        self._color = None
        self.meshes: dict = {}

    @property
    def color(self) -> np.ndarray:
        """(H, W, C) float32 in the source's value scale."""
        if self._color is None:
            self._color = as_float_color(self.raw)
            self._color.setflags(write=False)
        return self._color


_sources: "weakref.WeakKeyDictionary[View, _Source]" = weakref.WeakKeyDictionary()


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
    key = tuple(sorted(mesh_options.items()))
    mesh = src.meshes.get(key)
    if mesh is None:
        from ..mesh import build_mesh

        mesh = build_mesh(view, **mesh_options)
        src.meshes[key] = mesh
    return mesh


def _check_source(view, name: str) -> None:
    if not isinstance(view, View):
        raise TypeError(f"{name}: expected an ibr View, got {type(view).__name__}")
    if view.depth is None:
        raise ValueError(
            f"{name}: view {view.name!r} has no depth, so it cannot be a source "
            "(a view without depth can only give a target camera)"
        )


def _maps(view: View, camera: Camera, method: str, footprint: str, splat: str, mesh_options: dict, slot: str):
    """Where each target pixel samples ``view`` (per-thread scratch buffers of ``slot``, valid
    until the next call with the same slot; internal use only)."""
    if method == "mesh":
        return _rasterize_into(source_mesh(view, **mesh_options), camera, footprint, 0.01,
                               scratch_maps(slot, camera.shape))
    from .forward import forward_maps

    return forward_maps(view.depth, view.camera, camera, splat=splat)


def _render(views, camera, weights, *, method, footprint, splat, mesh_options, interpolation, composite_mode,
            depth_tol, dtype):
    """Render one or two sources into ``camera`` and composite them (output arrays are fresh)."""
    maps = [_maps(v, camera, method, footprint, splat, mesh_options, slot) for v, slot in zip(views, "ab")]
    if not any(m.coverage.any() for m in maps):
        return None
    if interpolation == "linear":  # fused numba pass (no layer images, no OpenCV thread pool)
        raw = [_source(v).raw for v in views]
        return sample_composite(raw, maps, weights, mode=composite_mode, depth_tol=depth_tol, dtype=dtype)
    colors = [_source(v).color for v in views]
    layers = []
    for m, c, slot in zip(maps, colors, "ab"):
        buf = scratch((slot, "color"), (*camera.shape, c.shape[2]), np.float32)
        layers.append(Layer(sample_maps(c, m.map_u, m.map_v, interpolation=interpolation, out=buf), m.depth,
                            m.coverage))
    return composite(layers, weights, mode=composite_mode, depth_tol=depth_tol, dtype=dtype)


def _finish(comp, camera, t, fill, previous, out_2d) -> Rendering:
    holes = ~comp.coverage
    color, depth = comp.color, comp.depth
    filled = np.zeros_like(holes)
    if holes.any():
        if fill == "previous" and previous is not None:  # seed step 7; only hole pixels change
            color[holes] = previous.color.reshape(color.shape)[holes]
            depth[holes] = previous.depth[holes]
            filled = holes.copy()
        elif fill in ("previous", "inpaint"):
            filled = _fill_background_inplace(color, depth, holes)
    if out_2d:
        color = color[..., 0]
    return Rendering(color, depth, holes, filled, camera, t)


def _check_target(camera, name="camera") -> Camera:
    if isinstance(camera, View):
        return camera.camera
    if not isinstance(camera, Camera):
        raise TypeError(f"{name}: expected a Camera (or a View whose camera to use), got {type(camera).__name__}")
    return camera


def _nothing_seen(camera: Camera, names, t) -> ValueError:
    where = f"target camera at t={t:g}" if t is not None else "target camera"
    return ValueError(
        f"{where} sees nothing of source view(s) {', '.join(map(repr, names))}: no surface of theirs "
        f"projects in front of it ({camera!r}); is it looking away or placed behind them?"
    )


# ------------------------------------------------------------------------- public calls
def warp(
    view: View,
    camera: Camera,
    *,
    method: str = "mesh",
    fill: str = "inpaint",
    footprint: str = "free",
    interpolation: str = "linear",
    splat: str = "inverse",
    mesh_options: dict | None = None,
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
    fill : {"inpaint", "none", "previous"}
        Hole filling: depth-aware background fill (default) or none. ``"previous"`` has no
        previous frame here and behaves like ``"inpaint"``.
    footprint : {"free", "surface", "quad"}
        Sample-footprint clamping of the mesh renderer (:func:`ibr.render.rasterize_mesh`).
    interpolation : {"linear", "cubic"}
        Color reconstruction filter (bicubic: sharper, about 5x the sampling time).
    splat : {"inverse", "nearest"}
        Splat mode of ``method="forward"`` (:func:`ibr.render.forward.forward_warp`).
    mesh_options : dict, optional
        Options of :func:`ibr.build_mesh` (level of detail); the mesh is cached per view.

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
    _check_source(view, "view")
    camera = _check_target(camera)
    comp = _render([view], camera, [1.0], method=method, footprint=footprint, splat=splat,
                   mesh_options=dict(mesh_options or {}), interpolation=interpolation, composite_mode="blend",
                   depth_tol=0.02, dtype=view.color.dtype)
    if comp is None:
        raise _nothing_seen(camera, [view.name], None)
    return _finish(comp, camera, None, fill, None, view.color.ndim == 2)


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
    interpolation: str = "linear",
    splat: str = "inverse",
    mesh_options: dict | None = None,
) -> Iterator[Rendering]:
    """Generator form of :func:`interpolate`: yields one :class:`Rendering` per target, in order
    (the previous-frame fill uses the frame yielded before)."""
    check_choice("method", method, METHODS)
    check_choice("composite_mode", composite_mode, COMPOSITE_MODES)
    check_choice("fill", fill, FILLS)
    check_choice("footprint", footprint, FOOTPRINTS)
    check_choice("interpolation", interpolation, INTERPOLATIONS)
    depth_tol = check_positive("depth_tol", depth_tol)
    _check_source(view_a, "view_a")
    _check_source(view_b, "view_b")
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
    cams, ts, _ = _targets(view_a, view_b, t)
    opts = dict(mesh_options or {})
    previous = None
    for cam, tv in zip(cams, ts):
        w = viewpoint_weights(cam, [view_a.camera, view_b.camera])
        comp = _render([view_a, view_b], cam, w, method=method, footprint=footprint, splat=splat, mesh_options=opts,
                       interpolation=interpolation, composite_mode=composite_mode, depth_tol=depth_tol,
                       dtype=view_a.color.dtype)
        if comp is None:
            raise _nothing_seen(cam, [view_a.name, view_b.name], tv)
        previous = _finish(comp, cam, tv, fill, previous, view_a.color.ndim == 2)
        yield previous


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
    interpolation: str = "linear",
    splat: str = "inverse",
    mesh_options: dict | None = None,
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
    fill : {"previous", "inpaint", "none"}
        Holes left after compositing: the previous output frame (default; seed step 7; the first
        frame, having none, gets the background fill), the depth-aware background fill for
        every frame, or nothing.
    depth_tol : float
        Relative depth tolerance under which both layers see the same surface.
    footprint, interpolation, splat, mesh_options
        See :func:`warp`. Meshes are built once per source view and reused for every frame
        (and by later calls with the same view objects).

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
            footprint=footprint, interpolation=interpolation, splat=splat, mesh_options=mesh_options,
        )
    )
    single = isinstance(t, (Camera, View)) or np.ndim(t) == 0
    return frames[0] if single else frames
