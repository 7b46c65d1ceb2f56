"""Multires tile pyramids for the web viewer (issue #18): large panoramas load progressively.

Level 0 is the six base faces of ``tile`` px (``px.png .. nz.png``, what every site has); level
k > 0 has faces of ``tile * 2^k`` px cut into ``2^k x 2^k`` tiles of ``tile`` px, written as
``tile-<k>-<face>-<row>-<col>.png`` (flat names: a site is one folder). The page shows the base
first, then fetches only the tiles of the level its field of view calls for that the view can
see (``panorama/web/index.html``). ``viewer.json`` holds ``{"tiles": {"size": T, "levels":
[T, 2T, ...]}}``.
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["TILE", "tile_levels", "tile_name", "write_tiles"]

#: Tile size in pixels (also the base faces' size).
TILE = 512


def tile_levels(face_size: int, tile: int = TILE) -> list[int]:
    """Face sizes of the levels: tile, 2 tile, ... up to ``face_size`` (a power-of-two multiple)."""
    if face_size < tile or face_size % tile or (face_size // tile) & (face_size // tile - 1):
        raise ValueError(f"face_size: tiled faces need tile * 2^k pixels (tile {tile}), got {face_size}")
    sizes = [tile]
    while sizes[-1] < face_size:
        sizes.append(sizes[-1] * 2)
    return sizes


def tile_name(level: int, face: str, row: int, col: int) -> str:
    return f"tile-{level}-{face}-{row}-{col}.png"


def write_tiles(folder, faces, names, tile: int = TILE, write_image=None) -> dict:
    """Write levels 1.. of six top-level faces (uint8, all ``S x S``, S = tile * 2^k); return
    the ``viewer.json`` entry. Level 0 (the base faces) is written by the caller."""
    size = faces[0].shape[0]
    levels = tile_levels(size, tile)
    for k, s in enumerate(levels[1:], start=1):
        for name, face in zip(names, faces):
            img = face if s == size else cv2.resize(face, (s, s), interpolation=cv2.INTER_AREA)
            n = s // tile
            for r in range(n):
                for c in range(n):
                    write_image(folder / tile_name(k, name, r, c),
                                np.ascontiguousarray(img[r * tile:(r + 1) * tile, c * tile:(c + 1) * tile]))
    return {"size": tile, "levels": levels}
