"""Spherical ray cameras: equirectangular (mono) and omnidirectional stereo (ODS) eyes.

A pinhole camera's pixels share one centre and one image plane; these cameras' pixels are rays
on a longitude/latitude grid whose origins may differ (ODS). The renderer draws quad meshes into
them exactly (:mod:`ibr.render.ray_raster`); :mod:`panorama.stitch` builds panoramas on them.

Conventions (the same as :mod:`panorama.directions`, tested to agree)
----------------------------------------------------------------------
* Rig frame: x right, y down, z forward; ``world_from_rig`` is a 4x4 rig-to-world pose, the rig
  centre is the capture point.
* Longitude ``lon = atan2(x, z)`` (0 = +z, +pi/2 = +x), latitude ``lat = atan2(-y, hypot(x, z))``
  (positive up = -y). Pixel (u, v) has its centre at integer coordinates and the W x H image
  covers ``lon in [-pi, pi)``, ``lat in [-pi/2, pi/2]``::

      lon(u) = ((u + 0.5) / W - 0.5) * 2 pi,      lat(v) = (0.5 - (v + 0.5) / H) * pi

* Ray of pixel (u, v): direction ``d = (cos lat sin lon, -sin lat, cos lat cos lon)`` (unit), origin
  ``o = s * r(lat) * right(lon)`` with ``right(lon) = (cos lon, 0, -sin lon)`` the horizontal unit
  vector to the right of the viewing direction, ``s = -1`` for the left eye, ``+1`` for the right
  eye, ``0`` for a mono camera. ``r(lat) = ipd / 2`` for ``|lat| <= fade_start`` and falls to 0 at
  ``|lat| = fade_end`` along a half cosine (C1-smooth): the fade keeps the poles free of swirls.
* Depth of a ray camera is the **range**: distance from the ray's own origin along its unit
  direction (scene units).

Inverse (point -> pixel), closed form for constant r: with the point's horizontal distance
``rho = hypot(x, z)`` and longitude ``alpha``, the ray through it satisfies
``rho * sin(alpha - lon) = s * r`` (tangent to the viewing circle) and
``tan(lat) = -y / sqrt(rho^2 - r^2)``, so ``lon = alpha - asin(s r / rho)``. Inside the fade, r
depends on lat: a few fixed-point steps on lat converge (|dr/dlat| << rho). Points with
``rho < r`` (closer to the axis than the viewing circle) are seen by no ray of the eye.
Worked number: ipd = 0.064, a point at (0, 0, 2) (2 m ahead) is seen by the left eye at
lon = -asin(-0.032 / 2) = +0.9168 deg, i.e. column 2057.93 of a 4096-wide image (the mono
camera sees it at 2047.5).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .camera import _check_pose, _readonly
from .validate import check_finite_scalar

__all__ = ["SphericalCamera", "EYES"]

#: Eye names and their sign s in the ray origin ``s * r(lat) * right(lon)``.
EYES = {"mono": 0, "left": -1, "right": 1}


@dataclass(frozen=True, eq=False)
class SphericalCamera:
    """A W x H equirectangular grid of rays, mono or one eye of omnidirectional stereo.

    Parameters
    ----------
    width, height : int
        Image size; ``width == 2 * height`` (full sphere, square pixels in angle).
    eye : {"mono", "left", "right"}
        ``"mono"``: every ray starts at the rig centre. ``"left"`` / ``"right"``: ODS eye rays
        start on the viewing circle of radius ``ipd / 2`` (see module doc).
    ipd : float
        Interpupillary distance in scene units (> 0 for an eye; ignored for mono).
    fade_start_deg, fade_end_deg : float
        Latitudes where the circle radius starts to fall and reaches 0 (0 < start < end <= 90).
    world_from_rig : (4, 4) array, optional
        Rig-to-world pose; identity by default.
    """

    width: int
    height: int
    eye: str = "mono"
    ipd: float = 0.064
    fade_start_deg: float = 60.0
    fade_end_deg: float = 80.0
    world_from_rig: np.ndarray = field(default_factory=lambda: np.eye(4))

    def __post_init__(self):
        for name in ("width", "height"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or not 1 <= v <= 1 << 16:
                raise ValueError(f"{name}: expected an integer in [1, 65536], got {v!r}")
        if self.width != 2 * self.height:
            raise ValueError(f"width, height: expected a 2:1 equirect size, got {self.width} x {self.height}")
        if self.eye not in EYES:
            raise ValueError(f"eye: expected one of {', '.join(map(repr, EYES))}, got {self.eye!r}")
        ipd = check_finite_scalar("ipd", self.ipd)
        if self.eye != "mono" and not ipd > 0:
            raise ValueError(f"ipd: expected a positive distance for an ODS eye, got {self.ipd!r}")
        a = check_finite_scalar("fade_start_deg", self.fade_start_deg)
        b = check_finite_scalar("fade_end_deg", self.fade_end_deg)
        if not 0 < a < b <= 90:
            raise ValueError(
                f"fade_start_deg, fade_end_deg: expected 0 < start < end <= 90, got {self.fade_start_deg!r}, "
                f"{self.fade_end_deg!r}"
            )
        pose = _check_pose("world_from_rig", self.world_from_rig)
        object.__setattr__(self, "ipd", ipd)
        object.__setattr__(self, "world_from_rig", _readonly(pose))

    # ------------------------------------------------------------------ grid
    @property
    def shape(self) -> tuple[int, int]:
        return (self.height, self.width)

    @property
    def sign(self) -> int:
        """s in the ray origin: -1 left eye, +1 right eye, 0 mono."""
        return EYES[self.eye]

    @property
    def center(self) -> np.ndarray:
        """Rig centre (capture point) in the world frame."""
        return self.world_from_rig[:3, 3].copy()

    def lon(self, u) -> np.ndarray:
        """Longitude (radians) of column coordinate(s) u (centres at integers)."""
        return ((np.asarray(u, dtype=np.float64) + 0.5) / self.width - 0.5) * 2 * np.pi

    def lat(self, v) -> np.ndarray:
        """Latitude (radians) of row coordinate(s) v (centres at integers)."""
        return (0.5 - (np.asarray(v, dtype=np.float64) + 0.5) / self.height) * np.pi

    def u_of_lon(self, lon) -> np.ndarray:
        return (np.asarray(lon, dtype=np.float64) / (2 * np.pi) + 0.5) * self.width - 0.5

    def v_of_lat(self, lat) -> np.ndarray:
        return (0.5 - np.asarray(lat, dtype=np.float64) / np.pi) * self.height - 0.5

    def radius(self, lat) -> np.ndarray:
        """Viewing-circle radius r(lat) in scene units (0 for mono): ipd/2, half-cosine fade."""
        lat = np.abs(np.asarray(lat, dtype=np.float64))
        if self.sign == 0:
            return np.zeros_like(lat)
        a, b = math.radians(self.fade_start_deg), math.radians(self.fade_end_deg)
        x = np.clip((lat - a) / (b - a), 0.0, 1.0)
        return 0.5 * self.ipd * 0.5 * (1.0 + np.cos(np.pi * x))

    def radius_slope(self, lat) -> np.ndarray:
        """d r / d lat (scene units per radian) of :meth:`radius` (odd in lat, 0 outside the fade)."""
        lat = np.asarray(lat, dtype=np.float64)
        if self.sign == 0:
            return np.zeros_like(lat)
        a, b = math.radians(self.fade_start_deg), math.radians(self.fade_end_deg)
        x = (np.abs(lat) - a) / (b - a)
        inside = (x > 0) & (x < 1)
        slope = -0.5 * self.ipd * 0.5 * np.pi * np.sin(np.pi * np.clip(x, 0, 1)) / (b - a)
        return np.where(inside, np.sign(lat) * slope, 0.0)

    def row_tables(self) -> np.ndarray:
        """(H, 3) float64 ``[sin lat, cos lat, s * r(lat)]`` of each row centre (for kernels)."""
        lat = self.lat(np.arange(self.height))
        return np.ascontiguousarray(np.stack([np.sin(lat), np.cos(lat), self.sign * self.radius(lat)], -1))

    def column_tables(self) -> np.ndarray:
        """(W, 2) float64 ``[sin lon, cos lon]`` of each column centre (for kernels)."""
        lon = self.lon(np.arange(self.width))
        return np.ascontiguousarray(np.stack([np.sin(lon), np.cos(lon)], -1))

    # ------------------------------------------------------------------ rays
    def rays_rig(self, u, v) -> tuple[np.ndarray, np.ndarray]:
        """Origins and unit directions (..., 3) in the rig frame of pixel coordinates (u, v)."""
        lon, lat = self.lon(u), self.lat(v)
        lon, lat = np.broadcast_arrays(lon, lat)
        cl = np.cos(lat)
        d = np.stack([cl * np.sin(lon), -np.sin(lat), cl * np.cos(lon)], -1)
        r = self.sign * self.radius(lat)
        o = np.stack([r * np.cos(lon), np.zeros_like(r), -r * np.sin(lon)], -1)
        return o, d

    def rays_world(self, u=None, v=None) -> tuple[np.ndarray, np.ndarray]:
        """World-frame origins and unit directions; every pixel centre (H, W, 3) by default."""
        if u is None and v is None:
            v, u = np.mgrid[0 : self.height, 0 : self.width]
        o, d = self.rays_rig(u, v)
        m = self.world_from_rig
        return o @ m[:3, :3].T + m[:3, 3], d @ m[:3, :3].T

    # ------------------------------------------------------------------ projection
    def project(self, points_world, *, iterations: int = 16) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Pixel coordinates (u, v) and range of world points seen by this camera.

        Returns ``(u, v, range)``; u in [-0.5, W - 0.5) (wrapped), v in [-0.5, H - 0.5]. Points the
        eye cannot see (closer to the vertical axis than the viewing circle, ``rho < r``) get NaN.
        Inside the fade latitude band r depends on the latitude: ``lat`` solves
        ``g(lat) = lat - atan2(-y, sqrt(rho^2 - r(lat)^2)) = 0``; g is strictly increasing (r falls
        toward the poles), so ``iterations`` Newton steps kept inside a shrinking bracket converge
        even for points a few centimetres from the viewing circle (where plain fixed-point steps
        diverge: their factor ``|dr/dlat| / rho`` exceeds 1).
        """
        p = np.asarray(points_world, dtype=np.float64)
        m = self.world_from_rig
        q = (p - m[:3, 3]) @ m[:3, :3]  # rig frame
        x, y, z = q[..., 0], q[..., 1], q[..., 2]
        rho = np.hypot(x, z)
        alpha = np.arctan2(x, z)
        lat = np.arctan2(-y, rho)
        r = np.zeros_like(rho)
        with np.errstate(invalid="ignore", divide="ignore"):
            if self.sign:
                lo = np.full_like(lat, -np.pi / 2)
                hi = np.full_like(lat, np.pi / 2)
                for _ in range(iterations):
                    r = self.radius(lat)
                    s2 = np.maximum(rho * rho - r * r, 1e-300)
                    sq = np.sqrt(s2)
                    g = lat - np.arctan2(-y, sq)
                    lo = np.where(g < 0, lat, lo)
                    hi = np.where(g > 0, lat, hi)
                    dg = 1.0 + y * r * self.radius_slope(lat) / (sq * (s2 + y * y))
                    step = lat - g / dg
                    bisect = ~((step > lo) & (step < hi))
                    lat = np.where(bisect, 0.5 * (lo + hi), step)
                r = self.radius(lat)
            lon = alpha - np.arcsin(self.sign * r / rho) if self.sign else alpha
            rng = np.sqrt(np.maximum(rho * rho - r * r, 0.0) + y * y)
        lon = (lon + np.pi) % (2 * np.pi) - np.pi
        bad = ~(rho >= r) | ~np.isfinite(lat) | ~np.isfinite(lon)  # lon: 0 / 0 on the axis where r = 0
        u = np.where(bad, np.nan, self.u_of_lon(lon))
        v = np.where(bad, np.nan, self.v_of_lat(lat))
        return u, v, np.where(bad, np.nan, rng)

    def with_eye(self, eye: str) -> "SphericalCamera":
        """The same camera for another eye (``"mono"``, ``"left"``, ``"right"``)."""
        return SphericalCamera(self.width, self.height, eye, self.ipd, self.fade_start_deg, self.fade_end_deg,
                               self.world_from_rig)

    def __repr__(self) -> str:
        c = self.center
        extra = "" if self.sign == 0 else f", ipd={self.ipd:g}, fade={self.fade_start_deg:g}..{self.fade_end_deg:g} deg"
        return f"SphericalCamera({self.width}x{self.height}, {self.eye}{extra}, centre=({c[0]:g}, {c[1]:g}, {c[2]:g}))"
