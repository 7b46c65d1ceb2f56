"""``ibr cubemap`` and ``ibr view`` through ``cli.main``, and the WebGL viewer in headless Chromium."""

from __future__ import annotations

import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np
import pytest

import panorama as P
from cli import main
from ibr.io import read_image, write_image
from panorama.directions import equirect_directions

from browser import chromium as _chromium


def smooth_eq(w=128, h=64):
    d = equirect_directions(w, h)
    return np.stack([0.5 + 0.3 * np.sin(3 * d[..., 0] + d[..., 1]), 0.5 + 0.3 * d[..., 1],
                     0.5 + 0.3 * np.cos(2 * d[..., 2])], -1).astype(np.float32)


@pytest.fixture()
def pano_files(tmp_path):
    eq = smooth_eq()
    write_image(tmp_path / "eq8.png", np.rint(eq * 255).astype(np.uint8))
    write_image(tmp_path / "eq16.png", np.rint(eq * 65535).astype(np.uint16))
    write_image(tmp_path / "eq.exr", eq)
    return tmp_path, eq


@pytest.mark.parametrize("layout", ["dice", "horizon", "vstrip", "files"])
@pytest.mark.parametrize("src, dtype", [("eq8.png", np.uint8), ("eq16.png", np.uint16), ("eq.exr", np.float32)])
def test_cubemap_round_trip_every_layout_and_dtype(pano_files, layout, src, dtype):
    tmp, eq = pano_files
    ext = Path(src).suffix
    out = tmp / ("faces" if layout == "files" else f"cube_{layout}{ext}")
    args = ["cubemap", str(tmp / src), "-o", str(out), "--face-size", "32"]
    args += ["--layout", layout] + (["--ext", ext] if layout == "files" else [])
    assert main(args) == 0
    stored = read_image(out / f"pz{ext}") if layout == "files" else read_image(out)
    assert stored.dtype == dtype
    expected = P.equirect_to_cubemap(read_image(tmp / src), 32, layout=layout if layout != "files" else "list")
    if layout != "files":
        np.testing.assert_array_equal(stored, expected)
    else:
        np.testing.assert_array_equal(stored, expected[4])  # pz = +z
    back = tmp / f"back{ext}"
    assert main(["cubemap", str(out), "-o", str(back), "--width", "128"]) == 0
    img = read_image(back)
    assert img.dtype == dtype and img.shape == (64, 128, 3)
    scale = {np.uint8: 255, np.uint16: 65535, np.float32: 1}[dtype]
    assert np.abs(img / scale - eq).max() < 0.03  # smooth content survives the round trip


def test_cubemap_depth(tmp_path, capsys):
    rng = np.full((64, 128), 2.0, np.float32)
    write_image(tmp_path / "range.exr", rng)
    assert main(["cubemap", str(tmp_path / "range.exr"), "-o", str(tmp_path / "z"), "--depth",
                 "--face-size", "16", "--ext", ".exr"]) == 0
    assert "a depth or range map?" not in capsys.readouterr().err
    # without --depth a range map is resampled as an image: said so (new-user review)
    assert main(["cubemap", str(tmp_path / "range.exr"), "-o", str(tmp_path / "asimage.exr"), "--face-size", "16"]) == 0
    assert "one float channel of median 2 (a depth or range map?)" in capsys.readouterr().err
    z = read_image(tmp_path / "z" / "px.exr")
    from panorama.depth import face_ray_lengths
    np.testing.assert_allclose(z, 2.0 / face_ray_lengths(16)[0], rtol=1e-6)
    assert main(["cubemap", str(tmp_path / "z"), "-o", str(tmp_path / "r.exr"), "--depth",
                 "--width", "64"]) == 0
    np.testing.assert_allclose(read_image(tmp_path / "r.exr"), 2.0, rtol=1e-6)


def test_view_and_tour(pano_files):
    tmp, eq = pano_files
    assert main(["view", str(tmp / "eq.exr"), "-o", str(tmp / "v.exr"), "--yaw", "30", "--pitch",
                 "-20", "--roll", "5", "--fov", "70", "--width", "40", "--height", "30"]) == 0
    expected = P.perspective(eq, yaw_deg=30, pitch_deg=-20, roll_deg=5, fov_deg=70, width=40, height=30)
    np.testing.assert_allclose(read_image(tmp / "v.exr"), expected, atol=1e-6)
    assert main(["cubemap", str(tmp / "eq8.png"), "-o", str(tmp / "faces"), "--face-size", "32"]) == 0
    assert main(["view", str(tmp / "faces"), "-o", str(tmp / "tour.gif"), "--tour", "4",
                 "--width", "32", "--height", "24"]) == 0
    frames = sorted((tmp / "tour_frames").glob("frame_*.png"))
    assert len(frames) == 4 and (tmp / "tour.gif").stat().st_size > 0
    faces = [read_image(tmp / "faces" / f"{n}.png") for n in ("px", "nx", "py", "ny", "pz", "nz")]
    third = P.perspective(faces, yaw_deg=180, pitch_deg=0, fov_deg=90, width=32, height=24)
    np.testing.assert_array_equal(read_image(frames[2]), third)


def test_cli_errors(tmp_path, capsys):
    assert main(["cubemap", str(tmp_path / "missing.png"), "-o", str(tmp_path / "x.png")]) == 1
    assert "not found" in capsys.readouterr().err
    (tmp_path / "bad.png").write_bytes(b"not an image")
    assert main(["view", str(tmp_path / "bad.png"), "-o", str(tmp_path / "v.png")]) == 1
    err = capsys.readouterr().err
    assert "bad.png" in err and ("cannot read" in err or "corrupt" in err)
    write_image(tmp_path / "wide.png", np.zeros((10, 37, 3), np.uint8))
    assert main(["cubemap", str(tmp_path / "wide.png"), "-o", str(tmp_path / "x.png")]) == 1
    assert "cannot tell the layout of a 37 x 10 image" in capsys.readouterr().err
    assert main(["cubemap", str(tmp_path / "wide.png"), "-o", "x.png", "--layout", "nope"]) == 2
    (tmp_path / "faces").mkdir()
    assert main(["view", str(tmp_path / "faces"), "-o", str(tmp_path / "v.png")]) == 1
    assert "no face file px" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists() and not (tmp_path / "v.png").exists()


def test_cubemap_refuses_a_4x3_photo_unless_told(tmp_path, capsys):
    """``ibr cubemap samples/data/clutter_a_color.png -o x.png`` took the 512 x 384 photo for a
    dice cubemap (exit 0, garbage equirect). Now exit 1 with the library's message, nothing
    written; ``--input-layout dice`` still forces it."""
    from samples import DATA_DIR

    photo = DATA_DIR / "clutter_a_color.png"
    out = tmp_path / "x.png"
    assert main(["cubemap", str(photo), "-o", str(out)]) == 1
    err = capsys.readouterr().err
    with pytest.raises(ValueError) as exc:
        P.detect_layout(read_image(photo))
    assert err.strip() == f"ibr cubemap: error: {exc.value}" and "Traceback" not in err
    assert "--input-layout dice" in err and not out.exists()
    assert main(["view", str(photo), "-o", str(tmp_path / "v.png"), "--width", "32", "--height", "24"]) == 1
    assert f"ibr view: error: {exc.value}" in capsys.readouterr().err
    assert main(["cubemap", str(photo), "-o", str(out), "--input-layout", "dice", "--width", "64"]) == 0
    assert read_image(out).shape == (32, 64, 3)


# ------------------------------------------------------------------ web viewer
@pytest.mark.skipif(_chromium() is None, reason="headless Chromium not installed (apt-get install chromium)")
def test_web_viewer_matches_library_render(tmp_path):
    """Serve the page, screenshot it in headless Chromium at a known view and compare it with
    panorama.perspective of the same 8-bit faces; a view 1 degree off must compare worse."""
    from panorama.viewer import serve, site_url, write_site
    w, h = 320, 240  # headless Chromium does not shrink its viewport much below ~300 px
    eq = smooth_eq(256, 128)
    eq += 0.15 * np.sin(40 * equirect_directions(256, 128)[..., :1])  # some texture to compare
    site = tmp_path / "site"
    write_site(site, np.clip(eq, 0, 1), face_size=64)
    faces = [read_image(site / f"{n}.png") for n in ("px", "nx", "py", "ny", "pz", "nz")]
    server = serve(site)
    profile = tempfile.mkdtemp(prefix="ibr-chromium-")
    try:
        view = dict(yaw_deg=40.0, pitch_deg=25.0, roll_deg=10.0, fov_deg=80.0)
        shot = tmp_path / "shot.png"
        cmd = [_chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
               "--no-first-run", "--disable-background-networking", "--disable-component-update",
               "--disable-sync", f"--user-data-dir={profile}", "--use-angle=swiftshader",
               "--enable-unsafe-swiftshader", "--force-device-scale-factor=1", "--hide-scrollbars",
               f"--screenshot={shot}", f"--window-size={w},{h}", "--virtual-time-budget=5000",
               site_url(server, hud=False, **view)]
        subprocess.run(cmd, capture_output=True, timeout=120, check=False)
        if not shot.exists():
            pytest.skip("Chromium ran but wrote no screenshot (no WebGL in this environment)")
        got = read_image(shot)[..., :3].astype(np.int16)
        assert got.shape == (h, w, 3)
        ref = P.perspective(faces, width=w, height=h, **view).astype(np.int16)
        diff = np.abs(got - ref)
        assert np.percentile(diff, 99) <= 3 and np.median(diff) <= 1
        off = P.perspective(faces, width=w, height=h, **{**view, "yaw_deg": 41.0}).astype(np.int16)
        assert np.abs(got - off).mean() > 3 * max(diff.mean(), 0.2)
    finally:
        server.shutdown()
        server.server_close()
        shutil.rmtree(profile, ignore_errors=True)


def test_viewer_site_is_served_on_loopback_only(tmp_path):
    import urllib.request
    from panorama.viewer import serve, site_url, write_site
    write_site(tmp_path, np.full((32, 64, 3), 0.5, np.float32), face_size=8)
    server = serve(tmp_path)
    try:
        assert server.server_address[0] == "127.0.0.1"
        url = site_url(server, yaw_deg=10, pitch_deg=-5, fov_deg=70)
        assert url.startswith("http://127.0.0.1:") and "yaw=10&pitch=-5" in url
        page = urllib.request.urlopen(url, timeout=10).read().decode()
        assert "TEXTURE_CUBE_MAP_POSITIVE_X" in page
        face = urllib.request.urlopen(url.split("index.html")[0] + "ny.png", timeout=10).read()
        assert face[:8] == b"\x89PNG\r\n\x1a\n"
    finally:
        server.shutdown()
        server.server_close()
    with pytest.raises(FileNotFoundError, match="has no index.html"):
        serve(tmp_path / "nowhere")


def test_every_advertised_extension_is_written(tmp_path, capsys):
    """``ibr cubemap PANO -o c.exr`` (and faces --ext .exr, ``ibr view -o v.exr``) of an 8-bit
    panorama failed after the work ("array: a .exr file stores float32 ..."); ``ibr stitch
    --depth-out d.png`` failed after the work on a missing scale. Colours are converted to what
    the extension stores; a PNG depth output is refused before any work."""
    from ibr.io import read_image
    from samples import DATA_DIR

    pano = DATA_DIR / "rig" / "capture_pano_color.png"
    assert main(["cubemap", str(pano), "-o", str(tmp_path / "c.exr")]) == 0
    assert main(["cubemap", str(pano), "-o", str(tmp_path / "faces"), "--ext", ".exr"]) == 0
    assert main(["view", str(pano), "-o", str(tmp_path / "v.exr")]) == 0
    for p in (tmp_path / "c.exr", tmp_path / "faces" / "px.exr", tmp_path / "v.exr"):
        img = read_image(p)
        assert img.dtype == np.float32 and 0.0 <= img.min() and img.max() <= 1.0
    rig = sorted(str(p) for p in (DATA_DIR / "rig").glob("rig_*.json"))
    assert main(["stitch", *rig, "-o", str(tmp_path / "p.png"), "--width", "64",
                     "--depth-out", str(tmp_path / "d.png")]) == 1
    assert "--depth-out: " in capsys.readouterr().err and not (tmp_path / "p.png").exists()
