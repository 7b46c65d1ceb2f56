"""``ibr distort``: radial lens pre-distortion of an image (seed 001 eq. 7.16), or its inverse.

The normalized radius is the distance from the lens center divided by ``--scale`` pixels
(default: half the image width; pixel centers at integers, default center ((W-1)/2, (H-1)/2)).
Without ``--inverse`` output pixel at radius r shows the input at f(r) = r + c1 r^3 + c2 r^5 (what
to display so that the lens shows the input undistorted); ``--inverse`` undoes that with the
exact (Newton) inverse. ``--sbs`` treats the image as a side-by-side stereo pair with per-eye
lens centers.
"""

from __future__ import annotations

HELP = "radial lens pre-distortion (c1, c2; per-channel for chromatic aberration) or its inverse"


def add_arguments(parser) -> None:
    from commands._common import finite_float, positive_float

    parser.add_argument("image", metavar="IMAGE", help="input image")
    parser.add_argument("--c1", type=finite_float, required=True, help="cubic coefficient (> 0 pincushion lens)")
    parser.add_argument("--c2", type=finite_float, default=0.0, help="quintic coefficient (default: 0)")
    parser.add_argument("--inverse", action="store_true", help="undo the pre-distortion (exact inverse)")
    parser.add_argument("--r-max", type=positive_float, default=1.5, help="lens range in normalized radius (default: 1.5)")
    parser.add_argument("--scale", type=positive_float, default=None, metavar="PX",
                        help="pixels per unit normalized radius (default: half the eye image width)")
    parser.add_argument("--center", type=finite_float, nargs=2, default=None, metavar=("U", "V"),
                        help="lens center in pixels (default: image center)")
    parser.add_argument("--chromatic", type=positive_float, nargs=2, default=None, metavar=("RED", "BLUE"),
                        help="scale c1, c2 by these factors for the red and blue channels (green uses c1, c2)")
    parser.add_argument("--sbs", action="store_true", help="side-by-side stereo input: each half is one eye")
    parser.add_argument("--centers", type=finite_float, nargs=4, default=None, metavar=("UL", "VL", "UR", "VR"),
                        help="--sbs: lens centers in each eye image's pixels")
    parser.add_argument("-o", "--out", required=True, metavar="OUT",
                        help="output image (.png, .jpg, .tif, .exr, .pfm; the input's dtype must fit)")


def run(args) -> int:
    import numpy as np

    from commands._common import info
    from ibr.io import read_image, write_image
    from ibr.io.images import check_write_dtype
    from ibr.io.outputs import IMAGE_EXTS, OutputPlan
    from ibr.stereo.lens import RadialDistortion, predistort, predistort_stereo

    if args.centers is not None and not args.sbs:
        raise ValueError("--centers: only with --sbs (use --center for one image)")
    if args.center is not None and args.sbs:  # was silently ignored: each eye used its image centre
        raise ValueError("--center: not with --sbs (give each eye's lens centre with --centers UL VL UR VR)")
    with OutputPlan("ibr distort", log=info) as plan:
        plan.add_input("IMAGE", args.image)
        out = plan.add_file("-o", args.out, IMAGE_EXTS)
        plan.check()  # every output checked before any work (#12)
        lens = RadialDistortion(args.c1, args.c2, args.r_max)
        if args.chromatic is not None:
            kr, kb = args.chromatic
            lens = (RadialDistortion(args.c1 * kr, args.c2 * kr, args.r_max), lens,
                    RadialDistortion(args.c1 * kb, args.c2 * kb, args.r_max))
        img = read_image(args.image)
        check_write_dtype("-o", out, img.dtype)  # the output keeps the dtype: refused before the work
        from ibr.stereo.lens import _check_center

        if args.center is not None or args.centers is not None:  # the option's name, not 'center_px'
            eye_w = img.shape[1] // 2 if args.sbs else img.shape[1]
            for c in ([args.center] if args.center is not None else [args.centers[:2], args.centers[2:]]):
                _check_center(c, eye_w, img.shape[0], name="--centers" if args.sbs else "--center")
        if args.sbs:
            w = img.shape[1]
            if w % 2:
                raise ValueError(f"IMAGE: --sbs needs an even width, got {w}")
            centers = None if args.centers is None else np.array(args.centers).reshape(2, 2)
            left, right = predistort_stereo(img[:, : w // 2], img[:, w // 2 :], lens, centers_px=centers,
                                            scale_px=args.scale, inverse=args.inverse)
            result = np.concatenate([left, right], axis=1)
        else:
            result = predistort(img, lens, center_px=args.center, scale_px=args.scale, inverse=args.inverse)
        write_image(plan.stage(out), result)
        plan.commit()
    info(f"distort: {'inverse' if args.inverse else 'pre-distortion'} c1={args.c1}, c2={args.c2} -> {out}")
    return 0
