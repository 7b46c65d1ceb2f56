"""``ibr stitch``: posed RGB-D views (or one RGB-D panorama) → mono or ODS stereo 360° panorama."""

from __future__ import annotations

from pathlib import Path

HELP = "stitch posed RGB-D views into a 360-degree panorama, mono or omnidirectional stereo (ODS)"

LAYOUTS = ("top-bottom", "sbs", "cube", "anaglyph")


def _even_width(text: str) -> int:
    """An argparse type: an even number of pixels in [2, 32768] (the equirect is width x width / 2)."""
    import argparse

    from commands._common import number_in

    value = number_in(2, 32768, integer=True, what="a number of pixels")(text)
    if value % 2:
        raise argparse.ArgumentTypeError(f"expected an even number of pixels (height = width / 2), got {text}")
    return value


def add_arguments(parser) -> None:
    from commands._common import positive_float

    parser.add_argument("views", nargs="*", metavar="VIEW.json",
                        help="posed RGB-D view files (each with depth and a world_from_cam pose); or one rig "
                             "file (rig.json, or its folder: its views, its centre as --center); or one "
                             "sequence per rig camera (manifest or folder of numbered views, all of one "
                             "length): frame k stitches view k of every sequence")
    parser.add_argument("--panorama", nargs=2, metavar=("COLOR", "RANGE"),
                        help="instead of views: one centre RGB-D panorama (equirect colour image and a float "
                             "range map, .exr/.tif/.pfm) -- for --stereo ods from a single capture")
    parser.add_argument("-o", "--output", required=True, metavar="PANO.png",
                        help="output colour (.png, .jpg, .exr, .tif); mono: the equirect (or a cubemap strip "
                             "with --layout cube); ODS: both eyes packed by --layout. With sequences: a "
                             "folder receiving pano_NNNN.png (and pano_NNNN_depth.exr)")
    parser.add_argument("--depth-out", metavar="DEPTH.exr",
                        help="depth output (range along each ray, packed like the colour; left over right for "
                             "anaglyph); default "
                             "<output stem>_depth.exr; 'none' to skip")
    parser.add_argument("--holes-out", metavar="HOLES.png", help="also write the hole mask (255 = no view saw it)")
    parser.add_argument("--width", type=_even_width, default=None,
                        help="equirect width per eye (even); default: the sources' own resolution (a --panorama's "
                             "width; for views 2 pi x their largest focal length in pixels, to a multiple of 4, at "
                             "most 8192)")
    parser.add_argument("--stereo", choices=("none", "ods"), default="none",
                        help="mono panorama (default) or omnidirectional stereo")
    parser.add_argument("--ipd", type=positive_float, default=None,
                        help="interpupillary distance in scene units (default 0.064, metres)")
    parser.add_argument("--fade", type=float, nargs=2, default=None, metavar=("START", "END"),
                        help="latitudes (deg) where the ODS eye baseline fades to 0 (default 60 80)")
    parser.add_argument("--layout", choices=("equirect",) + LAYOUTS, default=None,
                        help="ODS: top-bottom (left eye on top, default), sbs, cube, anaglyph; mono: equirect "
                             "(default) or cube (faces in a horizontal strip +x -x +y -y +z -z)")
    parser.add_argument("--fill", choices=("none", "background"), default="background",
                        help="pixels no view saw: background (default) fills disocclusions from the background "
                             "side and unseen regions such as a ring rig's poles smoothly; none leaves them "
                             "black; --holes-out always has the unfilled mask")
    parser.add_argument("--center", type=float, nargs=3, metavar=("X", "Y", "Z"),
                        help="capture point in the world frame (default: centroid of the view centres)")


def _check_args(args) -> None:
    if args.stereo != "ods":  # the eyes' options (were ignored for a mono panorama)
        given = [o for o, v in (("--ipd", args.ipd), ("--fade", args.fade)) if v is not None]
        if given:
            raise ValueError(f"{' / '.join(given)}: only used with --stereo ods (a mono panorama has no eyes)")
    args.ipd = 0.064 if args.ipd is None else args.ipd
    args.fade = (60.0, 80.0) if args.fade is None else args.fade
    a, b = args.fade  # (--width and --ipd are checked by their argparse types: usage errors)
    if not 0 < a < b <= 90:
        raise ValueError(f"--fade: expected 0 < START < END <= 90 (degrees of latitude), got {a:g} {b:g}")
    if bool(args.views) == bool(args.panorama):
        raise ValueError("VIEW.json / --panorama: give either view files or one --panorama COLOR RANGE")
    if args.panorama and args.stereo != "ods":
        raise ValueError("--panorama: a centre panorama is only an input for --stereo ods")
    if args.panorama and args.center is not None:  # was silently ignored: the eyes sit at the panorama's centre
        raise ValueError("--center: only used with view files; a --panorama is its own capture point")
    layout = args.layout
    if args.stereo == "none" and layout not in (None, "equirect", "cube"):
        raise ValueError(f"--layout: {layout} needs --stereo ods; a mono panorama is equirect or cube")
    if args.stereo == "ods" and layout == "equirect":
        raise ValueError("--layout: an ODS pair is packed top-bottom, sbs, cube or anaglyph, not equirect")
    if layout == "cube" and args.width is not None and args.width < 4:  # faces of width / 4 px (was "face_size ... 0" after the work)
        raise ValueError(f"--width: --layout cube makes faces of width / 4 pixels; expected >= 4, got {args.width}")


#: Widest default --width (2 pi x the views' focal length): a large photosphere, ~1 GB of work
#: arrays per eye; wider only when asked for.
MAX_DEFAULT_WIDTH = 8192


def _resolve_width(args, views, panorama) -> None:
    """Set ``args.width`` when it was not given: a --panorama's own width, or the views' angular
    resolution (2 pi x the largest focal length in pixels: one panorama pixel per source pixel at
    the centre of the sharpest view; a multiple of 4, so cube faces are whole), and say so."""
    import math

    from commands._common import info

    if args.width is not None:
        return
    if panorama is not None:
        args.width, why = int(panorama[0].shape[1]), "the --panorama's width"
    else:
        f = max(max(v.camera.fx, v.camera.fy) for v in views)
        native = max(4, 4 * math.ceil(2 * math.pi * f / 4))
        args.width = min(MAX_DEFAULT_WIDTH, native)
        why = f"2 pi x the views' focal length {f:.1f} px" + (f" is {native}: at most {MAX_DEFAULT_WIDTH} by default"
                                                              if native > MAX_DEFAULT_WIDTH else "")
    args.width += args.width % 2
    info(f"stitch: width {args.width} ({why}; --width to choose)")


def _expand_rig(args):
    """A rig file (``"format": "ibr-rig"``, or a folder holding ``rig.json``, as ``ibr samples``
    writes one) given as the only VIEW becomes its view files, and its capture point the default
    ``--center``. Returns the files the rig names besides its views (inputs never written over:
    the rig file, its centre panorama), or an empty list."""
    from panorama.stitch.rigs import RIG_FILE_NAME, is_rig_file, read_rig

    rigs = [v for v in args.views if is_rig_file(v)]
    if not rigs:
        return []
    if len(args.views) != 1:
        raise ValueError(f"VIEW.json: {rigs[0]} is a rig file; give it alone (its views are the rig's) or only "
                         "the view files")
    rig = read_rig(args.views[0])
    args.views = [str(v) for v in rig.views]
    if args.center is None:
        args.center = rig.center.tolist()
    path = Path(rigs[0])
    return [path / RIG_FILE_NAME if path.is_dir() else path, *(rig.panorama or ())]


def _strip(faces: dict):
    import numpy as np

    from panorama.directions import FACE_NAMES

    return np.concatenate([faces[n] for n in FACE_NAMES], axis=1)


def _stitch_frame(args, views, panorama, tick):
    """One panorama: ``(packed colour, depth, holes, share seen)`` as the options ask."""
    import numpy as np

    from panorama.convert import equirect_to_cubemap
    from panorama.stitch import equirect_camera, ods_from_panorama, ods_from_views, pack_ods, stitch_rgbd

    if args.stereo == "ods":
        kw = dict(ipd=args.ipd, fade_start_deg=args.fade[0], fade_end_deg=args.fade[1], fill=args.fill,
                  progress=tick)
        if panorama:
            pair = ods_from_panorama(*panorama, width=args.width, **kw)
        else:
            pair = ods_from_views(views, args.width, center=args.center, **kw)
        layout = args.layout or "top-bottom"
        packed = pack_ods(pair, layout)
        holes = [e.holes for e in pair.eyes]
        depth = [e.depth for e in pair.eyes]
        if layout == "cube":
            s = args.width // 4
            packed = np.concatenate([_strip(packed[0]), _strip(packed[1])], axis=0)
            depth = np.concatenate([_strip(equirect_to_cubemap(d, s, layout="dict", depth=True)) for d in depth], 0)
            holes = np.concatenate([_strip(equirect_to_cubemap(h.astype(np.uint8) * 255, s, layout="dict"))
                                    for h in holes], 0) > 127
        elif layout == "sbs":
            depth, holes = np.concatenate(depth, 1), np.concatenate(holes, 1)
        else:  # top-bottom, and anaglyph's masks/depths stacked left over right
            depth, holes = np.concatenate(depth, 0), np.concatenate(holes, 0)
        return packed, depth, holes, 1 - np.mean([e.holes.mean() for e in pair.eyes])
    center = args.center if args.center is not None else np.mean([v.camera.position for v in views], axis=0)
    res = stitch_rgbd(views, equirect_camera(args.width, center=center), progress=tick)
    if args.fill == "background":
        from panorama.stitch.fill import fill_stitched

        res = fill_stitched(res, views)
    packed, depth, holes = res.color, res.depth, res.holes
    if args.layout == "cube":
        s = args.width // 4
        packed = _strip(equirect_to_cubemap(packed, s, layout="dict"))
        depth = _strip(equirect_to_cubemap(depth, s, layout="dict", depth=True))
        holes = _strip(equirect_to_cubemap(holes.astype(np.uint8) * 255, s, layout="dict")) > 127
    return packed, depth, holes, 1 - holes.mean()


def _write(plan, out, dep, holes_out, packed, depth, holes) -> None:
    import numpy as np

    from commands._common import image_for
    from ibr.io import write_depth, write_image

    write_image(out, image_for(out, packed))
    if dep:
        write_depth(dep, depth.astype(np.float32))
    if holes_out:
        write_image(holes_out, holes.astype(np.uint8) * 255)


def _describe(args, n, seen, panorama) -> str:
    from commands._common import counted

    return (f"{f'{n} cube faces of the panorama' if panorama else counted(n, 'view')}, "
            f"{'ODS ' + (args.layout or 'top-bottom') if args.stereo == 'ods' else 'mono'}, "
            f"seen {seen:.2%} of the sphere (holes {1 - seen:.2%}{', filled' if args.fill != 'none' else ''})")


def first_run_kernels(args):
    """The kernel modules this run compiles and the first-run helper's kind (:func:`cli.main`
    starts the helper with them before the command's imports)."""
    modules = ("ibr.mesh._segment_kernels", "ibr.render._ray_kernels", "ibr.render._blend_kernels",
               "ibr.render._fill_kernels")
    return modules, "stitch-ods" if args.stereo == "ods" else "stitch"


def _run_sequences(args) -> int:
    """One rig camera per sequence: frame k stitches view k of every sequence into -o FOLDER."""
    from commands._common import info, note_first_run, progress
    from ibr.io import load_view
    from ibr.io.outputs import OutputPlan, number_width
    from ibr.sequence import load_sequence

    if args.panorama or args.holes_out or (args.depth_out not in (None, "none")):
        raise ValueError("VIEW.json: with sequences, -o is a folder of pano_NNNN.png (+ pano_NNNN_depth.exr "
                         "unless --depth-out none); --panorama, --holes-out and a --depth-out path do not apply")
    seqs = [load_sequence(p) for p in args.views]
    lengths = {len(s.views) for s in seqs}
    if len(lengths) != 1:
        raise ValueError(f"VIEW.json: every rig sequence needs the same number of frames, got "
                         f"{', '.join(f'{s.source}: {len(s.views)}' for s in seqs)}")
    frames = lengths.pop()
    depth = args.depth_out != "none"
    with OutputPlan("ibr stitch", log=info) as plan:
        for s in seqs:
            for v in s.views:
                plan.add_view_input("VIEW", v)
        folder = plan.add_folder("-o", args.output, ("pano_#.png",) + (("pano_#_depth.exr",) if depth else ()))
        plan.check()
        modules, warm = first_run_kernels(args)
        for k in progress(range(frames), frames, "stitch frames"):
            views = [load_view(s.views[k]) for s in seqs]
            _resolve_width(args, views, None)  # from the first frame's views, then kept
            note_first_run(*modules, warm=warm)  # the first inputs read: say that numba compiles (once)
            packed, z, holes, seen = _stitch_frame(args, views, None, None)
            name = f"pano_{k:0{number_width(frames)}d}"
            _write(plan, plan.stage(folder, f"{name}.png"),
                   plan.stage(folder, f"{name}_depth.exr") if depth else None, None, packed, z, holes)
        info(f"stitch: {frames} frames of {_describe(args, len(seqs), seen, False)} (last frame)")
        plan.commit()
    info(f"wrote {frames} panoramas to {Path(args.output)}/")
    return 0


def run(args) -> int:
    from pathlib import Path

    from commands._common import info, note_first_run, progress
    from ibr.io import load_view, read_depth, read_image
    from ibr.io.outputs import DEPTH_EXTS, IMAGE_EXTS, OutputPlan
    from ibr.sequence import is_sequence

    rig_files = _expand_rig(args)
    _check_args(args)
    if args.views and all(is_sequence(v) for v in args.views):
        return _run_sequences(args)
    out_path = Path(args.output)
    depth_arg = args.depth_out or str(out_path.with_name(out_path.stem + "_depth.exr"))
    with OutputPlan("ibr stitch", log=info) as plan:
        for path in rig_files:  # the rig file and the centre panorama it names
            plan.add_input("VIEW (rig)", path)
        for v in args.views:
            plan.add_view_input("VIEW", v)
        if args.panorama:
            plan.add_input("--panorama COLOR", args.panorama[0])
            plan.add_input("--panorama RANGE", args.panorama[1])
        out = plan.add_file("-o", args.output, IMAGE_EXTS)
        # float range: a 16-bit PNG would need a scale (it failed after the work)
        dep = None if depth_arg == "none" else plan.add_file("--depth-out", depth_arg,
                                                              tuple(e for e in DEPTH_EXTS if e != ".png"))
        holes_out = plan.add_file("--holes-out", args.holes_out, (".png", ".tif", ".tiff"))
        plan.check()  # every output checked before any work

        if args.panorama:
            from panorama.stitch import check_rgbd_panorama

            panorama = check_rgbd_panorama(read_image(args.panorama[0], what="--panorama COLOR"),
                                           read_depth(args.panorama[1], what="--panorama RANGE", name_channel=""),
                                           names=("--panorama COLOR", "--panorama RANGE"))
            views, n = None, 6
        else:
            panorama, views = None, [load_view(p) for p in args.views]
            n = len(views)
        _resolve_width(args, views, panorama)
        modules, warm = first_run_kernels(args)
        note_first_run(*modules, warm=warm)  # the inputs read: say that numba compiles
        steps = n * (2 if args.stereo == "ods" else 1)
        bar = progress(range(steps), steps, "stitch")
        next(bar)  # the bar prints step k when asked for item k + 1 (one step per rendered view)
        packed, depth, holes, seen = _stitch_frame(args, views, panorama, lambda i: next(bar, None))
        if not seen > 0:  # an all-black panorama is no result; nothing is written
            raise ValueError("no view sees any pixel of the panorama; check --center (and --ipd) against the "
                             "views' poses")
        info(f"stitch: {_describe(args, n, seen, panorama is not None)}")
        _write(plan, plan.stage(out), dep and plan.stage(dep), holes_out and plan.stage(holes_out), packed, depth,
               holes)
        written = plan.commit()
    info(f"wrote {', '.join(map(str, written))}")
    return 0
