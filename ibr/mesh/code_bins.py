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
surface, the quad keeps its plane).

Measured (``python -c "import bench_edges as be; be.section_quantized()"`` in ``benchmarks/``,
8-bit disparity against the exact depth, after :mod:`ibr.render.plane_refine`'s colour fit of
the large quads, for every quad it did not take): clutter -0.56 -> -0.30 dB (planes refitted on
the exact depth for every quad under 200 px: -0.27), room -0.25 -> -0.22; docs/edges.md
section 3.

Conventions: pixel centres at integer (u, v); rects ``(x0, y0, x1, y1)`` with exclusive ends;
planes of inverse planar depth ``1/z = a u + b v + c`` as in :class:`ibr.mesh.QuadMesh`.
"""

from __future__ import annotations

import numpy as np

from ..base.depth import DepthQuantization
from ..base.validate import check_array
from .quad_mesh import QuadMesh, _inv_depth

__all__ = ["ACCEPT_CODES", "GROW", "ITERATIONS", "MAX_WINDOW_PIXELS", "REJECT_AFTER", "REJECT_CODES", "RIDGE",
           "SURFACE_STEP_CODES", "fit_planes_in_code_bins"]

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
    from ._code_bins_kernels import fit_in_code_bins
    from ._segment_kernels import check_rects_inside

    if not isinstance(mesh, QuadMesh):
        raise TypeError(f"mesh: expected an ibr QuadMesh, got {type(mesh).__name__}")
    quant = mesh.info.get("quantization")
    if not isinstance(quant, DepthQuantization):
        raise ValueError("mesh: built without a quantization (build_mesh(..., quantization=...)); "
                         "its depth has no code bins")
    check_rects_inside(mesh.rects, *mesh.shape)
    q = _inv_depth(check_array("depth", depth, shape=mesh.shape, dtype_kind="fiu"))
    n = len(mesh.rects)
    chosen = np.ones(n, bool) if quads is None else check_array("quads", quads, shape=(n,), dtype_kind="b")
    step = np.where(np.isfinite(q), quant.inv_step(np.nan_to_num(q)), 1.0)
    if not (step > 0).all():
        raise ValueError(f"mesh: its quantization ({quant.describe()}) has no step at some depth of this view")
    idx = np.flatnonzero(chosen)
    got = fit_in_code_bins(q, np.ascontiguousarray(step), np.ascontiguousarray(mesh.rects, np.int64),
                           idx.astype(np.int64), GROW, SURFACE_STEP_CODES, ITERATIONS, REJECT_AFTER,
                           REJECT_CODES, ACCEPT_CODES, RIDGE, MAX_WINDOW_PIXELS)
    ok = np.isfinite(got).all(1)
    planes = np.array(mesh.inv_depth_planes, np.float64, copy=True)
    planes[idx[ok]] = got[ok]
    fitted = np.zeros(n, bool)
    fitted[idx[ok]] = True
    return planes, fitted
