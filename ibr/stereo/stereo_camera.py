"""Stereo camera with parallel axes and asymmetric frusta, parallax and viewing comfort (seed 000).

The stereo camera of seed 000 (Lü & Bao 2011) has a center of projection ``V_p``, a view
direction ``V_d``, an up vector ``V_u``, an interaxial distance ``e``, a zero-parallax ("focal")
distance ``f``, a vertical field of view ``theta``, near/far planes ``L_n``/``L_f`` and an aspect
``psi``. Its two eyes sit at ``V_p -/+ V`` with ``V = (V_d x V_u)/|V_d x V_u| * e/2`` (eqs. 1-2),
keep the same view direction (parallel axes: no vertical parallax) and use off-axis frusta whose
near-plane windows are shifted by ``+/- e L_n / 2f`` (eqs. 3-4) so that the plane at distance f
has zero parallax.

Conventions
-----------
* Scene inputs (``position``, ``view_dir``, ``up``) are world vectors in whatever world frame the
  caller uses (seed 000's table 1 uses an OpenGL-style world with y up). The eye cameras are
  :class:`ibr.base.camera.Camera` objects (OpenCV frame: x right, y down, z forward) built *from the
  OpenGL matrices* with :func:`ibr.base.camera.camera_from_gl_projection`, i.e. converted at the edge.
* Depth ``z`` below is planar depth along the view direction, **positive in front of the camera**
  (OpenCV). Seed 000 writes its formulas with OpenGL's z < 0; its eq. 9 ``P_h = e (1 + f/z_gl)``
  is ``P_h = e (1 - f/z)`` here.
* Parallax sign: P = x_right - x_left. P < 0 (crossed, in front of the screen) for z < f, 0 at
  z = f, P > 0 (uncrossed, behind the screen) for z > f, tending to e as z -> infinity.
* Pixel coordinates: pixel centers at integers, image spans [-0.5, W - 0.5]; a centered principal
  point of a 512-wide image is cx = 255.5. The left eye's principal point is
  ``cx = (W - 1)/2 - fx e / (2 f)`` (its frustum is shifted to +x), the right eye's is
  ``(W - 1)/2 + fx e / (2 f)``; e.g. W = 512, fx = 549.0, e = 0.088, f = 3.144 gives
  cx_left = 255.5 - 7.683 = 247.817.
* Visual angle (eq. 10): a parallax P on the zero-parallax plane, seen from the center of
  projection at distance f, subtends ``beta = 2 atan(P / (2 f))``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..base.validate import check_array, check_choice, check_finite_scalar, check_positive, check_unit_vector as _unit
from ..base.camera import Camera, GLFrustum, camera_from_gl_projection

__all__ = [
    "ComfortReport",
    "StereoCamera",
    "auto_stereo",
    "comfort",
    "interaxial_for_parallax",
    "max_interaxial",
    "max_interaxial_for_range",
    "parallax_angle_deg",
    "parallax_px",
    "parallax_scene",
]

EYES = ("left", "right")

#: Valyus's convergence tolerance (seed 000 section 3.3); 2 tan(0.8 deg) = 0.0279, the seed's 0.028f.
DEFAULT_MAX_ANGLE_DEG = 1.6


@dataclass(frozen=True, eq=False)
class StereoCamera:
    """Seed 000's stereo camera: parallel axes, asymmetric frusta (eqs. 1-4).

    Parameters
    ----------
    position : (3,) array
        Center of projection ``V_p`` (world units), midway between the eyes.
    view_dir : (3,) array
        Viewing direction ``V_d`` (any length > 0).
    up : (3,) array
        Up vector ``V_u`` (made orthogonal to ``view_dir``; must not be parallel to it).
    interaxial : float
        Eye separation ``e`` in scene units (>= 0; 0 gives a mono pair).
    focal_distance : float
        Zero-parallax distance ``f`` (> 0), scene units along the view direction.
    vfov_deg : float
        Vertical field of view ``theta`` of each eye, 0 < theta < 180 degrees.
    near, far : float
        Clip plane distances ``L_n`` < ``L_f`` (far may be inf).
    width, height : int
        Image size in pixels of each eye; the aspect ``psi = width / height``.
    """

    position: np.ndarray
    view_dir: np.ndarray
    up: np.ndarray
    interaxial: float
    focal_distance: float
    vfov_deg: float
    near: float
    far: float
    width: int = 512
    height: int = 512

    def __post_init__(self):
        set_ = object.__setattr__
        pos = check_array("position", self.position, shape=(3,), dtype_kind="fiu").astype(np.float64)
        if not np.all(np.isfinite(pos)):
            raise ValueError(f"position: expected finite coordinates, got {pos.tolist()}")
        d = _unit("view_dir", self.view_dir)
        u = _unit("up", self.up)
        if np.linalg.norm(np.cross(d, u)) < 1e-9:
            raise ValueError("up: must not be parallel to view_dir")
        for name, arr in (("position", pos), ("view_dir", d), ("up", u)):
            arr.setflags(write=False)
            set_(self, name, arr)
        e = check_finite_scalar("interaxial", self.interaxial)
        if e < 0:
            raise ValueError(f"interaxial: expected e >= 0, got {self.interaxial!r}")
        set_(self, "interaxial", e)
        set_(self, "focal_distance", check_positive("focal_distance", self.focal_distance))
        fov = check_finite_scalar("vfov_deg", self.vfov_deg)
        if not 0 < fov < 180:
            raise ValueError(f"vfov_deg: expected 0 < theta < 180, got {self.vfov_deg!r}")
        set_(self, "vfov_deg", fov)
        n = check_positive("near", self.near)
        f = check_positive("far", self.far, allow_inf=True)
        if not f > n:
            raise ValueError(f"far: expected far > near, got near={self.near!r}, far={self.far!r}")
        set_(self, "near", n)
        set_(self, "far", f)
        for name in ("width", "height"):
            v = getattr(self, name)
            if isinstance(v, bool) or int(v) != v or int(v) < 1:
                raise ValueError(f"{name}: expected a positive integer, got {v!r}")
            set_(self, name, int(v))

    # ------------------------------------------------------------------ geometry
    @property
    def aspect(self) -> float:
        """psi = width / height (seed 000's near-plane aspect)."""
        return self.width / self.height

    @property
    def right_dir(self) -> np.ndarray:
        """Unit vector ``(V_d x V_u) / |V_d x V_u|`` pointing from the left to the right eye."""
        r = np.cross(self.view_dir, self.up)
        return r / np.linalg.norm(r)

    @property
    def focal_px(self) -> float:
        """Focal length in pixels of each eye, ``H / (2 tan(theta / 2))``."""
        return self.height / (2 * np.tan(np.radians(self.vfov_deg) / 2))

    def eye_position(self, eye: str) -> np.ndarray:
        """Eq. 1-2: ``V_lp = V_p - V``, ``V_rp = V_p + V`` with ``V = right_dir * e / 2``."""
        check_choice("eye", eye, EYES)
        v = self.right_dir * self.interaxial / 2
        return self.position - v if eye == "left" else self.position + v

    def gl_frustum(self, eye: str) -> GLFrustum:
        """Eq. 3 (left) and eq. 4 (right): the off-axis near-plane window of one eye.

        ``l = -psi L_n tan(theta/2) +/- e L_n / 2f``, ``r = psi L_n tan(theta/2) +/- e L_n / 2f``
        (+ for the left eye, - for the right), ``b, t = -/+ L_n tan(theta/2)``.
        """
        check_choice("eye", eye, EYES)
        n = self.near
        half_h = n * np.tan(np.radians(self.vfov_deg) / 2)
        half_w = self.aspect * half_h
        shift = self.interaxial * n / (2 * self.focal_distance)
        s = shift if eye == "left" else -shift
        return GLFrustum(-half_w + s, half_w + s, -half_h, half_h, n, self.far)

    def gl_projection(self, eye: str) -> np.ndarray:
        """4x4 OpenGL projection (``glFrustum`` of :meth:`gl_frustum`), clip_from_eye_gl."""
        return GLFrustum.projection(self.gl_frustum(eye))

    def gl_view(self, eye: str) -> np.ndarray:
        """4x4 OpenGL view matrix eye_gl_from_world (``gluLookAt(V_ep, V_ep + V_d, V_u)``)."""
        s = self.right_dir
        u = np.cross(s, self.view_dir)
        m = np.eye(4)
        m[0, :3], m[1, :3], m[2, :3] = s, u, -self.view_dir
        m[:3, 3] = -m[:3, :3] @ self.eye_position(eye)
        return m

    def camera(self, eye: str) -> Camera:
        """The eye as an OpenCV :class:`Camera`, converted from the GL matrices at the edge."""
        cam, _, _ = camera_from_gl_projection(
            self.gl_projection(eye), self.width, self.height, view=self.gl_view(eye)
        )
        return cam

    def cameras(self) -> tuple[Camera, Camera]:
        """``(left, right)`` eye cameras."""
        return self.camera("left"), self.camera("right")

    def center_camera(self) -> Camera:
        """The mono camera at ``V_p`` with a symmetric frustum (the rig with e = 0)."""
        return self.with_interaxial(0.0).camera("left")

    def with_interaxial(self, interaxial: float) -> "StereoCamera":
        """Same rig with another eye separation."""
        return StereoCamera(self.position, self.view_dir, self.up, interaxial, self.focal_distance,
                            self.vfov_deg, self.near, self.far, self.width, self.height)

    # ------------------------------------------------------------------ parallax
    def depth_of(self, points_world) -> np.ndarray:
        """Planar depth of world points along the view direction from ``V_p`` (> 0 in front)."""
        pts = check_array("points_world", points_world, dtype_kind="fiu").astype(np.float64)
        if pts.shape[-1:] != (3,):
            raise ValueError(f"points_world: expected shape (..., 3), got {pts.shape}")
        return (pts - self.position) @ self.view_dir

    def parallax(self, points_world) -> dict[str, np.ndarray]:
        """Parallax of world points, measured by projecting them through both eye cameras.

        Returns a dict with ``scene`` (on the zero-parallax plane, scene units, eq. 9),
        ``px`` (u_right - u_left in pixels), ``vertical_px`` (v_right - v_left, zero by
        construction), ``angle_deg`` (eq. 10, signed) and ``z`` (planar depth).
        """
        left, right = self.cameras()
        uv_l, _ = left.project(points_world)
        uv_r, _ = right.project(points_world)
        px = uv_r[..., 0] - uv_l[..., 0]
        scene = px * self.focal_distance / self.focal_px  # pixel size on the plane z = f is f / fx
        return {
            "z": self.depth_of(points_world),
            "px": px,
            "vertical_px": uv_r[..., 1] - uv_l[..., 1],
            "scene": scene,
            "angle_deg": parallax_angle_deg(scene, f=self.focal_distance),
        }

    def max_parallax_angle_deg(self, z_near: float, z_far: float) -> float:
        """Largest |visual angle| of parallax over planar depths [z_near, z_far]."""
        return comfort(z_near, z_far, e=self.interaxial, f=self.focal_distance).max_angle_deg


def parallax_scene(z, *, e: float, f: float) -> np.ndarray:
    """Eq. 9 with z > 0 in front: horizontal parallax ``P = e (1 - f / z)`` on the zero-parallax
    plane, in scene units. Seed 000 prints ``e (1 + f/z)`` with OpenGL's z < 0."""
    z = np.asarray(z, dtype=np.float64)
    return e * (1.0 - f / z)


def parallax_px(z, *, e: float, f: float, focal_px: float) -> np.ndarray:
    """Parallax in pixels, ``u_right - u_left = focal_px * e * (1/f - 1/z)``.

    Equals :func:`parallax_scene` scaled by ``focal_px / f`` (the pixel size on the plane z = f
    is f / focal_px). Example: e = 0.088, f = 3.144, focal_px = 549.0, z = 2.344 gives -5.24 px.
    """
    z = np.asarray(z, dtype=np.float64)
    return focal_px * e * (1.0 / f - 1.0 / z)


def interaxial_for_parallax(parallax, z, *, f: float) -> np.ndarray:
    """Eq. 11 with z > 0 in front: the interaxial ``e = P / (1 - f/z)`` that gives parallax P
    (scene units on the zero-parallax plane) at depth z; the seed writes ``P z/(z + f)`` with
    GL's z < 0. Undefined (inf) at z = f, where every e gives zero parallax."""
    f = check_positive("f", f)
    z = np.asarray(z, dtype=np.float64)
    with np.errstate(divide="ignore"):
        return np.asarray(parallax, dtype=np.float64) / (1.0 - f / z)


def parallax_angle_deg(parallax, *, f: float) -> np.ndarray:
    """Eq. 10 inverted: visual angle ``beta = 2 atan(P / (2 f))`` in degrees (signed)."""
    f = check_positive("f", f)
    return np.degrees(2 * np.arctan(np.asarray(parallax, dtype=np.float64) / (2 * f)))


def max_interaxial(f: float, *, max_angle_deg: float = DEFAULT_MAX_ANGLE_DEG) -> float:
    """Eq. 12 with the limit as a parameter: ``e_max = 2 f tan(beta_max / 2)``.

    This bounds |P| <= 2 f tan(beta/2) for every depth in [f/2, inf): the far limit gives
    P -> e and the near limit z = f/2 gives P = -e. 1.6 degrees gives 0.0279 f (the seed's
    "0.028 f"); the seed's stated 1.5 degrees gives 0.0262 f (DESIGN.md section 3).
    """
    f = check_positive("f", f)
    beta = check_positive("max_angle_deg", max_angle_deg)
    if beta >= 180:
        raise ValueError(f"max_angle_deg: expected < 180, got {max_angle_deg!r}")
    return 2 * f * np.tan(np.radians(beta) / 2)


def max_interaxial_for_range(z_near: float, z_far: float, f: float, *,
                             max_angle_deg: float = DEFAULT_MAX_ANGLE_DEG) -> float:
    """Largest e keeping |P(z)| <= 2 f tan(beta/2) for all z in [z_near, z_far] (z_far may be inf).

    ``P(z) = e (1 - f/z)`` is monotone in z, so the extremes are ``e (f/z_near - 1)`` (crossed)
    and ``e (1 - f/z_far)`` (uncrossed).
    """
    zn = check_positive("z_near", z_near)
    zf = check_positive("z_far", z_far, allow_inf=True)
    if zf < zn:
        raise ValueError(f"z_far: expected z_far >= z_near, got {z_near!r}, {z_far!r}")
    p_max = max_interaxial(f, max_angle_deg=max_angle_deg)
    worst = max(f / zn - 1.0, 1.0 - f / zf, 0.0)
    return np.inf if worst == 0 else p_max / worst


@dataclass(frozen=True)
class ComfortReport:
    """Comfort check of a stereo setting over a depth range (seed 000 section 3.3, step 2)."""

    ok: bool  #: both limits hold
    max_angle_deg: float  #: largest |parallax visual angle| over the range
    angle_limit_deg: float
    nearest_ok: bool  #: z_near >= f / 2
    crossed_angle_deg: float  #: angle at z_near (negative: in front of the screen)
    uncrossed_angle_deg: float  #: angle at z_far (positive: behind the screen)


def comfort(z_near: float, z_far: float, *, e: float, f: float,
            max_angle_deg: float = DEFAULT_MAX_ANGLE_DEG) -> ComfortReport:
    """Check a stereo setting: parallax visual angle within the limit, nearest object >= f/2."""
    zn = check_positive("z_near", z_near)
    zf = check_positive("z_far", z_far, allow_inf=True)
    f = check_positive("f", f)
    e = check_finite_scalar("e", e)
    lim = check_positive("max_angle_deg", max_angle_deg)
    a_near = float(parallax_angle_deg(parallax_scene(zn, e=e, f=f), f=f))
    a_far = float(parallax_angle_deg(e if np.isinf(zf) else parallax_scene(zf, e=e, f=f), f=f))
    worst = max(abs(a_near), abs(a_far))
    nearest_ok = zn >= f / 2
    return ComfortReport(bool(worst <= lim + 1e-12 and nearest_ok), worst, lim, bool(nearest_ok), a_near, a_far)


#: ``auto_stereo`` ("balanced") takes at most this many times the seed's interaxial ``2 f tan(beta/2)``:
#: the eyes' principal-point shift ``fx e / (2 f)`` stays under ``10 fx tan(beta/2)`` (0.28 fx at 3.2 deg).
MAX_E_OVER_SEED = 10.0


def auto_stereo(depth, *, max_angle_deg: float = DEFAULT_MAX_ANGLE_DEG,
                percentiles: tuple[float, float] = (1.0, 99.0),
                mode: str = "balanced") -> tuple[float, float]:
    """Choose the zero-parallax distance f and the interaxial e from a depth map.

    The near and far depths are robust percentiles of the valid (finite, > 0) planar depths, so a
    few stray pixels do not decide. ``mode``:

    * ``"balanced"`` puts f at the harmonic mean ``2 / (1/z_near + 1/z_far)``, where the crossed
      and uncrossed extremes have equal magnitude, and takes the largest e that keeps both within
      the angle limit (:func:`max_interaxial_for_range`), at most :data:`MAX_E_OVER_SEED` times
      the seed's e (a nearly flat scene allows any e). f <= 2 z_near always holds, so the nearest
      object is never closer than f/2.
    * ``"seed"`` follows seed 000's recipe literally: f = 2 z_near (the nearest object exactly at
      f/2) and e = 2 f tan(beta/2) (eq. 12), safe for any far depth.

    Returns
    -------
    e, f : float
        Interaxial and zero-parallax distance in scene units.
    """
    z = check_array("depth", depth, dtype_kind="fiu").astype(np.float64).ravel()
    check_choice("mode", mode, ("balanced", "seed"))
    lo, hi = (check_finite_scalar("percentiles", p) for p in percentiles)
    if not 0 <= lo < hi <= 100:
        raise ValueError(f"percentiles: expected 0 <= low < high <= 100, got {percentiles!r}")
    z = z[np.isfinite(z) & (z > 0)]
    if z.size == 0:
        raise ValueError("depth: no valid (finite, positive) depth values")
    z_near, z_far = np.percentile(z, [lo, hi])
    if mode == "seed":
        f = 2 * z_near
        return max_interaxial(f, max_angle_deg=max_angle_deg), f
    f = 2.0 / (1.0 / z_near + 1.0 / z_far)
    e = max_interaxial_for_range(z_near, z_far, f, max_angle_deg=max_angle_deg)
    if not np.isfinite(e):  # flat depth: any e keeps zero parallax; fall back to the seed's rule
        e = max_interaxial(f, max_angle_deg=max_angle_deg)
    # a nearly flat scene allows an unbounded e (2..2.000001 gave e = 234 269 and a principal-point
    # shift of 7e6 px): at most MAX_E_OVER_SEED times the seed's e, safe for any depth
    e = min(e, MAX_E_OVER_SEED * max_interaxial(f, max_angle_deg=max_angle_deg))
    return float(e), float(f)
