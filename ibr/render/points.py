"""Bilinear samples of an image at scattered points, by ``cv2.remap``.

``cv2.remap`` takes maps narrower than 32767 columns and at most four channels, so the points
are laid out in rows of :data:`ROW` and the channels sampled four at a time. Pixel centres at
integer (u, v).
"""

from __future__ import annotations

import cv2
import numpy as np

__all__ = ["ROW", "sample_points"]

#: Points per row of the remap maps.
ROW = 1024


def sample_points(image, u, v, *, outside: float = 0.0) -> np.ndarray:
    """(N, C) float32 bilinear samples of ``image`` ((H, W) or (H, W, C), any channel count) at
    the points (``u``, ``v``) (any shape, N values each); ``outside`` where a point is outside the
    image (the border pixels' half-pixel margin included, as ``cv2.BORDER_CONSTANT``)."""
    u, v = np.asarray(u, np.float32).ravel(), np.asarray(v, np.float32).ravel()
    if u.shape != v.shape:
        raise ValueError(f"v: expected {u.size} values like u, got {v.size}")
    img = np.asarray(image, np.float32)
    img = img[..., None] if img.ndim == 2 else img
    n = u.size
    rows = max(1, -(-n // ROW))
    mu = np.full(rows * ROW, -1e6, np.float32)
    mv = np.full(rows * ROW, -1e6, np.float32)
    mu[:n], mv[:n] = u, v
    mu, mv = mu.reshape(rows, ROW), mv.reshape(rows, ROW)
    out = []
    for c0 in range(0, img.shape[2], 4):
        part = cv2.remap(np.ascontiguousarray(img[..., c0:c0 + 4]), mu, mv, cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_CONSTANT, borderValue=(outside,) * 4)
        out.append(part.reshape(rows * ROW, -1)[:n])
    return np.concatenate(out, 1)
