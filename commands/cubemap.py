"""``ibr cubemap``: equirectangular image <-> cube faces in a chosen layout (color or depth)."""

from __future__ import annotations

import math
from pathlib import Path

from ._common import image_side, info

HELP = "convert an equirectangular panorama to cube faces (any layout) and back; color or depth"

_LAYOUTS = ("dice", "horizon", "vstrip", "files", "hstrip", "exr", "cross", "hcross")


def add_arguments(parser) -> None:
    parser.add_argument("input", help="equirect image (2:1), cubemap image (6:1 horizon, 1:6 vstrip, "
                        "4:3 dice with empty corner cells) or a folder of px/nx/py/ny/pz/nz face files")
    parser.add_argument("-o", "--output", required=True,
                        help="output image (extension picks the format: .png 8/16-bit, .tif, .exr "
                        "float) or, for --layout files, a folder (face files of an earlier run there "
                        "are replaced, other files left alone)")
    parser.add_argument("--layout", choices=_LAYOUTS, default=None,
                        help="cube layout of the output (default: files if OUTPUT has no "
                        "extension, else dice)")
    parser.add_argument("--input-layout", default=None,
                        choices=("equirect",) + _LAYOUTS[:3] + _LAYOUTS[4:],
                        help="layout of INPUT (default: from its shape; folders are face files)")
    parser.add_argument("--face-size", type=image_side, default=None,
                        help="face edge in pixels (default: ceil(width / pi), full resolution at "
                        "the face centres)")
    parser.add_argument("--width", type=image_side, default=None,
                        help="equirect width when converting back (default 4 x face size); height "
                        "is width / 2")
    parser.add_argument("--depth", action="store_true",
                        help="INPUT is depth: equirect range along the ray <-> planar z per face "
                        "(float EXR/TIFF/PFM)")
    parser.add_argument("--interpolation", choices=("linear", "nearest"), default=None,
                        help="default linear for color, nearest for depth")
    parser.add_argument("--ext", default=".png", help="face file extension for --layout files "
                        "(default .png; use .exr for float or depth)")


def _read(args):
    from commands._common import read_panorama_arg

    return read_panorama_arg(args.input, args.input_layout, "--input-layout")


def _not_depth(pano, path) -> str | None:
    """Why INPUT is no depth / range map for --depth (one float channel), or None."""
    img = pano[0] if isinstance(pano, list) else pano
    channels = 1 if img.ndim == 2 else img.shape[2]
    if img.dtype.kind == "f" and channels == 1:
        return None
    bits = "float" if img.dtype.kind == "f" else f"{8 * img.dtype.itemsize}-bit"
    return (f"INPUT: {path} is not a depth/range map but {'an' if bits[0] == '8' else 'a'} {bits} "
            f"{'grey' if channels == 1 else 'colour'} "
            f"image; --depth needs one float channel (EXR/TIFF/PFM)")


def _note_looks_like_depth(pano, path) -> None:
    """Say so when INPUT, converted as an image, looks like a depth or range map (one float
    channel beyond [0, 1], the test of :func:`ibr.io.images.check_unit_colour`): without --depth
    it is resampled as colour, not converted."""
    from commands._common import info
    from ibr.io.images import _depth_like

    got = _depth_like(pano[0] if isinstance(pano, list) else pano)
    if got is not None:
        info(f"cubemap: {path} is one float channel of median {got[2]:.3g} (a depth or range map?): converted as "
             "an image; add --depth to turn range into each face's planar depth")


def run(args) -> int:
    import panorama
    from ibr.io import write_image
    from ibr.io.outputs import IMAGE_EXTS, OutputPlan
    from commands._common import face_file_patterns, image_for
    from panorama.directions import FACE_FILE_NAMES
    from panorama.files import FACE_EXTS, write_cubemap

    out = Path(args.output)
    ext = args.ext if args.ext.startswith(".") else "." + args.ext
    if ext.lower() not in FACE_EXTS:
        raise ValueError(f"--ext: expected one of {', '.join(FACE_EXTS)}, got {args.ext!r}")
    float_exts = (".exr", ".tif", ".tiff", ".pfm")
    with OutputPlan("ibr cubemap", log=info) as plan:
        plan.add_input("INPUT", args.input)
        # the layout of the output is known before reading: folder of faces or one image
        files_out = args.layout == "files" or (args.layout is None and out.suffix == "")
        if not files_out and args.ext != ".png":
            raise ValueError(f"--ext: only used for a folder of face files (--layout files or -o without an "
                             f"extension); {out.name} is one image, its extension chooses the format")
        if args.depth and (ext if files_out else out.suffix).lower() not in float_exts:
            why = _not_depth(_read(args)[0], args.input)  # the input is the mistake, if it is no depth map
            if why:
                raise ValueError(why)
            raise ValueError(f"{'--ext' if files_out else '-o'}: depth is float; use one of {', '.join(float_exts)}, "
                             f"got {ext if files_out else out.name}")
        if files_out:
            target = plan.add_folder("-o", out, face_file_patterns(ext))
        else:
            target = plan.add_file("-o", out, IMAGE_EXTS)
        plan.check()  # every output checked before any work (#12)

        pano, in_layout = _read(args)
        why = _not_depth(pano, args.input) if args.depth else None
        if why:
            raise ValueError(why)
        if not args.depth:
            _note_looks_like_depth(pano, args.input)
        if in_layout == "equirect":
            if args.width is not None:
                raise ValueError("--width: only used when converting a cubemap back to equirect; INPUT is "
                                 "equirect (the faces' size is --face-size)")
            h, w = pano.shape[:2]
            size = args.face_size if args.face_size is not None else math.ceil(w / math.pi)
            layout = args.layout or ("files" if out.suffix == "" else "dice")
            faces = panorama.equirect_to_cubemap(pano, size, layout="list", depth=args.depth,
                                                 interpolation=args.interpolation)
            staged = plan.stage(target)
            as_written = out / f"px{ext}" if files_out else out  # the extension the faces are stored in
            what = "--ext" if files_out else "-o"
            write_cubemap(staged, [image_for(as_written, f, what) for f in faces], layout=layout, ext=ext)
            plan.commit()
            written = [out / f"{n}{ext}" for n in FACE_FILE_NAMES] if files_out else [out]
            info(f"cubemap: {w}x{h} equirect -> {layout} faces of {size}px: "
                 f"{', '.join(map(str, written)) if len(written) < 3 else str(out) + '/'}")
        else:
            if files_out:
                raise ValueError(f"-o: {out} names a face folder, but INPUT is already a cubemap; converting "
                                 "back writes one equirect image (give -o a file name such as pano.png)")
            faces = panorama.unpack_faces(pano, in_layout)
            s = faces[0].shape[0]
            width = args.width if args.width is not None else 4 * s
            if width < 2 or width % 2:
                raise ValueError(f"--width: expected an even number >= 2 (height = width / 2), got {width}")
            eq = panorama.cubemap_to_equirect(faces, width, width // 2, layout="list", depth=args.depth,
                                              interpolation=args.interpolation)
            write_image(plan.stage(target), image_for(out, eq))
            plan.commit()
            info(f"cubemap: {in_layout} faces of {s}px -> {width}x{width // 2} equirect: {out}")
    return 0
