"""``ibr stitch``: posed RGB-D views (or one RGB-D panorama) → mono or ODS stereo 360° panorama."""

from __future__ import annotations

HELP = "stitch posed RGB-D views into a 360-degree panorama, mono or omnidirectional stereo (ODS)"

LAYOUTS = ("top-bottom", "sbs", "cube", "anaglyph")


def add_arguments(parser) -> None:
    parser.add_argument("views", nargs="*", metavar="VIEW.json",
                        help="posed RGB-D view files (each with depth and a world_from_cam pose)")
    parser.add_argument("--panorama", nargs=2, metavar=("COLOR", "RANGE"),
                        help="instead of views: one centre RGB-D panorama (equirect colour image and a float "
                             "range map, .exr/.tif/.pfm) -- for --stereo ods from a single capture")
    parser.add_argument("-o", "--output", required=True, metavar="PANO.png",
                        help="output colour (.png, .jpg, .exr, .tif); mono: the equirect (or a cubemap strip "
                             "with --layout cube); ODS: both eyes packed by --layout")
    parser.add_argument("--depth-out", metavar="DEPTH.exr",
                        help="depth output (range along each ray, packed like the colour; left over right for "
                             "anaglyph); default "
                             "<output stem>_depth.exr; 'none' to skip")
    parser.add_argument("--holes-out", metavar="HOLES.png", help="also write the hole mask (255 = no view saw it)")
    parser.add_argument("--width", type=int, default=4096, help="equirect width per eye (even; default 4096)")
    parser.add_argument("--stereo", choices=("none", "ods"), default="none",
                        help="mono panorama (default) or omnidirectional stereo")
    parser.add_argument("--ipd", type=float, default=0.064,
                        help="interpupillary distance in scene units (default 0.064, metres)")
    parser.add_argument("--fade", type=float, nargs=2, default=(60.0, 80.0), metavar=("START", "END"),
                        help="latitudes (deg) where the ODS eye baseline fades to 0 (default 60 80)")
    parser.add_argument("--layout", choices=("equirect",) + LAYOUTS, default=None,
                        help="ODS: top-bottom (left eye on top, default), sbs, cube, anaglyph; mono: equirect "
                             "(default) or cube (faces in a horizontal strip +x -x +y -y +z -z)")
    parser.add_argument("--fill", choices=("none", "background"), default=None,
                        help="fill pixels no view saw from the background side (default: none for views, "
                             "background for --panorama); --holes-out always has the unfilled mask")
    parser.add_argument("--center", type=float, nargs=3, metavar=("X", "Y", "Z"),
                        help="capture point in the world frame (default: centroid of the view centres)")


def _check_args(args) -> None:
    if args.width < 2 or args.width % 2 or args.width > 32768:
        raise ValueError(f"--width: expected an even number of pixels in [2, 32768], got {args.width}")
    if not args.ipd > 0:
        raise ValueError(f"--ipd: expected a positive interpupillary distance, got {args.ipd}")
    a, b = args.fade
    if not 0 < a < b <= 90:
        raise ValueError(f"--fade: expected 0 < START < END <= 90 (degrees of latitude), got {a:g} {b:g}")
    if bool(args.views) == bool(args.panorama):
        raise ValueError("VIEW.json / --panorama: give either view files or one --panorama COLOR RANGE")
    if args.panorama and args.stereo != "ods":
        raise ValueError("--panorama: a centre panorama is only an input for --stereo ods")
    layout = args.layout
    if args.stereo == "none" and layout not in (None, "equirect", "cube"):
        raise ValueError(f"--layout: {layout} needs --stereo ods; a mono panorama is equirect or cube")
    if args.stereo == "ods" and layout == "equirect":
        raise ValueError("--layout: an ODS pair is packed top-bottom, sbs, cube or anaglyph, not equirect")


def _strip(faces: dict):
    import numpy as np

    from panorama.directions import FACE_NAMES

    return np.concatenate([faces[n] for n in FACE_NAMES], axis=1)


def run(args) -> int:
    from pathlib import Path

    import numpy as np

    from commands._common import info, progress
    from commands.interpolate import _to_png
    from ibr.io import load_view, read_depth, read_image, write_depth, write_image
    from ibr.io.outputs import DEPTH_EXTS, IMAGE_EXTS, OutputPlan
    from panorama.convert import equirect_to_cubemap
    from panorama.stitch import equirect_camera, ods_from_panorama, ods_from_views, pack_ods, stitch_rgbd

    _check_args(args)
    out_path = Path(args.output)
    depth_arg = args.depth_out or str(out_path.with_name(out_path.stem + "_depth.exr"))
    with OutputPlan("ibr stitch", log=info) as plan:
        for v in args.views:
            plan.add_view_input("VIEW", v)
        if args.panorama:
            plan.add_input("--panorama COLOR", args.panorama[0])
            plan.add_input("--panorama RANGE", args.panorama[1])
        out = plan.add_file("-o", args.output, IMAGE_EXTS)
        dep = None if depth_arg == "none" else plan.add_file("--depth-out", depth_arg, DEPTH_EXTS)
        holes_out = plan.add_file("--holes-out", args.holes_out, (".png", ".tif", ".tiff"))
        plan.check()  # every output checked before any work

        if args.panorama:
            color = read_image(args.panorama[0], what="--panorama COLOR")
            rng = read_depth(args.panorama[1], what="--panorama RANGE")
            views, n = None, 6
        else:
            views = [load_view(p) for p in args.views]
            n = len(views)
        fill = args.fill or ("background" if args.panorama else "none")
        steps = n * (2 if args.stereo == "ods" else 1)
        bar = progress(range(steps), steps, "stitch")
        next(bar)  # the bar prints step k when asked for item k + 1 (one step per rendered view)
        tick = lambda i: next(bar, None)  # noqa: E731
        if args.stereo == "ods":
            kw = dict(ipd=args.ipd, fade_start_deg=args.fade[0], fade_end_deg=args.fade[1], fill=fill, progress=tick)
            if views is None:
                pair = ods_from_panorama(color, rng, width=args.width, **kw)
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
            saw = 1 - np.mean([e.holes.mean() for e in pair.eyes])
        else:
            center = args.center if args.center is not None else np.mean([v.camera.position for v in views], axis=0)
            res = stitch_rgbd(views, equirect_camera(args.width, center=center), progress=tick)
            packed, depth, holes = res.color, res.depth, res.holes
            if fill == "background" and holes.any():
                from ibr.render.fill import fill_background

                c3 = packed if packed.ndim == 3 else packed[..., None]
                packed, depth, _ = fill_background(c3, depth, holes)
            if args.layout == "cube":
                s = args.width // 4
                packed = _strip(equirect_to_cubemap(packed, s, layout="dict"))
                depth = _strip(equirect_to_cubemap(depth, s, layout="dict", depth=True))
                holes = _strip(equirect_to_cubemap(holes.astype(np.uint8) * 255, s, layout="dict")) > 127
            saw = 1 - holes.mean()
        info(f"stitch: {n} {'views' if views is not None else 'cube faces of the panorama'}, "
             f"{'ODS ' + (args.layout or 'top-bottom') if args.stereo == 'ods' else 'mono'}, "
             f"seen {saw:.2%} of the sphere (holes {1 - saw:.2%}{', filled' if fill != 'none' else ''})")
        if out.suffix.lower() in (".png", ".jpg", ".jpeg"):
            packed = _to_png(packed)
        elif packed.dtype == np.uint8 and out.suffix.lower() in (".exr", ".pfm"):
            packed = packed.astype(np.float32) / 255
        write_image(plan.stage(out), packed)
        if dep:
            write_depth(plan.stage(dep), depth.astype(np.float32))
        if holes_out:
            write_image(plan.stage(holes_out), holes.astype(np.uint8) * 255)
        written = plan.commit()
    info(f"wrote {', '.join(map(str, written))}")
    return 0
