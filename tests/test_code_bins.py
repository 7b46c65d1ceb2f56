"""Issue 11, part 3: planes of quantized depth placed inside the bins of the codes around each
quad (:mod:`ibr.mesh.code_bins`), against analytic surfaces in integer disparity codes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ibr.base.camera import Camera
from ibr.base.depth import DepthQuantization, set_quantization
from ibr.base.view import View
from ibr.mesh import build_mesh
from ibr.mesh import code_bins
from ibr.mesh.code_bins import MAX_WINDOW_PIXELS, fit_mesh_in_code_bins, fit_planes_in_code_bins
from ibr.mesh.quad_mesh import QuadMesh, fit_inv_depth_planes, mesh_depth

BF = 100.0  # baseline x focal length (px x scene units): disparity d = BF / z, one code = 1 px
H, W = 64, 80
QUANT = DepthQuantization.disparity(baseline=1.0, focal_px=BF)


def _grid_mesh(depth, size=8) -> QuadMesh:
    """A mesh of size x size quads tiling the valid pixels, planes on the stored depth."""
    rects = np.array([(x, y, min(x + size, W), min(y + size, H)) for y in range(0, H, size)
                      for x in range(0, W, size)], np.int32)
    rects = np.array([r for r in rects if np.isfinite(depth[r[1]:r[3], r[0]:r[2]]).all()], np.int32)
    qop = np.full((H, W), -1, np.int32)
    for i, (x0, y0, x1, y1) in enumerate(rects):
        qop[y0:y1, x0:x1] = i
    camera = Camera(fx=BF, fy=BF, cx=W / 2, cy=H / 2, width=W, height=H)
    return QuadMesh(camera, rects, fit_inv_depth_planes(depth, rects), qop, {"quantization": QUANT})


def _codes(disparity) -> np.ndarray:
    """Planar depth of integer disparity codes (no depth, inf, where the code is 0 or below)."""
    codes = np.rint(disparity)
    with np.errstate(divide="ignore"):
        return np.where(codes > 0, BF / codes, np.inf).astype(np.float32)


def _plane_error(planes, rects, disparity) -> np.ndarray:
    """rms disparity error (codes) of each quad's plane against the true disparity."""
    out = []
    for (x0, y0, x1, y1), p in zip(rects, planes):
        v, u = np.mgrid[y0:y1, x0:x1]
        out.append(np.sqrt(np.mean((BF * (p[0] * u + p[1] * v + p[2]) - disparity[y0:y1, x0:x1]) ** 2)))
    return np.array(out)


def _uv():
    return np.mgrid[0:H, 0:W].astype(np.float64)[::-1]


def test_a_gentle_slope_inside_flat_codes_is_found_from_the_codes_around():
    """A plane rising 0.06 code per pixel: an 8 x 8 quad holds one or two codes, so its
    least-squares plane on them is up to half a code off; the bins around it pin the slope."""
    u, v = _uv()
    disparity = 20.3 + 0.06 * u + 0.02 * v
    mesh = _grid_mesh(_codes(disparity))
    planes, fitted = fit_planes_in_code_bins(mesh, _codes(disparity))
    before = _plane_error(mesh.inv_depth_planes, mesh.rects, disparity)
    after = _plane_error(planes, mesh.rects, disparity)
    assert fitted.mean() > 0.9
    assert np.mean(before) > 0.15
    assert np.mean(after) < 0.25 * np.mean(before) and np.max(after) < np.max(before)


def test_a_curved_surface_is_placed_better_than_the_codes_place_it():
    """A paraboloid (a sphere's cap, disparity 14-26 codes): every quad's plane closer to the
    truth on average, none worse than half a code."""
    u, v = _uv()
    disparity = 26.0 - 0.004 * ((u - 40) ** 2 + (v - 32) ** 2)
    mesh = _grid_mesh(_codes(disparity))
    planes, fitted = fit_planes_in_code_bins(mesh, _codes(disparity))
    before = _plane_error(mesh.inv_depth_planes, mesh.rects, disparity)
    after = _plane_error(planes, mesh.rects, disparity)
    assert np.mean(after) < 0.6 * np.mean(before)
    assert np.max(after) < 0.5


def test_a_crease_and_a_depth_edge_do_not_bend_the_plane_beside_them():
    """A roof (two planes meeting at x = 40, slopes +-0.07 code/px) in front of a far wall
    (disparity 5) from y = 48 down: the quads touching the crease or the wall are placed better
    than their codes place them (the other face's pixels far from its plane are left out, the wall
    is another surface), though the near side of the crease bends them a little."""
    u, v = _uv()
    disparity = np.where(u < 40, 20.2 + 0.07 * (u - 40), 20.2 - 0.07 * (u - 40)) + 0.01 * v
    disparity = np.where(v >= 48, 5.0, disparity)
    mesh = _grid_mesh(_codes(disparity))
    planes, fitted = fit_planes_in_code_bins(mesh, _codes(disparity))
    before = _plane_error(mesh.inv_depth_planes, mesh.rects, disparity)
    after = _plane_error(planes, mesh.rects, disparity)
    x0, y0 = mesh.rects[:, 0], mesh.rects[:, 1]
    beside = ((x0 == 32) | (x0 == 40) | (y0 == 40)) & (y0 < 48)
    assert fitted[beside].all()
    assert np.mean(after[beside]) < 0.5 * np.mean(before[beside])
    assert np.max(after[beside]) < np.max(before[beside])
    assert np.array_equal(planes[y0 >= 48], mesh.inv_depth_planes[y0 >= 48]) or np.max(after[y0 >= 48]) < 1e-6


def test_depth_in_codes_of_5_cm_far_from_the_camera():
    """Planar depth stored in codes of 5 cm (uniform in z, not in 1/z) on a tilted plane 7.8-8 m
    away (6 codes): the bins work in inverse depth with each pixel's own step; the planes'
    mean error falls from 0.23 to 0.09 code."""
    u, v = _uv()
    z = 1.0 / (1 / 8.0 + 0.00004 * u + 0.00001 * v)
    stored = (np.rint(z / 0.05) * 0.05).astype(np.float32)
    grid = _grid_mesh(stored)
    mesh = QuadMesh(grid.camera, grid.rects, grid.inv_depth_planes, grid.quad_of_pixel,
                    {"quantization": DepthQuantization.codes(0.05)})
    planes, fitted = fit_planes_in_code_bins(mesh, stored)

    def error(p):  # rms error of each quad's plane, in codes of 5 cm
        out = []
        for (x0, y0, x1, y1), pl in zip(mesh.rects, p):
            vv, uu = np.mgrid[y0:y1, x0:x1]
            out.append(np.sqrt(np.mean((1 / (pl[0] * uu + pl[1] * vv + pl[2]) - z[y0:y1, x0:x1]) ** 2)) / 0.05)
        return np.array(out)

    assert fitted.all()
    assert np.mean(error(planes)) < 0.5 * np.mean(error(mesh.inv_depth_planes))
    assert np.max(error(planes)) <= np.max(error(mesh.inv_depth_planes))


def test_a_one_pixel_pole_in_front_of_a_wall():
    """Hard case: a pole one pixel wide (disparity 30.3, rising 0.01 code per row) in front of a
    tilted wall (10-15 codes). The pole's quad is a line (no curvature across it: the ridge keeps
    that at zero) and stays on its own codes; the wall's quads beside it are not pulled toward
    the pole (20 codes nearer) and are placed no worse than their codes place them (with the wall
    on one side only, the quadratic surface is least sure at the quads by the pole: 0.20 code
    rms against 0.04 on the open wall)."""
    u, v = _uv()
    wall = 10.2 + 0.06 * u + 0.01 * v
    disparity = np.where(u == 43, 30.3 + 0.01 * v, wall)
    depth = _codes(disparity)
    grid = _grid_mesh(depth)
    rects = [r for r in grid.rects if not r[0] <= 43 < r[2]]  # the grid without the pole's column...
    for x0, y0, x1, y1 in (r for r in grid.rects if r[0] <= 43 < r[2]):  # ...split around the pole
        rects += [(x0, y0, 43, y1), (43, y0, 44, y1), (44, y0, x1, y1)]
    rects = np.array(rects, np.int32)
    qop = np.full((H, W), -1, np.int32)
    for i, (x0, y0, x1, y1) in enumerate(rects):
        qop[y0:y1, x0:x1] = i
    mesh = QuadMesh(grid.camera, rects, fit_inv_depth_planes(depth, rects), qop, {"quantization": QUANT})
    planes, fitted = fit_planes_in_code_bins(mesh, depth)
    assert np.isfinite(planes).all()
    error = _plane_error(planes, rects, disparity)
    before = _plane_error(mesh.inv_depth_planes, rects, disparity)
    pole = (rects[:, 0] == 43) & (rects[:, 2] == 44)
    beside = ((rects[:, 2] == 43) | (rects[:, 0] == 44))
    assert pole.sum() == H // 8 and np.max(error[pole]) < 0.5
    assert fitted[beside].all() and np.max(error[beside]) < 0.4
    assert np.mean(error[beside]) <= np.mean(before[beside]) + 0.01


def test_codes_of_no_smooth_surface_keep_their_planes():
    """Noisy codes (a code's worth of noise on a plane): no quadratic surface lies within a
    quarter code of every bin of a quad, so (nearly) every quad keeps its plane exactly; on the
    same plane without noise every quad is fitted."""
    u, v = _uv()
    smooth = 20.3 + 0.06 * u + 0.02 * v
    noisy = smooth + np.random.default_rng(3).normal(0, 1.0, (H, W))
    for disparity, share in ((noisy, (0.0, 0.1)), (smooth, (1.0, 1.0))):
        depth = _codes(disparity)
        mesh = _grid_mesh(depth)
        planes, fitted = fit_planes_in_code_bins(mesh, depth)
        assert share[0] <= fitted.mean() <= share[1]
        assert np.array_equal(planes[~fitted], mesh.inv_depth_planes[~fitted])


def test_a_large_quad_is_fitted_on_a_random_share_of_its_window(monkeypatch):
    """A 64 x 64 quad (its grown window clipped to the 80 x 64 image: 5120 pixels, more than
    MAX_WINDOW_PIXELS) on a plane rising 0.03 code per pixel (two codes over the quad): within 0.02 code
    of the truth (its least-squares plane on the codes 0.05), the same planes on every call, and
    within 0.005 code of the fit on every pixel of the window."""
    u, v = _uv()
    disparity = 20.3 + 0.03 * u + 0.009 * v
    depth = _codes(disparity)
    mesh = _grid_mesh(depth, size=64)
    big = (mesh.rects[:, 2] - mesh.rects[:, 0]) * (mesh.rects[:, 3] - mesh.rects[:, 1]) == 64 * 64
    assert big.sum() == 1 and W * H > MAX_WINDOW_PIXELS
    first, fitted = fit_planes_in_code_bins(mesh, depth)
    again, _ = fit_planes_in_code_bins(mesh, depth)
    assert fitted[big].all() and np.array_equal(first, again)
    assert _plane_error(first[big], mesh.rects[big], disparity)[0] < 0.02
    assert _plane_error(mesh.inv_depth_planes[big], mesh.rects[big], disparity)[0] > 0.04
    monkeypatch.setattr(code_bins, "MAX_WINDOW_PIXELS", 10**9)
    every, _ = fit_planes_in_code_bins(mesh, depth)
    assert not np.array_equal(every[big], first[big])  # the share was a share
    x0, y0, x1, y1 = mesh.rects[big][0]
    corners = np.array([(x, y, 1) for x in (x0, x1 - 1) for y in (y0, y1 - 1)], float)
    assert np.abs(BF * corners @ (every[big][0] - first[big][0])).max() < 0.005


def test_a_quad_over_a_hole_in_the_depth_is_fitted_on_its_valid_pixels():
    """A hand-built quad whose middle has no depth (NaN, 0, inf): fitted from the pixels that
    have it, the plane as good as on the same quad without the hole."""
    u, v = _uv()
    disparity = 20.3 + 0.06 * u + 0.02 * v
    depth = _codes(disparity)
    holed = depth.copy()
    holed[20:24, 20:22], holed[20:24, 22], holed[20:24, 23] = np.nan, 0.0, np.inf
    full, _ = fit_planes_in_code_bins(_grid_mesh(depth), depth)
    mesh = _grid_mesh(depth)  # the rects of the full depth: one quad covers the hole
    planes, fitted = fit_planes_in_code_bins(mesh, holed)
    at = np.flatnonzero((mesh.rects[:, 0] == 16) & (mesh.rects[:, 1] == 16))[0]
    assert fitted[at] and np.isfinite(planes).all()
    error = _plane_error(planes, mesh.rects, disparity)
    assert error[at] < _plane_error(full, mesh.rects, disparity)[at] + 0.02 and error[at] < 0.1


def test_integer_codes_give_the_planes_of_the_same_codes_as_floats():
    """Depth in integer millimetre codes (uint16) against the same values as float32 metres:
    the same planes to a hundredth of a code."""
    u, v = _uv()
    mm = np.rint(3000 + 7 * u + 2 * v).astype(np.uint16)
    grid = _grid_mesh(mm.astype(np.float32) / 1000)
    planes = []
    for depth, scale in ((mm, 1.0), (mm.astype(np.float32) / 1000, 0.001)):
        per_m = 1000.0 if scale == 1.0 else 1.0  # inverse depth in 1/mm is 1/1000 of that in 1/m
        mesh = QuadMesh(grid.camera, grid.rects, grid.inv_depth_planes / per_m, grid.quad_of_pixel,
                        {"quantization": DepthQuantization.codes(scale)})
        got, fitted = fit_planes_in_code_bins(mesh, depth)
        assert fitted.mean() > 0.9
        planes.append(got * per_m)
    corners = np.array([(x, y, 1.0) for x0, y0, x1, y1 in grid.rects for x in (x0, x1 - 1) for y in (y0, y1 - 1)])
    quad = np.repeat(np.arange(len(grid.rects)), 4)
    q_int, q_float = (np.einsum("ij,ij->i", p[quad], corners) for p in planes)
    step = 0.001 * q_float**2  # one millimetre in inverse depth (1/m)
    assert np.abs(q_int - q_float).max() < 0.01 * step.min()  # float32 metres round below 0.001 mm


def test_a_quads_plane_does_not_depend_on_which_others_are_fitted(monkeypatch):
    """With a small window budget every quad is fitted on a random share; each quad draws its
    own, so fitting it alone gives the same plane as fitting it with all the others."""
    monkeypatch.setattr(code_bins, "MAX_WINDOW_PIXELS", 100)
    u, v = _uv()
    depth = _codes(20.3 + 0.06 * u + 0.02 * v)
    mesh = _grid_mesh(depth)
    together, _ = fit_planes_in_code_bins(mesh, depth)
    for i in (0, 7, len(mesh.rects) - 1):
        alone = np.zeros(len(mesh.rects), bool)
        alone[i] = True
        assert np.array_equal(fit_planes_in_code_bins(mesh, depth, alone)[0][i], together[i])


def test_only_the_chosen_quads_change_and_invalid_depth_is_not_used():
    u, v = _uv()
    disparity = 20.3 + 0.06 * u
    depth = _codes(disparity)
    depth[:, :8] = np.nan  # no depth in the first column of quads
    mesh = _grid_mesh(depth)
    chosen = np.zeros(len(mesh.rects), bool)
    chosen[::2] = True
    planes, fitted = fit_planes_in_code_bins(mesh, depth, chosen)
    assert not fitted[~chosen].any() and fitted[chosen].all()
    assert np.array_equal(planes[~chosen], mesh.inv_depth_planes[~chosen])
    assert np.isfinite(planes).all()


def test_build_mesh_s_own_meshes_of_codes():
    """build_mesh's mesh of a quantized paraboloid (90 quads, whose planes approximate the curve
    within the tolerance): their mean error falls by more than 0.02 code; of a tilted plane (one
    quad across nine codes, which pin it: 0.002 code): kept within 0.005 code."""
    u, v = _uv()
    camera = Camera(fx=BF, fy=BF, cx=W / 2, cy=H / 2, width=W, height=H)
    for disparity, curved in ((26.0 - 0.02 * ((u - 40) ** 2 + (v - 32) ** 2), True),
                              (12.4 + 0.11 * u - 0.03 * v, False)):
        depth = _codes(disparity)
        mesh = build_mesh(View(np.zeros((H, W, 3), np.uint8), depth, camera, "codes"), quantization=QUANT)
        planes, fitted = fit_planes_in_code_bins(mesh, depth)
        before = _plane_error(mesh.inv_depth_planes, mesh.rects, disparity)
        after = _plane_error(planes, mesh.rects, disparity)
        assert fitted.mean() > 0.5
        if curved:
            assert len(mesh) > 50 and np.mean(after) < np.mean(before) - 0.02
        else:
            assert len(mesh) == 1 and after[0] < 0.005


@pytest.mark.parametrize("change, error, match", [
    (lambda m, d, q: ("not a mesh", d, q), TypeError, "mesh: expected an ibr QuadMesh"),
    (lambda m, d, q: (QuadMesh(m.camera, m.rects, m.inv_depth_planes, m.quad_of_pixel, {}), d, q),
     ValueError, "mesh: built without a quantization"),
    (lambda m, d, q: (QuadMesh(m.camera, m.rects, m.inv_depth_planes, m.quad_of_pixel,
                               {"quantization": DepthQuantization()}), d, q), ValueError, "mesh: its quantization"),
    (lambda m, d, q: (QuadMesh(m.camera, m.rects + [0, 0, 1, 0], m.inv_depth_planes, m.quad_of_pixel,
                               m.info), d, q), ValueError, "rects: expected non-empty"),
    (lambda m, d, q: (m, None, q), TypeError, "depth: expected an array"),
    (lambda m, d, q: (m, d[:10], q), ValueError, "depth: expected shape"),
    (lambda m, d, q: (m, d > 0, q), ValueError, "depth: expected dtype"),
    (lambda m, d, q: (m, d, q[:3]), ValueError, "quads: expected shape"),
    (lambda m, d, q: (m, d, q.astype(int)), ValueError, "quads: expected dtype"),
])
@pytest.mark.parametrize("fit", [fit_planes_in_code_bins, fit_mesh_in_code_bins])
def test_bad_input_is_refused_by_name(change, error, match, fit):
    u, _ = _uv()
    depth = _codes(20.3 + 0.06 * u)
    mesh = _grid_mesh(depth)
    args = change(mesh, depth, np.ones(len(mesh.rects), bool))
    with pytest.raises(error, match=match):
        fit(*args)


@pytest.mark.parametrize("tolerance, error", [(-0.01, ValueError), (np.nan, ValueError), (-np.inf, ValueError),
                                              ("0.1", TypeError), (True, TypeError)])
def test_a_bad_split_tolerance_is_refused_by_name(tolerance, error):
    depth = _codes(20.3 + 0.06 * _uv()[0])
    with pytest.raises(error, match="tolerance"):
        fit_mesh_in_code_bins(_grid_mesh(depth), depth, tolerance=tolerance)


def _with_tolerance(mesh, codes) -> QuadMesh:
    """``mesh`` as build_mesh records it: a tolerance of ``codes`` disparity codes besides the
    codes' half-code allowance."""
    info = {**mesh.info, "tolerance_inv_depth": (codes + 0.5) / BF, "quantization_allowance_inv_depth": 0.5 / BF}
    return QuadMesh(mesh.camera, mesh.rects, mesh.inv_depth_planes, mesh.quad_of_pixel, info)


def _mesh_error(mesh, disparity) -> np.ndarray:
    """Disparity error (codes) of the mesh's planes at every pixel with a quad."""
    from ibr.mesh.quad_mesh import mesh_depth

    return (BF / mesh_depth(mesh) - disparity)[mesh.quad_of_pixel >= 0]


def test_a_quad_too_large_for_a_curve_is_split_until_its_parts_follow_it():
    """A sphere's cap (disparity 8-26 codes) under 16 x 16 quads, a tolerance of 0.25 code
    (0.075 with the default share): one plane per quad is up to a code off the cap near its
    rim, so the curved quads are halved until each part's plane follows the surface the bins
    allow; the parts tile their quad, and the mesh follows the true disparity far better than
    the unsplit planes in the bins do."""
    u, v = _uv()
    disparity = 26.0 - 0.01 * ((u - 40) ** 2 + (v - 32) ** 2)
    depth = _codes(disparity)
    mesh = _with_tolerance(_grid_mesh(depth, size=16), 0.25)
    split = fit_mesh_in_code_bins(mesh, depth)
    planes, fitted = fit_planes_in_code_bins(mesh, depth)
    unsplit = QuadMesh(mesh.camera, mesh.rects, planes, mesh.quad_of_pixel, mesh.info)
    assert split.info["bin_fitted_quads"] == fitted.sum() and split.info["bin_split_quads"] > 0.5 * len(mesh)
    assert len(split) > 2 * len(mesh)
    assert np.array_equal(split.quad_of_pixel >= 0, mesh.quad_of_pixel >= 0)  # the same pixels, once each
    assert split.areas.sum() == mesh.areas.sum()
    before, after = np.abs(_mesh_error(unsplit, disparity)), np.abs(_mesh_error(split, disparity))
    assert np.sqrt(np.mean(after**2)) < 0.6 * np.sqrt(np.mean(before**2))
    assert after.max() < 0.6 < before.max()


def test_a_plane_in_codes_is_not_split_and_without_a_tolerance_nothing_is():
    """A tilted plane at a tolerance of half a code: its quads' surfaces are planes to within
    0.06 code (the bins allow some bend), so none is split; the sphere's cap of the test above with no tolerance recorded (a hand-built mesh)
    is not split either, and gets the planes :func:`fit_planes_in_code_bins` gives."""
    u, v = _uv()
    plane = _codes(20.3 + 0.06 * u + 0.02 * v)
    mesh = _with_tolerance(_grid_mesh(plane, size=16), 0.5)
    got = fit_mesh_in_code_bins(mesh, plane)
    assert len(got) == len(mesh) and got.info["bin_split_quads"] == 0 and got.info["bin_fitted_quads"] > 0
    cap = _codes(26.0 - 0.01 * ((u - 40) ** 2 + (v - 32) ** 2))
    bare = _grid_mesh(cap, size=16)
    got = fit_mesh_in_code_bins(bare, cap)
    assert len(got) == len(bare) and got.info["bin_split_quads"] == 0
    assert np.array_equal(got.inv_depth_planes, fit_planes_in_code_bins(bare, cap)[0])


def test_the_split_tolerance_given_or_recorded():
    """The sphere's cap of the tests above: the tolerance the mesh records (0.25 code, times
    :data:`SPLIT_SHARE`) and the same value given give the same mesh; a looser one splits the
    quads into fewer parts, ``np.inf`` none."""
    u, v = _uv()
    depth = _codes(26.0 - 0.01 * ((u - 40) ** 2 + (v - 32) ** 2))
    mesh = _with_tolerance(_grid_mesh(depth, size=16), 0.25)
    recorded = fit_mesh_in_code_bins(mesh, depth)
    given = fit_mesh_in_code_bins(mesh, depth, tolerance=code_bins.SPLIT_SHARE * 0.25 / BF)
    assert np.array_equal(recorded.rects, given.rects) and np.array_equal(recorded.inv_depth_planes,
                                                                           given.inv_depth_planes)
    looser = fit_mesh_in_code_bins(mesh, depth, tolerance=0.3 / BF)
    assert 0 < looser.info["bin_split_quads"] <= recorded.info["bin_split_quads"] and len(looser) < len(recorded)
    none = fit_mesh_in_code_bins(mesh, depth, tolerance=float("inf"))
    assert len(none) == len(mesh) and none.info["bin_split_quads"] == 0
    assert np.array_equal(none.inv_depth_planes, fit_planes_in_code_bins(mesh, depth)[0])


def test_codes_of_no_smooth_surface_split_only_where_a_half_fits(monkeypatch):
    """Noisy codes of a wavy surface (4 x 4 quads, a tolerance of 0.05 code): the quads counted as
    fitted are those :func:`fit_planes_in_code_bins` fits, and a quad is split only where a half
    found a surface of its own (never into parts that all keep the quad's plane); the parts tile
    the quads, and a part's plane does not depend on which other quads are fitted (windows
    fitted on a random share of 64 pixels, drawn per quad of the mesh)."""
    monkeypatch.setattr(code_bins, "MAX_WINDOW_PIXELS", 64)
    rng = np.random.default_rng(3)
    u, v = _uv()
    depth = _codes(30 + 1.2 * np.sin(u / 3.0) * np.cos(v / 2.5) + rng.normal(0, 0.4, (H, W)))
    mesh = _grid_mesh(depth, size=4)
    planes, fitted = fit_planes_in_code_bins(mesh, depth)
    got = fit_mesh_in_code_bins(mesh, depth, tolerance=0.05 / BF)
    assert got.info["bin_fitted_quads"] == fitted.sum() and got.info["bin_split_quads"] > 3
    assert np.array_equal(got.quad_of_pixel >= 0, mesh.quad_of_pixel >= 0) and got.areas.sum() == mesh.areas.sum()
    for k in np.flatnonzero(fitted):
        x0, y0, x1, y1 = mesh.rects[k]
        parts = np.unique(got.quad_of_pixel[y0:y1, x0:x1])
        assert len(parts) == 1 or not all(np.array_equal(got.inv_depth_planes[i], planes[k]) for i in parts)
    alone = np.zeros(len(mesh.rects), bool)
    alone[np.flatnonzero(fitted)[:5]] = True
    some = fit_mesh_in_code_bins(mesh, depth, alone, tolerance=0.05 / BF)
    inside = np.isin(mesh.quad_of_pixel, np.flatnonzero(alone))
    from ibr.mesh.quad_mesh import mesh_depth
    assert np.array_equal(mesh_depth(some)[inside], mesh_depth(got)[inside])



@settings(max_examples=40, deadline=None)
@given(curvature=st.floats(0.0, 0.03), tilt=st.floats(-0.2, 0.2), size=st.sampled_from([3, 5, 8, 13]),
       tolerance_codes=st.floats(0.0, 1.0), holes=st.booleans(), seed=st.integers(0, 2**16))
def test_the_parts_always_tile_their_quads(curvature, tilt, size, tolerance_codes, holes, seed):
    """Any surface, grid of quads and tolerance (down to 0: parts of one pixel): every part lies
    inside one quad of the mesh, the parts cover exactly the quads' pixels, no plane is NaN, a
    quad is split only if it was fitted, and a quad that was not split keeps the plane
    :func:`fit_planes_in_code_bins` gives it."""
    rng = np.random.default_rng(seed)
    u, v = _uv()
    disparity = 24.0 + tilt * u - curvature * ((u - 40) ** 2 + (v - 32) ** 2) + rng.normal(0, 0.2, (H, W))
    depth = _codes(disparity)
    if holes:
        depth[rng.random((H, W)) < 0.05] = np.nan
    mesh = _grid_mesh(np.where(np.isfinite(depth), depth, 1.0).astype(np.float32), size=size)
    planes, fitted = fit_planes_in_code_bins(mesh, depth)
    got = fit_mesh_in_code_bins(mesh, depth, tolerance=tolerance_codes / BF)
    assert np.isfinite(got.inv_depth_planes).all()
    assert np.array_equal(got.quad_of_pixel >= 0, mesh.quad_of_pixel >= 0) and got.areas.sum() == mesh.areas.sum()
    x0, y0, x1, y1 = (np.asarray(got.rects)[:, i] for i in range(4))
    parent = mesh.quad_of_pixel[y0, x0]
    assert np.array_equal(mesh.quad_of_pixel[y1 - 1, x1 - 1], parent)  # a part never straddles two quads
    split = np.bincount(parent, minlength=len(mesh.rects)) > 1
    assert got.info["bin_split_quads"] == split.sum() and not (split & ~fitted).any()
    whole = np.flatnonzero(~split)
    part_of = {int(p): i for i, p in enumerate(parent) if not split[p]}
    assert all(np.array_equal(got.inv_depth_planes[part_of[k]], planes[k]) for k in whole)


# ---------------------------------------------------------------- per-pixel depth in the bins
def _disparity_rms(depth, disparity) -> float:
    return float(np.sqrt(np.nanmean((BF / depth - disparity) ** 2)))


@pytest.mark.parametrize("surface, before, after", [
    ("plane", 0.20, 0.12),  # measured 0.219 -> 0.099 codes rms
    ("paraboloid", 0.075, 0.07),  # 0.082 -> 0.061
    ("plane beside a far wall", 0.22, 0.18),  # 0.244 -> 0.159
])
def test_depth_in_code_bins_is_nearer_the_surface_than_the_planes_it_starts_from(surface, before, after):
    """Starting from 8 x 8 quads' least-squares planes on the codes, every pixel ends within half
    a code of its own and, on the whole, nearer the true disparity; across a depth edge (a plane
    of disparity 20-25 beside a wall at 8.2-10) nothing is averaged: the columns beside the edge
    improve too."""
    u, v = _uv()
    disparity = 20.3 + 0.06 * u + 0.02 * v
    if surface == "paraboloid":
        disparity = 26.0 - 0.004 * ((u - 40) ** 2 + (v - 32) ** 2)
    elif surface == "plane beside a far wall":
        disparity = np.where(u < 40, disparity, 8.2 + 0.03 * v)
    codes = _codes(disparity)
    start = mesh_depth(_grid_mesh(codes))
    out = code_bins.depth_in_code_bins(start, codes, QUANT)
    assert out.dtype == np.float32 and out.shape == codes.shape
    assert np.abs(BF / out - np.rint(disparity)).max() <= 0.5 + 1e-4
    assert _disparity_rms(start, disparity) > before
    assert _disparity_rms(out, disparity) < after
    beside = np.abs(BF / out - disparity)[:, 38:42].mean(0)
    assert (beside < np.abs(BF / start - disparity)[:, 38:42].mean(0) + 1e-3).all()


@settings(max_examples=25, deadline=None)
@given(st.floats(10, 40), st.floats(-0.1, 0.1), st.floats(-0.1, 0.1))
def test_depth_in_code_bins_leaves_a_true_plane_as_it_is(d0, du, dv):
    """A plane in inverse depth is a fixed point: the smoothing averages opposite neighbours
    (exact on a plane) and the truth lies in every bin."""
    u, v = _uv()
    disparity = d0 + du * u + dv * v
    exact = (BF / disparity).astype(np.float32)
    out = code_bins.depth_in_code_bins(exact, _codes(disparity), QUANT)
    assert np.allclose(out, exact, rtol=1e-5)


def test_depth_in_code_bins_keeps_the_start_where_either_has_no_depth():
    u, v = _uv()
    disparity = 20.3 + 0.06 * u
    codes = _codes(disparity)
    codes[10:20, 10:20] = np.nan
    start = (BF / disparity).astype(np.float32)
    start[30:40, 30:40] = np.nan
    out = code_bins.depth_in_code_bins(start, codes, QUANT, iterations=0)
    assert np.array_equal(out[10:20, 10:20], start[10:20, 10:20])
    assert np.isnan(out[30:40, 30:40]).all()
    assert np.isfinite(out).sum() == H * W - 100


@pytest.mark.parametrize("change, error, match", [
    ({"start": np.ones(5, np.float32)}, ValueError, "start: expected 2 dimensions"),
    ({"start": np.ones((H, W), np.int32)}, ValueError, "start: expected dtype of kind"),
    ({"codes": np.ones((H, W + 1), np.float32)}, ValueError, "codes: expected shape"),
    ({"quantization": 0.5}, TypeError, "quantization: expected an ibr.base.depth.DepthQuantization"),
    ({"iterations": -1}, ValueError, "iterations: expected an integer >= 0"),
    ({"iterations": True}, ValueError, "iterations: expected an integer >= 0"),
    ({"iterations": 2.0}, ValueError, "iterations: expected an integer >= 0"),
])
def test_depth_in_code_bins_refuses_bad_input_by_name(change, error, match):
    args = {"start": np.full((H, W), 5.0, np.float32), "codes": np.full((H, W), 5.0, np.float32),
            "quantization": QUANT, "iterations": 3}
    args.update(change)
    with pytest.raises(error, match=match):
        code_bins.depth_in_code_bins(args["start"], args["codes"], args["quantization"],
                                     iterations=args["iterations"])


# ---------------------------------------------------------------- the partner's codes as bounds
def _plane_pair(plane, partner_position):
    """A plane of inverse depth ``a u + b v + c`` in a camera at the origin and the same plane's
    8-bit disparity codes (``BF q``) in a partner camera at ``partner_position`` (no rotation):
    ``(camera, q, codes, partner)``."""
    a, b, c = plane
    camera = Camera(fx=BF, fy=BF, cx=W / 2, cy=H / 2, width=W, height=H)
    pose = np.eye(4)
    pose[:3, 3] = partner_position
    partner_camera = Camera(fx=BF, fy=BF, cx=W / 2, cy=H / 2, width=W, height=H, world_from_cam=pose)
    u, v = _uv()
    q = a * u + b * v + c
    normal = np.array([a * BF, b * BF, a * W / 2 + b * H / 2 + c])  # the plane n . X = 1 (camera frame)
    rays = np.stack([(u - W / 2) / BF, (v - H / 2) / BF, np.ones_like(u)], -1)
    q_partner = rays @ normal / (1 - normal @ np.asarray(partner_position, float))
    partner = View(np.zeros((H, W, 3), np.uint8), _codes(BF * q_partner), partner_camera, "partner")
    return camera, q, _codes(BF * q), partner


@pytest.mark.parametrize("position", [(1.0, 0, 0), (1.0, 0, 0.3), (1.0, 0.2, 0.5), (0.5, 0, 1.0)])
@pytest.mark.parametrize("plane", [(0.0006, 0.0002, 0.203), (0.0, 0.0, 0.2047), (-0.0004, 0.0007, 0.23)])
def test_partner_code_bins_hold_the_surface(plane, position):
    """The partner's bins carried back along each ray contain the true inverse depth wherever the
    partner sees the point (placed at the true depth), about one of its codes wide: (1 - t_z q)^2
    of this camera's (0.63-1.08 here)."""
    camera, q, _, partner = _plane_pair(plane, position)
    lo, hi = code_bins.partner_code_bins(camera, (1 / q).astype(np.float32), partner, QUANT)
    seen = np.isfinite(lo)
    assert 0.5 < seen.mean() < 0.8  # the rest falls outside the partner's image: NaN
    assert np.array_equal(seen, np.isfinite(hi))
    assert ((q >= lo - 1e-12) & (q <= hi + 1e-12))[seen].all()
    assert 0.5 < np.mean((hi - lo)[seen]) * BF < 1.3  # one partner code, in this camera's codes


def test_a_partner_that_moves_in_depth_places_a_wall_inside_one_code():
    """A wall at disparity 20.47 is code 20 everywhere: its own bins place it only within half a
    code (0.47 rms off, at the start). A partner beside it (a rectified pair) codes the same
    disparity function and adds nothing; one that also moved 0.3 forward codes another function
    of the same wall, whose changes cut the bin: 0.47 -> 0.34 codes rms (measured)."""
    results = {}
    for position in ((1.0, 0, 0), (1.0, 0, 0.3)):
        camera, q, codes, partner = _plane_pair((0.0, 0.0, 0.2047), position)
        start = mesh_depth(_grid_mesh(codes))
        alone = code_bins.depth_in_code_bins(start, codes, QUANT)
        bounds = code_bins.partner_code_bins(camera, start, partner, QUANT)
        both = code_bins.depth_in_code_bins(start, codes, QUANT, also_within=bounds)
        results[position] = [_disparity_rms(z, BF * q) for z in (alone, both)]
    assert results[(1.0, 0, 0)][0] > 0.45 and abs(results[(1.0, 0, 0)][1] - results[(1.0, 0, 0)][0]) < 1e-3
    assert results[(1.0, 0, 0.3)][1] < 0.36


def test_partner_code_bins_take_the_partner_s_recorded_quantization():
    camera, q, _, partner = _plane_pair((0.0006, 0.0002, 0.203), (1.0, 0, 0.3))
    with pytest.raises(ValueError, match="quantization: expected .* partner records none"):
        code_bins.partner_code_bins(camera, (1 / q).astype(np.float32), partner)
    set_quantization(partner, QUANT)
    got = code_bins.partner_code_bins(camera, (1 / q).astype(np.float32), partner)
    want = code_bins.partner_code_bins(camera, (1 / q).astype(np.float32), partner, QUANT)
    assert all(np.array_equal(g, w, equal_nan=True) for g, w in zip(got, want))


@pytest.mark.parametrize("change, error, match", [
    ({"camera": "cam"}, TypeError, "camera: expected an ibr Camera"),
    ({"partner": np.zeros((H, W))}, TypeError, "partner: expected an ibr View"),
    ({"start": np.ones((H, W + 1), np.float32)}, ValueError, "start: expected shape"),
    ({"quantization": 0.5}, TypeError, "quantization: expected an ibr.base.depth.DepthQuantization"),
])
def test_partner_code_bins_refuse_bad_input_by_name(change, error, match):
    camera, q, _, partner = _plane_pair((0.0006, 0.0002, 0.203), (1.0, 0, 0.3))
    args = {"camera": camera, "start": (1 / q).astype(np.float32), "partner": partner, "quantization": QUANT}
    args.update(change)
    with pytest.raises(error, match=match):
        code_bins.partner_code_bins(args["camera"], args["start"], args["partner"], args["quantization"])


@pytest.mark.parametrize("bounds, error, match", [
    (np.zeros((H, W)), TypeError, "also_within: expected a pair"),
    ((np.zeros((H, W)), np.zeros((H, W + 1))), ValueError, r"also_within\[1\]: expected shape"),
])
def test_depth_in_code_bins_refuses_bad_bounds_by_name(bounds, error, match):
    depth = np.full((H, W), 5.0, np.float32)
    with pytest.raises(error, match=match):
        code_bins.depth_in_code_bins(depth, depth, QUANT, also_within=bounds)
