"""Pinhole camera: intrinsics, pose, projection, rays, pose interpolation and OpenGL interop.

Conventions (DESIGN.md section 4)
---------------------------------
* Camera frame: x right, y down, z forward (OpenCV). A point in front of the camera has z > 0.
* Pose: ``world_from_cam`` is a 4x4 camera-to-world matrix, so
  ``X_world = world_from_cam @ [X_cam, 1]``.
* The world frame of a camera with the identity pose *is* its camera frame, so the default
  world "up" direction is -y: ``look_at(..., up=(0, -1, 0))``.
* Pixels: pixel (u, v) = (column, row); its center is at integer coordinates, the image spans
  [-0.5, W - 0.5] x [-0.5, H - 0.5]. Projection is ``u = fx * X / Z + cx``; a centered principal
  point is therefore ``cx = (W - 1) / 2`` (e.g. 255.5 for W = 512).
* OpenGL eye frame: x right, y up, looking down -z; ``cam_gl = GL_FROM_CV @ cam_cv`` with
  ``GL_FROM_CV = diag(1, -1, -1, 1)``. NDC x = -1 is the left edge of pixel column 0
  (u = -0.5) and NDC y = +1 the top edge of row 0 (v = -0.5).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import math

import numpy as np

from .validate import (MAX_FOCAL_PX, MAX_PRINCIPAL_PX, check_array, check_camera_dict, check_finite_scalar,
                       check_image_size, check_near_far, check_positive)

__all__ = [
    "Camera",
    "GL_FROM_CV",
    "GLFrustum",
    "camera_from_gl_projection",
    "gl_frustum_from_projection",
    "interpolate_cameras",
    "look_at",
]

GL_FROM_CV = np.diag([1.0, -1.0, -1.0, 1.0])
GL_FROM_CV.setflags(write=False)


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=np.float64, copy=True)
    a.setflags(write=False)
    return a


def _check_pose(name: str, pose) -> np.ndarray:
    m = check_array(name, pose, shape=(4, 4), dtype_kind="fiu").astype(np.float64)
    if not np.all(np.isfinite(m)):
        raise ValueError(f"{name}: pose has non-finite entries")
    # the last row exactly (rtol=0: np.allclose's default 1e-5 let 1.000009 through); R R^T within
    # 1e-5 in every entry: poses written with 6 decimals are ~1e-6 off (at 1e-6, 2-21 % failed)
    if not np.allclose(m[3], [0, 0, 0, 1], rtol=0, atol=1e-9):
        raise ValueError(f"{name}: last row must be [0, 0, 0, 1], got {m[3].tolist()}")
    r = m[:3, :3]
    with np.errstate(over="ignore", invalid="ignore"):  # huge entries overflow to inf: not a rotation either
        orthonormal = np.allclose(r @ r.T, np.eye(3), rtol=0, atol=1e-5)
    if not orthonormal or np.linalg.det(r) < 0:
        raise ValueError(f"{name}: rotation block must be a proper rotation (orthonormal, det +1)")
    return m


def _check_side(name: str, value) -> int:
    """An image side in pixels: an integer >= 1 (an integral float is taken), or ValueError naming ``name``."""
    if (isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating))
            or not (isinstance(value, (int, np.integer)) or math.isfinite(value))  # ints: np.isfinite overflows
            or int(value) != value or int(value) < 1):
        raise ValueError(f"{name}: expected a positive integer, got {value!r:.40}")
    return int(value)


@dataclass(frozen=True, eq=False)
class Camera:
    """Pinhole camera with intrinsics in pixels and a camera-to-world pose.

    Parameters
    ----------
    fx, fy : float
        Focal lengths in pixels (> 0).
    cx, cy : float
        Principal point in pixels, pixel-center convention: a centered principal point of a
        512-wide image is ``cx = 255.5``.
    width, height : int
        Image size in pixels (>= 1).
    world_from_cam : (4, 4) array, optional
        Camera-to-world rigid transform; identity by default. Stored read-only.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int
    world_from_cam: np.ndarray = field(default_factory=lambda: np.eye(4))

    def __post_init__(self):
        set_ = object.__setattr__
        # the ranges of a camera file (check_camera_dict): the library refuses what the CLI refuses
        for name in ("fx", "fy"):
            value = check_positive(name, getattr(self, name))
            if value > MAX_FOCAL_PX:
                raise ValueError(f"{name}: expected at most {MAX_FOCAL_PX:g} pixels, got {value!r}")
            set_(self, name, value)
        for name in ("cx", "cy"):
            value = check_finite_scalar(name, getattr(self, name))
            if abs(value) > MAX_PRINCIPAL_PX:
                raise ValueError(f"{name}: expected at most {MAX_PRINCIPAL_PX:g} pixels in magnitude, got {value!r}")
            set_(self, name, value)
        for name in ("width", "height"):
            set_(self, name, _check_side(name, getattr(self, name)))
        check_image_size("camera", self.width, self.height)  # ceilings before any image is allocated (#12)
        set_(self, "world_from_cam", _readonly(_check_pose("world_from_cam", self.world_from_cam)))

    # ----------------------------------------------------------------- construction
    @classmethod
    def from_fov(
        cls,
        width: int,
        height: int,
        *,
        hfov_deg: float | None = None,
        vfov_deg: float | None = None,
        world_from_cam=None,
    ) -> "Camera":
        """Camera with square pixels and a centered principal point from one field of view.

        ``hfov_deg`` spans the full image width (edge to edge, i.e. ``W`` pixels), so
        ``fx = W / (2 tan(hfov/2))``; for W = 512 and 90 degrees, fx = 256.
        """
        if (hfov_deg is None) == (vfov_deg is None):
            raise ValueError("from_fov: give exactly one of hfov_deg, vfov_deg")
        width, height = _check_side("width", width), _check_side("height", height)
        if hfov_deg is not None:
            fov = check_finite_scalar("hfov_deg", hfov_deg)
            if not 0 < fov < 180:
                raise ValueError(f"hfov_deg: expected 0 < fov < 180, got {hfov_deg!r}")
            f = width / (2 * np.tan(np.radians(fov) / 2))
        else:
            fov = check_finite_scalar("vfov_deg", vfov_deg)
            if not 0 < fov < 180:
                raise ValueError(f"vfov_deg: expected 0 < fov < 180, got {vfov_deg!r}")
            f = height / (2 * np.tan(np.radians(fov) / 2))
        pose = np.eye(4) if world_from_cam is None else world_from_cam
        return cls(f, f, (width - 1) / 2, (height - 1) / 2, width, height, pose)

    def with_pose(self, world_from_cam) -> "Camera":
        """Same intrinsics, another pose."""
        return replace(self, world_from_cam=world_from_cam)

    def translated(self, offset_cam) -> "Camera":
        """Same camera moved by ``offset_cam`` (3,) expressed in its own camera frame."""
        offset = check_array("offset_cam", offset_cam, shape=(3,), dtype_kind="fiu")
        pose = self.world_from_cam.copy()
        pose[:3, 3] += pose[:3, :3] @ offset
        return self.with_pose(pose)

    def resized(self, width: int, height: int) -> "Camera":
        """Camera for the same view rendered at another resolution (pixel-center aware)."""
        width, height = _check_side("width", width), _check_side("height", height)
        sx, sy = width / self.width, height / self.height
        return replace(
            self,
            fx=self.fx * sx,
            fy=self.fy * sy,
            cx=(self.cx + 0.5) * sx - 0.5,
            cy=(self.cy + 0.5) * sy - 0.5,
            width=width,
            height=height,
        )

    # ----------------------------------------------------------------- matrices
    @property
    def K(self) -> np.ndarray:
        """3x3 intrinsic matrix ``pix_from_cam``."""
        return np.array([[self.fx, 0, self.cx], [0, self.fy, self.cy], [0, 0, 1.0]])

    @property
    def cam_from_world(self) -> np.ndarray:
        """4x4 world-to-camera transform (inverse of the pose); a fresh array each time (made
        once per camera: a frame asks for it several times)."""
        m = self.__dict__.get("_cam_from_world")
        if m is None:
            r = self.world_from_cam[:3, :3]
            t = self.world_from_cam[:3, 3]
            m = np.eye(4)
            m[:3, :3] = r.T
            m[:3, 3] = -r.T @ t
            object.__setattr__(self, "_cam_from_world", m)
        return m.copy()

    @property
    def position(self) -> np.ndarray:
        """Camera center in world coordinates, shape (3,)."""
        return self.world_from_cam[:3, 3].copy()

    @property
    def shape(self) -> tuple[int, int]:
        """Image shape ``(height, width)``."""
        return (self.height, self.width)

    # ----------------------------------------------------------------- projection
    def project(self, points_world) -> tuple[np.ndarray, np.ndarray]:
        """Project world points to pixels.

        Parameters
        ----------
        points_world : (..., 3) array

        Returns
        -------
        uv : (..., 2) float64
            Pixel coordinates (column, row), centers at integers; NaN for points with z <= 0
            (on or behind the camera plane).
        z : (...,) float64
            Planar depth along the optical axis in scene units (negative behind the camera).
        """
        pts = check_array("points_world", points_world, dtype_kind="fiu")
        if pts.shape[-1:] != (3,):
            raise ValueError(f"points_world: expected shape (..., 3), got {pts.shape}")
        cam = pts.astype(np.float64) @ self.cam_from_world[:3, :3].T + self.cam_from_world[:3, 3]
        return self.project_cam(cam)

    def project_cam(self, points_cam) -> tuple[np.ndarray, np.ndarray]:
        """Project camera-frame points (..., 3) to pixels; see :meth:`project`."""
        pts = np.asarray(points_cam, dtype=np.float64)
        z = pts[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = np.where(z > 0, 1.0 / z, np.nan)
        uv = np.stack([self.fx * pts[..., 0] * inv + self.cx, self.fy * pts[..., 1] * inv + self.cy], -1)
        return uv, z

    def unproject(self, uv, z, *, frame: str = "world") -> np.ndarray:
        """Lift pixels with planar depth to 3-D points.

        Parameters
        ----------
        uv : (..., 2) array
            Pixel coordinates (column, row), centers at integers.
        z : (...,) array
            Planar depth (along the optical axis), scene units. NaN propagates.
        frame : {"world", "cam"}
            Frame of the returned points.
        """
        uv = np.asarray(uv, dtype=np.float64)
        z = np.asarray(z, dtype=np.float64)
        x = (uv[..., 0] - self.cx) / self.fx * z
        y = (uv[..., 1] - self.cy) / self.fy * z
        cam = np.stack([x, y, z], -1)
        if frame == "cam":
            return cam
        if frame != "world":
            raise ValueError(f"frame: expected 'world' or 'cam', got {frame!r}")
        return cam @ self.world_from_cam[:3, :3].T + self.world_from_cam[:3, 3]

    def pixel_grid(self) -> tuple[np.ndarray, np.ndarray]:
        """Integer pixel-center coordinates ``(u, v)``, each of shape (H, W), float64."""
        v, u = np.mgrid[0 : self.height, 0 : self.width].astype(np.float64)
        return u, v

    def rays_cam(self) -> np.ndarray:
        """Per-pixel ray directions in the camera frame, shape (H, W, 3), scaled to z = 1.

        Multiplying by a planar depth gives the camera-frame point; the ray length
        ``norm(rays_cam)`` converts planar z to range (distance along the ray).
        """
        u, v = self.pixel_grid()
        return np.stack([(u - self.cx) / self.fx, (v - self.cy) / self.fy, np.ones_like(u)], -1)

    def rays_world(self) -> tuple[np.ndarray, np.ndarray]:
        """Ray origin (3,) and unit directions (H, W, 3) in the world frame."""
        d = self.rays_cam() @ self.world_from_cam[:3, :3].T
        d /= np.linalg.norm(d, axis=-1, keepdims=True)
        return self.position, d

    # ----------------------------------------------------------------- OpenGL interop
    def gl_projection(self, near: float, far: float) -> np.ndarray:
        """OpenGL perspective matrix (clip_from_eye_gl) for this camera and clip planes.

        Off-axis (asymmetric) when the principal point is not centered. ``far`` may be
        ``inf`` (infinite far plane). Window depth ``d = (z_ndc + 1) / 2`` of a point at planar
        depth z is then ``far / (far - near) * (1 - near / z)``, seed 002 eq. 2 divided by 2^24.
        """
        return self.gl_frustum(near, far).projection()

    def gl_frustum(self, near: float, far: float) -> "GLFrustum":
        """glFrustum(l, r, b, t, n, f) of this camera: the image edges on the near plane.

        Pixel edges, not centers, bound the frustum: ``left = -(cx + 0.5) * near / fx``, so a
        512-wide camera with cx = 255.5 and fx = 256 has left = -near, right = +near.
        """
        n, f = check_near_far(near, far)
        return GLFrustum(
            left=-(self.cx + 0.5) * n / self.fx,
            right=(self.width - 0.5 - self.cx) * n / self.fx,
            bottom=-(self.height - 0.5 - self.cy) * n / self.fy,
            top=(self.cy + 0.5) * n / self.fy,
            near=n,
            far=f,
        )

    def gl_view(self) -> np.ndarray:
        """OpenGL view matrix ``eye_gl_from_world`` (the modelview of a scene in world units)."""
        return GL_FROM_CV @ self.cam_from_world

    # ----------------------------------------------------------------- serialization
    def to_dict(self) -> dict[str, Any]:
        """JSON-ready dict (see README, view file schema)."""
        return {
            "width": self.width,
            "height": self.height,
            "fx": self.fx,
            "fy": self.fy,
            "cx": self.cx,
            "cy": self.cy,
            "world_from_cam": self.world_from_cam.tolist(),
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "Camera":
        """Inverse of :meth:`to_dict`; raises ``ValueError`` naming a missing, unknown or bad key
        (:func:`~ibr.base.validate.check_camera_dict`)."""
        d = check_camera_dict(d, "camera")  # strict: unknown keys, types, finiteness, ranges (#12)
        return cls(d["fx"], d["fy"], d["cx"], d["cy"], d["width"], d["height"], d["world_from_cam"])

    def __repr__(self) -> str:
        p = self.position
        return (
            f"Camera({self.width}x{self.height}, fx={self.fx:.6g}, fy={self.fy:.6g}, "
            f"cx={self.cx:.6g}, cy={self.cy:.6g}, position=[{p[0]:.4g}, {p[1]:.4g}, {p[2]:.4g}])"
        )

    def allclose(self, other: "Camera", *, atol: float = 1e-9) -> bool:
        """True when intrinsics, size and pose agree within ``atol``."""
        return (
            self.width == other.width
            and self.height == other.height
            and np.allclose(
                [self.fx, self.fy, self.cx, self.cy], [other.fx, other.fy, other.cx, other.cy], atol=atol
            )
            and np.allclose(self.world_from_cam, other.world_from_cam, atol=atol)
        )


def look_at(eye, target, up=(0.0, -1.0, 0.0)) -> np.ndarray:
    """Camera-to-world pose of a camera at ``eye`` looking at ``target``.

    The camera's +z axis points at the target, +x to the right and +y down, so that the
    world ``up`` vector appears upward in the image. The default ``up = (0, -1, 0)`` matches
    the identity camera (world frame = camera frame of an unmoved camera).
    """
    eye = check_array("eye", eye, shape=(3,), dtype_kind="fiu").astype(float)
    target = check_array("target", target, shape=(3,), dtype_kind="fiu").astype(float)
    up = check_array("up", up, shape=(3,), dtype_kind="fiu").astype(float)
    for name, v in (("eye", eye), ("target", target), ("up", up)):
        if not np.all(np.isfinite(v)):
            raise ValueError(f"{name}: expected finite coordinates, got {v.tolist()}")
    z = target - eye
    if np.linalg.norm(z) == 0:
        raise ValueError("target: must differ from eye")
    if np.linalg.norm(up) == 0:
        raise ValueError("up: must not be the zero vector")
    z /= np.linalg.norm(z)
    x = np.cross(z, up / np.linalg.norm(up))  # x = y_cam × z with y_cam = -up (image y points down)
    if np.linalg.norm(x) < 1e-12:
        raise ValueError("up: must not be parallel to the viewing direction")
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2], pose[:3, 3] = x, y, z, eye
    return pose


def interpolate_cameras(a: Camera, b: Camera, t: float) -> Camera:
    """Camera between ``a`` (t = 0) and ``b`` (t = 1).

    Rotation by spherical linear interpolation (slerp), position and intrinsics by linear
    interpolation. ``t`` outside [0, 1] extrapolates. Image sizes must agree.
    """
    t = check_finite_scalar("t", t)
    if (a.width, a.height) != (b.width, b.height):
        raise ValueError(f"b: image size {b.width}x{b.height} differs from a's {a.width}x{a.height}")
    # slerp = the geodesic R(t) = exp(t log(Rb Ra^T)) Ra (also for t outside [0, 1]), with the
    # rotation vector of the relative rotation from cv2.Rodrigues (scipy.spatial cost 0.3-0.5 s
    # of import in every command, #13)
    import cv2

    ra, rb = a.world_from_cam[:3, :3], b.world_from_cam[:3, :3]
    rvec = cv2.Rodrigues(np.ascontiguousarray(rb @ ra.T))[0]
    r = cv2.Rodrigues(rvec * t)[0] @ ra
    pose = np.eye(4)
    pose[:3, :3] = r
    pose[:3, 3] = (1 - t) * a.world_from_cam[:3, 3] + t * b.world_from_cam[:3, 3]
    lerp = lambda p, q: (1 - t) * p + t * q  # noqa: E731
    try:
        return Camera(lerp(a.fx, b.fx), lerp(a.fy, b.fy), lerp(a.cx, b.cx), lerp(a.cy, b.cy), a.width, a.height,
                      pose)
    except ValueError as exc:  # far outside [0, 1]: a focal length <= 0, a pose that overflowed
        raise ValueError(f"t: {t!r} extrapolates to an impossible camera ({exc})") from None


@dataclass(frozen=True)
class GLFrustum:
    """Frustum recovered from an OpenGL projection matrix (glFrustum parameters).

    ``left, right, bottom, top`` are on the near plane in eye units; ``far`` may be inf.
    """

    left: float
    right: float
    bottom: float
    top: float
    near: float
    far: float

    def projection(self) -> np.ndarray:
        """The 4x4 OpenGL matrix (clip_from_eye_gl) of glFrustum(l, r, b, t, n, f); far may be inf."""
        l, r, b, t, n, f = self.left, self.right, self.bottom, self.top, self.near, self.far
        p = np.zeros((4, 4))
        p[0, 0] = 2 * n / (r - l)
        p[0, 2] = (r + l) / (r - l)
        p[1, 1] = 2 * n / (t - b)
        p[1, 2] = (t + b) / (t - b)
        if np.isinf(f):
            p[2, 2], p[2, 3] = -1.0, -2 * n
        else:
            p[2, 2], p[2, 3] = -(f + n) / (f - n), -2 * f * n / (f - n)
        p[3, 2] = -1.0
        return p


def gl_frustum_from_projection(projection) -> GLFrustum:
    """Recover glFrustum(l, r, b, t, n, f) from a 4x4 OpenGL perspective matrix (seed 003).

    Raises
    ------
    ValueError
        For an orthographic matrix (last row [0, 0, 0, 1]) or any matrix that is not of the
        perspective form ``[[a, 0, c, 0], [0, b, d, 0], [0, 0, e, g], [0, 0, -1, 0]]``
        with a, b > 0 and a valid near/far pair.
    """
    p = check_array("projection", projection, shape=(4, 4), dtype_kind="fiu").astype(np.float64)
    if not np.all(np.isfinite(p)):
        raise ValueError("projection: matrix has non-finite entries")
    if np.allclose(p[3], [0, 0, 0, 1]):
        raise ValueError("projection: this is an orthographic matrix (last row [0, 0, 0, 1]); "
                         "a perspective matrix is required")
    scale = -p[3, 2]
    if abs(scale) < 1e-12 or not np.allclose(p[3] / scale, [0, 0, -1, 0], atol=1e-9):
        raise ValueError(f"projection: last row must be [0, 0, -1, 0] for a perspective matrix, "
                         f"got {p[3].tolist()}")
    p = p / scale  # tolerate a uniformly scaled matrix (same homogeneous projection)
    zero_entries = [p[0, 1], p[0, 3], p[1, 0], p[1, 3], p[2, 0], p[2, 1]]
    if not np.allclose(zero_entries, 0, atol=1e-9):
        raise ValueError("projection: not a perspective matrix (unexpected shear or translation terms)")
    a, b, c, d, e, g = p[0, 0], p[1, 1], p[0, 2], p[1, 2], p[2, 2], p[2, 3]
    if a <= 0 or b <= 0:
        raise ValueError(f"projection: P[0,0] and P[1,1] must be positive, got {a}, {b}")
    if g >= 0:
        raise ValueError(f"projection: P[2,3] must be negative for near > 0, got {g}")
    near = g / (e - 1)
    far = np.inf if abs(e + 1) < 1e-12 else g / (e + 1)
    if not (near > 0 and (far > near)):
        raise ValueError(f"projection: implies near={near}, far={far}; need 0 < near < far")
    # glFrustum: a = 2n/(r-l), c = (r+l)/(r-l), b = 2n/(t-b), d = (t+b)/(t-b)
    left, right = near * (c - 1) / a, near * (c + 1) / a
    bottom, top = near * (d - 1) / b, near * (d + 1) / b
    return GLFrustum(left, right, bottom, top, near, far)


def camera_from_gl_projection(projection, width: int, height: int, *, view=None) -> tuple[Camera, float, float]:
    """Recover a :class:`Camera` plus (near, far) from an OpenGL projection matrix.

    Parameters
    ----------
    projection : (4, 4) array
        OpenGL perspective matrix (clip_from_eye_gl), column vectors.
    width, height : int
        Viewport size in pixels.
    view : (4, 4) array, optional
        OpenGL view matrix (eye_gl_from_world); identity when omitted.

    Returns
    -------
    camera, near, far
        Inverse of :meth:`Camera.gl_projection` and :meth:`Camera.gl_view`.
    """
    fr = gl_frustum_from_projection(projection)
    p = np.asarray(projection, dtype=np.float64)
    p = p / -p[3, 2]
    fx = p[0, 0] * width / 2
    fy = p[1, 1] * height / 2
    cx = (1 - p[0, 2]) * width / 2 - 0.5
    cy = (1 + p[1, 2]) * height / 2 - 0.5
    if view is None:
        pose = np.eye(4)
    else:
        v = check_array("view", view, shape=(4, 4), dtype_kind="fiu").astype(np.float64)
        pose = np.linalg.inv(GL_FROM_CV @ v)  # cam_cv_from_world = GL_FROM_CV @ eye_gl_from_world
    return Camera(fx, fy, cx, cy, width, height, pose), fr.near, fr.far
