"""``ibr stitch-photos``: overlapping photos from one spot -> equirect photosphere (+ cube faces).

Thin: parses, reads the photos, calls :func:`panorama.stitch_photos`, writes through one
:class:`ibr.io.outputs.OutputPlan` (every output checked before work, none on an input, nothing
written when stitching fails), prints the per-photo report table on stdout.
"""

from __future__ import annotations

from pathlib import Path

from ._common import image_side, info, nonnegative_float, nonnegative_int, positive_float

HELP = "stitch overlapping photos taken from one spot into an equirect photosphere (OpenCV pipeline)"


def _even_width(text: str) -> int:
    import argparse

    value = image_side(text)
    if value < 4 or value % 2:
        raise argparse.ArgumentTypeError(f"expected an even width >= 4 (height = width / 2), got {text}")
    return value


def add_arguments(parser) -> None:
    parser.add_argument("images", nargs="+", metavar="IMG", help="photos (any format ibr reads; a 4th "
                        "channel is used as a mask)")
    parser.add_argument("-o", "--output", required=True,
                        help="equirect image (.jpg/.png/.tif/.exr); uncovered pixels hold --fill")
    parser.add_argument("--width", type=_even_width, default=None,
                        help="equirect width (height = width/2; default: the photos' native "
                        "resolution, 2 pi x focal length, rounded up to 16)")
    parser.add_argument("--cube", default=None, metavar="FOLDER",
                        help="also write cube faces px nx py ny pz nz into FOLDER (same extension as -o)")
    parser.add_argument("--face-size", type=image_side, default=None,
                        help="cube face size (default ceil(width / pi))")
    parser.add_argument("--coverage", default=None, metavar="MASK.png",
                        help="also write the coverage mask (255 = covered by a photo)")
    parser.add_argument("--report", default=None, metavar="REPORT.json",
                        help="also write the report (cameras, used/dropped photos and why) as JSON")
    parser.add_argument("--focal", type=positive_float, default=None,
                        help="known focal length in pixels of the photos (then only rotations are estimated)")
    parser.add_argument("--detector", choices=("sift", "orb", "akaze"), default="sift")
    parser.add_argument("--exposure", choices=("gain", "channels", "none"), default="gain",
                        help="OpenCV exposure compensation (default gain)")
    parser.add_argument("--seam", choices=("gc_color", "gc_colorgrad", "dp_color", "voronoi", "none"),
                        default="gc_color", help="OpenCV seam finder (default graph cut on colour)")
    parser.add_argument("--bands", type=nonnegative_int, default=None,
                        help="multi-band blender levels (default OpenCV's rule for the output size)")
    parser.add_argument("--reference", type=nonnegative_int, default=0,
                        help="photo placed at longitude 0 (index in the list; default 0)")
    parser.add_argument("--keep-exposure-of", type=nonnegative_int, default=None, metavar="INDEX",
                        help="keep this photo's exposure (gain 1); default: gains near 1 on average")
    parser.add_argument("--conf", type=positive_float, default=1.0,
                        help="pair confidence that links two photos (OpenCV panoConfidenceThresh, default 1)")
    parser.add_argument("--fill", type=nonnegative_float, default=0.0,
                        help="value of uncovered pixels in output units (default 0 = black)")
    parser.add_argument("--no-level", action="store_true", help="skip wave correction (horizon levelling)")


def _report_dict(result) -> dict:
    import numpy as np

    def num(x):
        return None if not np.isfinite(x) else float(x)

    rep = result.report
    return {
        "format": "ibr.photo-stitch-report",
        "version": 1,
        "equirect": {"width": int(result.image.shape[1]), "height": int(result.image.shape[0]),
                     "covered_fraction": num(rep.covered_fraction),
                     "lon_range_deg": [num(v) for v in rep.lon_range_deg],
                     "lat_range_deg": [num(v) for v in rep.lat_range_deg]},
        "photos": [{"index": r.index, "name": r.name, "used": r.used, "reason": r.reason, "detail": r.detail,
                    "features": r.features, "yaw_deg": num(r.yaw_deg), "pitch_deg": num(r.pitch_deg),
                    "roll_deg": num(r.roll_deg), "gain": num(r.gain),
                    "camera": None if cam is None else cam.to_dict()}
                   for r, cam in zip(rep.images, result.cameras)],
        "notes": list(rep.notes),
        "seconds": {k: round(float(v), 4) for k, v in rep.seconds.items()},
    }


def run(args) -> int:
    import json
    import time

    import numpy as np

    import panorama
    from ibr.io import read_image, write_image
    from ibr.io.outputs import IMAGE_EXTS, JSON_EXTS, OutputPlan
    from commands._common import counted, face_file_patterns, image_for
    from panorama.files import write_cubemap

    out = Path(args.output)
    with OutputPlan("ibr stitch-photos", log=info) as plan:
        for k, p in enumerate(args.images):
            plan.add_input(f"IMG {k}", p)
        target = plan.add_file("-o", out, IMAGE_EXTS)
        cube = plan.add_folder("--cube", args.cube, face_file_patterns())
        cov = plan.add_file("--coverage", args.coverage, (".png", ".tif", ".tiff"))
        rep = plan.add_file("--report", args.report, JSON_EXTS)
        plan.check()  # every output checked before any work

        images = [read_image(p, what=f"IMG {k}") for k, p in enumerate(args.images)]
        names = [Path(p).name for p in args.images]
        if args.reference >= len(images):
            raise ValueError(f"--reference: expected a photo index 0..{len(images) - 1}, got {args.reference}")
        if args.keep_exposure_of is not None and args.keep_exposure_of >= len(images):
            raise ValueError(f"--keep-exposure-of: expected a photo index 0..{len(images) - 1}, "
                             f"got {args.keep_exposure_of}")
        start = time.perf_counter()

        def progress(step, done, total):
            if done == total:
                info(f"stitch-photos: {step} done ({time.perf_counter() - start:.1f}s)")

        info(f"stitch-photos: {counted(len(images), 'photo')}")
        result = panorama.stitch_photos(
            images, width=args.width, names=names, focal_px=args.focal, detector=args.detector,
            conf_thresh=args.conf, wave_correct=not args.no_level, reference=args.reference,
            exposure=args.exposure, exposure_reference=args.keep_exposure_of, seam=args.seam,
            bands=args.bands, fill=args.fill, progress=progress)
        print(result.report.table(), flush=True)
        pano = image_for(out, result.image)  # the dtype the format stores (EXR: float [0, 1] units)
        write_image(plan.stage(target), pano)
        if cube is not None:
            size = args.face_size or int(np.ceil(pano.shape[1] / np.pi))
            faces = panorama.equirect_to_cubemap(pano, size, layout="list")
            write_cubemap(plan.stage(cube), faces, layout="files", ext=out.suffix.lower())
        if cov is not None:
            write_image(plan.stage(cov), np.where(result.coverage, 255, 0).astype(np.uint8))
        if rep is not None:
            plan.stage(rep).write_text(json.dumps(_report_dict(result), indent=2) + "\n")
        plan.commit()
    h, w = result.image.shape[:2]
    info(f"stitch-photos: {len(result.report.used)} of {len(images)} photos -> {w}x{h} equirect {out}"
         + (f", cube faces in {Path(args.cube)}/" if args.cube else "")
         + f" ({time.perf_counter() - start:.1f}s); view it with: ibr view {out} --serve")
    _warn_most_dropped(len(result.report.used), len(images), args.focal)
    return 0


def _warn_most_dropped(used: int, total: int, focal) -> None:
    """Say loudly when fewer than half the photos made it into the photosphere (a wrong --focal
    removes every pair as a false match: one photo stitched, exit 0, and only the table said why)."""
    if total < 2 or 2 * used >= total:
        return
    hint = (f"; --focal {focal:g} may not be the photos' focal length in pixels: without it the focal length is "
            "estimated" if focal is not None else "; the table above says why each was left out")
    info(f"stitch-photos: WARNING: only {used} of {total} photos are in the photosphere{hint}")
