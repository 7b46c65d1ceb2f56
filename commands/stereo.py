"""``ibr stereo``: a stereo pair from one RGB-D view file, packed for a display.

The interaxial e and zero-parallax distance f are given (``--e --f``), or chosen from the view's
depth percentiles within a parallax visual-angle limit (``--auto``, the default; ``--f`` alone
picks the largest comfortable e for that f). ``--mode separate`` writes OUT with ``_left`` and
``_right`` inserted before the extension; the other modes write one image.
"""

from __future__ import annotations

HELP = "stereo pair from one RGB-D view: anaglyph, Dubois, side-by-side, top-bottom, interleaved, separate"

MODES = ("anaglyph", "dubois", "sbs", "sbs-half", "tb", "tb-half", "interleaved", "separate")


#: --max-angle's ceiling, degrees. The angle is the parallax the viewer sees on the screen;
#: comfortable stereo keeps it within about 1-2 degrees. Far past that the eyes cannot fuse the pair
#: and most of each eye is disocclusion (90 degrees left 60-70 % of the pixels filled in).
MAX_ANGLE_DEG = 10.0


def max_angle(text: str) -> float:
    """argparse type of --max-angle: 0 < DEG <= MAX_ANGLE_DEG (the ceiling's reason in the message)."""
    import argparse

    from commands._common import number_in

    try:
        return number_in(0, MAX_ANGLE_DEG, lo_open=True, what="an angle")(text)
    except argparse.ArgumentTypeError as exc:
        raise argparse.ArgumentTypeError(f"{exc} (degrees of on-screen parallax; comfortable stereo stays within "
                                         "1-2, past 10 the pair cannot be fused)") from None


def add_arguments(parser) -> None:
    from commands._common import nonnegative_float, number_in, positive_float

    parser.add_argument("view", metavar="VIEW.json", help="view file with color, depth and camera")
    parser.add_argument("--e", type=nonnegative_float, default=None, help="interaxial distance (scene units)")
    parser.add_argument("--f", type=positive_float, default=None, help="zero-parallax distance (scene units)")
    parser.add_argument("--auto", action="store_true", help="choose e and f from the depth (default)")
    parser.add_argument("--max-angle", type=max_angle, default=1.6, metavar="DEG",
                        help="parallax visual-angle limit for --auto and --f alone (with --e and --f: of the "
                        "comfort warning), degrees (0 < DEG <= 10: comfortable stereo stays within 1-2 "
                        "degrees, past 10 the pair cannot be fused; default: %(default)s)")
    parser.add_argument("--source", choices=("center", "left", "right"), default="center",
                        help="the input view is between the eyes (both new) or one eye (default: %(default)s)")
    parser.add_argument("--method", choices=("pixel", "mesh", "splat"), default="pixel",
                        help="pixel: seed 003 method 2 (fast); mesh: quad-mesh renderer (method 1)")
    parser.add_argument("--supersample", type=number_in(1, 5, integer=True), choices=(1, 3, 5), default=1,
                        metavar="K", help="with --method mesh: K x K subsamples per pixel from a view upsampled "
                                          "with sub-pixel silhouettes (1, 3 or 5; default 1 = off; about K^2 the time)")
    parser.add_argument("--interpolation", choices=("linear", "sharp"), default="linear",
                        help="with --method pixel: colour between row neighbours straight from one to the other "
                             "(default) or through their Lanczos-3 half-way sample (crisper eyes, about 1.3x the "
                             "time)")
    parser.add_argument("--mode", choices=MODES, default="anaglyph", help="output format (default: %(default)s)")
    parser.add_argument("--holes", action="store_true", help="also write the disocclusion masks (*_holes.png)")
    parser.add_argument("-o", "--out", required=True, metavar="OUT", help="output image (.png, .jpg, .tif, .exr); --mode separate writes OUT_left/OUT_right")
    from commands._sequence import add_stereo_arguments  # sequences: VIEW.json is a SEQ (#15)

    add_stereo_arguments(parser)


def _suffixed(path, tag):
    return path.with_name(f"{path.stem}_{tag}{path.suffix}")


def run(args) -> int:
    from pathlib import Path

    import numpy as np

    from commands._common import image_for, info
    from ibr.io import load_view, write_image
    from ibr.io.outputs import OutputPlan
    from ibr.stereo.pair import (check_stereo_interpolation, check_stereo_supersample, no_valid_depth_message,
                                 pack_stereo, stereo_pair)
    from ibr.stereo.stereo_camera import auto_stereo, comfort, max_interaxial_for_range
    from commands._sequence import is_sequence_argument, run_stereo  # sequences (#15)

    check_stereo_supersample(args.supersample, args.method)  # before any work, as the library says it
    check_stereo_interpolation(args.interpolation, args.method)

    if is_sequence_argument(args.view):
        if args.fps is not None and args.video is None:
            raise ValueError("--fps: only with --video (the video's frame rate)")
        return run_stereo(args)
    for opt, given in (("--video", args.video is not None), ("--fps", args.fps is not None)):
        if given:
            raise ValueError(f"{opt}: only used with a sequence (a manifest or a folder of numbered views), "
                             "not with one view file")
    if args.auto and (args.e is not None or args.f is not None):
        raise ValueError("--auto: give either --auto or --e/--f, not both")
    if args.e is not None and args.f is None:
        raise ValueError("--e: needs --f as well (or use --auto, or --f alone)")
    exts = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr")
    with OutputPlan("ibr stereo", log=info) as plan:
        plan.add_view_input("VIEW", args.view)
        out = Path(args.out)
        if args.mode == "separate":
            images = [plan.add_file(f"-o ({tag})", _suffixed(out, tag), exts) for tag in ("left", "right")]
        else:
            images = [plan.add_file("-o", out, exts)]
        holes = []
        if args.holes:
            holes = [plan.add_file(f"--holes ({tag})", _suffixed(out.with_suffix(".png"), f"{tag}_holes"),
                                   (".png",)) for tag in ("left", "right")]
        plan.check()  # every output checked before any work (#12)

        view = load_view(args.view)
        depth = view.require_depth("ibr stereo")
        valid = depth[np.isfinite(depth)]
        if valid.size == 0:
            raise ValueError(no_valid_depth_message(view, who=f"VIEW: {args.view}"))  # the file, not its 'name'
        z_near, z_far = np.percentile(valid, [1, 99])
        if args.f is None:
            e, f = auto_stereo(depth, max_angle_deg=args.max_angle)
            info(f"stereo: auto e = {e:.6g}, f = {f:.6g} (depth 1st-99th percentile {z_near:.4g}..{z_far:.4g})")
        else:
            f = args.f
            e = args.e if args.e is not None else max_interaxial_for_range(z_near, z_far, f,
                                                                            max_angle_deg=args.max_angle)
            info(f"stereo: e = {e:.6g}, f = {f:.6g}")
        rep = comfort(z_near, z_far, e=e, f=f, max_angle_deg=args.max_angle)
        info(f"stereo: parallax {rep.crossed_angle_deg:+.3f} .. {rep.uncrossed_angle_deg:+.3f} deg "
             f"(limit {rep.angle_limit_deg} deg); nearest >= f/2: {rep.nearest_ok}"
             + ("" if rep.ok else "  WARNING: outside the comfort limits"))
        pair = stereo_pair(view, e=e, f=f, source=args.source, method=args.method, supersample=args.supersample,
                           interpolation=args.interpolation)
        info(f"stereo: disocclusions filled: left {pair.left_holes.mean():.2%}, right {pair.right_holes.mean():.2%}")
        left, right = image_for(out, pair.left), image_for(out, pair.right)
        packed = pack_stereo(left, right, args.mode)
        for path, img in zip(images, packed if args.mode == "separate" else [packed]):
            write_image(plan.stage(path), img)
        for path, m in zip(holes, (pair.left_holes, pair.right_holes)):
            write_image(plan.stage(path), m.astype(np.uint8) * 255)
        written = plan.commit()
    for p in written:
        info(f"stereo: wrote {p}")
    return 0
