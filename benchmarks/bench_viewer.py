"""The web viewer with a large panorama (issue #18): time to the first picture and frame time per
view change, multires tiles beside whole faces, in headless Chromium with software GL.

    flock /tmp/ibr-bench.lock python benchmarks/bench_viewer.py            # 16384 x 8192
    python benchmarks/bench_viewer.py --quick                              # 4096 x 2048
    python benchmarks/bench_viewer.py --depth                              # mesh.bin bytes vs JPEG
    ibr bench viewer

Both sites hold the same panorama: ``tiles`` (512-px base faces first, then the 512-px tiles a
view needs, up to the panorama's own resolution: 8192-px faces, whose level is drawn as quads
beyond the 4096-px cube textures) and ``whole`` (six 4096-px faces, what the page loaded before
tiles). Time to first picture: page navigation until the page says it is ready (all its faces
decoded and uploaded, first frame drawn). Frame time: the median of 20 view changes (yaw + 1
degree, draw, read back one pixel so the frame is finished) at a 30 degree field of view, where the tiled site also fetches tiles.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parent / "tests"))
sys.path.insert(0, str(HERE))

from _timing import report  # noqa: E402

RESULTS = HERE / "results"
W, H = 800, 450


def panorama(width: int) -> np.ndarray:
    """A smooth uint8 equirect with fine detail (built row band by row band to stay small)."""
    h = width // 2
    out = np.empty((h, width, 3), np.uint8)
    lon = (np.arange(width) + 0.5) / width * 2 * np.pi - np.pi
    for r0 in range(0, h, 512):
        lat = (0.5 - (np.arange(r0, min(h, r0 + 512)) + 0.5) / h) * np.pi
        la, lo = np.meshgrid(lat, lon, indexing="ij")
        band = np.stack([0.5 + 0.4 * np.sin(300 * lo) * np.cos(200 * la), 0.5 + 0.4 * np.cos(7 * la),
                         0.5 + 0.3 * np.sin(5 * lo + 3 * la)], -1)
        out[r0:r0 + len(lat)] = np.rint(band * 255).astype(np.uint8)
    return out


def measure(site: Path, label: str, rows, fov: float = 30.0) -> None:
    from browser import DevTools
    from panorama.viewer import serve, site_url

    server = serve(site)
    profile = tempfile.mkdtemp(prefix="ibr-bench-chromium-")
    dt = DevTools.start(W, H, profile)
    try:
        dt.call("Page.enable")
        dt.call("Emulation.setDeviceMetricsOverride", width=W, height=H, deviceScaleFactor=1, mobile=False)
        t0 = time.perf_counter()
        dt.call("Page.navigate", url=site_url(server, hud=False, fov_deg=fov))
        dt.wait_for("document.title.includes('ready')", timeout=600)
        first = time.perf_counter() - t0
        ms = dt.eval("""(() => { const t = [], px = new Uint8Array(4);
            for (let i = 0; i < 20; i++) { const s = performance.now(); state.yaw += 1; draw();
                gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);  // waits for the frame
                t.push(performance.now() - s); }
            t.sort((a, b) => a - b); return t[10]; })()""")
        fetched = dt.eval("performance.getEntriesByType('resource').filter(e => /\\.png$/.test(e.name)).length")
        mb = dt.eval("performance.getEntriesByType('resource').filter(e => /\\.png$/.test(e.name))"
                     ".reduce((s, e) => s + (e.transferSize || e.encodedBodySize || 0), 0) / 1e6")
    finally:
        dt.close()
        server.shutdown()
        server.server_close()
        shutil.rmtree(profile, ignore_errors=True)
    rows.append((label, f"{fov:g}", f"{first:.2f} s", f"{ms:.1f} ms", f"{fetched} images, {mb:.1f} MB"))


def depth_bytes(widths=(1024, 2048, 4096)) -> None:
    """Bytes of a depth site's meshes (mesh.bin) against the panorama's JPEG (quality 90): the
    capture scene rendered at each width, faces of the site's default size."""
    import cv2

    from ibr.synth.scenes import make_scene
    from panorama.face_meshes import face_meshes, pack_face_meshes
    from panorama.synth import render_equirect
    from panorama.viewer import _pow2_face_size

    rows = []
    for w in widths:
        color, rng = render_equirect(make_scene("capture"), w, w // 2)
        color = np.rint(np.clip(color, 0, 1) * 255).astype(np.uint8)
        jpeg = cv2.imencode(".jpg", color[..., ::-1], [cv2.IMWRITE_JPEG_QUALITY, 90])[1]
        size = _pow2_face_size(w, 8, 2048)
        t = time.perf_counter()
        meshes = face_meshes(color, rng, face_size=size, head_box=0.1)
        t = time.perf_counter() - t
        quads, data = sum(map(len, meshes)), pack_face_meshes(meshes)
        rows.append((f"{w}x{w // 2}", f"{size}", f"{quads} ({quads / (6 * size * size) * 100:.2f} % of px)",
                     f"{len(data) / 1e3:.1f} kB", f"{len(jpeg) / 1e3:.1f} kB", f"{len(data) / len(jpeg):.2f}", f"{t:.1f} s"))
    report(rows, ("capture scene", "faces", "quads", "mesh.bin", "JPEG q90", "ratio", "meshing"),
           RESULTS / "viewer_depth.txt")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="a 4096 x 2048 panorama instead of 16384 x 8192")
    p.add_argument("--depth", action="store_true",
                   help="only the depth sites' mesh bytes against the panorama's JPEG (no browser)")
    args = p.parse_args(argv)
    if args.depth:
        depth_bytes()
        return 0
    from browser import chromium
    from ibr.io.view_files import read_json
    from panorama.viewer import write_site

    if chromium() is None:
        print("bench_viewer: headless Chromium not installed (apt-get install chromium); skipped")
        return 0
    width = 4096 if args.quick else 16384
    t0 = time.perf_counter()
    pano = panorama(width)
    rows = []
    with tempfile.TemporaryDirectory(prefix="ibr-bench-viewer-") as tmp:
        tiles, whole = Path(tmp) / "tiles", Path(tmp) / "whole"
        t = time.perf_counter()
        write_site(tiles, pano, tiles=True)
        t_tiles = time.perf_counter() - t
        face = 4096 if width >= 4096 * 3 else 2048
        t = time.perf_counter()
        write_site(whole, pano, face_size=face)
        t_whole = time.perf_counter() - t
        print(f"panorama {width}x{width // 2} built in {t - t0 - t_tiles:.1f} s; sites written: tiles "
              f"{t_tiles:.1f} s ({len(os.listdir(tiles))} files), whole faces {t_whole:.1f} s")
        top = read_json(tiles / "viewer.json", "viewer.json")["tiles"]["levels"][-1]
        measure(tiles, f"tiles (512-px base, then tiles up to {top}-px faces)", rows)
        measure(whole, f"whole faces ({face} px, loaded at once)", rows)
        if top > 4096:  # zoomed in far enough for the level finer than any cube texture: quad tiles
            measure(tiles, f"tiles, the {top}-px level drawn as quads", rows, fov=10.0)
    print(f"\n{width}x{width // 2} panorama, {W}x{H} page, headless Chromium (SwiftShader), "
          f"load {os.getloadavg()[0]:.2f}")
    report(rows, ("site", "fov", "first picture", "frame", "fetched"), RESULTS / "viewer.txt")
    return 0


if __name__ == "__main__":
    sys.exit(main())
