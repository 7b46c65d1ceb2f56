"""Photo sets with exact truth: perspective photos cut out of an equirect at known rotations.

* :func:`photo_sphere` builds a textured equirect quickly: six scikit-image photographs as the
  six cube faces (+x immunohistochemistry, -x coffee, +y floor gravel, -y sky grass, +z
  astronaut, -z chelsea; grey ones tinted), resampled with :func:`panorama.cubemap_to_equirect`.
  Natural texture everywhere (SIFT finds features on every face), exact and deterministic.
* :func:`ring_poses` lists (yaw, pitch) of rings of photos.
* :func:`cut_photos` renders each photo with :func:`panorama.perspective` (exact ray per pixel
  centre, ``Camera.from_fov``: fx = w / (2 tan(hfov/2)), cx = (w - 1)/2), multiplies it by an
  exposure gain, adds Gaussian noise and quantizes to uint8, and returns the true
  :class:`ibr.Camera` of each photo (``world_from_cam = world_from_view(yaw, pitch, roll)``).
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ibr.base.camera import Camera

from ..convert import cubemap_to_equirect, perspective
from ..directions import world_from_view

__all__ = ["PhotoSet", "cut_photos", "footprint_masks", "photo_sphere", "psnr", "ring_poses", "rotation_errors_deg",
           "seam_band"]

_FACES = ("immunohistochemistry", "coffee", "gravel", "grass", "astronaut", "chelsea")
_TINT = {"gravel": (1.0, 0.9, 0.75), "grass": (0.6, 0.8, 1.0)}


def photo_sphere(width: int = 2048) -> np.ndarray:
    """(width/2, width, 3) float32 equirect in [0, 1] from six scikit-image photos as cube faces
    (face size width / 4)."""
    import skimage.data

    s = int(width) // 4
    faces = []
    for name in _FACES:
        im = getattr(skimage.data, name)()
        if im.ndim == 2:
            im = np.stack([im] * 3, -1).astype(np.float32) * np.asarray(_TINT[name], np.float32)
        im = im[..., :3].astype(np.float32) / 255.0
        h, w = im.shape[:2]
        m = min(h, w)
        im = im[(h - m) // 2:(h - m) // 2 + m, (w - m) // 2:(w - m) // 2 + m]
        interp = cv2.INTER_AREA if m > s else cv2.INTER_CUBIC
        faces.append(np.clip(cv2.resize(im, (s, s), interpolation=interp), 0, 1))
    return cubemap_to_equirect(faces, int(width), int(width) // 2, layout="list")


def ring_poses(rings=((0.0, 8),), *, yaw0: float = 0.0) -> list[tuple[float, float]]:
    """(yaw, pitch) degrees of rings: ``rings`` is ((pitch, count), ...); ring k is turned by
    ``yaw0 + 180 k / count`` so rings interleave."""
    out = []
    for k, (pitch, count) in enumerate(rings):
        off = 0.0 if k == 0 else 180.0 / count
        out += [(yaw0 + off + 360.0 * i / count, float(pitch)) for i in range(int(count))]
    return out


@dataclass
class PhotoSet:
    """Photos cut from a panorama: ``images`` (uint8), true ``cameras``, ``gains`` applied."""

    images: list
    cameras: list
    gains: np.ndarray


def cut_photos(pano: np.ndarray, poses, *, width: int = 480, height: int = 360, hfov_deg: float = 75.0,
               gains=None, gain_spread: float = 0.0, noise: float = 0.0, roll_deg=0.0,
               seed: int = 0) -> PhotoSet:
    """Perspective photos of ``pano`` (float [0, 1] equirect) at ``poses`` [(yaw, pitch), ...].

    ``gains`` (one per photo) or ``gain_spread`` (uniform in [1 - spread, 1 + spread], photo 0
    at 1) scale each photo; ``noise`` is the Gaussian sigma in [0, 1] units; results are
    uint8. ``roll_deg`` is one roll for all or one per photo.
    """
    rng = np.random.default_rng(seed)
    n = len(poses)
    if gains is None:
        gains = rng.uniform(1 - gain_spread, 1 + gain_spread, n)
        gains[0] = 1.0
    gains = np.asarray(gains, np.float64)
    rolls = np.broadcast_to(np.asarray(roll_deg, np.float64), (n,))
    images, cams = [], []
    for k, (yaw, pitch) in enumerate(poses):
        view = perspective(pano, yaw_deg=yaw, pitch_deg=pitch, roll_deg=float(rolls[k]), fov_deg=hfov_deg,
                           width=width, height=height)
        view = view * gains[k] + (rng.normal(0.0, noise, view.shape) if noise > 0 else 0.0)
        images.append(np.clip(np.rint(view * 255.0), 0, 255).astype(np.uint8))
        pose = np.eye(4)
        pose[:3, :3] = world_from_view(yaw, pitch, float(rolls[k]))
        cams.append(Camera.from_fov(width, height, hfov_deg=hfov_deg, world_from_cam=pose))
    return PhotoSet(images, cams, gains)


def footprint_masks(cameras, width: int) -> list[np.ndarray]:
    """(H, W) bool per camera: equirect pixels (width x width/2) whose centre ray lands inside
    the photo ([-0.5, w - 0.5] x [-0.5, h - 0.5], in front of the camera)."""
    from ..directions import equirect_directions

    d = equirect_directions(int(width), int(width) // 2)
    out = []
    for cam in cameras:
        c = d @ cam.world_from_cam[:3, :3]
        z = c[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            u = cam.fx * c[..., 0] / z + cam.cx
            v = cam.fy * c[..., 1] / z + cam.cy
        out.append((z > 0) & (u >= -0.5) & (u <= cam.width - 0.5) & (v >= -0.5) & (v <= cam.height - 0.5))
    return out


def seam_band(cameras, width: int, px: int = 8) -> np.ndarray:
    """(H, W) bool: pixels within ``px`` pixels of any photo's footprint boundary (the places a
    seam or a photo edge can show)."""
    kernel = np.ones((3, 3), np.uint8)
    edge = np.zeros((int(width) // 2, int(width)), np.uint8)
    for m in footprint_masks(cameras, width):
        m8 = m.astype(np.uint8)
        edge |= m8 ^ cv2.erode(m8, kernel, borderType=cv2.BORDER_REPLICATE)
    band = cv2.dilate(edge, np.ones((2 * px + 1, 2 * px + 1), np.uint8))
    return band.astype(bool)


def psnr(a: np.ndarray, b: np.ndarray, mask: np.ndarray | None = None, peak: float = 1.0) -> float:
    """PSNR (dB) of ``a`` against ``b`` (same units, e.g. [0, 1]) over ``mask``."""
    d = np.asarray(a, np.float64) - np.asarray(b, np.float64)
    if mask is not None:
        d = d[mask]
    mse = float(np.mean(d ** 2))
    return float("inf") if mse == 0 else 10 * np.log10(peak ** 2 / mse)


def rotation_errors_deg(estimated, truth) -> np.ndarray:
    """Angle (degrees) of R_est^T R_true per pair of cameras (None entries give NaN)."""
    out = []
    for e, t in zip(estimated, truth):
        if e is None:
            out.append(np.nan)
            continue
        r = e.world_from_cam[:3, :3].T @ t.world_from_cam[:3, :3]
        out.append(np.degrees(np.arccos(np.clip((np.trace(r) - 1) / 2, -1.0, 1.0))))
    return np.array(out)
