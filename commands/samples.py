"""``ibr samples``: write the bundled sample views to a folder as view files.

Files are named ``<scene>_<view>.json`` (plus the color/depth files they reference); the
bundled ``manifest.json`` (scene pairs and ground-truth views) is copied alongside, the bundled
rig (``rig/``: ten posed views of the capture hall, ``rig.json`` and its centre panorama, the
input of ``ibr stitch``) into a ``rig`` subfolder; the Middlebury pair becomes ``motorcycle_left.json`` (disparity PFM with its calibration) and
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
    from commands._sequence import add_samples_arguments  # --sequence: a synthetic sequence (#15)

    add_samples_arguments(parser)


def _referenced_names(view_json):
    """The file names a bundled view file references (flat names in the sample folder)."""
    import json
    from pathlib import Path

    doc = json.loads(Path(view_json).read_text(encoding="utf-8"))
    refs = [doc["color"]] + ([doc["depth"]["path"]] if doc.get("depth") else [])
    for rel in refs:
        if Path(rel).name != rel:
            raise ValueError(f"{view_json}: referenced file {rel!r} must be a plain name inside the sample folder")
    return refs


def run(args) -> int:
    from pathlib import Path

    from commands._common import info
    from ibr.io.outputs import OutputPlan

    from samples import DATA_DIR

    out = Path(args.out)
    if out.resolve() == DATA_DIR.resolve():
        raise ValueError(f"--out: {out} is the bundled data folder itself; choose another folder")
    if DATA_DIR.resolve() in out.resolve().parents:
        raise ValueError(f"--out: {out} is inside the bundled data folder {DATA_DIR}; choose another folder")
    from commands._sequence import check_samples_sequence_unused, run_samples_sequence

    if args.sequence:  # a synthetic sequence with its exact up-converted frames (#15)
        return run_samples_sequence(args)
    check_samples_sequence_unused(args)
    if out.exists() and not out.is_dir():
        raise ValueError(f"--out: {out} exists and is not a folder")

    bundled = bundled_view_files()
    manifest = DATA_DIR / "manifest.json"
    names = []
    for p in bundled:
        names += [p.name] + _referenced_names(p)
    if bundled and manifest.is_file():
        names.append(manifest.name)
    mb = ["motorcycle_left.json", "motorcycle_left_color.png", "motorcycle_left_disp.pfm",
          "motorcycle_right.json", "motorcycle_right_color.png"]
    if not args.no_middlebury:
        names += mb
    rig_files = bundled_rig_files()
    with OutputPlan("ibr samples", log=info) as plan:
        plan.add_input("bundled samples", DATA_DIR)
        folder = plan.add_folder("--out", out, tuple(names))  # exactly the files this command writes
        rig_folder = plan.add_folder("--out", out / "rig", tuple(p.name for p in rig_files)) if rig_files else None
        plan.check()
        staged = plan.stage(folder)
        written = []
        if rig_folder is not None:
            written += [out / "rig" / p.name for p in copy_rig(rig_files, plan.stage(rig_folder))]
        if bundled:
            written += [out / copy_view_file(p, staged).name for p in bundled]
            if manifest.is_file():  # scene pairs and ground-truth views (written by samples/generate.py)
                import shutil

                shutil.copyfile(manifest, staged / manifest.name)
        else:
            info("samples: no bundled synthetic views found in samples/data")
        if not args.no_middlebury:
            from ibr.io import save_view
            from ibr.io.middlebury import MOTORCYCLE_CALIBRATION as C
            from ibr.io.middlebury import motorcycle_views

            left, right = motorcycle_views()
            params = {"baseline": C["baseline"], "focal_px": C["focal_px"], "doffs": C["doffs"]}
            save_view(left, staged / mb[0], color_name=mb[1], depth_name=mb[2], depth_encoding="disparity",
                      depth_params=params)
            save_view(right, staged / mb[3], color_name=mb[4])
            written += [out / mb[0], out / mb[3]]
        plan.commit()
    for path in written:
        info(f"wrote {path}")
    info(f"samples: {len(written)} view file(s) in {out}")
    return 0


def bundled_view_files():
    """The view files shipped in ``samples/data`` (JSON documents with format ``ibr-view``)."""
    from samples import DATA_DIR

    return [p for p in sorted(DATA_DIR.glob("*.json")) if _is_view_file(p)] if DATA_DIR.is_dir() else []


def _is_view_file(path) -> bool:
    """Whether ``path`` is a JSON document of format ``ibr-view``."""
    from ibr.io.view_files import VIEW_FORMAT, json_format

    return path.suffix == ".json" and json_format(path) == VIEW_FORMAT


def bundled_rig_files():
    """The files of the bundled rig folder ``samples/data/rig`` (none when it is missing)."""
    from samples import DATA_DIR

    rig = DATA_DIR / "rig"
    return sorted(p for p in rig.iterdir() if p.is_file()) if rig.is_dir() else []


def copy_rig(files, out_dir):
    """Copy the rig's files into ``out_dir``: view files through :func:`copy_view_file` (checked,
    with the images they name), the others (``rig.json``, the centre panorama) as they are.
    Returns the view files written (paths in ``out_dir``)."""
    import shutil
    from pathlib import Path

    from ibr.io import atomic_path

    copied, views = set(), []
    for p in files:
        if _is_view_file(p):
            views.append(copy_view_file(p, out_dir))
            copied.update([p.name] + _referenced_names(p))
    for p in files:
        if p.name not in copied:
            with atomic_path(Path(out_dir) / p.name) as tmp:
                shutil.copyfile(p, tmp)
    return views


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
