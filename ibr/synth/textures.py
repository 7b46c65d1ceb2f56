"""Textures for the synthetic scenes: images from scikit-image sampled bilinearly in float.

Texel convention (same as pixels, DESIGN.md section 4): texel (i, j) = (column, row) has its
center at integer coordinates, so texel coordinate x = 0.0 is the center of column 0 and
x = -0.5 its left edge. Outside the image the texture repeats *mirrored* (period 2W): the
mirror makes every tile boundary continuous, so tiled photographs show no seams.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

__all__ = ["ImageTexture", "image_texture", "checker_texture", "TEXTURE_NAMES"]

# Photographs bundled with scikit-image (no download needed) and a tint for the gray ones.
_SOURCES = {
    "brick": (0.95, 0.55, 0.42),
    "grass": (0.45, 0.78, 0.35),
    "gravel": (0.82, 0.78, 0.70),
    "astronaut": None,
    "coffee": None,
    "chelsea": None,
    "rocket": None,
    "immunohistochemistry": None,
    "hubble_deep_field": None,
    "camera": (0.85, 0.85, 0.9),
    "moon": (0.9, 0.88, 0.8),
}
TEXTURE_NAMES = tuple(sorted(_SOURCES)) + ("checker",)


@dataclass(frozen=True, eq=False)
class ImageTexture:
    """A float32 RGB image in [0, 1] plus its physical size.

    Parameters
    ----------
    image : (H, W, 3) float32
        Texel colors (linear reflectance, i.e. albedo) in [0, 1]. Stored read-only.
    width_units : float
        Scene units spanned by the image width (W texels) when mapped onto a plane; texels are
        square, so the height spans ``width_units * H / W``. Spheres ignore it (lat/long map).
    name : str
        Label (the scikit-image source), for repr and docs.
    """

    image: np.ndarray
    width_units: float = 1.0
    name: str = "texture"

    def __post_init__(self):
        img = np.asarray(self.image, dtype=np.float32)
        if img.ndim != 3 or img.shape[2] != 3:
            raise ValueError(f"image: expected shape (H, W, 3), got {img.shape}")
        if not float(self.width_units) > 0:
            raise ValueError(f"width_units: expected a positive number, got {self.width_units!r}")
        img = np.ascontiguousarray(img)
        img.setflags(write=False)
        object.__setattr__(self, "image", img)
        object.__setattr__(self, "width_units", float(self.width_units))

    @property
    def texel_units(self) -> float:
        """Scene units per texel on a plane."""
        return self.width_units / self.image.shape[1]

    def scaled(self, width_units: float) -> "ImageTexture":
        """Same image, another physical size."""
        return ImageTexture(self.image, width_units, self.name)

    def sample_plane(self, s: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Albedo at plane coordinates ``(s, t)`` in scene units (s along the image's columns).

        ``(s, t) = (0, 0)`` is the top-left *corner* of the image (edge of texel (0, 0)), so the
        texel coordinate is ``x = s / texel_units - 0.5``.
        """
        k = 1.0 / self.texel_units
        return sample_bilinear(self.image, s * k - 0.5, t * k - 0.5)

    def sample_unit(self, x01: np.ndarray, y01: np.ndarray) -> np.ndarray:
        """Albedo at normalized coordinates in [0, 1] x [0, 1] (corner to corner of the image)."""
        h, w = self.image.shape[:2]
        return sample_bilinear(self.image, x01 * w - 0.5, y01 * h - 0.5)


def _mirror(i: np.ndarray, n: int) -> np.ndarray:
    """Mirrored-repeat index (period 2n, edge texel repeated): ..., 1, 0 | 0, 1, ..., n-1 | n-1, ..."""
    i = np.mod(i, 2 * n)
    return np.where(i >= n, 2 * n - 1 - i, i)


def sample_bilinear(image: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Bilinear lookup of ``image`` (H, W, C) at float texel coordinates, mirrored repeat.

    Pixel-center convention: ``x = 3.0`` is the center of column 3 and returns it exactly;
    ``x = 3.5`` is the average of columns 3 and 4. Weights are computed in float64.
    Returns float32 (..., C).
    """
    h, w = image.shape[:2]
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    x0 = np.floor(x)
    y0 = np.floor(y)
    fx = (x - x0)[..., None]
    fy = (y - y0)[..., None]
    x0 = x0.astype(np.int64)
    y0 = y0.astype(np.int64)
    i0, i1 = _mirror(x0, w), _mirror(x0 + 1, w)
    j0, j1 = _mirror(y0, h), _mirror(y0 + 1, h)
    top = image[j0, i0] * (1 - fx) + image[j0, i1] * fx
    bot = image[j1, i0] * (1 - fx) + image[j1, i1] * fx
    return (top * (1 - fy) + bot * fy).astype(np.float32)


@lru_cache(maxsize=None)
def _photo(name: str) -> np.ndarray:
    import skimage.data
    from skimage.filters import gaussian

    img = getattr(skimage.data, name)()
    if img.ndim == 3 and img.shape[2] == 4:
        img = img[..., :3]
    img = img.astype(np.float32) / 255.0
    tint = _SOURCES[name]
    if img.ndim == 2:
        # Gray photo -> tinted RGB; stretch contrast a little around the mean.
        img = np.clip(0.25 + 0.75 * img, 0, 1)[..., None] * np.asarray(tint, np.float32)
    # A light pre-filter (sigma 0.6 texel) keeps minified textures from aliasing too much.
    img = gaussian(img, sigma=0.6, channel_axis=-1, preserve_range=True, mode="reflect")
    img = np.clip(img, 0, 1).astype(np.float32)
    img.setflags(write=False)
    return img


def image_texture(name: str, width_units: float = 1.0) -> ImageTexture:
    """Texture from a photograph bundled with scikit-image (``TEXTURE_NAMES``)."""
    if name == "checker":
        return checker_texture(width_units=width_units)
    if name not in _SOURCES:
        raise ValueError(f"texture: expected one of {', '.join(map(repr, TEXTURE_NAMES))}, got {name!r}")
    return ImageTexture(_photo(name), width_units, name)


@lru_cache(maxsize=None)
def _checker(cells_x: int, cells_y: int, c0: tuple, c1: tuple, cell_px: int) -> np.ndarray:
    iy, ix = np.mgrid[0 : cells_y * cell_px, 0 : cells_x * cell_px] // cell_px
    odd = ((ix + iy) % 2).astype(bool)
    img = np.where(odd[..., None], np.asarray(c1, np.float32), np.asarray(c0, np.float32))
    img = np.ascontiguousarray(img, dtype=np.float32)
    img.setflags(write=False)
    return img


def checker_texture(
    *,
    cells_x: int = 16,
    cells_y: int = 8,
    color0=(0.92, 0.9, 0.85),
    color1=(0.2, 0.25, 0.55),
    width_units: float = 1.0,
    cell_px: int = 16,
) -> ImageTexture:
    """Checkerboard image texture (sampled bilinearly like the photographs)."""
    img = _checker(int(cells_x), int(cells_y), tuple(map(float, color0)), tuple(map(float, color1)), int(cell_px))
    return ImageTexture(img, width_units, "checker")
