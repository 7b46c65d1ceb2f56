"""Supersampled rendering at depth edges (``supersample=k``, :mod:`ibr.render.supersample`)."""

from __future__ import annotations

import re
import sys
from pathlib import Path

import numpy as np
import pytest

import cli
from ibr.base.camera import Camera
from ibr.base.view import View
from ibr.io import load_view, read_image
from ibr.render.supersample import check_supersample, downsample_rendering, supersampled_camera
from ibr.render.view_synthesis import interpolate, warp
from samples import DATA_DIR

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the checkout, for its benchmarks
from benchmarks.bench_edges import edge_band  # noqa: E402  (issue 11's band: +-1 px of depth edges)

TS = (0.25, 0.5, 0.75)


def psnr(a, b, mask=None) -> float:
    d = (np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2
    d = d if mask is None else d[mask]
    return float(10 * np.log10(255.0**2 / d.mean()))


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


@pytest.mark.parametrize("bad", [2, 0, 7, -3, True, 3.0, "3", None, np.int64(2)])
def test_bad_factors_are_refused_by_name(bad, clutter):
    """The library refuses what ``--supersample`` refuses, naming the argument: the check, and
    warp, interpolate and upconvert before any work."""
    from ibr.sequence.frame_rate import upconvert

    a, b, truths = clutter
    with pytest.raises(ValueError, match="supersample"):
        check_supersample(bad)
    with pytest.raises(ValueError, match="supersample"):
        warp(a, truths[0].camera, supersample=bad)
    with pytest.raises(ValueError, match="supersample"):
        interpolate(a, b, 0.5, supersample=bad)
    with pytest.raises(ValueError, match="supersample"):
        next(upconvert([a, b], 2, supersample=bad))


def test_downsampling_copies_and_checks_shapes():
    """The results never share memory with the subsample arrays (a 1 x 1 target included:
    the previous-frame fill keeps those), and shapes that are not multiples of k are refused."""
    k = 3
    color = np.zeros((k, k, 3), np.uint8)
    color[:, :2] = 240
    depth = np.where(np.arange(k) < 2, 2.0, 5.0)[None].repeat(k, 0).astype(np.float32)
    holes = np.zeros((k, k), bool)
    before = color.copy()
    c, z, ho, fi = downsample_rendering(color, depth, holes, holes, k)
    assert c[0, 0, 0] == 160 and np.array_equal(color, before)
    assert not any(np.shares_memory(x, y) for x, y in ((c, color), (z, depth), (ho, holes), (fi, holes)))
    with pytest.raises(ValueError, match="multiples of k"):
        downsample_rendering(np.zeros((4, 6, 3)), np.zeros((4, 6)), np.zeros((4, 6), bool), np.zeros((4, 6), bool), 3)
    with pytest.raises(ValueError, match="depth_k"):
        downsample_rendering(color, depth[:2], holes, holes, k)


@pytest.mark.parametrize("dtype", ["gray", "gray3d", "uint16", "float32", "rgba"])
def test_every_colour_layout_and_the_forward_method_and_previous_fill(dtype, clutter):
    """Supersampled frames keep the source's colour dtype and layout, for the mesh and the
    forward method and with the previous-frame fill; the bright/dark edge band still gains."""
    a, b, truths = clutter

    def convert(v):
        c = v.color
        if dtype == "gray":
            c = c.mean(axis=2).astype(np.uint8)
        elif dtype == "gray3d":  # (H, W, 1): OpenCV's resize drops that axis
            c = c.mean(axis=2, keepdims=True).astype(np.uint8)
        elif dtype == "uint16":
            c = c.astype(np.uint16) * 257
        elif dtype == "float32":
            c = c.astype(np.float32) / 255
        else:
            c = np.concatenate([c, np.full(c.shape[:2] + (1,), 255, np.uint8)], axis=2)
        return View(c, v.depth, v.camera, v.name)

    va, vb = convert(a), convert(b)
    for method in ("mesh", "forward"):
        frames = interpolate(va, vb, [0.25, 0.5], method=method, fill="previous", supersample=3)
        for r in frames:
            assert r.color.shape == va.color.shape and r.color.dtype == va.color.dtype
            assert r.depth.shape == va.depth.shape and not r.holes[~r.filled].any()


def test_the_upsampled_source_follows_a_quantization_set_later():
    """The cached upsampled source takes the view's depth quantization as it is at each call."""
    from ibr.base.depth import DepthQuantization, quantization_of, set_quantization
    from ibr.render.sources import _source

    v = _edge_view(6.3)
    warp(v, v.camera, supersample=3)
    assert quantization_of(_source(v).upsampled(3)) is None
    q = DepthQuantization.codes(0.01)
    set_quantization(v, q)
    assert quantization_of(_source(v).upsampled(3)) == q


def test_quantization_steps_are_no_silhouettes_for_the_upsampler():
    """A smooth ramp stored in coarse integer codes steps by one code (more than 2 % of z here)
    between neighbours: with its quantization given those steps are not depth edges, a real
    step of many codes still is."""
    from ibr.base.depth import DepthQuantization
    from ibr.render.upsample import depth_edge_pixels

    z = np.repeat(np.round(np.linspace(1.0, 1.3, 40), 1)[None], 4, axis=0)  # codes of 0.1
    z[:, 30:] = 3.0
    q = DepthQuantization.codes(0.1)
    plain, quantized = depth_edge_pixels(z), depth_edge_pixels(z, quantization=q)
    assert plain[:, :29].any() and not quantized[:, :29].any()
    assert quantized[:, 29:31].all()


def test_box_filter_on_an_analytic_edge():
    """A vertical edge two thirds of the way through pixel column 1 (k = 3): the near surface
    (z = 2, colour 240) covers subsample columns 0..4, the far one (z = 5, colour 30) the rest,
    and a ramp runs down the far side. Every pixel is its subsamples' mean: column 1 exactly
    2/3 * 240 + 1/3 * 30 = 170, column 2 its ramp's mean (not its centre); depth, holes and
    filled are the centre subsample's; a pixel with an unfilled hole subsample keeps its centre."""
    k, h, w = 3, 2, 3
    depth = np.full((h * k, w * k), 5.0, np.float32)
    depth[:, :5] = 2.0
    color = np.where(depth[..., None] < 3, 240, 30).astype(np.uint8).repeat(3, axis=2)
    color[:, 6:] += np.array([0, 3, 12], np.uint8)[:, None]  # columns 6, 7, 8 of pixel 2: 30, 33, 42
    holes = np.zeros(depth.shape, bool)
    c, z, ho, fi = downsample_rendering(color, depth, holes, holes, k)
    assert c[..., 0].tolist() == [[240, 170, 35]] * h
    assert z.tolist() == [[2.0, 2.0, 5.0]] * h and not ho.any() and not fi.any()
    holes[0, 3] = True  # pixel (0, 1): nothing to average this subsample with
    c, *_ = downsample_rendering(color, depth, holes, np.zeros_like(holes), k)
    assert c[0, :, 0].tolist() == [240, 240, 35]
    c, *_ = downsample_rendering(color, depth, holes, holes, k)  # ... unless filled
    assert c[0, :, 0].tolist() == [240, 170, 35]


@pytest.mark.parametrize("dtype, k", [(np.uint8, 3), (np.uint16, 3), (np.uint16, 5), (np.float32, 3), (np.int32, 3)])
def test_the_box_is_the_rounded_block_mean_in_every_dtype(dtype, k):
    """Random colour of each dtype: every pixel is its k x k subsamples' mean (float64, rounded
    for integers), whether OpenCV's area resampling reads the colour directly (8 and 16 bit)
    or as float32."""
    rng = np.random.default_rng(k)
    top = 250 if dtype is np.uint8 else 60000
    color = rng.integers(0, top, (4 * k, 5 * k, 3)).astype(dtype)
    depth = np.ones((4 * k, 5 * k), np.float32)
    holes = np.zeros(depth.shape, bool)
    c, *_ = downsample_rendering(color, depth, holes, holes, k)
    mean = color.astype(np.float64).reshape(4, k, 5, k, 3).mean((1, 3))
    expected = mean if dtype is np.float32 else np.rint(mean)
    assert c.dtype == dtype
    np.testing.assert_allclose(c.astype(np.float64), expected, atol=1e-3 if dtype is np.float32 else 0)


def test_interpolate_supersampled_is_sharper_at_edges(clutter):
    """Clutter, fill "none", t = .25/.5/.75: the edge band (covered pixels) gains well over two
    dB and the whole covered frame over one and a half (measured 28.16 -> 31.02 and 37.07 ->
    39.29 dB); the geometry is the plain render's (holes within 0.05 % of the frame, depth
    within 2 % at 99 % of the pixels both cover)."""
    a, b, truths = clutter
    cams = [g.camera for g in truths]
    plain = interpolate(a, b, cams, fill="none")
    fine = interpolate(a, b, cams, fill="none", supersample=3)
    band_plain = [psnr(r.color, g.color, edge_band(g.depth) & ~r.holes) for r, g in zip(plain, truths)]
    band_fine = [psnr(r.color, g.color, edge_band(g.depth) & ~r.holes) for r, g in zip(fine, truths)]
    assert np.mean(band_fine) > np.mean(band_plain) + 2.0, (band_plain, band_fine)
    all_plain = [psnr(r.color, g.color, ~r.holes) for r, g in zip(plain, truths)]
    all_fine = [psnr(r.color, g.color, ~r.holes) for r, g in zip(fine, truths)]
    assert np.mean(all_fine) > np.mean(all_plain) + 1.5, (all_plain, all_fine)
    for p, f in zip(plain, fine):
        assert f.camera is p.camera or f.camera.allclose(p.camera)
        assert f.color.shape == p.color.shape and f.color.dtype == p.color.dtype
        assert abs(f.holes.mean() - p.holes.mean()) < 0.0005
        both = ~f.holes & ~p.holes
        assert np.percentile(np.abs(f.depth[both] / p.depth[both] - 1), 99) < 0.02


def test_motorcycle_left_to_right_gains_on_real_photographs():
    """The real Middlebury pair: covered pixels against the real right image, 27.55 -> 28.22 dB
    (measured; the silhouettes are placed from the photographs' own mixed pixels)."""
    from ibr.io.middlebury import motorcycle_views

    left, right = motorcycle_views()
    plain = warp(left, right.camera, fill="none")
    fine = warp(left, right.camera, fill="none", supersample=3)
    both = ~plain.holes & ~fine.holes
    assert psnr(fine.color, right.color, both) > psnr(plain.color, right.color, both) + 0.4


def test_cli_interpolate_and_warp_take_supersample(tmp_path, capsys):
    truth = load_view(DATA_DIR / "clutter_t050.json").color
    scores = {}
    for k in (1, 3):
        out = tmp_path / f"k{k}"
        assert cli.main(["interpolate", "--t", "0.5", "--out", str(out), "--supersample", str(k)]) == 0
        scores[k] = psnr(read_image(out / "frame_000_t0.500.png"), truth)
        err = capsys.readouterr().err  # the one-time upsampling is announced before the wait, timed after it
        if k == 3:
            announced, done = err.find("upsampling the sources 3 x 3"), err.find("sources upsampled 3 x 3, their colours")
            assert 0 <= announced < done, err
        else:
            assert "upsampling" not in err, err
    assert scores[3] > scores[1] + 0.5, scores  # measured over the whole frame
    assert cli.main(["interpolate", "--supersample", "2"]) == 2
    assert "supersample" in capsys.readouterr().err
    warped = {}
    for k in (1, 3):  # one source: 7 % holes; its report over covered pixels, 35.45 -> 36.90 dB measured
        out = tmp_path / f"w{k}.png"
        assert cli.main(["warp", str(DATA_DIR / "clutter_a.json"), "--to", str(DATA_DIR / "clutter_t050.json"),
                         "-o", str(out), "--supersample", str(k)]) == 0
        assert read_image(out).shape == truth.shape
        report = capsys.readouterr().err
        warped[k] = float(re.search(r"PSNR over covered pixels ([0-9.]+) dB", report).group(1))
    assert warped[3] > warped[1] + 1.0, warped


def _edge_view(x_edge: float, *, near=2.0, far=4.0, fg=200.0, bg=20.0, h=6, w=16):
    """A near plane left of the vertical line u = ``x_edge`` (pixel units, centres at integers)
    over a far one: colour box-filtered over each pixel (the near share of pixel u is
    clip(x_edge - (u - 0.5), 0, 1)), depth of the centre ray, as a camera and the scene
    renderer make them."""
    u = np.arange(w, dtype=np.float64)
    cover = np.clip(x_edge - (u - 0.5), 0.0, 1.0)
    row = np.rint(bg + cover * (fg - bg))
    color = np.repeat(np.tile(row, (h, 1))[..., None], 3, axis=2).astype(np.uint8)
    depth = np.tile(np.where(u < x_edge, near, far), (h, 1)).astype(np.float32)
    return View(color, depth, Camera(20.0, 20.0, (w - 1) / 2, (h - 1) / 2, w, h))


@pytest.mark.parametrize("x_edge", [6.1, 6.3, 6.45, 6.55, 6.8])
def test_upsampled_silhouette_follows_the_mixed_pixel(x_edge):
    """The 3 x 3 subsamples of the mixed pixel take the near depth exactly where their centre
    lies left of the true edge (the plain replicated depth would put the whole pixel on one
    side); the rest of the image keeps its surfaces."""
    from ibr.render.upsample import upsample_view

    v = _edge_view(x_edge)
    up = upsample_view(v, 3)
    assert up.camera.shape == (18, 48) and up.color.shape == (18, 48, 3)
    sub_u = (np.arange(48) - 1) / 3.0  # subsample centres in source pixel units
    expected = np.where(sub_u < x_edge, 2.0, 4.0)
    assert np.array_equal(up.depth[9], expected.astype(np.float32)), (up.depth[9], expected)


def test_upsampled_depth_is_exact_on_a_tilted_plane_and_keeps_the_quantization():
    """1/z is affine on a plane, so the subsamples of a tilted plane get its exact depth (no
    staircase), and the view's depth quantization carries over."""
    from ibr.base.depth import DepthQuantization, quantization_of, set_quantization
    from ibr.render.upsample import upsample_view

    h, w = 12, 20
    cam = Camera(30.0, 30.0, (w - 1) / 2, (h - 1) / 2, w, h)
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    inv = 0.3 + 0.004 * u - 0.003 * v
    view = View(np.full((h, w, 3), 90, np.uint8), (1.0 / inv).astype(np.float32), cam)
    q = DepthQuantization.codes(0.001)
    set_quantization(view, q)
    up = upsample_view(view, 3)
    assert quantization_of(up) == q
    su, sv = np.meshgrid((np.arange(3 * w) - 1) / 3.0, (np.arange(3 * h) - 1) / 3.0)
    exact = 1.0 / (0.3 + 0.004 * su - 0.003 * sv)
    inner = (slice(2, -2), slice(2, -2))  # the outermost subsamples clamp at the image border
    assert np.allclose(up.depth[inner], exact[inner], rtol=1e-5)


def test_silhouette_subsamples_take_their_own_surfaces_tilted_plane():
    """At the edge pixels each subsample gets the exact depth of the tilted plane on its side
    (1/z extrapolated from the side's nearest pixel), not the neighbourhood's nearest or
    farthest depth replicated (up to 2 % off: about a pixel of parallax)."""
    from ibr.render.upsample import depth_edge_pixels, upsample_view

    v = _edge_view(6.3, h=12)
    u, r = np.meshgrid(np.arange(16, dtype=np.float64), np.arange(12, dtype=np.float64))
    near_inv = lambda su, sv: 0.5 + 0.004 * su - 0.002 * sv  # noqa: E731  (1/z affine: planes)
    far_inv = lambda su, sv: 0.25 + 0.001 * su + 0.0015 * sv  # noqa: E731
    v = View(v.color, np.where(u < 6.3, 1 / near_inv(u, r), 1 / far_inv(u, r)).astype(np.float32), v.camera)
    up = upsample_view(v, 3)
    su, sv = np.meshgrid((np.arange(48) - 1) / 3.0, (np.arange(36) - 1) / 3.0)
    exact = np.where(su < 6.3, 1 / near_inv(su, sv), 1 / far_inv(su, sv))
    edge_k = np.repeat(np.repeat(depth_edge_pixels(v.depth), 3, 0), 3, 1)
    rows = slice(3, -3)  # off the image's top and bottom rows, where subsamples clamp
    assert edge_k[rows].sum() == 2 * 3 * 30
    assert np.allclose(up.depth[rows][edge_k[rows]], exact[rows][edge_k[rows]], rtol=1e-5)


@pytest.mark.parametrize("x_edge", [6.1, 6.2])
def test_a_receding_limb_pixel_is_split_as_the_foreground(x_edge):
    """A foreground whose last pixel before the silhouette recedes 2.5 % from its neighbour (a
    sphere's limb: 1.5 % beyond the neighbour's plane) over a far plane: that mixed pixel is
    still the foreground's, so its subsamples split at the true edge (the far ones at the far
    depth), not all kept in front.
    (At x_edge 6.3 the subsample at 6.33 stays in front: with no clean pixel in the 3 x 3 the
    foreground colour is the mean of the near side's pixels, the mixed ones above and below
    included, and the coverage reads 0.89 for 0.8; a 5 x 5 ring of clean pixels for it
    changed no scene's band, docs/edges.md.)"""
    from ibr.render.upsample import upsample_view

    v = _edge_view(x_edge)
    u = np.arange(16, dtype=np.float64)
    inv = 0.5 + 0.005 * (6 - u)
    inv[6] = inv[5] * 0.975
    depth = np.where(u < x_edge, 1 / inv, 4.0)
    up = upsample_view(View(v.color, np.tile(depth, (6, 1)).astype(np.float32), v.camera), 3)
    sub_u = (np.arange(48) - 1) / 3.0
    cols = slice(3, 45)  # the outermost subsamples clamp at the image border
    assert np.array_equal(up.depth[9, cols] > 3.0, sub_u[cols] >= x_edge), (up.depth[9], x_edge)


def test_low_contrast_edges_along_a_column_are_not_split():
    """Where the near and far colours are too alike to read a coverage from, an edge pixel of a
    silhouette along a pixel column keeps its own depth for all its subsamples (the smoothed
    staircase is the column's edge)."""
    from ibr.render.upsample import upsample_view

    up = upsample_view(_edge_view(6.3, fg=60.0, bg=40.0), 3)
    assert np.array_equal(up.depth[9, 18:21], np.full(3, 2.0, np.float32))  # pixel 6: its centre is near


@pytest.mark.parametrize("slope, x0", [(0.15, 9.6), (0.3, 8.2), (0.6, 5.1), (0.0, 9.3)])
def test_a_low_contrast_slanted_silhouette_follows_the_smoothed_staircase(slope, x0):
    """Where the colours cannot tell the coverage (one colour on both sides) a slanted
    silhouette u = x0 + slope v is cut inside the edge pixels along the depth's staircase
    smoothed: at most 3/4 of the subsamples the replicated staircase puts on the wrong side; a
    silhouette along a pixel column stays exactly where the staircase has it."""
    from ibr.render.upsample import depth_edge_pixels, upsample_view

    h = w = 24
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    near = u < x0 + slope * v
    z = np.where(near, 2.0, 4.0).astype(np.float32)
    up = upsample_view(View(np.full((h, w, 3), 90, np.uint8), z, Camera(20.0, 20.0, (w - 1) / 2, (h - 1) / 2, w, h)), 3)
    sv, su = (np.mgrid[0:3 * h, 0:3 * w] - 1) / 3.0  # subsample centres in source pixel units
    exact = su < x0 + slope * sv
    staircase = np.repeat(np.repeat(near, 3, 0), 3, 1)
    edge_k = np.repeat(np.repeat(depth_edge_pixels(z), 3, 0), 3, 1)
    edge_k[:9] = edge_k[-9:] = False  # off the rows whose 5 x 5 leaves the image
    wrong_ours = int(((up.depth < 3.0) != exact)[edge_k].sum())
    wrong_staircase = int((staircase != exact)[edge_k].sum())
    if slope == 0.0:
        assert np.array_equal(up.depth < 3.0, staircase)
    else:
        assert wrong_ours <= 0.75 * wrong_staircase, (wrong_ours, wrong_staircase)


def test_invalid_depth_stays_where_it_is():
    """NaN (and inf) depth pixels: their subsamples stay invalid and no valid subsample takes a
    NaN; at the source's own pose the supersampled render's holes are exactly those pixels."""
    from ibr.render.upsample import upsample_view

    h, w = 12, 16
    z = np.full((h, w), 3.0, np.float32)
    z[:, 8:] = 5.0
    z[3:6, 2:5] = np.nan
    z[0, 15] = np.inf
    c = np.full((h, w, 3), 100, np.uint8)
    c[:, 8:] = 200
    v = View(c, z, Camera(20.0, 20.0, (w - 1) / 2, (h - 1) / 2, w, h))
    up = upsample_view(v, 3)
    bad_k = np.repeat(np.repeat(~np.isfinite(z), 3, 0), 3, 1)
    assert np.array_equal(~np.isfinite(up.depth), bad_k)
    r = warp(v, v.camera, supersample=3, fill="none")
    assert np.array_equal(r.holes, ~np.isfinite(z))


def test_the_helpers_refuse_bad_input_by_name():
    """Each public helper of the supersampling refuses wrong types, ranks, shapes and values with
    an error naming the argument."""
    from ibr.render.superres import back_project, super_resolve_pair
    from ibr.render.upsample import depth_edge_pixels, upsample_view

    cam = Camera(20.0, 20.0, 7.5, 5.5, 16, 12)
    src = _edge_view(6.3)
    up3 = upsample_view(src, 3)
    z3 = np.ones((6, 6), np.float32)
    ok = np.ones((6, 6), bool)
    cases = [
        (lambda: supersampled_camera("cam", 3), TypeError, "camera"),
        (lambda: supersampled_camera(cam, 2), ValueError, "supersample"),
        (lambda: downsample_rendering(np.zeros((6, 6, 3), bool), z3, ~ok, ~ok, 3), ValueError, "color_k"),
        (lambda: depth_edge_pixels(np.ones(5, np.float32)), ValueError, "depth"),
        (lambda: depth_edge_pixels(z3, rel=float("nan")), ValueError, "rel"),
        (lambda: depth_edge_pixels(z3, quantization=0.1), TypeError, "quantization"),
        (lambda: upsample_view(View(np.zeros((12, 16, 3), np.uint8), None, cam), 3), ValueError, "view"),
        (lambda: upsample_view(_edge_view(6.3), 4), ValueError, "supersample"),
        (lambda: back_project(np.zeros((6, 6, 3)), np.zeros((2, 3, 3)), 3), ValueError, "color_k"),
        (lambda: back_project(np.zeros((6, 6, 3)), np.zeros((2, 2)), 3), ValueError, "color"),
        (lambda: back_project(np.zeros((6, 6, 3)), np.zeros((2, 2, 3)), 2), ValueError, "supersample"),
        (lambda: back_project(np.zeros((6, 6, 3)), np.zeros((2, 2, 3)), 3, iterations=-1), ValueError, "iterations"),
        (lambda: super_resolve_pair((src, src), (src, up3), 3), ValueError, r"upsampled\[0\]"),
        (lambda: super_resolve_pair((src, src), (up3, View(up3.color, None, up3.camera)), 3), ValueError,
         r"upsampled\[1\]"),
        (lambda: super_resolve_pair(src, (up3, up3), 3), TypeError, "sources"),
        (lambda: super_resolve_pair((src, src), (up3, up3), 3, weight=0), ValueError, "weight"),
    ]
    for call, exc, name in cases:
        with pytest.raises(exc, match=name):
            call()
