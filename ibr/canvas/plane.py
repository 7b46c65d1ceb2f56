"""The virtual canvas (seed 004): an RGBA buffer bound to a rectangle in the world.

A :class:`Canvas` is a ``W x H`` RGBA pixel buffer (the seed's "虚拟画布", a block of memory
whose colours feed a texture) laid onto a world rectangle given by its ``center``, unit
``normal`` (the side it is seen from), ``up`` direction and size ``width x height`` in scene
units. Any orientation is allowed.

Frame of the canvas
-------------------
``right = up x normal`` and ``down = -up`` (``up`` is first made orthogonal to ``normal``).
Seen from the normal side (a viewer looking along ``-normal`` with ``up`` pointing up in the
image), canvas columns grow to the viewer's right and rows grow downward -- the camera
convention of DESIGN.md section 4 (x right, y down, z forward = ``-normal``) applied to the
canvas. Pixel (x, y) = (column, row) has its centre at integer coordinates and the buffer spans
[-0.5, W - 0.5] x [-0.5, H - 0.5]. A world point P on the plane maps to

    x = ((P - center) . right / width  + 1/2) * W - 1/2
    y = ((P - center) . down  / height + 1/2) * H - 1/2

and back by ``P = center + right * width * ((x + 1/2) / W - 1/2) + down * height * ((y + 1/2) / H - 1/2)``.

Seed 004 (section 2.2) gives this mapping only for planes parallel to XOY or YOZ in a y-up
right-handed frame, with the texture coordinate measured from the pixel *edge*
(``X_d = ((X_p - X_o) + N/2) / N * T``). With ``up = (0, 1, 0)`` the general formula reproduces
its four cases -- normal +z: right = +x; normal -z: right = -x; normal +x: right = -z;
normal -x: right = +z; in all four, rows grow along -y -- and ``X_d = x + 1/2`` (edge versus
centre convention). ``tests/test_canvas.py`` checks all four.
"""

from __future__ import annotations

import numpy as np

from ..base.camera import Camera
from ..base.validate import check_array, check_image, check_image_size, check_number, check_unit_vector

__all__ = ["Canvas", "MAX_TEXELS"]

#: Largest canvas buffer accepted (pixels): 8192 x 8192 (also within ibr.base.validate's image ceilings).
MAX_TEXELS = 1 << 26

_DTYPES = (np.uint8, np.uint16, np.float32)


def _check_resolution(resolution) -> tuple[int, int]:
    try:
        items = tuple(resolution)
    except TypeError:
        raise TypeError(f"resolution: expected two positive integers (W, H), got {resolution!r}") from None
    if len(items) != 2:
        raise ValueError(f"resolution: expected two positive integers (W, H), got {resolution!r}")
    w = check_number("resolution: width", items[0], integer=True, minimum=1)
    h = check_number("resolution: height", items[1], integer=True, minimum=1)
    if w * h > MAX_TEXELS:
        raise ValueError(f"resolution: {w} x {h} exceeds the canvas limit of {MAX_TEXELS} pixels")
    return check_image_size("resolution", w, h, channels=4, itemsize=4)


def _check_size(size) -> tuple[float, float]:
    vals = check_array("size", size, shape=(2,), dtype_kind="fiu").astype(np.float64)
    if not np.all(np.isfinite(vals)) or np.any(vals <= 0):
        raise ValueError(f"size: expected a positive finite (width, height) in scene units, got {vals.tolist()}")
    return float(vals[0]), float(vals[1])


class Canvas:
    """An RGBA buffer bound to a world rectangle (see the module docstring for the frame).

    Parameters
    ----------
    center : (3,) array
        Centre of the rectangle, world coordinates (scene units).
    normal : (3,) array
        Normal of the visible side (normalized here; a zero vector is refused).
    size : (2,) array
        ``(width, height)`` of the rectangle in scene units (> 0).
    up : (3,) array
        Direction that is "up" on the canvas; made orthogonal to ``normal``. Default ``(0, -1, 0)``,
        the world up of the engine (y points down). Must not be parallel to ``normal``.
    resolution : (W, H) ints, optional
        Buffer size in pixels; default 512 pixels along the longer side, the other side in
        proportion to ``size`` (square texels).
    dtype : {uint8, uint16, float32}
        Buffer dtype; colours of float buffers are in [0, 1].
    rgba : (H, W, 4) array, optional
        Initial content (straight, i.e. not premultiplied, alpha); default transparent black.
    name : str
        Label for messages.

    Attributes
    ----------
    rgba : (H, W, 4) ndarray
        The buffer, straight alpha; content may be changed in place (video frames, strokes).
    right, down : (3,) float64
        Unit in-plane axes of columns and rows.
    """

    def __init__(self, center, normal, size, *, up=(0.0, -1.0, 0.0), resolution=None, dtype=np.uint8,
                 rgba=None, name: str = "canvas"):
        c = check_array("center", center, shape=(3,), dtype_kind="fiu").astype(np.float64)
        if not np.all(np.isfinite(c)):
            raise ValueError(f"center: expected finite coordinates, got {c.tolist()}")
        n = check_unit_vector("normal", normal)
        u = check_unit_vector("up", up)
        u = u - (u @ n) * n  # Gram-Schmidt: the in-plane component of up
        if np.linalg.norm(u) < 1e-9:
            raise ValueError(f"up: must not be parallel to normal, got up={np.asarray(up).tolist()}, "
                             f"normal={np.asarray(normal).tolist()}")
        u /= np.linalg.norm(u)
        self._width, self._height = _check_size(size)
        if rgba is not None:
            rgba = check_image("rgba", rgba, channels=(4,))
            dtype = rgba.dtype
            if resolution is not None and tuple(resolution) != (rgba.shape[1], rgba.shape[0]):
                raise ValueError(f"resolution: {tuple(resolution)} differs from the rgba buffer's "
                                 f"{rgba.shape[1]} x {rgba.shape[0]}")
            resolution = (rgba.shape[1], rgba.shape[0])
        if resolution is None:
            long = 512
            if self._width >= self._height:
                resolution = (long, max(1, round(long * self._height / self._width)))
            else:
                resolution = (max(1, round(long * self._width / self._height)), long)
        w, h = _check_resolution(resolution)
        dtype = np.dtype(dtype)
        if dtype not in [np.dtype(d) for d in _DTYPES]:
            raise ValueError(f"dtype: expected uint8, uint16 or float32, got {dtype}")
        self.rgba = np.zeros((h, w, 4), dtype) if rgba is None else np.ascontiguousarray(rgba).copy()
        self.name = str(name)
        self._center, self._normal, self._up = c, n, u
        self._right = np.cross(u, n)
        for a in (self._center, self._normal, self._up, self._right):
            a.setflags(write=False)

    # ------------------------------------------------------------------ geometry
    @property
    def center(self) -> np.ndarray:
        return self._center

    @property
    def normal(self) -> np.ndarray:
        return self._normal

    @property
    def up(self) -> np.ndarray:
        """Unit up vector, orthogonal to the normal."""
        return self._up

    @property
    def right(self) -> np.ndarray:
        """Unit direction of growing columns: ``up x normal``."""
        return self._right

    @property
    def down(self) -> np.ndarray:
        """Unit direction of growing rows: ``-up``."""
        return -self._up

    @property
    def size(self) -> tuple[float, float]:
        """``(width, height)`` in scene units."""
        return self._width, self._height

    @property
    def resolution(self) -> tuple[int, int]:
        """``(W, H)`` of the buffer in pixels."""
        return self.rgba.shape[1], self.rgba.shape[0]

    @property
    def max_value(self) -> float:
        """Value of full intensity in the buffer: 255, 65535 or 1.0."""
        return {"uint8": 255.0, "uint16": 65535.0}.get(self.rgba.dtype.name, 1.0)

    def world_from_canvas(self) -> np.ndarray:
        """3x3 affine map A with ``P = A @ (x, y, 1)`` for canvas pixel (x, y) (centres at integers)."""
        w, h = self.resolution
        sx, sy = self._width / w, self._height / h
        a = np.empty((3, 3))
        a[:, 0] = self._right * sx
        a[:, 1] = self.down * sy
        # pixel (x, y) = (-0.5, -0.5) is the top-left corner: center - right*W/2 - down*H/2
        a[:, 2] = self._center + a[:, 0] * (0.5 - w / 2) + a[:, 1] * (0.5 - h / 2)
        return a

    def pixel_from_world(self, points) -> np.ndarray:
        """Canvas pixel coordinates (..., 2) of world points (..., 3) (projected onto the plane
        along the normal; points on the plane map exactly)."""
        p = check_array("points", points, dtype_kind="fiu").astype(np.float64)
        if p.shape[-1:] != (3,):
            raise ValueError(f"points: expected shape (..., 3), got {p.shape}")
        rel = p - self._center
        w, h = self.resolution
        x = (rel @ self._right / self._width + 0.5) * w - 0.5
        y = (rel @ self.down / self._height + 0.5) * h - 0.5
        return np.stack([x, y], -1)

    def world_from_pixel(self, xy) -> np.ndarray:
        """World points (..., 3) of canvas pixel coordinates (..., 2)."""
        q = check_array("xy", xy, dtype_kind="fiu").astype(np.float64)
        if q.shape[-1:] != (2,):
            raise ValueError(f"xy: expected shape (..., 2), got {q.shape}")
        w, h = self.resolution
        s = ((q[..., 0] + 0.5) / w - 0.5) * self._width
        t = ((q[..., 1] + 0.5) / h - 0.5) * self._height
        return self._center + s[..., None] * self._right + t[..., None] * self.down

    def corners(self) -> np.ndarray:
        """(4, 3) world corners at the buffer's outer pixel edges: top-left, top-right,
        bottom-right, bottom-left (canvas pixels (-0.5, -0.5), (W-0.5, -0.5), ...)."""
        w, h = self.resolution
        return self.world_from_pixel(np.array([[-0.5, -0.5], [w - 0.5, -0.5], [w - 0.5, h - 0.5], [-0.5, h - 0.5]]))

    def contains(self, xy) -> np.ndarray:
        """Bool (...) : canvas pixel coordinates inside the buffer's area [-0.5, W-0.5] x [-0.5, H-0.5]."""
        q = np.asarray(xy, dtype=np.float64)
        w, h = self.resolution
        return (q[..., 0] >= -0.5) & (q[..., 0] <= w - 0.5) & (q[..., 1] >= -0.5) & (q[..., 1] <= h - 0.5)

    def intersect(self, origins, dirs) -> tuple[np.ndarray, np.ndarray]:
        """Ray-plane hits: ``(t, xy)`` with t (...) the ray parameter of ``origins + t * dirs`` and
        xy (..., 2) the canvas pixel hit; ``t = inf`` where the ray is parallel to the plane,
        hits it behind its origin (t <= 0) or misses the rectangle (xy is NaN there).

        Both faces of the canvas are hit (the normal only names the side whose view is not
        mirrored). ``dirs`` need not be unit vectors; t is then in units of ``|dirs|``.
        """
        o = np.asarray(origins, dtype=np.float64)
        d = np.asarray(dirs, dtype=np.float64)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = ((self._center - o) @ self._normal) / (d @ self._normal)
        t = np.where(np.isfinite(t) & (t > 0), t, np.inf)
        p = o + np.where(np.isfinite(t), t, 0.0)[..., None] * d
        xy = self.pixel_from_world(p)
        hit = np.isfinite(t) & self.contains(xy)
        return np.where(hit, t, np.inf), np.where(hit[..., None], xy, np.nan)

    def homography(self, camera: Camera) -> np.ndarray:
        """3x3 ``H`` with ``z * (u, v, 1) = H @ (x, y, 1)``: canvas pixel (x, y) to the target
        pixel (u, v) of a pinhole ``camera``; the third row gives the planar depth z of the point.

        One homography per canvas and camera (seed 001 section 7.5: the virtual screen is one
        textured rectangle); its inverse maps target pixels to canvas pixels with ``1/z`` as
        the third coordinate.
        """
        if not isinstance(camera, Camera):
            raise TypeError(f"camera: expected a Camera, got {type(camera).__name__}")
        cw = camera.cam_from_world
        a = self.world_from_canvas()
        cam = cw[:3, :3] @ a
        cam[:, 2] += cw[:3, 3]
        return camera.K @ cam

    # ------------------------------------------------------------------ content
    def clear(self, color=(0.0, 0.0, 0.0, 0.0)) -> None:
        """Fill the buffer with one RGBA colour given in [0, 1]."""
        col = check_array("color", color, shape=(4,), dtype_kind="fiu").astype(np.float64)
        if not np.all((col >= 0) & (col <= 1)):
            raise ValueError(f"color: expected RGBA in [0, 1], got {col.tolist()}")
        self.rgba[...] = self.from_unit(col)

    def from_unit(self, values) -> np.ndarray:
        """Values in [0, 1] converted to the buffer's dtype (rounded for integer buffers)."""
        v = np.asarray(values, dtype=np.float64) * self.max_value
        if self.rgba.dtype.kind == "u":
            return np.rint(v).astype(self.rgba.dtype)
        return v.astype(self.rgba.dtype)

    def geometry_dict(self) -> dict:
        """JSON-ready geometry: center, normal, up, size, resolution."""
        return {"center": self._center.tolist(), "normal": self._normal.tolist(), "up": self._up.tolist(),
                "size": [self._width, self._height], "resolution": list(self.resolution)}

    def with_geometry(self, **changes) -> "Canvas":
        """A new canvas with the same buffer (copied) and some geometry changed."""
        g = {"center": self._center, "normal": self._normal, "up": self._up, "size": self.size}
        g.update(changes)
        return Canvas(g["center"], g["normal"], g["size"], up=g["up"], rgba=self.rgba, name=self.name)

    def __repr__(self) -> str:
        c = self._center
        w, h = self.resolution
        return (f"Canvas({self.name!r}, {w}x{h} {self.rgba.dtype}, center=[{c[0]:.4g}, {c[1]:.4g}, {c[2]:.4g}], "
                f"size={self._width:.4g}x{self._height:.4g})")
