"""Stereo pairs from one RGB-D frame (seed 003) and their output formats.

Seed 003 (patent CN101477702) intercepts an application's color buffer, z-buffer and 4x4 OpenGL
projection matrix, recovers near/far/frustum from the matrix, lifts every pixel to eye space and
synthesizes a left and a right view, either by rendering the lifted surface (method 1, here the
quad-mesh renderer :func:`ibr.render.render_mesh`) or by mapping each pixel directly (method 2):

    u' = fx (X - Dx) / (Z - Dz) + cx + Dpixel,    v' = fy Y / (Z - Dz) + cy

with a horizontal eye offset Dx, a depth offset Dz and a pixel shift Dpixel (the right eye uses
the negated values). For a parallel-axis pair Dz = 0, so v' = v: rows are preserved and the
vertical parallax is exactly zero; Dpixel = +/- fx e / (2 f) is the asymmetric-frustum shift of
seed 000 that puts the zero-parallax plane at distance f.

Method 2 here maps rows with linear interpolation between connected neighbours (inverse depth and
color; see :mod:`ibr.stereo._pair_kernels`), which avoids the cracks of copying single pixels;
``method="splat"`` is the literal per-pixel copy (rounded to the nearest pixel, z-buffered) and
also supports Dz != 0. Disocclusions are filled per row from the background side (the deeper of
the two neighbours of a hole run), smoothed across rows so that no streaks show
(:func:`ibr.render.fill.fill_horizontal_parallax`), and reported as masks.

Conventions: camera frame x right, y down, z forward; pixel centers at integers (a centered
principal point of a 512-wide image is cx = 255.5); planar depth in scene units, NaN invalid.
The eye cameras are the source camera translated by +/- e/2 along its x axis (or by e when the
source is kept as one eye) with cx shifted by -/+ fx e / (2 f): e.g. fx = 443.4, e = 0.06,
f = 3.0 gives a left-eye cx of 255.5 - 4.434 = 251.066.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from functools import lru_cache

import cv2
import numpy as np

from . import _pair_kernels as _k
from ..render.bands import run_bands
from ..render.fill import _fill_horizontal_parallax_inplace
from ..base.validate import (check_array, check_choice, check_color, check_finite_scalar, check_image,
                             check_mesh_options, check_positive)
from ..base.camera import Camera, camera_from_gl_projection
from ..base.view import View, no_valid_depth_message as _no_valid_depth
from ..render.supersample import check_supersample, downsample_rendering, supersampled_camera

__all__ = [
    "PACK_MODES",
    "StereoPair",
    "anaglyph",
    "check_stereo_interpolation",
    "check_stereo_supersample",
    "dubois_anaglyph",
    "map_pixels",
    "pack_stereo",
    "stereo_cameras",
    "stereo_pair",
    "stereo_pair_from_zbuffer",
]

SOURCES = ("center", "left", "right")
METHODS = ("pixel", "mesh", "splat")
#: Colour reconstruction of method 2 (``"pixel"``): linear (the default) or sharp (half-way samples).
INTERPOLATIONS = ("linear", "sharp")
PACK_MODES = ("separate", "sbs", "sbs-half", "tb", "tb-half", "interleaved", "anaglyph", "dubois")

#: Dubois's least-squares red-cyan projection matrices (E. Dubois, "A projection method to
#: generate anaglyph stereo images", ICASSP 2001; values of his 2009 note), applied to linear RGB.
DUBOIS_RED_CYAN_LEFT = np.array([[0.437, 0.449, 0.164], [-0.062, -0.062, -0.024], [-0.048, -0.050, -0.017]])
DUBOIS_RED_CYAN_RIGHT = np.array([[-0.011, -0.032, -0.007], [0.377, 0.761, 0.009], [-0.026, -0.093, 1.234]])


# ---------------------------------------------------------------------- cameras
def stereo_cameras(camera: Camera, *, e: float, f: float, source: str = "center") -> tuple[Camera, Camera]:
    """Left and right eye cameras for a source camera (parallel axes, asymmetric frusta).

    ``source``: ``"center"`` (both eyes new, at -/+ e/2), ``"left"`` (the source is the left eye,
    the right eye is new at +e) or ``"right"``. The pair's principal points differ by
    ``cx_r - cx_l = fx e / f`` so that the plane z = f has zero parallax; the kept eye keeps its
    camera unchanged.
    """
    if not isinstance(camera, Camera):
        raise TypeError(f"camera: expected a Camera, got {type(camera).__name__}")
    e = check_finite_scalar("e", e)
    if e < 0:
        raise ValueError(f"e: expected an interaxial >= 0, got {e!r}")
    f = check_positive("f", f)
    check_choice("source", source, SOURCES)
    shift = camera.fx * e / f  # total principal-point difference in pixels
    if not shift <= 10 * camera.width:  # (#12) a parallax of many image widths is a unit mix-up
        raise ValueError(f"e: the zero-parallax shift fx*e/f = {shift:.6g} px exceeds 10 image widths "
                         f"({camera.width} px); e={e:g} is too large for f={f:g} (units mixed up?)")
    offsets = {"center": (-e / 2, e / 2), "left": (0.0, e), "right": (-e, 0.0)}[source]
    dcx = {"center": (-shift / 2, shift / 2), "left": (0.0, shift), "right": (-shift, 0.0)}[source]
    cams = []
    for off, dc in zip(offsets, dcx):
        cam = camera if off == 0 and dc == 0 else camera.translated([off, 0.0, 0.0])
        cams.append(replace(cam, cx=camera.cx + dc) if dc else cam)
    return cams[0], cams[1]


# ---------------------------------------------------------------------- method 2
@dataclass(frozen=True, eq=False)
class MappedLayer:
    """Result of :func:`map_pixels`: float32 color, target planar depth (NaN uncovered), coverage."""

    color: np.ndarray
    depth: np.ndarray
    coverage: np.ndarray


def map_pixels(view: View, *, dx: float, dz: float = 0.0, dpixel: float = 0.0,
               method: str = "pixel", max_jump_px: float = 1.0, interpolation: str = "linear",
               _color32: np.ndarray | None = None, _half: np.ndarray | None = None) -> MappedLayer:
    """Seed 003 method 2: map every source pixel into the view of an eye at offset (dx, 0, dz).

    ``u' = fx (X - dx)/(Z - dz) + cx + dpixel``, ``v' = fy Y/(Z - dz) + cy`` (camera frame of the
    source; X, Y, Z from the pixel's planar depth). ``method="pixel"`` (needs dz = 0) interpolates
    between row neighbours whose shifts differ by at most ``max_jump_px`` pixels;
    ``method="splat"`` copies each pixel to the nearest target pixel. Pixel centers at integers:
    with dx = 0, dz = 0, dpixel = 1.0 pixel (u, v) lands exactly on (u + 1, v).
    ``interpolation`` (``"pixel"`` only): ``"linear"`` runs the colour between two neighbours
    straight from one to the other (a blur half-way), ``"sharp"`` through their Lanczos-3
    half-way sample (:func:`~ibr.render.sharp_sampling.half_way_columns`, none across a depth
    step; :func:`stereo_pair`).
    """
    if not isinstance(view, View):
        raise TypeError(f"view: expected a View, got {type(view).__name__}")
    z = view.require_depth("a stereo pair")
    dx = check_finite_scalar("dx", dx)
    dz = check_finite_scalar("dz", dz)
    dpixel = check_finite_scalar("dpixel", dpixel)
    check_choice("method", method, ("pixel", "splat"))
    check_stereo_interpolation(interpolation, method)
    jump = check_positive("max_jump_px", max_jump_px, allow_inf=True)
    cam = view.camera
    zz = np.ascontiguousarray(z, dtype=np.float32)
    if method == "pixel":
        if dz != 0:
            raise ValueError(f"dz: method 'pixel' preserves rows and needs dz = 0, got {dz!r}; use method='splat'")
        # internal calls (stereo_pair) pass the source colour as it is and get the result in its
        # dtype (rounded half up in the kernel); the public result stays float32
        col = _color32 if _color32 is not None else _float_color(view)
        h, w, c = col.shape
        is_int = col.dtype.kind in "ui"
        out_c = np.empty((h, w, c), col.dtype if is_int else np.float32)
        out_z = np.empty((h, w), np.float32)
        cov = np.empty((h, w), np.bool_)
        half = None
        if interpolation == "sharp":
            half = _half if _half is not None else _half_way_table(col, zz)
        run_bands(_k.scanline_warp, h, col, zz, float(cam.fx), dx, dpixel, float(min(jump, 1e30)), out_c, out_z, cov,
                  is_int, half)
    else:
        col = _float_color(view)
        h, w, c = col.shape
        out_c = np.zeros((h, w, c), np.float32)
        out_z = np.full((h, w), np.inf, np.float32)
        cov = np.zeros((h, w), np.bool_)
        _k.point_splat(col, zz, float(cam.fx), float(cam.fy), float(cam.cx), float(cam.cy),
                       dx, dz, dpixel, out_c, out_z, cov)
        out_z[~cov] = np.nan
    return MappedLayer(out_c, out_z, cov)


# ---------------------------------------------------------------------- pairs
@dataclass(frozen=True, eq=False)
class StereoPair:
    """A synthesized stereo pair.

    ``left``/``right`` keep the source color's dtype; ``left_holes``/``right_holes`` (H, W) bool
    mark disocclusions and out-of-view pixels that were filled from the background side;
    ``left_depth``/``right_depth`` planar z in each eye camera (filled like the color);
    ``left_camera``/``right_camera`` the eye cameras.
    """

    left: np.ndarray
    right: np.ndarray
    left_holes: np.ndarray
    right_holes: np.ndarray
    left_depth: np.ndarray
    right_depth: np.ndarray
    left_camera: Camera
    right_camera: Camera


def _raw_color(view: View) -> np.ndarray:
    """(H, W, C) C-contiguous colour of a view in its own dtype (floats as float32)."""
    col = np.asarray(view.color)
    col = col[..., None] if col.ndim == 2 else col
    return np.ascontiguousarray(col if col.dtype.kind in "ui" else col.astype(np.float32, copy=False))


def _half_way_table(color: np.ndarray, depth: np.ndarray) -> np.ndarray:
    """(H, W, C) colour half-way between each pixel and the next on its row, in ``color``'s
    dtype: Lanczos-3 (:func:`~ibr.render.sharp_sampling.half_way_columns`) clamped to the two
    pixels, the mean where a tap lies across a depth step of ``depth`` (H, W)
    (:func:`~ibr.stereo._pair_kernels.resolve_half_way`). Method 2's sharp sampling; one table
    serves both eyes."""
    from ..render.sharp_sampling import half_way_columns

    half = np.ascontiguousarray(half_way_columns(color, clamp=False))
    run_bands(_k.resolve_half_way, color.shape[0], color, np.ascontiguousarray(depth, dtype=np.float32), half,
              color.dtype.kind in "ui")
    return half


def _float_color(view: View) -> np.ndarray:
    """(H, W, C) float32 C-contiguous colour of a view (its values, not rescaled)."""
    col = np.asarray(view.color)
    return np.ascontiguousarray((col[..., None] if col.ndim == 2 else col).astype(np.float32, copy=False))


def _to_dtype(img: np.ndarray, dtype, ndim: int) -> np.ndarray:
    """``img`` (H, W, C) (a fresh float32 array: rounded and clipped in place; or already
    ``dtype``) in ``dtype``, one channel squeezed to (H, W) when the source was ``ndim`` 2 (an
    (H, W, 1) source keeps its axis, as the kept eye and ``ibr.warp`` do)."""
    if img.shape[2] == 1 and ndim == 2:
        img = img[..., 0]
    if img.dtype == np.dtype(dtype):
        return img
    if np.dtype(dtype).kind in "ui":
        info = np.iinfo(dtype)
        np.rint(img, out=img)
        np.clip(img, info.min, info.max, out=img)
        return img.astype(dtype)
    return img.astype(dtype, copy=False)


def _render_eye(view: View, eye_cam: Camera, method: str, max_jump_px: float, mesh=None, color32=None, half=None):
    src = view.camera
    if method == "mesh":
        from ..render.rasterize import render_mesh

        layer = render_mesh(mesh, view.color, eye_cam)
        return layer.color, layer.depth, layer.coverage
    # method 2: eye = source translated along its x axis with a shifted principal point
    rel = src.cam_from_world @ eye_cam.world_from_cam
    # round-off of the pose products grows with the distance from the world origin (~1e-16 |p|)
    tol = 1e-12 * max(1.0, float(np.abs(src.position).max()), float(np.abs(eye_cam.position).max()))
    if not np.allclose(rel[:3, :3], np.eye(3), atol=1e-12) or abs(rel[1, 3]) > tol:
        raise ValueError("eye camera: method 2 needs an eye translated along the source's x (and z) axis")
    if (eye_cam.fx, eye_cam.fy, eye_cam.cy, eye_cam.shape) != (src.fx, src.fy, src.cy, src.shape):
        raise ValueError("eye camera: method 2 needs the source's fx, fy, cy and size")
    dx, dz = float(rel[0, 3]), float(rel[2, 3])
    if abs(dz) <= max(tol, 1e-12 * abs(dx)):  # round-off of the pose products
        dz = 0.0
    layer = map_pixels(view, dx=dx, dz=dz, dpixel=eye_cam.cx - src.cx,
                       method="pixel" if method == "pixel" else "splat", max_jump_px=max_jump_px,
                       interpolation="linear" if half is None else "sharp", _color32=color32, _half=half)
    return layer.color, layer.depth, layer.coverage


def no_valid_depth_message(view: View, who: str | None = None) -> str:
    """The error for a view whose depth has no valid pixel (library and CLI say the same), naming
    the view as ``who`` (the CLI: ``"VIEW: path/to/view.json"``), else by its name."""
    return _no_valid_depth(who or f"view {view.name!r}", "; a stereo pair needs depth")


def check_stereo_supersample(supersample, method: str) -> int:
    """``supersample`` (:func:`~ibr.render.supersample.check_supersample`) for a pair made with
    ``method``: above 1 only with ``"mesh"`` (the sub-pixel silhouettes live in the quad mesh)."""
    k = check_supersample(supersample)
    if k > 1 and method != "mesh":
        raise ValueError(f"supersample: {k} needs method='mesh' (the sub-pixel silhouettes live in the quad mesh; "
                         f"--method mesh on the command line), got method={method!r}")
    return k


def check_stereo_interpolation(interpolation, method: str) -> str:
    """``interpolation`` (:data:`INTERPOLATIONS`) for a pair made with ``method``: ``"sharp"``
    only with ``"pixel"`` (the half-way samples live in method 2's row kernel)."""
    check_choice("interpolation", interpolation, INTERPOLATIONS)
    if interpolation == "sharp" and method != "pixel":
        raise ValueError(f"interpolation: 'sharp' needs method='pixel' (method 2's row kernel; --method pixel on "
                         f"the command line), got method={method!r}")
    return interpolation


def stereo_pair(view: View, *, e: float, f: float, source: str = "center", method: str = "pixel",
                max_jump_px: float = 1.0, mesh_options: dict | None = None, supersample: int = 1,
                interpolation: str = "linear") -> StereoPair:
    """Synthesize a stereo pair from one RGB-D view (seed 003, step 3).

    Parameters
    ----------
    view : View
        Color + planar depth + camera.
    e, f : float
        Interaxial and zero-parallax distance (scene units); see :mod:`ibr.stereo` for choosing
        them (``ibr.stereo.auto_stereo``).
    source : {"center", "left", "right"}
        Where the source camera sits: between the eyes (both eyes new) or as one eye (kept as is).
    method : {"pixel", "mesh", "splat"}
        ``"pixel"``: method 2 with row interpolation (fast, exactly row-preserving);
        ``"mesh"``: method 1, quad mesh rendered by :func:`ibr.render.render_mesh`;
        ``"splat"``: method 2 literally (nearest-pixel copies; cracks are filled as holes).
    max_jump_px : float
        ``"pixel"`` only: neighbours whose parallax differs by more than this are not connected.
    mesh_options : dict, optional
        ``"mesh"`` only: options of :func:`ibr.mesh.build_mesh` (level of detail).
    supersample : {1, 3, 5}
        ``"mesh"`` only: the view upsampled k x k with sub-pixel silhouettes
        (:func:`ibr.render.upsample.upsample_view`), each eye rendered at k x k its resolution
        and box-filtered (:mod:`ibr.render.supersample`); about k^2 the time.
    interpolation : {"linear", "sharp"}
        ``"pixel"`` only: colour between two row neighbours straight from one to the other
        (default) or through their Lanczos-3 half-way sample (no tap across a depth step;
        :func:`map_pixels`): crisper eyes (against ray-traced eyes at 512 x 384: room +1.1,
        clutter +0.35, grazing +3.2 dB) for 1.4x the pair's time (a table per view, built once
        for both eyes; 1080p: 12.5 against 9.0 ms per eye in ``benchmarks/bench_speed.py``, so
        not the default where a head-mounted display waits). The other methods sample as
        :func:`ibr.render.render_mesh` and the splat do.
    """
    if not isinstance(view, View):
        raise TypeError(f"view: expected a View, got {type(view).__name__}")
    view.require_depth("a stereo pair")
    if not np.isfinite(view.depth).any():  # same check and message as `ibr stereo` (#12)
        raise ValueError(no_valid_depth_message(view))
    check_choice("method", method, METHODS)
    check_stereo_interpolation(interpolation, method)
    mesh_options = check_mesh_options(mesh_options)
    k = check_stereo_supersample(supersample, method)
    left_cam, right_cam = stereo_cameras(view.camera, e=e, f=f, source=source)
    mesh = None
    source_view = view
    if method == "mesh":
        from ..mesh.quad_mesh import build_mesh
        from ..render.upsample import upsample_view

        source_view = upsample_view(view, k)
        mesh = build_mesh(source_view, **mesh_options)  # one mesh serves both eyes
    out = {}
    color32 = _raw_color(view) if method == "pixel" else None  # (both eyes share one conversion)
    half = _half_way_table(color32, view.depth) if method == "pixel" and interpolation == "sharp" else None
    for eye, cam in (("left", left_cam), ("right", right_cam)):
        if cam is view.camera:  # the kept eye: the original frame, untouched
            col = np.asarray(view.color)
            out[eye] = (col.copy(), view.depth.copy(), np.zeros(view.shape, bool))
            continue
        c, d, cov = _render_eye(source_view, supersampled_camera(cam, k), method, max_jump_px, mesh, color32, half)
        if k > 1:  # box mean wherever every subsample is covered, else the centre; holes filled at 1x below
            c, d, uncovered, _ = downsample_rendering(c, d, ~cov, np.zeros(cov.shape, bool), k)
            cov = ~uncovered
        c = np.ascontiguousarray(c[..., None] if c.ndim == 2 else c)
        if c.dtype.kind not in "ui":
            c = np.ascontiguousarray(c, dtype=np.float32)
        d = np.ascontiguousarray(d, dtype=np.float32)
        holes = _fill_horizontal_parallax_inplace(c, d, cov)
        out[eye] = (_to_dtype(c, np.asarray(view.color).dtype, np.ndim(view.color)), d, holes)
    return StereoPair(out["left"][0], out["right"][0], out["left"][2], out["right"][2],
                      out["left"][1], out["right"][1], left_cam, right_cam)


def stereo_pair_from_zbuffer(color, zbuffer, projection, *, e: float, f: float, view_matrix=None,
                             source: str = "center", method: str = "pixel", far_is_empty: bool = True,
                             max_jump_px: float = 1.0, interpolation: str = "linear") -> StereoPair:
    """Seed 003 end to end: color buffer + OpenGL window-depth buffer + projection matrix.

    ``zbuffer`` holds window depths w in [0, 1] (``glReadPixels(GL_DEPTH_COMPONENT)``, rows top
    to bottom as in the color); near/far/frustum come from ``projection`` via
    :func:`ibr.base.camera.camera_from_gl_projection`, planar z from the exact inverse
    ``z = n f / (f - w (f - n))`` (:func:`ibr.base.depth.z_from_window`; seed 003's printed inverse is
    wrong). With ``far_is_empty`` the cleared value w = 1 is treated as no depth. The other
    options are :func:`stereo_pair`'s.
    """
    from ..base.depth import z_from_window

    col = check_image("color", color)
    w_buf = check_array("zbuffer", zbuffer, ndim=2, dtype_kind="f")
    if w_buf.shape != col.shape[:2]:
        raise ValueError(f"zbuffer: expected shape {col.shape[:2]} (the color's), got {w_buf.shape}")
    h, w = w_buf.shape
    cam, near, far = camera_from_gl_projection(projection, w, h, view=view_matrix)
    z = z_from_window(w_buf, near=near, far=far)
    if far_is_empty:
        z[w_buf >= 1.0] = np.nan
    return stereo_pair(View(col, z, cam, "zbuffer"), e=e, f=f, source=source, method=method,
                       max_jump_px=max_jump_px, interpolation=interpolation)


# ---------------------------------------------------------------------- output formats
def _pair(left, right) -> tuple[np.ndarray, np.ndarray]:
    l_img = check_color("left", left, channels=None)  # cv2.resize has no kernel for other dtypes
    r_img = check_color("right", right, channels=None)
    if l_img.shape != r_img.shape or l_img.dtype != r_img.dtype:
        raise ValueError(f"right: expected shape {l_img.shape} and dtype {l_img.dtype} (the left's), "
                         f"got {r_img.shape} {r_img.dtype}")
    return l_img, r_img


def _rgb(img: np.ndarray, name: str) -> np.ndarray:
    if img.ndim == 2:
        return np.repeat(img[..., None], 3, axis=2)
    if img.shape[2] == 1:
        return np.repeat(img, 3, axis=2)
    if img.shape[2] < 3:
        raise ValueError(f"{name}: expected a gray or RGB image, got shape {img.shape}")
    return img[..., :3]


def anaglyph(left, right) -> np.ndarray:
    """Red-cyan anaglyph by channels (seed 003 step 4y): red from the left image, green and blue
    from the right one. Keeps the dtype; gray inputs are treated as RGB."""
    l_img, r_img = _pair(left, right)
    out = _rgb(r_img, "right").copy()
    out[..., 0] = _rgb(l_img, "left")[..., 0]
    return out


def _srgb_to_linear(x):
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4)


def _linear_to_srgb(x):
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(np.maximum(x, 0), 1 / 2.4) - 0.055)


def dubois_anaglyph(left, right, *, linear_input: bool = False) -> np.ndarray:
    """Least-squares (Dubois) red-cyan anaglyph, which reduces retinal rivalry.

    ``out = clip(A_l @ rgb_left + A_r @ rgb_right)`` in linear RGB with Dubois's matrices
    (:data:`DUBOIS_RED_CYAN_LEFT`, :data:`DUBOIS_RED_CYAN_RIGHT`). Inputs are sRGB-encoded
    display values (uint8/uint16 or float in [0, 1]) unless ``linear_input``; the output has the
    input's dtype and encoding. Each row of A_l + A_r sums to 1.000 +/- 0.001, so a gray at zero
    parallax stays (nearly) the same gray.
    """
    l_img, r_img = _pair(left, right)
    dtype = l_img.dtype
    if dtype == np.uint8 and not linear_input:  # tables: exact to 0.006 codes at 8 bits (16-bit
        return _dubois_lut(_rgb(l_img, "left"), _rgb(r_img, "right"))  # linear steps cost uint16 7)
    scale = float(np.iinfo(dtype).max) if dtype.kind in "ui" else 1.0
    lf = _rgb(l_img, "left").astype(np.float64) / scale
    rf = _rgb(r_img, "right").astype(np.float64) / scale
    if not linear_input:
        lf, rf = _srgb_to_linear(np.clip(lf, 0, 1)), _srgb_to_linear(np.clip(rf, 0, 1))
    out = np.clip(lf @ DUBOIS_RED_CYAN_LEFT.T + rf @ DUBOIS_RED_CYAN_RIGHT.T, 0.0, 1.0)
    if not linear_input:
        out = _linear_to_srgb(out)
    out = out * scale
    if dtype.kind in "ui":
        return np.clip(np.rint(out), 0, scale).astype(dtype)
    return out.astype(dtype)


@lru_cache(maxsize=4)
def _srgb_tables(dtype_name: str):
    """Decode table (code -> linear float32) and encode table (16-bit linear -> code)."""
    dtype = np.dtype(dtype_name)
    peak = np.iinfo(dtype).max
    decode = _srgb_to_linear(np.arange(peak + 1) / peak).astype(np.float32)
    encode = np.clip(np.rint(_linear_to_srgb(np.arange(65536) / 65535.0) * peak), 0, peak).astype(dtype)
    decode.setflags(write=False)
    encode.setflags(write=False)
    return decode, encode


def _dubois_lut(l_img: np.ndarray, r_img: np.ndarray) -> np.ndarray:
    """uint8 fast path of :func:`dubois_anaglyph`: table decode, float32 matrices
    (``cv2.transform``), 16-bit linear quantization, table encode (< 0.1 code value error; at
    16 bits that quantization cost up to 7 codes near black, so uint16 takes the float path)."""
    decode, encode = _srgb_tables(l_img.dtype.name)
    lf = cv2.LUT(np.ascontiguousarray(l_img), decode)  # uint8: 256-entry table, float32 output
    rf = cv2.LUT(np.ascontiguousarray(r_img), decode)
    lin = cv2.transform(lf, DUBOIS_RED_CYAN_LEFT.astype(np.float32))
    lin += cv2.transform(rf, DUBOIS_RED_CYAN_RIGHT.astype(np.float32))
    idx = np.clip(lin * 65535.0 + 0.5, 0, 65535).astype(np.uint16)
    return encode[idx]


def pack_stereo(left, right, mode: str):
    """Pack a stereo pair for a display.

    ``mode``: ``"separate"`` -> ``(left, right)``; ``"sbs"`` (H, 2W) left | right;
    ``"sbs-half"`` (H, W), each eye squeezed to half width (left gets W//2 columns, area
    filter); ``"tb"`` (2H, W) left over right; ``"tb-half"`` (H, W); ``"interleaved"`` (H, W)
    rows 0, 2, 4, ... from the left eye and 1, 3, 5, ... from the right (row-interleaved
    polarized displays); ``"anaglyph"`` red-cyan by channels; ``"dubois"`` least-squares anaglyph.
    """
    check_choice("mode", mode, PACK_MODES)
    l_img, r_img = _pair(left, right)
    h, w = l_img.shape[:2]
    if mode == "separate":
        return l_img, r_img
    if mode == "sbs":
        return np.concatenate([l_img, r_img], axis=1)
    if mode == "tb":
        return np.concatenate([l_img, r_img], axis=0)
    if mode == "sbs-half":
        wl = w // 2
        if wl < 1:
            raise ValueError(f"left: sbs-half needs width >= 2, got {w}")
        return np.concatenate([cv2.resize(l_img, (wl, h), interpolation=cv2.INTER_AREA).reshape(h, wl, *l_img.shape[2:]),
                               cv2.resize(r_img, (w - wl, h), interpolation=cv2.INTER_AREA).reshape(h, w - wl, *l_img.shape[2:])], axis=1)
    if mode == "tb-half":
        hl = h // 2
        if hl < 1:
            raise ValueError(f"left: tb-half needs height >= 2, got {h}")
        return np.concatenate([cv2.resize(l_img, (w, hl), interpolation=cv2.INTER_AREA).reshape(hl, w, *l_img.shape[2:]),
                               cv2.resize(r_img, (w, h - hl), interpolation=cv2.INTER_AREA).reshape(h - hl, w, *l_img.shape[2:])], axis=0)
    if mode == "interleaved":
        out = l_img.copy()
        out[1::2] = r_img[1::2]
        return out
    if mode == "anaglyph":
        return anaglyph(l_img, r_img)
    return dubois_anaglyph(l_img, r_img)
