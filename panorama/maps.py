"""Where to sample: cached, read-only float32 maps from output pixels to source pixels.

Geometry only (no image data). Every builder is keyed by plain numbers, computed once in
float64 with :mod:`panorama.directions` and stored as float32 ``(map_x, map_y)`` for
``cv2.remap``; the arrays are read-only because they are shared through ``lru_cache``.

Source coordinate conventions (pixel centers at integers, as everywhere in the project):

* equirect source, ``pad=0``: (u, v) of the W x H image itself, u in [-0.5, W - 0.5]; sampled
  with ``cv2.BORDER_WRAP`` so column -1 is column W - 1 (no duplicated seam column). Valid only
  when every v lies in [0, H - 1]; otherwise the map is built for the image padded by one
  texel (``pad=1``: u + 1, v + 1), whose extra rows hold the row across the pole
  (:func:`panorama.sampling.pad_equirect`).
* cube source: the padded atlas of :func:`panorama.sampling.pad_faces`, faces stacked
  vertically in FACE_NAMES order, each (S + 2) x (S + 2): face f pixel (i, j) is at atlas
  (i + 1, j + 1 + f (S + 2)). Example, S = 4: face -x (f = 1) pixel (0, 0) is atlas (1, 7).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ibr.base.camera import Camera

from .directions import (
    equirect_directions,
    equirect_pixel_from_direction,
    face_directions,
    face_pixel_from_direction,
    world_from_view,
)
from .layouts import canonical_layout, layout_index_maps

__all__ = ["SampleMap", "cube_face_map", "equirect_map", "map_from_directions", "perspective_map",
           "perspective_rays"]

_CACHE = 16


@dataclass(frozen=True, eq=False)
class SampleMap:
    """float32 remap coordinates into a source, plus how the source must be prepared.

    ``source`` is ``"equirect"`` or ``"cube"``; ``pad`` is 1 when the source must be padded
    by one texel (cube atlas always; equirect only when samples reach past the pole rows).
    """

    map_x: np.ndarray
    map_y: np.ndarray
    source: str
    pad: int
    src_shape: tuple[int, int]  # (H, W) of the equirect, or (S, S) of one face


def _freeze(*arrays):
    for a in arrays:
        a.setflags(write=False)


def map_from_directions(d: np.ndarray, source: str, src_shape: tuple[int, int]) -> SampleMap:
    """Build a :class:`SampleMap` for directions ``d`` (..., 3) into an equirect or cube source."""
    if source == "equirect":
        h, w = src_shape
        u, v = equirect_pixel_from_direction(d, w, h)
        pad = int(bool(np.any(v < 0) or np.any(v > h - 1)))
        mx, my = (u + pad).astype(np.float32), (v + pad).astype(np.float32)
    elif source == "cube":
        s = src_shape[0]
        face, u, v = face_pixel_from_direction(d, s)
        pad = 1
        mx = (u + 1).astype(np.float32)
        my = (v + 1 + face * (s + 2)).astype(np.float32)
    else:
        raise ValueError(f"source: expected 'equirect' or 'cube', got {source!r}")
    _freeze(mx, my)
    return SampleMap(mx, my, source, pad, tuple(src_shape))


@lru_cache(maxsize=_CACHE)
def cube_face_map(layout: str, face_size: int, src_h: int, src_w: int) -> SampleMap:
    """Map from cube faces (in ``layout``, or the 6S x S canonical stack for list/dict/dice)
    to an equirect source of src_h x src_w."""
    layout = canonical_layout(layout)
    if layout in ("horizon", "vstrip"):
        face, i, j = layout_index_maps(layout, face_size)
        d = face_directions(face_size)[face, j, i]
    else:  # canonical stack, faces one below the other
        d = face_directions(face_size).reshape(6 * face_size, face_size, 3)
    return map_from_directions(d, "equirect", (src_h, src_w))


@lru_cache(maxsize=_CACHE)
def equirect_map(width: int, height: int, source: str, src_size: int, src_w: int = 0) -> SampleMap:
    """Map from a width x height equirect output to a cube (src_size = S) or equirect source
    (src_size = H, src_w = W)."""
    d = equirect_directions(width, height)
    shape = (src_size, src_size) if source == "cube" else (src_size, src_w)
    return map_from_directions(d, source, shape)


def perspective_rays(yaw_deg, pitch_deg, roll_deg, fov_deg, width, height) -> np.ndarray:
    """(H, W, 3) world-frame rays of a pinhole view (``Camera.from_fov``: fov_deg spans the full
    image width edge to edge; pixel centers at integers, cx = (W - 1) / 2)."""
    cam = Camera.from_fov(width, height, hfov_deg=fov_deg)
    return cam.rays_cam() @ world_from_view(yaw_deg, pitch_deg, roll_deg).T


@lru_cache(maxsize=_CACHE)
def perspective_map(yaw_deg: float, pitch_deg: float, roll_deg: float, fov_deg: float,
                    width: int, height: int, source: str, src_h: int, src_w: int) -> SampleMap:
    """Map from a perspective view to an equirect (src_h x src_w) or cube (src_h = S) source.

    Built per pixel by a numba kernel (:mod:`panorama._map_kernels`: same formulas as
    :func:`map_from_directions` of :func:`perspective_rays`, without the (H, W, 3) arrays), so a
    new view direction every frame (a tour, a viewer) costs one pass.
    """
    from . import _map_kernels
    from .directions import _AXIS_OF, _SIGN_OF

    if source not in ("equirect", "cube"):
        raise ValueError(f"source: expected 'equirect' or 'cube', got {source!r}")
    cam = Camera.from_fov(width, height, hfov_deg=fov_deg)
    rot = np.ascontiguousarray(world_from_view(yaw_deg, pitch_deg, roll_deg))
    mx = np.empty((height, width), np.float32)
    my = np.empty((height, width), np.float32)
    _map_kernels.perspective_map(rot, cam.fx, cam.fy, cam.cx, cam.cy, source == "cube", src_h, src_w,
                                 np.ascontiguousarray(_AXIS_OF, np.int64), np.ascontiguousarray(_SIGN_OF, np.float64),
                                 _map_kernels.ATAN_POLY, mx, my)
    pad = 1 if source == "cube" else int(bool(my.min() < 0 or my.max() > src_h - 1))
    if source == "equirect" and pad:  # the padded equirect (pole rows): +1 texel both ways
        mx += 1.0
        my += 1.0
    _freeze(mx, my)
    return SampleMap(mx, my, source, pad, (src_h, src_w))
