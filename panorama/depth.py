"""Depth on the sphere: planar z per cube face <-> range along the ray.

An equirectangular depth map stores **range** (distance from the centre along the pixel's ray,
scene units); a cube face, being a 90-degree pinhole camera, stores **planar z** along that
face's forward axis (the engine's depth convention). For a face pixel with face coordinates
(a, b) (see :mod:`panorama.directions`) the ray is ``right*a + down*b + forward``, so exactly

    range = z * sqrt(1 + a^2 + b^2),        z = range / sqrt(1 + a^2 + b^2).

Worked number, S = 2: pixel (0, 0) has a = b = -0.5, so z = 1 is range sqrt(1.5) = 1.2247.
For a perspective view the same holds with the camera's z = 1 rays: range = z * |ray|.
NaN (invalid) stays NaN.
"""

from __future__ import annotations

import numpy as np

from .directions import face_directions

__all__ = ["face_ray_lengths", "planar_from_range", "range_from_planar"]


def face_ray_lengths(face_size: int) -> np.ndarray:
    """(6, S, S) float64 lengths sqrt(1 + a^2 + b^2) of the z = 1 rays of every face pixel."""
    return np.linalg.norm(face_directions(face_size), axis=-1)


def range_from_planar(z, ray_length) -> np.ndarray:
    """Range along the ray from planar z: ``z * ray_length`` (float32; NaN stays NaN)."""
    return (np.asarray(z, dtype=np.float64) * ray_length).astype(np.float32)


def planar_from_range(rng, ray_length) -> np.ndarray:
    """Planar z from range along the ray: ``range / ray_length`` (float32; NaN stays NaN)."""
    return (np.asarray(rng, dtype=np.float64) / ray_length).astype(np.float32)
