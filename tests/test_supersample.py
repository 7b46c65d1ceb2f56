"""Supersampled rendering at depth edges (``supersample=k``, :mod:`ibr.render.supersample`)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage

import cli
from ibr.base.camera import Camera
from ibr.io import load_view, read_image
from ibr.render.supersample import check_supersample, downsample_rendering, edge_pixels, supersampled_camera
from ibr.render.view_synthesis import interpolate, warp
from samples import DATA_DIR

TS = (0.25, 0.5, 0.75)


def psnr(a, b, mask=None) -> float:
    d = (np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2
    d = d if mask is None else d[mask]
    return float(10 * np.log10(255.0**2 / d.mean()))


def edge_band(depth, rel=0.02):
    """Pixels within 1 px (8-connected) of a depth step of more than ``rel`` (benchmarks' band)."""
    z = np.asarray(depth, np.float64)
    e = np.zeros(z.shape, bool)
    with np.errstate(invalid="ignore"):
        dh = (np.abs(z[:, 1:] - z[:, :-1]) > rel * np.fmin(z[:, 1:], z[:, :-1])) | (np.isnan(z[:, 1:]) != np.isnan(z[:, :-1]))
        dv = (np.abs(z[1:] - z[:-1]) > rel * np.fmin(z[1:], z[:-1])) | (np.isnan(z[1:]) != np.isnan(z[:-1]))
    e[:, 1:] |= dh
    e[:, :-1] |= dh
    e[1:] |= dv
    e[:-1] |= dv
    return ndimage.binary_dilation(e, np.ones((3, 3), bool))


@pytest.fixture(scope="module")
def clutter():
    return (load_view(DATA_DIR / "clutter_a.json"), load_view(DATA_DIR / "clutter_b.json"),
            [load_view(DATA_DIR / f"clutter_t{round(t * 100):03d}.json") for t in TS])


def test_centre_subsample_is_the_pixel_centre_ray():
    cam = Camera(100.0, 90.0, 31.5, 23.25, 64, 48)
    big = supersampled_camera(cam, 3)
    assert big.shape == (144, 192)
    # the ray through pixel (u, v) of cam is the ray through subsample (3u + 1, 3v + 1) of big
    for u, v in ((0, 0), (17, 5), (63, 47)):
        assert np.allclose(((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy),
                           ((3 * u + 1 - big.cx) / big.fx, (3 * v + 1 - big.cy) / big.fy), atol=1e-12)
    assert supersampled_camera(cam, 1) is cam


@pytest.mark.parametrize("bad", [2, 0, 7, -3, True, 3.0, "3", None])
def test_bad_factors_are_refused_by_name(bad):
    with pytest.raises(ValueError, match="supersample"):
        check_supersample(bad)


def test_edge_pixels_and_box_filter_on_an_analytic_edge():
    """A vertical edge two thirds of the way through pixel column 1 (k = 3): the near surface
    (z = 2, colour 240) covers subsample columns 0..4, the far one (z = 5, colour 30) the rest.
    Column 1 is the only edge pixel and gets exactly 2/3 * 240 + 1/3 * 30 = 170; the others
    keep their centre subsample; depth, holes and filled are the centre subsample's."""
    k, h, w = 3, 2, 3
    depth = np.full((h * k, w * k), 5.0, np.float32)
    depth[:, :5] = 2.0
    color = np.where(depth[..., None] < 3, 240, 30).astype(np.uint8).repeat(3, axis=2)
    holes = np.zeros(depth.shape, bool)
    edge = edge_pixels(depth, ~holes, k, 0.02)
    assert edge.tolist() == [[False, True, False]] * h
    c, z, ho, fi = downsample_rendering(color, depth, holes, holes, k)
    assert c[..., 0].tolist() == [[240, 170, 30]] * h
    assert z.tolist() == [[2.0, 2.0, 5.0]] * h and not ho.any() and not fi.any()
    # an unfilled hole subsample: not an edge pixel (nothing to average it with), centre kept
    holes[0, 3] = True
    depth[0, 3] = np.nan
    assert not edge_pixels(depth, ~holes, k, 0.02)[0, 1]
    # a depth difference under the tolerance is one surface
    flat = np.full((k, k), 2.0, np.float32)
    flat[0, 0] = 2.02
    assert not edge_pixels(flat, np.ones((k, k), bool), k, 0.02).any()
    assert edge_pixels(flat, np.ones((k, k), bool), k, 0.005).all()


def test_interpolate_supersampled_is_sharper_at_edges_and_the_same_elsewhere(clutter):
    """Clutter, fill "none", t = .25/.5/.75: the edge band (covered pixels) gains over a dB and a
    half (measured 28.16 -> 29.95 dB); holes and depth are exactly the plain render's, and so is
    the colour of every pixel that is not an edge pixel (about 98.5 % of them)."""
    a, b, truths = clutter
    cams = [g.camera for g in truths]
    plain = interpolate(a, b, cams, fill="none")
    fine = interpolate(a, b, cams, fill="none", supersample=3)
    band_plain = [psnr(r.color, g.color, edge_band(g.depth) & ~r.holes) for r, g in zip(plain, truths)]
    band_fine = [psnr(r.color, g.color, edge_band(g.depth) & ~r.holes) for r, g in zip(fine, truths)]
    assert np.mean(band_fine) > np.mean(band_plain) + 1.2, (band_plain, band_fine)
    for p, f in zip(plain, fine):
        assert f.camera is p.camera or f.camera.allclose(p.camera)
        assert np.array_equal(f.holes, p.holes) and np.array_equal(f.filled, p.filled)
        assert np.array_equal(f.depth, p.depth, equal_nan=True)
        changed = np.any(f.color != p.color, axis=-1)
        assert 0.005 < changed.mean() < 0.03
        # the changed pixels are at depth edges of the render (a few more where subsamples
        # straddle a crease steeper than the band's 2 % between pixel centres: 1, 10, 3 here)
        assert (changed & ~edge_band(p.depth)).sum() <= 0.01 * changed.sum()


def test_motorcycle_left_to_right_gains_on_real_photographs():
    """The real Middlebury pair: covered pixels against the real right image, 27.55 -> 27.91 dB
    (measured), same holes."""
    from ibr.io.middlebury import motorcycle_views

    left, right = motorcycle_views()
    plain = warp(left, right.camera, fill="none")
    fine = warp(left, right.camera, fill="none", supersample=3)
    assert np.array_equal(plain.holes, fine.holes)
    assert psnr(fine.color, right.color, ~fine.holes) > psnr(plain.color, right.color, ~plain.holes) + 0.2


def test_cli_interpolate_and_warp_take_supersample(tmp_path, capsys):
    truth = load_view(DATA_DIR / "clutter_t050.json").color
    scores = {}
    for k in (1, 3):
        out = tmp_path / f"k{k}"
        assert cli.main(["interpolate", "--t", "0.5", "--out", str(out), "--supersample", str(k)]) == 0
        scores[k] = psnr(read_image(out / "frame_000_t0.500.png"), truth)
    assert scores[3] > scores[1] + 0.2, scores  # measured 36.60 -> 36.92 dB over the whole frame
    assert cli.main(["interpolate", "--supersample", "2"]) == 2
    assert "supersample" in capsys.readouterr().err
    out = tmp_path / "w.png"
    assert cli.main(["warp", str(DATA_DIR / "clutter_a.json"), "--to", str(DATA_DIR / "clutter_t050.json"),
                     "-o", str(out), "--supersample", "3"]) == 0
    assert read_image(out).shape == truth.shape
