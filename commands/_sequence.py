"""Sequence handling of ``ibr interpolate SEQ`` and ``ibr stereo SEQ`` (issue #15).

``interpolate.py`` and ``stereo.py`` call :func:`add_interpolate_arguments` /
:func:`add_stereo_arguments` from their ``add_arguments`` and hand over to
:func:`run_interpolate` / :func:`run_stereo` when their first argument is a sequence (a manifest
with ``"format": "ibr-sequence"`` or a folder of numbered view files). The algorithms live in
:mod:`ibr.sequence`; this module parses, plans the outputs (:class:`ibr.io.outputs.OutputPlan`:
everything checked before work, staged, renamed at the end), streams frames and reports progress
with frames/s and ETA, PSNR against a ground-truth sequence and temporal flicker.
"""

from __future__ import annotations

import sys
import time

from commands._common import info, invented, invented_warning, note_first_run


# --------------------------------------------------------------------------- progress
class Progress:
    """Progress on stderr: a bar with frames/s and ETA on a terminal, a line every ~10 % otherwise."""

    def __init__(self, total: int, label: str, unit: str = "frames"):
        self.total, self.label, self.unit = max(int(total), 1), label, unit
        self.start = time.perf_counter()
        self.done = 0
        self.tty = sys.stderr.isatty()
        self._next_line = 0

    def line(self) -> str:
        elapsed = time.perf_counter() - self.start
        rate = self.done / elapsed if elapsed > 0 else 0.0
        eta = (self.total - self.done) / rate if rate > 0 else float("nan")
        eta_s = f"{int(eta // 60)}:{int(eta % 60):02d}" if eta == eta else "?"
        return (f"{self.label} {self.done}/{self.total} {self.unit}, {rate:.2f} {self.unit}/s, "
                f"elapsed {elapsed:.1f} s, ETA {eta_s}")

    def step(self, n: int = 1, note: str = "") -> None:
        self.done += n
        if self.tty:
            width = 24
            filled = int(width * self.done / self.total)
            sys.stderr.write(f"\r[{'#' * filled}{'-' * (width - filled)}] {self.line()} {note}\033[K")
            if self.done >= self.total:
                sys.stderr.write("\n")
            sys.stderr.flush()
        elif self.done >= self._next_line or self.done >= self.total:
            info(self.line() + (f" {note}" if note else ""))
            self._next_line = self.done + max(1, self.total // 10)


# --------------------------------------------------------------------------- helpers
def FACTOR(text: str) -> int:  # noqa: N802 - an argparse type, named like one
    """``--factor``: an integer 1 .. 1000 (a usage error otherwise)."""
    from commands._common import number_in

    return number_in(1, 1000, integer=True, what="an up-conversion factor")(text)


def is_sequence_argument(path) -> bool:
    """True when ``path`` names a sequence (manifest or folder of numbered views)."""
    from ibr.sequence.files import is_sequence

    return path is not None and is_sequence(path)


def _display(color):
    """uint8/uint16 stay; float [0, 1] becomes uint8 (rounded)."""
    import numpy as np

    if color.dtype in (np.uint8, np.uint16):
        return color
    return np.clip(np.rint(np.asarray(color, np.float64) * 255), 0, 255).astype(np.uint8)


class VideoStream:
    """Frames appended one by one to an OpenCV ``VideoWriter`` (mp4v for mp4/m4v/mov, MJPG for avi)."""

    def __init__(self, path, fps: float):
        self.path, self.fps, self.writer, self.size = path, float(fps), None, None

    def add(self, color) -> None:
        import cv2
        import numpy as np

        f = _display(color)
        if f.dtype == np.uint16:
            f = (f // 257).astype(np.uint8)
        if f.ndim == 2:
            f = np.repeat(f[..., None], 3, -1)
        f = np.ascontiguousarray(f[..., 2::-1])  # RGB -> BGR
        if self.writer is None:
            fourcc = cv2.VideoWriter_fourcc(*("MJPG" if str(self.path).lower().endswith(".avi") else "mp4v"))
            self.size = (f.shape[1], f.shape[0])
            self.writer = cv2.VideoWriter(str(self.path), fourcc, self.fps, self.size)
            if not self.writer.isOpened():
                raise OSError(f"--video: OpenCV cannot write {self.path.suffix} video files here")
        self.writer.write(f)

    def close(self) -> None:
        if self.writer is not None:
            self.writer.release()
            self.writer = None


def add_video_arguments(parser, *, fps: bool = True) -> None:
    """``--video`` and ``--fps`` for commands that do not have them yet (``ibr stereo``)."""
    from commands._common import frame_rate

    parser.add_argument("--video", metavar="OUT.mp4", help="sequences: also write the frames as a video")
    if fps:
        parser.add_argument("--fps", type=frame_rate, default=None,
                            help="sequences: video frame rate (default: the manifest's fps, else 24)")


# --------------------------------------------------------------------------- interpolate
def add_interpolate_arguments(parser) -> None:
    """The options ``ibr interpolate SEQ`` adds to the two-view command."""
    g = parser.add_argument_group("sequences (VIEW.json is a sequence manifest or a folder of numbered views)")
    g.add_argument("--factor", type=FACTOR, default=None, metavar="F",
                   help="frame-rate up-conversion: F - 1 new frames between consecutive views (default 4)")
    g.add_argument("--no-tail", action="store_true",
                   help="end on the last view ((N-1)F+1 frames) instead of extrapolating F-1 frames after it (N F)")
    g.add_argument("--truth", metavar="SEQ",
                   help="ground-truth sequence of the output frames (default: the manifest's ground_truth); "
                        "for a pair A B: a view file or a sequence whose views are matched to the frames by "
                        "camera")
    g.add_argument("--report", metavar="REPORT.json",
                   help="write per-frame timing, holes, PSNR and the flicker figures as JSON")


def _check_interpolate_args(args) -> int:
    if len(args.views) != 1:
        raise ValueError(f"views: a sequence is up-converted on its own, got {len(args.views)} arguments")
    for opt, given, instead in (("--frames", args.frames is not None, " (use --factor)"),
                                ("--t", bool(args.t), " (use --factor)"), ("--scene", bool(args.scene), ""),
                                ("--contact-sheet", bool(getattr(args, "contact_sheet", None)), "")):
        if given:
            raise ValueError(f"{opt}: not used with a sequence{instead}")
    factor = 4 if args.factor is None else args.factor
    if factor < 1:
        raise ValueError(f"--factor: expected an integer >= 1, got {factor}")
    return factor


def _check_keys_listed(seq) -> None:
    """Before any frame: at least two views, each with depth (its view file's 'depth' is not
    null), named as the sequence file lists them (the library's checks came after frame 1 and
    named its own parameters, "keys" / "view_b")."""
    import json

    if len(seq) < 2:
        raise ValueError(f"SEQ: {seq.source} lists {len(seq)} view(s) in its 'views'; a sequence to up-convert "
                         "needs at least 2")
    for i, path in enumerate(seq.views):
        try:
            depth = json.loads(path.read_text(encoding="utf-8")).get("depth")
        except (OSError, ValueError, AttributeError):
            continue  # unreadable: load_view names the problem when the view is reached
        if depth is None:
            raise ValueError(f"SEQ: view {i} of {seq.source} ({path.name}) has no depth; every key of an "
                             "up-conversion needs depth")


def _truth_sequence(args, seq, factor, n_out):
    from pathlib import Path

    from ibr.sequence.files import load_sequence

    path = Path(args.truth) if args.truth else seq.truth
    if path is None:
        return None
    truth = load_sequence(path)
    if seq.truth_factor not in (None, factor) and not args.truth:
        info(f"interpolate: ground truth {path} is for --factor {seq.truth_factor}, not {factor}: not scored")
        return None
    what = "--truth" if args.truth else f"SEQ: its ground truth {path}"
    # the truth of N keys at factor F: (N - 1) F + 1 frames, or N F with the extrapolated tail
    fits = {(len(seq) - 1) * factor + 1, len(seq) * factor}
    if len(truth) < n_out or len(truth) not in fits:
        raise ValueError(f"{what}: {len(truth)} frames, but {len(seq)} keys at --factor {factor} make "
                         f"{' or '.join(map(str, sorted(fits)))} (the up-conversion writes {n_out}): "
                         "not the truth of these keys")
    return truth


def _add_truth_inputs(plan, args, seq, truth) -> None:
    """The ground-truth sequence (``--truth`` or the manifest's), its views and their images, as
    inputs of ``plan``."""
    from pathlib import Path

    from ibr.sequence.files import load_sequence

    path = Path(args.truth) if args.truth else seq.truth
    if path is None:
        return
    if truth is None:  # declared but not scored (another factor): still not to be written over
        try:
            truth = load_sequence(path)
        except (OSError, ValueError):
            plan.add_input("ground truth", path)
            return
    plan.add_input("ground truth", truth.source)
    for i, v in enumerate(truth.views):
        plan.add_view_input(f"ground truth view {i}", v)


def run_interpolate(args) -> int:
    """``ibr interpolate SEQ --factor F``: up-convert a whole sequence (see ibr.sequence.frame_rate)."""
    import json
    from pathlib import Path

    import numpy as np

    from ibr.io import load_view, write_image
    from ibr.io.outputs import JSON_EXTS, VIDEO_EXTS, OutputPlan, number_width
    from ibr.sequence.files import iter_views, load_sequence
    from ibr.sequence.metrics import (frame_change, psnr, static_mask_from_motion, static_mask_from_truth,
                                      summarize_flicker)
    from ibr.sequence.frame_rate import frame_count, upconvert

    factor = _check_interpolate_args(args)
    seq = load_sequence(args.views[0])
    _check_keys_listed(seq)
    n_out = frame_count(len(seq), factor, tail=not args.no_tail)
    truth = _truth_sequence(args, seq, factor, n_out)
    ext = "." + args.format
    with OutputPlan("ibr interpolate", log=info) as plan:
        plan.add_input("SEQ", seq.source)
        for i, v in enumerate(seq.views):
            plan.add_view_input(f"SEQ view {i}", v)
        _add_truth_inputs(plan, args, seq, truth)  # scored or not, the ground truth is never written over
        out = plan.add_folder("--out", args.out, patterns=(f"frame_#{ext}", "frame_#_holes.png"))
        video = plan.add_file("--video", args.video, VIDEO_EXTS)
        report = plan.add_file("--report", args.report, JSON_EXTS)
        plan.check()

        fps = args.fps  # None: not given (an explicit --fps 24 is kept)
        if fps is None:
            fps = seq.fps * factor if seq.fps else 24.0
        stream = VideoStream(plan.stage(video), fps) if video else None
        truth_views = iter_views(truth) if truth is not None else None
        info(f"interpolate: {seq.name}: {len(seq)} views -> {n_out} frames (factor {factor}"
             f"{', tail extrapolated' if not args.no_tail else ''}), fill {args.fill}"
             + (f", scored against {truth.source}" if truth is not None else ""))
        bar = Progress(n_out, "interpolate")
        rows, changes, shares, guessed = [], [], [], []
        hole_changes, hole_shares, truth_changes = [], [], []
        prev = prev_truth = None
        t_prev = time.perf_counter()
        try:
            for fr in upconvert(iter_views(seq), factor, fill=args.fill, tail=not args.no_tail,
                                method=args.method, composite_mode=args.composite,
                                interpolation=args.interpolation, supersample=args.supersample,
                                antialias=args.antialias):
                r = fr.rendering
                if fr.index == 0:  # the first key read: now say whether numba compiles (cli.main asked)
                    from commands.interpolate import first_run_kernels

                    modules, warm = first_run_kernels(args)
                    note_first_run(*modules, warm=warm)
                name = f"frame_{fr.index:0{number_width(n_out)}d}"  # sorted by name in order
                color = (_unit_float(r.color) if args.format == "exr" else _display(r.color))
                write_image(plan.stage(out, name + ext), color)
                if args.holes:
                    write_image(plan.stage(out, name + "_holes.png"), (r.holes * 255).astype(np.uint8))
                if stream is not None:
                    stream.add(r.color)
                row = {"frame": fr.index, "segment": fr.segment, "t": round(fr.t, 6), "key": fr.key,
                       "ms": round((time.perf_counter() - t_prev) * 1e3, 3), "holes": float(r.holes.mean())}
                gt = next(truth_views).color if truth_views is not None else None
                if gt is not None and not fr.key:
                    row["psnr"] = round(psnr(r.color, gt), 4)
                if prev is not None:
                    static = (static_mask_from_truth(prev_truth, gt) if gt is not None
                              else static_mask_from_motion(r.depth, r.camera, prev.camera))
                    changes.append(frame_change(prev.color, r.color, static))
                    shares.append(float(static.mean()))
                    in_holes = static & (r.holes | prev.holes)  # where the fill, not the warp, decides
                    hole_changes.append(frame_change(prev.color, r.color, in_holes))
                    hole_shares.append(float(in_holes.mean()))
                    if gt is not None:
                        truth_changes.append(frame_change(prev_truth, gt, static))
                prev, prev_truth = r, gt
                rows.append(row)
                guessed.append((f"frame {fr.index} (t={fr.t:.3f} of segment {fr.segment})", *invented(r)))
                bar.step()
                t_prev = time.perf_counter()
        finally:
            if stream is not None:
                stream.close()
        fl = summarize_flicker(changes, shares)
        fl_holes = summarize_flicker(hole_changes, hole_shares)
        inner = [row for row in rows if not row["key"]]
        med = np.median([row["ms"] for row in inner]) if inner else float("nan")
        if inner:  # --factor 1: keys only (no mean of an empty list: a RuntimeWarning and "nan%")
            info(f"interpolate: {len(inner)} new frames, median {med:.1f} ms per frame; holes "
                 f"{np.mean([row['holes'] for row in inner]):.3%} of pixels before filling")
        basis = "ground truth unchanged" if truth is not None else "static by depth and camera motion (< 0.5 px)"
        floor = summarize_flicker(truth_changes, shares).mean if truth_changes else None
        if not np.isfinite(fl.mean):  # e.g. --factor 1 (keys only, they moved): nothing stayed still
            info(f"interpolate: flicker not measured (no pixel static between consecutive frames: {basis})")
        else:
            info(f"interpolate: flicker {fl.mean * 255:.4f} 8-bit levels (mean |change| between consecutive "
                 f"frames over static pixels: {basis}; {fl.static_fraction:.1%} of pixels"
                 + (f"; the exact frames: {floor * 255:.4f}" if floor is not None and np.isfinite(floor) else "")
                 + "); "
                 + (f"in static hole pixels {fl_holes.mean * 255:.3f} ({fl_holes.static_fraction:.4%} of pixels)"
                    if np.isfinite(fl_holes.mean) else "no static pixel was a hole"))
        summary = {"frames": len(rows), "keys": len(seq), "factor": factor, "fill": args.fill,
                   "flicker": fl.mean, "flicker_8bit": fl.mean * 255, "static_fraction": fl.static_fraction,
                   "flicker_holes_8bit": fl_holes.mean * 255, "hole_static_fraction": fl_holes.static_fraction,
                   "flicker_truth_8bit": None if floor is None else floor * 255,
                   "static_basis": "truth" if truth is not None else "motion", "median_ms": med}
        scored = [row["psnr"] for row in inner if "psnr" in row]
        if scored:
            interior = [row["psnr"] for row in inner if "psnr" in row and row["t"] < 1]
            summary.update(psnr_mean=float(np.mean(scored)), psnr_min=float(np.min(scored)),
                           psnr_interior_mean=float(np.mean(interior)) if interior else None)
            info(f"interpolate: PSNR vs ground truth: mean {np.mean(scored):.2f} dB over {len(scored)} new frames "
                 f"(min {np.min(scored):.2f}; between keys {np.mean(interior):.2f} dB"
                 + (f", extrapolated tail {np.mean([x for x in scored if x not in interior]):.2f} dB)"
                    if len(interior) < len(scored) else ")"))
        if report:
            doc = _json_safe({"summary": summary, "frames": rows})  # NaN/inf (nothing to measure) -> null
            Path(plan.stage(report)).write_text(json.dumps(doc, indent=1, allow_nan=False) + "\n", encoding="utf-8")
        plan.commit()
    info(f"interpolate: wrote {len(rows)} frames to {out}/" + (f", video {video} at {fps:g} fps" if video else "")
         + (f", report {report}" if report else ""))
    warning = invented_warning("interpolate", guessed, what="the frame",
                               hint="do consecutive views see what lies between them?")
    if warning:  # exit 0 all the same: the frames are written, mostly a guess
        info(warning)
    return 0


def _json_safe(value):
    """``value`` with every non-finite float (NaN: no static hole pixel, no new frame; inf: a
    perfect PSNR) as None, so that the report is strict JSON (``NaN`` is not JSON)."""
    import math

    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def _unit_float(color):
    from ibr.sequence.metrics import as_unit_float

    c = as_unit_float(color)
    return c[..., 0] if c.shape[-1] == 1 else c


# --------------------------------------------------------------------------- stereo
def add_stereo_arguments(parser) -> None:
    """The options ``ibr stereo SEQ`` adds to the one-view command."""
    g = parser.add_argument_group("sequences (VIEW.json is a sequence manifest or a folder of numbered views; "
                                  "-o names a frame folder)")
    add_video_arguments(g)


def run_stereo(args) -> int:
    """``ibr stereo SEQ -o DIR``: one stereo pair per frame, one e and f for the whole sequence."""
    from pathlib import Path

    import numpy as np

    from ibr.io import write_image
    from ibr.io.outputs import VIDEO_EXTS, OutputPlan, number_width
    from ibr.sequence.files import iter_views, load_sequence
    from ibr.sequence.metrics import frame_change, static_mask_from_motion, summarize_flicker
    from ibr.sequence.stereo import pool_depths, sequence_stereo_params, stereo_sequence
    from ibr.stereo.pair import pack_stereo
    from ibr.stereo.stereo_camera import max_interaxial_for_range

    seq = load_sequence(args.view)
    if args.auto and (args.e is not None or args.f is not None):
        raise ValueError("--auto: give either --auto or --e/--f, not both")
    if args.e is not None and args.f is None:
        raise ValueError("--e: needs --f as well (or use --auto, or --f alone)")
    with OutputPlan("ibr stereo", log=info) as plan:
        plan.add_input("SEQ", seq.source)
        for i, v in enumerate(seq.views):
            plan.add_view_input(f"SEQ view {i}", v)
        pats = ("stereo_#.png", "stereo_#_left.png", "stereo_#_right.png", "stereo_#_holes.png")
        out = plan.add_folder("-o", args.out, patterns=pats)
        video = plan.add_file("--video", args.video, VIDEO_EXTS)
        plan.check()
        if args.f is None or args.e is None:
            depths = (v.require_depth("ibr stereo") for v in iter_views(seq))
            if args.f is None:
                e, f = sequence_stereo_params(depths, max_angle_deg=args.max_angle)
            else:
                z = pool_depths(depths)
                f = args.f
                e = max_interaxial_for_range(*np.percentile(z, [1, 99]), f, max_angle_deg=args.max_angle)
        else:
            e, f = args.e, args.f
        info(f"stereo: {seq.name}: {len(seq)} frames, one pair for all: e = {e:.6g}, f = {f:.6g}")
        fps = args.fps or (seq.fps or 24.0)
        stream = VideoStream(plan.stage(video), fps) if video else None
        bar = Progress(len(seq), "stereo")
        changes, shares, prev = [], [], None
        try:
            for i, pair in enumerate(stereo_sequence(iter_views(seq), e=e, f=f, source=args.source,
                                                     method=args.method, supersample=args.supersample,
                                                     interpolation=args.interpolation)):
                left, right = _display(pair.left), _display(pair.right)
                packed = pack_stereo(left, right, args.mode)
                name = f"stereo_{i:0{number_width(len(seq))}d}"
                if args.mode == "separate":
                    write_image(plan.stage(out, name + "_left.png"), packed[0])
                    write_image(plan.stage(out, name + "_right.png"), packed[1])
                    shown = np.concatenate(packed, axis=1)
                else:
                    write_image(plan.stage(out, name + ".png"), packed)
                    shown = packed
                if args.holes:
                    both = np.concatenate([pair.left_holes, pair.right_holes], axis=1)
                    write_image(plan.stage(out, name + "_holes.png"), both.astype(np.uint8) * 255)
                if stream is not None:
                    stream.add(shown)
                if prev is not None:
                    static = static_mask_from_motion(pair.left_depth, pair.left_camera, prev.left_camera)
                    changes.append(frame_change(prev.left, pair.left, static))
                    shares.append(float(static.mean()))
                prev = pair
                bar.step()
        finally:
            if stream is not None:
                stream.close()
        fl = summarize_flicker(changes, shares)
        info(f"stereo: flicker (left eye) {fl.mean * 255:.3f} 8-bit levels over {fl.static_fraction:.1%} static pixels")
        plan.commit()
    info(f"stereo: wrote {len(seq)} frames to {Path(args.out)}/" + (f", video {video} at {fps:g} fps" if video else ""))
    return 0


# --------------------------------------------------------------------------- samples
#: Defaults of the --sequence options of ``ibr samples`` (given without --sequence, any other
#: value is an error rather than silently ignored).
SAMPLES_SEQUENCE_DEFAULTS = {"scene": "room", "keys": 10, "factor": 4, "size": "320x240", "fps": 10.0}


def check_samples_sequence_unused(args) -> None:
    """Refuse --scene/--keys/--factor/--size/--fps of ``ibr samples`` without --sequence."""
    for name, default in SAMPLES_SEQUENCE_DEFAULTS.items():
        if getattr(args, name) != default:
            raise ValueError(f"--{name}: only used with --sequence (a synthetic sequence instead of the bundled views)")


def add_samples_arguments(parser) -> None:
    """``ibr samples --sequence``: a short synthetic RGB-D sequence with exact in-between frames."""
    from commands._common import frame_rate, number_in

    g = parser.add_argument_group("a synthetic sequence (--sequence; instead of the bundled views)")
    g.add_argument("--sequence", action="store_true",
                   help="write a camera path through a synthetic scene: key views (SCENE_walk.json) and the exact "
                        "frames of their up-conversion by --factor (SCENE_truth.json, the ground truth)")
    d = SAMPLES_SEQUENCE_DEFAULTS
    g.add_argument("--scene", type=_scene_argument, default=d["scene"],
                   help="synthetic scene of the sequence (default: %(default)s)")
    g.add_argument("--keys", type=number_in(2, 10000, integer=True, what="a number of key views"), default=d["keys"],
                   help="number of key views (default: %(default)s)")
    g.add_argument("--factor", type=FACTOR, default=d["factor"],
                   help="up-conversion factor of the ground truth (default: %(default)s)")
    g.add_argument("--size", type=_size_argument, default=d["size"], metavar="WxH",
                   help="image size (default: %(default)s)")
    g.add_argument("--fps", type=frame_rate, default=d["fps"], help="frame rate of the key views (default: %(default)s)")


def _scene_argument(name: str) -> str:
    """argparse type of ``--scene``: a scene of :data:`ibr.synth.SCENES` (else exit 2, as a bad choice)."""
    import argparse

    from ibr.synth import SCENES

    if name not in SCENES:
        raise argparse.ArgumentTypeError(f"expected one of {', '.join(SCENES)}, got {name!r}")
    return name


def _size_argument(text: str) -> str:
    """argparse type of ``--size``: WxH as :func:`_size` reads it (else exit 2, a malformed value)."""
    import argparse

    try:
        _size(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("--size: ")) from None
    return text


def _size(text: str) -> tuple[int, int]:
    import re

    m = re.fullmatch(r"(\d+)[xX](\d+)", text.strip())
    if not m or not (8 <= int(m[1]) <= 4096 and 8 <= int(m[2]) <= 4096):
        raise ValueError(f"--size: expected WxH with 8..4096 pixels each (e.g. 320x240), got {text!r}")
    return int(m[1]), int(m[2])


#: Most ground-truth frames ``ibr samples --sequence`` writes (like the other commands' frame counts),
#: and the most memory they may hold (each frame is kept until all are written).
MAX_SAMPLE_FRAMES = 100000
MAX_SAMPLE_BYTES = 4 * 2**30


def run_samples_sequence(args) -> int:
    """Write ``<scene>_walk.json`` (keys) and ``<scene>_truth.json`` (exact frames) into ``--out``."""
    from pathlib import Path

    from ibr.io.outputs import OutputPlan, number_width
    from ibr.sequence.files import save_sequence
    from ibr.synth import SCENES, camera_path, make_scene, path_frame_cameras, render_path

    if args.scene not in SCENES:
        raise ValueError(f"--scene: expected one of {', '.join(SCENES)}, got {args.scene!r}")
    if args.keys < 2:
        raise ValueError(f"--keys: expected at least 2 key views, got {args.keys}")
    if args.factor < 1:
        raise ValueError(f"--factor: expected an integer >= 1, got {args.factor}")
    if not args.fps > 0:
        raise ValueError(f"--fps: expected a positive frame rate, got {args.fps}")
    frames_total = (args.keys - 1) * args.factor + 1  # the ground truth's frames (each kept until written)
    if frames_total > MAX_SAMPLE_FRAMES:  # --keys 10000 --factor 1000 ran for hours, 10 GB before a frame
        raise ValueError(f"--keys, --factor: {args.keys} keys x {args.factor} make {frames_total} ground-truth frames; "
                         f"at most {MAX_SAMPLE_FRAMES}")
    width, height = _size(args.size)
    held = frames_total * width * height * 7  # every frame's RGB and float depth until written
    if held > MAX_SAMPLE_BYTES:
        raise ValueError(f"--keys, --factor, --size: {frames_total} frames of {width}x{height} would hold "
                         f"{held / 2**30:.1f} GiB; at most {MAX_SAMPLE_BYTES / 2**30:.0f} GiB")
    out = Path(args.out)
    keys_name, truth_name = f"{args.scene}_walk", f"{args.scene}_truth"
    pats = tuple(f"{n}{suffix}" for n in (keys_name, truth_name)
                 for suffix in (".json", "_#.json", "_#_color.png", "_#_depth.exr"))
    with OutputPlan("ibr samples", log=info) as plan:
        folder = plan.add_folder("--out", out, pats)
        plan.check()
        staged = plan.stage(folder)
        cams = camera_path(args.scene, args.keys, width=width, height=height)
        frames = path_frame_cameras(cams, args.factor)
        world = make_scene(args.scene)
        bar = Progress(len(frames), "samples: rendering", unit="frames")
        keys = []
        truth = []
        for j, cam in enumerate(frames):
            v = render_path(world, [cam], supersample=3, name=f"{truth_name}_{j:0{number_width(len(frames))}d}")[0]
            truth.append(v)
            if j % args.factor == 0:
                keys.append(v)
            bar.step()
        # Both manifests list their own view files (the truth's key frames are the keys' renders).
        save_sequence(truth, staged / f"{truth_name}.json", name=truth_name, fps=args.fps * args.factor)
        save_sequence(keys, staged / f"{keys_name}.json", name=keys_name, fps=args.fps,
                      ground_truth={"sequence": f"{truth_name}.json", "factor": args.factor})
        for n in sorted(p.name for p in Path(staged).iterdir()):
            plan.stage(folder, n)  # every file written counts as this run's
        plan.commit()
    info(f"samples: wrote {out / (keys_name + '.json')} ({len(keys)} key views, {args.fps:g} fps) and "
         f"{out / (truth_name + '.json')} ({len(truth)} exact frames of --factor {args.factor})")
    info(f"samples: try  ibr interpolate {out / (keys_name + '.json')} --factor {args.factor} --out frames")
    return 0
