"""Planes of quantized depth placed inside the codes' bins (issue 11, part 3).

A depth code says only that the surface lies somewhere in its bin, half a code either side of
the stored value, and the least-squares plane on the codes of a small quad is up to half a code
off (a quad inside one code is flat at that code whatever the surface's slope). Where the codes
change, though, the surface crosses a bin boundary: the codes of the pixels around a quad pin
its surface there. :func:`fit_planes_in_code_bins` fits, for each chosen quad, a quadratic
surface in inverse depth to the quad's pixels and those reached from them in at most
:data:`GROW` 4-connected steps, none between neighbours more than :data:`SURFACE_STEP_CODES`
codes apart (the same surface), by alternating projections: fit, move each pixel's target to
the nearest point of its bin, fit again (a surface through all the bins where one exists; the
bins' boundaries are where the codes change). Pixels outside the quad more than
:data:`REJECT_CODES` beyond their bin after :data:`REJECT_AFTER` rounds are left out (a crease,
another surface at the same depth). The quad gets the least-squares plane of that surface over
its rect (the surface extrapolated over pixels without depth), kept only if the surface lies
within :data:`ACCEPT_CODES` of every own pixel's bin (where the codes are not those of a smooth
surface, the quad keeps its plane). The codes' allowance lets the segmentation take a curve as one
quad that the exact depth would have split (clutter: 1 250 quads against 1 455), so
:func:`fit_mesh_in_code_bins` then halves a quad whose plane departs from its surface by more
than a share of the exact depth's tolerance, and fits the halves again, until each part follows.

:func:`depth_in_code_bins` does the same per pixel for what reads depth pixel by pixel (the
upsampling of ``supersample=3``): a start (the fitted mesh's planes) smoothed within surfaces and
moved into each pixel's bin, round after round.

Measured (``python -c "import bench_edges as be; be.section_quantized()"`` in ``benchmarks/``,
8-bit disparity against the exact depth, after :mod:`ibr.render.plane_refine`'s colour fit of
the large quads, for every quad it did not take): clutter -0.56 -> -0.30 dB (planes refitted on
the exact depth for every quad under 200 px: -0.27), room -0.25 -> -0.22; split where a plane
does not follow the bins: clutter -0.17, room -0.17 (the exact depth's planes on the codes' quads
split to the exact tolerance: +0.02 / -0.03); docs/edges.md section 3.

Conventions: pixel centres at integer (u, v); rects ``(x0, y0, x1, y1)`` with exclusive ends;
planes of inverse planar depth ``1/z = a u + b v + c`` as in :class:`ibr.mesh.QuadMesh`.
"""

from __future__ import annotations

import numpy as np

from ..base.camera import Camera
from ..base.depth import DepthQuantization, quantization_of
from ..base.validate import check_array, check_finite_scalar
from ..base.view import View
from .quad_mesh import QuadMesh, _inv_depth, _rect_areas

__all__ = ["ACCEPT_CODES", "DEQUANTIZE_ITERATIONS", "GROW", "ITERATIONS", "MAX_WINDOW_PIXELS", "REJECT_AFTER",
           "REJECT_CODES", "RIDGE", "SPLIT_SHARE", "SURFACE_STEP_CODES", "depth_in_code_bins", "fit_mesh_in_code_bins",
           "fit_planes_in_code_bins", "partner_code_bins"]

#: Pixels up to this many 4-connected steps from a quad inform its surface (10 px: clutter
#: -0.297 dB, room -0.223; with the plane rather than the surface tested, 8 / 10 / 12 px gave
#: clutter -0.39 / -0.33 / -0.30 and room -0.21 / -0.23 / -0.27: a trade between the scenes).
GROW = 10
#: A step between neighbours of more than this many codes ends the surface.
SURFACE_STEP_CODES = 1.5
#: Rounds of fit-and-project; after :data:`REJECT_AFTER` of them, pixels outside the quad more
#: than :data:`REJECT_CODES` beyond their bin are left out.
ITERATIONS = 20
REJECT_AFTER = 4
REJECT_CODES = 0.25
#: The surface must lie within this many codes of every own pixel's bin (the real motorcycle's
#: small quads, whose surfaces are not smooth, drifted off the truth without a test: 0.206 ->
#: 0.215 px rms; testing the plane instead of the surface rejected the limbs' quads, whose planes
#: cannot follow the curve: clutter -0.30 -> -0.33 dB).
ACCEPT_CODES = 0.25
#: Ridge on the normal equations, relative to their diagonal.
RIDGE = 1e-9
#: A quad with more pixels than this within reach is fitted on a random share of about this many
#: (the largest quads, whose many codes pin them anyway: 1.37 -> 0.48 s for a 1080p view's 1 197
#: quads).
MAX_WINDOW_PIXELS = 4096
#: A fitted quad is halved (and its halves fitted again) while its plane departs from its surface
#: by more than this share of the tolerance the mesh would have without the codes' allowance
#: (8-bit disparity, clutter / room: no split -0.297 / -0.223 dB; 1.0 -0.29 / -0.18; 0.5 -0.20 /
#: -0.17; 0.3 -0.17 / -0.17; 0.2 -0.26 / -0.16: the quadratic over the grown window is flatter
#: than the curve it follows, so its gap understates the plane's error about twofold).
SPLIT_SHARE = 0.3
#: Rounds of :func:`depth_in_code_bins` (8-bit disparity under ``supersample=3``, clutter / room
#: covered pixels: 10 rounds 40.04 / 41.94 dB, 20 40.05 / 41.92, 40 40.01 / 41.88).
DEQUANTIZE_ITERATIONS = 20
#: Neighbours whose starting inverse depths differ by more than this many codes are on different
#: surfaces for :func:`depth_in_code_bins` (1.5: room 41.93 dB, one more pixel off the band).
DEQUANTIZE_SURFACE_CODES = 1.0


def fit_planes_in_code_bins(mesh: QuadMesh, depth, quads=None) -> tuple[np.ndarray, np.ndarray]:
    """Planes for the ``quads`` of ``mesh`` that lie inside the bins of the codes around them.

    Parameters
    ----------
    mesh : QuadMesh
        Built with a quantization (``mesh.info["quantization"]``, an
        :class:`ibr.base.depth.DepthQuantization`).
    depth : (H, W) float or integer array
        The stored (quantized) planar depth the mesh was built from (scene units); NaN, 0 or inf
        where none.
    quads : (Q,) bool array, optional
        Which quads to fit (default: all).

    Returns
    -------
    planes : (Q, 3) float64
        ``mesh.inv_depth_planes`` with the accepted quads' planes replaced.
    fitted : (Q,) bool
        The quads whose plane was replaced.
    """
    planes, fitted, _ = _fit_quads(mesh, _Codes(mesh, depth), quads)
    return planes, fitted


def depth_in_code_bins(start, codes, quantization: DepthQuantization, *, also_within=None,
                       iterations: int = DEQUANTIZE_ITERATIONS) -> np.ndarray:
    """Per-pixel depth inside each pixel's code bin, smooth within surfaces, from a start.

    Alternating projections (the per-pixel sibling of :func:`fit_planes_in_code_bins`): each
    round replaces a pixel's inverse depth by the mean of its opposite 4-neighbour pairs (left
    and right, up and down) that lie on its surface, which leaves every plane of inverse depth as
    it is and flattens only what curves or steps, then moves it to the nearest point of its bin
    (half a code either side of its stored value). A mesh's planes (the start) are up to a code
    off where a plane must follow a curve or where its fit missed; the codes pin the surface
    where they change, and the smoothing carries that between the changes.

    Measured (8-bit disparity of the bundled pairs, ``interpolate(..., supersample=3)``, covered
    pixels, against the exact depth's; the start the sources' fitted meshes,
    :mod:`ibr.render.plane_refine`): clutter -1.12 -> -0.85 dB, room -0.52 -> -0.21 (with the
    partner source's codes as ``also_within``, :func:`partner_code_bins`: -0.72 / -0.14);
    clamping the planes into the bins alone -0.99 / -0.38; the plain 4-neighbour mean (planes bent at their
    borders) pushed the depth-edge pixels' errors up. The real motorcycle's disparity rounded to
    integers, planes fitted to the right view's colour as the start: 0.197 -> 0.166 px rms
    against the float ground truth.

    Parameters
    ----------
    start : (H, W) float array
        Planar depth to start from (scene units), e.g. :func:`ibr.mesh.mesh_depth` of a mesh of
        ``codes``; NaN, 0 or inf where none. It also tells the surfaces apart: neighbours whose
        starting inverse depths differ by more than :data:`DEQUANTIZE_SURFACE_CODES` codes are on
        different ones.
    codes : (H, W) float or integer array
        The stored (quantized) planar depth, as decoded (scene units); NaN, 0 or inf where none.
    quantization : DepthQuantization
        The encoding's step (:class:`ibr.base.depth.DepthQuantization`).
    also_within : (lo, hi), optional
        Further bounds on each pixel's inverse depth (1 / scene units, (H, W) each, NaN where
        none), e.g. another view's codes (:func:`partner_code_bins`), intersected with the
        pixel's bin wherever the two overlap (elsewhere the bin alone: the other view sees
        another surface there).
    iterations : int
        Rounds of smoothing and projection, >= 0 (0: the start moved into the bins).

    Returns
    -------
    (H, W) float32
        Planar depth within half a code of ``codes`` wherever both inputs have depth; ``start``
        elsewhere.
    """
    start = check_array("start", start, ndim=2, dtype_kind="f")
    codes = check_array("codes", codes, shape=start.shape, dtype_kind="fiu")
    if not isinstance(quantization, DepthQuantization):
        raise TypeError(f"quantization: expected an ibr.base.depth.DepthQuantization, got "
                        f"{type(quantization).__name__}")
    if isinstance(iterations, (bool, np.bool_)) or not isinstance(iterations, (int, np.integer)) or iterations < 0:
        raise ValueError(f"iterations: expected an integer >= 0, got {iterations!r}")
    guide, qc = _inv_depth(start), _inv_depth(codes)
    valid = np.isfinite(guide) & np.isfinite(qc)
    step = quantization.inv_step(np.where(valid, qc, 0.0))
    lo, hi = np.where(valid, qc - 0.5 * step, 0.0), np.where(valid, qc + 0.5 * step, 0.0)
    if also_within is not None:
        lo, hi = _intersected(lo, hi, also_within, start.shape)
    pairs = _surface_pairs(np.where(valid, guide, np.nan), DEQUANTIZE_SURFACE_CODES * step)
    q = np.clip(np.where(valid, guide, 0.0), lo, hi)
    count = sum(p.astype(np.float64) for p in pairs)
    smoothed = count > 0
    for _ in range(iterations):
        padded = np.pad(q, 1, mode="edge")
        total = np.where(pairs[0], padded[1:-1, :-2] + padded[1:-1, 2:], 0.0)
        total += np.where(pairs[1], padded[:-2, 1:-1] + padded[2:, 1:-1], 0.0)
        q = np.clip(np.where(smoothed, 0.5 * total / np.maximum(count, 1.0), q), lo, hi)
    with np.errstate(divide="ignore"):
        return np.where(valid, 1.0 / np.where(valid, q, 1.0), start).astype(np.float32)


def _intersected(lo, hi, bounds, shape) -> tuple[np.ndarray, np.ndarray]:
    """The bins ``(lo, hi)`` narrowed to ``bounds`` where the two overlap."""
    if not isinstance(bounds, (tuple, list)) or len(bounds) != 2:
        raise TypeError(f"also_within: expected a pair (lo, hi) of arrays, got {type(bounds).__name__}")
    b_lo, b_hi = (check_array(f"also_within[{i}]", b, shape=shape, dtype_kind="f") for i, b in enumerate(bounds))
    new_lo, new_hi = np.fmax(lo, b_lo), np.fmin(hi, b_hi)  # fmax / fmin: NaN bounds leave the bin
    overlap = new_lo <= new_hi
    return np.where(overlap, new_lo, lo), np.where(overlap, new_hi, hi)


def partner_code_bins(camera: Camera, start, partner: View,
                      quantization: DepthQuantization | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Bounds on the inverse depth of ``camera``'s pixels from the codes of another view.

    Each pixel's point (on its ray at the ``start`` depth) lands on a pixel of ``partner``, whose
    code holds the surface's depth there to half a code in the partner's frame. Where that depth
    is another function of the surface than the pixel's own (cameras that verge or move in
    depth; a rectified pair codes the same disparity twice and adds nothing), its codes change
    at other places on the surface and narrow the pixel's bin. The partner's bin,
    carried back along the pixel's ray (the inverse depth in the partner's frame, ``q / w_2``,
    is monotonic along the ray), is widened by half a pixel's change of ``start`` on its surface
    (the partner's pixel centre lies up to half a pixel from the point).

    Parameters
    ----------
    camera : Camera
        The camera of ``start``.
    start : (H, W) float array
        Planar depth of ``camera``'s pixels (scene units) that places the points; NaN, 0 or
        inf where none.
    partner : View
        The other view, with its stored (quantized) depth.
    quantization : DepthQuantization, optional
        The step of ``partner``'s codes; default the one it records
        (:func:`ibr.base.depth.quantization_of`), required one way or the other.

    Returns
    -------
    lo, hi : (H, W) float64
        Inverse depth (1 / scene units) in ``camera``'s frame; NaN where the point falls outside
        the partner, behind it, or on a pixel without depth. For
        :func:`depth_in_code_bins`'s ``also_within``.
    """
    if not isinstance(camera, Camera):
        raise TypeError(f"camera: expected an ibr Camera, got {type(camera).__name__}")
    if not isinstance(partner, View):
        raise TypeError(f"partner: expected an ibr View, got {type(partner).__name__}")
    partner.require_depth("partner_code_bins")
    quant = quantization_of(partner) if quantization is None else quantization
    if quant is None:
        raise ValueError("quantization: expected an ibr.base.depth.DepthQuantization (the step of partner's codes), "
                         "got None, and partner records none")
    if not isinstance(quant, DepthQuantization):
        raise TypeError(f"quantization: expected an ibr.base.depth.DepthQuantization (the step of partner's codes), "
                        f"got {type(quant).__name__}")
    q = _inv_depth(check_array("start", start, shape=(camera.height, camera.width), dtype_kind="f"))
    m = partner.camera.cam_from_world @ camera.world_from_cam  # the partner's frame from the camera's
    a = partner.camera.K @ m[:3, :3] @ np.linalg.inv(camera.K)
    s = partner.camera.K @ m[:3, 3]
    u, v = camera.pixel_grid()
    ax = [a[i, 0] * u + a[i, 1] * v + a[i, 2] for i in range(3)]  # w = A x + s q (homogeneous, times q)
    with np.errstate(invalid="ignore", divide="ignore"):
        w2 = ax[2] + s[2] * q
        pu, pv = np.rint((ax[0] + s[0] * q) / w2), np.rint((ax[1] + s[1] * q) / w2)
        seen = (w2 > 0) & (pu >= 0) & (pu < partner.camera.width) & (pv >= 0) & (pv < partner.camera.height)
    iu, iv = (np.where(seen, c, 0).astype(np.intp) for c in (pu, pv))
    qp = np.where(seen, _inv_depth(partner.depth)[iv, iu], np.nan)
    half = 0.5 * quant.inv_step(np.nan_to_num(qp))
    widen = 0.5 * _surface_change(q)
    with np.errstate(invalid="ignore", divide="ignore"):
        # q_partner = q / (ax2 + s2 q)  <=>  q = q_partner ax2 / (1 - q_partner s2)
        ends = [(qp + sign * half) * ax[2] / (1 - (qp + sign * half) * s[2]) for sign in (-1, 1)]
        lo, hi = np.fmin(*ends) - widen, np.fmax(*ends) + widen
        ok = np.isfinite(lo) & np.isfinite(hi) & (lo > 0)
    return np.where(ok, lo, np.nan), np.where(ok, hi, np.nan)


def _surface_change(q) -> np.ndarray:
    """(H, W): the change of ``q`` over one pixel along u plus along v, each the smaller of the
    two one-sided differences (the one on the pixel's own surface beside a depth edge); 0 where
    a pixel has no neighbour along an axis."""
    total = np.zeros(q.shape)
    padded = np.pad(q, 1, constant_values=np.nan)
    with np.errstate(invalid="ignore"):
        for before, after in ((padded[1:-1, :-2], padded[1:-1, 2:]), (padded[:-2, 1:-1], padded[2:, 1:-1])):
            total += np.nan_to_num(np.fmin(np.abs(q - before), np.abs(after - q)))
    return total


def _surface_pairs(guide, tolerance) -> tuple[np.ndarray, np.ndarray]:
    """(left-right, up-down), each (H, W) bool: pixels both of whose neighbours along the axis
    lie within ``tolerance`` ((H, W)) of their own ``guide`` value (NaN: no pixel)."""
    padded = np.pad(guide, 1, constant_values=np.nan)
    with np.errstate(invalid="ignore"):
        def near(n):
            return np.abs(n - guide) <= tolerance
        return (near(padded[1:-1, :-2]) & near(padded[1:-1, 2:]),
                near(padded[:-2, 1:-1]) & near(padded[2:, 1:-1]))


def fit_mesh_in_code_bins(mesh: QuadMesh, depth, quads=None, *, tolerance=None) -> QuadMesh:
    """``mesh`` with the ``quads`` placed inside the codes' bins, and split where one plane does
    not follow the surface the bins allow.

    Each chosen quad is fitted as by :func:`fit_planes_in_code_bins`; an accepted quad whose plane
    departs from its surface by more than ``tolerance`` at one of its pixels is halved across its
    longer side and each half fitted again the same way (its own surface, from the pixels around
    it), until every part follows its surface or is one pixel. A half whose fit is not accepted
    keeps the plane of the quad it came from; a quad neither of whose halves is accepted stays
    whole.

    Parameters
    ----------
    mesh, depth, quads
        As for :func:`fit_planes_in_code_bins`.
    tolerance : float, optional
        Largest distance in inverse depth (1 / scene units) between a part's plane and its
        surface, >= 0 (``np.inf``: no split); default :data:`SPLIT_SHARE` times the mesh's
        tolerance without the codes' allowance (``mesh.info["tolerance_inv_depth"] -
        mesh.info["quantization_allowance_inv_depth"]``; no split when the mesh records no
        tolerance, as a hand-built one).

    Returns
    -------
    QuadMesh
        Same camera; the quads not split first (in their order), then the parts and the quads
        whose halves were refused; ``quad_of_pixel`` made from the rects; ``info`` adds
        ``"bin_fitted_quads"`` (quads of ``mesh`` whose plane came from the bins) and
        ``"bin_split_quads"`` (quads of ``mesh`` split into parts).
    """
    from ._segment_kernels import label_rects

    codes = _Codes(mesh, depth)
    tol = _split_tolerance(mesh, tolerance)
    planes, fitted, gaps = _fit_quads(mesh, codes, quads)
    rects, origin = np.asarray(mesh.rects, np.int64), np.arange(len(mesh.rects))
    halve = fitted & (gaps > tol) & (_rect_areas(rects) > 1)
    parts = _split(codes, rects[halve], planes[halve], origin[halve], tol)
    rects, planes, origin = (np.concatenate(x) for x in zip((rects[~halve], planes[~halve], origin[~halve]), parts))
    info = {**mesh.info, "bin_fitted_quads": int(fitted.sum()),
            "bin_split_quads": int(np.count_nonzero(np.bincount(origin, minlength=len(mesh.rects)) > 1))}
    return QuadMesh(mesh.camera, rects, planes, label_rects(rects, *mesh.shape), info)


def _split(codes: "_Codes", rects, planes, origin, tol) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rects (their planes, and the index of the mesh's quad each came from) halved and
    fitted again, round after round, until every part follows its surface within ``tol``, is one
    pixel, or has no surface of its own (:func:`fit_mesh_in_code_bins`)."""
    done = []
    while len(rects):
        n = len(rects)
        halves, half_origin = _halves(rects), np.tile(origin, 2)
        got, gap = codes.fit(halves, half_origin)  # seeded by the quad of the mesh they came from
        ok = np.isfinite(got).all(1)
        whole = ~(ok[:n] | ok[n:])  # neither half follows a surface of its own: the quad stays whole
        done.append((rects[whole], planes[whole], origin[whole]))
        kept = np.tile(~whole, 2)
        halves, half_origin, got, gap, ok = halves[kept], half_origin[kept], got[kept], gap[kept], ok[kept]
        half_planes = np.where(ok[:, None], got, np.tile(planes[~whole], (2, 1)))
        again = ok & (gap > tol) & (_rect_areas(halves) > 1)
        done.append((halves[~again], half_planes[~again], half_origin[~again]))
        rects, planes, origin = halves[again], half_planes[again], half_origin[again]
    if not done:
        return rects, planes, origin
    return tuple(np.concatenate(x) for x in zip(*done))


def _split_tolerance(mesh: QuadMesh, tolerance) -> float:
    """``tolerance`` checked, or the default from the mesh's record (``inf`` without one)."""
    if tolerance is not None:
        if isinstance(tolerance, (float, np.floating)) and tolerance == np.inf:
            return float(np.inf)
        tol = check_finite_scalar("tolerance", tolerance)
        if tol < 0:
            raise ValueError(f"tolerance: expected a distance in inverse depth >= 0, got {tolerance!r}")
        return tol
    own = mesh.info.get("tolerance_inv_depth")
    if own is None:
        return float(np.inf)
    allowance = mesh.info.get("quantization_allowance_inv_depth") or 0.0
    try:
        return SPLIT_SHARE * (float(own) - float(allowance))
    except (TypeError, ValueError):
        raise TypeError(f"mesh: info['tolerance_inv_depth'] and info['quantization_allowance_inv_depth'] "
                        f"should be numbers, got {own!r} and {allowance!r}") from None


def _halves(rects) -> np.ndarray:
    """(2 N, 4) the rects halved across their longer side: all first halves, then all second."""
    wide = rects[:, 2] - rects[:, 0] >= rects[:, 3] - rects[:, 1]
    first, second = rects.copy(), rects.copy()
    mid_u, mid_v = (rects[:, 0] + rects[:, 2]) // 2, (rects[:, 1] + rects[:, 3]) // 2
    first[wide, 2] = second[wide, 0] = mid_u[wide]
    first[~wide, 3] = second[~wide, 1] = mid_v[~wide]
    return np.concatenate([first, second])


class _Codes:
    """A mesh's stored depth as inverse depth ``q`` and each pixel's code size ``step`` (inverse
    depth), checked once; :meth:`fit` runs the kernel on any rects of that image."""

    def __init__(self, mesh, depth):
        from ._segment_kernels import check_rects_inside

        if not isinstance(mesh, QuadMesh):
            raise TypeError(f"mesh: expected an ibr QuadMesh, got {type(mesh).__name__}")
        quant = mesh.info.get("quantization")
        if not isinstance(quant, DepthQuantization):
            raise ValueError("mesh: built without a quantization (build_mesh(..., quantization=...)); "
                             "its depth has no code bins")
        check_rects_inside(mesh.rects, *mesh.shape)
        q = _inv_depth(check_array("depth", depth, shape=mesh.shape, dtype_kind="fiu"))
        step = np.where(np.isfinite(q), quant.inv_step(np.nan_to_num(q)), 1.0)
        if not (step > 0).all():
            raise ValueError(f"mesh: its quantization ({quant.describe()}) has no step at some depth of this view")
        self.q, self.step = q, np.ascontiguousarray(step)

    def fit(self, rects, seeds) -> tuple[np.ndarray, np.ndarray]:
        """(N, 3) planes of the rects in the bins (NaN rows where refused) and (N,) the largest
        distance of each from its surface."""
        from ._code_bins_kernels import fit_in_code_bins

        return fit_in_code_bins(self.q, self.step, np.ascontiguousarray(rects, np.int64),
                                np.asarray(seeds, np.int64), GROW, SURFACE_STEP_CODES, ITERATIONS, REJECT_AFTER,
                                REJECT_CODES, ACCEPT_CODES, RIDGE, MAX_WINDOW_PIXELS)


def _fit_quads(mesh: QuadMesh, codes: _Codes, quads=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`fit_planes_in_code_bins`'s planes and fitted quads, and each fitted quad's largest
    distance between plane and surface (NaN for the others)."""
    n = len(mesh.rects)
    chosen = np.ones(n, bool) if quads is None else check_array("quads", quads, shape=(n,), dtype_kind="b")
    idx = np.flatnonzero(chosen)
    got, gap = codes.fit(np.asarray(mesh.rects)[idx], idx)
    ok = np.isfinite(got).all(1)
    planes = np.array(mesh.inv_depth_planes, np.float64, copy=True)
    planes[idx[ok]] = got[ok]
    fitted = np.zeros(n, bool)
    fitted[idx[ok]] = True
    gaps = np.full(n, np.nan)
    gaps[idx[ok]] = gap[ok]
    return planes, fitted, gaps
