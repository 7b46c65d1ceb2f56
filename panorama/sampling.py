"""How to sample: one ``cv2.remap`` wrapper, seam-free padding and area pre-filtering.

* :func:`remap` samples any image with a :class:`panorama.maps.SampleMap` (float32 maps; OpenCV
  5 uses the float coordinates without the 1/32-pixel rounding of fixed-point maps).
* :func:`pad_equirect` adds one texel on every side: the columns wrap around the seam and the
  rows beyond the poles hold the row across the pole (column u + W/2), so bilinear sampling is
  continuous everywhere on the sphere.
* :func:`pad_faces` builds the padded cube atlas (faces stacked vertically, 1 texel border)
  whose border texels are *resampled* from the neighbouring faces at the exact directions of
  the border texel centres, so bilinear sampling is continuous across edges and corners
  (copying the neighbour's edge row would misplace samples by up to half a texel near corners).
* :func:`area_prefilter` reduces a source with ``cv2.INTER_AREA`` when the output samples it
  more than 1.5x more coarsely than its texels, so small previews are not aliased.
"""

from __future__ import annotations

from functools import lru_cache

import cv2
import numpy as np

from ibr.base.validate import check_choice

from .directions import WORLD_FROM_FACE, face_pixel_from_direction
from .maps import SampleMap

__all__ = ["INTERPOLATIONS", "area_prefilter", "pad_equirect", "pad_faces", "remap"]

INTERPOLATIONS = ("linear", "nearest")
_CV_INTERP = {"linear": cv2.INTER_LINEAR, "nearest": cv2.INTER_NEAREST}
PREFILTER_THRESHOLD = 1.5
#: Output pixels per source pixel from which 8-bit RGB is sampled as RGBA (see :func:`remap`)
_FOUR_CHANNEL_MIN = 0.5
#: ``cv2.remap`` asserts a source of fewer rows than this (SHRT_MAX); taller ones go in strips
_MAX_REMAP_ROWS = 32767


def _as_remappable(img: np.ndarray) -> np.ndarray:
    if img.dtype in (np.uint8, np.uint16, np.int16, np.float32):
        return img
    if img.dtype in (np.float16, np.float64):
        return img.astype(np.float32)
    if img.dtype == np.bool_:
        return img.astype(np.uint8)
    raise TypeError(f"image: expected dtype uint8, uint16, float16/32/64, got {img.dtype}")


def remap(src: np.ndarray, smap: SampleMap, *, interpolation: str = "linear", out_dtype=None,
          dst: np.ndarray | None = None) -> np.ndarray:
    """Sample ``src`` (already padded if ``smap.pad``) at ``smap``'s coordinates.

    Unpadded equirect sources use ``BORDER_WRAP`` (column -1 = column W-1); padded sources never
    sample outside. Keeps the channel axis of a (H, W, 1) input; float64/float16 inputs are
    sampled in float32 and returned as ``out_dtype`` (default: the input dtype).
    """
    check_choice("interpolation", interpolation, INTERPOLATIONS)
    out_dtype = np.dtype(out_dtype or src.dtype)
    work = _as_remappable(src)
    border = cv2.BORDER_WRAP if (smap.source == "equirect" and not smap.pad) else cv2.BORDER_REPLICATE
    flag = _CV_INTERP[interpolation]
    channels = 1 if work.ndim == 2 else work.shape[2]
    if work.shape[0] >= _MAX_REMAP_ROWS:  # a cube atlas of faces over 5458 px (6 (S + 2) rows)
        out = _remap_in_strips(work, smap, flag, border)
        if dst is not None:
            dst[...] = out.reshape(dst.shape)
            out = dst
    elif channels == 3 and work.dtype == np.uint8 and smap.map_x.size >= _FOUR_CHANNEL_MIN * work.shape[0] * work.shape[1]:
        # OpenCV 5 samples four 8-bit channels with SIMD, three without (1.6x the time per output
        # pixel): a fourth channel pays when the output has at least half the source's pixels
        # (e2c), not for a view much smaller than its panorama. Results are identical.
        out4 = cv2.remap(cv2.cvtColor(work, cv2.COLOR_RGB2RGBA), smap.map_x, smap.map_y, flag, borderMode=border)
        out = cv2.cvtColor(out4, cv2.COLOR_RGBA2RGB, dst=dst)
    else:
        out = _remap_channels(work, smap.map_x, smap.map_y, flag, border, dst)
    return out if out.dtype == out_dtype else out.astype(out_dtype)


def _remap_channels(work, map_x, map_y, flag, border, dst=None) -> np.ndarray:
    """``cv2.remap`` of any number of channels (OpenCV takes at most 4 per call); a (H, W, 1)
    input keeps its channel axis."""
    channels = 1 if work.ndim == 2 else work.shape[2]
    if channels <= 4:
        out = cv2.remap(work, map_x, map_y, flag, dst=dst, borderMode=border)
        return out[..., None] if work.ndim == 3 and out.ndim == 2 else out
    return np.concatenate([cv2.remap(work[..., c:c + 4], map_x, map_y, flag, borderMode=border)
                           .reshape(map_x.shape + (-1,)) for c in range(0, channels, 4)], axis=-1)


def _remap_in_strips(work, smap: SampleMap, flag, border) -> np.ndarray:
    """:func:`remap` of a source with too many rows for ``cv2.remap`` (it asserts fewer than
    32767): strips of rows overlapping by one row, each output pixel taken from the strip that
    holds its bilinear taps (rows floor(y) and floor(y) + 1; the first and last strips also
    take what lies above or below the image, as the border mode says)."""
    h = work.shape[0]
    step = _MAX_REMAP_ROWS - 2
    owner = np.clip(np.floor(smap.map_y) // step, 0, (h - 1) // step).astype(np.int64)
    out = None
    for k in range(int(owner.max()) + 1):
        mine = owner == k
        if not mine.any():
            continue
        r0 = k * step
        part = _remap_channels(work[r0:min(r0 + step + 1, h)], smap.map_x, smap.map_y - np.float32(r0), flag, border)
        if out is None:
            out = part
        else:
            out[mine] = part[mine]
    return out


def pad_equirect(img: np.ndarray) -> np.ndarray:
    """(H+2, W+2[, C]) copy of an equirect image with a one-texel border.

    Columns -1 and W are columns W-1 and 0 (wrap). Row -1 at column u is row 0 at column
    u + W/2 (the texel across the north pole), row H likewise for the south pole; for odd W the
    two texels nearest to u + W/2 are averaged.
    """
    h, w = img.shape[:2]
    out = cv2.copyMakeBorder(img, 1, 1, 1, 1, cv2.BORDER_WRAP)
    if out.ndim == 2 and img.ndim == 3:
        out = out[..., None]

    def across(row):
        if w % 2 == 0:
            return np.roll(row, w // 2, axis=0)
        a = np.roll(row.astype(np.float32), w // 2, axis=0)
        b = np.roll(row.astype(np.float32), w // 2 + 1, axis=0)
        return ((a + b) * 0.5).astype(row.dtype)

    for dst_row, src_row in ((0, 0), (h + 1, h - 1)):
        r = across(img[src_row])
        out[dst_row, 1:-1] = r
        out[dst_row, 0] = r[-1]
        out[dst_row, -1] = r[0]
    return out


@lru_cache(maxsize=8)
def _border_taps(face_size: int, interpolation: str):
    """Border texels of the padded atlas and where on the neighbouring faces they come from.

    Returns (dst_row, dst_col, src_rows (N, T), src_cols (N, T), weights (N, T)) in atlas
    coordinates; T = 4 bilinear taps (or 1 for nearest), always inside a face's interior.
    """
    s = face_size
    ring = [(i, -1) for i in range(-1, s + 1)] + [(i, s) for i in range(-1, s + 1)] \
        + [(-1, j) for j in range(s)] + [(s, j) for j in range(s)]
    ij = np.array(ring, dtype=np.float64)  # (n, 2) columns i (x), j (y)
    a = 2 * (ij[:, 0] + 0.5) / s - 1
    b = 2 * (ij[:, 1] + 0.5) / s - 1
    ab1 = np.stack([a, b, np.ones_like(a)], axis=-1)
    dst_r, dst_c, rows, cols, wts = [], [], [], [], []
    for f in range(6):
        d = ab1 @ WORLD_FROM_FACE[f].T
        g, u, v = face_pixel_from_direction(d, s)
        # A border texel lies at most ~half a texel outside the neighbour's texel-centre range
        # (on its edge row/column); clamping keeps the taps on that face.
        u = np.clip(u, 0, s - 1)
        v = np.clip(v, 0, s - 1)
        base = g * (s + 2) + 1
        if interpolation == "nearest":
            rows.append((base + np.rint(v)).astype(np.int64)[:, None])
            cols.append((1 + np.rint(u)).astype(np.int64)[:, None])
            wts.append(np.ones((len(u), 1)))
        else:
            u0 = np.minimum(np.floor(u), s - 2).astype(np.int64) if s > 1 else np.zeros(len(u), np.int64)
            v0 = np.minimum(np.floor(v), s - 2).astype(np.int64) if s > 1 else np.zeros(len(v), np.int64)
            fu, fv = u - u0, v - v0
            u1, v1 = np.minimum(u0 + 1, s - 1), np.minimum(v0 + 1, s - 1)
            rows.append(np.stack([base + v0, base + v0, base + v1, base + v1], axis=1))
            cols.append(np.stack([1 + u0, 1 + u1, 1 + u0, 1 + u1], axis=1))
            wts.append(np.stack([(1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv], axis=1))
        dst_r.append(f * (s + 2) + 1 + ij[:, 1].astype(np.int64))
        dst_c.append(1 + ij[:, 0].astype(np.int64))
    out = tuple(np.concatenate(x) for x in (dst_r, dst_c, rows, cols, wts))
    for x in out:
        x.setflags(write=False)
    return out


def pad_faces(faces, *, interpolation: str = "linear", dtype=None) -> np.ndarray:
    """Padded cube atlas (6 (S+2), S+2[, C]) from six canonical faces (FACE_NAMES order).

    Interior texels are copied; each border texel is sampled (bilinear, or nearest) from the
    face that its centre direction actually hits, so the atlas is continuous across every
    edge and corner of the cube. Example, S = 4: atlas rows 0..5 belong to face +x, and atlas
    pixel (0, 1) is +x's texel (-1, 0), taken from face +z near its right edge.
    """
    s = faces[0].shape[0]
    dtype = np.dtype(dtype or faces[0].dtype)
    shape = (6 * (s + 2), s + 2) + faces[0].shape[2:]
    atlas = np.empty(shape, dtype=dtype)
    for f, face in enumerate(faces):
        atlas[f * (s + 2) + 1:f * (s + 2) + 1 + s, 1:s + 1] = face
    dr, dc, rows, cols, wts = _border_taps(s, interpolation)
    taps = atlas[rows, cols]  # (N, T[, C])
    work = np.float64 if dtype == np.float64 else np.float32
    with np.errstate(invalid="ignore"):  # NaN depth stays NaN
        vals = np.einsum("nt,nt...->n...", wts.astype(work), taps.astype(work, copy=False))
    if dtype.kind in "ui":
        info = np.iinfo(dtype)
        vals = np.clip(np.rint(vals), info.min, info.max)
    atlas[dr, dc] = vals.astype(dtype, copy=False)
    return atlas


def area_prefilter(img: np.ndarray, ratio: float) -> np.ndarray:
    """Reduce ``img`` by ``ratio`` (output texel / source texel angle) with ``cv2.INTER_AREA``.

    Returns ``img`` unchanged when ratio <= 1.5 (bilinear sampling is then alias-free enough and
    exact at texel centres). The reduced image keeps the pixel-centre convention: OpenCV
    resizes with aligned image edges, so reduced pixel i covers source [i r - 0.5, (i+1) r - 0.5].
    """
    if ratio <= PREFILTER_THRESHOLD:
        return img
    h, w = img.shape[:2]
    nw, nh = max(1, int(round(w / ratio))), max(1, int(round(h / ratio)))
    if w == 2 * h:  # equirect: stay exactly 2:1 with an even width
        nw = max(2, nw + nw % 2)
        nh = nw // 2
    elif w == h:  # cube face: stay square
        nh = nw
    work = _as_remappable(img)
    if work.ndim == 3 and work.shape[2] > 4:  # cv2.resize takes at most 4 channels: 4 at a time
        out = np.concatenate([cv2.resize(np.ascontiguousarray(work[..., c:c + 4]), (nw, nh),
                                         interpolation=cv2.INTER_AREA).reshape(nh, nw, -1)
                              for c in range(0, work.shape[2], 4)], axis=2)
    else:
        out = cv2.resize(work, (nw, nh), interpolation=cv2.INTER_AREA)
    if img.ndim == 3 and out.ndim == 2:
        out = out[..., None]
    return out.astype(img.dtype) if out.dtype != img.dtype else out
