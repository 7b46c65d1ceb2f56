"""Post-rendering image warp ("time-warp") to a newer head pose (seed 001 section 7.4).

A frame rendered for one head pose is re-projected just before scan-out to the latest pose:

* **Rotation** (yaw, pitch, roll) is exact: pixels of a camera rotated about its center map by
  the homography ``dst_pix_from_src_pix = K_dst R_dst_from_src K_src^-1`` (no depth needed);
  :func:`rotation_homography`, :func:`warp_rotation`.
* **Translation** needs depth (motion parallax, visibility events): the frame is warped through
  the renderer (:func:`ibr.warp`, quad mesh + z-buffer + background-side hole fill);
  :func:`timewarp` picks the path.
* **Guard band**: render a larger image than the display (:func:`guard_band_camera`), so that
  a turned head still finds rendered pixels; where the band runs out, the edge pixels are
  replicated rather than shown black (the seed's recommendation), and reported as a mask.
* **Frame-rate up-conversion** (:func:`upconvert`): render every k-th pose (e.g. 10 of 60
  frames per second) and warp it to the poses in between, with the per-frame error against
  fully rendered frames.

Conventions: camera frame x right, y down, z forward; poses world_from_cam; pixel centers at
integers, so a homography maps pixel centers: the center of a 512 x 512 image is (255.5, 255.5)
and a pure rotation about the optical axis keeps that pixel fixed.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Sequence

import cv2
import numpy as np

from ..base.validate import check_choice, check_color, check_finite_scalar
from ..base.camera import Camera
from ..base.view import View

__all__ = [
    "TimewarpFrame",
    "UpconvertResult",
    "guard_band_camera",
    "rotation_homography",
    "timewarp",
    "timewarp_mode",
    "upconvert",
    "warp_rotation",
]

MODES = ("auto", "rotation", "depth")


def _check_camera(name: str, cam) -> Camera:
    if not isinstance(cam, Camera):
        raise TypeError(f"{name}: expected a Camera, got {type(cam).__name__}")
    return cam


def guard_band_camera(camera: Camera, *, margin_px: int) -> Camera:
    """The display camera enlarged by ``margin_px`` pixels on every side (same fx, fy, pose).

    Display pixel (u, v) is band pixel (u + m, v + m): ``cx_band = cx + m``; e.g. a 512 x 512
    display with cx = 255.5 and m = 32 gives a 576 x 576 band with cx = 287.5.
    """
    _check_camera("camera", camera)
    if isinstance(margin_px, bool) or int(margin_px) != margin_px or margin_px < 0:
        raise ValueError(f"margin_px: expected an integer >= 0, got {margin_px!r}")
    m = int(margin_px)
    return replace(camera, cx=camera.cx + m, cy=camera.cy + m, width=camera.width + 2 * m,
                   height=camera.height + 2 * m)


def rotation_homography(src: Camera, dst: Camera, *, ignore_translation: bool = False,
                        atol: float = 1e-9) -> np.ndarray:
    """3x3 ``dst_pix_from_src_pix = K_dst R_dst_from_src K_src^-1`` (pixel centers at integers).

    Exact for cameras that share a center. A translation between them raises ``ValueError``
    unless ``ignore_translation`` (the seed's cheap time-warp, which is then only approximate:
    it ignores motion parallax).
    """
    _check_camera("src", src)
    _check_camera("dst", dst)
    dst_from_src = dst.cam_from_world @ src.world_from_cam
    if not ignore_translation and np.linalg.norm(dst_from_src[:3, 3]) > atol:
        raise ValueError(
            f"dst: camera centers differ by {np.linalg.norm(dst_from_src[:3, 3]):.3g} scene units; "
            "a rotation homography is exact only for a shared center (use timewarp(..., mode='depth'))"
        )
    return dst.K @ dst_from_src[:3, :3] @ np.linalg.inv(src.K)


@dataclass(frozen=True, eq=False)
class TimewarpFrame:
    """A warped frame: ``color`` (display size, the source's dtype), ``outside`` (H, W) bool where
    the source had no rendered pixel (edge-replicated for rotation, hole-filled for depth warps),
    ``holes`` (H, W) bool disocclusions (depth warps only), ``camera`` the display camera."""

    color: np.ndarray
    outside: np.ndarray
    holes: np.ndarray
    camera: Camera


def rotation_maps(src: Camera, dst: Camera, *, ignore_translation: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(map_u, map_v, outside)``: for each dst pixel center the src pixel it samples (float32,
    centers at integers) and whether that lies outside the src image [-0.5, W - 0.5]."""
    h_sd = np.linalg.inv(rotation_homography(src, dst, ignore_translation=ignore_translation))
    u, v = dst.pixel_grid()
    p = np.stack([u, v, np.ones_like(u)], -1) @ h_sd.T
    with np.errstate(divide="ignore", invalid="ignore"):
        mu, mv = p[..., 0] / p[..., 2], p[..., 1] / p[..., 2]
    behind = ~(p[..., 2] > 0)
    outside = behind | (mu < -0.5) | (mu > src.width - 0.5) | (mv < -0.5) | (mv > src.height - 0.5)
    mu = np.where(behind, -1e6, mu)
    mv = np.where(behind, -1e6, mv)
    return mu.astype(np.float32), mv.astype(np.float32), outside


def warp_rotation(color, src: Camera, dst: Camera, *, ignore_translation: bool = False) -> TimewarpFrame:
    """Re-project a frame rendered with ``src`` to the rotated camera ``dst`` (exact homography).

    Bilinear ``cv2.warpPerspective`` (``cv2.remap`` of explicit maps when part of the new view
    looks behind the old camera); where the source (the guard band) runs out, the nearest edge
    pixel is replicated (``BORDER_REPLICATE``) and flagged in ``outside``. Keeps the dtype.
    """
    _check_camera("src", src)
    _check_camera("dst", dst)
    img = check_color("color", color, channels=None)  # cv2.warpPerspective / remap: these dtypes only
    if img.shape[:2] != src.shape:
        raise ValueError(f"color: size {img.shape[1]}x{img.shape[0]} does not match src {src.width}x{src.height}")
    h_sd = np.linalg.inv(rotation_homography(src, dst, ignore_translation=ignore_translation))
    corners = np.array([[-0.5, -0.5, 1], [dst.width - 0.5, -0.5, 1], [-0.5, dst.height - 0.5, 1],
                        [dst.width - 0.5, dst.height - 0.5, 1]]) @ h_sd.T
    size = (dst.width, dst.height)
    if np.all(corners[:, 2] > 0):  # w is affine in (u, v): positive at the corners -> everywhere
        flags = cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP
        out = cv2.warpPerspective(img, h_sd, size, flags=flags, borderMode=cv2.BORDER_REPLICATE)
        inside = cv2.warpPerspective(np.ones(src.shape, np.uint8), h_sd, size,
                                     flags=cv2.INTER_NEAREST | cv2.WARP_INVERSE_MAP,
                                     borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        outside = inside == 0
    else:  # part of the new view looks behind the old camera: explicit maps flag it
        mu, mv, outside = rotation_maps(src, dst, ignore_translation=ignore_translation)
        out = cv2.remap(img, mu, mv, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    if out.ndim == 2 and img.ndim == 3:
        out = out[..., None]
    return TimewarpFrame(out, outside, np.zeros(dst.shape, bool), dst)


def _depth_warp(view: View, dst: Camera) -> TimewarpFrame:
    from ..render.view_synthesis import warp  # the renderer: quad mesh + z-buffer + background hole fill

    res = warp(view, dst)
    color = np.asarray(res.color)
    dtype = np.asarray(view.color).dtype
    if color.dtype != dtype:
        if dtype.kind in "ui":
            color = np.clip(np.rint(color), 0, np.iinfo(dtype).max).astype(dtype)
        else:
            color = color.astype(dtype)
    holes = np.asarray(res.holes, bool)
    # pixels whose ray leaves the rendered frame: the source's view frustum does not contain them
    mu, mv, outside = rotation_maps(view.camera, dst, ignore_translation=True)
    return TimewarpFrame(color, outside & holes, holes, dst)


def timewarp_mode(src: Camera, dst: Camera, *, mode: str = "auto", atol: float = 1e-9) -> str:
    """The warp :func:`timewarp` uses from ``src`` to ``dst``: ``"rotation"`` or ``"depth"``
    (``mode`` itself unless it is ``"auto"``: rotation when the centres coincide within
    ``atol`` scene units). A caller checks with it, before any work, whether a list of poses
    needs the view's depth."""
    _check_camera("src", src)
    _check_camera("dst", dst)
    check_choice("mode", mode, MODES)
    tol = check_finite_scalar("atol", atol)
    if tol < 0:
        raise ValueError(f"atol: expected a distance >= 0 (scene units), got {atol!r}")
    if mode != "auto":
        return mode
    return "depth" if np.linalg.norm(src.position - dst.position) > tol else "rotation"


def timewarp(view: View, dst: Camera, *, mode: str = "auto", atol: float = 1e-9) -> TimewarpFrame:
    """Warp a rendered frame (ideally a guard-band render) to the display camera ``dst``.

    ``mode``: ``"rotation"`` (homography, ignoring any translation), ``"depth"`` (through the
    renderer with the view's depth), ``"auto"`` (rotation when the centers coincide within
    ``atol``, otherwise depth).
    """
    if not isinstance(view, View):
        raise TypeError(f"view: expected a View, got {type(view).__name__}")
    mode = timewarp_mode(view.camera, dst, mode=mode, atol=atol)  # checks dst
    if mode == "rotation":
        return warp_rotation(view.color, view.camera, dst, ignore_translation=True)
    view.require_depth("a depth time-warp")
    return _depth_warp(view, dst)


@dataclass(frozen=True, eq=False)
class UpconvertResult:
    """Frames of :func:`upconvert`: ``frames`` (list of display images), ``rendered`` (bool per
    frame: fully rendered rather than warped), ``source_index`` (the rendered pose each frame
    was warped from), ``psnr_db`` (per frame vs the reference, or None), ``outside_fraction``."""

    frames: list
    rendered: np.ndarray
    source_index: np.ndarray
    psnr_db: np.ndarray | None
    outside_fraction: np.ndarray


def _psnr(a: np.ndarray, b: np.ndarray, peak: float) -> float:
    mse = float(np.mean((np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2))
    return float("inf") if mse == 0 else 10 * np.log10(peak**2 / mse)


def upconvert(render_frame: Callable[[Camera], View], cameras: Sequence[Camera], *, every: int = 6,
              margin_px: int = 32, mode: str = "auto",
              reference: Callable[[Camera], np.ndarray] | None = None) -> UpconvertResult:
    """Frame-rate up-conversion by time-warp: render every ``every``-th pose, warp the rest.

    Parameters
    ----------
    render_frame : callable(Camera) -> View
        Renders color (+ depth for depth warps) for a camera; called with guard-band cameras.
    cameras : sequence of Camera
        Display cameras at the display rate (e.g. 60 per second); ``every = 6`` renders 10/s.
    margin_px : int
        Guard band on every side (:func:`guard_band_camera`).
    mode : {"auto", "rotation", "depth"}
        Warp of the in-between frames (see :func:`timewarp`).
    reference : callable(Camera) -> array, optional
        Fully rendered display frame for a camera; gives the per-frame PSNR (peak 1 for float,
        the dtype maximum for integers).
    """
    cams = [_check_camera(f"cameras[{i}]", c) for i, c in enumerate(cameras)]
    if not cams:
        raise ValueError("cameras: expected at least one camera")
    if isinstance(every, bool) or int(every) != every or every < 1:
        raise ValueError(f"every: expected an integer >= 1, got {every!r}")
    check_choice("mode", mode, MODES)
    frames, src_idx, psnr, outside = [], [], [], []
    base = None
    for i, cam in enumerate(cams):
        k = (i // every) * every
        if i == k:
            band = render_frame(guard_band_camera(cams[k], margin_px=margin_px))
            if not isinstance(band, View):
                raise TypeError(f"render_frame: expected a View, got {type(band).__name__}")
            base = band
        fr = timewarp(base, cam, mode=mode)
        frames.append(fr.color)
        src_idx.append(k)
        outside.append(float(fr.outside.mean()))
        if reference is not None:
            ref = np.asarray(reference(cam))
            peak = float(np.iinfo(ref.dtype).max) if ref.dtype.kind in "ui" else 1.0
            psnr.append(_psnr(fr.color, ref, peak))
    idx = np.array(src_idx)
    return UpconvertResult(frames, idx == np.arange(len(cams)), idx,
                           None if reference is None else np.array(psnr), np.array(outside))
