"""Web viewer quality (issue #18): mipmapped minification against a box-filtered reference, in
headless Chromium."""

from __future__ import annotations

import numpy as np
import pytest

import panorama as P
from ibr.io import read_image
from panorama.directions import equirect_directions
from panorama.viewer import serve, site_url, write_site

from test_stitch_viewer import H, W, _chromium, _screenshot


def _psnr(a, b) -> float:
    d = a.astype(np.float64) - b.astype(np.float64)
    return float(10 * np.log10(255.0**2 / np.mean(d * d)))


@pytest.mark.skipif(_chromium() is None, reason="headless Chromium not installed (apt-get install chromium)")
def test_mipmaps_filter_fine_texture_seen_at_a_wide_field_of_view(tmp_path):
    """Fine stripes on 512-px faces seen at 120 degrees over 320 px (about 2-4 face pixels per
    screen pixel): the mipmapped page is close to the view of box-filtered faces, the plain
    bilinear page (``?mipmaps=0``) aliases."""
    d = equirect_directions(2048, 1024)
    lon = np.arctan2(d[..., 0], d[..., 2])
    stripes = 0.5 + 0.45 * np.sin(130 * lon + 90 * d[..., 1])
    eq = np.stack([stripes, 0.3 + 0.4 * stripes, 1 - stripes], -1).astype(np.float32)
    site = tmp_path / "site"
    write_site(site, eq)
    faces = [read_image(site / f"{n}.png") for n in ("px", "nx", "py", "ny", "pz", "nz")]
    assert faces[0].shape[0] == 1024  # power of two >= 2048 / pi
    view = dict(yaw_deg=20.0, pitch_deg=10.0, roll_deg=0.0, fov_deg=120.0)
    # reference: panorama.perspective, which box-filters (area prefilter) the faces to the view's
    # sampling rate before sampling them
    ref = P.perspective(faces, width=W, height=H, **view)
    server = serve(site)
    try:
        mip = _screenshot(site_url(server, hud=False, **view), tmp_path / "mip.png")
        plain = _screenshot(site_url(server, hud=False, **view) + "&mipmaps=0", tmp_path / "plain.png")
    finally:
        server.shutdown()
        server.server_close()
    assert _psnr(mip, ref) > 26 and _psnr(mip, ref) > _psnr(plain, ref) + 3  # measured 28.1 vs 24.0 dB


@pytest.fixture()
def tour_site(tmp_path):
    import json

    from ibr.io import write_image
    from panorama.tour import write_tour_site

    d = equirect_directions(256, 128)
    for name, k in (("hall", 3), ("kitchen", 7)):
        img = np.stack([0.5 + 0.4 * np.sin(k * d[..., 0]), 0.5 + 0.4 * d[..., 1], 0.5 + 0.4 * np.cos(k * d[..., 2])], -1)
        write_image(tmp_path / f"{name}.png", np.rint(img * 255).astype(np.uint8))
    tour = {"first": "hall", "scenes": {
        "hall": {"panorama": "hall.png", "title": "Hall",
                 "hotspots": [{"yaw": 10, "pitch": 0, "scene": "kitchen"}, {"yaw": -30, "pitch": 10, "label": "A label"}]},
        "kitchen": {"panorama": "kitchen.png", "yaw": 90, "hotspots": [{"yaw": 180, "pitch": 0, "scene": "hall"}]}}}
    (tmp_path / "tour.json").write_text(json.dumps(tour))
    site = tmp_path / "site"
    write_tour_site(site, tmp_path / "tour.json", face_size=64)
    return site


def _faces(site, prefix):
    return [read_image(site / f"{prefix}{n}.png") for n in ("px", "nx", "py", "ny", "pz", "nz")]


@pytest.mark.skipif(_chromium() is None, reason="headless Chromium not installed (apt-get install chromium)")
def test_tour_hotspot_click_changes_the_scene_and_keys_turn_the_view(tmp_path, tour_site):
    """A click on the hall's link (yaw 10, pitch 0: at 0.5 + tan 10 / (2 tan 45) = 0.588 of the
    window's width, half its height, in a view at yaw 0, fov 90) opens the kitchen at its own
    initial yaw (90); a click beside it does nothing; two presses of the right arrow turn the view
    by 2 x 5 degrees (at fov 90)."""
    hall, kitchen = _faces(tour_site, "scene-hall-"), _faces(tour_site, "scene-kitchen-")
    server = serve(tour_site)
    try:
        base = site_url(server, hud=False, yaw_deg=0.0, pitch_deg=0.0, fov_deg=90.0)
        clicked = _screenshot(base + "&click=0.588,0.5", tmp_path / "click.png")
        missed = _screenshot(base + "&click=0.3,0.8", tmp_path / "miss.png")  # no spot there
        turned = _screenshot(site_url(server, hud=False, yaw_deg=170.0, pitch_deg=0.0, fov_deg=90.0)
                             + "&keys=ArrowRight,ArrowRight", tmp_path / "keys.png")
    finally:
        server.shutdown()
        server.server_close()
    view = dict(pitch_deg=0.0, roll_deg=0.0, fov_deg=90.0, width=W, height=H)
    assert _psnr(clicked, P.perspective(kitchen, yaw_deg=90.0, **view)) > 40
    hall0 = P.perspective(hall, yaw_deg=0.0, **view).astype(np.int16)
    assert np.median(np.abs(missed - hall0)) <= 1  # still the hall (its two spots drawn over it)
    assert _psnr(missed, P.perspective(kitchen, yaw_deg=90.0, **view)) < 20
    assert _psnr(turned, P.perspective(hall, yaw_deg=180.0, **view)) > 40
    assert _psnr(turned, P.perspective(hall, yaw_deg=170.0, **view)) < 30


def test_tour_files_are_checked(tmp_path, tour_site):
    import json

    from panorama.tour import load_tour

    good = json.loads((tmp_path / "tour.json").read_text())
    cases = [
        (("scenes", "hall", "hotspots", 0, "scene"), "kitchn", r"hotspot 0 links to scene 'kitchn', which the tour does not have \(did you mean 'kitchen'\?\)"),
        (("scenes", "hall", "hotspots", 1, "pitch"), 120, r"hotspot 1: 'pitch': 120 is an impossible angle \(expected -90..90 degrees\)"),
        (("first",), "kitchen2", r"'first' is 'kitchen2', which the tour does not have"),
        (("scenes", "kitchen", "panorama"), "nope.png", r"scene 'kitchen': 'panorama' refers to a missing file"),
        (("scenes", "hall", "hotspot"), [], r"unknown key 'hotspot' \(did you mean 'hotspots'\?\)"),
    ]
    for path, value, message in cases:
        doc = json.loads(json.dumps(good))
        node = doc
        for k in path[:-1]:
            node = node[k]
        if path[-1] == "hotspot":
            node["hotspot"] = node.pop("hotspots")
        else:
            node[path[-1]] = value
        (tmp_path / "bad.json").write_text(json.dumps(doc))
        with pytest.raises((ValueError, FileNotFoundError), match=message):
            load_tour(tmp_path / "bad.json")
    import cli

    (tmp_path / "bad.json").write_text(json.dumps({"scenes": {"hall": {"panorama": "hall.png", "hotspots": [
        {"yaw": 0, "pitch": 0, "scene": "attic"}]}}}))
    assert cli.main(["view", str(tmp_path / "bad.json"), "--site", str(tmp_path / "s2")]) == 1
    assert not (tmp_path / "s2").exists()
    assert cli.main(["view", str(tmp_path / "tour.json"), "--stereo", "sbs", "--site", str(tmp_path / "s4")]) == 1
    assert cli.main(["view", str(tmp_path / "tour.json"), "-o", str(tmp_path / "v.png")]) == 1
    assert not (tmp_path / "s4").exists() and not (tmp_path / "v.png").exists()
    assert cli.main(["view", str(tmp_path / "tour.json"), "--site", str(tmp_path / "s3")]) == 0
    assert (tmp_path / "s3" / "scene-kitchen-nz.png").is_file() and (tmp_path / "s3" / "viewer.json").is_file()


def test_faces_over_the_device_limit_are_refused_or_explained(tmp_path):
    """write_site refuses faces larger than phones show; the page checks its own device's limit
    and prints a message in place of a black page."""
    from panorama.viewer import MAX_FACE_SIZE, WEB_DIR

    with pytest.raises(ValueError, match=r"face_size: 8192 px faces exceed .* choose --face-size <= 4096"):
        write_site(tmp_path / "s", np.zeros((64, 128, 3), np.float32), face_size=2 * MAX_FACE_SIZE)
    assert not (tmp_path / "s").exists()
    page = (WEB_DIR / "index.html").read_text()
    assert "MAX_CUBE_MAP_TEXTURE_SIZE" in page and "write the site with a smaller --face-size" in page


@pytest.mark.skipif(_chromium() is None, reason="headless Chromium not installed (apt-get install chromium)")
@pytest.mark.parametrize("maxcube", [None, 1024])
def test_tiles_load_only_what_a_zoomed_view_needs(tmp_path, maxcube):
    """A 4096-wide panorama as a tile pyramid (base faces 512, levels 1024 and 2048): zoomed to
    30 degrees at yaw 0 the page needs faces of >= 2 f = 1194 px, i.e. level 2, and fetches only
    the four tiles of face +z around its centre (tan 15 deg = 0.27 of the half face); the picture
    matches the full-resolution faces. At 100 degrees the base faces suffice: no tile is fetched.
    With a device limit of 1024-px cube faces (``?maxcube=1024``) level 2 is drawn as its tiles
    (textured quads on the cube): the same four tiles, the same picture."""
    import functools
    import http.server
    import threading

    from panorama.viewer import _SiteHandler

    d = equirect_directions(4096, 2048)
    lon, lat = np.arctan2(d[..., 0], d[..., 2]), np.arcsin(-d[..., 1])
    # detail the base faces cannot hold: a period of 0.3 degrees is 6.8 px on 2048-px faces, 1.7 on 512
    eq = np.stack([0.5 + 0.4 * np.sin(1200 * lon) * np.cos(900 * lat), 0.5 + 0.4 * np.cos(25 * lat),
                   0.5 + 0.3 * np.sin(13 * lon + 7 * lat)], -1).astype(np.float32)
    site = tmp_path / "site"
    write_site(site, eq, tiles=True)
    assert read_image(site / "px.png").shape[0] == 512 and (site / "tile-2-pz-3-3.png").is_file()
    assert not (site / "tile-3-pz-0-0.png").exists()
    requested = []

    class Recorder(_SiteHandler):
        def send_head(self):
            requested.append(self.path.split("?")[0].lstrip("/"))
            return super().send_head()

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(Recorder, directory=str(site)))
    threading.Thread(target=server.serve_forever, daemon=True).start()
    try:
        zoom = dict(yaw_deg=0.0, pitch_deg=0.0, roll_deg=0.0, fov_deg=30.0)
        extra = f"&maxcube={maxcube}" if maxcube else ""
        shot = _screenshot(site_url(server, hud=False, **zoom) + extra, tmp_path / "zoom.png")
        zoom_tiles = sorted(p for p in requested if p.startswith("tile-"))
        requested.clear()
        _screenshot(site_url(server, hud=False, yaw_deg=0.0, pitch_deg=0.0, fov_deg=100.0) + extra, tmp_path / "wide.png")
        wide_tiles = [p for p in requested if p.startswith("tile-")]
    finally:
        server.shutdown()
        server.server_close()
    assert zoom_tiles == ["tile-2-pz-1-1.png", "tile-2-pz-1-2.png", "tile-2-pz-2-1.png", "tile-2-pz-2-2.png"]
    assert wide_tiles == []
    def view(size):
        faces = P.equirect_to_cubemap(eq, size, layout="list")
        return P.perspective([np.rint(np.clip(f, 0, 1) * 255).astype(np.uint8) for f in faces], width=W, height=H,
                             **zoom)

    assert _psnr(shot, view(2048)) > 35 and _psnr(view(512), view(2048)) < 30  # the tiles made the detail


def test_faces_as_perspective_views_are_the_cube_faces():
    """Faces too large for one cubemap image are made one at a time as 90-degree perspective
    views (FACE_VIEWS): the same rays as equirect_to_cubemap, face by face and in order."""
    from panorama.viewer import FACE_VIEWS

    d = equirect_directions(512, 256)
    lon = np.arctan2(d[..., 0], d[..., 2])
    eq = np.stack([0.5 + 0.4 * np.sin(5 * lon + 3 * d[..., 1]), 0.5 + 0.4 * d[..., 1], 0.5 + 0.3 * np.cos(3 * lon)],
                  -1).astype(np.float32)
    faces = P.equirect_to_cubemap(eq, 128, layout="list")
    for face, (yaw, pitch) in zip(faces, FACE_VIEWS, strict=True):
        view = P.perspective(eq, yaw_deg=yaw, pitch_deg=pitch, fov_deg=90.0, width=128, height=128)
        np.testing.assert_allclose(view, face, atol=1e-5)


@pytest.mark.skipif(_chromium() is None, reason="headless Chromium not installed (apt-get install chromium)")
def test_a_missing_tile_is_named_in_the_page(tmp_path):
    """A tile pyramid with one tile deleted: a zoomed view that needs it names it in the HUD (the
    base faces stay on screen), never a blank page; the message stays when the view turns (the
    compass line is redrawn beside it)."""
    import tempfile

    from browser import DevTools

    site = tmp_path / "site"
    write_site(site, np.full((1024, 2048, 3), 0.5, np.float32), tiles=True, face_size=1024)
    (site / "tile-1-pz-0-0.png").unlink()  # level 1: 1024-px faces in 2 x 2 tiles of 512 px
    server = serve(site)
    dt = DevTools.start(W, H, tempfile.mkdtemp(prefix="ibr-chromium-", dir=tmp_path))
    try:
        dt.call("Page.enable")
        dt.call("Page.navigate", url=site_url(server, yaw_deg=0.0, pitch_deg=0.0, fov_deg=30.0))
        dt.wait_for("((document.getElementById('hud') || {}).textContent || '').startsWith('missing tile ')", timeout=30)
        problem = dt.eval("document.getElementById('hud').textContent").split("  |  ")[0]
        assert problem.endswith("/tile-1-pz-0-0.png")
        assert dt.eval("getComputedStyle(document.getElementById('hud')).display") == "block"
        dt.eval("window.dispatchEvent(new KeyboardEvent('keydown', {key: 'ArrowRight'}))")
        dt.wait_for("document.getElementById('hud').textContent.includes('yaw 1.7')", timeout=30)  # 5 deg x 30/90
        assert dt.eval("document.getElementById('hud').textContent").startswith(problem + "  |  ")
    finally:
        dt.close()
        server.shutdown()
        server.server_close()


def test_cubemap_sites_take_face_size_and_tours_take_roll(tmp_path):
    """Found by a review: a cubemap input ignored ``face_size`` (600-px faces stayed 600, not a
    power of two for WebGL1 mipmaps; 4100-px faces passed the 4096 limit; ``--tiles`` failed
    unless the faces were 512 * 2^k); the tour site had no face-size limit; ``--roll`` was
    dropped by tours."""
    import json

    from panorama.tour import write_tour_site
    from panorama.viewer import tour_views
    from samples import DATA_DIR

    faces = [np.full((600, 600, 3), 40 * k, np.uint8) for k in range(6)]
    write_site(tmp_path / "a", faces, layout="list", face_size=64)
    assert read_image(tmp_path / "a" / "px.png").shape == (64, 64, 3)
    write_site(tmp_path / "b", faces, layout="list")  # the default: a power of two >= the faces'
    assert read_image(tmp_path / "b" / "px.png").shape == (1024, 1024, 3)
    write_site(tmp_path / "c", faces, layout="list", tiles=True)
    assert read_image(tmp_path / "c" / "px.png").shape == (512, 512, 3)
    tour = tmp_path / "tour.json"
    tour.write_text(json.dumps({"scenes": [{"id": "a", "panorama": str(DATA_DIR / "rig" / "capture_pano_color.png")}]}))
    with pytest.raises(ValueError, match="face_size: 4200 px faces exceed"):
        write_tour_site(tmp_path / "t", tour, face_size=4200)
    eq = np.random.default_rng(0).integers(0, 255, (64, 128, 3)).astype(np.uint8)
    rolled = next(tour_views(eq, 4, width=32, height=24, roll_deg=30.0))
    assert np.array_equal(rolled, P.perspective(eq, yaw_deg=0.0, pitch_deg=0.0, roll_deg=30.0, fov_deg=90.0, width=32, height=24))
    assert not np.array_equal(rolled, next(tour_views(eq, 4, width=32, height=24)))
