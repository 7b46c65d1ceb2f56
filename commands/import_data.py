"""``ibr import``: other tools' RGB-D data -> view files; ``ibr import export-nerf``: view files ->
transforms.json; ``ibr import blender --script``: the path of the script to run inside Blender.

Thin: parses, calls :mod:`ibr.io.importers`, writes through one
:class:`ibr.io.outputs.OutputPlan` (the output folder staged, nothing written on failure, never
onto an input), prints the report (frames written, dropped and why, ignored keys).
"""

from __future__ import annotations

from pathlib import Path

from ._common import info, positive_float

HELP = ("import RGB-D data from other tools (NeRF transforms.json, COLMAP, TUM RGB-D; Blender via a script) "
        "as view files, or export view files as transforms.json")


def _written_names(frames, sequence_name: str, out) -> tuple:
    """The exact file names an import owns in ``--out`` (escaped as glob patterns): each frame's
    view file, colour and depth, and the manifest. Only these are replaced there; a bare
    ``*.json`` pattern removed every JSON file of the folder, the user's own included (#12).

    The manifest is written for several frames; a one-frame import still owns an earlier import's
    manifest of that name (an ``ibr-sequence`` file, not a user's other JSON), which the commit
    then removes: it listed the earlier frames next to the new one (a stale sequence)."""
    import glob

    from ibr.io.importers.common import is_sequence_manifest

    manifest = f"{sequence_name}.json"
    owned = len(frames) > 1 or is_sequence_manifest(Path(out) / manifest)
    names = [manifest] if owned else []  # the manifest (write_views)
    for f in frames:
        names += [f"{f.name}.json", f"{f.name}_color.png", f"{f.name}_color.exr", f"{f.name}_depth.exr"]
    return tuple(glob.escape(n).replace("#", "[#]") for n in names)  # '#' in a pattern means digits


def add_arguments(parser) -> None:
    parser.add_argument("format", choices=("nerf", "colmap", "tum", "blender", "export-nerf"),
                        help="nerf: SRC is a transforms.json; colmap: SRC is the folder of cameras.txt and "
                        "images.txt; tum: SRC is a TUM RGB-D sequence folder; blender: see --script; "
                        "export-nerf: SRC are view files, --out the transforms.json to write")
    parser.add_argument("src", nargs="*", metavar="SRC")
    parser.add_argument("--out", help="folder for the view files (new, or only its view files are replaced); "
                        "for export-nerf the transforms.json file")
    parser.add_argument("--script", action="store_true",
                        help="blender: print the path of the script to run inside Blender "
                        "(blender -b scene.blend --python PATH -- --out DIR [--all-cameras] [--multilayer])")
    parser.add_argument("--images", help="colmap: the image folder (default: SRC/../images or SRC/../../images, "
                        "the first that exists: project/sparse or project/sparse/0 beside project/images)")
    parser.add_argument("--depth", help="colmap: folder of depth maps (NAME.geometric.bin or <stem>.exr/.png)")
    parser.add_argument("--depth-scale", type=positive_float, default=None,
                        help="scene units per stored depth unit (e.g. 0.001 for millimetre PNGs)")
    parser.add_argument("--intrinsics", type=float, nargs=4, metavar=("FX", "FY", "CX", "CY"),
                        help="tum: camera intrinsics in pixels (default the ROS set 525 525 319.5 239.5)")
    parser.add_argument("--tolerance", type=positive_float, default=None,
                        help="tum: max time difference (s) when associating colour, depth and poses (default 0.02)")
    parser.add_argument("--name", default=None, help="name of the sequence manifest (default: the format)")


#: The options (and SRC) each format uses; any other given is refused, naming it (they were
#: accepted and silently ignored: ``ibr import nerf ... --intrinsics 1 2 3 4``).
_USES = {"nerf": ("SRC", "--out", "--depth-scale", "--name"),
         "colmap": ("SRC", "--out", "--depth-scale", "--name", "--images", "--depth"),
         "tum": ("SRC", "--out", "--depth-scale", "--name", "--intrinsics", "--tolerance"),
         "blender": ("--script",),
         "export-nerf": ("SRC", "--out")}


def _check_options_apply(args) -> None:
    given = {"SRC": bool(args.src), "--out": args.out is not None, "--script": args.script,
             "--images": args.images is not None, "--depth": args.depth is not None,
             "--depth-scale": args.depth_scale is not None, "--intrinsics": args.intrinsics is not None,
             "--tolerance": args.tolerance is not None, "--name": args.name is not None}
    stray = [o for o, g in given.items() if g and o not in _USES[args.format]]
    if stray:
        where = [f"{o} ({', '.join(f for f, uses in _USES.items() if o in uses)} only)" for o in stray]
        raise ValueError(f"{', '.join(where)}: not used by `ibr import {args.format}`; remove "
                         f"{'it' if len(stray) == 1 else 'them'}")


def _export(args) -> int:
    from ibr.io.importers import export_nerf
    from ibr.io.importers.nerf import _expand
    from ibr.io.outputs import OutputPlan

    if not args.src:
        raise ValueError("SRC: export-nerf needs view files")
    if args.out is None:
        raise ValueError("--out: export-nerf needs the transforms.json to write")
    with OutputPlan("ibr import", log=info) as plan:
        for s in args.src:
            plan.add_input("SRC", s)
        for v in _expand(args.src):  # the views a sequence manifest lists are inputs too
            plan.add_input("SRC", v)
        out = plan.add_file("--out", args.out, (".json",))
        plan.check()
        notes = export_nerf(args.src, plan.stage(out), base=Path(args.out).resolve().parent)
        plan.commit()
    for note in notes:
        info(f"import: {note}")
    import json

    info(f"import: wrote {args.out} ({len(json.loads(Path(args.out).read_text())['frames'])} frames)")
    return 0


def run(args) -> int:
    from ibr.io.importers import blender_script_path, import_views, read_frames, write_views
    from ibr.io.importers.common import ImportReport, check_sequence_name
    from ibr.io.outputs import OutputPlan

    _check_options_apply(args)
    if args.format == "blender":
        if not args.script:
            raise ValueError("blender: renders are imported by the script run inside Blender; "
                             "`ibr import blender --script` prints its path")
        print(blender_script_path())
        return 0
    if args.format == "export-nerf":
        return _export(args)
    if len(args.src) != 1:
        raise ValueError(f"SRC: {args.format} takes one source, got {len(args.src)}")
    if args.out is None:
        raise ValueError("--out: the folder for the view files is required")
    report = ImportReport()
    options = {"depth_scale": args.depth_scale}
    if args.format == "colmap":  # messages name the options as the user wrote them
        options.update(images=args.images, depth=args.depth, labels={"images": "--images", "depth": "--depth"})
    if args.format == "tum":
        options.update(intrinsics=args.intrinsics, tolerance=0.02 if args.tolerance is None else args.tolerance)
    frames = read_frames(args.format, args.src[0], report=report, **options)  # every entry checked first
    with OutputPlan("ibr import", log=info) as plan:
        plan.add_input("SRC", args.src[0])
        for f in frames:
            plan.add_input("SRC", f.color)
            plan.add_input("SRC", f.depth)
        if len(frames) > 1:
            check_sequence_name(args.name or args.format, [f.name for f in frames])  # before any work
        folder = plan.add_folder("--out", args.out, _written_names(frames, args.name or args.format, args.out))
        plan.check()
        write_views(frames, plan.stage(folder), report, sequence_name=args.name or args.format,
                    progress=lambda k, n: info(f"import: {k}/{n} frames") if k == n or k % 10 == 0 else None)
        plan.commit()
    for line in report.lines():
        info(f"import: {line}")
    return 0
