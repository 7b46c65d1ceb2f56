"""Sharp colour sampling (``interpolation="sharp"``, the default of warp / interpolate): bilinear
taps on each source upsampled 2 x 2 once, co-sited, by Lanczos-3 half-way samples that never
reach across a depth edge (:mod:`ibr.render.sharp_sampling`)."""

import numpy as np
import pytest

from ibr import interpolate, warp
from ibr.base.camera import Camera
from ibr.base.view import View
from ibr.io import load_view
from ibr.render.composite import remap_composite, rgbt_source
from ibr.render.rasterize import SourceMaps
from ibr.base.depth import depth_steps
from ibr.render.sharp_sampling import half_sample_kernel, upsample_cosited


def depth_edges(z):  # what sharp sampling protects: steps of 2 % in 1/z, the edge of valid depth
    with np.errstate(divide="ignore"):
        return depth_steps(1.0 / z, 0.02)
from samples import DATA_DIR


def test_the_half_way_kernel_is_lanczos3_at_half_offsets():
    k = half_sample_kernel()
    x = np.array([-2.5, -1.5, -0.5, 0.5, 1.5, 2.5])
    lanczos = np.sinc(x) * np.sinc(x / 3)
    assert k.shape == (6,) and k.sum() == pytest.approx(1.0, abs=1e-6)
    assert np.allclose(k, lanczos / lanczos.sum(), atol=1e-7)
    assert np.allclose(k, k[::-1])  # symmetric about the half-way point


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32])
def test_the_source_pixels_stay_at_the_even_positions(dtype):
    rng = np.random.default_rng(1)
    img = rng.integers(0, 200, (9, 13, 3)).astype(dtype)
    up = upsample_cosited(img)
    assert up.shape == (18, 26, 3) and up.dtype == img.dtype
    assert np.array_equal(up[::2, ::2], img)


def test_half_way_samples_of_a_smooth_signal_are_closer_than_the_bilinear_mean():
    """A band-limited signal (a sinusoid of period 5 px) sampled half-way between its pixels:
    Lanczos-3 within 3 % of the amplitude, where the bilinear mean is off by cos(pi/5)'s 19 %."""
    x = np.arange(64, dtype=np.float32)
    img = np.repeat((100 + 80 * np.sin(2 * np.pi * x / 5))[None, :], 8, 0).astype(np.float32)
    up = upsample_cosited(img)
    exact = 100 + 80 * np.sin(2 * np.pi * (x + 0.5) / 5)
    half = up[0, 1::2]
    inner = slice(4, -4)  # away from the replicated border
    lanczos_err = np.abs(half - exact)[inner].max()
    bilinear_err = np.abs((img[0] + np.roll(img[0], -1)) / 2 - exact)[inner].max()
    assert lanczos_err < 0.03 * 80
    assert bilinear_err > 0.15 * 80


def test_half_way_samples_stay_within_their_two_pixels():
    """A texture step (no depth edge): Lanczos' lobes would ring on both sides (below 50 beside
    the dark side, above 200 beside the bright one); each half-way sample stays between its two
    pixels, so flat texture beside an edge does not change with the sub-pixel phase (flicker)."""
    img = np.full((4, 20), 50, np.uint8)
    img[:, 10:] = 200
    up = upsample_cosited(img).astype(int)
    lo = np.minimum(img, np.concatenate([img[:, 1:], img[:, -1:]], 1)).astype(int)
    hi = np.maximum(img, np.concatenate([img[:, 1:], img[:, -1:]], 1)).astype(int)
    assert (up[0, 1::2] >= lo[0]).all() and (up[0, 1::2] <= hi[0]).all()
    assert up.min() == 50 and up.max() == 200
    assert 50 < up[0, 19] < 200  # the half-way sample across the step itself


def test_no_tap_reaches_across_a_depth_edge():
    """Beside an edge every half-way sample is the mean of its two pixels (what bilinear
    sampling would give), so a bright one-pixel pole leaves no Lanczos lobe on the wall."""
    img = np.full((6, 16), 100, np.uint8)
    img[:, 8] = 250  # a bright pole
    z = np.full((6, 16), 5.0, np.float32)
    z[:, 8] = 2.0
    edges = depth_edges(z)
    assert edges[:, 7:10].all() and not edges[:, :7].any() and not edges[:, 10:].any()
    plain, aware = upsample_cosited(img), upsample_cosited(img, edges)
    assert plain[0, 15] > 175  # Lanczos gives the pole more than half of the sample beside it ...
    assert aware[0, 13] == 100 and aware[0, 11] == 100  # ... the wall stays the wall
    assert aware[0, 15] == aware[0, 17] == 175  # the two half-way samples beside the pole: means
    assert np.array_equal(aware[::2, ::2], img)


def test_depth_steps_mark_steps_and_the_edge_of_valid_depth_not_a_slope():
    z = np.tile(np.linspace(2.0, 2.3, 12, dtype=np.float32), (5, 1))  # a slope: 0.3 % per pixel
    assert not depth_edges(z).any()
    z[2, 5] = np.nan
    e = depth_edges(z)
    assert e[2, 5] and e[1, 5] and e[3, 5] and e[2, 4] and e[2, 6] and e.sum() == 5
    z[2, 6] = 0.0  # two pixels without depth side by side are no step between them
    e = depth_edges(z)
    assert e[2, 4] and e[2, 7] and e.sum() == 8 and not depth_edges(np.full((3, 3), np.nan)).any()
    inv = np.array([[1.0, 1.04, 1.2]])  # 4 % is a step at rel 0.02, not at 0.05
    assert depth_steps(inv, 0.02).all() and depth_steps(inv, 0.05).tolist() == [[False, True, True]]


@pytest.mark.parametrize("kwargs, match", [
    (dict(image=np.zeros((4, 4, 5), np.uint8)), "image: expected"),
    (dict(image=np.zeros((4,), np.uint8)), "image: expected"),
    (dict(image=np.zeros((0, 4), np.uint8)), "image: expected"),
    (dict(image=np.zeros((4, 4), np.int64)), "image: expected uint8, uint16 or float32"),
    (dict(image=np.zeros((4, 4), np.uint8), edges=np.zeros((4, 5), bool)), "edges: expected shape"),
])
def test_upsample_cosited_refuses_bad_input(kwargs, match):
    with pytest.raises(ValueError, match=match):
        upsample_cosited(**kwargs)


def test_one_channel_images_keep_their_channel_axis():
    img = np.arange(12, dtype=np.uint8).reshape(3, 4, 1)
    up = upsample_cosited(img)
    assert up.shape == (6, 8, 1) and np.array_equal(up[::2, ::2], img)


def test_remap_composite_of_an_upsampled_source_samples_it_at_twice_the_coordinates():
    """source_scale=2: map coordinates stay the image's own (maps unchanged on return); at
    integer positions the image's pixels come back exactly, half-way the Lanczos samples."""
    rng = np.random.default_rng(3)
    img = rng.integers(0, 255, (10, 12, 3), dtype=np.uint8)
    up = upsample_cosited(rgbt_source(img))
    v, u = np.mgrid[0:10, 0:12].astype(np.float32)
    maps = SourceMaps(u.copy(), v.copy(), np.full((10, 12), 2.0, np.float32), np.ones((10, 12), bool))
    same = remap_composite([up], [maps], [1.0], source_scale=2)
    assert np.array_equal(same.color, img)
    assert np.array_equal(maps.map_u, u) and np.array_equal(maps.map_v, v)
    half = SourceMaps(np.minimum(u + 0.5, 11).astype(np.float32), v.copy(), maps.depth, maps.coverage)
    got = remap_composite([up], [half], [1.0], source_scale=2)
    assert np.array_equal(got.color[:, :11], up[::2, 1:22:2, :3])
    with pytest.raises(ValueError, match="source_scale: expected 1 or 2"):
        remap_composite([up], [maps], [1.0], source_scale=3)
    with pytest.raises(ValueError, match="rims: .*before the 2 x 2 upsampling"):
        remap_composite([up, up], [maps, maps], [0.5, 0.5], rims=[np.zeros((20, 24), bool)] * 2, source_scale=2)


@pytest.mark.parametrize("dtype", [np.uint8, np.float32])
def test_a_view_warped_into_its_own_camera_comes_back_exactly(dtype):
    a = load_view(DATA_DIR / "clutter_a.json")
    color = a.color if dtype == np.uint8 else a.color.astype(np.float32) / 255
    view = View(color, a.depth, a.camera, "a")
    r = warp(view, a.camera, fill="none")
    assert not r.holes.any()
    assert np.array_equal(r.color, view.color)


def test_sharp_sampling_renders_the_bundled_pair_closer_to_its_ground_truth():
    """Clutter t = 0.5, covered pixels: sharp (default) 37.7 dB against plain bilinear's 37.1
    (bicubic 37.8); the 8-bit path and the float path (other dtypes) agree within a few levels."""
    a, b = load_view(DATA_DIR / "clutter_a.json"), load_view(DATA_DIR / "clutter_b.json")
    truth = load_view(DATA_DIR / "clutter_t050.json")

    def psnr(r):
        d = (r.color.astype(np.float64) - truth.color)[~r.holes]
        return 10 * np.log10(255.0**2 / np.mean(d * d))

    sharp = interpolate(a, b, truth.camera, fill="none")
    linear = interpolate(a, b, truth.camera, fill="none", interpolation="linear")
    assert psnr(sharp) > psnr(linear) + 0.3
    fa, fb = (View(v.color.astype(np.float32), v.depth, v.camera, v.name) for v in (a, b))
    floats = interpolate(fa, fb, truth.camera, fill="none")
    diff = np.abs(floats.color - sharp.color.astype(np.float32))[~sharp.holes]
    assert np.percentile(diff, 99) <= 3


def test_interpolation_choices_are_checked():
    a = load_view(DATA_DIR / "clutter_a.json")
    with pytest.raises(ValueError, match="interpolation"):
        warp(a, a.camera, interpolation="lanczos")
    cam = Camera(100.0, 100.0, 15.5, 11.5, 32, 24)
    with pytest.raises(ValueError, match="interpolation"):
        interpolate(a, a, cam, interpolation="nearest")


def test_upsample_rgbt_equals_the_upsampled_four_channel_image():
    from ibr.render.composite import trust_channel
    from ibr.render.sharp_sampling import upsample_rgbt

    rng = np.random.default_rng(5)
    color = rng.integers(0, 255, (11, 14, 3), dtype=np.uint8)
    trust = rng.random((11, 14)).astype(np.float32)
    z = np.full((11, 14), 3.0, np.float32)
    z[:, 9:] = 1.5
    edges = depth_edges(z)
    t8 = trust_channel(trust, (11, 14))
    assert t8.dtype == np.uint8 and np.array_equal(t8, np.rint(trust * 255).astype(np.uint8))
    assert np.array_equal(upsample_rgbt(color, t8, edges), upsample_cosited(rgbt_source(color, trust), edges))
    with pytest.raises(ValueError, match=r"trust: expected shape \(11, 15\), got \(11, 14\)"):
        trust_channel(trust, (11, 15))


@pytest.mark.parametrize("inv, rel, match", [
    (np.ones(5), 0.02, "inv_depth: expected an"),
    (np.ones((3, 3), bool), 0.02, "inv_depth: expected an"),
    (np.ones((3, 3)), 0.0, "rel: expected a positive"),
    (np.ones((3, 3)), float("nan"), "rel: expected a positive"),
    (np.ones((3, 3)), "0.02", "rel: expected a positive"),
])
def test_depth_steps_refuses_bad_input(inv, rel, match):
    with pytest.raises(ValueError, match=match):
        depth_steps(inv, rel)


@pytest.mark.parametrize("args, match", [
    ((np.zeros((4, 5, 3), np.float32), np.zeros((4, 5), np.uint8)), "color: expected"),
    ((np.zeros((4, 5, 4), np.uint8), np.zeros((4, 5), np.uint8)), "color: expected"),
    ((np.zeros((4, 5, 3), np.uint8), np.zeros((4, 6), np.uint8)), "trust: expected"),
    ((np.zeros((4, 5, 3), np.uint8), np.zeros((4, 5), np.float32)), "trust: expected"),
    ((np.zeros((4, 5, 3), np.uint8), np.zeros((4, 5), np.uint8), np.zeros((5, 5), bool)), "edges: expected"),
])
def test_upsample_rgbt_refuses_bad_input(args, match):
    from ibr.render.sharp_sampling import upsample_rgbt

    with pytest.raises(ValueError, match=match):
        upsample_rgbt(*args)


@pytest.mark.parametrize("a", [0, -2, 2.5, True])
def test_half_sample_kernel_refuses_bad_lobes(a):
    with pytest.raises(ValueError, match="a: expected a positive integer"):
        half_sample_kernel(a)
