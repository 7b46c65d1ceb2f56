"""WebXR immersive-vr in the web viewer (issue #18, item 3), in headless Chromium with a stand-in
``navigator.xr``: a session whose two views have known projections and poses. Each eye's viewport
is compared with what the library renders for that eye."""

from __future__ import annotations

import base64
import json
import tempfile

import numpy as np
import pytest

import panorama as P
from ibr.io import read_image
from panorama.canvas import view_camera
from panorama.stitch import stitch_rgbd
from panorama.stitch.ods import panorama_views
from panorama.viewer import serve, site_url, write_site

from browser import DevTools, chromium
from test_stitch_viewer import _close, _eye
from test_viewer_depth import _psnr, capture  # noqa: F401 - the fixture

W, H = 640, 240  # two 320 x 240 eye viewports
YAW = 30.0

#: A headset as the WebXR API presents it: two views of 90 degrees across each half of the canvas,
#: eyes at window.ibrFakeXR.pose (metres, XR space: y up, -z forward), looking along -z.
FAKE_XR = """
(() => {
  const persp = (t, aspect) => {  // column-major GL projection, 90 degrees across when t = 1
    const n = 0.05, f = 100;
    return new Float32Array([1 / t, 0, 0, 0, 0, aspect / t, 0, 0, 0, 0, -(f + n) / (f - n), -1, 0, 0, -2 * f * n / (f - n), 0]);
  };
  const move = (p) => new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, p[0], p[1], p[2], 1]);
  const canvas = () => document.getElementById("view");
  const viewport = (eye) => { const c = canvas(), half = Math.floor(c.width / 2);
    return eye === "left" ? { x: 0, y: 0, width: half, height: c.height } : { x: half, y: 0, width: c.width - half, height: c.height }; };
  window.ibrFakeXR = { pose: { left: [-0.032, 0, 0], right: [0.032, 0, 0] }, sessions: 0 };
  const frame = { getViewerPose: () => ({ views: ["left", "right"].map((eye) => {
    const p = window.ibrFakeXR.pose[eye], vp = viewport(eye);
    return { eye, projectionMatrix: persp(1, vp.width / vp.height),
             transform: { matrix: move(p), inverse: { matrix: move(p.map((x) => -x)) } } };
  }) }) };
  const session = { ended: false, onend: [],
    updateRenderState(s) { this.renderState = s; },
    requestReferenceSpace: async (kind) => ({ kind }),
    requestAnimationFrame(cb) { if (!this.ended) setTimeout(() => cb(performance.now(), frame), 16); },
    addEventListener(type, f) { if (type === "end") this.onend.push(f); },
    end() { this.ended = true; this.onend.forEach((f) => f()); } };
  for (const C of [WebGLRenderingContext, window.WebGL2RenderingContext]) {  // no XR runtime to move to
    if (C) C.prototype.makeXRCompatible = async () => {};
  }
  window.XRWebGLLayer = class { constructor(s, gl) { this.framebuffer = null; } getViewport(view) { return viewport(view.eye); } };
  Object.defineProperty(navigator, "xr", { configurable: true, value: {
    isSessionSupported: async (mode) => mode === "immersive-vr",
    requestSession: async (mode) => { window.ibrFakeXR.sessions++; return session; } } });
})();
"""


def _xr_screenshot(site, tmp_path, pose=None) -> np.ndarray:
    """Open the site at YAW, enter VR through the page's button, return the canvas after a few
    XR frames as (H, W, 3) int16."""
    server = serve(site)
    dt = DevTools.start(W, H, tempfile.mkdtemp(prefix="ibr-chromium-", dir=tmp_path))
    try:
        dt.call("Page.enable")
        dt.call("Emulation.setDeviceMetricsOverride", width=W, height=H, deviceScaleFactor=1, mobile=False)
        dt.call("Page.addScriptToEvaluateOnNewDocument", source=FAKE_XR)
        dt.call("Page.navigate", url=site_url(server, yaw_deg=YAW, fov_deg=90.0))
        dt.wait_for("document.title.includes('ready')", timeout=60)
        dt.wait_for("getComputedStyle(document.getElementById('vr')).display === 'block'")  # offered
        if pose:
            dt.eval(f"window.ibrFakeXR.pose = {json.dumps(pose)}")
        dt.eval("document.getElementById('vr').click()")
        dt.wait_for("(window.ibrXRFrames || 0) >= 3", timeout=60)
        assert dt.eval("window.ibrFakeXR.sessions") == 1
        dt.eval("document.getElementById('hud').style.display = 'none'; "
                "document.querySelectorAll('.ctl, #mode').forEach((b) => b.style.display = 'none')")
        shot = base64.b64decode(dt.call("Page.captureScreenshot", format="png")["data"])
    finally:
        dt.close()
        server.shutdown()
        server.server_close()
    (tmp_path / "xr.png").write_bytes(shot)
    return read_image(tmp_path / "xr.png")[..., :3].astype(np.int16)


pytestmark = pytest.mark.skipif(chromium() is None, reason="headless Chromium not installed (apt-get install chromium)")


def test_a_stereo_panorama_shows_each_eye_in_the_headset(tmp_path):
    """Left viewport = panorama.perspective of the left eye's panorama at the view the session
    started from (yaw 30), right viewport = the right eye's: the eyes are not swapped or mixed."""
    left, right = _eye(0.0), _eye(0.25)
    site = tmp_path / "site"
    write_site(site, np.concatenate([left, right], axis=0), stereo="top-bottom", face_size=256)
    shot = _xr_screenshot(site, tmp_path)
    view = dict(yaw_deg=YAW, pitch_deg=0.0, fov_deg=90.0, width=W // 2, height=H)
    faces = {s: [read_image(site / f"{n}{s}.png") for n in ("px", "nx", "py", "ny", "pz", "nz")] for s in ("", "_r")}
    ref_l, ref_r = P.perspective(faces[""], **view), P.perspective(faces["_r"], **view)
    assert _close(shot[:, : W // 2], ref_l) and _close(shot[:, W // 2:], ref_r)
    assert not _close(shot[:, : W // 2], ref_r)  # the two eyes differ enough to tell


def test_a_depth_panorama_follows_the_head_position(tmp_path, capture):  # noqa: F811 - the fixture
    """With a depth site the headset's position moves the viewpoint: the left eye 5 cm to the
    right (XR +x) matches the engine's warp of the RGB-D panorama to that camera (>= 30 dB over
    covered pixels); XR +x is the world's right of the starting yaw."""
    color, rng = capture
    site = tmp_path / "site"
    write_site(site, color, depth=rng, head_box=0.1)
    shot = _xr_screenshot(site, tmp_path, pose={"left": [0.05, 0, 0], "right": [0.0, 0, 0]})
    size = read_image(site / "pz.png").shape[0]
    views = panorama_views(color, rng, face_size=size)
    y = np.radians(YAW)
    for half, at in ((shot[:, : W // 2], (0.05 * np.cos(y), 0.0, -0.05 * np.sin(y))), (shot[:, W // 2:], (0, 0, 0))):
        ref = stitch_rgbd(views, view_camera(YAW, 0.0, 0.0, 90.0, W // 2, H, origin=at))
        covered = ~ref.holes
        assert covered.mean() > 0.95 and _psnr(half[covered], ref.color[covered]) >= 30
