"""Back-projected and two-view super-resolved colour of the upsampled sources (issue 11,
``ibr.render.superres``): each pixel's subsamples average to it, a texture comes out sharper
than a Lanczos reading, and the partner source brings the colour nearer the scene's own."""

from pathlib import Path

import cv2
import numpy as np
import pytest

from ibr.base.camera import Camera
from ibr.base.view import View
from ibr.io import load_view
from ibr.render.superres import back_project, super_resolve_pair
from ibr.render.supersample import _block_means
from ibr.render.upsample import depth_edge_pixels, upsample_view
from ibr.render.view_synthesis import warp
from ibr.synth import make_scene, render

DATA_DIR = Path(__file__).resolve().parents[1] / "samples" / "data"


def _texture(h, w, k):
    """(k h, k w, 3) float32: a sum of sinusoids sampled at the subsample centres (periods of
    3.1 to 7 source pixels: detail a pixel's mean blurs)."""
    y, x = (np.mgrid[0:h * k, 0:w * k] + 0.5) / k
    t = 128 + 60 * np.sin(2 * np.pi * x / 3.1) * np.cos(2 * np.pi * y / 4.3) + 40 * np.sin(2 * np.pi * (x + y) / 7.0)
    return np.repeat(t[..., None], 3, axis=2).astype(np.float32)


def test_back_projection_keeps_each_pixels_mean_and_sharpens_a_texture():
    """Pixels = 3 x 3 means of a known texture: after back-projection every pixel's subsamples
    average to it (to float precision), and the subsamples are far nearer the texture than the
    Lanczos-4 reading they start from (measured rms 6.65 -> 2.45 levels)."""
    k, h, w = 3, 24, 32
    truth = _texture(h, w, k)
    pixels = _block_means(truth, k)
    lanczos = cv2.resize(pixels, (w * k, h * k), interpolation=cv2.INTER_LANCZOS4)
    sharp = back_project(lanczos, pixels, k)
    assert np.abs(_block_means(sharp, k) - pixels).max() < 1e-3

    def rms(x):
        return float(np.sqrt(((x - truth)[6:-6, 6:-6] ** 2).mean()))  # off the border's replicated rows

    assert rms(sharp) < 0.5 * rms(lanczos)


def test_back_projection_stays_in_range_and_keeps_the_means():
    """A saturated checkerboard (0 / 255): a Lanczos reading overshoots the range, clipping alone
    would move the pixels' means; the subsamples stay in [0, 255] and the means hold."""
    k = 3
    pixels = (np.indices((8, 10)).sum(0) % 2 * 255.0).astype(np.float32)[..., None]
    lanczos = cv2.resize(pixels, (30, 24), interpolation=cv2.INTER_LANCZOS4)[..., None]
    assert lanczos.min() < 0 or lanczos.max() > 255
    out = back_project(lanczos, pixels, k, limits=(0.0, 255.0))
    assert out.min() >= 0 and out.max() <= 255
    assert np.abs(_block_means(out, k) - pixels).max() < 0.5


def test_a_supersampled_source_at_its_own_pose_gives_itself_back():
    """Clutter a warped into its own camera with ``supersample=3``: every pixel its own colour
    within one level (the rounding of nine subsamples; before the back-projection 821 pixels
    were off by up to 22 levels, and with clipping alone 533 by up to 18)."""
    a = load_view(DATA_DIR / "clutter_a.json")
    r = warp(a, a.camera, supersample=3, fill="none")
    assert not r.holes.any()
    diff = np.abs(r.color.astype(int) - a.color.astype(int)).max(-1)
    assert diff.max() <= 1


@pytest.mark.parametrize("name", ["room", "clutter"])
def test_the_partner_brings_both_sources_nearer_the_scene(name):
    """Each source of a bundled pair rendered at 160 x 120 (3 x 3 box-filtered, as the bundled
    views): its 3x colour refined with the other's is nearer the scene's exact 3x colour than
    its own back-projection alone, off the depth edges by 8 % or more (measured room 7.31 ->
    6.65, clutter 6.79 -> 6.15 levels rms) and on them too (10.86 -> 10.47)."""
    scene = make_scene(name)
    views = []
    for side in ("a", "b"):
        cam = load_view(DATA_DIR / f"{name}_{side}.json").camera.resized(160, 120)
        v = render(scene, cam, supersample=3)
        views.append(View(np.clip(np.rint(v.color * 255), 0, 255).astype(np.uint8), v.depth, cam))
    ups = [upsample_view(v, 3) for v in views]
    pair = super_resolve_pair(tuple(views), tuple(ups), 3)
    for v, u, c in zip(views, ups, pair):
        assert c.dtype == u.color.dtype and c.shape == u.color.shape
        exact = render(scene, u.camera, supersample=3).color * 255
        edge = np.repeat(np.repeat(depth_edge_pixels(v.depth), 3, 0), 3, 1)
        for where, gain in ((~edge & np.isfinite(u.depth), 0.92), (edge, 0.99)):
            single = np.sqrt(((u.color - exact)[where] ** 2).mean())
            refined = np.sqrt(((c - exact)[where] ** 2).mean())
            assert refined < gain * single
        assert np.abs(_block_means(c.astype(np.float32), 3) - v.color).max() <= 1.0  # still its pixels' means


def test_a_partner_whose_depth_disagrees_is_left_out():
    """Room at 160 x 120 with the partner's depth scaled: 1 % off (within the 2 % of one surface)
    the partner still brings source a nearer the scene off the edges (measured 7.27 -> 6.62
    levels rms); 3 % off it sees nothing of a's surfaces and a's colour is as near the scene as
    its own back-projection's, within 1 % (7.27 either way: no misregistered colour drawn in)."""
    scene = make_scene("room")
    views = []
    for side in ("a", "b"):
        cam = load_view(DATA_DIR / f"room_{side}.json").camera.resized(160, 120)
        v = render(scene, cam, supersample=3)
        views.append(View(np.clip(np.rint(v.color * 255), 0, 255).astype(np.uint8), v.depth, cam))
    a = views[0]
    up_a = upsample_view(a, 3)
    exact = render(scene, up_a.camera, supersample=3).color * 255
    inside = ~np.repeat(np.repeat(depth_edge_pixels(a.depth), 3, 0), 3, 1) & np.isfinite(up_a.depth)

    def refined(scale):
        b = View(views[1].color, views[1].depth * np.float32(scale), views[1].camera)
        return super_resolve_pair((a, b), (up_a, upsample_view(b, 3)), 3)[0]

    def rms(c):
        return float(np.sqrt(((c - exact)[inside] ** 2).mean()))

    assert rms(refined(1.01)) < 0.95 * rms(up_a.color)
    assert abs(rms(refined(1.03)) - rms(up_a.color)) < 0.01 * rms(up_a.color)


def test_the_pair_is_refined_once_and_dropped_with_a_view(monkeypatch):
    """Two interpolations of one pair refine the sources' colours once; a new partner is
    refined anew, and a partner that no longer exists takes its refined views with it."""
    import gc

    import ibr.render.superres as superres
    from ibr.render.sources import _source
    from ibr.render.view_synthesis import interpolate

    calls = []
    real = superres.super_resolve_pair

    def counted(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(superres, "super_resolve_pair", counted)
    scene = make_scene("room")
    a, b, c = (render(scene, load_view(DATA_DIR / f"room_{s}.json").camera.resized(64, 48), supersample=3)
               for s in ("a", "b", "a"))
    a, b, c = (View(np.clip(np.rint(v.color * 255), 0, 255).astype(np.uint8), v.depth, v.camera) for v in (a, b, c))
    first = interpolate(a, b, 0.5, fill="none", supersample=3)
    again = interpolate(a, b, 0.5, fill="none", supersample=3)
    assert len(calls) == 1 and np.array_equal(first.color, again.color)
    interpolate(a, c, 0.5, fill="none", supersample=3)
    assert len(calls) == 2
    held = len(_source(a)._upsampled)
    del c
    gc.collect()
    interpolate(a, b, 0.5, fill="none", supersample=3)  # a's refinement with the dead partner is dropped
    assert len(calls) == 2 and len(_source(a)._upsampled) == held - 1


def test_a_mixed_partner_pixel_does_not_draw_a_ghost_line():
    """Clutter at t = 0.75, ``supersample=3``: source a holds the left pole's dark limb mixed
    into a face pixel whose depth is all face (pixel (60, 223) and its column). Left to explain
    source b, it drew a dark line into b's face beside the pole: the worst column right of the
    pole (rows 30-77, columns 226-231) averaged 12.9 levels off the truth (7.2 before the
    partner's colour); with such pixels' large residuals left out 7.0, and with the upsampled
    sources' low trust over their whole mixed 1x pixels (b's clean face wins the blend) 4.0
    (11.2 with the trust alone). With the twentieth session's longer steps 5.7 at 24/255, 3.7
    with such residuals left out from 20/255."""
    from ibr.render.view_synthesis import interpolate

    a, b = (load_view(DATA_DIR / f"clutter_{s}.json") for s in ("a", "b"))
    truth = load_view(DATA_DIR / "clutter_t075.json")
    r = interpolate(a, b, truth.camera, fill="none", supersample=3)
    err = np.abs(r.color.astype(int) - truth.color.astype(int)).max(-1)[30:78, 226:232]
    assert not r.holes[30:78, 226:232].any()
    assert err.mean(axis=0).max() < 4.5


def test_a_silhouette_on_pixel_edges_keeps_each_side_flat():
    """A near square (200 levels, depth 1) on a far wall (50, depth 2) whose outline runs along
    pixel edges: the upsampled colour of every depth-edge pixel is its own flat colour, on both
    sides of the silhouette (its subsamples start from the taps on their own surface; a
    Lanczos-4 start, back-projected, kept a ramp up to 66 levels off)."""
    h, w = 16, 20
    near = np.zeros((h, w), bool)
    near[5:11, 6:14] = True
    color = np.where(near, 200, 50).astype(np.uint8)[..., None].repeat(3, axis=2)
    view = View(color, np.where(near, 1.0, 2.0).astype(np.float32), _camera(w, h))
    up = upsample_view(view, 3)
    expected = np.repeat(np.repeat(color, 3, 0), 3, 1)
    edge = np.repeat(np.repeat(depth_edge_pixels(view.depth), 3, 0), 3, 1)
    assert edge.sum() == (24 + 28) * 9  # the square's outer ring and the wall's pixels around it
    assert np.abs(up.color.astype(int) - expected)[edge].max() <= 1


def test_a_mixed_pixel_of_a_pair_starts_from_its_clean_neighbours_on_the_same_surface():
    """The start of a depth-edge pixel's subsamples (``_within_surfaces``): a far pixel that mixes
    a near surface (colour 100 between the near 200 and the far 50) gives its subsample a third of
    a pixel toward its clean far neighbour that neighbour's colour (50) for a pair
    (``clean_start``), and keeps its own colour where its surface has no clean tap (the centre
    subsample, and the one toward the near side); a lone source's start takes the mixed pixel's
    own colour among the taps (83.3)."""
    from ibr.render.upsample import _within_surfaces

    color = np.array([[200, 200, 100, 50, 50]], np.float32)[..., None].repeat(3, axis=2)
    depth = np.array([[1, 1, 2, 2, 2]], np.float32)
    edge = depth_edge_pixels(depth)
    assert edge.tolist() == [[False, True, True, False, False]]
    depth_k = np.repeat(np.repeat(depth, 3, 0), 3, 1)  # every subsample of the mixed pixel on the far side
    for edge_pixels, outer in ((edge, 50.0), (None, 100 * 2 / 3 + 50 / 3)):
        got, from_clean = _within_surfaces(color, depth, depth_k, edge_pixels, 3, np.array([0]), np.array([2]))
        np.testing.assert_allclose(got[0, :, 0].reshape(3, 3), [[100, 100, outer]] * 3, atol=1e-4)
        assert from_clean[0].reshape(3, 3).tolist() == [[False, False, edge_pixels is not None]] * 3
    view = View(color.astype(np.uint8).repeat(4, axis=0), depth.repeat(4, axis=0), _camera(5, 4))
    clean, lone = (upsample_view(view, 3, clean_start=c).color.astype(float) for c in (True, False))
    assert (clean[:, 8] < lone[:, 8]).all()  # the outer subsample nearer the far colour
    for up in (clean, lone):  # each pixel's subsamples still average to it
        np.testing.assert_allclose(up.reshape(4, 3, 5, 3, 3).mean(axis=(1, 3)), view.color, atol=0.5)
    with pytest.raises(TypeError, match="clean_start: expected True or False"):
        upsample_view(view, 3, clean_start="yes")


def test_a_pairs_unsplit_mixed_pixel_holds_the_other_surfaces_share_beside_the_step():
    """``_share_beside_the_step``: a far pixel (colour 100 between the near 200 and the far 50),
    all of whose subsamples lie on the far surface, keeps the far colour (50) away from the step
    and puts what its colour holds beyond it (the near surface's third) in the subsample column
    next to the step: 200, 50, 50, so that its mean stays 100; a near pixel mixing in the far
    surface likewise (150 between 50 and 200: 50, 200, 200). Where that share would leave the
    colour's range (a far pixel of 220: 560), the start stays as it was."""
    from ibr.render.upsample import _share_beside_the_step, _within_surfaces

    py, px = np.array([0]), np.array([2])
    for row, z, expected in (([200, 200, 100, 50, 50], [1, 1, 2, 2, 2], [200, 50, 50]),
                             ([50, 50, 150, 200, 200], [2, 2, 1, 1, 1], [50, 200, 200]),
                             ([200, 200, 220, 50, 50], [1, 1, 2, 2, 2], None)):
        depth = np.array([z], np.float32)
        edge = depth_edge_pixels(depth)
        depth_k = np.repeat(np.repeat(depth, 3, 0), 3, 1)  # the mixed pixel's subsamples all on its own surface
        color = np.array([row], np.float32)[..., None].repeat(3, axis=2)
        values, from_clean = _within_surfaces(color, depth, depth_k, edge, 3, py, px)
        before = values.copy()
        _share_beside_the_step(values, from_clean, color, depth, depth_k, edge, 3, py, px, (0.0, 255.0))
        if expected is None:
            np.testing.assert_array_equal(values, before)
        else:
            np.testing.assert_allclose(values[0, :, 0].reshape(3, 3), [expected] * 3, atol=1e-3)
            assert values[0, :, 0].mean() == pytest.approx(row[2])


def test_the_edge_total_variation_is_the_divergence_of_the_unit_gradient():
    """``_EdgeZone.tv_descent`` at the zone's subsamples against the whole-image formula
    ``div(grad x / sqrt(|grad x|^2 + eps^2))`` (forward differences, zero past the border)."""
    from ibr.render.superres import _EdgeZone

    rng = np.random.default_rng(3)
    z = np.full((10, 12), 2.0, np.float32)
    z[3:7, 0:5] = 1.0  # a near block touching the left border
    up = upsample_view(View(np.zeros((10, 12, 3), np.uint8), z, _camera(12, 10)), 3)
    zone = _EdgeZone(up, 3)
    x = rng.uniform(0, 255, (30, 36, 3)).astype(np.float32)
    eps = np.float32(4.0)
    gx, gy = np.zeros_like(x), np.zeros_like(x)
    gx[:, :-1], gy[:-1] = x[:, 1:] - x[:, :-1], x[1:] - x[:-1]
    n = np.sqrt(gx**2 + gy**2 + eps**2)
    px, py = gx / n, gy / n
    div = px + py
    div[:, 1:] -= px[:, :-1]
    div[1:] -= py[:-1]
    assert zone.at.size > 0 and np.isin(0, zone.at % 36)  # the zone reaches the left border
    np.testing.assert_allclose(zone.tv_descent(x, eps), div.reshape(-1, 3)[zone.at], atol=1e-5)


def _camera(w, h):
    return Camera(20.0, 20.0, (w - 1) / 2, (h - 1) / 2, w, h)
