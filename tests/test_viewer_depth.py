"""Parallax from depth in the web viewer (issue #18, item 4): per-face quad meshes packed for the
page, checked against the engine's own warp of the same RGB-D panorama."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from cli import main
from ibr.io import read_image, write_depth, write_image
from ibr.synth.scenes import make_scene
from panorama.canvas import view_camera
from panorama.directions import equirect_directions
from panorama.face_meshes import face_meshes, pack_face_meshes, unpack_face_meshes
from panorama.stitch import stitch_rgbd
from panorama.stitch.ods import panorama_views
from panorama.synth import render_equirect
from panorama.viewer import serve, site_url, write_site

from browser import chromium, screenshot

W, H = 480, 270


@pytest.fixture(scope="module")
def capture():
    """The stitching scene seen from its centre: an 8-bit colour equirect and its range map."""
    color, rng = render_equirect(make_scene("capture"), 1024, 512)
    return np.rint(np.clip(color, 0, 1) * 255).astype(np.uint8), rng


def _psnr(a, b) -> float:
    d = a.astype(np.float64) - b.astype(np.float64)
    return float(10 * np.log10(255.0**2 / np.mean(d * d)))


def test_a_room_of_flat_walls_is_one_quad_per_face():
    """Inside a cube room aligned with the faces every face sees one wall at planar z = 2: one quad
    each, 20 bytes a quad after the 36-byte header, and the file reads back what was packed."""
    d = equirect_directions(512, 256)
    rng = (2.0 / np.abs(d).max(-1)).astype(np.float32)
    meshes = face_meshes(np.zeros((256, 512, 3), np.uint8), rng, face_size=64)
    assert [len(m) for m in meshes] == [1] * 6
    data = pack_face_meshes(meshes)
    assert len(data) == 36 + 6 * 20
    size, faces = unpack_face_meshes(data)
    assert size == 64
    for (rects, planes), m in zip(faces, meshes):
        assert rects.tolist() == [[0, 0, 64, 64]]
        np.testing.assert_allclose(planes, m.inv_depth_planes, rtol=1e-6, atol=1e-9)
        # 1/z = 1/2 everywhere, up to the nearest-neighbour resampling of range onto the faces
        np.testing.assert_allclose(planes[0], [0, 0, 0.5], atol=5e-4)
    with pytest.raises(ValueError, match="expected 156 bytes for 6 quads"):
        unpack_face_meshes(data[:-2])
    with pytest.raises(ValueError, match="not a version-1 face-mesh file"):
        unpack_face_meshes(b"PNG" + data[3:])


def test_the_mesh_is_a_fraction_of_the_jpeg(capture):
    """Quads, not pixels: the capture room's meshes take a fraction of the colour JPEG's bytes
    (measured: 27 kB against 114 kB at quality 90, 1363 quads for 6 x 326^2 face pixels)."""
    color, rng = capture
    data = pack_face_meshes(face_meshes(color, rng, head_box=0.1))
    ok, jpeg = cv2.imencode(".jpg", color[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, 90])
    assert ok and len(data) < 0.4 * len(jpeg)


@pytest.mark.skipif(chromium() is None, reason="headless Chromium not installed (apt-get install chromium)")
def test_a_5cm_move_in_the_page_matches_the_engine_warp(tmp_path, capture):
    """The page at 5 cm right of the centre against ``stitch_rgbd`` of the six face views (the
    engine's warp of the same RGB-D panorama) into that camera, over the pixels it covers: >= 30 dB
    (measured 41.6). The flat sphere seen from the centre is far from it: the parallax is real."""
    color, rng = capture
    site = tmp_path / "site"
    write_site(site, color, depth=rng, head_box=0.1)
    size = read_image(site / "pz.png").shape[0]
    view = dict(yaw_deg=30.0, pitch_deg=0.0, fov_deg=90.0)
    server = serve(site)
    try:
        moved = screenshot(site_url(server, hud=False, **view) + "&x=0.05", tmp_path / "moved.png", W, H)
        centre = screenshot(site_url(server, hud=False, **view), tmp_path / "centre.png", W, H)
    finally:
        server.shutdown()
        server.server_close()
    views = panorama_views(color, rng, face_size=size)
    ref = stitch_rgbd(views, view_camera(30.0, 0.0, 0.0, 90.0, W, H, origin=(0.05, 0.0, 0.0)))
    covered = ~ref.holes
    assert covered.mean() > 0.95
    assert _psnr(moved[covered], ref.color[covered]) >= 30
    assert _psnr(centre[covered], ref.color[covered]) < _psnr(moved[covered], ref.color[covered]) - 8
    # from the centre the mesh shows what the panorama holds (no move, no holes)
    ref0 = stitch_rgbd(views, view_camera(30.0, 0.0, 0.0, 90.0, W, H))
    assert _psnr(centre, ref0.color) >= 35


def test_depth_sites_refuse_what_they_cannot_show(tmp_path, capture, capsys):
    color, rng = capture
    for kwargs, message in [(dict(depth=rng[:, :-2]), "expected shape"),
                            (dict(depth=(rng * 1000).astype(np.uint16)), "float range map"),
                            (dict(depth=-rng), "positive ranges"),
                            (dict(depth=rng, tiles=True), "without tiles"),
                            (dict(depth=np.full_like(rng, np.nan)), "no depth at all")]:
        with pytest.raises((ValueError, TypeError), match=message):
            write_site(tmp_path / "s", color, **kwargs)
        assert not (tmp_path / "s").exists()
    write_image(tmp_path / "pano.png", color)
    write_depth(tmp_path / "small.exr", rng[::2, ::2].copy())
    assert main(["view", str(tmp_path / "pano.png"), "--depth", str(tmp_path / "small.exr"),
                 "--site", str(tmp_path / "s")]) != 0
    assert "--depth: expected shape (512, 1024)" in capsys.readouterr().err
    assert not (tmp_path / "s").exists()
    assert main(["view", str(tmp_path / "pano.png"), "--depth", str(tmp_path / "small.exr"), "-o",
                 str(tmp_path / "v.png")]) != 0
    assert "add --serve or --site" in capsys.readouterr().err


@pytest.mark.skipif(chromium() is None, reason="headless Chromium not installed (apt-get install chromium)")
def test_side_by_side_from_depth_with_lens_predistortion(tmp_path, capture):
    """Side by side on a depth site: the two eyes differ by their parallax, and ``?lens=`` turns
    each half into ``ibr.stereo.predistort`` of the plain half (same radial model as the sphere
    path)."""
    from ibr.stereo.lens import RadialDistortion, predistort

    color, rng = capture
    site = tmp_path / "site"
    write_site(site, color, depth=rng, head_box=0.1)
    url = dict(yaw_deg=30.0, pitch_deg=0.0, fov_deg=90.0, hud=False, mode="sbs")
    server = serve(site)
    try:
        plain = screenshot(site_url(server, **url), tmp_path / "plain.png", W, H)
        bent = screenshot(site_url(server, **url) + "&lens=0.22,0.05", tmp_path / "lens.png", W, H)
    finally:
        server.shutdown()
        server.server_close()
    half = W // 2
    assert np.abs(plain[:, :half] - plain[:, half:]).mean() > 3  # two eyes 6.4 cm apart
    for k in range(2):
        want = predistort(plain[:, k * half:(k + 1) * half].astype(np.uint8), RadialDistortion(0.22, 0.05))
        got = bent[:, k * half:(k + 1) * half]
        diff = np.abs(got - want.astype(np.int16)).max(-1)
        assert np.median(diff) <= 1 and np.percentile(diff, 99) <= 3  # measured: 99th percentile 1/255


@pytest.mark.skipif(chromium() is None, reason="headless Chromium not installed (apt-get install chromium)")
def test_a_damaged_or_missing_mesh_file_is_named_in_the_page(tmp_path):
    """A truncated or missing mesh.bin is said in the page's HUD, never a blank page."""
    import tempfile

    from browser import DevTools

    d = equirect_directions(256, 128)
    rng = (2.0 / np.abs(d).max(-1)).astype(np.float32)
    site = tmp_path / "site"
    write_site(site, np.full((128, 256, 3), 0.5, np.float32), depth=rng)
    data = (site / "mesh.bin").read_bytes()
    server = serve(site)
    dt = DevTools.start(W, H, tempfile.mkdtemp(prefix="ibr-chromium-", dir=tmp_path))
    try:
        dt.call("Page.enable")
        for damage, message in ((data[:-4], "depth mesh: truncated mesh file"), (None, "depth mesh: cannot load mesh.bin (404)")):
            if damage is None:
                (site / "mesh.bin").unlink()
            else:
                (site / "mesh.bin").write_bytes(damage)
            dt.call("Page.navigate", url=site_url(server))
            dt.wait_for(f"((document.getElementById('hud') || {{}}).textContent || '').startsWith({message!r})", timeout=30)
            assert dt.eval("getComputedStyle(document.getElementById('hud')).display") == "block"
    finally:
        dt.close()
        server.shutdown()
        server.server_close()
