"""The web viewer's stereo modes for ODS panoramas (issue #20, item 7): mono / red-cyan anaglyph /
side by side, screenshot in headless Chromium and compared with panorama.perspective of each eye."""

from __future__ import annotations

import json

import numpy as np
import pytest

import panorama as P
from cli import main
from ibr.io import read_image, write_image
from ibr.stereo.pair import pack_stereo
from panorama.directions import equirect_directions
from panorama.viewer import SITE_FILES, serve, site_url, split_stereo, write_site

from browser import chromium as _chromium, screenshot

W, H = 320, 240  # headless Chromium does not shrink its viewport much below ~300 px
VIEW = dict(yaw_deg=40.0, pitch_deg=20.0, roll_deg=5.0, fov_deg=80.0)


def _eye(shift: float) -> np.ndarray:
    """A smooth, textured 256 x 128 equirect; ``shift`` (radians of longitude) makes the two eyes
    differ the way parallax does (and each channel differently, so anaglyph mixing is visible)."""
    d = equirect_directions(256, 128)
    lon = np.arctan2(d[..., 0], d[..., 2]) + shift
    return np.clip(np.stack([0.5 + 0.35 * np.sin(6 * lon + d[..., 1]), 0.5 + 0.3 * d[..., 1] + 0.15 * np.cos(9 * lon),
                             0.5 + 0.3 * np.cos(4 * lon) * np.cos(2 * d[..., 1])], -1), 0, 1).astype(np.float32)


@pytest.fixture(scope="module")
def ods_pair():
    return _eye(0.0), _eye(0.25)


def _screenshot(url, out):
    return screenshot(url, out, W, H)


def _close(got, ref):
    diff = np.abs(got - ref.astype(np.int16))
    return np.percentile(diff, 99) <= 3 and np.median(diff) <= 1


def test_stereo_site_holds_both_eyes(tmp_path, ods_pair):
    left, right = ods_pair
    site = tmp_path / "site"
    write_site(site, np.concatenate([left, right], axis=0), face_size=32, stereo="top-bottom")
    assert sorted(p.name for p in site.iterdir()) == sorted(set(SITE_FILES) - {"mesh.bin"})  # mesh.bin: depth sites only
    assert json.loads((site / "viewer.json").read_text()) == {"stereo": True}
    for name, key in (("px", "+x"), ("nz", "-z")):  # each eye's faces are that eye's cube faces
        for eye, suffix in ((left, ""), (right, "_r")):
            want = P.equirect_to_cubemap(eye, 32, layout="dict")[key]
            assert np.abs(read_image(site / f"{name}{suffix}.png").astype(int) - np.rint(want * 255)).max() <= 1
    mono = tmp_path / "mono"
    write_site(mono, left, face_size=32)
    assert json.loads((mono / "viewer.json").read_text()) == {"stereo": False}
    assert not (mono / "px_r.png").exists()
    # side by side packs the same eyes
    a, b = split_stereo(np.concatenate([left, right], axis=1), "sbs")
    assert np.array_equal(a, left) and np.array_equal(b, right)


def test_stereo_site_refuses_a_wrong_packing(tmp_path, ods_pair, capsys):
    left, _ = ods_pair
    with pytest.raises(ValueError, match="top-bottom ODS pair of 2:1 eyes is square"):
        write_site(tmp_path / "a", left, stereo="top-bottom")
    with pytest.raises(ValueError, match="stereo: expected one of top-bottom, sbs"):
        write_site(tmp_path / "b", left, stereo="tb")
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()
    write_image(tmp_path / "mono.png", np.rint(left * 255).astype(np.uint8))
    code = main(["view", str(tmp_path / "mono.png"), "--stereo", "sbs", "--serve", "--site", str(tmp_path / "site")])
    assert code == 1 and "PANO: a side-by-side ODS pair of 2:1 eyes is 4:1" in capsys.readouterr().err
    assert not (tmp_path / "site").exists()


@pytest.mark.skipif(_chromium() is None, reason="headless Chromium not installed (apt-get install chromium)")
def test_web_viewer_stereo_modes_match_each_eye(tmp_path, ods_pair):
    left, right = ods_pair
    site = tmp_path / "site"
    write_site(site, np.concatenate([left, right], axis=0), face_size=64, stereo="top-bottom")
    faces_l = [read_image(site / f"{n}.png") for n in ("px", "nx", "py", "ny", "pz", "nz")]
    faces_r = [read_image(site / f"{n}_r.png") for n in ("px", "nx", "py", "ny", "pz", "nz")]
    view_l = P.perspective(faces_l, width=W, height=H, **VIEW)
    view_r = P.perspective(faces_r, width=W, height=H, **VIEW)
    server = serve(site)
    try:
        mono = _screenshot(site_url(server, hud=False, mode="mono", **VIEW), tmp_path / "mono.png")
        assert _close(mono, view_l) and not _close(mono, view_r)
        ana = _screenshot(site_url(server, hud=False, mode="anaglyph", **VIEW), tmp_path / "ana.png")
        assert _close(ana, pack_stereo(view_l, view_r, "anaglyph"))
        assert not _close(ana, view_l) and not _close(ana, view_r)
        sbs = _screenshot(site_url(server, hud=False, mode="sbs", **VIEW), tmp_path / "sbs.png")
        half = W // 2  # each eye gets half the page, the field of view across its own half
        assert _close(sbs[:, :half], P.perspective(faces_l, width=half, height=H, **VIEW))
        assert _close(sbs[:, half:], P.perspective(faces_r, width=W - half, height=H, **VIEW))
    finally:
        server.shutdown()
        server.server_close()
    # a mono site asked for a stereo mode shows the mono view (no second eye to mix)
    mono_site = tmp_path / "mono_site"
    write_site(mono_site, left, face_size=64)
    server = serve(mono_site)
    try:
        got = _screenshot(site_url(server, hud=False, mode="anaglyph", **VIEW), tmp_path / "fallback.png")
        assert _close(got, view_l)
    finally:
        server.shutdown()
        server.server_close()


@pytest.mark.skipif(_chromium() is None, reason="headless Chromium not installed (apt-get install chromium)")
def test_side_by_side_with_lens_predistortion(tmp_path, ods_pair):
    """?lens=c1,c2 pre-distorts each eye of the side-by-side mode like ibr.stereo.predistort of
    that eye's perspective view (same radial model and pixel convention)."""
    from ibr.stereo.lens import RadialDistortion, predistort

    left, right = ods_pair
    site = tmp_path / "site"
    write_site(site, np.concatenate([left, right], axis=0), face_size=64, stereo="top-bottom")
    half = W // 2
    lens = RadialDistortion(0.22, 0.05)
    server = serve(site)
    try:
        sbs = _screenshot(site_url(server, hud=False, mode="sbs", **VIEW) + "&lens=0.22,0.05", tmp_path / "lens.png")
    finally:
        server.shutdown()
        server.server_close()
    for k, suffix in enumerate(("", "_r")):
        faces = [read_image(site / f"{n}{suffix}.png") for n in ("px", "nx", "py", "ny", "pz", "nz")]
        plain = P.perspective(faces, width=half, height=H, **VIEW)
        want = predistort(plain, lens)
        got = sbs[:, k * half:(k + 1) * half]
        diff = np.abs(got - want.astype(np.int16)).max(-1)
        assert np.median(diff) <= 1 and np.percentile(diff, 97) <= 4  # the black border ring differs by a pixel
        assert np.abs(got - plain.astype(np.int16)).mean() > 5 * max(np.abs(got - want.astype(np.int16)).mean(), 0.2)
