"""Depth encodings: exact round trips, invalid values, seed 003's wrong inverse, quantization.

References are analytic: the window/z-buffer formula of seed 002 eq. 2 (z' / 2^24), the
Middlebury disparity relation, and the depth of each fixed-point code computed in float64 here.
"""

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from ibr.base import depth as D
from ibr.base.camera import Camera

HYP = settings(max_examples=80, deadline=None)
finite = dict(allow_nan=False, allow_infinity=False)

near_far = st.tuples(st.floats(0.01, 10, **finite), st.floats(1.5, 1e4, **finite)).map(
    lambda nf: (nf[0], nf[0] * nf[1])
)


def z_of_code(q, n, f, bits):
    """Planar depth of fixed-point code q (float64 reference): w = q / (2^bits - 1)."""
    w = np.asarray(q, dtype=np.float64) / (2**bits - 1)
    return n * f / (f - w * (f - n))


def seed003_inverse(zp, n, f):
    """Seed 003 as printed: Z = Z' (zFar - zNear) / zFar + zNear (wrong, DESIGN.md section 3)."""
    return zp * (f - n) / f + n


# ----------------------------------------------------------------------------- round trips
@HYP
@given(near_far, st.lists(st.floats(0, 1, **finite), min_size=1, max_size=20))
def test_window_reversed_zprime_round_trips(nf, fractions):
    n, f = nf
    z = n + np.asarray(fractions) * (f - n)  # inside [near, far]
    w = D.window_from_z(z, near=n, far=f)
    assert np.all((w >= -1e-12) & (w <= 1 + 1e-12))
    np.testing.assert_allclose(D.z_from_window(np.clip(w, 0, 1), near=n, far=f), z, rtol=2e-6)
    rev = D.reversed_from_z(z, near=n, far=f)
    np.testing.assert_allclose(rev, 1 - w, atol=1e-15)
    np.testing.assert_allclose(D.z_from_reversed(np.clip(rev, 0, 1), near=n, far=f), z, rtol=2e-6)
    zp = D.zprime_from_z(z, near=n, far=f)
    np.testing.assert_allclose(zp, D.ZPRIME_SCALE * f / (f - n) * (1 - n / z), rtol=1e-12)  # seed 002 eq. 2
    np.testing.assert_allclose(D.z_from_zprime(np.clip(zp, 0, D.ZPRIME_SCALE), near=n, far=f), z, rtol=2e-6)


@HYP
@given(st.floats(0.01, 10, **finite), st.lists(st.floats(1, 1e6, **finite), min_size=1, max_size=20))
def test_infinite_far_round_trips(n, ratios):
    z = n * np.asarray(ratios)
    w = D.window_from_z(z, near=n, far=np.inf)
    np.testing.assert_allclose(w, 1 - n / z, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(D.z_from_window(w, near=n, far=np.inf), z, rtol=2e-6)
    rev = D.reversed_from_z(z, near=n, far=np.inf)
    np.testing.assert_allclose(rev, n / z, rtol=1e-12)
    np.testing.assert_allclose(D.z_from_reversed(rev, near=n, far=np.inf), z, rtol=2e-6)


@HYP
@given(st.floats(0.01, 1, **finite), st.floats(10, 2000, **finite), st.floats(-20, 60, **finite),
       st.lists(st.floats(0.1, 500, **finite), min_size=1, max_size=20))
def test_disparity_round_trip(baseline, focal, doffs, zs):
    z = np.asarray(zs)
    d = D.disparity_from_z(z, baseline=baseline, focal_px=focal, doffs=doffs)
    np.testing.assert_allclose(d, baseline * focal / z - doffs, rtol=1e-6, atol=1e-4)
    back = D.z_from_disparity(d, baseline=baseline, focal_px=focal, doffs=doffs)
    ok = np.isfinite(back)  # d + doffs rounded to float32 can only fail for huge z
    assert ok.all()
    # float32 d: relative error of z is that of (d + doffs), at most eps * (|d| + |doffs|) / (d + doffs)
    tol = 2e-7 * (np.abs(d) + abs(doffs)) / (baseline * focal / z) + 1e-7
    assert np.all(np.abs(back - z) / z <= tol)


def test_disparity_worked_example():
    z = D.z_from_disparity(np.array([100.0]), baseline=193.001, focal_px=994.978, doffs=31.086)
    assert z[0] == pytest.approx(193.001 * 994.978 / 131.086, rel=1e-6)  # 1464.93 mm


@HYP
@given(st.integers(4, 64), st.integers(4, 64), st.floats(20, 500, **finite), st.floats(0.1, 50, **finite))
def test_range_round_trip(w, h, f, zval):
    cam = Camera(f, f * 1.1, w * 0.3, h * 0.6, w, h)
    z = np.full((h, w), zval)
    r = D.range_from_z(z, cam)
    u, v = cam.pixel_grid()
    expected = zval * np.sqrt(1 + ((u - cam.cx) / cam.fx) ** 2 + ((v - cam.cy) / cam.fy) ** 2)
    np.testing.assert_allclose(r, expected, rtol=1e-6)
    np.testing.assert_allclose(D.z_from_range(r, cam), z, rtol=1e-6)


def test_range_is_distance_to_unprojected_point():
    cam = Camera(60.0, 60.0, 15.5, 11.5, 32, 24)
    rng = np.random.default_rng(1)
    z = rng.uniform(1, 5, (24, 32))
    u, v = cam.pixel_grid()
    pts = cam.unproject(np.stack([u, v], -1), z, frame="cam")
    np.testing.assert_allclose(D.range_from_z(z, cam), np.linalg.norm(pts, axis=-1), rtol=1e-6)
    with pytest.raises(ValueError, match="does not match camera size 24x32"):
        D.range_from_z(z[:, :10], cam)


@HYP
@given(near_far, st.sampled_from([16, 24]), st.lists(st.floats(0, 1, **finite), min_size=1, max_size=30))
@example(nf=(1.0, 8878.0), bits=16, fractions=[0.9375])  # rounds to the far code, 563 m away (half a z step: 530 m)
def test_fixed_round_trip_within_half_a_code(nf, bits, fractions):
    n, f = nf
    z = n + np.asarray(fractions) * (f - n) * 0.999
    q = D.fixed_from_z(z, near=n, far=f, bits=bits)
    assert q.dtype == (np.uint16 if bits == 16 else np.uint32)
    back = D.z_from_fixed(q, near=n, far=f, bits=bits, far_is_empty=False).astype(np.float64)
    np.testing.assert_allclose(back, z_of_code(q, n, f, bits), rtol=1e-6)  # float32 output
    # Rounding to the nearest code in window space: z lies between the depths of the half codes
    # around q. (Not within half a z step: near the far plane one code spans hundreds of metres
    # and the window-space midpoint is far from the z-space midpoint.)
    qf, top = q.astype(np.float64), 2**bits - 1
    lo, hi = z_of_code(np.maximum(qf - 0.5, 0), n, f, bits), z_of_code(np.minimum(qf + 0.5, top), n, f, bits)
    assert np.all((z >= lo * (1 - 1e-9)) & (z <= hi * (1 + 1e-9)))
    # and the result is within one whole code step of z
    step = D.zbuffer_step(z_of_code(np.maximum(qf - 1, 0), n, f, bits), near=n, far=f, bits=bits)
    assert np.all(np.abs(back - z) <= step * (1 + 1e-6) + 4e-7 * z)  # + float32 rounding of the output


# ----------------------------------------------------------------------------- seed 003 error
def test_seed003_printed_inverse_is_wrong_and_ours_is_exact():
    n, f = 0.1, 100.0
    z = np.array([0.1, 0.5, 2.0, 10.0, 50.0, 100.0])  # (it also happens to be right at z = 1 m)
    zp = (z - n) / z * f / (f - n)  # seed 003's forward mapping, as printed
    np.testing.assert_allclose(zp, D.window_from_z(z, near=n, far=f), rtol=1e-12)
    wrong = seed003_inverse(zp, n, f)
    # Agrees only at the near plane; 10 m comes back as 1.09 m and the far plane as 1.099 m.
    assert wrong[3] == pytest.approx(1.0891, abs=1e-3)
    assert wrong[-1] == pytest.approx(1.099, abs=1e-9)
    assert np.min(np.abs(wrong[1:] - z[1:]) / z[1:]) > 0.4
    assert wrong[0] == pytest.approx(z[0], rel=1e-12)
    np.testing.assert_allclose(D.z_from_window(zp, near=n, far=f), z, rtol=1e-6)
    np.testing.assert_allclose(n * f / (f - zp * (f - n)), z, rtol=1e-12)  # DESIGN.md's exact inverse


# ----------------------------------------------------------------------------- invalid values
def test_invalid_depth_becomes_nan_with_mask():
    z = np.array([1.0, 0.0, -2.0, np.nan, np.inf, -np.inf, 150.0, 0.05])
    out, valid = D.sanitize_depth(z, near=0.1, far=100.0)
    assert out.dtype == np.float32
    np.testing.assert_array_equal(valid, [True, False, False, False, False, False, False, False])
    assert np.isnan(out[~valid]).all() and out[0] == 1.0
    np.testing.assert_array_equal(D.valid_mask(z), [True, False, False, False, False, False, True, True])
    for enc in (D.window_from_z, D.reversed_from_z, D.zprime_from_z):
        assert np.isnan(enc(z, near=0.1, far=100.0)[1:6]).all()
    assert np.isnan(D.disparity_from_z(z, baseline=1.0, focal_px=10.0)[1:6]).all()


def test_invalid_encoded_values_become_nan():
    n, f = 0.5, 20.0
    w = np.array([-0.1, 1.5, np.nan, np.inf, 0.0, 1.0])
    z = D.z_from_window(w, near=n, far=f)
    assert np.isnan(z[:4]).all()
    np.testing.assert_allclose(z[4:], [n, f], rtol=1e-6)
    assert np.isnan(D.z_from_window([1.0], near=n, far=np.inf)).all()  # cleared infinite far
    assert np.isnan(D.z_from_reversed([0.0, -0.2, 1.2], near=n, far=np.inf)).all()
    # Disparity with d + doffs <= 0 has no depth (at or beyond infinity).
    zd = D.z_from_disparity([-31.086, -40.0, np.nan, np.inf, 10.0], baseline=0.19, focal_px=995.0, doffs=31.086)
    assert np.isnan(zd[:4]).all() and np.isfinite(zd[4])
    assert np.isnan(D.z_from_range([[-1.0, 0.0]], Camera(10.0, 10.0, 0.5, 0.0, 2, 1))).all()


def test_fixed_codes_clamp_clear_and_reject():
    n, f = 1.0, 1000.0
    q = D.fixed_from_z(np.array([0.5, 2000.0, np.nan, -1.0, 1.0]), near=n, far=f, bits=16)
    np.testing.assert_array_equal(q, [0, 65535, 65535, 65535, 0])  # clamped; invalid = cleared
    z = D.z_from_fixed(q, near=n, far=f, bits=16)
    assert np.isnan(z[1:4]).all() and z[0] == pytest.approx(1.0)
    assert D.z_from_fixed(q, near=n, far=f, bits=16, far_is_empty=False)[1] == pytest.approx(1000.0)
    with pytest.raises(ValueError, match=r"q: codes must lie in \[0, 65535\]"):
        D.z_from_fixed(np.array([70000]), near=n, far=f, bits=16)
    with pytest.raises(ValueError, match="bits: expected 16, 24 or 32, got 12"):
        D.fixed_from_z([1.0], near=n, far=f, bits=12)
    with pytest.raises(ValueError, match="fixed-point z-buffer needs a finite far"):
        D.fixed_from_z([1.0], near=n, far=np.inf)
    with pytest.raises(ValueError, match="q: expected dtype of kind 'iu'"):
        D.z_from_fixed(np.array([0.5]), near=n, far=f)


@pytest.mark.parametrize("near,far,match", [(0.0, 1.0, "near: expected a positive"), (2.0, 1.0, "far: expected far > near"),
                                            (1.0, np.nan, "far: expected a finite"), (-1.0, 5.0, "near: expected a positive")])
def test_bad_near_far(near, far, match):
    with pytest.raises(ValueError, match=match):
        D.window_from_z([1.0], near=near, far=far)


def test_bad_disparity_parameters():
    with pytest.raises(ValueError, match="baseline: expected a positive"):
        D.z_from_disparity([1.0], baseline=0.0, focal_px=1.0)
    with pytest.raises(TypeError, match="doffs: expected a real number"):
        D.z_from_disparity([1.0], baseline=1.0, focal_px=1.0, doffs="x")


# ----------------------------------------------------------------------------- quantization
@pytest.mark.parametrize("bits", [16, 24])
@pytest.mark.parametrize("near,far", [(0.1, 100.0), (1.0, 1000.0)])
def test_zbuffer_step_is_the_difference_of_consecutive_codes(bits, near, far):
    top = 2**bits - 1
    q = np.unique(np.linspace(0, top - 1, 2001).astype(np.int64))
    z0 = z_of_code(q, near, far, bits)
    exact = z_of_code(q + 1, near, far, bits) - z0
    step = D.zbuffer_step(z0, near=near, far=far, bits=bits)
    np.testing.assert_allclose(step, exact, rtol=1e-6)
    # First-order formula of the module docstring, valid where steps are small against z.
    first_order = z0**2 * (far - near) / (near * far * top)
    small = exact < 1e-3 * z0
    np.testing.assert_allclose(first_order[small], exact[small], rtol=2e-3)
    # The last code has no next code below the far plane.
    assert np.isnan(D.zbuffer_step(np.array([far]), near=near, far=far, bits=bits))[0]


def test_far_plane_precision_of_16_and_24_bit_buffers():
    n, f = 0.1, 100.0
    z = np.linspace(80.0, 98.0, 20001)  # within one 16-bit step (~1.5 m) of far there is no next code
    err16 = np.abs(D.z_from_fixed(D.fixed_from_z(z, near=n, far=f, bits=16), near=n, far=f, bits=16) - z)
    err24 = np.abs(D.z_from_fixed(D.fixed_from_z(z, near=n, far=f, bits=24), near=n, far=f, bits=24) - z)
    step16 = D.zbuffer_step(z, near=n, far=f, bits=16)
    # 16 bits near the far plane: steps of ~1 to 1.5 m for a 100 m far plane, and the measured
    # round-trip error really reaches half a step (so the step function is not a loose bound).
    assert 0.9 < step16.min() and step16.max() < 1.6
    assert np.max(err16 / step16) == pytest.approx(0.5, abs=0.01)
    assert np.max(err16) > 0.45
    # 24 bits: 256x finer (~4-6 mm); float32 output adds at most ~4e-6 m at 100 m.
    step24 = D.zbuffer_step(z, near=n, far=f, bits=24)
    ratio = step16 / step24  # (2^24 - 1) / (2^16 - 1) = 256.004 to first order; curvature adds ~1%
    assert 256.0 < ratio.min() and ratio.max() < 262.0
    assert np.max(err24 / step24) < 0.5 + 0.01
    assert np.max(err24) < 3.1e-3
    # Linear 16-bit storage (z codes with scale) would have a constant 1.5 mm step instead:
    assert f / 65535 < step16.min() / 500


def test_zbuffer_step_with_an_infinite_far_plane():
    """far = inf is accepted everywhere; the step was inf / inf = NaN. With z = n / (1 - w) the
    step of one code is z(w + 1/(2^b - 1)) - z(w): for 24 bits and n = 0.1 about
    z^2 / (n (2^24 - 1)), 5.96e-7 at z = 1."""
    n, bits = 0.1, 24
    z = np.array([1.0, 10.0])
    step = D.zbuffer_step(z, near=n, far=np.inf, bits=bits)
    w = 1 - n / z
    exact = n / (1 - (w + 1 / (2**bits - 1))) - z
    np.testing.assert_allclose(step, exact, rtol=1e-6)
    np.testing.assert_allclose(step, z**2 / (n * (2**bits - 1)), rtol=1e-4)
