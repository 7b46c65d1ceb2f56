"""Spherical conventions, written once: equirectangular angles and the six cube faces.

Frame
-----
Directions live in the project's camera/world frame: **x right, y down, z forward**
(``ibr.base.camera``). "Up" is therefore **-y**.

Equirectangular images (longitude/latitude)
-------------------------------------------
* longitude ``lon`` (radians) = ``atan2(x, z)``: **lon = 0 is +z** (forward), lon increases
  toward **+x** (to the right), lon = +pi/2 is +x, lon = +-pi is -z (behind).
* latitude ``lat`` = ``asin(-y / |d|)``: **positive toward -y (up)**; lat = +pi/2 is straight up.
* Pixel (u, v) = (column, row) has its center at integer coordinates (project convention), the
  image spans [-0.5, W-0.5] x [-0.5, H-0.5] and covers the sphere exactly once, so no column is
  duplicated at the seam::

      lon = ((u + 0.5) / W - 0.5) * 2 pi        lat = (0.5 - (v + 0.5) / H) * pi
      u   = (lon / (2 pi) + 0.5) * W - 0.5      v   = (0.5 - lat / pi) * H - 0.5

  Worked number, W x H = 4096 x 2048: the seam (lon = +-180 deg) is the left edge u = -0.5 of
  column 0; column 0's center is at lon = -179.956 deg; lon = 0 (+z) is the edge u = 2047.5
  between columns 2047 and 2048; +x (lon = 90 deg) is at u = 3071.5; the top row's center is
  at lat = +89.956 deg and the horizon is the edge v = 1023.5. The same convention as
  py360convert's ``coor2uv`` (its front face, +z, is at the image center, right is +x).

Cube faces
----------
Faces are indexed 0..5 in the order **+x, -x, +y, -y, +z, -z** (:data:`FACE_NAMES`; file-safe
names ``px nx py ny pz nz``). Names are in the project frame, so **+y is the bottom (down)
face and -y the top (up) face**. Each face is a 90-degree pinhole camera at the cube center:
face pixel (i, j) = (column, row) of an S x S face has its center at integer coordinates, and

    a = 2 (i + 0.5) / S - 1,   b = 2 (j + 0.5) / S - 1      (a, b in (-1, 1))
    direction = right_f * a + down_f * b + forward_f

with ``(right_f, down_f, forward_f)`` the columns of :data:`WORLD_FROM_FACE` ``[f]``:

    face  forward  right  down   looking ...            seen from the inside
    +x    +x       -z     +y     right                  upright
    -x    -x       +z     +y     left                   upright
    +y    +y       +x     -z     down (floor)           top edge toward +z (front)
    -y    -y       +x     +z     up (sky)               top edge toward -z (back)
    +z    +z       +x     +y     forward                upright
    -z    -z       -x     +y     back                   upright

Every face is a proper rotation (det +1), i.e. no face is mirrored: seen from the cube center
each face looks like a photo taken in its direction. This is the orientation py360convert
uses for its F R B L U D faces (F = +z, R = +x, B = -z, L = -x, U = -y, D = +y) and the one
OpenGL/WebGL cube maps use after flipping y (GL direction = (x, -y, z); GL's +Y face is our -y).
Worked number, S = 512: direction (1, 0.5, 0.25) hits face +x at a = -0.25, b = 0.5, i.e. face
pixel (u, v) = ((a + 1) / 2 * 512 - 0.5, (b + 1) / 2 * 512 - 0.5) = (191.5, 383.5).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = [
    "FACE_NAMES",
    "FACE_FILE_NAMES",
    "WORLD_FROM_FACE",
    "direction_from_equirect_pixel",
    "equirect_pixel_from_direction",
    "equirect_directions",
    "face_directions",
    "face_pixel_from_direction",
    "face_index",
    "lonlat_from_direction",
    "direction_from_lonlat",
    "world_from_view",
]

FACE_NAMES = ("+x", "-x", "+y", "-y", "+z", "-z")
FACE_FILE_NAMES = ("px", "nx", "py", "ny", "pz", "nz")


def _face_table() -> np.ndarray:
    # columns: right, down, forward (the face camera's x, y, z axes in the world frame)
    t = {
        "+x": ((0, 0, -1), (0, 1, 0), (1, 0, 0)),
        "-x": ((0, 0, 1), (0, 1, 0), (-1, 0, 0)),
        "+y": ((1, 0, 0), (0, 0, -1), (0, 1, 0)),
        "-y": ((1, 0, 0), (0, 0, 1), (0, -1, 0)),
        "+z": ((1, 0, 0), (0, 1, 0), (0, 0, 1)),
        "-z": ((-1, 0, 0), (0, 1, 0), (0, 0, -1)),
    }
    out = np.stack([np.array(t[name], dtype=np.float64).T for name in FACE_NAMES])
    out.setflags(write=False)
    return out


#: (6, 3, 3) rotation matrices; ``WORLD_FROM_FACE[f] @ (a, b, 1)`` is the direction of face
#: coordinates (a, b) in [-1, 1]^2. The single source of truth for face orientation.
WORLD_FROM_FACE = _face_table()


# Derived from the table (not a second table): which axis and sign each face's right (0) and
# down (1) vectors are, e.g. face +x: right = -z -> axis 2, sign -1.
_AXIS_OF = np.argmax(np.abs(WORLD_FROM_FACE), axis=1).T[:2]  # (2, 6)
_SIGN_OF = np.stack([WORLD_FROM_FACE[np.arange(6), _AXIS_OF[k], k] for k in (0, 1)])  # (2, 6)


def face_index(name: str) -> int:
    """Index 0..5 of a face given as ``'+x'``..``'-z'`` or ``'px'``..``'nz'``."""
    if name in FACE_NAMES:
        return FACE_NAMES.index(name)
    if name in FACE_FILE_NAMES:
        return FACE_FILE_NAMES.index(name)
    raise ValueError(
        f"face: expected one of {', '.join(FACE_NAMES + FACE_FILE_NAMES)}, got {name!r}"
    )


# ------------------------------------------------------------------------------- equirect
def lonlat_from_direction(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lon, lat) in radians of directions ``d`` (..., 3), not necessarily unit.

    lon = atan2(x, z) (0 at +z, +pi/2 at +x); lat = atan2(-y, hypot(x, z)) (+pi/2 up = -y).
    """
    d = np.asarray(d, dtype=np.float64)
    x, y, z = d[..., 0], d[..., 1], d[..., 2]
    return np.arctan2(x, z), np.arctan2(-y, np.hypot(x, z))


def direction_from_lonlat(lon, lat) -> np.ndarray:
    """Unit directions (..., 3) from lon/lat in radians (inverse of :func:`lonlat_from_direction`)."""
    lon = np.asarray(lon, dtype=np.float64)
    lat = np.asarray(lat, dtype=np.float64)
    c = np.cos(lat)
    return np.stack([c * np.sin(lon), -np.sin(lat), c * np.cos(lon)], axis=-1)


def equirect_pixel_from_direction(d, width: int, height: int) -> tuple[np.ndarray, np.ndarray]:
    """Equirect pixel coordinates (u, v) of directions; centers at integers.

    u in [-0.5, W - 0.5), v in [-0.5, H - 0.5]. Example: for 4096 x 2048, +z maps to
    (2047.5, 1023.5) and +x to (3071.5, 1023.5).
    """
    lon, lat = lonlat_from_direction(d)
    u = (lon / (2 * np.pi) + 0.5) * width - 0.5
    v = (0.5 - lat / np.pi) * height - 0.5
    return u, v


def direction_from_equirect_pixel(u, v, width: int, height: int) -> np.ndarray:
    """Unit directions of equirect pixel coordinates (u, v) (centers at integers)."""
    lon = ((np.asarray(u, dtype=np.float64) + 0.5) / width - 0.5) * 2 * np.pi
    lat = (0.5 - (np.asarray(v, dtype=np.float64) + 0.5) / height) * np.pi
    return direction_from_lonlat(lon, lat)


@lru_cache(maxsize=8)
def equirect_directions(width: int, height: int) -> np.ndarray:
    """(H, W, 3) float64 unit directions of every equirect pixel center; cached, read-only."""
    lon = ((np.arange(width) + 0.5) / width - 0.5) * 2 * np.pi
    lat = (0.5 - (np.arange(height) + 0.5) / height) * np.pi
    c = np.cos(lat)[:, None]
    d = np.empty((height, width, 3))
    d[..., 0] = c * np.sin(lon)  # separable form of direction_from_lonlat
    d[..., 1] = -np.sin(lat)[:, None]
    d[..., 2] = c * np.cos(lon)
    d.setflags(write=False)
    return d


# ----------------------------------------------------------------------------------- cube
@lru_cache(maxsize=8)
def face_directions(face_size: int, normalize: bool = False) -> np.ndarray:
    """(6, S, S, 3) float64 directions of every face pixel center, faces in FACE_NAMES order.

    Not normalized by default: the forward component is exactly 1 (the face plane at distance
    1), which is what planar depth per face needs. Cached and read-only.
    """
    s = int(face_size)
    c = 2 * (np.arange(s, dtype=np.float64) + 0.5) / s - 1  # a or b of pixel centers
    right, down, fwd = (WORLD_FROM_FACE[:, None, None, :, k] for k in range(3))  # (6, 1, 1, 3)
    d = right * c[None, None, :, None] + down * c[None, :, None, None] + fwd
    if normalize:
        d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    d.setflags(write=False)
    return d


def face_pixel_from_direction(d, face_size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(face, u, v) of directions ``d`` (..., 3): the face hit and its pixel coordinates.

    The face is the one whose forward axis has the largest dot product with ``d`` (ties go to
    the lower index). u, v are in [-0.5, S - 0.5] with centers at integers (see module doc).
    """
    d = np.asarray(d, dtype=np.float64)
    # The face's forward axis is +-e_k for the dominant axis k: FACE_NAMES order is 2k (+) and
    # 2k + 1 (-); ties go to the lower axis (argmax), i.e. the lower face index.
    axis = np.argmax(np.abs(d), axis=-1)
    comp = np.take_along_axis(d, axis[..., None], axis=-1)[..., 0]
    face = 2 * axis + (comp < 0)
    # local coordinates: a = d . right_f / d . forward_f, b = d . down_f / d . forward_f; right_f
    # and down_f are signed unit axes, so each dot product picks one component of d
    inv = 1.0 / np.abs(comp)
    a = np.take_along_axis(d, _AXIS_OF[0][face][..., None], axis=-1)[..., 0] * (_SIGN_OF[0][face] * inv)
    b = np.take_along_axis(d, _AXIS_OF[1][face][..., None], axis=-1)[..., 0] * (_SIGN_OF[1][face] * inv)
    s = float(face_size)
    return face, (a + 1) * 0.5 * s - 0.5, (b + 1) * 0.5 * s - 0.5


# ---------------------------------------------------------------------------- view poses
def world_from_view(yaw_deg: float, pitch_deg: float, roll_deg: float = 0.0) -> np.ndarray:
    """3x3 rotation of a viewing camera looking at (lon, lat) = (yaw, pitch).

    ``world_from_view = R_y(yaw) @ R_x(pitch) @ R_z(roll)`` with the camera frame x right,
    y down, z forward: yaw 90 looks at +x (right), pitch +90 looks straight up (-y), and a
    positive roll turns the camera clockwise about its viewing axis as seen from behind (its
    right side dips), so the scene appears rotated counter-clockwise in the image.
    Example: yaw 90, pitch 0, roll 0 maps the view's forward (0, 0, 1) to +x (1, 0, 0).
    """
    y, p, r = np.radians([yaw_deg, pitch_deg, roll_deg])
    ry = np.array([[np.cos(y), 0, np.sin(y)], [0, 1, 0], [-np.sin(y), 0, np.cos(y)]])
    rx = np.array([[1, 0, 0], [0, np.cos(p), -np.sin(p)], [0, np.sin(p), np.cos(p)]])
    rz = np.array([[np.cos(r), -np.sin(r), 0], [np.sin(r), np.cos(r), 0], [0, 0, 1]])
    return ry @ rx @ rz
