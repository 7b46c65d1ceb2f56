"""Regenerate the bundled synthetic camera rig in ``samples/data/rig/`` (for ``ibr stitch``).

Run from the repository root::

    python samples/generate_rig.py            # writes samples/data/rig/ (about a minute on 2 cores)

Scene ``capture`` of :mod:`ibr.synth` (a hall around the capture point at the origin, objects from
0.5 m to 20 m). The rig is a ring of 8 outward cameras (radius 0.1 m, 256 x 256, 110 x 110
degrees) plus one camera looking straight up and one straight down, so the views cover the
whole sphere: ``rig_00.json`` .. ``rig_09.json`` (8-bit PNG colour, 3 x 3 supersampled; exact
planar depth EXR). ``rig.json`` lists the views; ``capture_pano_color.png`` and
``capture_pano_range.exr`` are the centre panorama (512 x 256 equirect colour and range) for
``ibr stitch --panorama``. Deterministic: the scene has no randomness.

Try::

    ibr stitch samples/data/rig/rig_*.json -o pano.png --width 2048
    ibr stitch samples/data/rig/rig_*.json -o ods.png --stereo ods --width 2048
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

SIZE, HFOV, RADIUS, SUPERSAMPLE, PANO_WIDTH = 256, 110.0, 0.1, 3, 512


def rig_cameras():
    """The 10 bundled rig cameras: ring of 8, then up and down."""
    from ibr.base.camera import Camera
    from panorama.stitch import ring_rig

    cams = ring_rig(8, radius=RADIUS, width=SIZE, height=SIZE, hfov_deg=HFOV)
    for pitch in (90.0, -90.0):
        c = ring_rig(1, radius=0.0, width=SIZE, height=SIZE, hfov_deg=HFOV, pitches_deg=(pitch,))[0]
        cams.append(Camera(c.fx, c.fy, c.cx, c.cy, c.width, c.height, c.world_from_cam))
    return cams


def main(argv=None) -> int:
    from ibr.base.view import View
    from ibr.io import atomic_path, save_view, write_depth, write_image
    from ibr.synth import make_scene, render
    from panorama.stitch import equirect_camera
    from panorama.synth import render_spherical

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=str(ROOT / "samples" / "data" / "rig"))
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    scene = make_scene("capture")
    names = []
    for i, cam in enumerate(rig_cameras()):
        v = render(scene, cam, supersample=SUPERSAMPLE, name=f"rig_{i:02d}")
        color = np.clip(np.rint(v.color * 255.0), 0, 255).astype(np.uint8)
        path = save_view(View(color, v.depth, cam, v.name), out / f"{v.name}.json")
        names.append(path.name)
        print(f"wrote {path}", file=sys.stderr)
    color, rng = render_spherical(scene, equirect_camera(PANO_WIDTH), supersample=SUPERSAMPLE)
    write_image(out / "capture_pano_color.png", np.clip(np.rint(color * 255.0), 0, 255).astype(np.uint8))
    write_depth(out / "capture_pano_range.exr", rng)
    doc = {"format": "ibr-rig", "version": 1, "scene": "capture", "center": [0.0, 0.0, 0.0], "views": names,
           "panorama": {"color": "capture_pano_color.png", "range": "capture_pano_range.exr", "width": PANO_WIDTH}}
    with atomic_path(out / "rig.json") as tmp:
        tmp.write_text(json.dumps(doc, indent=2) + "\n", encoding="utf-8")
    print(f"wrote {out / 'rig.json'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
