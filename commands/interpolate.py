"""``ibr interpolate``: intermediate views between two RGB-D views (seed 002).

Without view files it runs on the bundled sample pair (``samples/data``, the clutter scene) at
the ground-truth positions t = 0.25, 0.5, 0.75 and prints PSNR/SSIM against the bundled
ground-truth views. Frames go to ``--out`` (default ``./out``) as ``frame_000_t0.250.png`` ... (more digits for more than 1000 frames).
"""

from __future__ import annotations

HELP = "render intermediate views between two RGB-D views (no arguments: the bundled sample pair)"

SAMPLE_SCENE = "clutter"
#: The bundled scenes (samples/data/manifest.json's "scenes"; a test keeps the two in step).
SAMPLE_SCENES = ("room", "clutter", "grazing")


def add_arguments(parser) -> None:
    from commands._common import finite_float, frame_count, frame_rate, number_in

    parser.add_argument("views", nargs="*", metavar="VIEW.json",
                        help="two view files A and B (default: the bundled sample pair)")
    where = parser.add_mutually_exclusive_group()
    where.add_argument("--frames", type=frame_count, metavar="N",
                       help="N frames evenly spaced from A to B, both included (t = i / (N - 1); N = 1: t = 0.5)")
    where.add_argument("--t", type=finite_float, nargs="+", metavar="T",
                       help="interpolation parameters (0 = A, 1 = B; default 0.25 0.5 0.75)")
    parser.add_argument("--scene", default=None, choices=SAMPLE_SCENES,
                        help=f"bundled sample scene when no view files are given: {', '.join(SAMPLE_SCENES)} "
                             f"(default {SAMPLE_SCENE})")
    parser.add_argument("-o", "--out", default="out", metavar="DIR",
                        help="output folder (default: %(default)s); frames of an earlier run there "
                             "(frame_NNN_tT.TTT.png/.exr, _holes.png) are replaced, other files are left alone")
    parser.add_argument("--fill", choices=("previous", "inpaint", "none"), default="previous",
                        help="hole filling: the previous frame where it showed background there, else "
                             "the background fill (seed step 7, default); the depth-aware background "
                             "fill of each frame; or none")
    parser.add_argument("--method", choices=("mesh", "forward"), default="mesh",
                        help="quad-mesh inverse warp (default) or per-pixel forward splat (preview)")
    parser.add_argument("--interpolation", choices=("sharp", "linear", "cubic"), default="sharp",
                        help="colour reconstruction (default %(default)s: bilinear taps on the sources upsampled "
                             "2x2 once, about bicubic's sharpness at 1.1x the frame time; linear: plain bilinear, "
                             "softer textures; cubic: bicubic, ~3x the frame time)")
    parser.add_argument("--supersample", type=number_in(1, 5, integer=True), choices=(1, 3, 5), default=1,
                        metavar="K",
                        help="K x K subsamples per pixel, box-filtered, from sources upsampled with sub-pixel "
                             "silhouettes and their colours refined by each other (1, 3 or 5; default 1 = off; "
                             "about K^2 the frame time)")
    parser.add_argument("--antialias", action="store_true",
                        help="anti-aliased silhouettes: pixels at depth edges are the mean of their centre and four "
                             "diagonal subsamples (+1.4 dB at clutter's edges for about 1.5x the frame time; "
                             "ibr.render.edge_antialias)")
    parser.add_argument("--composite", choices=("blend", "front"), default="blend",
                        help="depth-aware blend (default) or the seed's nearer-source-in-front order")
    parser.add_argument("--format", choices=("png", "exr"), default="png",
                        help="frame format: png (the sources' 8/16-bit) or exr (float32)")
    parser.add_argument("--video", metavar="OUT.mp4",
                        help="also write the frames as a video (OpenCV writer; .mp4, .m4v, .mov, .avi)")
    parser.add_argument("--fps", type=frame_rate, default=None,
                        help="frame rate of --video (only with --video; default 24; for a sequence: the manifest's "
                             "fps x --factor, else 24)")
    parser.add_argument("--contact-sheet", metavar="SHEET.png",
                        help="pairs only: also write a contact sheet of all frames (.png, .jpg, .tif; may be inside "
                             "--out)")
    parser.add_argument("--holes", action="store_true",
                        help="also write each frame's hole mask (holes before filling) as a PNG")
    from commands._sequence import add_interpolate_arguments  # sequences: VIEW.json is a SEQ (#15)

    add_interpolate_arguments(parser)


def _sample_pair(scene):
    """(A, B, {t: ground-truth path}) of a bundled scene from samples/data/manifest.json."""
    import json

    from samples import DATA_DIR

    manifest_path = DATA_DIR / "manifest.json"
    if not manifest_path.is_file():
        raise FileNotFoundError(f"bundled samples: {manifest_path} is missing (reinstall the package)")
    manifest = json.loads(manifest_path.read_text(encoding="utf-8"))
    scenes = manifest.get("scenes", {})
    name = scene or (SAMPLE_SCENE if SAMPLE_SCENE in scenes else next(iter(scenes), None))
    if name not in scenes:
        raise ValueError(f"--scene: expected one of {', '.join(map(repr, scenes))}, got {name!r}")
    entry = scenes[name]
    truth = {float(g["t"]): DATA_DIR / g["view"] for g in entry.get("ground_truth", [])}
    return DATA_DIR / entry["a"], DATA_DIR / entry["b"], truth


def _to_png(color):
    import numpy as np

    if color.dtype in (np.uint8, np.uint16):
        return color
    return (np.clip(color, 0, 1) * 255 + 0.5).astype(np.uint8)


def _to_float(color):
    import numpy as np

    if color.dtype == np.uint8:
        return color.astype(np.float32) / 255
    if color.dtype == np.uint16:
        return color.astype(np.float32) / 65535
    return color.astype(np.float32)


def _metrics(color, truth):
    """PSNR (dB) and SSIM of a frame against a ground-truth color image, on [0, 1] values.

    Both are scikit-image's definitions, evaluated without importing its metrics (its PSNR's
    module imports scipy.stats: 0.6 s of a 1.6 s warm run, #13): PSNR as
    :func:`ibr.sequence.metrics.psnr`, SSIM as :func:`_ssim` (NaN for images under 7 px a side)."""
    from ibr.sequence.metrics import psnr

    return psnr(color, truth), _ssim(_to_float(truth), _to_float(color))


def _ssim(x, y, data_range: float = 1.0) -> float:
    """Mean SSIM of two (H, W) or (H, W, C) images, scikit-image's ``structural_similarity``
    with its defaults (7x7 uniform window, K1 = 0.01, K2 = 0.03, sample covariance, the
    3-pixel border left out of the mean, channels averaged), in float64 with ``cv2.blur`` as the
    window: 15 ms a frame where scikit-image took 100 ms plus 0.24 s to import scipy.ndimage
    (#13; ``tests/test_interpolate.py`` checks the two agree to 1e-9)."""
    import cv2
    import numpy as np

    x, y = (np.asarray(a, np.float64) for a in (x, y))
    if min(x.shape[:2]) < 7:  # no whole window (scikit-image refuses such images)
        return float("nan")
    if x.ndim == 3 and x.shape[2] > 4:  # cv2.blur takes up to four channels at a time
        return float(np.mean([_ssim(x[..., c], y[..., c], data_range) for c in range(x.shape[2])]))
    win, n = 7, 49
    mean = lambda a: cv2.blur(a, (win, win), borderType=cv2.BORDER_REFLECT)  # noqa: E731 (scipy's "reflect")
    ux, uy = mean(x), mean(y)
    cov = n / (n - 1)
    vx = cov * (mean(x * x) - ux * ux)
    vy = cov * (mean(y * y) - uy * uy)
    vxy = cov * (mean(x * y) - ux * uy)
    c1, c2 = (0.01 * data_range) ** 2, (0.03 * data_range) ** 2
    s = ((2 * ux * uy + c1) * (2 * vxy + c2)) / ((ux * ux + uy * uy + c1) * (vx + vy + c2))
    pad = (win - 1) // 2
    return float(s[pad:-pad, pad:-pad].mean())


def contact_sheet(images, labels, *, columns: int = 4, width: int = 256):
    """One uint8 RGB image with the frames in a grid of at most ``columns`` columns (as few as the
    rows need, so the last row is as full as it can be), each scaled to ``width`` px and labelled."""
    import cv2
    import numpy as np

    tiles = []
    for img, label in zip(images, labels):
        img = _to_png(img)
        if img.dtype == np.uint16:
            img = (img // 257).astype(np.uint8)
        if img.ndim == 2:
            img = np.repeat(img[..., None], 3, -1)
        img = img[..., :3]
        h = max(1, round(img.shape[0] * width / img.shape[1]))
        tile = cv2.resize(np.ascontiguousarray(img), (width, h), interpolation=cv2.INTER_AREA)
        cv2.putText(tile, label, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 3, cv2.LINE_AA)
        cv2.putText(tile, label, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
        tiles.append(tile)
    rows = -(-len(tiles) // max(1, min(columns, len(tiles))))
    columns = -(-len(tiles) // rows)  # as few columns as those rows need: 6 frames 3 x 2, not 4 + 2
    th = max(t.shape[0] for t in tiles)
    sheet = np.zeros((rows * th, columns * width, 3), np.uint8)
    for i, tile in enumerate(tiles):
        r, c = divmod(i, columns)
        sheet[r * th : r * th + tile.shape[0], c * width : (c + 1) * width] = tile
    return sheet


def write_video(path, frames, fps: float) -> None:
    """Write uint8 RGB frames with OpenCV's VideoWriter (mp4v for .mp4, MJPG otherwise), atomically."""
    from pathlib import Path

    import cv2
    import numpy as np

    from ibr.io import atomic_path

    path = Path(path)
    if not fps > 0:
        raise ValueError(f"--fps: expected a positive frame rate, got {fps}")
    fourcc = cv2.VideoWriter_fourcc(*("mp4v" if path.suffix.lower() in (".mp4", ".m4v", ".mov") else "MJPG"))
    h, w = frames[0].shape[:2]
    with atomic_path(path) as tmp:
        writer = cv2.VideoWriter(str(tmp), fourcc, float(fps), (w, h))
        if not writer.isOpened():
            raise OSError(f"--video: OpenCV cannot write {path.suffix or 'this'} video files here")
        try:
            for f in frames:
                f = _to_png(f)
                if f.dtype == np.uint16:
                    f = (f // 257).astype(np.uint8)
                if f.ndim == 2:
                    f = np.repeat(f[..., None], 3, -1)
                writer.write(np.ascontiguousarray(f[..., 2::-1]))  # RGB -> BGR
        finally:
            writer.release()


#: File-name patterns of the frames this command writes into ``--out`` (and removes from an
#: earlier run there); nothing else in the folder is touched.
FRAME_PATTERNS = tuple(f"frame_#_t{sign}#.#{tail}" for sign in ("", "-") for tail in (".png", "_holes.png", ".exr"))


#: The kernel modules an interpolation (and a mesh warp) runs: the segmentation, the rasterizer,
#: the compositor and the fill (any of them without a fresh numba cache: a first run).
FRAME_KERNELS = ("ibr.mesh._segment_kernels", "ibr.render._raster_kernels", "ibr.render._composite_kernels",
                 "ibr.render._fill_kernels")
#: ... and with ``--antialias`` (compiled by the main process: the first-run helper compiling them
#: too made every first run ~0.9 s longer, #13)
EDGE_KERNELS = ("ibr.render._edge_kernels",)
#: ... and for sources whose depth is in coarse codes (compiled by the main process when it
#: builds their meshes; told apart once the views are read)
CODE_BIN_KERNELS = ("ibr.mesh._code_bins_kernels",)


def first_run_kernels(args):
    """The kernel modules this run compiles and the first-run helper's kind (:func:`cli.main`
    starts the helper with them before the command's imports, #13)."""
    return FRAME_KERNELS + (EDGE_KERNELS if getattr(args, "antialias", False) else ()), "frame"


def _truth_for_pair(truth, path_a, path_b, ts) -> dict:
    """{t: ground-truth view file} for a pair's frames: the views of ``--truth`` (a view file or a
    sequence) whose camera is a frame's (A's and B's cameras interpolated at t, within 1e-6)."""
    from pathlib import Path

    from ibr.base.camera import interpolate_cameras
    from ibr.io import load_camera
    from ibr.sequence import is_sequence, load_sequence

    try:
        paths = list(load_sequence(truth).views) if is_sequence(truth) else [Path(truth)]
    except (OSError, ValueError) as exc:
        raise type(exc)(f"--truth: {exc}") from None
    cams = [(p, load_camera(p, what="--truth view")) for p in paths]
    ca, cb = load_camera(path_a, what="A"), load_camera(path_b, what="B")
    found = {}
    for t in ts:
        frame = interpolate_cameras(ca, cb, t)
        hit = next((p for p, c in cams if c.allclose(frame, atol=1e-6)), None)
        if hit is not None:
            found[t] = hit
    if not found:
        raise ValueError(f"--truth: no view of {truth} has the camera of a frame (t = "
                         f"{', '.join(f'{t:g}' for t in ts)}); ground truth is matched to the frames by camera")
    return found


def truth_summary(scores) -> str:
    """The "ground truth: mean PSNR ..." line of a pair's scored frames: the means over the new
    frames only (0 < t < 1 and beyond: the key frames t = 0 and 1 are copies of A and B, exact,
    and made a mean of ``inf dB``), an identical new frame left out of the PSNR mean (said), and
    never ``inf``.

    Parameters
    ----------
    scores : sequence of (t, psnr, ssim)
        One per frame with a ground truth (PSNR ``inf`` for an identical frame).
    """
    import numpy as np

    from commands._common import counted

    new = [(p, s) for t, p, s in scores if not (abs(t) < 1e-9 or abs(t - 1) < 1e-9)]
    keys = len(scores) - len(new)
    left_out = (f" (the key {'frame' if keys == 1 else 'frames'} t = 0 / 1, copies of A / B, left out)"
                if keys else "")
    if not new:
        return ("ground truth: only the key frames (t = 0 / 1, copies of A / B) have one; no new frame to "
                "score (use --t or more --frames)")
    ssim = float(np.mean([s for _, s in new]))
    psnrs = [p for p, _ in new if np.isfinite(p)]
    if not psnrs:
        return f"ground truth: {counted(len(new), 'new frame')} identical to it (SSIM {ssim:.4f}){left_out}"
    line = (f"ground truth: mean PSNR {np.mean(psnrs):.2f} dB, mean SSIM {ssim:.4f} over "
            f"{counted(len(new), 'new frame')}")
    if len(psnrs) < len(new):
        line += f" ({len(new) - len(psnrs)} identical, left out of the PSNR mean)"
    return line + left_out


def _comparable(color, truth, path):
    """A frame and its ground truth with the same channels: an alpha channel of either is dropped
    (RGB against RGBA); otherwise the counts must agree (an error naming ``path``)."""
    c = [1 if x.ndim == 2 else x.shape[2] for x in (color, truth)]
    if c[0] != c[1] and min(c) == 3:
        return color[..., :3], truth[..., :3]
    if c[0] != c[1]:
        raise ValueError(f"--truth: {path} has {c[1]} colour channel(s), the frames {c[0]}")
    return color, truth


def _check_pair(path_a, view_a, path_b, view_b, method: str = "mesh"):
    """The library's source checks, naming the positionals A / B (not ``view_a`` / ``view_b``) and
    their files (not the views' names): both views hold depth (with a valid pixel, for the mesh
    warp) and have one size; colours of two types (8- and 16-bit) are both made float 0-1.
    Returns the two views."""
    from commands._common import check_source_depth

    for name, path, view in (("A", path_a, view_a), ("B", path_b, view_b)):
        if view.depth is None:
            raise ValueError(f"{name}: {path} has no depth, so it cannot be a source (a view without depth can "
                             "only give a target camera)")
        if method == "mesh":
            check_source_depth(name, path, view)
    if view_a.shape != view_b.shape:
        raise ValueError(f"B: {path_b} is {view_b.camera.width}x{view_b.camera.height}, A ({path_a}) is "
                         f"{view_a.camera.width}x{view_a.camera.height}; both sources must have the same size")
    channels = [1 if v.color.ndim == 2 else v.color.shape[2] for v in (view_a, view_b)]
    if channels[0] != channels[1]:
        raise ValueError(f"B: {path_b} has {channels[1]} colour channel(s), A ({path_a}) {channels[0]}; "
                         "both sources must have the same channels")
    if view_a.color.dtype != view_b.color.dtype:
        # the library asks for one colour type; a CLI user has no way to convert: float [0, 1]
        from ibr.base.view import View
        from ibr.sequence.metrics import as_unit_float

        from commands._common import info

        ca, cb = as_unit_float(view_a.color, "A: color"), as_unit_float(view_b.color, "B: color")
        info(f"interpolate: A's colour is {view_a.color.dtype}, B's {view_b.color.dtype}: both used as float 0-1")
        view_a = View(ca, view_a.depth, view_a.camera, view_a.name)
        view_b = View(cb, view_b.depth, view_b.camera, view_b.name)
    return view_a, view_b


def run(args) -> int:
    import time
    from pathlib import Path

    import numpy as np

    from commands._common import counted, holes_summary, info, invented, invented_warning, note_first_run, progress
    from ibr.io import load_view, write_image
    from ibr.io.outputs import OutputPlan, VIDEO_EXTS, number_width
    from commands._sequence import is_sequence_argument, run_interpolate  # sequences (#15)

    if args.fps is not None and not args.video:  # it was silently ignored
        raise ValueError(f"--fps: only used with --video (the video's frame rate); add --video OUT.mp4 or leave "
                         f"--fps {args.fps:g} out")
    if len(args.views) == 1 and is_sequence_argument(args.views[0]):
        return run_interpolate(args)
    truth_paths = {}
    if not args.views:
        path_a, path_b, truth_paths = _sample_pair(args.scene)
        info(f"interpolate: bundled sample pair {path_a.name} / {path_b.name}")
    elif len(args.views) == 2:
        if args.scene:
            raise ValueError("--scene: only used without view files")
        path_a, path_b = map(Path, args.views)
    elif len(args.views) == 1 and not Path(args.views[0]).exists():  # a mistyped sequence or view file
        raise FileNotFoundError(f"SEQ: file not found: {args.views[0]} (one argument is a sequence: a manifest "
                                "or a folder of numbered views; a pair needs two view files)")
    else:
        raise ValueError(f"views: expected two view files A.json B.json (or none), got {len(args.views)}")
    # the sequence options would be silently ignored for a pair (or the bundled pair)
    for opt, given, instead in (
            ("--factor", args.factor is not None, "use --frames or --t for a pair"),
            ("--no-tail", args.no_tail, "a pair has no extrapolated tail (its frames are --frames or --t)"),
            ("--report", args.report is not None, "a pair's timing, holes and PSNR (with --truth) are printed, "
                                                  "one line a frame")):
        if given:
            raise ValueError(f"{opt}: only used with a sequence (one manifest or folder of numbered views), "
                             f"not with two view files; {instead}")

    if args.frames is not None:
        if args.frames < 1:
            raise ValueError(f"--frames: expected N >= 1, got {args.frames}")
        ts = [0.5] if args.frames == 1 else [i / (args.frames - 1) for i in range(args.frames)]
    else:
        ts = list(args.t) if args.t else [0.25, 0.5, 0.75]
    for t in ts:
        if not np.isfinite(t):
            raise ValueError(f"--t: expected finite numbers, got {t}")
    if args.truth is not None:  # a pair's own ground truth (the bundled pair has its manifest's)
        truth_paths = _truth_for_pair(args.truth, path_a, path_b, ts)
    fps = 24.0 if args.fps is None else args.fps
    if not (isinstance(fps, (int, float)) and np.isfinite(fps) and fps > 0):
        raise ValueError(f"--fps: expected a positive frame rate, got {fps}")

    with OutputPlan("ibr interpolate", log=info) as plan:
        plan.add_view_input("A", path_a)
        plan.add_view_input("B", path_b)
        for truth in truth_paths.values():
            plan.add_view_input("ground truth", truth)
        out = plan.add_folder("--out", args.out, FRAME_PATTERNS)
        video = plan.add_file("--video", args.video, VIDEO_EXTS)
        sheet = plan.add_file("--contact-sheet", args.contact_sheet, (".png", ".jpg", ".jpeg", ".tif", ".tiff"))
        plan.check()  # every output checked before any work (#12)
        # imported after cli.main started the first-run helper: numba's import (0.3 s) overlaps it
        from ibr.render.view_synthesis import coarse_sources, interpolation_meshes, iter_interpolate

        view_a, view_b = _check_pair(path_a, load_view(path_a), path_b, load_view(path_b), args.method)
        # the inputs read: say that numba compiles (not before a view without depth is refused)
        modules, warm = first_run_kernels(args)
        with_depth = view_a.depth is not None and view_b.depth is not None
        compiling = note_first_run(*modules, warm=warm, announce=with_depth)

        if args.method == "mesh" and with_depth and any(coarse_sources(view_a, view_b)):
            # depth in coarse codes: the codes' bins kernel compiles (here, or with the first supersampled frame), once
            compiling = note_first_run(*modules, *CODE_BIN_KERNELS, warm=warm, announce=not compiling) or compiling
        if args.method == "mesh" and args.supersample == 1:  # supersampled: meshes of the upsampled
            t0 = time.perf_counter()  # sources, built with the first frame
            mesh_a, mesh_b = interpolation_meshes(view_a, view_b, ts)
            n_fitted = [m.info.get("refined_quads", 0) for m in (mesh_a, mesh_b)]
            n_binned = [m.info.get("bin_fitted_quads", 0) for m in (mesh_a, mesh_b)]
            n_split = [m.info.get("bin_split_quads", 0) for m in (mesh_a, mesh_b)]
            fitted = (f" (coarse depth codes: planes of {n_fitted[0]} + {n_fitted[1]} large quads fitted to the "
                      f"other view's colour, of {n_binned[0]} + {n_binned[1]} more placed inside the codes' bins "
                      f"around them, {n_split[0]} + {n_split[1]} of these split where one plane does not follow "
                      "the bins)") if any(n_fitted + n_binned) else ""
            info(f"meshes: {len(mesh_a)} + {len(mesh_b)} quads{fitted}, built in "
                 f"{(time.perf_counter() - t0) * 1e3:.1f} ms (once, {'compiling' if compiling else 'loading'} the "
                 "segmentation kernels included; reused for every frame)")

        k = args.supersample
        if k > 1:  # seconds at 1080p: say so before the wait
            h, w = view_a.depth.shape
            guess = 1.5 * w * h / (512 * 384)  # ~1.1-1.5 s at 512 x 384, 12 s at 1440 x 1080 on two cores
            info(f"upsampling the sources {k} x {k} and refining their colours by each other (once; roughly "
                 f"{guess:.0f} s at {w} x {h}) ...")
        t0 = time.perf_counter()
        frames_iter = iter_interpolate(view_a, view_b, ts, method=args.method, composite_mode=args.composite,
                                       fill=args.fill, interpolation=args.interpolation,
                                       supersample=k, antialias=args.antialias)
        if k > 1:  # the sources were upsampled by the call (ibr.render.superres)
            info(f"sources upsampled {k} x {k}, their colours refined by each other: "
                 f"{(time.perf_counter() - t0) * 1e3:.0f} ms (once)")
        long_run = len(ts) > 10
        if long_run:
            frames_iter = progress(frames_iter, len(ts), "interpolate")
        times, colors, labels, scores, guessed = [], [], [], [], []
        ext = "." + args.format
        digits = number_width(len(ts), 3)  # frame_1000_... sorts after frame_0999_..., not before frame_100_...
        t_prev = time.perf_counter()
        for i, (frame, t) in enumerate(zip(frames_iter, ts)):  # frames first: the bar draws its last step
            dt = time.perf_counter() - t_prev
            times.append(dt)
            name = f"frame_{i:0{digits}d}_t{t:.3f}"
            color = _to_float(frame.color) if args.format == "exr" else _to_png(frame.color)
            write_image(plan.stage(out, name + ext), color)
            if args.holes:
                write_image(plan.stage(out, name + "_holes.png"), (frame.holes * 255).astype(np.uint8))
            line = f"frame {i + 1}/{len(ts)} t={t:.3f}: {dt * 1e3:6.1f} ms, {holes_summary(frame)}"
            truth = next((p for tt, p in truth_paths.items() if abs(tt - t) < 1e-9), None)
            if truth is not None:
                psnr, ssim = _metrics(*_comparable(frame.color, load_view(truth).color, truth))
                scores.append((t, psnr, ssim))
                line += (f", PSNR {psnr:.2f} dB, SSIM {ssim:.4f} vs {truth.name}" if np.isfinite(psnr)
                         else f", identical to {truth.name}")  # (a key frame: PSNR infinite)
            if not long_run:
                info(line)
            colors.append(frame.color)
            labels.append(f"t={t:.3f}")
            guessed.append((f"frame {i + 1} (t={t:.3f})", *invented(frame)))
            t_prev = time.perf_counter()

        if video:
            write_video(plan.stage(video), colors, fps)
        if sheet:
            write_image(plan.stage(sheet), contact_sheet(colors, labels))
        plan.commit()  # frames, video and sheet appear together, or not at all

    first = f"first frame {times[0] * 1e3:.1f} ms"
    if args.method == "mesh" and args.supersample > 1:
        first += ", including the meshes of the upsampled sources"
    elif compiling:
        first += ", including the one-time numba compilation (cached for later runs)"
    elif len(times) > 1 and times[0] > 3 * np.median(times[1:]):
        first += ", including loading the compiled kernels"
    # the first frame loads (or compiles) the kernels: the typical frame is the median of the rest
    per = np.median(times[1:]) if len(times) > 1 else times[0]
    info(f"wrote {counted(len(ts), 'frame')} to {out}/ (median {per * 1e3:.1f} ms per frame, {first})")
    if scores:
        info(truth_summary(scores))
    elif truth_paths:  # e.g. the bundled pair with --frames 6: no frame at a ground-truth position
        at = ", ".join(f"{t:g}" for t in sorted(truth_paths))
        info(f"ground truth: none at these t (its views are at t = {at}); no PSNR/SSIM")
    if video:
        info(f"wrote video {video}")
    if sheet:
        info(f"wrote contact sheet {sheet}")
    warning = invented_warning("interpolate", guessed, what="the frame",
                               hint="do A and B see what lies between them?")
    if warning:  # exit 0 all the same: the frames are written, mostly a guess
        info(warning)
    return 0
