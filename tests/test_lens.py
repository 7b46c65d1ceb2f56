"""Tests of ibr.lens (seed 001 section 7.3: radial distortion, inverse, pre-distortion)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ibr.stereo.lens import RadialDistortion, distortion_maps, fit_radial, predistort, predistort_stereo

LENSES = [RadialDistortion(0.22, 0.24, 1.5), RadialDistortion(-0.25, 0.05, 1.2), RadialDistortion(0.5, 0.0, 1.0)]


@pytest.mark.parametrize("lens", LENSES)
def test_newton_inverse_to_1e9(lens):
    r = np.linspace(0.0, lens.r_max, 200001)
    back = lens.undistort(lens.distort(r))
    assert np.max(np.abs(back - r)) < 1e-9
    # and forward of the inverse on a uniform r_d grid
    rd = np.linspace(0.0, lens.rd_max, 200001)
    assert np.max(np.abs(lens.distort(lens.undistort(rd)) - rd)) < 1e-9


@settings(max_examples=60, deadline=None)
@given(st.floats(-0.3, 0.6), st.floats(-0.05, 0.4), st.floats(0.0, 1.0))
def test_newton_inverse_property(c1, c2, t):
    try:
        lens = RadialDistortion(c1, c2, 1.0)
    except ValueError:
        return  # not monotone on [0, 1]: rejected by design (tested below)
    r = t * lens.r_max
    assert abs(float(lens.undistort(lens.distort(r))) - r) < 1e-9


def test_lut_and_approximation_errors():
    lens = LENSES[0]
    r = np.linspace(0, lens.r_max, 20001)
    rd = lens.distort(r)
    lut_err = np.abs(lens.undistort(rd, method="lut", lut_size=1024) - r)
    # linear interpolation: error <= h^2 / 8 * max|g''| with g = f^-1; about 1e-6 here
    assert 1e-9 < lut_err.max() < 1e-5
    approx_err = np.abs(lens.undistort(rd, method="approx") - r)
    # eq. 7.17 completed as r_d (1 - N/D): good near the center, useless at the rim
    assert approx_err[r <= 0.3].max() < 1e-5
    assert approx_err[r >= 1.0].max() > 0.1
    # the seed's printed ratio N/D alone is not the inverse (DESIGN.md section 3)
    r2 = rd**2
    c1, c2 = lens.c1, lens.c2
    ratio = (c1 * r2 + c2 * r2**2 + c1**2 * r2**2 + c2**2 * r2**4 + 2 * c1 * c2 * r2**3) / (1 + 4 * c1 * r2 + 6 * c2 * r2**2)
    assert np.median(np.abs(ratio - r)[r > 0.2]) > 0.1


def test_k1k2_form_matches_opencv():
    fx, s, k1, k2 = 300.0, 256.0, -0.2, 0.05
    lens = RadialDistortion.from_k1k2(k1, k2, focal_px=fx, scale_px=s)
    assert lens.to_k1k2(focal_px=fx, scale_px=s) == pytest.approx((k1, k2), rel=1e-14)
    rng = np.random.default_rng(0)
    pts = np.c_[rng.uniform(-0.4, 0.4, (100, 2)), np.ones(100)]
    k = np.array([[fx, 0, 255.5], [0, fx, 255.5], [0, 0, 1]])
    uv, _ = cv2.projectPoints(pts, np.zeros(3), np.zeros(3), k, np.array([k1, k2, 0, 0.0]))
    r_d = np.linalg.norm(uv[:, 0] - 255.5, axis=1) / s
    r_u = np.linalg.norm(pts[:, :2] * fx, axis=1) / s
    np.testing.assert_allclose(lens.distort(r_u), r_d, atol=1e-12)
    # and cv2.undistortPoints (iterative) agrees with the exact inverse to its own accuracy
    und = cv2.undistortPoints(uv, k, np.array([k1, k2, 0, 0.0]), P=k)[:, 0]
    np.testing.assert_allclose(lens.undistort(r_d), np.linalg.norm(und - 255.5, axis=1) / s, atol=1e-5)


def test_fit_radial_least_squares():
    true = RadialDistortion(0.21, 0.17, 1.0)
    rng = np.random.default_rng(1)
    r_u = rng.uniform(0.05, 1.0, 400)
    r_d = true.distort(r_u)
    fit = fit_radial(r_u, r_d)
    assert fit.c1 == pytest.approx(0.21, abs=1e-12) and fit.c2 == pytest.approx(0.17, abs=1e-12)
    noisy = fit_radial(r_u, r_d + rng.normal(0, 1e-4, r_u.shape))
    assert abs(noisy.c1 - 0.21) < 2e-3 and abs(noisy.c2 - 0.17) < 4e-3
    # point pairs (relative to the lens center) work too
    ang = rng.uniform(0, 2 * np.pi, 400)
    pu = np.c_[np.cos(ang), np.sin(ang)] * r_u[:, None]
    pd = np.c_[np.cos(ang), np.sin(ang)] * r_d[:, None]
    assert fit_radial(pu, pd).c1 == pytest.approx(0.21, abs=1e-12)
    with pytest.raises(ValueError, match="r_d: expected the shape"):
        fit_radial(r_u, r_d[:10])


def test_bad_lens_rejected(tmp_path, capsys):
    with pytest.raises(ValueError, match="not increasing"):
        RadialDistortion(-0.6, 0.0, 1.0)  # f'(1) = 1 - 1.8 < 0
    with pytest.raises(ValueError, match="method: expected one of"):
        LENSES[0].undistort(0.5, method="bisect")
    assert np.isnan(LENSES[0].undistort(LENSES[0].rd_max * 1.01))
    with pytest.raises(TypeError, match="lens: expected a RadialDistortion or a sequence of three"):
        predistort(np.zeros((4, 4, 3), np.uint8), [LENSES[0]] * 2)
    # r_max^2 overflowed (OverflowError traceback from `ibr distort --r-max 1e200`)
    with pytest.raises(ValueError, match="r_max: expected a number <= 1000"):
        RadialDistortion(0.1, 0.0, 1e200)
    import cli
    from samples import DATA_DIR

    assert cli.main(["distort", str(DATA_DIR / "room_a_color.png"), "--c1", "0.1", "--r-max", "1e200",
                     "-o", str(tmp_path / "x.png")]) == 1
    assert "r_max: expected a number <= 1000" in capsys.readouterr().err and not (tmp_path / "x.png").exists()


def test_distortion_maps_geometry_and_center():
    lens = RadialDistortion(0.3, 0.1, 1.5)
    w, h = 64, 48
    mx, my = distortion_maps(w, h, lens)
    # the lens center (31.5, 23.5) lies between pixels; pixel (40, 23.5 +- 0.5): compute exactly
    u, v = 40, 30
    dx, dy = (u - 31.5) / 32, (v - 23.5) / 32
    r = np.hypot(dx, dy)
    s = lens.distort(r) / r
    assert mx[v, u] == pytest.approx(31.5 + dx * s * 32, abs=1e-4)
    assert my[v, u] == pytest.approx(23.5 + dy * s * 32, abs=1e-4)
    # symmetric about the center: a half-pixel error in the center would break this
    np.testing.assert_allclose(mx[:, ::-1], w - 1 - mx, atol=1e-4)
    np.testing.assert_allclose(my[::-1], h - 1 - my, atol=1e-4)


def test_predistort_round_trip_and_chromatic():
    w = h = 96
    v, u = np.mgrid[0:h, 0:w].astype(np.float32)
    img = np.stack([0.5 + 0.4 * np.sin(u / 7), 0.5 + 0.4 * np.cos(v / 9), 0.5 + 0.2 * np.sin((u + v) / 11)], -1).astype(np.float32)
    lens = RadialDistortion(0.2, 0.05, 1.5)
    pre = predistort(img, lens)
    back = predistort(pre, lens, inverse=True)
    inner = np.hypot(u - 47.5, v - 47.5) < 30
    assert np.max(np.abs(back - img)[inner]) < 0.01  # two bilinear resamplings of a smooth image
    # pincushion compensation compresses the image toward the center (barrel look)
    mx, _ = distortion_maps(w, h, lens)
    assert mx[47, 90] > 90
    # chromatic aberration: each channel uses its own coefficients
    lenses = (RadialDistortion(0.22, 0.05, 1.5), lens, RadialDistortion(0.18, 0.05, 1.5))
    ca = predistort(img, lenses)
    np.testing.assert_array_equal(ca[..., 1], pre[..., 1])
    np.testing.assert_array_equal(ca[..., 0], predistort(img[..., 0], lenses[0]))
    assert not np.array_equal(ca[..., 0], predistort(img[..., 0], lens))


def test_predistort_stereo_per_eye_centers():
    img = np.zeros((40, 40), np.float32)
    img[20, 30] = 1.0  # impulse
    lens = RadialDistortion(0.0, 0.0, 2.0)  # identity lens: output equals input wherever defined
    l_out, r_out = predistort_stereo(img, img, lens, centers_px=((24.5, 19.5), (14.5, 19.5)))
    np.testing.assert_array_equal(l_out, img)
    np.testing.assert_array_equal(r_out, img)
    lens = RadialDistortion(0.3, 0.0, 2.0)
    l_out, r_out = predistort_stereo(img, img, lens, centers_px=((30.0, 20.0), (10.0, 20.0)))
    # the impulse sits on the left lens's center: it stays put there, but moves in the right eye
    assert l_out[20, 30] == pytest.approx(1.0)
    assert r_out[20, 30] < 0.5


def test_cli_distort(tmp_path):
    from cli import main
    from ibr.io import read_image, write_image

    rng = np.random.default_rng(2)
    img = rng.integers(0, 256, (32, 48, 3), dtype=np.uint8)
    write_image(tmp_path / "in.png", img)
    assert main(["distort", str(tmp_path / "in.png"), "--c1", "0.2", "--c2", "0.05", "-o", str(tmp_path / "o.png")]) == 0
    np.testing.assert_array_equal(read_image(tmp_path / "o.png"), predistort(img, RadialDistortion(0.2, 0.05, 1.5)))
    assert main(["distort", str(tmp_path / "o.png"), "--c1", "0.2", "--c2", "0.05", "--inverse",
                 "-o", str(tmp_path / "i.png")]) == 0
    assert main(["distort", str(tmp_path / "in.png"), "--c1", "0.2", "--sbs", "--centers", "12", "15.5", "11", "15.5",
                 "-o", str(tmp_path / "s.png")]) == 0
    left, _ = predistort_stereo(img[:, :24], img[:, 24:], RadialDistortion(0.2, 0.0, 1.5),
                                centers_px=((12, 15.5), (11, 15.5)))
    np.testing.assert_array_equal(read_image(tmp_path / "s.png")[:, :24], left)
    # a non-invertible lens, the input as output, a missing input
    assert main(["distort", str(tmp_path / "in.png"), "--c1", "-0.9", "-o", str(tmp_path / "x.png")]) == 1
    assert main(["distort", str(tmp_path / "in.png"), "--c1", "0.1", "-o", str(tmp_path / "in.png")]) == 1
    assert main(["distort", str(tmp_path / "nope.png"), "--c1", "0.1", "-o", str(tmp_path / "x.png")]) == 1
    assert main(["distort", str(tmp_path / "in.png"), "-o", str(tmp_path / "x.png")]) == 2  # --c1 missing
    assert not (tmp_path / "x.png").exists()
    np.testing.assert_array_equal(read_image(tmp_path / "in.png"), img)
