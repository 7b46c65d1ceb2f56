"""``ibr warp``: render one RGB-D view from another camera (quad-mesh inverse warp)."""

from __future__ import annotations

HELP = "render one RGB-D view from another camera (target: a view file or a bare camera JSON)"


def add_arguments(parser) -> None:
    from commands._common import number_in

    parser.add_argument("view", metavar="VIEW.json", help="source view file (must have depth)")
    parser.add_argument("--to", required=True, metavar="CAMERA.json",
                        help="target camera: a view file (its camera; depth not needed) or a JSON camera "
                             "object {width, height, fx, fy, cx, cy, world_from_cam}")
    parser.add_argument("-o", "--output", required=True, metavar="OUT.png",
                        help="output color image (.png, .exr, .tif, .jpg); all outputs are checked before work "
                             "and renamed into place together at the end")
    parser.add_argument("--method", choices=("mesh", "forward"), default="mesh",
                        help="quad-mesh inverse warp (default) or per-pixel forward splat")
    parser.add_argument("--fill", choices=("inpaint", "none"), default="inpaint",
                        help="depth-aware background fill of the holes (default) or none")
    parser.add_argument("--interpolation", choices=("sharp", "linear", "cubic"), default="sharp",
                        help="colour reconstruction (default %(default)s: bilinear taps on the source upsampled "
                             "2x2 once; linear: plain bilinear, softer; cubic: bicubic, ~3x the frame time)")
    parser.add_argument("--supersample", type=number_in(1, 5, integer=True), choices=(1, 3, 5), default=1,
                        metavar="K",
                        help="K x K subsamples per pixel, box-filtered, from a source upsampled with sub-pixel "
                             "silhouettes (1, 3 or 5; default 1 = off; about K^2 the time)")
    parser.add_argument("--antialias", action="store_true",
                        help="anti-aliased silhouettes: pixels at depth edges are the mean of their centre and four "
                             "diagonal subsamples (+1.4 dB at clutter's edges for about 1.5x the frame time; "
                             "ibr.render.edge_antialias)")
    parser.add_argument("--depth-out", metavar="DEPTH.exr",
                        help="also write the rendered planar depth (.exr, .tif, .pfm)")
    parser.add_argument("--holes-out", metavar="HOLES.png", help="also write the hole mask (before filling; .png, .tif)")


def load_camera(path):
    """The target of ``--to``: a full View for a view file (so the result can be scored against
    its colour), else a Camera from a bare camera JSON (strict schema, :func:`ibr.io.load_camera`)."""
    import json
    from pathlib import Path

    from ibr.io import load_camera as _load_camera
    from ibr.io import load_view

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"--to: {path} does not exist")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"--to: {path} is not valid JSON ({exc})") from None
    if isinstance(doc, dict) and doc.get("format") == "ibr-view":
        return load_view(path)
    return _load_camera(path, what="--to")


def first_run_kernels(args):
    """The kernel modules this run compiles and the first-run helper's kind (None: the forward
    splat, no helper); :func:`cli.main` starts the helper with them before the command's imports."""
    if args.method != "mesh":
        return None
    from commands.interpolate import first_run_kernels as interpolate_kernels

    return interpolate_kernels(args)  # interpolate's


def run(args) -> int:
    import time
    from pathlib import Path

    import numpy as np

    from commands._common import (check_source_depth, holes_summary, image_for, info, invented, invented_warning,
                                  note_first_run)
    from commands.interpolate import _to_float
    from ibr.base.view import View
    from ibr.io import load_view, write_depth, write_image
    from ibr.io.outputs import IMAGE_EXTS, OutputPlan
    from ibr.sequence.metrics import psnr

    with OutputPlan("ibr warp", log=info) as plan:
        plan.add_view_input("VIEW", args.view)
        plan.add_view_input("--to", args.to)
        out = plan.add_file("-o", args.output, IMAGE_EXTS)
        depth_out = plan.add_file("--depth-out", args.depth_out, (".exr", ".tif", ".tiff", ".pfm"))
        holes_out = plan.add_file("--holes-out", args.holes_out, (".png", ".tif", ".tiff"))
        plan.check()  # every output checked before any work (#12)
        from ibr.render.view_synthesis import source_mesh, warp  # after cli.main started the helper

        view = load_view(args.view)
        if args.method == "mesh":  # (the forward splat of such a view is all holes, as the library's)
            check_source_depth("VIEW", args.view, view)
        target = load_camera(args.to)
        kernels = first_run_kernels(args)
        if kernels is not None:  # the inputs read: say that numba compiles (not before a view
            modules, warm = kernels  # without depth is refused)
            note_first_run(*modules, warm=warm, announce=view.depth is not None)
        if args.method == "mesh" and view.depth is not None and args.supersample == 1:
            t0 = time.perf_counter()
            mesh = source_mesh(view)
            info(f"mesh: {len(mesh)} quads in {(time.perf_counter() - t0) * 1e3:.1f} ms")
        t0 = time.perf_counter()
        result = warp(view, target, method=args.method, fill=args.fill, interpolation=args.interpolation,
                      supersample=args.supersample, antialias=args.antialias)
        dt = time.perf_counter() - t0
        line = f"warp: {dt * 1e3:.1f} ms, {holes_summary(result)}"
        if isinstance(target, View) and target.color.shape == result.color.shape and not result.holes.all():
            cov = ~result.holes  # the same PSNR as the whole image's (inf for an exact copy, was 200.00)
            covered_db = psnr(_to_float(result.color)[cov][None], _to_float(target.color)[cov][None])
            line += f", PSNR over covered pixels {covered_db:.2f} dB vs {Path(args.to).name}"
            if args.fill != "none":
                line += f" (whole image: {psnr(result.color, target.color):.2f} dB)"
        write_image(plan.stage(out), image_for(out, result.color))
        if depth_out:
            write_depth(plan.stage(depth_out), result.depth)
        if holes_out:
            write_image(plan.stage(holes_out), (result.holes * 255).astype(np.uint8))
        written = plan.commit()
    info(line)
    warning = invented_warning("warp", [("", *invented(result))],
                               hint="does the --to camera see what VIEW shows?")
    if warning:  # exit 0 all the same: the picture is written, mostly a guess
        info(warning)
    info(f"wrote {', '.join(map(str, written))}")
    return 0
