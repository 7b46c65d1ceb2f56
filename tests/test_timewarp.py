"""Tests of ibr.timewarp (seed 001 section 7.4: post-rendering warp, guard band, up-conversion)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ibr import synth
from ibr.base.camera import Camera
from ibr.stereo.timewarp import guard_band_camera, rotation_homography, timewarp, upconvert, warp_rotation
from ibr.base.view import View


def _rotated(cam: Camera, yaw=0.0, pitch=0.0, roll=0.0) -> Camera:
    pose = cam.world_from_cam.copy()
    pose[:3, :3] = pose[:3, :3] @ Rotation.from_euler("yxz", [yaw, pitch, roll], degrees=True).as_matrix()
    return cam.with_pose(pose)


def _direction_image(cam: Camera) -> np.ndarray:
    """Color as a smooth function of the world direction of each pixel's ray (exact reference)."""
    _, d = cam.rays_world()
    return np.stack([0.5 + 0.4 * np.sin(6 * d[..., 0] + 1), 0.5 + 0.4 * np.cos(5 * d[..., 1]),
                     0.5 + 0.3 * np.sin(4 * (d[..., 0] + d[..., 1]))], -1).astype(np.float32)


def test_homography_maps_projections():
    cam = Camera.from_fov(160, 120, hfov_deg=70)
    dst = _rotated(cam, 5, -3, 10)
    h = rotation_homography(cam, dst)
    rng = np.random.default_rng(0)
    pts = cam.unproject(rng.uniform(0, [160, 120], (40, 2)), rng.uniform(1, 10, 40))
    uv_s, _ = cam.project(pts)
    uv_d, _ = dst.project(pts)
    p = np.c_[uv_s, np.ones(40)] @ h.T
    np.testing.assert_allclose(p[:, :2] / p[:, 2:], uv_d, atol=1e-9)
    with pytest.raises(ValueError, match="camera centers differ"):
        rotation_homography(cam, cam.translated([0.1, 0, 0]))


def test_rotation_warp_equals_direct_render_of_direction_function():
    """Rotation-only time-warp is exact up to bilinear interpolation (smooth reference)."""
    disp = Camera.from_fov(128, 96, hfov_deg=60)
    band = guard_band_camera(disp, margin_px=24)
    src_img = _direction_image(band)
    dst = _rotated(disp, 4, -2.5, 3)
    fr = warp_rotation(src_img, band, dst)
    expect = _direction_image(dst)
    assert not fr.outside.any()
    err = np.abs(fr.color - expect).max()
    # interpolation error only: |g''| h^2 / 8 is ~ 1e-3 here; OpenCV's 1/32-pixel position
    # quantization adds at most |g'| / 64 ~ 2e-3
    assert err < 4e-3, err
    # a half-pixel mistake in the pixel-center convention would be an order of magnitude worse
    half = Camera(band.fx, band.fy, band.cx + 0.5, band.cy, band.width, band.height, band.world_from_cam)
    shifted = warp_rotation(src_img, half, dst)
    assert np.abs(shifted.color - expect).max() > 5 * err


def test_identity_warp_is_exact_crop_of_band():
    disp = Camera.from_fov(40, 30, hfov_deg=60)
    band = guard_band_camera(disp, margin_px=5)
    assert (band.width, band.height, band.cx, band.cy) == (50, 40, disp.cx + 5, disp.cy + 5)
    img = np.random.default_rng(1).integers(0, 256, (40, 50, 3), dtype=np.uint8)
    fr = warp_rotation(img, band, disp)
    np.testing.assert_array_equal(fr.color, img[5:35, 5:45])
    assert fr.color.dtype == np.uint8


def test_guard_band_runs_out_edge_replicated():
    disp = Camera.from_fov(64, 48, hfov_deg=60)
    band = guard_band_camera(disp, margin_px=4)
    img = np.zeros((56, 72, 3), np.float32)
    img[:, -1] = 1.0  # the band's right edge column
    dst = _rotated(disp, yaw=15)  # turn right: more than the band holds
    fr = warp_rotation(img, band, dst)
    assert fr.outside[:, -1].all() and not fr.outside[:, 0].any()
    # beyond the band the edge pixel is replicated instead of black
    np.testing.assert_allclose(fr.color[fr.outside], 1.0)
    # the band's right edge (u_band = 71.5) seen from the display turned by 15 degrees about its
    # y axis lies at u = cx + fx * tan(atan((71.5 - cx_band) / fx) - 15 deg)
    edge = disp.cx + disp.fx * np.tan(np.arctan((71.5 - band.cx) / band.fx) - np.radians(15))
    row = fr.outside[int(disp.cy)]
    assert np.argmax(row) == int(np.floor(edge)) + 1


def test_rotation_timewarp_matches_synth_render():
    scene = synth.make_scene("room")
    disp, _ = synth.scene_cameras("room", width=128, height=96)
    band = guard_band_camera(disp, margin_px=20)
    src = synth.render(scene, band, supersample=3)
    dst = _rotated(disp, 3, -2, 2)
    fr = timewarp(src, dst)  # auto: same center -> homography
    gt = synth.render(scene, dst, supersample=3).color
    psnr = 10 * np.log10(1 / np.mean((fr.color - gt) ** 2))
    assert psnr > 32, psnr
    # not warping at all is far worse: the test can fail
    stale = warp_rotation(src.color, band, disp).color
    assert 10 * np.log10(1 / np.mean((stale - gt) ** 2)) < psnr - 8


def test_translation_uses_depth_and_beats_rotation_only():
    scene = synth.make_scene("clutter")
    disp, _ = synth.scene_cameras("clutter", width=128, height=96)
    band = guard_band_camera(disp, margin_px=16)
    src = synth.render(scene, band, supersample=2)
    dst = disp.translated([0.08, 0.0, 0.05])
    gt = synth.render(scene, dst, supersample=2)
    with_depth = timewarp(src, dst)
    rot_only = timewarp(src, dst, mode="rotation")
    e_depth = np.mean((with_depth.color - gt.color) ** 2)
    e_rot = np.mean((rot_only.color - gt.color) ** 2)
    assert with_depth.color.shape == (96, 128, 3)
    assert e_depth < 0.5 * e_rot
    assert 10 * np.log10(1 / e_depth) > 25


def test_upconvert_10_to_60():
    scene = synth.make_scene("room")
    disp, _ = synth.scene_cameras("room", width=96, height=72)
    cams = [_rotated(disp, yaw=0.5 * i, pitch=-0.2 * i) for i in range(8)]  # a head turn at 60 Hz
    res = upconvert(lambda c: synth.render(scene, c, supersample=2), cams, every=6, margin_px=16,
                    reference=lambda c: synth.render(scene, c, supersample=2).color)
    assert res.rendered.tolist() == [True] + [False] * 5 + [True, False]
    assert res.source_index.tolist() == [0] * 6 + [6, 6]
    assert len(res.frames) == 8 and res.frames[3].shape == (72, 96, 3)
    # rendered frames are exact crops of the band render
    assert res.psnr_db[0] > 60 and res.psnr_db[6] > 60
    # warped frames: interpolation error only (rotation is exact), every frame reported
    assert np.all(res.psnr_db[1:6] > 28), res.psnr_db
    assert np.all(res.outside_fraction == 0)


def test_timewarp_bad_input():
    cam = Camera.from_fov(16, 12, hfov_deg=60)
    view = View(np.zeros((12, 16, 3), np.float32), None, cam)
    with pytest.raises(ValueError, match="mode: expected one of"):
        timewarp(view, cam, mode="fast")
    with pytest.raises(ValueError, match="needs depth"):
        timewarp(view, cam.translated([0.1, 0, 0]))
    with pytest.raises(ValueError, match="margin_px"):
        guard_band_camera(cam, margin_px=-1)
    with pytest.raises(ValueError, match="color: size"):
        warp_rotation(np.zeros((5, 5, 3)), cam, cam)
    with pytest.raises(ValueError, match="every"):
        upconvert(lambda c: view, [cam], every=0)


def test_cli_timewarp(tmp_path):
    import json

    from cli import main
    from ibr.io import read_image, save_view

    disp = Camera.from_fov(48, 36, hfov_deg=60)
    band = guard_band_camera(disp, margin_px=6)
    img = (_direction_image(band) * 255).round().astype(np.uint8)
    depth = np.full(band.shape, 3.0, np.float32)
    src = save_view(View(img, depth, band), tmp_path / "band.json")
    dst = _rotated(disp, yaw=2, pitch=1)
    poses = [disp.world_from_cam.tolist(), dst.world_from_cam.tolist(), dst.to_dict()]
    (tmp_path / "poses.json").write_text(json.dumps({"poses": poses}))
    out = tmp_path / "frames"
    assert main(["timewarp", str(src), "--poses", str(tmp_path / "poses.json"), "--margin", "6", "-o", str(out)]) == 0
    f0 = read_image(out / "frame_0000.png")
    np.testing.assert_array_equal(f0, img[6:42, 6:54])  # same pose: the display crop
    f1 = read_image(out / "frame_0001.png")
    np.testing.assert_array_equal(f1, warp_rotation(img, band, dst).color)
    np.testing.assert_array_equal(read_image(out / "frame_0002.png"), f1)
    (tmp_path / "bad.json").write_text("[[1, 2, 3]]")
    assert main(["timewarp", str(src), "--poses", str(tmp_path / "bad.json"), "-o", str(out)]) == 1
    assert main(["timewarp", str(src), "--poses", str(tmp_path / "none.json"), "-o", str(out)]) == 1
    assert main(["timewarp", str(src), "--poses", str(tmp_path / "poses.json"), "--margin", "30", "-o", str(out)]) == 1


def test_cli_timewarp_without_depth_fails_before_any_frame(tmp_path, capsys):
    """A view without depth and a list of poses whose third moves the head: refused before the
    first frame is warped, naming the pose (it used to fail at that pose, after two frames'
    work); the same poses with ``--mode rotation`` run."""
    import json

    from cli import main
    from ibr.io import save_view
    from ibr.stereo.timewarp import timewarp_mode

    cam = Camera.from_fov(32, 24, hfov_deg=60)
    src = save_view(View(np.zeros((24, 32, 3), np.uint8), None, cam), tmp_path / "flat.json")
    turned = _rotated(cam, yaw=2, pitch=0)
    moved = cam.translated([0.05, 0, 0])
    poses = [cam.world_from_cam.tolist(), turned.world_from_cam.tolist(), moved.world_from_cam.tolist()]
    (tmp_path / "poses.json").write_text(json.dumps(poses))
    assert [timewarp_mode(cam, c) for c in (cam, turned, moved)] == ["rotation", "rotation", "depth"]
    out = tmp_path / "frames"
    args = ["timewarp", str(src), "--poses", str(tmp_path / "poses.json"), "-o", str(out)]
    assert main(args) == 1
    err = capsys.readouterr().err
    assert "VIEW:" in err and "pose 2" in err and "--mode rotation" in err
    assert "a depth time-warp needs depth, but the view has none" in err  # the library's words
    assert not out.exists() or not any(out.iterdir())
    assert main(args + ["--mode", "rotation"]) == 0
    assert len(list(out.glob("frame_*.png"))) == 3
    with pytest.raises(ValueError, match="mode: expected one of"):
        timewarp_mode(cam, moved, mode="fast")
    with pytest.raises(TypeError, match="src"):
        timewarp_mode(None, moved)
    with pytest.raises(ValueError, match="atol"):
        timewarp_mode(cam, moved, atol=-1.0)
    with pytest.raises(ValueError, match="atol"):
        timewarp_mode(cam, moved, atol=float("nan"))
    assert timewarp_mode(cam, moved, atol=0.1) == "rotation"  # a 5 cm move within the tolerance
