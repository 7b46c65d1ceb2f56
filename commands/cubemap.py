"""``ibr cubemap``: equirectangular image <-> cube faces in a chosen layout (color or depth)."""

from __future__ import annotations

import math
from pathlib import Path

from ._common import info

HELP = "convert an equirectangular panorama to cube faces (any layout) and back; color or depth"

_LAYOUTS = ("dice", "horizon", "vstrip", "files", "hstrip", "exr", "cross", "hcross")


def add_arguments(parser) -> None:
    parser.add_argument("input", help="equirect image (2:1), cubemap image (6:1 horizon, 1:6 vstrip, "
                        "4:3 dice) or a folder of px/nx/py/ny/pz/nz face files")
    parser.add_argument("-o", "--output", required=True,
                        help="output image (extension picks the format: .png 8/16-bit, .tif, .exr "
                        "float) or, for --layout files, a folder")
    parser.add_argument("--layout", choices=_LAYOUTS, default=None,
                        help="cube layout of the output (default: files if OUTPUT has no "
                        "extension, else dice)")
    parser.add_argument("--input-layout", default=None,
                        choices=("equirect",) + _LAYOUTS[:3] + _LAYOUTS[4:],
                        help="layout of INPUT (default: from its shape; folders are face files)")
    parser.add_argument("--face-size", type=int, default=None,
                        help="face edge in pixels (default: ceil(width / pi), full resolution at "
                        "the face centres)")
    parser.add_argument("--width", type=int, default=None,
                        help="equirect width when converting back (default 4 x face size); height "
                        "is width / 2")
    parser.add_argument("--depth", action="store_true",
                        help="INPUT is depth: equirect range along the ray <-> planar z per face "
                        "(float EXR/TIFF/PFM)")
    parser.add_argument("--interpolation", choices=("linear", "nearest"), default=None,
                        help="default linear for color, nearest for depth")
    parser.add_argument("--ext", default=".png", help="face file extension for --layout files "
                        "(default .png; use .exr for float or depth)")


def run(args) -> int:
    import panorama
    from ibr.io import write_image
    from panorama.files import read_panorama, write_cubemap

    pano, in_layout = read_panorama(args.input, layout=args.input_layout)
    out = Path(args.output)
    if in_layout == "equirect":
        h, w = pano.shape[:2]
        size = args.face_size if args.face_size is not None else math.ceil(w / math.pi)
        layout = args.layout or ("files" if out.suffix == "" else "dice")
        faces = panorama.equirect_to_cubemap(pano, size, layout="list", depth=args.depth,
                                             interpolation=args.interpolation)
        ext = args.ext if args.ext.startswith(".") else "." + args.ext
        written = write_cubemap(out, faces, layout=layout, ext=ext)
        info(f"cubemap: {w}x{h} equirect -> {layout} faces of {size}px: "
             f"{', '.join(map(str, written)) if len(written) < 3 else str(out) + '/'}")
    else:
        faces = panorama.unpack_faces(pano, in_layout)
        s = faces[0].shape[0]
        width = args.width if args.width is not None else 4 * s
        if width < 2 or width % 2:
            raise ValueError(f"--width: expected an even number >= 2 (height = width / 2), got {width}")
        eq = panorama.cubemap_to_equirect(faces, width, width // 2, layout="list", depth=args.depth,
                                          interpolation=args.interpolation)
        write_image(out, eq)
        info(f"cubemap: {in_layout} faces of {s}px -> {width}x{width // 2} equirect: {out}")
    return 0
