"""``ibr mesh``: build the adaptive quad mesh of a view (seed 002) and export it.

Prints the quad count, the share of one-pixel quads and the segmentation time; optionally
writes the mesh as OBJ and/or PLY (textured with the source image) and a PNG of the segmentation
drawn over the image. Outputs are written atomically; the view's own files are never touched.
"""

from __future__ import annotations

HELP = "build the adaptive planar quad mesh of a view; export OBJ/PLY and a segmentation picture"

METHODS = ("edge", "separate", "paper")


def add_arguments(parser) -> None:
    from commands._common import number_in, positive_float

    parser.add_argument("view", metavar="VIEW.json", help="view file with depth")
    lod = parser.add_mutually_exclusive_group()
    lod.add_argument("--threshold", type=positive_float, metavar="T",
                     help="level of detail in 24-bit z' units (the seed's 2^15 = 32768, 2^11 = 2048); default: "
                          "the threshold --max-error's 0.5 px gives for the baseline, printed (e.g. 214606 for "
                          "the bundled clutter view with --method paper), not the seed's 32768")
    lod.add_argument("--max-error", type=positive_float, metavar="PX", dest="max_error",
                     help="max reprojection error in pixels for a move of one baseline (default 0.5)")
    parser.add_argument("--baseline", type=positive_float, metavar="B",
                        help="camera move for --max-error, scene units (default 5%% of the median depth)")
    parser.add_argument("--method", choices=METHODS, default="edge",
                        help="edge (default: edge-aware, error-bounded), separate, or paper (faithful seed 002)")
    parser.add_argument("--obj", metavar="OUT.obj",
                        help="write the mesh as Wavefront OBJ, with OUT.mtl and the texture OUT_texture.png beside it "
                             "(the view's colour; files of these names are replaced, an input is refused)")
    parser.add_argument("--ply", metavar="OUT.ply",
                        help="write the mesh as binary PLY, with the texture OUT_texture.png beside it (with --obj: "
                             "the OBJ's texture; replaced as --obj's)")
    parser.add_argument("--frame", choices=("cam", "world"), default="cam",
                        help="vertex coordinates of the exports (default: source camera frame)")
    parser.add_argument("--viz", metavar="SEG.png",
                        help="write the segmentation drawn over the image (dimmed to 70%%): red one-pixel outlines "
                             "(each quad's top row and left column), yellow one-pixel quads, black pixels without "
                             "depth (no quad)")
    parser.add_argument("--viz-scale", type=number_in(1, 64, integer=True, what="a scale"), default=1, metavar="N",
                        help="upscale the segmentation picture N times (1..64, default 1)")


def first_run_kernels(args):
    """The kernel modules this run compiles and the first-run helper's kind (:func:`cli.main`
    starts the helper with them before the command's imports)."""
    return ("ibr.mesh._segment_kernels",), "mesh"


def run(args) -> int:
    import os
    import time
    from pathlib import Path

    from commands._common import check_source_depth, info, note_first_run
    from ibr.base.validate import check_image_size
    from ibr.io import load_view, write_image
    from ibr.io.mesh_files import write_obj, write_ply, write_segmentation_png
    from ibr.io.outputs import OutputPlan

    with OutputPlan("ibr mesh", log=info) as plan:
        plan.add_view_input("VIEW", args.view)
        obj = plan.add_file("--obj", args.obj, (".obj",))
        ply = plan.add_file("--ply", args.ply, (".ply",))
        viz = plan.add_file("--viz", args.viz, (".png",))
        texture = mtl = None
        if obj or ply:
            # the texture is the view's color image, copied next to the mesh as <stem>_texture.png
            first = obj or ply
            texture = plan.add_file(f"--{'obj' if obj else 'ply'} (its texture)",
                                    first.parent / f"{first.stem}_texture.png", (".png",))
        if obj:
            mtl = plan.add_file("--obj (its material file)", obj.with_suffix(".mtl"), (".mtl",))
        plan.check()  # every output checked before any work (#12)
        # the implicit outputs (not named on the command line) are said to be replaced when they were there
        existed = {p: p.exists() for p in (texture, mtl) if p is not None}
        from ibr.mesh.quad_mesh import build_mesh  # after cli.main started the helper (numba: 0.3 s)

        view = load_view(args.view)
        check_source_depth("VIEW", args.view, view, purpose="so it has no mesh")
        # the input read: say that numba compiles (not before a view without depth is refused)
        modules, warm = first_run_kernels(args)
        note_first_run(*modules, warm=warm, announce=view.depth is not None)
        if viz:
            check_image_size("--viz-scale", view.shape[1] * args.viz_scale, view.shape[0] * args.viz_scale,
                             channels=3, itemsize=1)
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
            quant = i["quantization"]
            if i["guaranteed_px"] is not None:
                bound += f" (= {i['guaranteed_px']:.3g} px for a baseline of {i['baseline']:.4g}"
                if quant is not None and i["quantization_allowance_inv_depth"]:
                    bound += f": {i['max_error_px']:g} px plus half a code of the depth's quantization"
                bound += ")"
            if quant is not None:  # recorded by load_view from the file's encoding
                bound += f"; the file's depth quantization ({quant.describe()}) applied"
            info(f"mesh: guaranteed {bound}")
        else:
            info(f"mesh: threshold {i['threshold_zprime']:.6g} in z' units (near {i['near']:.4g}, far {i['far']:.4g})"
                 + (f"; the file's depth quantization ({i['quantization'].describe()}) applied: second differences "
                    "of up to 1.5 codes split nothing" if i["quantization"] is not None else ""))
        info(f"mesh: segmentation {i['seconds_segment'] * 1e3:.1f} ms, total {seconds * 1e3:.1f} ms "
             "(first call includes loading the compiled kernels)")

        if texture:
            color = view.color
            if color.dtype.kind == "f":
                import numpy as np

                color = (np.clip(np.nan_to_num(color), 0, 1) * 255 + 0.5).astype(np.uint8)
            write_image(plan.stage(texture), color)
        if obj:
            n_obj = write_obj(mesh, plan.stage(obj), texture=texture.name, frame=args.frame)
            if not plan.stage(mtl).is_file():
                raise OSError(f"--obj: the material file {mtl} was not written")
        if ply:
            rel = os.path.relpath(texture, ply.parent)
            n_ply = write_ply(mesh, plan.stage(ply), texture=rel, frame=args.frame)
        if viz:
            write_segmentation_png(mesh, view.color, plan.stage(viz), scale=args.viz_scale)
        plan.commit()
    said = lambda p: f"{p}{' (replaced)' if existed[p] else ''}"  # noqa: E731
    if obj:
        info(f"wrote {obj} ({n_obj} quads), its material {said(mtl)} and texture {said(texture)}")
    if ply:
        info(f"wrote {ply} ({n_ply} quads), " + (f"its texture {said(texture)}" if not obj else
                                                 f"textured with {texture.name}"))
    if viz:
        info(f"wrote {viz}")
    return 0
