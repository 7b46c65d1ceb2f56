"""Compositing canvases into images: pinhole targets by one homography per canvas, any rays.

Seed 004 renders its virtual canvas as the texture of a plane in the 3-D scene; seed 001 (section
7.5, "纹理映射到虚拟屏幕上") notes that a virtual screen is one rectangle whose texture is the
current photo or movie frame. Here a canvas is drawn into an already rendered RGB-D image:

* **Pinhole targets** (a :class:`~ibr.base.Camera`: ``ibr.warp``/``ibr.interpolate`` renderings,
  views, perspective views, cube faces): the canvas maps to the image by one exact 3x3 homography
  (:meth:`Canvas.homography`); every target pixel in the projected quad's bounding box is mapped
  back to the canvas by its inverse (one ``cv2.warpPerspective`` of the box; OpenCV quantizes
  the sample position to 1/32 texel), so there is no texture drift; ``1/z``, the coverage and the
  depth test are affine in the target pixel (numba kernel, no division).
* **Any rays** (equirect panoramas; :func:`composite_rays_into`): ray-plane intersection per pixel.

Per pixel: coverage is anti-aliased in target pixels (distance to the projected edges), colour
is the bilinear, border-clamped sample of the alpha-premultiplied buffer, blended "over" the
image. **Occlusion**: where the scene depth is finite and the canvas point is farther than
``depth * (1 + depth_tol)``, the canvas is hidden and the pixel is left exactly as it was.
Several canvases are drawn far to near (by the distance of their centres) and, where a canvas is
at least half opaque, its depth is written, so a later canvas behind it is hidden as well.

Conventions: pixel centres at integers (target and canvas); depth is planar z for pinhole
targets and range (distance along the ray) for ray targets, NaN where unknown (no occluder).
Integer images are rounded to nearest.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..base.camera import Camera
from ..base.validate import check_image, check_positive
from ..base.view import View
from ..render.rendering import Rendering
from . import _compositor_kernels as _k
from .plane import Canvas

__all__ = ["composite", "composite_into", "composite_rays_into", "projected_bbox"]

_MAXVAL = {"uint8": 255.0, "uint16": 65535.0}


def _check_canvases(canvases) -> list[Canvas]:
    if isinstance(canvases, Canvas):
        return [canvases]
    try:
        items = list(canvases)
    except TypeError:
        raise TypeError(f"canvases: expected a Canvas or a sequence of them, got {type(canvases).__name__}") from None
    for i, c in enumerate(items):
        if not isinstance(c, Canvas):
            raise TypeError(f"canvases[{i}]: expected a Canvas, got {type(c).__name__}")
    return items


def _check_color(color) -> np.ndarray:
    img = check_image("color", color, channels=(1, 3, 4))
    if img.dtype not in (np.uint8, np.uint16, np.float32):
        raise ValueError(f"color: expected uint8, uint16 or float32 pixels, got {img.dtype}")
    if not img.flags.writeable:
        raise ValueError("color: the array is read-only; pass a writable copy")
    return img


def _texture(canvas: Canvas, channels: int) -> np.ndarray:
    """The buffer as an alpha-premultiplied texture for a target with ``channels`` channels:
    RGBA for RGB(A) targets, (luma, alpha) float32 for gray targets (Rec. 601 luma).

    Premultiplied colour interpolates correctly across transparent texels (no dark fringes at
    stroke edges); an opaque buffer (every video frame) is used as it is, without a copy.
    """
    rgba = canvas.rgba
    m = canvas.max_value
    alpha = rgba[..., 3]
    opaque = bool(alpha.min() >= m)
    if channels == 1:
        out = np.empty(rgba.shape[:2] + (2,), np.float32)
        out[..., 0] = rgba[..., :3].astype(np.float32) @ np.array([0.299, 0.587, 0.114], np.float32)
        out[..., 1] = alpha
        if not opaque:
            out[..., 0] *= out[..., 1] / np.float32(m)
        return out
    if opaque:
        return rgba
    a = alpha.astype(np.float32) / np.float32(m)
    pre = rgba[..., :3] * a[..., None]
    out = np.empty_like(rgba)
    out[..., :3] = np.rint(pre) if rgba.dtype.kind == "u" else pre
    out[..., 3] = alpha
    return out


def projected_bbox(canvas: Canvas, camera: Camera, *, margin: int = 1) -> tuple[int, int, int, int] | None:
    """``(u0, v0, u1, v1)`` half-open pixel box of ``camera`` that can see ``canvas``, or None.

    The rectangle is clipped against the plane just in front of the camera centre (so a canvas
    crossing the camera plane still gets a correct box), projected, grown by ``margin`` pixels
    (anti-aliased edges) and clipped to the image.
    """
    cw = camera.cam_from_world
    pts = canvas.corners() @ cw[:3, :3].T + cw[:3, 3]
    zmin = 1e-9 * (1.0 + np.abs(pts[:, 2]).max())
    clipped = []
    for i in range(4):  # Sutherland-Hodgman against z >= zmin
        p, q = pts[i], pts[(i + 1) % 4]
        pin, qin = p[2] >= zmin, q[2] >= zmin
        if pin:
            clipped.append(p)
        if pin != qin:
            s = (zmin - p[2]) / (q[2] - p[2])
            clipped.append(p + s * (q - p))
    if len(clipped) < 3:
        return None
    c = np.array(clipped)
    uv, _ = camera.project_cam(c)
    u0 = int(np.floor(uv[:, 0].min())) - margin
    u1 = int(np.ceil(uv[:, 0].max())) + margin + 1
    v0 = int(np.floor(uv[:, 1].min())) - margin
    v1 = int(np.ceil(uv[:, 1].max())) + margin + 1
    u0, v0 = max(u0, 0), max(v0, 0)
    u1, v1 = min(u1, camera.width), min(v1, camera.height)
    if u0 >= u1 or v0 >= v1:
        return None
    return u0, v0, u1, v1


def _far_to_near(canvases: list[Canvas], origin: np.ndarray) -> list[Canvas]:
    return sorted(canvases, key=lambda c: -float(np.linalg.norm(c.center - origin)))


def composite_into(color, camera: Camera, canvases, *, depth=None, depth_tol: float = 1e-3,
                   antialias: bool = True, write_depth: bool = False) -> None:
    """Draw ``canvases`` into ``color`` (in place) as seen by the pinhole ``camera``.

    Parameters
    ----------
    color : (H, W[, C]) array
        uint8, uint16 or float32 ([0, 1]) target image of ``camera``'s size; C = 1, 3 or 4.
        Modified in place.
    camera : Camera
        The target camera (pixel centres at integers).
    canvases : Canvas or sequence of Canvas
    depth : (H, W) float array, optional
        The scene's planar z in ``camera`` (NaN = nothing there). Canvas points farther than
        ``depth * (1 + depth_tol)`` are hidden.
    depth_tol : float
        Relative tolerance that lets a canvas lying on a surface win over it.
    antialias : bool
        Anti-aliased coverage at the canvas edges (default); False gives hard edges (a pixel is
        covered when its centre's ray hits the rectangle).
    write_depth : bool
        Store the canvas depth in ``depth`` (float32, in place) where a canvas is at least half
        opaque.
    """
    if not isinstance(camera, Camera):
        raise TypeError(f"camera: expected a Camera, got {type(camera).__name__}")
    img = _check_color(color)
    if img.shape[:2] != camera.shape:
        raise ValueError(f"color: size {img.shape[1]}x{img.shape[0]} does not match the camera's "
                         f"{camera.width}x{camera.height}")
    items = _check_canvases(canvases)
    tol = check_positive("depth_tol", depth_tol) if depth_tol != 0 else 0.0
    out = img if img.ndim == 3 else img[..., None]
    use_depth = depth is not None
    if use_depth:
        z = check_image("depth", depth, channels=(1,))
        z = z.reshape(z.shape[:2])
        if z.shape != camera.shape:
            raise ValueError(f"depth: size {z.shape[1]}x{z.shape[0]} does not match the camera's "
                             f"{camera.width}x{camera.height}")
        if write_depth and (z.dtype != np.float32 or not z.flags.writeable):
            raise ValueError(f"depth: write_depth needs a writable float32 array, got {z.dtype}")
        if z.dtype != np.float32:
            z = z.astype(np.float32)
    else:
        if write_depth:
            raise ValueError("depth: write_depth=True needs a depth array to write into")
        z = np.empty((1, 1), np.float32)
    if len(items) > 1 and not write_depth:  # a depth buffer of its own (the caller's is not
        # written): a nearer canvas hides a farther one per pixel, not only by centre distance
        z = np.full(camera.shape, np.nan, np.float32) if not use_depth else np.array(z, np.float32, copy=True)
        use_depth = write_depth = True
    maxval = _MAXVAL.get(out.dtype.name, 1.0)
    for canvas in _far_to_near(items, camera.position):
        box = projected_bbox(canvas, camera)
        if box is None:
            continue
        h = canvas.homography(camera)
        try:
            hinv = np.linalg.inv(h)
        except np.linalg.LinAlgError:  # seen edge-on: no area
            continue
        if not np.all(np.isfinite(hinv)):
            continue
        _blend_one(out, z, use_depth, write_depth, canvas, hinv, box, tol, maxval, bool(antialias))


def _blend_one(out, z, use_depth, write_depth, canvas: Canvas, hinv: np.ndarray, box, tol, maxval, antialias):
    """Sample the premultiplied canvas at every pixel of ``box`` through ``hinv`` (one
    ``cv2.warpPerspective``, bilinear, border texels replicated), then blend (numba kernel)."""
    import cv2

    wt, ht = canvas.resolution
    # edge lines in canvas coordinates (inside >= 0): x + 1/2, W - 1/2 - x, y + 1/2, H - 1/2 - y;
    # as target-image lines they are hinv^T l; scaled by |l[:2]| their value is the signed
    # distance in target pixels (seed-free geometry: a projective map keeps lines straight)
    lines = np.array([[1.0, 0, 0.5], [-1.0, 0, wt - 0.5], [0, 1.0, 0.5], [0, -1.0, ht - 0.5]]) @ hinv
    norms = np.linalg.norm(lines[:, :2], axis=1)
    if not np.all(norms > 0):
        return
    lines /= norms[:, None]
    u0, v0, u1, v1 = box
    shift = np.array([[1.0, 0, u0], [0, 1.0, v0], [0, 0, 1.0]])
    tex = _texture(canvas, out.shape[2])
    samp = cv2.warpPerspective(tex, hinv @ shift, (u1 - u0, v1 - v0),
                               flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP, borderMode=cv2.BORDER_REPLICATE)
    if samp.ndim == 2:
        samp = samp[..., None]
    scale = 1.0 / canvas.max_value  # the texture's values are in the canvas's scale (gray: float32 of them)
    direct = samp.dtype == out.dtype and samp.shape[2] == out.shape[2]
    _k.blend_samples(out, z, use_depth, write_depth, samp, scale, v0, u0, np.ascontiguousarray(hinv[2]), lines,
                     tol, maxval, out.dtype.kind == "u", maxval, antialias, direct)


def composite(target, canvases, *, camera: Camera | None = None, depth=None, depth_tol: float = 1e-3,
              antialias: bool = True):
    """Canvases drawn into a rendering, a view or an image (a new object; the input is unchanged).

    Parameters
    ----------
    target : Rendering, View or array
        A :class:`~ibr.Rendering` (``ibr.warp``/``ibr.interpolate``; its camera and depth are
        used), a :class:`~ibr.View` (camera and depth used), or an image array (give ``camera``;
        ``depth`` optional).
    canvases : Canvas or sequence of Canvas
    camera, depth
        For an array target: its pinhole camera and (optional) planar depth for occlusion.
    depth_tol, antialias
        See :func:`composite_into`.

    Returns
    -------
    Same kind as ``target``
        A Rendering or View keeps ``holes``/``filled``/``name``; its depth takes the canvas depth
        where a canvas is at least half opaque. An array target gives a new array.
    """
    if isinstance(target, (Rendering, View)):
        if camera is not None or depth is not None:
            raise ValueError("camera, depth: taken from the Rendering/View target; do not pass them")
        color = np.array(target.color, copy=True)
        wide = color.dtype == np.float64  # a View may hold float64: drawn in float32, given back as float64
        if wide:
            color = color.astype(np.float32)
        z = None if target.depth is None else np.array(target.depth, dtype=np.float32, copy=True)
        composite_into(color, target.camera, canvases, depth=z, depth_tol=depth_tol, antialias=antialias,
                       write_depth=z is not None)
        if wide:
            color = color.astype(np.float64)
        if isinstance(target, Rendering):
            return replace(target, color=color, depth=z)
        return View(color, z, target.camera, target.name)
    if camera is None:
        raise ValueError("camera: required when the target is an image array")
    color = np.array(_check_color_readable(target), copy=True)
    composite_into(color, camera, canvases, depth=depth, depth_tol=depth_tol, antialias=antialias)
    return color


def _check_color_readable(color) -> np.ndarray:
    img = check_image("target", color, channels=(1, 3, 4))
    if img.dtype not in (np.uint8, np.uint16, np.float32):
        raise ValueError(f"target: expected uint8, uint16 or float32 pixels, got {img.dtype}")
    return img


# ----------------------------------------------------------------------------- any rays
def _plane_coords(canvas: Canvas, origin, dirs):
    """(t, x, y) of rays against the canvas's infinite plane; t = inf (x, y NaN) when the ray is
    parallel or meets the plane behind its origin. ``dirs`` (..., 3)."""
    n = canvas.normal
    with np.errstate(divide="ignore", invalid="ignore"):
        t = ((canvas.center - origin) @ n) / (dirs @ n)
    ok = np.isfinite(t) & (t > 0)
    t = np.where(ok, t, np.inf)
    p = origin + np.where(ok, t, np.nan)[..., None] * dirs
    xy = canvas.pixel_from_world(p)
    return t, xy[..., 0], xy[..., 1]


def _sample_premultiplied(tex: np.ndarray, scale: float, x: np.ndarray, y: np.ndarray):
    """Bilinear, border-clamped, alpha-premultiplied samples: (colour (N, nc) in [0, 1], alpha (N,))."""
    ht, wt = tex.shape[:2]
    nc = tex.shape[2] - 1
    xs = np.clip(x, 0.0, wt - 1.0)
    ys = np.clip(y, 0.0, ht - 1.0)
    x0 = np.floor(xs).astype(np.intp)
    y0 = np.floor(ys).astype(np.intp)
    x1 = np.minimum(x0 + 1, wt - 1)
    y1 = np.minimum(y0 + 1, ht - 1)
    fx = xs - x0
    fy = ys - y0
    col = np.zeros((len(x), nc))
    alpha = np.zeros(len(x))
    for yy, xx, wgt in ((y0, x0, (1 - fx) * (1 - fy)), (y0, x1, fx * (1 - fy)),
                        (y1, x0, (1 - fx) * fy), (y1, x1, fx * fy)):
        alpha += tex[yy, xx, nc].astype(np.float64) * (wgt * scale)
        col += tex[yy, xx, :nc].astype(np.float64) * (wgt * scale)[:, None]  # premultiplied already
    return col, alpha


def composite_rays_into(color, origin, dirs, canvases, *, rng=None, depth_tol: float = 1e-3,
                        antialias: bool = True, write_range: bool = False) -> None:
    """Draw ``canvases`` into ``color`` (in place) for per-pixel rays (equirect or any camera).

    Parameters
    ----------
    color : (H, W[, C]) array
        uint8, uint16 or float32 ([0, 1]) image; modified in place.
    origin : (3,) array
        Common ray origin, world coordinates.
    dirs : (H, W, 3) array
        Unit ray direction of every pixel centre (world frame).
    canvases : Canvas or sequence of Canvas
    rng : (H, W) array, optional
        Scene range (distance along the ray) per pixel, NaN = nothing there; canvas points
        farther than ``rng * (1 + depth_tol)`` are hidden.
    antialias : bool
        Coverage from the signed distance to the edges in target pixels, estimated with the
        finite-difference gradient of the canvas coordinates across neighbouring pixels.
    write_range : bool
        Store the canvas range in ``rng`` (float32, in place) where a canvas is at least half opaque.
    """
    img = _check_color(color)
    out = img if img.ndim == 3 else img[..., None]
    d = np.asarray(dirs, dtype=np.float64)
    if d.shape != out.shape[:2] + (3,):
        raise ValueError(f"dirs: expected shape {out.shape[:2] + (3,)}, got {d.shape}")
    o = np.asarray(origin, dtype=np.float64).reshape(3)
    items = _check_canvases(canvases)
    tol = float(depth_tol)
    if rng is not None:
        rng = np.asarray(rng)
        if rng.shape != out.shape[:2]:
            raise ValueError(f"rng: expected shape {out.shape[:2]}, got {rng.shape}")
    if write_range and (rng is None or rng.dtype != np.float32 or not rng.flags.writeable):
        raise ValueError("rng: write_range=True needs a writable float32 range array")
    if len(items) > 1 and not write_range:  # a range buffer of its own: canvases hide each other per pixel
        rng = np.full(out.shape[:2], np.nan, np.float32) if rng is None else np.array(rng, np.float32, copy=True)
        write_range = True
    maxval = _MAXVAL.get(out.dtype.name, 1.0)
    for canvas in _far_to_near(items, o):
        t, x, y = _plane_coords(canvas, o, d)
        wt, ht = canvas.resolution
        if antialias:
            with np.errstate(invalid="ignore"):
                gx = np.hypot(*np.gradient(x)) if min(x.shape) > 1 else np.ones_like(x)
                gy = np.hypot(*np.gradient(y)) if min(y.shape) > 1 else np.ones_like(y)
                gx = np.where(gx > 0, gx, np.nan)
                gy = np.where(gy > 0, gy, np.nan)
                cov = (np.clip(0.5 + (x + 0.5) / gx, 0, 1) * np.clip(0.5 + (wt - 0.5 - x) / gx, 0, 1)
                       * np.clip(0.5 + (y + 0.5) / gy, 0, 1) * np.clip(0.5 + (ht - 0.5 - y) / gy, 0, 1))
        else:
            with np.errstate(invalid="ignore"):
                cov = ((x >= -0.5) & (x < wt - 0.5) & (y >= -0.5) & (y < ht - 0.5)).astype(np.float64)
        cov = np.where(np.isfinite(cov) & np.isfinite(t), cov, 0.0)
        if rng is not None:
            with np.errstate(invalid="ignore"):
                hidden = np.isfinite(rng) & (rng > 0) & (t > rng * (1.0 + tol))
            cov[hidden] = 0.0
        sel = np.nonzero(cov > 0)
        if not len(sel[0]):
            continue
        tex = _texture(canvas, out.shape[2])
        col, alpha = _sample_premultiplied(tex, 1.0 / canvas.max_value, x[sel], y[sel])
        c = cov[sel]
        if out.shape[2] == 4:  # an RGBA target: its alpha channel blends like a (premultiplied) colour
            col = np.concatenate([col, alpha[:, None]], axis=1)
        alpha *= c
        dst = out[sel].astype(np.float64)
        val = col * (c * maxval)[:, None] + dst * (1.0 - alpha)[:, None]
        if out.dtype.kind == "u":
            val = np.clip(np.rint(val), 0, maxval)
        out[sel] = val.astype(out.dtype)
        if write_range:
            opaque = alpha >= 0.5
            rng[sel[0][opaque], sel[1][opaque]] = t[sel][opaque]
