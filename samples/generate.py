"""Regenerate the bundled synthetic RGB-D samples in ``samples/data/``.

Run from the repository root::

    python samples/generate.py            # writes samples/data/ (about 1-2 minutes on 2 cores)
    python samples/generate.py --out DIR  # anywhere else

For each of the scenes room, clutter and grazing it writes the source pair ``<scene>_a.json`` and
``<scene>_b.json`` (``ibr.synth.scene_cameras``) and ground-truth intermediate views at
t = 0.25, 0.5, 0.75 (``ibr.interpolate_cameras(cam_a, cam_b, t)``) named ``<scene>_t025.json``,
``<scene>_t050.json``, ``<scene>_t075.json``. Each view file references an 8-bit PNG color image
(rendered with a 3x3 supersampling box filter) and a float32 EXR of exact planar depth (the
value at the pixel center, never supersampled). ``manifest.json`` lists the scenes, their pairs
and ground-truth views (schema in the README, section "Synthetic scenes and samples").
The scenes have no randomness, so the output is deterministic.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # allow `python samples/generate.py` without installing
    sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

SAMPLE_SCENES = ("room", "clutter", "grazing")
GROUND_TRUTH_T = (0.25, 0.5, 0.75)
WIDTH, HEIGHT, SUPERSAMPLE = 512, 384, 3
MANIFEST_VERSION = 1


def view_stem(scene: str, t: float) -> str:
    """File stem of a view: ``a`` for t = 0, ``b`` for t = 1, ``t025`` for t = 0.25."""
    if t == 0:
        return f"{scene}_a"
    if t == 1:
        return f"{scene}_b"
    return f"{scene}_t{int(round(t * 100)):03d}"


def quantize8(color: np.ndarray) -> np.ndarray:
    """float [0, 1] -> uint8 by rounding to nearest (the inverse is ``c / 255``)."""
    return np.clip(np.rint(color.astype(np.float64) * 255.0), 0, 255).astype(np.uint8)


def render_sample_view(scene_name: str, t: float, *, width=WIDTH, height=HEIGHT, supersample=SUPERSAMPLE):
    """The bundled view of ``scene_name`` at interpolation parameter ``t`` (color uint8)."""
    from ibr import interpolate_cameras
    from ibr.synth import make_scene, render, scene_cameras
    from ibr.base.view import View

    cam_a, cam_b = scene_cameras(scene_name, width=width, height=height)
    cam = cam_a if t == 0 else cam_b if t == 1 else interpolate_cameras(cam_a, cam_b, t)
    v = render(make_scene(scene_name), cam, supersample=supersample, name=view_stem(scene_name, t))
    return View(quantize8(v.color), v.depth, v.camera, v.name)


def contact_sheet(data_dir, png_path, *, thumb_width=208) -> Path:
    """Write a PNG contact sheet of the a/b views of each sample scene (one row per scene)."""
    import cv2

    from ibr.io import load_view, write_image

    rows = []
    for name in SAMPLE_SCENES:
        tiles = []
        for side in ("a", "b"):
            color = load_view(Path(data_dir) / f"{name}_{side}.json").color
            h = round(color.shape[0] * thumb_width / color.shape[1])
            tile = cv2.resize(color, (thumb_width, h), interpolation=cv2.INTER_AREA)
            cv2.putText(tile, f"{name} {side}", (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 3, cv2.LINE_AA)
            cv2.putText(tile, f"{name} {side}", (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
            tiles.append(tile)
        rows.append(np.concatenate(tiles, axis=1))
    write_image(png_path, np.concatenate(rows, axis=0))
    return Path(png_path)


def main(argv=None) -> int:
    from ibr.io import atomic_path, save_view
    from ibr.synth import SCENES

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", default=str(ROOT / "samples" / "data"), help="output folder (default samples/data)")
    ap.add_argument("--width", type=int, default=WIDTH)
    ap.add_argument("--height", type=int, default=HEIGHT)
    ap.add_argument("--supersample", type=int, default=SUPERSAMPLE)
    ap.add_argument("--sheet", metavar="PNG", help="also write a contact sheet of the a/b views")
    ap.add_argument("--sheet-only", action="store_true", help="only (re)write the contact sheet from --out")
    args = ap.parse_args(argv)
    out = Path(args.out)
    if args.sheet_only:
        if not args.sheet:
            ap.error("--sheet-only needs --sheet PNG")
        print(f"wrote {contact_sheet(out, args.sheet)}", file=sys.stderr)
        return 0
    out.mkdir(parents=True, exist_ok=True)

    manifest = {
        "format": "ibr-samples",
        "version": MANIFEST_VERSION,
        "generator": "samples/generate.py",
        "width": args.width,
        "height": args.height,
        "color": {"dtype": "uint8", "supersample": args.supersample},
        "depth": {"encoding": "z", "dtype": "float32", "sampling": "pixel center (exact)"},
        "scenes": {},
    }
    for name in SAMPLE_SCENES:
        entry = {"description": SCENES[name], "a": None, "b": None, "ground_truth": []}
        for t in (0.0, 1.0) + GROUND_TRUTH_T:
            view = render_sample_view(name, t, width=args.width, height=args.height,
                                      supersample=args.supersample)
            path = save_view(view, out / f"{view.name}.json")
            print(f"wrote {path}", file=sys.stderr)
            if t == 0:
                entry["a"] = path.name
            elif t == 1:
                entry["b"] = path.name
            else:
                entry["ground_truth"].append({"t": t, "view": path.name})
        manifest["scenes"][name] = entry
    with atomic_path(out / "manifest.json") as tmp:
        tmp.write_text(json.dumps(manifest, indent=2) + "\n", encoding="utf-8")
    print(f"wrote {out / 'manifest.json'}", file=sys.stderr)
    if args.sheet:
        print(f"wrote {contact_sheet(out, args.sheet)}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
