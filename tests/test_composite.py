"""Two-source compositing and hole filling."""

from __future__ import annotations

import numpy as np
import pytest

from ibr.base.camera import Camera, interpolate_cameras
from ibr.render.composite import composite, viewpoint_weights
from ibr.render.fill import fill_background, fill_previous
from ibr.render.rasterize import Layer


def layer(color, depth):
    depth = np.asarray(depth, np.float32)
    color = np.asarray(color, np.float32)
    if color.ndim == 2:
        color = np.repeat(color[..., None], 3, -1)
    return Layer(color, depth, np.isfinite(depth))


NAN = np.nan


def test_blend_mixes_agreeing_depths_and_lets_the_nearer_surface_win():
    za = np.array([[2.0, 2.0, 2.0, NAN, NAN]])
    zb = np.array([[2.02, 5.0, 1.0, 3.0, NAN]])
    a = layer(np.full((1, 5), 100.0), za)
    b = layer(np.full((1, 5), 200.0), zb)
    out = composite([a, b], [0.75, 0.25], depth_tol=0.02)
    np.testing.assert_allclose(out.color[0, :, 0], [125.0, 100.0, 200.0, 200.0, 0.0])
    np.testing.assert_allclose(out.depth[0, :4], [0.75 * 2 + 0.25 * 2.02, 2.0, 1.0, 3.0], rtol=1e-6)
    assert np.isnan(out.depth[0, 4])
    np.testing.assert_array_equal(out.coverage[0], [True, True, True, True, False])
    # just outside the tolerance: no blend
    out2 = composite([a, b], [0.75, 0.25], depth_tol=0.009)
    assert out2.color[0, 0, 0] == 100.0


def test_front_mode_is_the_seed_order():
    """Nearer source (larger weight) in front even where the other is nearer in depth."""
    a = layer(np.full((1, 3), 10.0), [[2.0, NAN, 4.0]])
    b = layer(np.full((1, 3), 20.0), [[1.0, 3.0, NAN]])
    out = composite([b, a], [0.4, 0.6], mode="front")  # a has the larger weight
    np.testing.assert_array_equal(out.color[0, :, 0], [10.0, 20.0, 10.0])
    np.testing.assert_array_equal(out.depth[0], [2.0, 3.0, 4.0])


def test_integer_output_is_rounded_and_clipped():
    a = layer(np.array([[10.0, 300.0, -5.0]]), [[1.0, 1.0, 1.0]])
    b = layer(np.array([[11.0, 300.0, -5.0]]), [[1.0, 1.0, 1.0]])
    out = composite([a, b], [0.5, 0.5], dtype=np.uint8)
    assert out.color.dtype == np.uint8
    np.testing.assert_array_equal(out.color[0, :, 0], [11, 255, 0])  # 10.5 rounds half up


def test_viewpoint_weights_follow_t():
    a = Camera.from_fov(8, 6, hfov_deg=60)
    b = a.translated(np.array([1.0, 0, 0]))
    for t in (0.0, 0.25, 0.5, 0.9):
        w = viewpoint_weights(interpolate_cameras(a, b, t), [a, b])
        np.testing.assert_allclose(w, [1 - t, t], atol=1e-12)


def test_composite_errors():
    a = layer(np.zeros((2, 2)), np.ones((2, 2)))
    with pytest.raises(ValueError, match="mode: expected one of"):
        composite([a, a], [1, 1], mode="max")
    with pytest.raises(ValueError, match="weights: expected 2 non-negative"):
        composite([a, a], [1, -1])
    with pytest.raises(ValueError, match="layers: expected 1 or 2"):
        composite([a, a, a], [1, 1, 1])
    with pytest.raises(ValueError, match=r"layers\[1\]: color shape"):
        composite([a, layer(np.zeros((3, 2)), np.ones((3, 2)))], [1, 1])


# ----------------------------------------------------------------------------- fill
def test_previous_fill_touches_only_hole_pixels():
    rng = np.random.default_rng(0)
    color = rng.integers(0, 256, (20, 30, 3), dtype=np.uint8)
    depth = rng.uniform(1, 2, (20, 30)).astype(np.float32)
    holes = rng.random((20, 30)) < 0.2
    depth[holes] = np.nan
    prev = rng.integers(0, 256, (20, 30, 3), dtype=np.uint8)
    prev_z = rng.uniform(3, 4, (20, 30)).astype(np.float32)
    out, z, filled = fill_previous(color, depth, holes, prev, prev_z)
    np.testing.assert_array_equal(out[~holes], color[~holes])
    np.testing.assert_array_equal(z[~holes], depth[~holes])
    np.testing.assert_array_equal(out[holes], prev[holes])
    np.testing.assert_array_equal(z[holes], prev_z[holes])
    np.testing.assert_array_equal(filled, holes)
    assert out is not color


def test_background_fill_takes_the_far_side_of_a_disocclusion():
    """Row: far wall (blue, z=5) | hole | near object (red, z=1): the hole gets blue only, with
    the wall's depth; pixels outside the hole are untouched."""
    color = np.zeros((5, 20, 3), np.uint8)
    color[:, :8] = (0, 0, 255)
    color[:, 12:] = (255, 0, 0)
    depth = np.full((5, 20), 5.0, np.float32)
    depth[:, 12:] = 1.0
    holes = np.zeros((5, 20), bool)
    holes[:, 8:12] = True
    depth[holes] = np.nan
    out, z, filled = fill_background(color, depth, holes)
    np.testing.assert_array_equal(filled, holes)
    np.testing.assert_array_equal(out[holes], np.broadcast_to([0, 0, 255], (20, 3)))
    np.testing.assert_array_equal(z[holes], 5.0)
    np.testing.assert_array_equal(out[~holes], color[~holes])


def test_background_fill_reports_what_it_could_not_fill():
    color = np.zeros((4, 4, 3), np.float32)
    depth = np.full((4, 4), np.nan, np.float32)
    holes = np.ones((4, 4), bool)
    out, z, filled = fill_background(color, depth, holes)
    assert not filled.any() and np.isnan(z).all()


def test_fused_sampling_matches_remap_then_composite():
    """sample_composite == composite(Layer(cv2.remap(...))) up to remap's 1/32-px rounding."""
    from ibr.render.composite import sample_composite
    from ibr.render.rasterize import SourceMaps, sample_maps

    rng = np.random.default_rng(3)
    h, w = 24, 32
    src = [rng.uniform(0, 255, (20, 30, 3)).astype(np.float32) for _ in range(2)]
    maps = []
    for k in range(2):
        z = rng.uniform(1.0, 1.05, (h, w)).astype(np.float32) if k == 0 else rng.uniform(0.9, 1.2, (h, w)).astype(np.float32)
        z[rng.random((h, w)) < 0.2] = np.nan
        u = rng.uniform(0, 29, (h, w)).astype(np.float32)
        v = rng.uniform(0, 19, (h, w)).astype(np.float32)
        maps.append(SourceMaps(u, v, z, np.isfinite(z)))
    fused = sample_composite(src, maps, [0.3, 0.7], dtype=np.float32)
    layers = [Layer(sample_maps(s, m.map_u, m.map_v), m.depth, m.coverage) for s, m in zip(src, maps)]
    ref = composite(layers, [0.3, 0.7], dtype=np.float32)
    np.testing.assert_array_equal(fused.coverage, ref.coverage)
    np.testing.assert_array_equal(np.isnan(fused.depth), np.isnan(ref.depth))
    c = fused.coverage
    np.testing.assert_allclose(fused.depth[c], ref.depth[c], rtol=1e-6)
    # gradient of the random image <= 255 per pixel, remap position error <= 1/64 px per axis
    assert np.abs(fused.color - ref.color)[c].max() <= 2 * 255 / 64 + 1e-3
    assert np.abs(fused.color - ref.color)[c].mean() < 1.0


def test_remap_composite_matches_the_exact_sampler_within_a_level():
    """remap_composite (cv2.remap of colour + trust, then one pass) against sample_composite (exact
    float32 bilinear) on the bundled clutter pair rendered half-way, trust and rims from each
    mesh: same coverage, same pixels handed to the fill, colours within one 8-bit level. And
    on random maps reaching past the border (repeated border pixels in both): within the
    position rounding of remap (1/64 px of a gradient up to 255 per pixel) plus the rounding of
    the 8-bit layers."""
    from ibr.io import load_view
    from ibr.render.composite import remap_composite, rgbt_source, sample_composite
    from ibr.render.rasterize import SourceMaps
    from ibr.render.frame_composite import _source_maps
    from ibr.render.sources import _mesh_key, _source
    from samples import DATA_DIR

    a, b = load_view(DATA_DIR / "clutter_a.json"), load_view(DATA_DIR / "clutter_b.json")
    cam = interpolate_cameras(a.camera, b.camera, 0.5)
    maps = _source_maps((a, b), cam, "mesh", "free", "", ({}, {}))
    w = viewpoint_weights(cam, [a.camera, b.camera])
    packed = [_source(v).trust(_mesh_key({})) for v in (a, b)]
    ref = sample_composite([a.color, b.color], maps, w, dtype=np.uint8, trust=packed)
    new = remap_composite([rgbt_source(v.color, k[..., 0]) for v, k in zip((a, b), packed)], maps, w,
                          rims=[k[..., 1] < 0 for k in packed])
    np.testing.assert_array_equal(new.coverage, ref.coverage)
    assert ref.replace is not None and np.array_equal(new.replace, ref.replace)
    c = ref.coverage
    assert np.abs(new.color.astype(int) - ref.color.astype(int))[c].max() <= 1
    np.testing.assert_allclose(new.depth[c], ref.depth[c], rtol=1e-3)

    rng = np.random.default_rng(5)
    h, wd = 24, 32
    src = [rng.integers(0, 256, (20, 30, 3)).astype(np.uint8) for _ in range(2)]
    rmaps = []
    for k in range(2):
        z = rng.uniform(1.0, 1.05, (h, wd)).astype(np.float32)
        z[rng.random((h, wd)) < 0.2] = np.nan
        u = rng.uniform(-0.5, 29.5, (h, wd)).astype(np.float32)
        v = rng.uniform(-0.5, 19.5, (h, wd)).astype(np.float32)
        rmaps.append(SourceMaps(u, v, z, np.isfinite(z)))
    ref = sample_composite(src, rmaps, [0.4, 0.6], dtype=np.uint8)
    new = remap_composite([rgbt_source(s) for s in src], rmaps, [0.4, 0.6])
    np.testing.assert_array_equal(new.coverage, ref.coverage)
    d = np.abs(new.color.astype(int) - ref.color.astype(int))[ref.coverage]
    assert d.max() <= 2 * 255 / 64 + 1.5 and d.mean() < 1.0
    with pytest.raises(ValueError, match=r"sources\[0\]: expected \(H, W, 4\) uint8"):
        remap_composite([src[0]], rmaps[:1], [1.0])
    with pytest.raises(ValueError, match="color: expected"):
        rgbt_source(src[0][..., :2])
    with pytest.raises(ValueError, match=r"trust: expected shape \(20, 30\)"):
        rgbt_source(src[0], np.ones((20, 31), np.float32))
    four = [rgbt_source(x) for x in src]
    with pytest.raises(ValueError, match="weights: expected 2 non-negative finite weights"):
        remap_composite(four, rmaps, [0.5, -0.5])
    with pytest.raises(ValueError, match="rims: expected one"):
        remap_composite(four, rmaps, [0.5, 0.5], rims=[np.zeros((20, 30), bool)])
    with pytest.raises(ValueError, match="sources, maps: expected 1 or 2 of each"):
        remap_composite(four, rmaps[:1], [1.0])
    with pytest.raises(ValueError, match="mode"):
        remap_composite(four, rmaps, [0.5, 0.5], mode="max")


def test_layers_one_quantization_code_apart_blend():
    """Integer disparities (baseline 0.1, f 1000: one code is 0.01 in inverse depth, 2 % of z at
    z = 2). Without the quantization the 2 % tolerance z-tests layers a code and more apart (the
    nearer wins); with it, layers QUANT_BLEND_CODES codes apart in inverse depth (beyond the
    relative tolerance) are blended, and twice that is still z-tested."""
    from ibr.base.depth import DepthQuantization
    from ibr.render.composite import QUANT_BLEND_CODES

    q = DepthQuantization.disparity(baseline=0.1, focal_px=1000.0)
    za = 1 / 0.5
    zb_in = 1 / (0.5 + 0.9 * QUANT_BLEND_CODES * 0.01)  # inside the quantization tolerance
    zb_out = 1 / (0.5 + 2.0 * QUANT_BLEND_CODES * 0.01)  # outside it (and the 2 % beside it)
    assert (za - zb_in) / zb_in > 0.02  # beyond the relative tolerance alone
    a = layer(np.full((1, 2), 100.0), [[za, za]])
    b = layer(np.full((1, 2), 200.0), [[zb_in, zb_out]])
    plain = composite([a, b], [0.5, 0.5])
    quant = composite([a, b], [0.5, 0.5], quantization=[q, None])
    np.testing.assert_allclose(plain.color[0, :, 0], [200.0, 200.0])  # z-test: b is nearer
    np.testing.assert_allclose(quant.color[0, :, 0], [150.0, 200.0])  # blended / still z-tested
    with pytest.raises(TypeError, match="quantization: expected an ibr.base.depth.DepthQuantization"):
        composite([a, b], [0.5, 0.5], quantization=0.5)


@pytest.mark.parametrize("options", [{}, {"interpolation": "cubic"}, {"float_color": True}])
def test_view_synthesis_never_reads_the_maps_of_uncovered_pixels(monkeypatch, options):
    """View synthesis writes uncovered pixels' map coordinates inside the source (so that
    cv2.remap skips its border path, #13): every sampler must read only covered pixels' maps, so
    the frames are the same as with coordinates far off the source (the 8-bit, the cubic and
    the float-colour paths; the motorcycle warp has 16 % uncovered pixels)."""
    from ibr.base.view import View
    from ibr.io.middlebury import motorcycle_views
    from ibr.render import frame_composite, view_synthesis as vs
    from ibr.render.rasterize import _FAR

    left, right = motorcycle_views()
    opts = dict(options)
    if opts.pop("float_color", False):
        left = View(left.color.astype(np.float32) / 255, left.depth, left.camera)
    inside = vs.warp(left, right.camera, fill="none", **opts)
    monkeypatch.setattr(frame_composite, "_UNCOVERED_COORD", _FAR)
    far = vs.warp(left, right.camera, fill="none", **opts)
    assert 0.1 < inside.holes.mean() < 0.25  # many uncovered pixels
    np.testing.assert_array_equal(inside.holes, far.holes)
    np.testing.assert_array_equal(inside.color, far.color)


def test_source_trust_from_the_depth_or_from_its_mixed_pixels_alike():
    """``source_trust(mixed=...)`` (the mask already found) gives what ``source_trust(depth)`` does;
    neither or both is refused by name."""
    from ibr.render.composite import mixed_pixels, source_trust

    z = np.full((8, 10), 4.0, np.float32)
    z[:, 5:] = 2.0
    assert np.array_equal(source_trust(z), source_trust(mixed=mixed_pixels(z)))
    assert (source_trust(z) < 1).sum() == 16
    for kw in ({}, {"depth": z, "mixed": mixed_pixels(z)}):
        with pytest.raises(ValueError, match="depth, mixed"):
            source_trust(**kw)
