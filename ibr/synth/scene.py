"""Synthetic scenes with exact ground truth: a vectorized ray caster over analytic primitives.

Seed 001 section 7.1: *ray casting* finds, for every viewing ray, the nearest intersection with
the scene (closed-form plane, box-slab and sphere intersections here, float64 throughout), then
*shading* computes the pixel's RGB from the light and the material at that point:

* Lambert (eq. 7.1/7.2) plus ambient (eq. 7.5): ``L = d * (ambient + diffuse * max(0, n . l))``
  with albedo ``d`` from the texture, a white directional light toward unit vector ``l``.
  It does not depend on the viewing ray, so a point has the same color from every camera and a
  correctly warped view can match a direct render exactly. This is the default.
* Optional Blinn-Phong highlight (eq. 7.3/7.4): ``+ specular * max(0, n . b) ** shininess``,
  ``b = (l + v) / |l + v|`` with ``v`` toward the viewer; off unless ``Scene.specular > 0``.

Shading uses the normal turned toward the incoming ray (surfaces are two-sided); there are no
shadows or inter-reflections.

Conventions (DESIGN.md section 4): world and camera frames have y pointing *down* (world up is
-y); pixel (u, v) = (column, row) with centers at integers, so pixel (0, 0) of a 512-wide image
with ``cx = 255.5`` looks along the camera ray ``((0 - 255.5) / fx, (0 - cy) / fy, 1)``.
Depth is planar z = t * (dir . optical_axis) with t the distance along the unit ray.

Antialiasing: :func:`render` may supersample *color* with a k x k box filter (subpixel samples
at ``u + (i + 0.5) / k - 0.5``, i = 0..k-1, e.g. u - 0.25 and u + 0.25 for k = 2), but *depth*
is always the exact value of the ray through the pixel center: depth is never averaged across
an edge.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from .primitives import Primitive, mat3
from ..base.camera import Camera
from ..base.validate import check_array, check_unit_vector as _unit
from ..base.view import View

__all__ = ["Hit", "Scene", "render", "render_rays"]

_CHUNK = 1 << 17  # rays per batch: bounds memory (~50 MB of temporaries) without slowing numpy


@dataclass(frozen=True, eq=False)
class Hit:
    """Result of :meth:`Scene.trace` for N rays.

    Attributes
    ----------
    t : (N,) float64
        Distance along the unit ray to the nearest hit; ``inf`` on a miss.
    normal : (N, 3) float64
        Unit surface normal at the hit, turned toward the ray (``normal . dir <= 0``); NaN on a miss.
    color : (N, 3) float32
        Shaded RGB in [0, 1]; the scene's background color on a miss.
    prim : (N,) int32
        Index into ``scene.primitives`` of the surface hit; -1 on a miss.
    """

    t: np.ndarray
    normal: np.ndarray
    color: np.ndarray
    prim: np.ndarray

    @property
    def valid(self) -> np.ndarray:
        """(N,) bool, True where the ray hit something."""
        return self.prim >= 0


@dataclass(frozen=True, eq=False)
class Scene:
    """A list of textured primitives plus one directional light.

    Parameters
    ----------
    primitives : sequence of Rect, Box, Sphere
    name : str
    light_dir : (3,) array
        Direction *toward* the light in world coordinates (normalized here). World up is -y,
        so a light from above has a negative y component.
    ambient, diffuse : float
        Weights of the ambient term and the Lambertian term; ``ambient + diffuse <= 1`` keeps
        colors in [0, 1] without clipping.
    specular : float
        Blinn-Phong highlight weight, 0 (off, view-independent) by default.
    shininess : float
        Blinn-Phong exponent x of eq. 7.4.
    background : (3,) array
        Color returned for rays that hit nothing.
    """

    primitives: tuple
    name: str = "scene"
    light_dir: np.ndarray = field(default_factory=lambda: np.array([-0.35, -1.0, -0.55]))
    ambient: float = 0.35
    diffuse: float = 0.65
    specular: float = 0.0
    shininess: float = 60.0
    background: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self):
        prims = tuple(self.primitives)
        if not prims:
            raise ValueError("primitives: expected at least one primitive, got none")
        for i, p in enumerate(prims):
            if not isinstance(p, Primitive):
                raise TypeError(f"primitives[{i}]: expected Rect, Box or Sphere, got {type(p).__name__}")
        object.__setattr__(self, "primitives", prims)
        light = _unit("light_dir", self.light_dir)
        light.setflags(write=False)
        object.__setattr__(self, "light_dir", light)
        for k in ("ambient", "diffuse", "specular"):
            val = float(getattr(self, k))
            if not 0 <= val <= 1:
                raise ValueError(f"{k}: expected a weight in [0, 1], got {val!r}")
            object.__setattr__(self, k, val)
        if not float(self.shininess) > 0:
            raise ValueError(f"shininess: expected a positive exponent, got {self.shininess!r}")
        object.__setattr__(self, "background", tuple(float(c) for c in self.background))

    def with_specular(self, specular: float = 0.3, shininess: float | None = None) -> "Scene":
        """Same scene with the Blinn-Phong highlight switched on (view-*dependent*)."""
        return replace(self, specular=specular, shininess=self.shininess if shininess is None else shininess)

    # ------------------------------------------------------------------ ray casting
    def trace(self, origins, dirs, *, shade: bool = True) -> Hit:
        """Cast N rays and shade the nearest hits.

        Parameters
        ----------
        origins : (N, 3) or (3,) array
            Ray origins in world coordinates (a (3,) origin is shared by all rays).
        dirs : (N, 3) array
            Unit ray directions (|d| = 1 within 1e-6), world coordinates.
        shade : bool
            When False only ``t``, ``normal`` and ``prim`` are computed (color is background).

        Returns
        -------
        Hit
        """
        o, d = _check_rays(origins, dirs)
        n = len(d)
        t = np.full(n, np.inf)
        prim = np.full(n, -1, np.int32)
        normal = np.full((n, 3), np.nan)
        color = np.empty((n, 3), np.float32)
        color[:] = np.asarray(self.background, np.float32)
        for s in range(0, n, _CHUNK):
            sl = slice(s, min(n, s + _CHUNK))
            self._trace_chunk(o[sl] if o.ndim == 2 else o, d[sl], t[sl], prim[sl], normal[sl], color[sl], shade)
        return Hit(t, normal, color, prim)

    def _trace_chunk(self, o, d, t, prim, normal, color, shade):
        # Ray casting: nearest intersection over all primitives (seed 001 section 7.1).
        for i, p in enumerate(self.primitives):
            ti = p.intersect(o, d)
            closer = ti < t
            t[closer] = ti[closer]
            prim[closer] = i
        for i in np.unique(prim):
            if i < 0:
                continue
            sel = np.nonzero(prim == i)[0]
            pts = (o[sel] if o.ndim == 2 else o) + t[sel, None] * d[sel]
            nrm, albedo = self.primitives[i].surface(pts)
            nrm = np.array(nrm, dtype=np.float64)
            flip = np.einsum("ij,ij->i", nrm, d[sel]) > 0  # two-sided: face the incoming ray
            nrm[flip] *= -1
            normal[sel] = nrm
            if shade:
                color[sel] = self._shade(nrm, albedo, d[sel])

    def _shade(self, nrm, albedo, d):
        """Seed 001 eq. 7.5 with one white directional light (I = 1)."""
        l = self.light_dir
        lam = np.maximum(0.0, nrm @ l)  # eq. 7.1/7.2: max(0, n . l)
        rgb = albedo * (self.ambient + self.diffuse * lam)[:, None]
        if self.specular > 0:  # eq. 7.3/7.4: bisector of light and view directions
            b = l - d
            b /= np.linalg.norm(b, axis=1, keepdims=True)
            rgb = rgb + (self.specular * np.maximum(0.0, np.einsum("ij,ij->i", nrm, b)) ** self.shininess)[:, None]
        return np.clip(rgb, 0.0, 1.0).astype(np.float32)


def _check_rays(origins, dirs) -> tuple[np.ndarray, np.ndarray]:
    d = check_array("dirs", dirs, shape=(None, 3), dtype_kind="fiu").astype(np.float64)
    o = check_array("origins", origins, ndim=(1, 2), dtype_kind="fiu").astype(np.float64)
    if o.shape != (3,) and o.shape != d.shape:
        raise ValueError(f"origins: expected shape (3,) or {d.shape} to match dirs, got {o.shape}")
    if not np.all(np.isfinite(o)):
        raise ValueError("origins: expected finite coordinates, got NaN or inf")
    norms = np.linalg.norm(d, axis=1)
    bad = ~(np.abs(norms - 1.0) <= 1e-6)
    if np.any(bad):
        i = int(np.argmax(bad))
        raise ValueError(f"dirs: expected unit vectors (|d| = 1 within 1e-6), got |dirs[{i}]| = {norms[i]!r}")
    return o, d


# ---------------------------------------------------------------------- rendering
def render_rays(scene: Scene, origins, dirs) -> tuple[np.ndarray, np.ndarray]:
    """Color and range for arbitrary rays (cube faces, equirectangular or any other camera).

    Parameters
    ----------
    scene : Scene
    origins : (..., 3) or (3,) array
        Ray origins, world coordinates; (3,) is shared by all rays.
    dirs : (..., 3) array
        Unit directions, world coordinates, any leading shape (e.g. (H, W, 3)).

    Returns
    -------
    color : (..., 3) float32
        Shaded RGB in [0, 1] (background on a miss).
    range : (...) float32
        Distance along the ray to the hit in scene units, NaN on a miss. (Planar depth for a
        pinhole camera is ``range * (dir . optical_axis)``; :func:`render` does that in float64.)
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a Scene, got {type(scene).__name__}")
    d = check_array("dirs", dirs, dtype_kind="fiu")
    if d.ndim < 1 or d.shape[-1] != 3:
        raise ValueError(f"dirs: expected shape (..., 3), got {d.shape}")
    lead = d.shape[:-1]
    o = check_array("origins", origins, dtype_kind="fiu")
    if o.shape != (3,):
        if o.shape != d.shape:
            raise ValueError(f"origins: expected shape (3,) or {d.shape} to match dirs, got {o.shape}")
        o = o.reshape(-1, 3)
    hit = scene.trace(o, d.reshape(-1, 3))
    rng = np.where(hit.valid, hit.t, np.nan).astype(np.float32)
    return hit.color.reshape(lead + (3,)), rng.reshape(lead)


def _camera_dirs(camera: Camera, du: float = 0.0, dv: float = 0.0) -> np.ndarray:
    """Unit world directions (H*W, 3) through pixel centers shifted by (du, dv) pixels."""
    u, v = camera.pixel_grid()
    rays = np.stack([(u + du - camera.cx) / camera.fx, (v + dv - camera.cy) / camera.fy, np.ones_like(u)], -1)
    d = mat3(rays.reshape(-1, 3), camera.world_from_cam[:3, :3].T)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return d


def render(scene: Scene, camera: Camera, *, supersample: int = 1, name: str | None = None) -> View:
    """Render color and exact planar depth for a pinhole camera.

    Parameters
    ----------
    scene : Scene
    camera : Camera
        Pixel (u, v) = (column, row), centers at integers: the depth of pixel (10, 4) is that of
        the ray through ``((10 - cx) / fx, (4 - cy) / fy, 1)`` in the camera frame.
    supersample : int
        k >= 1: color is the mean of k x k samples at subpixel offsets ``(i + 0.5) / k - 0.5``
        (a box filter over the pixel; k = 2 samples at +-0.25). Depth is always the exact
        pixel-center value, never averaged.
    name : str, optional
        View name, default the scene's name.

    Returns
    -------
    View
        ``color`` (H, W, 3) float32 in [0, 1]; ``depth`` (H, W) float32 planar z
        ``= t * (dir . optical_axis)`` computed in float64, NaN where the ray misses.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a Scene, got {type(scene).__name__}")
    if not isinstance(camera, Camera):
        raise TypeError(f"camera: expected a Camera, got {type(camera).__name__}")
    if isinstance(supersample, bool) or not isinstance(supersample, (int, np.integer)) or supersample < 1:
        raise ValueError(f"supersample: expected an integer >= 1, got {supersample!r}")
    k = int(supersample)
    h, w = camera.shape
    origin = camera.position
    axis = camera.world_from_cam[:3, 2]
    d = _camera_dirs(camera)
    center = scene.trace(origin, d, shade=(k == 1))
    depth = np.where(center.valid, center.t * (d @ axis), np.nan).astype(np.float32)
    if k == 1:
        color = center.color
    else:
        acc = np.zeros((h * w, 3), np.float64)
        offsets = (np.arange(k) + 0.5) / k - 0.5
        for dv in offsets:
            for du in offsets:
                acc += scene.trace(origin, _camera_dirs(camera, du, dv)).color
        color = (acc / (k * k)).astype(np.float32)
    return View(color.reshape(h, w, 3), depth.reshape(h, w), camera, scene.name if name is None else name)
