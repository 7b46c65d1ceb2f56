"""Content for a canvas: an image of any size resampled once to the canvas buffer.

Seed 004 (section 2.3) copies a ``Width x Height`` image into a ``T x T`` power-of-two texture
(``T = 2^n``) through ``x1 = f_x x0``, ``y1 = f_y y0`` (its eq. 4) and fills the gaps bilinearly
(eqs. 7-9). Its eqs. 5-6 print ``f_x = ceil(Height / T)`` and ``f_y = ceil(Width / T)``: width and
height are swapped and the ratio is inverted (for a 728 x 480 video frame into T = 1024 they
give 1 and 1, i.e. no scaling at all). What the seed means, built here (DESIGN.md section 3):

    f_x = T / Width,    f_y = T / Height                               (:func:`texture_scale`)

with the pixel-centre convention of the engine, ``x1 + 1/2 = f_x (x0 + 1/2)``: the image's outer
edges land on the texture's outer edges. Enlarging is bilinear (``cv2.INTER_LINEAR``, exactly the
seed's eqs. 7-9 at those positions); reducing an axis uses ``cv2.INTER_AREA`` (box filter), which
bilinear interpolation would alias.

The power-of-two texture is kept as an option (``power_of_two=True``); by default the canvas
takes the image's own resolution, i.e. no resampling at all.
"""

from __future__ import annotations

import cv2
import numpy as np

from ..base.validate import check_image, check_number
from .plane import Canvas

__all__ = ["canvas_from_image", "image_to_rgba", "power_of_two_size", "resample", "set_image", "texture_scale"]


def power_of_two_size(width: int, height: int) -> int:
    """Smallest ``T = 2^n`` (n >= 1) with ``T >= max(width, height)`` (seed 004's texture size)."""
    width = check_number("width", width, integer=True, minimum=1)
    height = check_number("height", height, integer=True, minimum=1)
    return max(2, 1 << (max(width, height) - 1).bit_length())


def texture_scale(width: int, height: int, t: int) -> tuple[float, float]:
    """``(f_x, f_y) = (T / width, T / height)``: seed 004 eqs. 5-6 corrected (see module doc).

    Example: a 728 x 480 frame into a 1024 x 1024 texture: ``(1.4066, 2.1333)``.
    """
    width, height, t = (check_number(name, v, integer=True, minimum=1)
                        for name, v in (("width", width), ("height", height), ("t", t)))
    return t / width, t / height


def _resize_axis(img: np.ndarray, w: int, h: int) -> np.ndarray:
    sh, sw = img.shape[:2]
    if (w, h) == (sw, sh):
        return img
    shrink = w <= sw and h <= sh
    grow = w >= sw and h >= sh
    if shrink or grow:
        return cv2.resize(img, (w, h), interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)
    # one axis grows, the other shrinks: one pass per axis
    return _resize_axis(_resize_axis(img, w, sh), w, h)


def resample(image, resolution) -> np.ndarray:
    """``image`` (H, W[, C]) resampled to ``resolution = (W', H')`` (same dtype; C <= 4).

    Pixel centres map by ``x' + 1/2 = (W'/W) (x + 1/2)``; bilinear when enlarging, box filter
    (``INTER_AREA``) when reducing.
    """
    img = check_image("image", image)
    if img.ndim == 3 and img.shape[2] > 4:
        raise ValueError(f"image: at most 4 channels, got shape {img.shape}")
    if np.ndim(resolution) != 1 or len(resolution) != 2:
        raise ValueError(f"resolution: expected (W, H), got {resolution!r}")
    w, h = (check_number(f"resolution[{i}]", r, integer=True, minimum=1) for i, r in enumerate(resolution))
    src = img if img.dtype in (np.uint8, np.uint16, np.float32) else img.astype(np.float32)
    out = _resize_axis(np.ascontiguousarray(src), w, h)
    if img.ndim == 3 and out.ndim == 2:
        out = out[..., None]
    return out


def _scale_of(dtype: np.dtype) -> float:
    return {"uint8": 255.0, "uint16": 65535.0}.get(np.dtype(dtype).name, 1.0)


def _check_pixel_dtype(img: np.ndarray) -> None:
    """A canvas image holds uint8, uint16 or float pixels (ValueError naming ``image``)."""
    if img.dtype.kind != "f" and img.dtype not in (np.uint8, np.uint16):
        raise ValueError(f"image: expected uint8, uint16 or float pixels, got {img.dtype}")


def image_to_rgba(image, dtype=np.uint8) -> np.ndarray:
    """(H, W, 4) straight-alpha RGBA of ``dtype`` from a gray, gray+alpha, RGB or RGBA image.

    Values are rescaled between dtypes (uint8 255 = uint16 65535 = float 1.0); images without
    alpha are opaque. Float input must lie in [0, 1] (NaN is refused).
    """
    img = check_image("image", image, channels=(1, 2, 3, 4))
    if img.dtype.kind == "f":
        if not np.all(np.isfinite(img)):
            raise ValueError("image: float image contains NaN or inf")
        lo, hi = float(img.min()), float(img.max())
        if lo < -1e-6 or hi > 1 + 1e-6:  # float64 was clipped on conversion, float32 kept as is: neither (#12)
            raise ValueError(f"image: float pixels must lie in [0, 1] (1.0 = white), got values in [{lo:g}, {hi:g}]; "
                             "scale the image (e.g. / 255) or pass uint8/uint16")
    else:
        _check_pixel_dtype(img)
    if img.ndim == 2:
        img = img[..., None]
    c = img.shape[2]
    dtype = np.dtype(dtype)
    same = img.dtype == dtype
    if c == 3 and same and dtype == np.uint8:
        return cv2.cvtColor(np.ascontiguousarray(img), cv2.COLOR_RGB2RGBA)
    f = 1.0 if same else _scale_of(dtype) / _scale_of(img.dtype)
    src = img if same else img.astype(np.float64) * f
    out = np.empty(img.shape[:2] + (4,), np.float64 if not same else dtype)
    if c in (1, 2):
        out[..., :3] = src[..., :1]
    else:
        out[..., :3] = src[..., :3]
    out[..., 3] = src[..., -1] if c in (2, 4) else _scale_of(dtype)
    if same:
        return out
    if dtype.kind == "u":
        return np.clip(np.rint(out), 0, _scale_of(dtype)).astype(dtype)
    return np.clip(out, 0.0, 1.0).astype(dtype)


def set_image(canvas: Canvas, image) -> None:
    """Write ``image`` into ``canvas.rgba``, resampled once to the canvas resolution.

    The fast path of a video frame whose size equals the canvas's is one conversion pass, no
    resampling.
    """
    if not isinstance(canvas, Canvas):
        raise TypeError(f"canvas: expected a Canvas, got {type(canvas).__name__}")
    img = check_image("image", image, channels=(1, 2, 3, 4))
    _check_pixel_dtype(img)  # before resample() makes an int64 image float32
    w, h = canvas.resolution
    if img.shape[:2] != (h, w):
        img = resample(img, (w, h))
    canvas.rgba[...] = image_to_rgba(img, canvas.rgba.dtype)


def canvas_from_image(image, center, normal, size, *, up=(0.0, -1.0, 0.0), resolution=None,
                      power_of_two: bool = False, name: str = "image") -> Canvas:
    """A canvas showing ``image`` on the world rectangle ``(center, normal, up, size)``.

    Parameters
    ----------
    image : (H, W[, C]) array
        uint8, uint16 or float ([0, 1]) pixels; gray, gray+alpha, RGB or RGBA.
    center, normal, size, up
        Geometry, see :class:`~ibr.canvas.Canvas`.
    resolution : (W', H'), optional
        Buffer size; default the image's own size (no resampling).
    power_of_two : bool
        Seed 004's square ``T x T`` texture, ``T`` = :func:`power_of_two_size` of the image,
        filled with the corrected scale factors of :func:`texture_scale`.

    Returns
    -------
    Canvas
        Buffer dtype uint8 for uint8 images, uint16 for uint16, float32 otherwise.
    """
    img = check_image("image", image, channels=(1, 2, 3, 4))
    h, w = img.shape[:2]
    if power_of_two:
        if resolution is not None:
            raise ValueError("resolution: give either resolution or power_of_two=True, not both")
        t = power_of_two_size(w, h)
        resolution = (t, t)
    elif resolution is None:
        resolution = (w, h)
    dtype = img.dtype if img.dtype in (np.uint8, np.uint16) else np.float32
    canvas = Canvas(center, normal, size, up=up, resolution=resolution, dtype=dtype, name=name)
    set_image(canvas, img)
    return canvas
