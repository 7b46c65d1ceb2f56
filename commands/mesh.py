"""``ibr mesh``: build the adaptive quad mesh of a view (seed 002) and export it.

Prints the quad count, the share of one-pixel quads and the segmentation time; optionally
writes the mesh as OBJ and/or PLY (textured with the source image) and a PNG of the segmentation
drawn over the image. Outputs are written atomically; the view's own files are never touched.
"""

from __future__ import annotations

HELP = "build the adaptive planar quad mesh of a view; export OBJ/PLY and a segmentation picture"

METHODS = ("edge", "separate", "paper")


def add_arguments(parser) -> None:
    parser.add_argument("view", metavar="VIEW.json", help="view file with depth")
    lod = parser.add_mutually_exclusive_group()
    lod.add_argument("--threshold", type=float, metavar="T",
                     help="level of detail in 24-bit z' units (the seed's 2^15 = 32768, 2^11 = 2048)")
    lod.add_argument("--max-error", type=float, metavar="PX", dest="max_error",
                     help="max reprojection error in pixels for a move of one baseline (default 0.5)")
    parser.add_argument("--baseline", type=float, metavar="B",
                        help="camera move for --max-error, scene units (default 5%% of the median depth)")
    parser.add_argument("--method", choices=METHODS, default="edge",
                        help="edge (default: edge-aware, error-bounded), separate, or paper (faithful seed 002)")
    parser.add_argument("--obj", metavar="OUT.obj", help="write the mesh as Wavefront OBJ (+ .mtl)")
    parser.add_argument("--ply", metavar="OUT.ply", help="write the mesh as binary PLY")
    parser.add_argument("--frame", choices=("cam", "world"), default="cam",
                        help="vertex coordinates of the exports (default: source camera frame)")
    parser.add_argument("--viz", metavar="SEG.png", help="write the segmentation drawn over the image")
    parser.add_argument("--viz-scale", type=int, default=1, metavar="N",
                        help="upscale the segmentation picture N times (default 1)")


def run(args) -> int:
    import os
    import time
    from pathlib import Path

    from commands._common import info
    from ibr.io import load_view, write_image
    from ibr.mesh.quad_mesh import build_mesh
    from ibr.io.mesh_files import write_obj, write_ply, write_segmentation_png

    for name in ("obj", "ply", "viz"):
        out = getattr(args, name)
        if out is not None:
            folder = Path(out).parent
            if str(folder) and not folder.is_dir():
                raise FileNotFoundError(f"--{name}: output folder {folder} does not exist")
            if Path(out).resolve() == Path(args.view).resolve():
                raise ValueError(f"--{name}: refusing to overwrite the input view file {out}")

    view = load_view(args.view)
    t0 = time.perf_counter()
    mesh = build_mesh(view, threshold=args.threshold, max_error_px=args.max_error,
                      baseline=args.baseline, method=args.method)
    seconds = time.perf_counter() - t0
    h, w = view.shape
    i = mesh.info
    info(f"mesh: {len(mesh)} quads for {w}x{h} pixels ({len(mesh) / (w * h):.2%} of pixels), "
         f"one-pixel quads {mesh.one_pixel_share:.1%}, method {i['method']}")
    if i["tolerance_inv_depth"] is not None:
        bound = f"max |error in 1/z| {i['tolerance_inv_depth']:.4g}"
        if i["max_error_px"] is not None:
            bound += f" (= {i['max_error_px']:g} px for a baseline of {i['baseline']:.4g})"
        info(f"mesh: guaranteed {bound}")
    else:
        info(f"mesh: threshold {i['threshold_zprime']:.6g} in z' units (near {i['near']:.4g}, far {i['far']:.4g})")
    info(f"mesh: segmentation {i['seconds_segment'] * 1e3:.1f} ms, total {seconds * 1e3:.1f} ms "
         "(first call includes loading the compiled kernels)")

    texture = None
    if args.obj or args.ply:
        # the texture is the view's color image, copied next to the mesh as <stem>_texture.png
        first = Path(args.obj or args.ply)
        texture = f"{first.stem}_texture.png"
        color = view.color
        if color.dtype.kind == "f":
            import numpy as np

            color = (np.clip(np.nan_to_num(color), 0, 1) * 255 + 0.5).astype(np.uint8)
        write_image(first.parent / texture, color)
    if args.obj:
        n = write_obj(mesh, args.obj, texture=texture, frame=args.frame)
        info(f"wrote {args.obj} ({n} quads, texture {texture})")
    if args.ply:
        n = write_ply(mesh, args.ply, texture=os.path.relpath(Path(args.obj or args.ply).parent / texture,
                                                              Path(args.ply).parent), frame=args.frame)
        info(f"wrote {args.ply} ({n} quads)")
    if args.viz:
        write_segmentation_png(mesh, view.color, args.viz, scale=args.viz_scale)
        info(f"wrote {args.viz}")
    return 0
