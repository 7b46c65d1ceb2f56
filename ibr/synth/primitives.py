"""Analytic primitives of the synthetic scenes: ray intersection and surface attributes.

Every primitive answers two vectorized questions (float64 throughout; ``o`` is one (3,) origin
shared by all rays or (N, 3)):

* ``intersect(o, d) -> t`` (N,): distance along the unit ray ``o + t d`` to the nearest hit with
  ``t > T_MIN``, ``inf`` on a miss (seed 001 section 7.1, "ray casting": closed-form
  intersections from dot products and plane equations).
* ``surface(p) -> (normal, albedo)`` at hit points ``p`` (M, 3): the geometric outward unit
  normal and the textured albedo (float32 RGB in [0, 1]). Albedo depends on the surface point
  only, never on the viewing ray, so shading with a Lambertian model is view-independent.

World frame follows the engine convention: y points *down* (world up is -y).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .textures import ImageTexture

__all__ = ["Primitive", "Rect", "Box", "Sphere", "T_MIN", "rotation"]

T_MIN = 1e-9  # rays start at camera centers, never on surfaces; this only rejects t <= 0


def rotation(yaw_deg: float = 0.0, pitch_deg: float = 0.0, roll_deg: float = 0.0) -> np.ndarray:
    """3x3 rotation ``world_from_local``: yaw about -y (up, counter-clockwise seen from above),
    then pitch about x, then roll about z (intrinsic, applied as R = Ry(yaw) Rx(pitch) Rz(roll))."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_euler("YXZ", [-yaw_deg, pitch_deg, roll_deg], degrees=True).as_matrix()


def mat3(a: np.ndarray, m: np.ndarray) -> np.ndarray:
    """``a @ m`` for a (3,) or (N, 3) array ``a`` and a 3x3 ``m``, one column at a time.

    numpy's (N, 3) @ (3, 3) path is 10-50x slower than three matrix-vector products here.
    """
    if a.ndim == 1:
        return a @ m
    out = np.empty((len(a), 3))
    for k in range(3):
        out[:, k] = a @ m[:, k]
    return out


def _vec(name: str, v, shape=(3,)) -> np.ndarray:
    a = np.asarray(v, dtype=np.float64)
    if a.shape != shape or not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: expected finite array of shape {shape}, got {np.asarray(v).shape}")
    return a


@dataclass(frozen=True, eq=False)
class Primitive:
    """Base class: a textured analytic surface (see the module docstring)."""

    texture: ImageTexture

    def intersect(self, o: np.ndarray, d: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError

    def surface(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # pragma: no cover - abstract
        raise NotImplementedError


@dataclass(frozen=True, eq=False)
class Rect(Primitive):
    """Planar rectangle ``center + s*axis_u + t*axis_v`` with |s| <= half_u, |t| <= half_v.

    ``half_u`` / ``half_v`` may be ``inf`` for an infinite plane. The normal is
    ``axis_u x axis_v``. Texture coordinates: the image's columns run along ``axis_u`` and its
    rows along ``axis_v``, the image corner sits at ``center + tex_offset[0]*axis_u +
    tex_offset[1]*axis_v``, one image width spans ``texture.width_units``.
    """

    center: np.ndarray = field(default_factory=lambda: np.zeros(3))
    axis_u: np.ndarray = field(default_factory=lambda: np.array([1.0, 0, 0]))
    axis_v: np.ndarray = field(default_factory=lambda: np.array([0, 1.0, 0]))
    half_u: float = np.inf
    half_v: float = np.inf
    tex_offset: tuple = (0.0, 0.0)

    def __post_init__(self):
        c = _vec("center", self.center)
        u = _vec("axis_u", self.axis_u)
        v = _vec("axis_v", self.axis_v)
        u = u / np.linalg.norm(u)
        v = v - (v @ u) * u  # orthonormalize
        if np.linalg.norm(v) < 1e-12:
            raise ValueError("axis_v: must not be parallel to axis_u")
        v = v / np.linalg.norm(v)
        if not (float(self.half_u) > 0 and float(self.half_v) > 0):
            raise ValueError(f"half_u, half_v: expected positive sizes, got {self.half_u}, {self.half_v}")
        for k, val in (("center", c), ("axis_u", u), ("axis_v", v)):
            val.setflags(write=False)
            object.__setattr__(self, k, val)
        n = np.cross(u, v)
        n.setflags(write=False)
        object.__setattr__(self, "normal", n)

    def intersect(self, o, d):
        n = self.normal
        denom = d @ n
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((self.center - o) @ n) / denom  # plane n.(x - c) = 0
        t = np.where(np.isfinite(t) & (t > T_MIN), t, np.inf)
        p = o + np.where(np.isfinite(t), t, 0.0)[:, None] * d
        rel = p - self.center
        inside = (np.abs(rel @ self.axis_u) <= self.half_u) & (np.abs(rel @ self.axis_v) <= self.half_v)
        return np.where(inside, t, np.inf)

    def surface(self, p):
        rel = p - self.center
        s = rel @ self.axis_u - self.tex_offset[0]
        t = rel @ self.axis_v - self.tex_offset[1]
        normal = np.broadcast_to(self.normal, p.shape)
        return normal, self.texture.sample_plane(s, t)


_FACE_AXES = ((1, 2), (0, 2), (0, 1))  # texture axes (s, t) of the faces normal to x, y, z


@dataclass(frozen=True, eq=False)
class Box(Primitive):
    """Oriented box: ``center``, ``half_size`` (3,) along its local axes, ``world_from_box`` (3, 3).

    Each face is textured along its two in-plane local axes, measured in scene units from the
    box's min corner: x faces use (y, z) as (columns, rows), y faces (x, z), z faces (x, y);
    the three face pairs read different parts of the image (rows offset by 3 units per axis).
    """

    center: np.ndarray = field(default_factory=lambda: np.zeros(3))
    half_size: np.ndarray = field(default_factory=lambda: np.full(3, 0.5))
    world_from_box: np.ndarray = field(default_factory=lambda: np.eye(3))

    def __post_init__(self):
        c = _vec("center", self.center)
        h = _vec("half_size", self.half_size)
        r = _vec("world_from_box", self.world_from_box, (3, 3))
        if np.any(h <= 0):
            raise ValueError(f"half_size: expected positive sizes, got {h.tolist()}")
        if not np.allclose(r @ r.T, np.eye(3), atol=1e-9) or np.linalg.det(r) < 0:
            raise ValueError("world_from_box: expected a proper rotation matrix")
        for k, val in (("center", c), ("half_size", h), ("world_from_box", r)):
            val.setflags(write=False)
            object.__setattr__(self, k, val)

    def _local(self, o, d):
        r = self.world_from_box
        return mat3(o - self.center, r), mat3(d, r)  # box_from_world = r.T, applied to row vectors

    def intersect(self, o, d):
        lo, ld = self._local(o, d)
        h = self.half_size
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / ld
            t1 = (-h - lo) * inv
            t2 = (h - lo) * inv
        tmin = np.minimum(t1, t2)
        tmax = np.maximum(t1, t2)
        # A ray parallel to a slab: inside the slab -> (-inf, inf); outside -> empty (0*inf = nan).
        par = ld == 0
        inside_slab = np.abs(lo) <= h
        tmin = np.where(par, np.where(inside_slab, -np.inf, np.inf), tmin)
        tmax = np.where(par, np.where(inside_slab, np.inf, -np.inf), tmax)
        tn = tmin.max(axis=1)
        tf = tmax.min(axis=1)
        t = np.where(tn > T_MIN, tn, tf)  # from inside a box, the exit face is hit
        hit = (tn <= tf) & (t > T_MIN)
        return np.where(hit, t, np.inf)

    def surface(self, p):
        lp = mat3(p - self.center, self.world_from_box)
        h = self.half_size
        q = np.abs(lp) / h  # 1 on the face that was hit
        axis = np.argmax(q, axis=1)
        m = len(p)
        rows = np.arange(m)
        n_local = np.zeros((m, 3))
        n_local[rows, axis] = np.sign(lp[rows, axis])
        normal = mat3(n_local, self.world_from_box.T)
        corner = lp + h  # measured from the min corner, in scene units
        s = np.empty(m)
        t = np.empty(m)
        for k, (a, b) in enumerate(_FACE_AXES):
            sel = axis == k
            s[sel] = corner[sel, a]
            t[sel] = corner[sel, b] + 3.0 * k  # different faces use different parts of the image
        return normal, self.texture.sample_plane(s, t)


@dataclass(frozen=True, eq=False)
class Sphere(Primitive):
    """Sphere with a latitude/longitude texture: image columns = longitude (the image's center
    column faces -z, i.e. the default viewpoint), rows = colatitude from the world's up (-y)."""

    center: np.ndarray = field(default_factory=lambda: np.zeros(3))
    radius: float = 1.0

    def __post_init__(self):
        c = _vec("center", self.center)
        if not float(self.radius) > 0:
            raise ValueError(f"radius: expected a positive number, got {self.radius!r}")
        c.setflags(write=False)
        object.__setattr__(self, "center", c)
        object.__setattr__(self, "radius", float(self.radius))

    def intersect(self, o, d):
        oc = o - self.center  # (3,) for a shared origin, else (N, 3)
        b = d @ oc if oc.ndim == 1 else np.einsum("ij,ij->i", oc, d)
        # Numerically stable discriminant: r^2 - |oc - b d|^2 (perpendicular distance squared).
        perp = oc - b[:, None] * d
        disc = self.radius**2 - np.einsum("ij,ij->i", perp, perp)
        root = np.sqrt(np.maximum(disc, 0.0))
        t_near = -b - root
        t_far = -b + root
        t = np.where(t_near > T_MIN, t_near, t_far)
        return np.where((disc >= 0) & (t > T_MIN), t, np.inf)

    def surface(self, p):
        n = (p - self.center) / self.radius
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        lon = np.arctan2(n[:, 0], -n[:, 2])  # 0 facing -z (toward the default viewpoint)
        colat = np.arccos(np.clip(-n[:, 1], -1.0, 1.0))  # 0 at the top (-y)
        return n, self.texture.sample_unit(lon / (2 * np.pi) + 0.5, colat / np.pi)
