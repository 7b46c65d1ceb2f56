"""``ibr samples``: write the bundled sample views to a folder as view files.

Files are named ``<scene>_<view>.json`` (plus the color/depth files they reference); the
bundled ``manifest.json`` (scene pairs and ground-truth views) is copied alongside; the
Middlebury pair becomes ``motorcycle_left.json`` (disparity PFM with its calibration) and
``motorcycle_right.json`` (color and camera only). Existing files of the same names in the
output folder are replaced atomically; the bundled data folder itself is refused as output.
"""

from __future__ import annotations

HELP = "write the bundled sample views (synthetic scenes + Middlebury motorcycle) as view files"


def add_arguments(parser) -> None:
    parser.add_argument("--out", default="samples_out", metavar="DIR",
                        help="output folder, created if missing (default: %(default)s)")
    parser.add_argument("--no-middlebury", action="store_true",
                        help="skip the Middlebury motorcycle pair")


def run(args) -> int:
    from pathlib import Path

    from commands._common import info

    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out: {out} exists and is not a folder")
    from samples import DATA_DIR

    if out.resolve() == DATA_DIR.resolve():
        raise ValueError(f"--out: {out} is the bundled data folder itself; choose another folder")
    out.mkdir(parents=True, exist_ok=True)

    written = []
    bundled = bundled_view_files()
    if bundled:
        written += [copy_view_file(p, out) for p in bundled]
        manifest = bundled[0].parent / "manifest.json"
        if manifest.is_file():  # scene pairs and ground-truth views (written by samples/generate.py)
            import shutil

            from ibr.io import atomic_path

            with atomic_path(out / manifest.name) as tmp:
                shutil.copyfile(manifest, tmp)
    else:
        info("samples: no bundled synthetic views found in samples/data")
    if not args.no_middlebury:
        from ibr.io import save_view
        from ibr.io.middlebury import MOTORCYCLE_CALIBRATION as C
        from ibr.io.middlebury import motorcycle_views

        left, right = motorcycle_views()
        targets = [out / "motorcycle_left.json", out / "motorcycle_right.json"]
        params = {"baseline": C["baseline"], "focal_px": C["focal_px"], "doffs": C["doffs"]}
        written.append(save_view(left, targets[0], depth_name="motorcycle_left_disp.pfm",
                                 depth_encoding="disparity", depth_params=params))
        written.append(save_view(right, targets[1]))
    for path in written:
        info(f"wrote {path}")
    info(f"samples: {len(written)} view file(s) in {out}")
    return 0


def bundled_view_files():
    """The view files shipped in ``samples/data`` (JSON documents with format ``ibr-view``)."""
    import json

    from samples import DATA_DIR

    found = []
    for path in sorted(DATA_DIR.glob("*.json")) if DATA_DIR.is_dir() else []:
        try:
            doc = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            continue
        if isinstance(doc, dict) and doc.get("format") == "ibr-view":
            found.append(path)
    return found


def copy_view_file(src, out_dir):
    """Copy one view file and the color/depth files it references into ``out_dir``.

    The view is loaded first (so a broken bundled file fails loudly instead of being copied);
    referenced files keep their paths relative to the JSON, every copy is atomic, the JSON last.
    """
    import json
    import shutil
    from pathlib import Path

    from ibr.io import atomic_path, load_view

    src, out_dir = Path(src), Path(out_dir)
    load_view(src)  # validates files, sizes, camera and depth parameters
    doc = json.loads(src.read_text(encoding="utf-8"))
    refs = [doc["color"]] + ([doc["depth"]["path"]] if doc.get("depth") else [])
    for rel in refs:
        if Path(rel).is_absolute() or ".." in Path(rel).parts:
            raise ValueError(f"{src}: referenced file {rel!r} must be inside the sample folder")
        dst = out_dir / rel
        dst.parent.mkdir(parents=True, exist_ok=True)
        with atomic_path(dst) as tmp:
            shutil.copyfile(src.parent / rel, tmp)
    with atomic_path(out_dir / src.name) as tmp:
        shutil.copyfile(src, tmp)
    return out_dir / src.name
