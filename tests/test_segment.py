"""Tests of ibr.segment: z', Δ² buffers, break edges and the binary splits (seed 002 §1.2).

Depth maps are built analytically from a Camera and plane/saddle formulas: over a plane
n·X = 1 (camera frame) the inverse depth is exactly 1/z = n·(x/z, y/z, 1), affine in (u, v).
"""

from __future__ import annotations

import numpy as np
import pytest

from ibr.mesh import _segment_kernels as K
from ibr.mesh import segment as S
from ibr.base.camera import Camera
from ibr.base.depth import zprime_from_z

CAM = Camera.from_fov(48, 40, hfov_deg=70)


def plane_depth(cam: Camera, n) -> np.ndarray:
    """Planar depth of the plane n·X = 1 seen by ``cam`` (camera frame), float64."""
    r = cam.rays_cam()
    return 1.0 / (r @ np.asarray(n, float))


def piecewise_scene(seed: int, h=23, w=29) -> np.ndarray:
    """Random piecewise-planar depth with steps, creases, noise spots and NaN/inf/0 islands."""
    rng = np.random.default_rng(seed)
    cam = Camera.from_fov(w, h, hfov_deg=60)
    u, v = cam.pixel_grid()
    q = 0.5 + 0.01 * u - 0.004 * v
    for _ in range(4):
        u0, v0 = rng.integers(0, w - 3), rng.integers(0, h - 3)
        u1, v1 = u0 + rng.integers(2, w - u0 + 1), v0 + rng.integers(2, h - v0 + 1)
        a, b, c = rng.normal(0, 0.01), rng.normal(0, 0.01), rng.uniform(0.3, 1.0)
        sl = (slice(v0, v1), slice(u0, u1))
        q[sl] = a * u[sl] + b * v[sl] + c
    q = np.abs(q) + 0.2
    q += (rng.random(q.shape) < 0.03) * rng.normal(0, 0.05, q.shape)  # sparse spikes
    z = 1.0 / q
    z[rng.random(z.shape) < 0.04] = np.nan
    z[rng.integers(0, h), rng.integers(0, w)] = np.inf
    z[rng.integers(0, h), rng.integers(0, w)] = 0.0
    return z


def covers_valid_exactly_once(rects, z):
    lab = np.zeros(z.shape, int)
    for u0, v0, u1, v1 in rects:
        assert u1 > u0 and v1 > v0
        lab[v0:v1, u0:u1] += 1
    valid = np.isfinite(z) & (z > 0)
    assert np.array_equal(lab, valid.astype(int)), "rects must cover every valid pixel once, invalid none"


# ------------------------------------------------------------------ z'


def test_zprime_matches_seed_eq2_and_kernel():
    z = piecewise_scene(0)
    zp, n, f = S.zprime(z)
    valid = np.isfinite(z) & (z > 0)
    assert n == pytest.approx(z[valid].min()) and f == pytest.approx(z[valid].max())
    ref = (2.0**24) * f / (f - n) * (1 - n / z[valid])
    np.testing.assert_allclose(zp[valid], ref, rtol=1e-12, atol=1e-6)
    assert np.isnan(zp[~valid]).all()
    kz = K.zprime_kernel(np.ascontiguousarray(z), n, f, 2.0**24)
    np.testing.assert_allclose(kz[valid], zprime_from_z(z, near=n, far=f)[valid], rtol=1e-13)
    assert np.array_equal(np.isnan(kz), ~valid)
    # the nearest pixel maps to 0 and the farthest to 2^24, as a tight z-buffer would
    assert np.nanmin(zp) == pytest.approx(0, abs=1e-6) and np.nanmax(zp) == pytest.approx(2**24)


def test_auto_near_far_constant_depth_and_errors():
    assert S.auto_near_far(np.full((3, 4), 7.0)) == (7.0, 14.0)
    with pytest.raises(ValueError, match="no valid pixel"):
        S.auto_near_far(np.full((3, 4), np.nan))
    with pytest.raises(ValueError, match="depth: expected 2 dimensions"):
        S.zprime(np.ones(5))
    with pytest.raises(ValueError, match="far: expected far > near"):
        S.zprime(np.ones((2, 2)), near=2.0, far=1.0)


# ------------------------------------------------------------------ Δ² and measures


def test_delta2_zero_on_planes_including_borders():
    z = plane_depth(CAM, (0.3, -0.2, 0.4))
    zp, _, _ = S.zprime(z)
    d = S.delta2(zp)
    # exactly affine z' up to float rounding of ~2^24-sized values
    assert np.abs(d).max() < 1e-6 * 2**24 * 1e-3
    # the stencil sign: Δ² = 4z - 4 neighbours (a bump up gives a positive value)
    bump = np.zeros((5, 5))
    bump[2, 2] = 1.0
    assert S.delta2(bump)[2, 2] == 4.0 and S.delta2(bump)[1, 2] == -1.0


def test_delta2_axis_dropped_at_border_and_next_to_nan():
    zp = np.arange(20, dtype=float).reshape(4, 5) ** 2  # curved along both axes
    d = S.delta2(zp)
    # corner pixel: no complete stencil on either axis
    assert d[0, 0] == 0
    # interior: d2/du2 of (5v + u)^2 is 2, d2/dv2 is 50 -> -(2 + 50)
    assert d[1, 1] == pytest.approx(-52)
    zp[1, 2] = np.nan
    d = S.delta2(zp)
    assert np.isnan(d[1, 2])
    assert d[1, 1] == pytest.approx(-50)  # u axis touches the NaN: dropped


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_measure_kernels_match_references(seed):
    zp, _, _ = S.zprime(piecewise_scene(seed))
    np.testing.assert_allclose(S.planarity_measure(zp, method="paper"), S._laplacian_measure_reference(zp))
    np.testing.assert_allclose(S.planarity_measure(zp, method="separate"), S._separate_measure_reference(zp))


def test_harmonic_saddle_fools_the_laplacian_not_separate_differences():
    u, v = CAM.pixel_grid()
    zp = 1000.0 * ((u - CAM.cx) ** 2 - (v - CAM.cy) ** 2)  # Δ² = 0 everywhere, not planar
    lap = S.planarity_measure(zp, method="paper")
    assert lap[1:-1, 1:-1].max() < 1e-6  # (border pixels see one axis only: 2000)
    sep = S.planarity_measure(zp, method="separate")
    assert sep[1:-1, 1:-1].min() == pytest.approx(2000.0)
    # the mixed term catches z' = u v, which both axis terms miss
    zp2 = 1000.0 * u * v
    assert S.planarity_measure(zp2, method="separate")[1:-1, 1:-1].min() == pytest.approx(1000.0)


# ------------------------------------------------------------------ break edges


def test_break_edges_step_crease_and_plane_next_to_edge():
    line = np.array([0, 1, 2, 3, 4, 50, 51, 52, 53], float)  # step between index 4 and 5
    hb, vb = S.break_edges(line[None, :], 0.5)
    assert hb[0].tolist() == [0, 0, 0, 0, 1, 0, 0, 0]
    assert vb.shape == (0, 9)
    crease = np.array([0, 1, 2, 3, 4, 3, 2, 1, 0], float)  # crease exactly at index 4
    hb, _ = S.break_edges(crease[None, :], 0.5)
    assert hb[0].tolist() == [0, 0, 0, 0, 1, 0, 0, 0]  # pixel 4 joins the low side
    crease2 = np.array([0, 1, 2, 3, 4, 4.5, 3.5, 2.5, 1.5], float)  # crease between 4 and 5
    hb, _ = S.break_edges(crease2[None, :], 0.3)
    assert hb[0].tolist() == [0, 0, 0, 0, 1, 0, 0, 0]
    nan = np.array([1, 2, np.nan, np.nan, 5, 6], float)
    hb, _ = S.break_edges(nan[None, :], 0.5)
    assert hb[0].tolist() == [0, 1, 0, 1, 0]
    # same along columns
    _, vb = S.break_edges(line[:, None], 0.5)
    assert vb[:, 0].tolist() == [0, 0, 0, 0, 1, 0, 0, 0]


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_break_edges_kernel_matches_reference(seed):
    zp, _, _ = S.zprime(piecewise_scene(seed))
    for thr in (1e3, 1e5, 1e6):
        hb, vb = S.break_edges(zp, thr)
        rh, rv = S._break_edges_reference(zp, thr)
        assert np.array_equal(hb, rh) and np.array_equal(vb, rv)
        # the fused prefix sums the split kernel reads
        ch, rvt = K.edge_prefix(zp, thr)
        assert np.array_equal(ch[1:], np.cumsum(rh, axis=0)) and not ch[0].any()
        assert np.array_equal(rvt[1:], np.cumsum(rv, axis=1).T) and not rvt[0].any()


# ------------------------------------------------------------------ binary split


def test_paper_split_worked_example():
    """Seed 002 split on a 5x3 map with one pixel over threshold at (u=3, v=1), by hand:
    scan columns from the left, split before column 3; the right part [3,5)x[0,3) is split by
    rows: before row 1; [3,5)x[1,3) by columns: the left band is empty, from the right one clean
    column -> split at 4; [3,4)x[1,3) by rows: from the bottom -> split at 2."""
    bad = np.zeros((3, 5), np.uint8)
    bad[1, 3] = 1
    inv = np.zeros_like(bad)
    expected = [[0, 0, 3, 3], [3, 0, 5, 1], [3, 1, 4, 2], [3, 2, 4, 3], [4, 1, 5, 3]]
    assert S._split_pixels_reference(bad, inv, 1, 0).tolist() == expected
    assert K.split_pixels(bad, inv, 1, 0).tolist() == expected


def test_paper_split_min_band_and_middle_fallback():
    bad = np.zeros((1, 8), np.uint8)
    bad[0, [1, 6]] = 1  # bands of 1 on both sides
    inv = np.zeros_like(bad)
    # min_band 2: neither side is large enough -> split in the middle (u = 4), then recurse
    got = K.split_pixels(bad, inv, 2, 0).tolist()
    assert got == S._split_pixels_reference(bad, inv, 2, 0).tolist()
    assert got[0][2] <= 4 and [r for r in got if r[0] == 4 or r[2] == 4]
    # min_band 1: split before column 1 first
    assert K.split_pixels(bad, inv, 1, 0).tolist()[0] == [0, 0, 1, 1]


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("method", ["paper", "separate", "edge"])
def test_split_kernels_match_references_and_partition(seed, method):
    z = piecewise_scene(seed)
    zp, n, f = S.zprime(z)
    for thr in (2.0**11, 2.0**15, 2.0**18):
        got = S.split_rects(zp, method=method, threshold=thr)
        ref = S.split_rects(zp, method=method, threshold=thr, reference=True)
        assert got.tolist() == ref.tolist()
        covers_valid_exactly_once(got, z)


def test_split_rects_rejects_bad_arguments():
    zp = np.zeros((4, 4))
    with pytest.raises(ValueError, match="method: expected one of 'edge', 'separate', 'paper'"):
        S.split_rects(zp, method="laplace", threshold=1)
    with pytest.raises(ValueError, match="threshold: expected a number >= 0"):
        S.split_rects(zp, threshold=-1)
    with pytest.raises(ValueError, match="min_band: expected an integer >= 1"):
        S.split_rects(zp, method="paper", threshold=1, min_band=0)
    with pytest.raises(ValueError, match="zp: expected dtype of kind 'f'"):
        S.split_rects(np.zeros((4, 4), int), threshold=1)


def test_segment_options():
    z = plane_depth(CAM, (0.1, 0.05, 0.3))
    with pytest.raises(ValueError, match="give at most one"):
        S.segment(z, camera=CAM, threshold=1.0, max_error_px=1.0)
    with pytest.raises(ValueError, match="camera: needed"):
        S.segment(z)
    with pytest.raises(ValueError, match="max_error_px: expected a positive number"):
        S.segment(z, camera=CAM, max_error_px=0)
    with pytest.raises(ValueError, match="depth: no valid pixel"):
        S.segment(np.full((3, 3), np.nan), camera=Camera.from_fov(3, 3, hfov_deg=60))
    seg = S.segment(z, camera=CAM)
    assert seg.max_error_px == 0.5
    assert seg.baseline == pytest.approx(0.05 * np.median(z))
    assert seg.tolerance_inv_depth == pytest.approx(0.5 / (CAM.fx * seg.baseline))


def test_tolerance_from_error_px_worked_example():
    assert S.tolerance_from_error_px(0.5, focal_px=1000, baseline=0.1) == pytest.approx(0.005)
    # derivation: moving the camera by b along x shifts a pixel by f b / z; check with the Camera
    cam = Camera.from_fov(64, 48, hfov_deg=60)
    b, z1, z2 = 0.2, 3.0, 3.05
    moved = cam.translated([b, 0, 0])
    p1 = cam.unproject(np.array([10.0, 20.0]), z1)
    p2 = cam.unproject(np.array([10.0, 20.0]), z2)
    shift = abs(moved.project(p1)[0][0] - moved.project(p2)[0][0])
    assert shift == pytest.approx(cam.fx * b * abs(1 / z1 - 1 / z2), rel=1e-9)


def test_shallow_crease_is_cut_where_it_lies():
    """A crease too shallow to be a break edge: the failed fit is cut at the crease, not the middle."""
    u = np.arange(31, dtype=float)
    zp = (1000.0 * np.abs(u - 10))[None, :].repeat(3, 0)  # crease at column 10
    rects = S.split_rects(zp, method="edge", threshold=1e9, tolerance=1.0)  # no breaks at all
    assert rects.tolist() == [[0, 0, 10, 3], [10, 0, 31, 3]]
    assert S.split_rects(zp, method="edge", threshold=1e9, tolerance=1.0, reference=True).tolist() == rects.tolist()
    # smooth curvature has no distinct line: cut in the middle of the longer side
    zp2 = (np.arange(31.0) ** 2)[None, :].repeat(3, 0)
    assert K.crease_split(zp2, 0, 0, 31, 3, S.CREASE_PEAK) == (0, 15)


@pytest.mark.parametrize("seed", range(4))
def test_edge_split_fit_path_matches_reference(seed):
    """Break edges off (huge break threshold): every cut comes from failed fits."""
    zp, _, _ = S.zprime(piecewise_scene(seed))
    zp = np.where(np.isfinite(zp), zp, 0.0)  # all valid, so that no break is forced
    for tol in (2.0**12, 2.0**16):
        got = S.split_rects(zp, method="edge", threshold=1e12, tolerance=tol)
        ref = S.split_rects(zp, method="edge", threshold=1e12, tolerance=tol, reference=True)
        assert got.tolist() == ref.tolist()
        for u0, v0, u1, v1 in got:
            if (u1 - u0) * (v1 - v0) > 1:
                assert S._fit_max_residual_reference(zp, u0, v0, u1, v1) <= tol * (1 + 1e-12)


@pytest.mark.parametrize("method", ["paper", "separate", "edge"])
def test_segment_on_inverse_depth_equals_split_on_zprime(method):
    """segment() splits 1/z with thresholds divided by dz'/d(1/z); same rects as on z' itself."""
    cam = Camera.from_fov(29, 23, hfov_deg=60)
    for seed in range(3):
        z = piecewise_scene(seed)
        seg = S.segment(z, camera=cam, method=method, threshold=2.0**16)
        zp, n, f = S.zprime(z)
        assert (seg.near, seg.far) == (n, f)
        np.testing.assert_allclose(seg.zprime, zp, rtol=1e-12, atol=1e-5)
        assert seg.rects.tolist() == S.split_rects(zp, method=method, threshold=2.0**16).tolist()


# ------------------------------------------------------------------ fast kernels vs references


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_inv_depth_range_matches_numpy(dtype):
    """1/z, valid range and count (taken on integer bit patterns in the kernel) equal numpy's."""
    rng = np.random.default_rng(7)
    z = rng.uniform(0.5, 40.0, (13, 17))
    specials = [np.nan, np.inf, -np.inf, 0.0, -0.0, -3.0, 1e-40 if dtype == np.float32 else 1e-310]
    for i, s in enumerate(specials):
        z[i, (3 * i) % 17] = s
    z = z.astype(dtype)
    q, lo, hi, n = K.inv_depth_range(z)
    z64 = z.astype(np.float64)
    with np.errstate(divide="ignore", over="ignore"):
        valid = np.isfinite(z64) & (z64 > 0) & np.isfinite(1.0 / z64)  # 1/1e-310 overflows: no depth
        ref = np.where(valid, 1.0 / z64, np.nan)
    assert q.dtype == np.float64 and np.array_equal(q, ref, equal_nan=True)
    assert (lo, hi, n) == (z64[valid].min(), z64[valid].max(), valid.sum())
    assert type(lo) is float and type(n) is int
    q, lo, hi, n = K.inv_depth_range(np.full((2, 3), np.nan, dtype))
    assert np.isnan(q).all() and np.isnan(lo) and np.isnan(hi) and n == 0


@pytest.mark.parametrize("shape", [(70, 9), (33, 40), (64, 5), (2, 2), (1, 6), (6, 1)])
def test_edge_prefix_row_blocks_match_pairwise_kernel(shape):
    """The fused prefix kernel buffers vertical flags in blocks of rows; heights around and over
    the block size, with NaN and inf samples, give the prefix sums of the per-pair kernel."""
    rng = np.random.default_rng(shape[0] * 100 + shape[1])
    zp = rng.normal(0, 1, shape).cumsum(0).cumsum(1)
    zp[rng.random(shape) < 0.1] = np.nan
    zp[rng.random(shape) < 0.03] = np.inf
    for thr in (0.5, 3.0):
        hb, vb = K.edge_breaks(zp, thr)
        ch, rv = K.edge_prefix(zp, thr)
        assert ch.dtype == rv.dtype == np.int16
        assert np.array_equal(ch[1:], np.cumsum(hb, axis=0)) and not ch[0].any()
        assert np.array_equal(rv[1:], np.cumsum(vb, axis=1).T) and not rv[0].any()


def test_edge_prefix_wide_image_uses_int32():
    zp = np.sin(np.arange(32768.0) / 50.0)[None, :] * 100.0
    ch, rv = K.edge_prefix(zp, 1e-3)
    hb, _ = S.break_edges(zp, 1e-3)
    assert ch.dtype == np.int32 and rv.shape == (32769, 0)
    assert np.array_equal(ch[1], hb[0]) and hb.sum() > 0


@pytest.mark.parametrize("seed", range(3))
def test_rect_fit_within_and_planes_match_lstsq(seed):
    """The split's fit test (SIMD moments, row-wise residual count) decides like the lstsq
    reference at 1 +- 1e-6 of the reference's max residual, and the mesh's planes are lstsq's."""
    zp, _, _ = S.zprime(piecewise_scene(seed, h=31, w=37))
    zp = np.ascontiguousarray(np.where(np.isfinite(zp), zp, 0.0))
    rng = np.random.default_rng(seed)
    rects = []
    for _ in range(40):
        u0, v0 = rng.integers(0, 36), rng.integers(0, 30)
        rects.append((u0, v0, rng.integers(u0 + 1, 38), rng.integers(v0 + 1, 32)))
    for u0, v0, u1, v1 in rects:
        ref = S._fit_max_residual_reference(zp, u0, v0, u1, v1)
        if ref > 1e-3:
            assert K.rect_fit_within(zp, u0, v0, u1, v1, ref * (1 + 1e-6))
            assert not K.rect_fit_within(zp, u0, v0, u1, v1, ref * (1 - 1e-6))
        assert K.rect_fit_max_residual(zp, u0, v0, u1, v1, np.inf) == pytest.approx(ref, rel=1e-9, abs=1e-6)
    planes = K.fit_planes_inv_depth(zp, np.array(rects, np.int32))
    for (u0, v0, u1, v1), (a, b, c) in zip(rects, planes):
        v, u = np.mgrid[v0:v1, u0:u1].astype(float)
        got = a * u + b * v + c
        if u1 - u0 > 1 and v1 - v0 > 1:
            m = np.stack([u.ravel(), v.ravel(), np.ones(u.size)], 1)
            coef, *_ = np.linalg.lstsq(m, zp[v0:v1, u0:u1].ravel(), rcond=None)
            np.testing.assert_allclose(got.ravel(), m @ coef, rtol=0, atol=1e-6 * np.abs(zp).max())


@pytest.mark.parametrize("seed", range(3))
def test_crease_split_matches_reference(seed):
    """Vectorized column profile and sampled row profile: same cut as the plain-Python twin."""
    zp, _, _ = S.zprime(piecewise_scene(seed, h=70, w=90))
    zp = np.ascontiguousarray(np.where(np.isfinite(zp), zp, 0.0))
    rng = np.random.default_rng(seed)
    for _ in range(60):
        u0, v0 = rng.integers(0, 89), rng.integers(0, 69)
        u1, v1 = rng.integers(u0 + 1, 91), rng.integers(v0 + 1, 71)
        for peak in (1.5, S.CREASE_PEAK):
            got = K.crease_split(zp, u0, v0, u1, v1, peak)
            assert got == S._crease_split_reference(zp, u0, v0, u1, v1, peak)


def test_crease_split_with_one_scratch_row_for_a_whole_split():
    """The split passes one column-profile scratch row to every crease split it makes: nested and
    unrelated rects in any order get the cut of a fresh call and of the reference."""
    zp, _, _ = S.zprime(piecewise_scene(5, h=60, w=80))
    zp = np.ascontiguousarray(np.where(np.isfinite(zp), zp, 0.0))
    scratch = np.full(zp.shape[1], np.nan)  # whatever an earlier rect left there
    rng = np.random.default_rng(5)
    rects = [(0, 0, 80, 60), (0, 3, 80, 60), (0, 3, 80, 4), (2, 4, 79, 60), (10, 4, 70, 50), (5, 10, 70, 50)]
    for _ in range(40):  # random nests: cut a strip off one side of the last rect, or restart
        u0, v0, u1, v1 = rects[-1]
        side = rng.integers(0, 5)
        if side == 4 or min(u1 - u0, v1 - v0) < 4:
            u0, v0 = rng.integers(0, 40), rng.integers(0, 30)
            rects.append((u0, v0, rng.integers(u0 + 3, 81), rng.integers(v0 + 3, 61)))
            continue
        k = rng.integers(1, 3)
        rects.append(((u0 + k, v0, u1, v1), (u0, v0 + k, u1, v1), (u0, v0, u1 - k, v1), (u0, v0, u1, v1 - k))[side])
    for r in rects:
        got = K._crease_split_kernel(zp, *(np.int64(x) for x in r), S.CREASE_PEAK, scratch)
        assert got == K.crease_split(zp, *r, S.CREASE_PEAK) == S._crease_split_reference(zp, *r, S.CREASE_PEAK)


def test_segment_fast_path_equals_reference_on_rendered_room():
    """Default segment() (fused break-edge prefix sums, SIMD fits) on a ray-traced room with
    creases and occlusion steps: the same rects as the plain-Python reference split."""
    from ibr.synth import make_scene, render, scene_cameras

    cam = scene_cameras("room", width=160, height=120)[0]
    view = render(make_scene("room"), cam)
    seg = S.segment(view.depth, camera=cam)
    tol = seg.tolerance_inv_depth
    ref = S.split_rects(seg.inv_depth, method="edge", threshold=tol, reference=True)
    assert len(seg.rects) > 20
    assert seg.rects.tolist() == ref.tolist()
    covers_valid_exactly_once(seg.rects, view.depth)
    for u0, v0, u1, v1 in seg.rects:
        if (u1 - u0) * (v1 - v0) > 1:
            assert S._fit_max_residual_reference(seg.inv_depth, u0, v0, u1, v1) <= tol * (1 + 1e-9)
