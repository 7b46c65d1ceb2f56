"""Camera conventions of other tools, converted once (docs/import.md has a worked number for each).

Ours (``docs/files.md``): camera frame x right, y down, z forward (OpenCV); ``world_from_cam`` the
4 x 4 camera-to-world pose; pixel (u, v) centres at integers, so a centred principal point of a
W-wide image is ``cx = (W - 1) / 2``.

* **OpenGL / Blender / NeRF** camera frame: x right, y up, z backward (the camera looks down -z).
  ``world_from_cam_ours = world_from_cam_gl @ diag(1, -1, -1, 1)`` (the flip is its own inverse).
* **Continuous pixel coordinates** (COLMAP, instant-ngp/nerfstudio ``cx``, Blender's sensor): the
  top-left pixel covers [0, 1] x [0, 1], its centre at (0.5, 0.5): ``cx_ours = cx - 0.5``.
* **Quaternions**: COLMAP writes ``QW QX QY QZ`` of the world-to-camera rotation (camera frame as
  ours); TUM RGB-D writes ``qx qy qz qw`` of the camera-to-world rotation of the optical frame
  (as ours). Both are Hamilton, unit length up to rounding (normalized here).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["GL_FLIP", "gl_from_ours", "ours_from_gl", "pose_from_world_to_camera", "rotation_from_quaternion",
           "quaternion_from_rotation"]

#: diag(1, -1, -1, 1): OpenGL camera axes <-> ours.
GL_FLIP = np.diag([1.0, -1.0, -1.0, 1.0])


def ours_from_gl(world_from_cam_gl) -> np.ndarray:
    """Camera-to-world pose with OpenGL camera axes (NeRF ``transform_matrix``, Blender
    ``matrix_world``) -> ours."""
    m = np.asarray(world_from_cam_gl, np.float64)
    if m.shape == (3, 4):
        m = np.vstack([m, [0.0, 0.0, 0.0, 1.0]])
    if m.shape != (4, 4) or not np.all(np.isfinite(m)):
        raise ValueError(f"transform_matrix: expected a finite 4x4 (or 3x4) matrix, got shape {m.shape}")
    return m @ GL_FLIP


def gl_from_ours(world_from_cam) -> np.ndarray:
    """Our camera-to-world pose -> OpenGL camera axes (what ``transforms.json`` stores)."""
    return np.asarray(world_from_cam, np.float64) @ GL_FLIP


def rotation_from_quaternion(w: float, x: float, y: float, z: float) -> np.ndarray:
    """3 x 3 rotation of a Hamilton quaternion (normalized first)."""
    n = math.sqrt(w * w + x * x + y * y + z * z)
    if not (n > 0 and math.isfinite(n)):
        raise ValueError(f"quaternion: expected a non-zero finite quaternion, got {(w, x, y, z)}")
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def quaternion_from_rotation(r) -> tuple[float, float, float, float]:
    """(w, x, y, z) with w >= 0 of a rotation matrix (Shepperd's method)."""
    r = np.asarray(r, np.float64)
    t = np.trace(r)
    if t > 0:
        s = 2.0 * math.sqrt(1.0 + t)
        q = (0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s)
    else:
        i = int(np.argmax(np.diag(r)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * math.sqrt(max(1.0 + r[i, i] - r[j, j] - r[k, k], 1e-300))
        q = [0.0] * 4
        q[0] = (r[k, j] - r[j, k]) / s
        q[1 + i] = 0.25 * s
        q[1 + j] = (r[j, i] + r[i, j]) / s
        q[1 + k] = (r[k, i] + r[i, k]) / s
        q = tuple(q)
    return tuple(float(-c) for c in q) if q[0] < 0 else tuple(float(c) for c in q)


def pose_from_world_to_camera(rot, t) -> np.ndarray:
    """``world_from_cam`` of a world-to-camera transform ``X_cam = R X_world + t``."""
    rot = np.asarray(rot, np.float64)
    m = np.eye(4)
    m[:3, :3] = rot.T
    m[:3, 3] = -rot.T @ np.asarray(t, np.float64)
    return m
