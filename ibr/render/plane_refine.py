"""Photo-consistent planes for the quads of coarsely quantized depth (issue 11, part 3).

Depth stored in coarse codes (8-bit integer disparity, 16-bit z-buffers far from the camera)
tells a plane only to half a code: the least-squares plane on the codes of a wall that lies
inside one code is flat at the code, up to half a code (half a pixel of the pair's parallax) off
the truth, and an interpolation then draws each source's texture a fraction of a pixel apart. The
other source of an interpolation sees the same surfaces, so its colour says where the plane is.
For every large quad of one source whose codes span at most two codes (wider ones are pinned
by where their codes change), :func:`refine_planes` fits the plane ``1/z = a u + b v + c`` (the
quad's own parametrisation, :class:`ibr.mesh.QuadMesh`) whose plane-induced homography maps the
quad's interior pixels onto the other source's colour best, with one brightness offset per
channel (the views' exposures may differ): a robust (Huber) Gauss-Newton fit, the Lucas-Kanade
alignment of a plane (Baker & Matthews, "Lucas-Kanade 20 years on", 2004), first on blurred
colour, then on the colour itself, pixels that the other source sees occluded left out. The fitted plane replaces the
code plane only where it matches the other source better (robust cost over the pixels both
planes see) and explains the code of every pixel it was fitted on within :data:`TOLERANCE_CODES`;
otherwise the quad keeps its plane (weak texture along the epipolar lines, occlusions, small
quads), and it and every quad not fitted to the colour get the plane the bins of the codes
around them allow (:mod:`ibr.mesh.code_bins`). ``interpolate`` fits its two sources to each
other; when it supersamples, it upsamples a coarse source from the depth of its fitted mesh moved
into its codes' bins and its partner's pixel by pixel (:func:`ibr.mesh.code_bins.depth_in_code_bins`).

Measured (``python benchmarks/bench_edges.py --quick``, section 3: 8-bit disparity against the
exact depth, covered pixels, t = .25/.5/.75): room -0.40 -> -0.25 dB, clutter -0.71 -> -0.56;
with the bins for the other quads (sixteenth session) room -0.22, clutter -0.30, split where a
plane does not follow them (seventeenth) -0.17 / -0.17; docs/edges.md
section 3 has the other scenes and what was tried.

Conventions: pixel centres at integer (u, v); planes in inverse planar depth per source pixel;
colours compared in units of their dtype's full scale.
"""

from __future__ import annotations

import cv2
import numpy as np

from ..base.depth import DepthQuantization, quantization_of
from ..base.validate import check_finite_scalar, check_positive
from ..base.view import View
from ..mesh.code_bins import fit_mesh_in_code_bins
from ..mesh.quad_mesh import QuadMesh, _inv_depth
from .points import sample_points
from .rasterize import src_from_tgt
from .upsample import _unit_color

__all__ = ["COARSE_PX", "MIN_AREA", "TOLERANCE_CODES", "is_coarse", "refine_planes"]

#: Quads of at least this many pixels are fitted: smaller ones hold too few pixels for a plane
#: (full planes from 50 or 100 px: clutter -0.53 dB against -0.56; an offset alone for quads of
#: 20-200 px: -0.50, but other scenes lost: docs/edges.md section 3).
MIN_AREA = 200
#: A source's depth is refined when one code moves a point at its median depth by at least this
#: many pixels between the two cameras (8-bit disparity at the pair's baseline: 1 px; 16-bit
#: millimetres at 3 m and 0.24 m: 0.01 px, left as it is).
COARSE_PX = 0.25
#: How far (codes, beyond the half code of rounding) a fitted plane may leave a pixel's code:
#: a quad's plane also approximates a curved surface (room -0.30 dB at 0.5, -0.25 at 1.0).
TOLERANCE_CODES = 1.0
#: Only quads whose stored codes lie within this many codes of each other (at most three
#: distinct codes) are fitted: wider ones are pinned by where their codes change.
SPAN_CODES = 2
#: Huber threshold of the colour residual, of full scale.
HUBER = 8 / 255
#: Levenberg-Marquardt damping, relative to the normal matrix's diagonal.
DAMPING = 1e-3
#: Gauss-Newton iterations on colour blurred with this sigma (px), then on the colour itself.
BLUR_SIGMA = 1.0
ITERATIONS = (4, 4)
#: A quad with fewer pixels that the other source sees keeps its plane.
MIN_VISIBLE = 30
#: A larger quad is fitted on a random share of its interior pixels, about this many (room:
#: 0.38 -> 0.31 s per source, the same figures; 5000 were noisier where a third of a wall was
#: occluded, and every k-th row and column biased the slope: a regular grid's sub-pixel phases
#: do not average out).
MAX_PIXELS = 20000


def is_coarse(quantization: DepthQuantization | None, depth: float, baseline: float, focal_px: float) -> bool:
    """Whether one code of ``quantization`` at planar depth ``depth`` (e.g. a source's median)
    moves a point by at least :data:`COARSE_PX` pixels over a camera move of ``baseline``
    (scene units) at focal length ``focal_px``; ``False`` without a quantization."""
    depth, focal_px = check_positive("depth", depth), check_positive("focal_px", focal_px)
    baseline = check_finite_scalar("baseline", baseline)
    if baseline < 0:
        raise ValueError(f"baseline: expected a distance >= 0, got {baseline!r}")
    if quantization is None:
        return False
    if not isinstance(quantization, DepthQuantization):
        raise TypeError(f"quantization: expected an ibr.base.depth.DepthQuantization or None, got "
                        f"{type(quantization).__name__}")
    return float(quantization.inv_step(1.0 / depth)) * focal_px * baseline >= COARSE_PX


def refine_planes(mesh: QuadMesh, view: View, other: View) -> QuadMesh:
    """``mesh`` (of ``view``) with the planes of its large quads fitted to ``other``'s colour.

    Parameters
    ----------
    mesh : QuadMesh
        A mesh of ``view`` built with a quantization (``mesh.info["quantization"]``); without
        one it is returned as it is.
    view, other : View
        The mesh's source and another view of the same scene (any camera and size, same
        colour channels), both with depth (``other``'s tells which pixels it sees occluded).

    Returns
    -------
    QuadMesh
        Planes of quads of :data:`MIN_AREA` pixels or more within :data:`SPAN_CODES` codes
        replaced where the fit matched ``other`` better and explains the codes (module
        docstring), ``info["refined_quads"]`` of them; every other quad placed inside the bins
        of the codes around it where that works, and split where one plane does not follow the
        surface they allow (:func:`ibr.mesh.code_bins.fit_mesh_in_code_bins`),
        ``info["bin_fitted_quads"]`` and ``info["bin_split_quads"]`` of them (all 0 without a
        quantization, and the mesh then as it was; with one, ``quad_of_pixel`` is made anew from
        the rects).
    """
    _check_inputs(mesh, view, other)
    quant = mesh.info.get("quantization")
    if quant is None:
        return QuadMesh(mesh.camera, mesh.rects, mesh.inv_depth_planes, mesh.quad_of_pixel,
                        {**mesh.info, "refined_quads": 0, "bin_fitted_quads": 0, "bin_split_quads": 0})
    px = _interior_pixels(mesh, _quads_to_fit(mesh, view.depth, quant))
    planes, keep = _fit_to_colour(mesh, view, other, px)
    coloured = QuadMesh(mesh.camera, mesh.rects, planes, mesh.quad_of_pixel,
                        {**mesh.info, "refined_quads": int(keep.sum())})
    return fit_mesh_in_code_bins(coloured, view.depth, ~keep)


def _fit_to_colour(mesh: QuadMesh, view: View, other: View, px: "_Pixels") -> tuple[np.ndarray, np.ndarray]:
    """The mesh's planes with those of ``px``'s quads fitted to ``other``'s colour where kept
    (module docstring), (Q, 3), and which were kept, (Q,) bool."""
    start = mesh.inv_depth_planes
    if len(px.qi) == 0:
        return start, np.zeros(len(start), bool)
    quant = mesh.info["quantization"]
    other_quant = quantization_of(other)
    warp = _PlaneWarp(view.camera, other.camera, other.depth, quant if other_quant is None else other_quant)
    own, target = _unit_color(view.color).astype(np.float32), _unit_color(other.color).astype(np.float32)
    fitted, offsets = start.copy(), np.zeros((len(start), own.shape[2]))
    for sigma, steps in zip((BLUR_SIGMA, 0.0), ITERATIONS):  # coarse to fine
        own_s, target_s = ((cv2.GaussianBlur(c, (0, 0), sigma).reshape(c.shape) for c in (own, target)) if sigma
                           else (own, target))
        own_px, target_grad = _at(own_s, px.u, px.v), _with_gradients(target_s)
        for _ in range(steps):
            fitted, offsets = _gauss_newton_step(fitted, offsets, px, warp, own_px, target_grad)
    keep = _matches_better(start, fitted, px, warp, _at(own, px.u, px.v), target)
    keep &= _explains_codes(fitted, px, view, quant)
    return np.where(keep[:, None], fitted, start), keep


def _check_inputs(mesh, view, other) -> None:
    if not isinstance(mesh, QuadMesh):
        raise TypeError(f"mesh: expected an ibr QuadMesh, got {type(mesh).__name__}")
    for name, v in (("view", view), ("other", other)):
        if not isinstance(v, View):
            raise TypeError(f"{name}: expected an ibr View, got {type(v).__name__}")
        v.require_depth("refine_planes")
    if mesh.shape != view.shape or not mesh.camera.allclose(view.camera):
        raise ValueError(f"mesh: built for another camera than view's ({mesh.camera!r} against "
                         f"{view.camera!r}); pass the view the mesh was built from")
    if _channels(view) != _channels(other):
        raise ValueError(f"other: {_channels(other)} colour channels, view has {_channels(view)}; "
                         "the planes are fitted by comparing their colours")


def _channels(view: View) -> int:
    return 1 if view.color.ndim == 2 else min(view.color.shape[2], 3)


class _Pixels:
    """The interior pixels of the quads to refine: (u, v) float64, quad index ``qi``, and the
    homogeneous pixel vectors ``x = (u, v, 1)`` (N, 3)."""

    def __init__(self, u, v, qi, n_quads):
        self.u, self.v, self.qi, self.n_quads = u, v, qi, n_quads
        self.x = np.stack([u, v, np.ones_like(u)], 1)

    def plane_values(self, planes) -> np.ndarray:
        """(N,) inverse depth ``p . x`` of each pixel's quad plane (``planes`` (Q, 3))."""
        return np.einsum("ij,ij->i", planes[self.qi], self.x)

    def per_quad(self, values) -> np.ndarray:
        """Sum of per-pixel ``values`` over each quad, (Q,)."""
        return np.bincount(self.qi, values, minlength=self.n_quads)


def _quads_to_fit(mesh: QuadMesh, depth, quant: DepthQuantization) -> np.ndarray:
    """(Q + 1,) bool (the last entry, for pixels without a quad, False): quads of :data:`MIN_AREA`
    pixels or more whose stored codes lie within :data:`SPAN_CODES` codes. A plane across more
    codes is pinned by where they change (a tilted plane's least-squares fit on 12 codes is within
    0.01 code); on the real motorcycle pair (its disparity rounded to integers) fitting the quads
    spanning five codes or more to the colour moved them off the ground truth (0.065 -> 0.32 px
    rms)."""
    qop = mesh.quad_of_pixel
    q = _inv_depth(depth)  # NaN where no depth
    valid = (qop >= 0) & np.isfinite(q)
    code = q[valid] / quant.inv_step(q[valid])  # the code index (disparity, or z / step)
    hi, lo = np.full(len(mesh), -np.inf), np.full(len(mesh), np.inf)
    np.maximum.at(hi, qop[valid], code)
    np.minimum.at(lo, qop[valid], code)
    large = mesh.areas >= MIN_AREA
    return np.append(large & (hi - lo <= SPAN_CODES + 1e-6), False)


def _interior_pixels(mesh: QuadMesh, quads) -> _Pixels:
    """Pixels of the ``quads`` ((Q + 1,) bool, see :func:`_quads_to_fit`) whose 3 x 3
    neighbourhood lies in their own quad (the quad's border pixels may mix in the neighbouring
    surface's colour)."""
    r = mesh.rects
    ids = mesh.quad_of_pixel.astype(np.float32)  # exact for any quad count a mesh can have (< 2^24)
    box = np.ones((3, 3), np.uint8)
    inside = cv2.erode(ids, box) == cv2.dilate(ids, box)
    v, u = np.nonzero(inside & quads[mesh.quad_of_pixel])
    qi = mesh.quad_of_pixel[v, u]
    # at most about MAX_PIXELS per quad: a random share of a larger one's (fixed seed)
    share = np.minimum(1.0, MAX_PIXELS / np.maximum(np.bincount(qi, minlength=len(r)), 1))[qi]
    keep = np.random.default_rng(0).random(len(qi)) < share
    return _Pixels(u[keep].astype(np.float64), v[keep].astype(np.float64), qi[keep], len(r))


class _PlaneWarp:
    """Where the pixels of a plane of the source land in the other camera.

    A source pixel ``x = (u, v, 1)`` on the plane ``1/z = p . x`` is the point ``K_s^-1 x / (p . x)``;
    in the other camera ``w = A x + s (p . x)`` (homogeneous, scaled by ``p . x``) with
    ``A = K_o R K_s^-1`` and ``s = K_o t`` for the relative pose ``(R, t)``: the plane-induced
    homography ``A + s p^T``. The other camera's depth of the point is ``w_2 / (p . x)``.
    """

    def __init__(self, source, other, other_depth, quant):
        rotation, translation = src_from_tgt(other, source)  # other's camera frame from the source's
        self.A = other.K @ rotation @ np.linalg.inv(source.K)
        self.s = other.K @ translation
        self.q_other = np.nan_to_num(_inv_depth(other_depth), nan=0.0)  # 0 where the other has no depth
        self.quant = quant
        self.h, self.w = self.q_other.shape

    def project(self, planes, px: _Pixels):
        """(u', v') in the other camera, the homogeneous ``w`` (N, 3), and whether the other
        camera sees the point: inside its image (1 px margin for the gradient) and not behind
        its depth there by more than 2 % plus one code (its depth is quantized too)."""
        q = px.plane_values(planes)
        w = px.x @ self.A.T + self.s[None] * q[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            uo, vo = w[:, 0] / w[:, 2], w[:, 1] / w[:, 2]
            ok = (w[:, 2] > 0) & (q > 0) & (uo > 1) & (uo < self.w - 2) & (vo > 1) & (vo < self.h - 2)
        uo, vo = np.where(ok, uo, -10.0), np.where(ok, vo, -10.0)
        q_seen = self.q_other[np.clip(np.rint(vo), 0, self.h - 1).astype(np.intp),
                              np.clip(np.rint(uo), 0, self.w - 1).astype(np.intp)]
        with np.errstate(divide="ignore", invalid="ignore"):
            q_point = q / w[:, 2]  # 1/z of the point in the other camera
        ok &= q_point >= q_seen * 0.98 - self.quant.inv_step(q_seen)
        return uo, vo, w, ok


def _at(image, u, v) -> np.ndarray:
    """Bilinear samples (N, C) float32 of ``image`` at (u, v), NaN outside."""
    return sample_points(image, u, v, outside=np.nan)


def _with_gradients(image) -> np.ndarray:
    """(H, W, 3C) float32: the image's C channels, then their d/du, then their d/dv (Sobel)."""
    gx = cv2.Sobel(image, cv2.CV_32F, 1, 0, ksize=3) / 8
    gy = cv2.Sobel(image, cv2.CV_32F, 0, 1, ksize=3) / 8
    return np.concatenate([image, gx.reshape(image.shape), gy.reshape(image.shape)], 2)


def _gauss_newton_step(planes, offsets, px: _Pixels, warp: _PlaneWarp, own_px, other_grad):
    """One damped, Huber-weighted Gauss-Newton step of every quad's plane and brightness offsets:
    residual ``r_c = I_other,c(H_p x) - I_own,c(x) - offset_c`` per channel c; its derivative by
    the plane is ``g_c x`` with ``g_c = grad I_other,c . d(u', v')/dw . s`` (the homography moves
    points along ``s``), by ``offset_c`` it is -1. ``other_grad`` is :func:`_with_gradients` of
    the other view's colour. Returns the new ``(planes, offsets)``."""
    uo, vo, w, ok = warp.project(planes, px)
    samples = _at(other_grad, uo, vo)
    nc = own_px.shape[1]  # colour channels
    r = samples[:, :nc] - own_px - offsets[px.qi]
    ok &= np.isfinite(r).all(1)
    du = (warp.s[0] - warp.s[2] * uo) / w[:, 2]  # d u' along s: (s0 w2 - s2 w0) / w2^2
    dv = (warp.s[1] - warp.s[2] * vo) / w[:, 2]
    g = np.nan_to_num(samples[:, nc:2 * nc] * du[:, None] + samples[:, 2 * nc:] * dv[:, None])
    r = np.where(ok[:, None], r, 0.0)
    weight = np.where(np.abs(r) <= HUBER, 1.0, HUBER / np.maximum(np.abs(r), 1e-12)) * ok[:, None]
    n = 3 + nc  # unknowns per quad: the plane (a, b, c) and one offset per channel
    normal = np.zeros((px.n_quads, n, n))
    rhs = np.zeros((px.n_quads, n))
    gg, gr = (weight * g * g).sum(1), (weight * g * r).sum(1)
    for i in range(3):
        rhs[:, i] = px.per_quad(gr * px.x[:, i])
        for j in range(i, 3):
            normal[:, i, j] = normal[:, j, i] = px.per_quad(gg * px.x[:, i] * px.x[:, j])
    for ch in range(nc):
        rhs[:, 3 + ch] = -px.per_quad(weight[:, ch] * r[:, ch])
        normal[:, 3 + ch, 3 + ch] = px.per_quad(weight[:, ch])
        for i in range(3):
            normal[:, i, 3 + ch] = normal[:, 3 + ch, i] = -px.per_quad(weight[:, ch] * g[:, ch] * px.x[:, i])
    diag = np.diagonal(normal, axis1=1, axis2=2)
    normal += (DAMPING * diag)[:, :, None] * np.eye(n) + 1e-12 * np.eye(n)
    step = -np.linalg.solve(normal, rhs[..., None])[..., 0]
    step[(px.per_quad(ok) < MIN_VISIBLE) | ~np.isfinite(step).all(1)] = 0.0
    return planes + step[:, :3], offsets + step[:, 3:]


def _residuals(planes, px: _Pixels, warp: _PlaneWarp, own_px, other):
    """(N, C) colour residuals ``I_other(H_p x) - I_own(x)`` and the pixels the other sees."""
    uo, vo, _, ok = warp.project(planes, px)
    r = _at(other, uo, vo) - own_px
    ok &= np.isfinite(r).all(1)
    return np.where(ok[:, None], r, 0.0), ok


def _matches_better(start, fitted, px: _Pixels, warp: _PlaneWarp, own_px, other) -> np.ndarray:
    """(Q,) bool: quads whose fitted plane has the lower Huber cost over the pixels both planes
    let the other camera see, where those are at least half of the quad's fitted pixels; each
    plane's residuals less their mean there per channel (its brightness offset, the same
    estimate for both)."""
    r0, ok0 = _residuals(start, px, warp, own_px, other)
    r1, ok1 = _residuals(fitted, px, warp, own_px, other)
    both = ok0 & ok1
    seen = px.per_quad(both)

    def cost(r):
        offset = np.stack([px.per_quad(r[:, ch] * both) for ch in range(r.shape[1])], 1) / np.maximum(seen, 1)[:, None]
        return px.per_quad(_huber(r - offset[px.qi]) * both)

    return (cost(r1) < cost(r0)) & (seen >= 0.5 * px.per_quad(np.ones(len(px.qi))))


def _huber(r) -> np.ndarray:
    """Huber cost of residuals (N, C), summed over channels."""
    a = np.abs(r)
    return np.where(a <= HUBER, 0.5 * a * a, HUBER * (a - 0.5 * HUBER)).sum(1)


def _explains_codes(planes, px: _Pixels, view: View, quant: DepthQuantization) -> np.ndarray:
    """(Q,) bool: quads whose plane stays within half a code plus :data:`TOLERANCE_CODES` of
    the stored inverse depth of every pixel it was fitted on."""
    stored = 1.0 / np.asarray(view.depth, np.float64)[px.v.astype(np.intp), px.u.astype(np.intp)]
    q = px.plane_values(planes)
    outside = np.abs(q - stored) > quant.inv_step(stored) * (0.5 + TOLERANCE_CODES)
    return px.per_quad(outside) == 0
