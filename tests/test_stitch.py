"""Stitched panoramas and ODS against the ray-traced truth of the synthetic "capture" scene."""

from __future__ import annotations

import math

import numpy as np
import pytest

import cli
from ibr.base.camera import Camera
from ibr.base.view import View
from ibr.io import load_view, read_depth, read_image
from ibr.synth import make_scene, render
from panorama.convert import cubemap_to_equirect
from panorama.stitch import (
    OdsPair,
    cube_rig,
    equirect_camera,
    ods_cameras,
    ods_from_panorama,
    ods_from_views,
    pack_ods,
    ring_rig,
    stitch_rgbd,
    stitch_rgbd_cubemap,
)
from panorama.stitch.baselines import slit_boundaries, slit_stitch, strip_stitch
from panorama.stitch.ods import vertical_disparity
from panorama.synth import render_spherical
from samples import DATA_DIR

W = 256  # equirect width of the accuracy tests


def psnr(a, b, mask) -> float:
    d = (np.asarray(a, np.float64) - np.asarray(b, np.float64))[mask]
    return float(10 * np.log10(1.0 / np.mean(d * d)))


def mse(a, b, mask) -> float:
    d = (np.asarray(a, np.float64) - np.asarray(b, np.float64))[mask]
    return float(np.mean(d * d))


@pytest.fixture(scope="module")
def scene():
    return make_scene("capture")


@pytest.fixture(scope="module")
def cube_views(scene):
    return [render(scene, c, supersample=2) for c in cube_rig(96)]


@pytest.fixture(scope="module")
def ring_views(scene):
    return [render(scene, c, supersample=2) for c in ring_rig(8, radius=0.1, width=128, height=128, hfov_deg=110.0)]


@pytest.fixture(scope="module")
def truths(scene):
    cams = (equirect_camera(W),) + ods_cameras(W)
    return {c.eye: render_spherical(scene, c, supersample=2) for c in cams}


@pytest.fixture(scope="module")
def ceiling(truths):
    """What one resampling costs at this size: the truth against itself shifted by half a pixel
    (32.6 dB for this scene at 256 x 128). A stitch resamples each source once."""
    import cv2

    t = truths["mono"][0]
    mu, mv = np.meshgrid(np.arange(W, dtype=np.float32) + 0.5, np.arange(W // 2, dtype=np.float32))
    shifted = cv2.remap(t, mu, mv, cv2.INTER_LINEAR, borderMode=cv2.BORDER_WRAP)
    return psnr(shifted, t, np.ones(t.shape[:2], bool))


def test_mono_stitch_from_cube_faces_and_a_ring(cube_views, ring_views, truths, ceiling):
    color, rng = truths["mono"]
    assert 31.0 < ceiling < 34.0
    for views in (cube_views, ring_views):
        r = stitch_rgbd(views, equirect_camera(W))
        seen = ~r.holes
        assert psnr(r.color, color, seen) > ceiling - 1.0
        assert r.color.dtype == views[0].color.dtype and r.depth.dtype == np.float32
        # depth is the range along the ray from each pixel's own origin
        ok = seen & np.isfinite(rng)
        # within the mesh level of detail (planes fitted to 0.5 px of disparity; 0.2 % measured)
        assert np.median(np.abs(r.depth[ok] - rng[ok]) / rng[ok]) < 5e-3
    assert (~stitch_rgbd(cube_views, equirect_camera(W)).holes).all()  # six faces see everything


def test_ods_eyes_from_views(cube_views, ring_views, truths, ceiling):
    for views in (cube_views, ring_views):
        pair = ods_from_views(views, W)
        for eye in pair.eyes:
            seen = ~eye.holes
            assert psnr(eye.color, truths[eye.camera.eye][0], seen) > ceiling - 1.5
    # the eyes differ where there is parallax (near objects), and agree at the poles (fade)
    left, right = pair.left.color, pair.right.color
    assert np.abs(left - right).max() > 0.2
    lat = np.degrees(pair.left.camera.lat(np.arange(W // 2)))
    pole_rows = np.abs(lat) >= 80
    both = ~pair.left.holes[pole_rows] & ~pair.right.holes[pole_rows]
    assert np.array_equal(left[pole_rows][both], right[pole_rows][both])


def test_no_vertical_disparity_between_the_eyes():
    left, right = ods_cameras(512)
    rng = np.random.default_rng(1)
    pts = rng.uniform(-10, 10, (2000, 3))
    dv = vertical_disparity((left, right), pts)
    seen = np.isfinite(dv)
    assert seen.mean() > 0.99 and np.abs(dv[seen]).max() < 1e-9
    # at the horizon the eyes differ only in columns
    ul, vl, _ = left.project(np.array([[3.0, 0.0, 1.0]]))
    ur, vr, _ = right.project(np.array([[3.0, 0.0, 1.0]]))
    assert vl[0] == pytest.approx(127.5) and vr[0] == pytest.approx(127.5) and ur[0] < ul[0]


def test_seams_between_sources_do_not_show(ring_views, truths):
    """Error within 4 px of a change of winning source <= 2x the interior error."""
    import cv2

    r = stitch_rgbd(ring_views, equirect_camera(W))
    w = r.winner.astype(np.int32)
    edge = np.zeros(w.shape, np.uint8)
    edge[:, 1:] |= w[:, 1:] != w[:, :-1]
    edge[1:] |= w[1:] != w[:-1]
    band = cv2.dilate(edge, np.ones((9, 9), np.uint8)).astype(bool) & ~r.holes
    interior = ~band & ~r.holes
    assert band.sum() > 500
    assert mse(r.color, truths["mono"][0], band) <= 2.0 * mse(r.color, truths["mono"][0], interior)


def test_cube_faces_then_convert_agree_with_the_direct_equirect(ring_views, ceiling):
    """Ring views rendered per cube face (pinhole path) and converted with panorama agree with the
    direct per-pixel equirect render, to within one extra resampling (the ceiling)."""
    faces, zfaces, holes = stitch_rgbd_cubemap(ring_views, 128)
    via_faces = cubemap_to_equirect(faces, W, W // 2)
    direct = stitch_rgbd(ring_views, equirect_camera(W))
    hole_eq = cubemap_to_equirect({k: v.astype(np.float32) for k, v in holes.items()}, W, W // 2) > 0
    both = ~direct.holes & ~hole_eq
    assert both.mean() > 0.5
    assert psnr(via_faces, direct.color, both) > ceiling
    rng_faces = cubemap_to_equirect(zfaces, W, W // 2, depth=True)
    ok = np.isfinite(rng_faces) & both
    assert np.median(np.abs(rng_faces[ok] / direct.depth[ok] - 1)) < 5e-3


def test_ods_from_one_centre_panorama(truths, ceiling):
    color, rng = truths["mono"]
    pair = ods_from_panorama(color, rng)
    for eye in pair.eyes:
        t = truths[eye.camera.eye][0]
        share = eye.holes.mean()
        assert 0.0005 < share < 0.02  # disocclusions exist behind the near objects, and are few
        assert psnr(eye.color, t, ~eye.holes) > ceiling - 1.5
        assert np.isfinite(eye.depth).all() and not np.isnan(eye.color).any()  # filled from the background


def test_strip_stitching_without_depth_is_much_worse(ring_views, truths):
    for cam in ods_cameras(W):
        ours = stitch_rgbd(ring_views, cam)
        strip = strip_stitch(ring_views, cam)
        m = ~ours.holes & ~strip.holes
        # +3 dB at this small size (4.3-4.5 dB measured); +10 dB at 1024 wide (benchmarks/bench_stitch.py)
        assert psnr(ours.color, truths[cam.eye][0], m) > psnr(strip.color, truths[cam.eye][0], m) + 3.0


def test_mesh_slits_are_no_better_than_ours_and_stop_at_the_fade(ring_views, truths):
    """Slits cover |lat| <= 60 deg only; over what they cover, ours is at least as accurate.
    (How their error and seams shrink with N shows at full size: benchmarks/bench_stitch.py.)"""
    cam = ods_cameras(W)[0]
    t = truths["left"][0]
    ours = stitch_rgbd(ring_views, cam)
    lat = np.abs(cam.lat(np.arange(W // 2)))[:, None] * np.ones((1, W))
    for n in (8, 16):
        sl = slit_stitch(ring_views, cam, n)
        m = ~sl.holes & ~ours.holes
        assert m.mean() > 0.5
        assert (lat[~sl.holes] <= math.radians(60.0) + 1e-9).all()
        assert psnr(ours.color, t, m) >= psnr(sl.color, t, m) - 0.1
        assert set(np.unique(sl.winner[~sl.holes])) == set(range(n))  # every slit used once
    assert len(slit_boundaries(8, W)) == 8 and slit_boundaries(8, W)[1] == pytest.approx(W / 8 - 0.5)


def test_views_with_different_sizes_and_intrinsics(scene, truths, ceiling):
    cams = ring_rig(4, radius=0.05, width=160, height=120, hfov_deg=120.0)
    cams += [Camera(70.0, 90.0, 40.0, 55.0, 96, 100, c.world_from_cam)
             for c in ring_rig(4, radius=0.05, width=96, height=100, hfov_deg=100.0, pitches_deg=(0.0,))]
    views = [render(scene, c, supersample=2) for c in cams]
    r = stitch_rgbd(views, equirect_camera(W))
    assert psnr(r.color, truths["mono"][0], ~r.holes) > ceiling - 1.5
    assert set(np.unique(r.winner[~r.holes])) >= {0, 4}  # both kinds of camera contribute


def _eye_row_fill(eye):
    """An ODS eye's colour as ``fill_stitched`` fills it: along its rows, the rim samples on the
    deeper side of its runs of holes (``_row_rim_samples``) filled with them."""
    from panorama.stitch.fill import _row_rim_samples, fill_panorama

    rim = _row_rim_samples(eye.color, eye.depth, eye.holes)
    depth = np.where(rim, np.float32(np.nan), eye.depth).astype(np.float32)
    return fill_panorama(eye.color, depth, eye.holes | rim, parallax="rows")[0]


def test_ods_eye_rim_samples_beside_row_holes_are_filled_not_copied(truths):
    """The row fill copies a run's deeper neighbour; beside a silhouette that pixel holds the
    foreground's colour mixed into the background's (a translucent brown crescent beside the
    bundled rig's eyeball sphere in the right eye, new-user review). It is filled with the run
    when its colour holds RIM_SHARE or more of the nearer side's; a clean one is copied as before.
    Measured on the eyes from one centre panorama (hole pixels): 512 wide 22.74 / 23.88 ->
    23.87 / 23.86 dB (left / right), 1024: 20.28 / 22.78 -> 23.60 / 22.77, 2048: 20.13 / 22.90 ->
    23.99 / 24.01; the whole eyes +0.05 to +0.93 dB."""
    from panorama.stitch.fill import RIM_SHARE, _row_rim_samples, fill_panorama

    far, near, blue, brown = 5.0, 2.0, np.array([0.1, 0.2, 0.8]), np.array([0.6, 0.4, 0.2])
    color = np.tile(blue, (3, 12, 1)).astype(np.float32)
    depth = np.full((3, 12), far, np.float32)
    color[:, 8:], depth[:, 8:] = brown, near  # the foreground on the right
    holes = np.zeros((3, 12), bool)
    holes[:, 5:8] = True  # the disocclusion left of it; pixel 4 is the background's end of the run
    color[0, 4] = 0.5 * blue + 0.5 * brown  # row 0: a rim sample, half foreground
    color[1, 4] = (1 - 0.5 * RIM_SHARE) * blue + 0.5 * RIM_SHARE * brown  # row 1: a little
    rim = _row_rim_samples(color, depth, holes)
    assert rim.tolist() == [[k == 4 for k in range(12)], [False] * 12, [False] * 12]
    filled = fill_panorama(color, np.where(rim, np.nan, depth), holes | rim, parallax="rows")[0]
    np.testing.assert_allclose(filled[0, 4:8], np.tile(blue, (4, 1)), atol=0.02)  # the background's colour
    plain = fill_panorama(color, depth, holes, parallax="rows")[0]
    assert np.abs(plain[0, 5:8] - blue).max() > 0.2  # without: the mixed colour copied across the run
    # 8-bit colour: the same pixels; the far end at the image border: left alone
    assert np.array_equal(_row_rim_samples((color * 255).round().astype(np.uint8), depth, holes), rim)
    assert not _row_rim_samples(color[:, :8], depth[:, :8], holes[:, :8]).any()


def test_unseen_polar_caps_are_filled_smoothly_not_with_streaks(ring_views, truths):
    """The 8-camera ring sees no zenith or nadir (41.5 % of each ODS eye). The directional
    background fill copied rows and columns into those caps (tall streaks); the panorama fill
    blends, beyond a few pixels from any seen pixel, into a smooth pyramid of the seen colours:
    closer to the truth on the hole pixels (measured 26.3 -> 27.0 dB at 256 wide), neighbouring
    cap pixels 10x smoother, and every hole pixel near a seen one (thin disocclusions) exactly
    as the directional fill has it."""
    import cv2

    from ibr.render.fill import fill_background
    from panorama.stitch.fill import fill_panorama

    eye = ods_from_views(ring_views, W, fill="none").eyes[0]
    truth, holes = truths["left"][0], eye.holes
    assert holes.mean() > 0.3
    old, old_z, _ = fill_background(eye.color, eye.depth, holes)
    new, new_z, filled = fill_panorama(eye.color, eye.depth, holes)
    assert psnr(new, truth, holes) > psnr(old, truth, holes) + 0.4
    far = cv2.distanceTransform(holes.astype(np.uint8), cv2.DIST_L2, 5) > 4

    def streaks(c):  # mean |difference of horizontal neighbours| inside the caps
        d = np.abs(np.diff(c.astype(np.float64), axis=1)).mean(-1)
        return d[far[:, 1:] & far[:, :-1]].mean()

    assert streaks(new) < 0.1 * streaks(old)
    np.testing.assert_array_equal(new[~far], old[~far])
    np.testing.assert_array_equal(new_z, old_z)
    assert np.array_equal(filled, holes)
    filled_eye = ods_from_views(ring_views, W, fill="background").eyes[0]  # an eye: filled along its rows
    np.testing.assert_array_equal(filled_eye.color, _eye_row_fill(eye))
    u8, _, _ = fill_panorama((np.clip(eye.color, 0, 1) * 255).round().astype(np.uint8), eye.depth, holes)
    assert u8.dtype == np.uint8 and np.abs(u8.astype(np.float64) / 255 - new).max() < 1.0 / 255 + 1e-6



def test_ods_eye_holes_take_the_row_fill(ring_views, truths):
    """An ODS eye's parallax runs along its rows: its disocclusions take the deeper row
    neighbour smoothed across rows (``parallax="rows"``), which beats the row-and-column fill of
    mono panoramas on the hole pixels. Measured at 256 wide: ODS from one centre panorama 19.97
    -> 22.90 / 19.88 -> 22.09 dB (left / right), the ring's eyes within 4 px of a seen pixel
    26.76 -> 28.35 / 26.74 -> 28.62 dB (the caps beyond still blend into the smooth fill)."""
    import cv2

    from panorama.stitch.fill import fill_panorama

    color, rng = truths["mono"]
    bare = ods_from_panorama(color, rng, fill="none")
    filled = ods_from_panorama(color, rng)
    for e, f in zip(bare.eyes, filled.eyes):
        t = truths[e.camera.eye][0]
        rows = fill_panorama(e.color, e.depth, e.holes, parallax="rows")[0]
        any_way = fill_panorama(e.color, e.depth, e.holes)[0]
        np.testing.assert_array_equal(f.color, _eye_row_fill(e))
        assert psnr(rows, t, e.holes) > psnr(any_way, t, e.holes) + 1.5
    for e in ods_from_views(ring_views, W, fill="none").eyes:
        t = truths[e.camera.eye][0]
        near = e.holes & (cv2.distanceTransform(e.holes.astype(np.uint8), cv2.DIST_L2, 5) <= 4)
        rows = fill_panorama(e.color, e.depth, e.holes, parallax="rows")[0]
        any_way = fill_panorama(e.color, e.depth, e.holes)[0]
        assert psnr(rows, t, near) > psnr(any_way, t, near) + 1.0
    with pytest.raises(ValueError, match="parallax"):
        fill_panorama(e.color, e.depth, e.holes, parallax="columns")


def test_panorama_fill_far_from_a_seen_region_keeps_its_colour():
    """Hard cases of the smooth fill: a panorama seen over one side only (20 % of the columns),
    hole values that are NaN, a 1-row strip, a view with no depth at all (the directional fill
    reaches nothing) and grey (H, W) colour. A constant seen colour must come out constant
    everywhere (the coarsest pyramid level used to leave empty cells black: 47 % of these holes
    were darker than half the colour), every hole pixel counts as filled, seen pixels unchanged."""
    from panorama.stitch.fill import fill_panorama

    for shape, seen_cols, depth_value in (((128, 256), 51, 2.0), ((1, 64), 3, 2.0), ((40, 64), 20, np.nan)):
        color = np.full(shape + (3,), 0.8, np.float32)
        holes = np.ones(shape, bool)
        holes[:, :seen_cols] = False
        color[holes] = np.nan  # ignored
        depth = np.where(holes, np.nan, depth_value).astype(np.float32)
        out, _, filled = fill_panorama(color, depth, holes, cap_px=4)
        np.testing.assert_allclose(out, 0.8, atol=1e-4)
        assert filled[holes].all() and not filled[~holes].any()
        grey, _, _ = fill_panorama(color[..., 0], depth, holes, cap_px=4)
        assert grey.shape == shape
        np.testing.assert_allclose(grey, 0.8, atol=1e-4)
    with pytest.raises(TypeError, match="cap_px"):
        fill_panorama(color, depth, holes, cap_px=True)
    with pytest.raises(ValueError, match="cap_px"):
        fill_panorama(color, depth, holes, cap_px=0)


def test_a_source_that_sees_nothing_changes_nothing(cube_views):
    plane = make_scene("plane")
    pose = np.eye(4)
    pose[:3, 3] = (0.0, 0.0, -8.0)  # rig is behind the plane the extra view sees
    away = render(plane, Camera.from_fov(64, 64, hfov_deg=60.0, world_from_cam=pose))
    cam = equirect_camera(128, center=(0.0, 0.0, 5.0))
    a = stitch_rgbd(cube_views[:2], cam)
    b = stitch_rgbd(cube_views[:2] + [away], cam)
    assert np.array_equal(a.color, b.color) and np.array_equal(a.holes, b.holes)
    alone = stitch_rgbd([away], cam)
    assert alone.holes.all() and (alone.winner == -1).all()


def test_pack_layouts(cube_views):
    pair = ods_from_views(cube_views, 64)
    assert pack_ods(pair, "top-bottom").shape == (64, 64, 3)
    assert np.array_equal(pack_ods(pair, "top-bottom")[:32], pair.left.color)  # left eye on top
    assert pack_ods(pair, "sbs").shape == (32, 128, 3)
    ana = pack_ods(pair, "anaglyph")
    assert np.array_equal(ana[..., 0], pair.left.color[..., 0]) and np.array_equal(ana[..., 1:], pair.right.color[..., 1:])
    lf, rf = pack_ods(pair, "cube")
    assert set(lf) == {"+x", "-x", "+y", "-y", "+z", "-z"} and lf["+z"].shape == (16, 16, 3)
    with pytest.raises(ValueError, match="layout"):
        pack_ods(pair, "diagonal")
    with pytest.raises(TypeError, match="pair"):
        pack_ods((pair.left, pair.right))
    assert isinstance(pair, OdsPair)


def test_bad_inputs_are_refused_clearly(cube_views):
    v = cube_views[0]
    with pytest.raises(ValueError, match="no depth"):
        stitch_rgbd([View(v.color, None, v.camera, "flat")], 64)
    with pytest.raises(ValueError, match="at least one"):
        stitch_rgbd([], 64)
    with pytest.raises(TypeError, match="views\\[0\\]"):
        stitch_rgbd(["a.json"], 64)
    with pytest.raises(ValueError, match="ipd"):
        ods_from_views(cube_views, 64, ipd=0.0)
    with pytest.raises(ValueError, match="ipd"):
        ods_from_views(cube_views, 64, ipd=-0.06)
    with pytest.raises(ValueError, match="fade"):
        ods_from_views(cube_views, 64, fade_start_deg=80, fade_end_deg=60)
    with pytest.raises(TypeError, match="camera"):
        stitch_rgbd(cube_views, "equirect")
    with pytest.raises(ValueError, match="width"):
        equirect_camera(101)
    with pytest.raises(ValueError, match="range_map"):
        ods_from_panorama(np.zeros((8, 16, 3), np.float32), -np.ones((8, 16), np.float32))


# ------------------------------------------------------------------------------------- CLI
RIG = sorted(str(p) for p in (DATA_DIR / "rig").glob("rig_*.json"))


def test_cli_stitch_mono_and_ods_on_the_bundled_rig(tmp_path, capsys):
    assert len(RIG) == 10
    out = tmp_path / "pano.png"
    assert cli.main(["stitch", *RIG, "-o", str(out), "--width", "256", "--holes-out", str(tmp_path / "h.png")]) == 0
    pano = read_image(out)
    depth = read_depth(tmp_path / "pano_depth.exr")
    assert pano.shape == (128, 256, 3) and depth.shape == (128, 256)
    truth, rng = render_spherical(make_scene("capture"), equirect_camera(256), supersample=2)
    seen = read_image(tmp_path / "h.png") == 0
    assert psnr(pano / 255.0, truth, seen) > 32.0
    assert np.isfinite(depth).all() and 0 < (~seen).mean() < 0.01  # what no view saw: filled by default
    assert cli.main(["stitch", *RIG, "-o", str(tmp_path / "raw.png"), "--width", "256", "--fill", "none"]) == 0
    raw = read_image(tmp_path / "raw.png")
    assert (raw[~seen] == 0).all()
    # seen pixels keep their colour, but the background-rim samples beside a hole (refilled)
    import cv2

    beside = cv2.dilate((~seen).astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool) & seen
    differ = (raw != pano).any(-1) & seen
    assert not (differ & ~beside).any() and (differ & beside).any()  # some rim samples refilled
    err = capsys.readouterr().err
    assert "stitch 10/10" in err and "seen" in err
    ods = tmp_path / "ods.png"
    assert cli.main(["stitch", *RIG, "-o", str(ods), "--stereo", "ods", "--width", "256", "--depth-out", "none"]) == 0
    assert read_image(ods).shape == (256, 256, 3)
    assert not (tmp_path / "ods_depth.exr").exists()
    sbs = tmp_path / "sbs.png"
    assert cli.main(["stitch", *RIG, "-o", str(sbs), "--stereo", "ods", "--width", "128", "--layout", "sbs"]) == 0
    assert read_image(sbs).shape == (64, 256, 3)
    assert read_depth(tmp_path / "sbs_depth.exr").shape == (64, 256)


def test_cli_stitch_from_the_bundled_centre_panorama(tmp_path):
    out = tmp_path / "ods.png"
    pano = [str(DATA_DIR / "rig" / "capture_pano_color.png"), str(DATA_DIR / "rig" / "capture_pano_range.exr")]
    assert cli.main(["stitch", "--panorama", *pano, "-o", str(out), "--stereo", "ods", "--width", "256",
                     "--holes-out", str(tmp_path / "holes.png")]) == 0
    holes = read_image(tmp_path / "holes.png")
    assert holes.shape == (256, 256) and 0 < (holes > 0).mean() < 0.05


def test_cli_stitch_default_width_is_the_sources_resolution(tmp_path, capsys):
    """Without --width the panorama has the sources' resolution (it was 4096 whatever they were:
    a 512-wide centre panorama came out 8x magnified): a --panorama's own width; for views 2 pi x
    their focal length in pixels (one panorama pixel per source pixel at a view's centre), to a
    multiple of 4."""
    import math

    from ibr.io import load_view

    pano = [str(DATA_DIR / "rig" / "capture_pano_color.png"), str(DATA_DIR / "rig" / "capture_pano_range.exr")]
    assert cli.main(["stitch", "--panorama", *pano, "-o", str(tmp_path / "ods.png"), "--stereo", "ods"]) == 0
    width = read_image(pano[0]).shape[1]
    assert read_image(tmp_path / "ods.png").shape[:2] == (width, width)  # two eyes of width x width / 2
    assert f"stitch: width {width} (the --panorama's width" in capsys.readouterr().err
    assert cli.main(["stitch", *RIG[:2], "-o", str(tmp_path / "mono.png"), "--fill", "none"]) == 0
    f = max(load_view(RIG[0]).camera.fx, load_view(RIG[1]).camera.fx)
    expected = 4 * math.ceil(2 * math.pi * f / 4)
    assert read_image(tmp_path / "mono.png").shape[:2] == (expected // 2, expected)
    assert f"stitch: width {expected} (2 pi x the views' focal length" in capsys.readouterr().err
    # long focal lengths: at most MAX_DEFAULT_WIDTH unless --width asks for more
    from types import SimpleNamespace

    from commands.stitch import MAX_DEFAULT_WIDTH, _resolve_width

    args = SimpleNamespace(width=None)
    _resolve_width(args, [SimpleNamespace(camera=SimpleNamespace(fx=5000.0, fy=5000.0))], None)
    assert args.width == MAX_DEFAULT_WIDTH == 8192
    assert "is 31416: at most 8192 by default" in capsys.readouterr().err


@pytest.mark.parametrize("extra, message, code", [
    (["--stereo", "ods", "--ipd", "0"], "argument --ipd: expected a positive number", 2),  # usage errors: exit 2
    (["--width", "101"], "argument --width: expected an even number of pixels", 2),
    (["--width", "0"], "argument --width: expected a number of pixels >= 2 and <= 32768", 2),
    (["--stereo", "ods", "--fade", "80", "60"], "--fade", 1),
    (["--layout", "sbs"], "--layout", 1),
])
def test_cli_stitch_bad_arguments(tmp_path, capsys, extra, message, code):
    out = tmp_path / "x.png"
    assert cli.main(["stitch", *RIG[:2], "-o", str(out), *extra]) == code
    assert message in capsys.readouterr().err
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_cli_stitch_refuses_views_without_depth_or_pose(tmp_path, capsys):
    from ibr.io import save_view

    v = load_view(RIG[0])
    flat = save_view(View(v.color, None, v.camera, "flat"), tmp_path / "flat.json")
    assert cli.main(["stitch", str(flat), "-o", str(tmp_path / "p.png"), "--width", "64"]) == 1
    assert "no depth" in capsys.readouterr().err
    assert cli.main(["stitch", "-o", str(tmp_path / "p.png")]) == 1
    assert not (tmp_path / "p.png").exists()
    # an output that is one of the inputs is refused before any work
    before = (DATA_DIR / "rig" / "rig_00_color.png").read_bytes()
    assert cli.main(["stitch", *RIG, "-o", str(DATA_DIR / "rig" / "rig_00_color.png"), "--width", "64"]) == 1
    assert (DATA_DIR / "rig" / "rig_00_color.png").read_bytes() == before


def test_cli_stitch_over_rig_sequences(tmp_path, capsys):
    """One sequence per rig camera: frame k stitches view k of each; a static rig gives the
    single-frame panorama at every frame."""
    import json

    seqs = []
    for i, view in enumerate(RIG):
        doc = {"format": "ibr-sequence", "version": 1, "name": f"cam{i}", "views": [view, view]}
        path = tmp_path / f"cam{i}.json"
        path.write_text(json.dumps(doc))
        seqs.append(str(path))
    out = tmp_path / "frames"
    assert cli.main(["stitch", *seqs, "-o", str(out), "--width", "128"]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == ["pano_0000.png", "pano_0000_depth.exr", "pano_0001.png", "pano_0001_depth.exr"]
    single = tmp_path / "one.png"
    assert cli.main(["stitch", *RIG, "-o", str(single), "--width", "128"]) == 0
    assert np.array_equal(read_image(out / "pano_0001.png"), read_image(single))
    short = tmp_path / "short.json"
    short.write_text(json.dumps({"format": "ibr-sequence", "version": 1, "views": [RIG[0]]}))
    capsys.readouterr()
    assert cli.main(["stitch", *seqs[:2], str(short), "-o", str(tmp_path / "f2"), "--width", "64"]) == 1
    assert "same number of frames" in capsys.readouterr().err
    assert not (tmp_path / "f2").exists()


def test_cli_view_shows_an_ods_pair_as_anaglyph(tmp_path, capsys):
    import panorama
    from panorama.viewer import to_uint8

    ods = tmp_path / "ods.png"
    assert cli.main(["stitch", *RIG, "-o", str(ods), "--stereo", "ods", "--width", "256", "--depth-out", "none"]) == 0
    pair = read_image(ods)
    out = tmp_path / "ana.png"
    assert cli.main(["view", str(ods), "--stereo", "top-bottom", "-o", str(out), "--yaw", "30", "--width", "96",
                     "--height", "64"]) == 0
    ana = read_image(out)
    kw = dict(yaw_deg=30.0, pitch_deg=0.0, fov_deg=90.0, width=96, height=64, layout="equirect")
    left = to_uint8(panorama.perspective(pair[:128], **kw))
    right = to_uint8(panorama.perspective(pair[128:], **kw))
    assert np.array_equal(ana[..., 0], left[..., 0]) and np.array_equal(ana[..., 1:], right[..., 1:])
    assert not np.array_equal(left, right)  # the eyes differ (parallax)
    assert cli.main(["view", str(ods), "--stereo", "sbs", "-o", str(tmp_path / "x.png")]) == 1
    assert "4:1" in capsys.readouterr().err and not (tmp_path / "x.png").exists()


def test_incidence_is_the_cosine_between_the_source_ray_and_the_plane_normal():
    """A tilted plane n . X = 1 seen by a pinhole: incidence = |n . r| / (|n| |r|) per pixel."""
    from ibr import build_mesh
    from ibr.render.blend import incidence

    cam = Camera(60.0, 60.0, 31.5, 23.5, 64, 48)
    n = np.array([0.25, -0.1, 0.5])  # plane 0.25 x - 0.1 y + 0.5 z = 1, z ~ 2 m, tilted ~28 deg
    v, u = np.mgrid[0:48, 0:64]
    r = np.stack([(u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, np.ones(u.shape)], -1)
    depth = (1.0 / (r @ n)).astype(np.float32)
    mesh = build_mesh(View(np.zeros((48, 64, 3), np.float32), depth, cam))
    assert len(mesh.rects) <= 4  # one plane: a handful of quads, not pixels
    expected = np.abs(r @ n) / (np.linalg.norm(n) * np.linalg.norm(r, axis=-1))
    np.testing.assert_allclose(incidence(mesh), expected, atol=1e-4)


def test_antialias_prefilters_sources_finer_than_the_target(scene, truths):
    """Cube faces 2.4x finer than the equirect alias when point-sampled; the prefilter (sigma from
    the sampling ratio) brings the stitch closer to the box-filtered truth."""
    from ibr.render.blend import PREFILTER_K, prefilter_sigma

    views = [render(scene, c, supersample=2) for c in cube_rig(192)]
    eq = equirect_camera(W)
    s = views[0].camera.fx / (W / (2 * math.pi))
    assert prefilter_sigma(views[0].camera, eq) == pytest.approx(PREFILTER_K * math.sqrt(s * s - 1))
    assert prefilter_sigma(eq_cam := cube_rig(16)[0], eq) == 0.0 and eq_cam.fx < W / (2 * math.pi)
    sharp = stitch_rgbd(views, eq, antialias=False)
    smooth = stitch_rgbd(views, eq)
    seen = ~sharp.holes & ~smooth.holes
    assert psnr(smooth.color, truths["mono"][0], seen) > psnr(sharp.color, truths["mono"][0], seen) + 0.5


def test_ods_from_a_panorama_whose_sky_has_no_range():
    """A centre panorama with range on the floor only (NaN in the sky, as a depth sensor gives
    it): the cube face that sees only sky has nothing to render and is left out instead of
    refusing the whole panorama; the floor reaches both eyes, the sky directions are reported as
    holes. A range that is NaN everywhere is refused by name."""
    from panorama.directions import equirect_directions
    from panorama.stitch.ods import panorama_views

    h, w = 32, 64
    d = equirect_directions(w, h)
    color = np.random.default_rng(0).random((h, w, 3)).astype(np.float32)
    with np.errstate(divide="ignore"):
        rng = np.where(d[..., 1] > 0.05, 1.6 / d[..., 1], np.nan).astype(np.float32)  # y down: the floor
    views = panorama_views(color, rng)  # six faces, as the viewer's face meshes need them
    assert len(views) == 6 and sum(np.isfinite(v.depth).any() for v in views) == 5
    pair = ods_from_panorama(color, rng, fill="none")
    for eye in pair.eyes:
        floor = d[..., 1] > 0.5  # well below the horizon
        sky = d[..., 1] < -0.5
        assert not eye.holes[floor].any() and eye.holes[sky].all()
    with pytest.raises(ValueError, match="range_map"):
        ods_from_panorama(color, np.full((h, w), np.nan, np.float32))


def test_small_review_findings_of_the_ods_helpers(cube_views):
    """(1) Slits must cover their whole latitude band: at a strip's side edge the ray to
    lat_max meets the slit's plane 1 / cos(pi / n) farther out (64 holes on the rows at
    +-59.8 deg before). (2) A point on the rig's vertical axis, where an eye's circle has shrunk
    to 0, has no longitude: all NaN like every unseen point (u was NaN, v and range finite).
    (3) ``pack_ods(..., "cube")`` of a 2-wide pair: faces of 1 px (the default W / 4 was 0)."""
    from ibr.base.ray_camera import SphericalCamera

    mono = SphericalCamera(W, W // 2, "mono", fade_start_deg=60, fade_end_deg=80)
    r = slit_stitch(cube_views, mono, 8)
    lat = np.degrees(mono.lat(np.arange(W // 2)))
    assert not r.holes[np.abs(lat) <= 60].any()
    eye = ods_cameras(4096)[0]
    u, v, rng = eye.project(np.array([[0.0, -3.0, 0.0]]))
    assert np.isnan(u).all() and np.isnan(v).all() and np.isnan(rng).all()
    u, v, rng = eye.project(np.array([[0.0, 0.0, 2.0]]))  # the module docstring's worked number
    assert u[0] == pytest.approx(2057.93, abs=0.01)
    faces = pack_ods(ods_from_views(cube_views, 2), "cube")[0]
    assert all(f.shape[:2] == (1, 1) for f in faces.values())


def test_equirect_widths_past_the_image_ceiling_are_refused():
    """``ibr stitch --width 32768`` (inside the argparse range) allocated several 32768 x 16384
    float arrays and was killed at 24 GB; the cameras refuse widths past the pixel ceiling."""
    for make in (equirect_camera, ods_cameras):
        with pytest.raises(ValueError, match="width: 32768x16384 = 536870912 pixels exceeds the ceiling"):
            make(32768)
    assert equirect_camera(16384).shape == (8192, 16384)


def test_background_rim_samples_beside_holes_are_refilled_not_copied():
    """A silhouette's mixed colour at the background's depth, beside a disocclusion, was copied
    into it by the fill (a comb of dark stripes under the bundled rig's eyeball sphere). With the
    sources, ``fill_stitched`` fills those samples too: over the holes and those samples, the
    bundled rig at 1024 wide 19.9 -> 20.7 dB against a truth rendered without supersampling
    (21.8 -> 23.8 with a 2x2-supersampled one; 2048 wide: +2.2 dB); every other seen pixel is
    unchanged, and ``holes`` still marks only what no view saw."""
    from panorama.stitch.fill import fill_stitched, rim_samples
    from samples import DATA_DIR

    views = [load_view(p) for p in sorted((DATA_DIR / "rig").glob("rig_0*.json"))]
    res = stitch_rgbd(views, equirect_camera(1024, center=(0, 0, 0)))
    truth = render_spherical(make_scene("capture"), res.camera, supersample=1)[0]
    rim = rim_samples(res, views)
    assert rim.sum() > 50 and not (rim & res.holes).any()
    old, new = fill_stitched(res), fill_stitched(res, views)
    changed = res.holes | rim

    def score(img):
        return -10 * np.log10(np.mean((img.color[changed] / 255.0 - truth[changed]) ** 2))

    assert score(new) > score(old) + 0.5
    np.testing.assert_array_equal(new.color[~changed], res.color[~changed])
    np.testing.assert_array_equal(new.holes, res.holes)
    np.testing.assert_array_equal(new.depth[rim], res.depth[rim])  # recoloured; seen, so their depth stays
    # views of another order hardly agree with the panorama's geometry; too few are refused
    assert rim_samples(res, views[::-1]).sum() < 0.2 * rim.sum()
    with pytest.raises(ValueError, match="views: the panorama was stitched from at least 10 views, got 3"):
        rim_samples(res, views[:3])


def test_rim_samples_of_a_pinhole_target_are_none():
    """``rim_samples`` reads spherical targets (range along each ray); a pinhole target has no
    ``rays_world`` and planar depth: none marked, and ``fill_stitched(res, views)`` still fills."""
    import ibr
    from panorama.stitch.fill import fill_stitched, rim_samples

    views = [load_view(p) for p in RIG]
    res = stitch_rgbd(views, ibr.Camera.from_fov(128, 96, hfov_deg=120))
    assert res.holes.any() and not rim_samples(res, views).any()
    np.testing.assert_array_equal(fill_stitched(res, views).color, fill_stitched(res).color)
