"""panorama.canvas: canvases in equirect/cubemap panoramas, picking there, the store, and the viewer
page's click-to-place UI driven in headless Chromium."""

from __future__ import annotations

import base64
import json
import shutil
import tempfile
import urllib.request
from pathlib import Path

import numpy as np
import pytest

from ibr.canvas import Canvas, camera_rays, canvas_from_image
from ibr.io import read_image, write_image
from ibr.synth import Box, ImageTexture, Rect, Scene, checker_texture
from ibr.synth.textures import _photo
from panorama.canvas import (canvases_from_store, composite_cubemap, composite_equirect, composite_perspective,
                             equirect_pixel_of, face_camera, load_store, pick_equirect, save_store,
                             serve_canvas_site, store_image_dir, store_path, view_camera, write_canvas_site)
from panorama.directions import equirect_directions
from panorama.synth import render_cubemap, render_equirect
from panorama.viewer import site_url, write_site


def psnr(a, b):
    return 10 * np.log10(1.0 / max(float(np.mean((np.asarray(a, float) - np.asarray(b, float)) ** 2)), 1e-30))


def truth_rect(canvas, image):
    w, h = canvas.size
    return Rect(ImageTexture(image, w), canvas.center, canvas.right, canvas.down, w / 2, h / 2, (-w / 2, -h / 2))


@pytest.fixture(scope="module")
def sphere_scene():
    img = _photo("coffee")[::2, ::2].copy()
    h, w = img.shape[:2]
    c = canvas_from_image(img, [1.0, -0.3, 2.0], [-0.4, 0.1, -1.0], [1.5, 1.5 * h / w], up=[0.1, -1, 0])
    room = Box(checker_texture(width_units=2.0), np.zeros(3), np.array([5.0, 3, 5]))
    box = Box(checker_texture(width_units=0.5), np.array([0.8, 0.2, 1.5]), np.array([0.15, 0.15, 0.15]))
    bg = Scene((room, box), ambient=1.0, diffuse=0.0)
    full = Scene((room, box, truth_rect(c, img)), ambient=1.0, diffuse=0.0)
    return c, bg, full


def test_equirect_composite_matches_the_ray_caster(sphere_scene):
    c, bg, full = sphere_scene
    truth, _ = render_equirect(full, 512, 256)
    base, rng = render_equirect(bg, 512, 256)
    hard = composite_equirect(base, [c], rng=rng, antialias=False)
    assert psnr(hard, truth) > 80  # same rays, same bilinear texels
    soft = composite_equirect(base, [c], rng=rng)
    assert psnr(soft, truth) > 40
    # occlusion: where the box is in front of the canvas, the panorama is untouched
    d = equirect_directions(512, 256).reshape(-1, 3)
    t, _ = c.intersect(np.zeros(3), d)
    hidden = (np.isfinite(t) & (rng.reshape(-1) < t - 0.05)).reshape(rng.shape)
    assert hidden.sum() > 20
    np.testing.assert_array_equal(soft[hidden], base[hidden])
    np.testing.assert_array_equal(hard[hidden], base[hidden])
    with pytest.raises(ValueError, match="2:1"):
        composite_equirect(base[:, :300], [c])


def test_cubemap_composite_matches_the_ray_caster(sphere_scene):
    c, bg, full = sphere_scene
    tc, _ = render_cubemap(full, 96)
    bc, bz = render_cubemap(bg, 96)
    hard = composite_cubemap(bc, [c], depth=bz, antialias=False)
    assert psnr(np.stack(hard), np.stack(tc)) > 80
    soft = composite_cubemap(bc, [c], depth=bz)
    assert psnr(np.stack(soft), np.stack(tc)) > 40
    assert face_camera(4, 96).fx == 48 and face_camera(4, 96).cx == 47.5


def test_equirect_pick_round_trip_and_misses():
    rng = np.random.default_rng(5)
    origin = np.array([0.1, -0.2, 0.05])
    worst = 0.0
    for _ in range(20):
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        c = Canvas(origin + d * rng.uniform(1, 4), -d + rng.normal(size=3) * 0.3, rng.uniform(0.3, 1.5, 2),
                   up=rng.normal(size=3), resolution=tuple(rng.integers(10, 1500, 2)))
        w, h = c.resolution
        for xy in np.stack([rng.uniform(-0.4, w - 0.6, 5), rng.uniform(-0.4, h - 0.6, 5)], -1):
            u, v = equirect_pixel_of(c.world_from_pixel(xy), 4096, 2048, origin=origin)
            p = pick_equirect(u, v, 4096, 2048, [c], origin=origin)
            worst = max(worst, float(np.abs(p.xy - xy).max()))
    assert worst < 1e-6
    c = Canvas((0, 0, 2), (0, 0, -1), (1, 1))
    assert pick_equirect(0, 0, 512, 256, [c]) is None  # looking up-back: a click on nothing
    rngmap = np.full((256, 512), 1.5, np.float32)  # a surface in front of the canvas everywhere
    assert pick_equirect(255.5, 127.5, 512, 256, [c]) is not None
    assert pick_equirect(255.5, 127.5, 512, 256, [c], rng=rngmap) is None


# ----------------------------------------------------------------------------- the store
def _board(**extra):
    e = {"kind": "strokes", "center": [0, 0, 2], "normal": [0, 0, -1], "up": [0, -1, 0], "size": [1, 0.5],
         "resolution": [64, 32], "strokes": [{"points": [[2, 2], [60, 30]], "width": 3, "color": "#00ff00"}]}
    e.update(extra)
    return e


def test_store_round_trip_and_refusals(tmp_path):
    pano = tmp_path / "room.png"
    assert store_path(pano) == tmp_path / "room.canvas.json"
    assert store_image_dir(store_path(pano)) == tmp_path / "room.canvas-images"
    assert load_store(store_path(pano)) == {"version": 1, "canvases": []}
    write_image(tmp_path / "poster.png", np.full((8, 16, 3), 200, np.uint8))
    doc = {"version": 1, "canvases": [_board(), {"kind": "image", "image": "poster.png", "center": [1, 0, 3],
                                                   "normal": [0, 0, -1], "up": [0, -1, 0], "size": [2, 1]}]}
    save_store(store_path(pano), doc)
    back = load_store(store_path(pano))
    assert back["canvases"][1]["image"] == "poster.png"
    canvases = canvases_from_store(back, tmp_path)
    assert canvases[0].rgba[..., 3].max() == 255 and canvases[0].rgba[16, 32, 1] == 255  # the green stroke
    assert canvases[1].resolution == (16, 8) and canvases[1].rgba[0, 0, 0] == 200
    bad = [
        ({"version": 1, "canvases": [_board(normal=[0, 0, 0])]}, "normal"),
        ({"version": 1, "canvases": [_board(size=[0, 1])]}, "size"),
        ({"version": 1, "canvases": [_board(up=[0, 0, 1])]}, "up: must not be parallel"),
        ({"version": 1, "canvases": [_board(colour="#fff")]}, "unknown key 'colour'"),
        ({"version": 1, "canvases": [{**_board(), "kind": "image", "image": "../x.png"}]}, "unknown key|relative"),
        ({"version": 2, "canvases": []}, "version"),
        ({"version": 1, "canvases": [_board(strokes=[{"points": []}])]}, "points"),
    ]
    for d, match in bad:
        with pytest.raises((ValueError, TypeError), match=match):
            save_store(tmp_path / "x.canvas.json", d)
    assert not (tmp_path / "x.canvas.json").exists()
    (tmp_path / "broken.canvas.json").write_text("{not json")
    with pytest.raises(ValueError, match="not valid JSON"):
        load_store(tmp_path / "broken.canvas.json")


def test_server_accepts_saves_and_serves_only_named_images(tmp_path):
    import cv2

    site = tmp_path / "site"
    write_site(site, np.full((32, 64, 3), 0.5, np.float32), face_size=8)
    write_canvas_site(site)
    (tmp_path / "secret.png").write_bytes(b"x")
    store = tmp_path / "room.canvas.json"
    server = serve_canvas_site(site, store)
    base = f"http://127.0.0.1:{server.server_address[1]}/"

    def post(path, body, ctype="application/json"):
        req = urllib.request.Request(base + path, data=body, method="POST", headers={"Content-Type": ctype})
        try:
            with urllib.request.urlopen(req, timeout=10) as r:
                return r.status, json.loads(r.read())
        except urllib.error.HTTPError as e:
            return e.code, json.loads(e.read())

    try:
        assert urllib.request.urlopen(base + "canvas.js", timeout=10).status == 200
        assert json.loads(urllib.request.urlopen(base + "canvas-store.json", timeout=10).read())["canvases"] == []
        ok, png = cv2.imencode(".png", np.zeros((4, 6, 3), np.uint8))
        code, body = post("canvas-images/pic-1.png", png.tobytes(), "image/png")
        assert code == 200 and body == {"image": "room.canvas-images/pic-1.png", "width": 6, "height": 4}
        entry = {"kind": "image", "image": body["image"], "center": [0, 0, 2], "normal": [0, 0, -1],
                 "up": [0, -1, 0], "size": [1, 1]}
        code, _ = post("canvas-store.json", json.dumps({"version": 1, "canvases": [entry, _board()]}).encode())
        assert code == 200 and len(load_store(store)["canvases"]) == 2
        assert urllib.request.urlopen(base + "canvas-files/room.canvas-images/pic-1.png", timeout=10).status == 200
        for path in ("canvas-files/secret.png", "canvas-files/../secret.png", "secret.png"):
            with pytest.raises(urllib.error.HTTPError):
                urllib.request.urlopen(base + path, timeout=10)
        assert post("canvas-images/evil.png", b"not an image")[0] == 400
        assert post("canvas-images/../x.png", png.tobytes())[0] in (400, 404)
        assert post("canvas-store.json", b"{bad")[0] == 400
        code, body = post("canvas-store.json", json.dumps({"version": 1, "canvases": [_board(normal=[0, 0, 0])]}).encode())
        assert code == 400 and "normal" in body["error"]
        missing = dict(entry, image="room.canvas-images/nope.png")
        assert post("canvas-store.json", json.dumps({"version": 1, "canvases": [missing]}).encode())[0] == 400
        assert len(load_store(store)["canvases"]) == 2  # refused saves leave the store as it was
    finally:
        server.shutdown()
        server.server_close()


# ----------------------------------------------------------------------------- headless Chromium
from browser import DevTools as _DevTools, chromium as _chromium  # noqa: E402


def _open(dt, url, w, h):
    dt.call("Page.enable")
    dt.call("Emulation.setDeviceMetricsOverride", width=w, height=h, deviceScaleFactor=1, mobile=False)
    dt.call("Page.navigate", url=url)
    dt.wait_for("document.title.includes('ready') && window.ibrCanvas && window.ibrCanvas.loaded", timeout=60)


def _mouse(dt, kind, x, y, buttons=1):
    dt.call("Input.dispatchMouseEvent", type=kind, x=x, y=y, button="left", buttons=buttons, clickCount=1)


@pytest.mark.skipif(_chromium() is None, reason="headless Chromium not installed (apt-get install chromium)")
def test_viewer_click_places_an_image_and_draws_strokes(tmp_path):
    """A person's clicks (real mouse events through the DevTools protocol): choose an image, click the
    photosphere to place it, switch to draw and drag a stroke; the store next to the panorama holds
    both, at the geometry the library computes for those pixels; a fresh page reloads them and
    shows what panorama.canvas.composite_perspective renders."""
    w, h = 400, 300
    view = dict(yaw_deg=20.0, pitch_deg=10.0, roll_deg=0.0, fov_deg=80.0)
    d = equirect_directions(256, 128)
    eq = np.stack([0.5 + 0.3 * np.sin(3 * d[..., 0] + d[..., 1]), 0.5 + 0.3 * d[..., 1],
                   0.5 + 0.3 * np.cos(2 * d[..., 2])], -1).astype(np.float32)
    pano = tmp_path / "room.png"
    write_image(pano, np.rint(eq * 255).astype(np.uint8))
    poster = tmp_path / "poster.png"
    yy, xx = np.mgrid[0:60, 0:90]
    write_image(poster, np.stack([xx * 2.8, yy * 4.2, 255 - xx * 2.8], -1).astype(np.uint8))
    site = tmp_path / "site"
    write_site(site, eq, face_size=64)
    write_canvas_site(site)
    store = store_path(pano)
    server = serve_canvas_site(site, store)
    profile = tempfile.mkdtemp(prefix="ibr-chromium-")
    dt = _DevTools([_chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
                    "--enable-unsafe-swiftshader", "--remote-debugging-pipe", f"--user-data-dir={profile}",
                    "--no-first-run", "--disable-background-networking", "--disable-component-update",
                    "--disable-sync", "--force-device-scale-factor=1", "--hide-scrollbars",
                    f"--window-size={w},{h}", "about:blank"])
    try:
        targets = dt.call("Target.getTargets")["targetInfos"]
        page = next(t for t in targets if t["type"] == "page")
        dt.session = dt.call("Target.attachToTarget", targetId=page["targetId"], flatten=True)["sessionId"]
        try:
            _open(dt, site_url(server, **view), w, h)
        except (TimeoutError, RuntimeError) as exc:
            pytest.skip(f"the viewer page did not come up in this Chromium ({exc})")
        # 1. choose the image (the toolbar's file input), then click where it goes
        root = dt.call("DOM.getDocument")["root"]["nodeId"]
        node = dt.call("DOM.querySelector", nodeId=root, selector="#canvas-file")["nodeId"]
        dt.call("DOM.setFileInputFiles", files=[str(poster)], nodeId=node)
        dt.wait_for("ibrCanvas.mode === 'image'")
        _mouse(dt, "mousePressed", 240, 120)
        _mouse(dt, "mouseReleased", 240, 120, buttons=0)
        dt.wait_for("ibrCanvas.saves >= 1 && ibrCanvas.saving === 0")
        # 2. draw: press on empty sky (a new board facing the viewer) and drag
        dt.call("Runtime.evaluate", expression="ibrCanvas.setMode('draw')")
        path = [(60, 200), (80, 210), (100, 222), (130, 230), (160, 232)]
        _mouse(dt, "mousePressed", *path[0])
        for x, y in path[1:]:
            _mouse(dt, "mouseMoved", x, y)
        _mouse(dt, "mouseReleased", *path[-1], buttons=0)
        dt.wait_for("ibrCanvas.saves >= 2 && ibrCanvas.saving === 0")

        doc = load_store(store)
        assert [e["kind"] for e in doc["canvases"]] == ["image", "strokes"]
        cam = view_camera(view["yaw_deg"], view["pitch_deg"], view["roll_deg"], view["fov_deg"], w, h)
        _, ray, _ = camera_rays(cam, [[239.5, 119.5]])  # pointer (240, 120) is pixel centre (239.5, 119.5)
        img = doc["canvases"][0]
        np.testing.assert_allclose(img["center"], 2.0 * ray[0], atol=1e-9)
        np.testing.assert_allclose(img["normal"], -ray[0], atol=1e-9)
        assert img["resolution"] == [90, 60] and (store_image_dir(store) / Path(img["image"]).name).is_file()
        canvases = canvases_from_store(doc, store.parent)
        board = doc["canvases"][1]
        pts = np.array(board["strokes"][0]["points"])
        assert len(pts) == len(path)
        uv, _ = cam.project(canvases[1].world_from_pixel(pts))
        np.testing.assert_allclose(uv, np.array(path) - 0.5, atol=1e-6)  # picked exactly where the pointer was

        # 3. a fresh page reloads the store and shows what the library renders
        _open(dt, site_url(server, hud=False, **view) + "&reload=1", w, h)
        dt.eval("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
        shot = base64.b64decode(dt.call("Page.captureScreenshot", format="png")["data"])
        (tmp_path / "shot.png").write_bytes(shot)
        got = read_image(tmp_path / "shot.png")[..., :3].astype(np.int16)
        faces = [read_image(site / f"{n}.png") for n in ("px", "nx", "py", "ny", "pz", "nz")]
        ref = composite_perspective(faces, canvases, width=w, height=h, **view).astype(np.int16)
        bare = composite_perspective(faces, [], width=w, height=h, **view).astype(np.int16)
        diff = np.abs(got - ref).max(-1)
        placed = np.abs(ref - bare).max(-1) > 30  # where the canvases show
        assert placed.sum() > 2000
        assert np.median(diff[placed]) <= 3 and np.percentile(diff, 99) <= 60
        assert np.abs(got - bare).max(-1)[placed].mean() > 5 * max(diff[placed].mean(), 1)
    finally:
        dt.close()
        server.shutdown()
        server.server_close()
        shutil.rmtree(profile, ignore_errors=True)


def test_only_a_canvas_site_asks_for_canvas_js(tmp_path):
    """A static viewer site (write_site, a tour site) has no canvas.js, so its page does not ask
    for it (a 404 on every load); write_canvas_site adds the script and the page's tag."""
    from panorama.viewer import CANVAS_SCRIPT_TAG

    site = tmp_path / "site"
    write_site(site, np.full((32, 64, 3), 0.5, np.float32), face_size=8)
    page = (site / "index.html").read_text(encoding="utf-8")
    assert "canvas.js" not in page and not (site / "canvas.js").exists()
    assert "</html>" in page and "viewer.json" in page  # the rest of the page is there
    write_canvas_site(site)
    assert CANVAS_SCRIPT_TAG in (site / "index.html").read_text(encoding="utf-8")
    assert (site / "canvas.js").is_file()
