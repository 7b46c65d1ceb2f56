"""Adaptive planar quad meshes from a depth buffer (seed 002, section 1.2).

A :class:`QuadMesh` is the output of the segmentation in :mod:`ibr.mesh.segment`: one planar quad per
rectangle of source pixels, stored as arrays (no Python object per quad).

Conventions
-----------
* Pixel (u, v) = (column, row), centers at integer coordinates; the image spans
  [-0.5, W - 0.5] x [-0.5, H - 0.5]. A rect ``[u0, v0, u1, v1]`` covers the half-open pixel ranges
  ``u0 .. u1-1`` and ``v0 .. v1-1``; its outer pixel edges (the quad's corners) are at
  ``u0 - 0.5``, ``u1 - 0.5``, ``v0 - 0.5``, ``v1 - 0.5``. Example: rect [2, 3, 6, 4] covers pixels
  (2..5, 3) and has corners u in {1.5, 5.5}, v in {2.5, 3.5}.
* Each quad carries the plane of **inverse planar depth** ``1/z(u, v) = a*u + b*v + c`` in source
  pixel coordinates (a least-squares fit over the rect's pixel centers). 1/z is affine in (u, v) over
  any scene plane (seed 002 eq. 2: z' is affine in 1/z), so extending the fit to the pixel-edge
  corners (the seed's half-pixel outward expansion) is exact for planar surfaces.
* In the source camera frame the quad's plane is ``n . X = 1`` with
  ``n = (a*fx, b*fy, a*cx + b*cy + c)``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..base.camera import Camera
from ..base.validate import check_image

__all__ = [
    "QuadMesh",
    "build_mesh",
    "fit_inv_depth_planes",
    "mesh_depth",
    "segmentation_image",
]


@dataclass(frozen=True, eq=False)
class QuadMesh:
    """Planar quads over rectangles of source pixels (contract 3 of the team brief).

    Parameters
    ----------
    camera : Camera
        The source camera (the quads live in its camera frame).
    rects : (Q, 4) int32
        ``[u0, v0, u1, v1]`` half-open pixel ranges: columns ``u0 .. u1-1``, rows ``v0 .. v1-1``.
    inv_depth_planes : (Q, 3) float64
        ``(a, b, c)`` with ``1/z(u, v) = a*u + b*v + c`` in source pixel coordinates (centers at
        integers), valid on the whole rect extended to its pixel-edge corners ``u0-0.5 .. u1-0.5``.
        A one-pixel rect has ``a = b = 0``, ``c = 1/z`` of its center.
    quad_of_pixel : (H, W) int32
        Index of the quad covering each source pixel, -1 for pixels with no quad (invalid depth).
    info : dict
        Free-form metadata (method, threshold, tolerance, timings); not used by consumers.
    """

    camera: Camera
    rects: np.ndarray
    inv_depth_planes: np.ndarray
    quad_of_pixel: np.ndarray
    info: dict = field(default_factory=dict)

    def __post_init__(self):
        if not isinstance(self.camera, Camera):
            raise TypeError(f"camera: expected a Camera, got {type(self.camera).__name__}")
        rects = np.ascontiguousarray(self.rects, dtype=np.int32).reshape(-1, 4)
        planes = np.ascontiguousarray(self.inv_depth_planes, dtype=np.float64).reshape(-1, 3)
        qop = np.ascontiguousarray(self.quad_of_pixel, dtype=np.int32)
        if planes.shape[0] != rects.shape[0]:
            raise ValueError(
                f"inv_depth_planes: expected shape ({rects.shape[0]}, 3) to match rects, got {planes.shape}"
            )
        if qop.shape != self.camera.shape:
            raise ValueError(f"quad_of_pixel: expected shape {self.camera.shape}, got {qop.shape}")
        for a in (rects, planes, qop):
            a.setflags(write=False)
        object.__setattr__(self, "rects", rects)
        object.__setattr__(self, "inv_depth_planes", planes)
        object.__setattr__(self, "quad_of_pixel", qop)

    def __len__(self) -> int:
        return len(self.rects)

    # ----------------------------------------------------------------- derived arrays
    @property
    def shape(self) -> tuple[int, int]:
        """Source image shape ``(H, W)``."""
        return self.camera.shape

    @property
    def areas(self) -> np.ndarray:
        """(Q,) number of source pixels covered by each quad."""
        return _rect_areas(self.rects)

    @property
    def one_pixel_share(self) -> float:
        """Share of quads that cover a single pixel (0 for an empty mesh)."""
        return float(np.mean(self.areas == 1)) if len(self) else 0.0

    @property
    def corners_uv(self) -> np.ndarray:
        """(Q, 4, 2) pixel-edge corners ``(u0-.5, v0-.5), (u1-.5, v0-.5), (u1-.5, v1-.5), (u0-.5, v1-.5)``."""
        r = self.rects.astype(np.float64) - 0.5
        u0, v0, u1, v1 = r[:, 0], r[:, 1], r[:, 2], r[:, 3]
        return np.stack(
            [np.stack([u0, v0], -1), np.stack([u1, v0], -1), np.stack([u1, v1], -1), np.stack([u0, v1], -1)], 1
        )

    @property
    def corners_inv_depth(self) -> np.ndarray:
        """(Q, 4) inverse depth 1/z of the plane at the four corners (see :attr:`corners_uv`)."""
        uv = self.corners_uv
        p = self.inv_depth_planes
        return p[:, None, 0] * uv[..., 0] + p[:, None, 1] * uv[..., 1] + p[:, None, 2]

    @property
    def corners_cam(self) -> np.ndarray:
        """(Q, 4, 3) camera-frame corners of each quad, order as :attr:`corners_uv`.

        A corner whose plane gives 1/z <= 0 (plane through or behind the camera; only possible for
        grazing fits at the image border) is NaN.
        """
        uv = self.corners_uv
        q = self.corners_inv_depth
        with np.errstate(divide="ignore", invalid="ignore"):
            z = np.where(q > 0, 1.0 / q, np.nan)
        return self.camera.unproject(uv, z, frame="cam")

    @property
    def plane_normals_cam(self) -> np.ndarray:
        """(Q, 3) ``n`` such that the quad's plane is ``n . X_cam = 1``: ``(a fx, b fy, a cx + b cy + c)``."""
        cam = self.camera
        a, b, c = self.inv_depth_planes.T
        return np.stack([a * cam.fx, b * cam.fy, a * cam.cx + b * cam.cy + c], -1)

    def depth(self) -> np.ndarray:
        """(H, W) float32 planar depth of the mesh at each source pixel center (NaN where no quad)."""
        return mesh_depth(self)

    def __repr__(self) -> str:
        h, w = self.shape
        return f"QuadMesh({len(self)} quads over {w}x{h}, one-pixel share {self.one_pixel_share:.1%})"


def mesh_depth(mesh: QuadMesh) -> np.ndarray:
    """Planar depth z of the mesh evaluated at every source pixel center, NaN where no quad."""
    h, w = mesh.shape
    if len(mesh.inv_depth_planes) == 0:  # no quad (e.g. an all-NaN view): nothing to evaluate
        return np.full((h, w), np.nan, np.float32)
    out = np.empty((h, w), np.float32)
    u = np.arange(w, dtype=np.float64)
    rows = max(1, (1 << 16) // max(w, 1))  # strips of rows: small temporaries (a 1080p mesh took 130 MB)
    for r0 in range(0, h, rows):
        idx = mesh.quad_of_pixel[r0:r0 + rows]
        p = mesh.inv_depth_planes[np.maximum(idx, 0)]
        v = np.arange(r0, r0 + idx.shape[0], dtype=np.float64)[:, None]
        q = p[..., 0] * u + p[..., 1] * v + p[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            out[r0:r0 + rows] = np.where((idx >= 0) & (q > 0), 1.0 / q, np.nan)
    return out


def fit_inv_depth_planes(depth, rects) -> np.ndarray:
    """Least-squares planes of inverse depth ``1/z = a u + b v + c`` over rects, (Q, 3) float64.

    Pixel centers at integer (u, v). Over a full rectangle the normal equations decouple in
    centered coordinates (a = sum(q du)/sum(du^2), b likewise, c = mean), so the fit is exact and
    cheap; least squares averages 16/24-bit quantization noise instead of trusting the corners. A
    one-pixel rect gets a = b = 0, c = 1/z of its center. Every pixel of every rect must be valid.
    """
    from ._segment_kernels import check_rects_inside, fit_planes_inv_depth

    q = _inv_depth(depth)
    r = np.ascontiguousarray(rects, dtype=np.int32).reshape(-1, 4)
    check_rects_inside(r, *q.shape)
    if len(r) and not np.isfinite(q[_rect_pixels_mask(r, q.shape)]).all():
        raise ValueError("rects: cover pixels with invalid depth")
    return fit_planes_inv_depth(q, r)


def _rect_areas(rects) -> np.ndarray:
    """(N,) pixels of each rect ``(x0, y0, x1, y1)`` (exclusive ends), int64."""
    r = np.asarray(rects, np.int64)
    return (r[:, 2] - r[:, 0]) * (r[:, 3] - r[:, 1])


def _rect_pixels_mask(rects, shape) -> np.ndarray:
    from ._segment_kernels import rect_coverage

    return rect_coverage(rects, shape[0], shape[1])


def _inv_depth(depth) -> np.ndarray:
    z = np.asarray(depth, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.ascontiguousarray(np.where(np.isfinite(z) & (z > 0), 1.0 / z, np.nan))


def build_mesh(
    view,
    *,
    threshold: float | None = None,
    max_error_px: float | None = None,
    method: str = "edge",
    baseline: float | None = None,
    near: float | None = None,
    far: float | None = None,
    min_band: int = 1,
    quantization=None,
) -> QuadMesh:
    """Adaptive planar quad mesh of a view's depth (seed 002 section 1.2, improved).

    Parameters
    ----------
    view : View
        Source view with planar depth (NaN where invalid; those pixels get no quad).
    threshold : float, optional
        Level of detail in 24-bit z' units (seed eq. 2; the seed shows 2^15 and 2^11). Exclusive
        with ``max_error_px``.
    max_error_px : float, optional
        Max reprojection error in pixels for a camera move of ``baseline`` (default 0.5 px when
        neither option is given). With the default ``method="edge"`` it is guaranteed at every
        source pixel center: each quad's plane reproduces 1/z within
        ``tol = max_error_px / (f * baseline)`` (``mesh.info["tolerance_inv_depth"]``).
    method : {"edge", "separate", "paper"}
        ``"edge"`` (default): edge-aware break edges + error-bounded plane fits. ``"paper"``: the
        seed's |Δ²z'| and scan split, faithfully. ``"separate"``: the seed's split on separate
        second differences. See :mod:`ibr.mesh.segment`.
    baseline : float, optional
        Camera displacement (scene units) for ``max_error_px``; default 5% of the median depth.
    near, far : float, optional
        Clip planes that define z'; default the view's depth range.
    min_band : int
        The seed's "large enough" band, in lines (``paper``/``separate``).
    quantization : DepthQuantization, optional
        Quantization step of the depth's encoding (:class:`ibr.base.depth.DepthQuantization`);
        default: what :func:`ibr.io.load_view` recorded for the view's file
        (:func:`ibr.base.depth.quantization_of`), else none. Edges and plane tolerances then
        ignore steps of one code (:func:`ibr.mesh.segment.segment`).

    Returns
    -------
    QuadMesh
        ``len(mesh)`` is the number of quads; ``mesh.info`` records the parameters and timings:
        ``tolerance_inv_depth`` (``"edge"``: the guaranteed max |error in 1/z| against the stored
        depth, including ``quantization_allowance_inv_depth``, half a code of a quantized
        encoding) and ``guaranteed_px`` (that bound in pixels for ``baseline``: ``max_error_px``
        plus the allowance's share; None without a baseline).

    Examples
    --------
    >>> mesh = build_mesh(view)                        # doctest: +SKIP
    >>> mesh = build_mesh(view, threshold=2**15, method="paper")  # doctest: +SKIP
    """
    from .segment import segment
    from ..base.depth import quantization_of
    from ..base.view import View

    if not isinstance(view, View):
        raise TypeError(f"view: expected an ibr.View, got {type(view).__name__}")
    depth = view.require_depth("build_mesh")
    t0 = time.perf_counter()
    seg = segment(
        depth,
        camera=view.camera,
        threshold=threshold,
        max_error_px=max_error_px,
        baseline=baseline,
        method=method,
        near=near,
        far=far,
        min_band=min_band,
        quantization=quantization if quantization is not None else quantization_of(view),
    )
    return _mesh_from_segmentation(view.camera, depth, seg, t0)


def _mesh_from_segmentation(camera, depth, seg, t0) -> QuadMesh:
    from ..base.first_run import await_kernels
    from ._segment_kernels import fit_planes_inv_depth, label_rects

    await_kernels("plane-fit")  # a first run: the helper may be caching the plane fit right now
    planes = fit_planes_inv_depth(seg.inv_depth, seg.rects)
    h, w = camera.shape
    qop = label_rects(seg.rects, h, w)
    # the bound with the quantization's allowance (half a code, ibr.mesh.segment.QUANT_FIT_CODES) in it,
    # as pixels for the baseline: 0.5 px asked of 5 cm codes guarantees 0.85 px, not 0.5
    allowance = guaranteed_px = None
    if seg.tolerance_inv_depth is not None:
        allowance = seg.tolerance_inv_depth * (1.0 - seg.threshold / seg.tolerance) if seg.tolerance else 0.0
        if seg.baseline is not None:
            guaranteed_px = seg.tolerance_inv_depth * max(camera.fx, camera.fy) * seg.baseline
    info = {
        "method": seg.method,
        "threshold_zprime": seg.threshold,
        "tolerance_zprime": seg.tolerance,
        "tolerance_inv_depth": seg.tolerance_inv_depth,
        "max_error_px": seg.max_error_px,
        "baseline": seg.baseline,
        "near": seg.near,
        "far": seg.far,
        "quantization": seg.quantization,
        "quantization_allowance_inv_depth": allowance,
        "guaranteed_px": guaranteed_px,
        "seconds_segment": seg.seconds,
        "seconds_total": time.perf_counter() - t0,
    }
    return QuadMesh(camera, seg.rects, planes, qop, info)


def segmentation_image(mesh: QuadMesh, color, *, line_color=(255, 40, 40), one_pixel_color=(255, 220, 0),
                       invalid_color=(0, 0, 0)) -> np.ndarray:
    """(H, W, 3) uint8 picture of the segmentation over the source image (seed plate I-A).

    The first column and first row of each quad's rect are drawn in ``line_color`` (so every
    boundary is a one-pixel line); one-pixel quads in
    ``one_pixel_color``; pixels with no quad in ``invalid_color``; the rest shows the source image
    (float colors are taken as [0, 1], uint16 as [0, 65535]), dimmed to 70% for contrast.
    """
    img = check_image("color", color, channels=(1, 3, 4))
    if img.shape[:2] != mesh.shape:
        raise ValueError(f"color: expected size {mesh.shape[1]}x{mesh.shape[0]}, got {img.shape[1]}x{img.shape[0]}")
    if img.ndim == 2:
        img = img[..., None]
    img = img[..., :3]
    if img.shape[2] == 1:
        img = np.repeat(img, 3, axis=2)
    if img.dtype == np.uint8:
        base = img.astype(np.float32) / 255
    elif img.dtype == np.uint16:
        base = img.astype(np.float32) / 65535
    else:
        base = np.clip(np.nan_to_num(img.astype(np.float32)), 0, 1)
    out = (base * 0.7 * 255 + 0.5).astype(np.uint8)
    lab = mesh.quad_of_pixel
    border = np.zeros(lab.shape, bool)
    # one-pixel-wide outlines: the left/top pixel row or column of every rect
    border[:, 1:] |= lab[:, 1:] != lab[:, :-1]
    border[1:, :] |= lab[1:, :] != lab[:-1, :]
    border[0, :] = border[:, 0] = True
    areas = mesh.areas
    one = np.zeros(lab.shape, bool)
    ok = lab >= 0
    one[ok] = areas[lab[ok]] == 1
    out[border & ok] = line_color
    out[one] = one_pixel_color
    out[~ok] = invalid_color
    return out
