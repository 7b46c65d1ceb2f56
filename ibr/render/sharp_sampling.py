"""Sharp colour sampling at bilinear speed: bilinear taps on a source upsampled 2 x 2 once.

Bilinear interpolation at a fractional offset is a low-pass filter: half-way between two pixels
it averages them, and a rendered view whose pixels mostly fall between source pixels comes out
visibly softer than the source (the synthetic pairs' textures lose 1-1.5 dB against their ground
truth). Bicubic sampling keeps them crisp but costs 2.8x the 512x512 frame (OpenCV's bicubic
remap has no SIMD path for 8-bit colour). Here each source is upsampled 2 x 2 once, by a
co-sited Lanczos-3 interpolation (the source's own pixels stay at the even positions, the new
ones are Lanczos-3 half-way samples), and every frame samples that image bilinearly at twice the
map coordinates: the taps are then never more than a quarter source pixel from their position,
so the blur of the bilinear weights is a quarter of what it was, and the sharpness is the
Lanczos interpolation's. At a source pixel's own position (map coordinates integers) the result
is that pixel exactly, so a view warped into its own camera comes back unchanged.

Measured (``python benchmarks/bench_edges.py --quick``, issue 11; covered pixels of the bundled
pairs, t = .25/.5/.75): see docs/render.md ("Sharp sampling").
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["SHARP_SCALE", "half_sample_kernel", "half_way_columns", "upsample_cosited", "upsample_rgbt"]

#: The factor of the upsampled sources: map coordinates are multiplied by it (a power of two:
#: the product, and its inverse back, are exact in float32).
SHARP_SCALE = 2

#: Lanczos window (lobes) of the half-way samples.
_LANCZOS_A = 3

#: Rows per strip of the horizontal pass.
_ROWS = 64


def half_sample_kernel(a: int = _LANCZOS_A) -> np.ndarray:
    """(2a,) float32: Lanczos-a weights of the samples at offsets -a+1 .. a from a position
    half-way between sample 0 and sample 1 (normalized to sum 1)."""
    if isinstance(a, bool) or not isinstance(a, (int, np.integer)) or a < 1:
        raise ValueError(f"a: expected a positive integer (Lanczos lobes), got {a!r}")
    x = np.arange(-a + 1, a + 1) - 0.5
    k = np.sinc(x) * np.sinc(x / a)
    return (k / k.sum()).astype(np.float32)


_KERNEL = half_sample_kernel()


def _lanczos_half_way(image: np.ndarray, axis: int, dst: np.ndarray | None = None) -> np.ndarray:
    """The Lanczos-3 samples half-way between each pixel and the next along ``axis`` (0 rows, 1
    columns), unclamped; past the last pixel the border pixel repeats. Same dtype (rounded and
    saturated)."""
    k = _KERNEL.reshape(1, -1) if axis == 1 else _KERNEL.reshape(-1, 1)
    anchor = (_LANCZOS_A - 1, 0) if axis == 1 else (0, _LANCZOS_A - 1)  # taps at -a+1 .. a
    if dst is None:
        return cv2.filter2D(image, -1, k, anchor=anchor, borderType=cv2.BORDER_REPLICATE)
    return cv2.filter2D(image, -1, k, dst=dst, anchor=anchor, borderType=cv2.BORDER_REPLICATE)


def _half_way(image: np.ndarray, axis: int, edges: np.ndarray | None, dst: np.ndarray | None = None) -> np.ndarray:
    """Samples half-way between each pixel and the next along ``axis`` (0 rows, 1 columns);
    past the last pixel the border pixel repeats. Same dtype (rounded and saturated). Each is
    clamped to the range of its two pixels, and where one of the six Lanczos taps lies on
    ``edges`` (a depth discontinuity) it is the plain mean of the two instead (bilinear: nothing
    is carried across a silhouette)."""
    out = _lanczos_half_way(image, axis, dst)
    anchor = (_LANCZOS_A - 1, 0) if axis == 1 else (0, _LANCZOS_A - 1)  # taps at -a+1 .. a
    # no overshoot: within the range of the two pixels it lies between (Lanczos' lobes made flat
    # areas beside texture change with the sub-pixel phase: a sequence's flicker 0.36 -> 0.56 levels)
    n = image.shape[axis]
    for r0 in range(0, image.shape[0], _ROWS):  # strips of rows: small temporaries
        r1 = min(r0 + _ROWS, image.shape[0])
        a = image[r0:r1]
        if axis == 1:
            b = np.concatenate([a[:, 1:], a[:, -1:]], 1)
        else:  # the next row, the last one repeated
            b = image[np.minimum(np.arange(r0 + 1, r1 + 1), n - 1)]
        np.clip(out[r0:r1], np.minimum(a, b), np.maximum(a, b), out=out[r0:r1])
    if edges is not None and edges.any():
        taps = np.ones((1, 2 * _LANCZOS_A) if axis == 1 else (2 * _LANCZOS_A, 1), np.uint8)
        near = cv2.dilate(edges.view(np.uint8), taps, anchor=anchor, borderType=cv2.BORDER_REPLICATE)
        ys, xs = np.nonzero(near)  # few pixels: the mean there only (no image-sized temporaries)
        ys1, xs1 = (ys, np.minimum(xs + 1, image.shape[1] - 1)) if axis == 1 else (np.minimum(ys + 1, image.shape[0] - 1), xs)
        a, b = image[ys, xs], image[ys1, xs1]
        if image.dtype.kind == "f":
            out[ys, xs] = (a + b) * 0.5
        else:  # rounded half up, as the filters round
            out[ys, xs] = (a.astype(np.int32) + b + 1) >> 1
    return out


def half_way_columns(image: np.ndarray, edges: np.ndarray | None = None, *, clamp: bool = True) -> np.ndarray:
    """The samples half-way between each pixel and the next one on its row: the odd columns of
    :func:`upsample_cosited` on the source's rows, for warps that keep rows (a stereo eye,
    :func:`ibr.stereo.map_pixels`), which need no other half-way sample.

    Parameters
    ----------
    image : (H, W) or (H, W, C) array, C <= 4
        uint8, uint16 or float32.
    edges : (H, W) bool, optional
        Pixels beside a depth discontinuity: no Lanczos tap reaches across them (the plain mean
        of the two pixels there).
    clamp : bool
        Clamp each sample to the range of its two pixels (as :func:`upsample_cosited` does).
        ``False`` (and no ``edges``) gives the plain Lanczos-3 samples, for a caller that clamps
        and checks depth steps itself (method 2's row kernel does, 4x faster than here).

    Returns
    -------
    Array of ``image``'s shape and dtype: element (y, x) lies at x + 0.5 (pixel centres at
    integers; the last column repeats the border pixel).
    """
    img = _check_image(image, edges)
    if not clamp and edges is not None:
        raise ValueError("edges: only with clamp=True (unclamped samples are the plain Lanczos ones)")
    if img.ndim == 3 and img.shape[2] == 1:  # OpenCV's filters return one channel as (H, W)
        return half_way_columns(img[..., 0], edges, clamp=clamp)[..., None]
    img = np.ascontiguousarray(img)
    if not clamp:
        return _lanczos_half_way(img, 1)
    return _half_way(img, 1, None if edges is None else np.ascontiguousarray(edges, dtype=bool))


def _check_image(image, edges) -> np.ndarray:
    img = np.asarray(image)
    if img.ndim not in (2, 3) or (img.ndim == 3 and not 1 <= img.shape[2] <= 4) or min(img.shape[:2]) < 1:
        raise ValueError(f"image: expected (H, W) or (H, W, C <= 4), got shape {img.shape}")
    if img.dtype not in (np.uint8, np.uint16, np.float32):
        raise ValueError(f"image: expected uint8, uint16 or float32, got {img.dtype}")
    if edges is not None and np.shape(edges) != img.shape[:2]:
        raise ValueError(f"edges: expected shape {img.shape[:2]}, got {np.shape(edges)}")
    return img


def upsample_cosited(image: np.ndarray, edges: np.ndarray | None = None) -> np.ndarray:
    """``image`` upsampled 2 x 2, co-sited: output pixel (2y, 2x) is input pixel (y, x)
    exactly; the others are Lanczos-3 half-way samples clamped to the range of their two pixels
    (separable; the border repeats), or the mean of the two where a tap lies on ``edges``.

    Parameters
    ----------
    image : (H, W) or (H, W, C) array, C <= 4
        uint8, uint16 or float32 (8-bit and 16-bit results are rounded and saturated).
    edges : (H, W) bool, optional
        Pixels beside a depth discontinuity (:func:`ibr.base.depth.depth_steps`): no Lanczos tap reaches
        across them.

    Returns
    -------
    (2H, 2W[, C]) array of the same dtype. A map coordinate x of ``image`` (pixel centres at
    integers) is 2x in the result.
    """
    img = _check_image(image, edges)
    edges = None if edges is None else np.ascontiguousarray(edges, dtype=bool)
    if img.ndim == 3 and img.shape[2] == 1:  # OpenCV's filters return one channel as (H, W)
        return upsample_cosited(img[..., 0], edges)[..., None]
    h, w = img.shape[:2]
    out = np.empty((2 * h, 2 * w, *img.shape[2:]), img.dtype)
    out[0::2, 0::2] = img
    _fill_half_way(out, edges)
    return out


def _fill_half_way(out: np.ndarray, edges: np.ndarray | None) -> None:
    """Write the half-way samples of a (2H, 2W[, C]) image whose even rows and columns hold the
    source (:func:`upsample_cosited`'s second step; callers may fill those from several arrays)."""
    h, w = out.shape[0] // 2, out.shape[1] // 2
    even = out[0::2]  # rows of the source (each row contiguous: OpenCV reads and writes them in place)
    for r0 in range(0, h, _ROWS):  # in strips: no image-sized temporary (peak memory at 1080p)
        r1 = min(r0 + _ROWS, h)
        strip = np.ascontiguousarray(even[r0:r1, 0::2])
        even[r0:r1, 1::2] = _half_way(strip, 1, None if edges is None else edges[r0:r1])
    odd = out[1::2]
    edges2 = None if edges is None else np.repeat(edges, 2, axis=1)
    if edges2 is not None:  # a half-way column touches the edges of both its pixels
        edges2[:, 1::2] |= np.concatenate([edges[:, 1:], edges[:, -1:]], 1)
    got = _half_way(even, 0, edges2, dst=odd)
    if got is not odd and not np.shares_memory(got, odd):  # OpenCV could not write in place
        odd[...] = got


def upsample_rgbt(color: np.ndarray, trust: np.ndarray, edges: np.ndarray | None = None) -> np.ndarray:
    """:func:`upsample_cosited` of the (H, W, 4) uint8 image that is ``color`` (H, W, 3) uint8
    with ``trust`` (H, W) uint8 as its fourth channel, built without that image (one frame-sized
    temporary less: peak memory of a 1920 x 1080 interpolation)."""
    color, trust = np.asarray(color), np.asarray(trust)
    if color.ndim != 3 or color.shape[2] != 3 or color.dtype != np.uint8 or min(color.shape[:2]) < 1:
        raise ValueError(f"color: expected (H, W, 3) uint8, got {color.dtype} {color.shape}")
    h, w = color.shape[:2]
    if trust.shape != (h, w) or trust.dtype != np.uint8:
        raise ValueError(f"trust: expected ({h}, {w}) uint8, got {trust.dtype} {trust.shape}")
    if edges is not None and np.shape(edges) != (h, w):
        raise ValueError(f"edges: expected shape {(h, w)}, got {np.shape(edges)}")
    out = np.empty((2 * h, 2 * w, 4), np.uint8)
    out[0::2, 0::2, :3] = color
    out[0::2, 0::2, 3] = trust
    _fill_half_way(out, edges)
    return out
