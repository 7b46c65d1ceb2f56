"""Write docs/img/viewer_modes.png: the web viewer's modes, screenshot in headless Chromium.

    python docs/viewer_pictures.py          # about 30 s; needs chromium

One RGB-D panorama of the bundled ``capture`` scene (1024 x 512, its range map from the renderer)
is written as a depth site (``write_site(depth=...)``) and shown as: mono from the centre, after two
moves (parallax; black = disoccluded), red-cyan anaglyph and side by side
(two eyes from depth), and the WebXR headset view (through the tests' stand-in ``navigator.xr``,
left eye 5 cm to the right).
"""

from __future__ import annotations

import base64
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from browser import DevTools, screenshot  # noqa: E402
from ibr.io import read_image, write_image  # noqa: E402
from ibr.synth.scenes import make_scene  # noqa: E402
from panorama.synth import render_equirect  # noqa: E402
from panorama.viewer import serve, site_url, write_site  # noqa: E402
from test_viewer_xr import FAKE_XR  # noqa: E402

W, H = 480, 270


def _xr_shot(server, out: Path) -> np.ndarray:
    dt = DevTools.start(W, H, tempfile.mkdtemp(prefix="ibr-chromium-"))
    try:
        dt.call("Page.enable")
        dt.call("Emulation.setDeviceMetricsOverride", width=W, height=H, deviceScaleFactor=1, mobile=False)
        dt.call("Page.addScriptToEvaluateOnNewDocument", source=FAKE_XR)
        dt.call("Page.navigate", url=site_url(server, yaw_deg=30.0, hud=False))
        dt.wait_for("document.title.includes('ready')", timeout=60)
        dt.eval("window.ibrFakeXR.pose = {left: [0.05, 0, 0], right: [0.114, 0, 0]}")
        dt.eval("document.getElementById('vr').click()")
        dt.wait_for("(window.ibrXRFrames || 0) >= 3", timeout=60)
        out.write_bytes(base64.b64decode(dt.call("Page.captureScreenshot", format="png")["data"]))
    finally:
        dt.close()
    return read_image(out)[..., :3]


def main() -> None:
    color, rng = render_equirect(make_scene("capture"), 1024, 512, supersample=2)
    color = np.rint(np.clip(color, 0, 1) * 255).astype(np.uint8)
    tmp = Path(tempfile.mkdtemp(prefix="ibr-viewer-pictures-"))
    write_site(tmp / "site", color, depth=rng, head_box=0.1)
    server = serve(tmp / "site")
    view = dict(yaw_deg=30.0, fov_deg=90.0, hud=False)
    panels = [
        ("mono, from the centre", site_url(server, **view)),
        ("moved 8 cm right, 5 cm forward (parallax)", site_url(server, **view) + "&x=0.069&z=0.065"),
        ("moved 10 cm back, 3 cm up", site_url(server, **view) + "&z=-0.095&y=-0.03"),
        ("anaglyph (two eyes from depth)", site_url(server, mode="anaglyph", **view)),
        ("side by side (phone headsets)", site_url(server, mode="sbs", **view)),
    ]
    try:
        shots = [(label, screenshot(url, tmp / f"{i}.png", W, H).astype(np.uint8)) for i, (label, url) in enumerate(panels)]
        shots.append(("WebXR headset (stand-in runtime)", _xr_shot(server, tmp / "xr.png")))
    finally:
        server.shutdown()
        server.server_close()
    tiles = []
    for label, img in shots:
        img = np.ascontiguousarray(img)
        if label:
            cv2.rectangle(img, (0, 0), (8 * len(label) + 12, 22), (0, 0, 0), -1)
            cv2.putText(img, label, (6, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (255, 255, 255), 1, cv2.LINE_AA)
        tiles.append(cv2.copyMakeBorder(img, 2, 2, 2, 2, cv2.BORDER_CONSTANT, value=(255, 255, 255)))
    rows = [np.hstack(tiles[i:i + 2]) for i in range(0, 6, 2)]
    out = HERE / "img" / "viewer_modes.png"
    write_image(out, np.vstack(rows))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
