"""Cubemap layouts: how six faces are arranged in memory or in one image.

Faces are always held internally in the order and orientation of :mod:`panorama.directions`
(+x, -x, +y, -y, +z, -z; +y is the *down* face in the project frame, x right / y down /
z forward). A layout only moves (and for some tools turns) whole faces:

=========  ==============  ===========================================================
layout     shape           arrangement
=========  ==============  ===========================================================
list       6 x (S, S[,C])  ``[+x, -x, +y, -y, +z, -z]``
dict       6 x (S, S[,C])  keys ``'+x' .. '-z'``; input also accepts ``'px' .. 'nz'`` and
                           py360convert's ``'F R B L U D'`` (F=+z R=+x B=-z L=-x U=-y D=+y)
horizon    (S, 6S[,C])     horizontal strip, left to right F R B L U D = +z +x -z -x -y +y,
                           as py360convert's ``cube_format="horizon"``
vstrip     (6S, S[,C])     vertical strip as OpenEXR's ``exrenvmap`` writes a cube map:
                           top to bottom OpenEXR's +X -X +Y -Y +Z -Z. OpenEXR's frame is
                           y up with x to the *left* (its latlong centre is +Z, longitude
                           growing to the left), i.e. ours turned 180 deg about z, so the
                           tiles are -x +x -y +y +z -z, and its up/down tiles are turned
                           180 deg relative to ours (ImfEnvmap.cpp, CubeMap::pixelPosition)
dice       (3S, 4S[,C])    horizontal cross as py360convert's ``cube_format="dice"``::

                                  . U . .          U = -y (up),  D = +y (down)
                                  L F R B          L = -x, F = +z, R = +x, B = -z
                                  . D . .          unused cells are 0
=========  ==============  ===========================================================

A 4:3 image is only auto-detected as a dice when its six unused cells are empty, one uniform
colour (:func:`dice_unused_spread` at most :data:`DICE_EMPTY_MAX_SPREAD`): an ordinary 4:3 photo
is no cubemap.

Aliases: ``hstrip`` = horizon, ``exr`` = vstrip, ``cross``/``hcross`` = dice. A folder of six
files (``px.png`` ...) is the "files" layout of :mod:`panorama.files`.

py360convert's faces have the same orientation as ours (checked in the tests against
py360convert's own sampling grid), so its horizon/dice images open unchanged; OpenEXR puts
the outermost texel centres *on* the cube edges (it scales by S - 1), we inset them by half a
texel (pixel centres at (i + 0.5) / S), which differs by at most half a texel at the edges.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Literal

import numpy as np

from ibr.base.validate import check_choice, check_image

from .directions import FACE_FILE_NAMES, FACE_NAMES

__all__ = ["DICE_EMPTY_MAX_SPREAD", "LAYOUTS", "Layout", "canonical_layout", "dice_unused_spread",
           "layout_faces", "layout_index_maps", "layout_shape", "pack_faces", "unpack_faces", "cube_face_size"]

Layout = Literal["list", "dict", "horizon", "vstrip", "dice"]
LAYOUTS = ("list", "dict", "horizon", "vstrip", "dice")
_ALIASES = {"hstrip": "horizon", "exr": "vstrip", "cross": "dice", "hcross": "dice"}
_PY360_KEYS = {"F": "+z", "R": "+x", "B": "-z", "L": "-x", "U": "-y", "D": "+y"}

# The one table of tile positions: layout -> tuple over faces in FACE_NAMES order of
# (tile column, tile row, k) where the tile holds np.rot90(face, k) (k counter-clockwise turns).
_TILES = {
    #            +x         -x         +y         -y         +z         -z
    "horizon": ((1, 0, 0), (3, 0, 0), (5, 0, 0), (4, 0, 0), (0, 0, 0), (2, 0, 0)),
    "vstrip": ((0, 1, 0), (0, 0, 0), (0, 3, 2), (0, 2, 2), (0, 4, 0), (0, 5, 0)),
    "dice": ((2, 1, 0), (0, 1, 0), (1, 2, 0), (1, 0, 0), (1, 1, 0), (3, 1, 0)),
}
_GRID = {"horizon": (6, 1), "vstrip": (1, 6), "dice": (4, 3)}  # (tiles across, tiles down)
#: Largest :func:`dice_unused_spread` (the unused cells' spread over the faces') of an image
#: auto-detected as a dice: the project's dice images give 0 (PNG), 0.12 at most after a JPEG
#: round trip of tiny blurred faces (24 px, quality 75); photos about 1 (the value range no longer decides: an HDR photo with
#: one bright highlight or 12-bit values in uint16 passed the earlier fraction-of-range test).
DICE_EMPTY_MAX_SPREAD = 0.25
#: Samples per side of each unused cell that :func:`dice_unused_spread` reads (a stride above).
_SPREAD_SAMPLES = 256


def canonical_layout(layout: str) -> str:
    """Resolve aliases and check ``layout`` against :data:`LAYOUTS`."""
    layout = _ALIASES.get(layout, layout)
    return check_choice("layout", layout, LAYOUTS + tuple(_ALIASES))


def layout_shape(layout: str, face_size: int) -> tuple[int, int]:
    """(height, width) of a single-image layout with faces of ``face_size``."""
    layout = canonical_layout(layout)
    if layout not in _GRID:
        raise ValueError(f"layout: {layout!r} is not a single-image layout")
    nx, ny = _GRID[layout]
    return ny * face_size, nx * face_size


def dice_unused_spread(img) -> float:
    """How far the six unused cells of a 4:3 image are from one uniform colour, against how much
    the six face cells vary (interquartile ranges).

    Parameters
    ----------
    img : (3S, 4S[, C]) array
        A candidate dice image (any dtype; NaN and inf are ignored).

    Returns
    -------
    float
        The larger of the largest per-channel interquartile range of any unused cell's pixels and
        the largest per-channel range of the six cells' medians, over the largest per-channel
        interquartile range of the face cells' pixels (pooled): 0
        for the project's dice (unused cells 0), about 1 for a photo whose cells all hold
        picture content (``clutter_a_color.png``, an HDR photo with a 1e4 highlight in a face,
        12-bit noise in uint16), whatever the dtype, the value range or a few outliers. Each cell is read
        without a border of S // 8 pixels (JPEG ringing from the faces' edges) and with a stride
        that keeps at most 256 samples a side; an image without any variation gives 0.
    """
    img = check_image("pano", img)
    h, w = img.shape[:2]
    if 3 * w != 4 * h:
        raise ValueError(f"pano: a dice image is (3S, 4S), got {w} x {h}")
    s = h // 3
    m, step = s // 8, max(1, (s - 2 * (s // 8)) // _SPREAD_SAMPLES)
    used = {(col, row) for col, row, _ in _TILES["dice"]}
    channels = 1 if img.ndim == 2 else img.shape[2]

    def cells(keep):
        return [img[r * s + m:(r + 1) * s - m:step, c * s + m:(c + 1) * s - m:step].reshape(-1, channels)
                for r in range(3) for c in range(4) if ((c, r) in used) == keep]

    empty = [c.astype(np.float64) for c in cells(False)]
    # every unused cell on its own (one cell with content among five empty ones must count), and
    # the cells against each other (each flat but of another colour: a sky above, a lawn below)
    spread = max(float(np.max(_finite_iqr(c))) for c in empty)
    medians = np.array([[np.median(col[np.isfinite(col)]) if np.isfinite(col).any() else np.nan for col in c.T]
                        for c in empty])
    if np.isfinite(medians).any():
        spread = max(spread, float(np.nanmax(np.nanmax(medians, axis=0) - np.nanmin(medians, axis=0))))
    faces = float(np.max(_finite_iqr(np.concatenate(cells(True)).astype(np.float64))))
    return spread / faces if faces > 0 else (0.0 if spread == 0 else float("inf"))


def _finite_iqr(x: np.ndarray) -> np.ndarray:
    """Per-column interquartile range of the finite values of ``x`` (N, C); 0 for a column
    without any (robust: one bright highlight or a few outliers do not move it)."""
    out = np.zeros(x.shape[1])
    for c in range(x.shape[1]):
        col = x[:, c][np.isfinite(x[:, c])]
        if col.size:
            q1, q3 = np.percentile(col, [25.0, 75.0])
            out[c] = q3 - q1
    return out


def cube_face_size(cube, layout: str) -> int:
    """Face size S of a cubemap given in ``layout``; checks the shape and says what is wrong."""
    return _split(cube, canonical_layout(layout))[0].shape[0]


def _check_face(name: str, face) -> np.ndarray:
    arr = check_image(name, face)
    if arr.shape[0] != arr.shape[1]:
        raise ValueError(f"{name}: cube faces must be square, got shape {arr.shape}")
    return arr


def _split(cube, layout: str) -> list[np.ndarray]:
    """Six face arrays (views, canonical orientation) from ``cube`` in ``layout``."""
    if layout == "list":
        if not isinstance(cube, (list, tuple)) or len(cube) != 6:
            got = f"{type(cube).__name__} of length {len(cube)}" if isinstance(cube, (list, tuple)) \
                else type(cube).__name__
            raise TypeError(f"cube: layout 'list' expects a list of 6 faces, got {got}")
        faces = [_check_face(f"cube[{i}]", f) for i, f in enumerate(cube)]
    elif layout == "dict":
        if not isinstance(cube, dict):
            raise TypeError(f"cube: layout 'dict' expects a dict of 6 faces, got {type(cube).__name__}")
        faces = []
        for name, file_name in zip(FACE_NAMES, FACE_FILE_NAMES):
            py360 = next(k for k, v in _PY360_KEYS.items() if v == name)
            key = next((k for k in (name, file_name, py360) if k in cube), None)
            if key is None:
                raise ValueError(
                    f"cube: dict has no face {name!r} (also accepted: {file_name!r}, {py360!r}); "
                    f"got keys {sorted(map(str, cube))}"
                )
            faces.append(_check_face(f"cube[{key!r}]", cube[key]))
    else:
        img = check_image("cube", cube)
        nx, ny = _GRID[layout]
        h, w = img.shape[:2]
        if h % ny or w % nx or h // ny != w // nx:
            raise ValueError(
                f"cube: layout {layout!r} needs a ({ny}*S, {nx}*S) image of square faces, "
                f"got shape {img.shape}"
            )
        s = h // ny
        faces = []
        for col, row, k in _TILES[layout]:
            tile = img[row * s:(row + 1) * s, col * s:(col + 1) * s]
            faces.append(np.rot90(tile, -k))
    first = faces[0]
    for i, f in enumerate(faces[1:], 1):
        if f.shape != first.shape or f.dtype != first.dtype:
            raise ValueError(
                f"cube: face {FACE_NAMES[i]} has shape {f.shape} dtype {f.dtype}, "
                f"face {FACE_NAMES[0]} has shape {first.shape} dtype {first.dtype}"
            )
    return faces


def unpack_faces(cube, layout: str) -> list[np.ndarray]:
    """Six faces in FACE_NAMES order and canonical orientation (views where possible)."""
    return _split(cube, canonical_layout(layout))


def layout_faces(stack: np.ndarray, layout: str):
    """Wrap a (6, S, S[, C]) stack of canonical faces as ``layout`` without copying if possible."""
    return pack_faces(list(stack), layout)


def pack_faces(faces, layout: str):
    """Arrange six canonical faces (FACE_NAMES order) in ``layout``.

    ``list`` and ``dict`` return the given arrays; image layouts allocate a new image with the
    faces' dtype (unused dice cells 0).
    """
    layout = canonical_layout(layout)
    faces = _split(list(faces), "list")
    if layout == "list":
        return list(faces)
    if layout == "dict":
        return dict(zip(FACE_NAMES, faces))
    s = faces[0].shape[0]
    h, w = layout_shape(layout, s)
    out = np.zeros((h, w) + faces[0].shape[2:], dtype=faces[0].dtype)
    for face, (col, row, k) in zip(faces, _TILES[layout]):
        out[row * s:(row + 1) * s, col * s:(col + 1) * s] = np.rot90(face, k)
    return out


@lru_cache(maxsize=16)
def layout_index_maps(layout: str, face_size: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For every pixel of a single-image layout: (face, i, j) of the canonical face pixel.

    ``face`` is -1 on unused dice cells. Built by packing index images with
    :func:`pack_faces`, so it cannot disagree with the layout table. Cached, read-only.
    """
    layout = canonical_layout(layout)
    s = int(face_size)
    j, i = np.mgrid[0:s, 0:s].astype(np.int32)
    idx = np.stack([np.stack([np.full((s, s), f, np.int32), i, j], axis=-1) for f in range(6)])
    packed = pack_faces(list(idx), layout)
    if isinstance(packed, (list, dict)):
        packed = np.concatenate(list(packed.values()) if isinstance(packed, dict) else packed)
    face = packed[..., 0].copy()
    if layout == "dice":
        covered = np.zeros(face.shape, bool)
        for col, row, _ in _TILES["dice"]:
            covered[row * s:(row + 1) * s, col * s:(col + 1) * s] = True
        face[~covered] = -1
    out = (face, packed[..., 1].copy(), packed[..., 2].copy())
    for a in out:
        a.setflags(write=False)
    return out
