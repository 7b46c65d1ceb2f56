"""``ibr canvas``: put an image, a video or strokes on a plane in an RGB-D view or a panorama."""

from __future__ import annotations

HELP = "place an image, a video or drawn strokes on a plane in a view file or a panorama (virtual canvas)"

_VIEW_EXTS = (".json",)


def add_arguments(parser) -> None:
    from commands._common import finite_float, frame_count, frame_rate, image_side, positive_float

    parser.add_argument("scene", metavar="SCENE",
                        help="a view file (.json; its depth hides what is behind) or a panorama (equirect 2:1, "
                             "cubemap image, or a folder of px/nx/py/ny/pz/nz faces)")
    what = parser.add_mutually_exclusive_group(required=True)
    what.add_argument("--image", metavar="FILE", help="image to show on the canvas (any size; resampled once)")
    what.add_argument("--video", metavar="FILE", help="video to play on the canvas (OpenCV decodes it frame by frame)")
    what.add_argument("--strokes", metavar="FILE",
                      help='strokes JSON: {"strokes": [{"points": [[x, y], ...], "width": 4, "color": "#ff0000"}], '
                           '"space": "canvas" (canvas pixels, default) or "screen" (pixels of SCENE), '
                           '"background": "#ffffff00"}')
    parser.add_argument("--center", type=finite_float, nargs=3, required=True, metavar=("X", "Y", "Z"),
                        help="canvas centre in scene units (world frame: x right, y down, z forward)")
    parser.add_argument("--normal", type=finite_float, nargs=3, required=True, metavar=("NX", "NY", "NZ"),
                        help="normal of the visible side (points toward the viewer)")
    parser.add_argument("--up", type=finite_float, nargs=3, default=(0.0, -1.0, 0.0), metavar=("UX", "UY", "UZ"),
                        help="up direction on the canvas (default 0 -1 0: world up is -y)")
    parser.add_argument("--size", type=positive_float, nargs=2, required=True, metavar=("W", "H"),
                        help="canvas width and height in scene units")
    parser.add_argument("--resolution", type=image_side, nargs=2, default=None, metavar=("PW", "PH"),
                        help="canvas buffer in pixels (default: the image's or video's size; 512 on the long "
                             "side for strokes)")
    parser.add_argument("--power-of-two", action="store_true",
                        help="resample the content into a square power-of-two texture (seed 004)")
    parser.add_argument("--depth", metavar="RANGE.exr",
                        help="panoramas: equirect range map (distance along the ray) that hides the canvas")
    parser.add_argument("--frames", type=frame_count, default=None, metavar="N", help="--video: at most N frames")
    parser.add_argument("--fps", type=frame_rate, default=None, help="--video with a video output: frame rate "
                        "(default: the input's)")
    parser.add_argument("--no-antialias", action="store_true", help="hard canvas edges")
    parser.add_argument("-o", "--output", required=True, metavar="OUT",
                        help="image (.png/.jpg/.tif/.exr; a folder for a face-folder panorama); with --video a "
                             "folder of frame_0000.png ... or a video file (.mp4/.avi/.mov/.m4v)")


def _strokes_doc(path):
    import json
    from pathlib import Path

    from ibr.base.validate import check_keys

    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"--strokes: file not found: {p}")
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"--strokes: {p} is not valid JSON ({exc})") from None
    check_keys(f"--strokes {p.name}", doc, ("strokes", "space", "background"), required=("strokes",))
    if doc.get("space", "canvas") not in ("canvas", "screen"):
        raise ValueError(f"--strokes: space: expected 'canvas' or 'screen', got {doc['space']!r}")
    if not isinstance(doc["strokes"], list):
        raise ValueError("--strokes: strokes: expected a list")
    for i, s in enumerate(doc["strokes"]):
        check_keys(f"--strokes: strokes[{i}]", s, ("points", "width", "color"), required=("points",))
    return doc


class _Target:
    """Where the canvas goes: a view (pinhole camera + depth) or a panorama (layout + range)."""

    def __init__(self, args):
        from pathlib import Path

        self.path = Path(args.scene)
        self.is_view = self.path.suffix.lower() in _VIEW_EXTS
        if self.is_view:
            from ibr.io import load_view

            if args.depth:
                raise ValueError("--depth: only for panoramas; a view file brings its own depth")
            self.view = load_view(self.path)
        else:
            from ibr.io import read_image
            from panorama.files import read_panorama

            self.pano, self.layout = read_panorama(self.path)
            self.rng = None
            if args.depth:
                if self.layout != "equirect":
                    raise ValueError("--depth: a range map is for equirect panoramas")
                self.rng = read_image(args.depth, what="--depth")
                if self.rng.ndim != 2 or self.rng.shape != self.pano.shape[:2] or self.rng.dtype.kind != "f":
                    raise ValueError(f"--depth: expected a float range map of {self.pano.shape[1]}x"
                                     f"{self.pano.shape[0]}, got {self.rng.dtype} {self.rng.shape}")
        self.antialias = not args.no_antialias

    def render(self, canvases):
        import ibr.canvas as C

        if self.is_view:
            return C.composite(self.view, canvases, antialias=self.antialias).color
        from panorama.canvas import composite_panorama

        kw = {"rng": self.rng} if self.layout == "equirect" and self.rng is not None else {}
        return composite_panorama(self.pano, canvases, layout=self.layout, antialias=self.antialias, **kw)

    def viewpoint(self):
        """The scene's camera centre (a view) or the panorama's centre (the origin), world frame."""
        import numpy as np

        return self.view.camera.position if self.is_view else np.zeros(3)

    def screen_to_canvas(self, points, canvas):
        """Canvas polylines of a stroke given in SCENE pixels."""
        import numpy as np

        import ibr.canvas as C

        if self.is_view:
            return C.stroke_from_screen(self.view.camera, points, canvas, depth=self.view.depth)
        if self.layout != "equirect":
            raise ValueError("--strokes: screen-space strokes need a view file or an equirect panorama")
        from panorama.directions import direction_from_equirect_pixel

        h, w = self.pano.shape[:2]
        q = np.asarray(points, dtype=np.float64)
        d = direction_from_equirect_pixel(q[:, 0], q[:, 1], w, h)
        scene = None
        if self.rng is not None:
            iu = np.floor(q[:, 0] + 0.5).astype(int) % w
            iv = np.clip(np.floor(q[:, 1] + 0.5).astype(int), 0, h - 1)
            scene = self.rng[iv, iu]
        index, xy, _ = C.pick_rays([canvas], np.zeros(3), d, scene_distance=scene)
        parts, cur = [], []
        for i, p in zip(index, xy):
            if i == 0:
                cur.append(p)
            elif cur:
                parts.append(np.array(cur))
                cur = []
        return parts + ([np.array(cur)] if cur else [])


def _write(path, img, plan, name=None):
    from commands._common import image_for
    from ibr.io import write_image

    write_image(plan.stage(path, name) if name else plan.stage(path), image_for(path, img))


def _note_unseen(target, img) -> None:
    """Say so when the canvas changed no pixel of the output (it was written anyway: the scene)."""
    import numpy as np

    from commands._common import info

    scene = target.view.color if target.is_view else target.pano
    if np.shape(img) == np.shape(scene) and np.array_equal(img, scene):
        info("canvas: the canvas covers no pixel of the output (behind the camera, outside the field of view or "
             "hidden behind the scene's depth), so the output is the scene unchanged; check --center and --normal")


def _note_back_side(geo, viewpoint) -> None:
    """Say so when the viewpoint sees the canvas from behind: a canvas has two faces and is drawn
    mirrored from its back (a user who gave the opposite --normal saw mirrored text, no word)."""
    import numpy as np

    from commands._common import info

    if float(np.dot(np.asarray(geo["normal"], float), viewpoint - np.asarray(geo["center"], float))) < 0:
        info("canvas: the viewpoint sees its back (--normal points away from it), so it is drawn mirrored; "
             "give the opposite --normal to see its front")


def run(args) -> int:
    from pathlib import Path

    import numpy as np

    import ibr.canvas as C
    from commands._common import face_file_patterns, info
    from ibr.io import read_image
    from ibr.io.outputs import IMAGE_EXTS, VIDEO_EXTS, OutputPlan

    if args.video is None and (args.frames is not None or args.fps is not None):
        raise ValueError("--frames, --fps: only with --video")
    if args.video is not None and Path(args.video).suffix.lower() in IMAGE_EXTS + (".bmp", ".webp"):
        raise ValueError(f"--video: {args.video} is a still image; use --image for it")
    geo = dict(center=args.center, normal=args.normal, size=args.size, up=args.up)
    out = Path(args.output)
    face_folder = Path(args.scene).is_dir()
    if args.fps is not None and out.suffix.lower() not in VIDEO_EXTS:
        raise ValueError(f"--fps: only with a video file -o ({', '.join(VIDEO_EXTS)}); frames in a folder have no rate")
    if face_folder and args.video is not None:  # each frame would be six faces (was a traceback)
        raise ValueError("--video: not on a folder of faces; make SCENE one image first "
                         "(ibr cubemap FACES -o pano.png)")
    with OutputPlan("ibr canvas", log=info) as plan:
        if Path(args.scene).suffix.lower() in _VIEW_EXTS:
            plan.add_view_input("SCENE", args.scene)
        else:
            plan.add_input("SCENE", args.scene)
        for opt, p in (("--image", args.image), ("--video", args.video), ("--strokes", args.strokes),
                       ("--depth", args.depth)):
            plan.add_input(opt, p)
        video_file = args.video is not None and out.suffix.lower() in VIDEO_EXTS
        if args.video is not None and out.suffix and not video_file:
            raise ValueError(f"-o: with --video, expected a folder for frame_0000.png ... (no extension) or a "
                             f"video file ({', '.join(VIDEO_EXTS)}), got {out}")
        if args.video is not None and not video_file:
            plan.add_folder("-o", out, patterns=("frame_#.png",))
        elif video_file:
            plan.add_file("-o", out, VIDEO_EXTS)
        elif face_folder:
            plan.add_folder("-o", out, patterns=face_file_patterns())
        else:
            plan.add_file("-o", out, IMAGE_EXTS)
        plan.check()  # every output checked before any work

        target = _Target(args)
        _note_back_side(geo, target.viewpoint())
        if args.image is not None:
            img = read_image(args.image, what="--image")
            canvas = C.canvas_from_image(img, resolution=args.resolution, power_of_two=args.power_of_two,
                                         name=Path(args.image).name, **geo)
            img = target.render([canvas])
            _note_unseen(target, img)
            _write_still(plan, out, img, face_folder)
            info(f"canvas: {canvas!r} -> {out}")
        elif args.strokes is not None:
            doc = _strokes_doc(args.strokes)
            canvas = C.Canvas(resolution=args.resolution, name="strokes", **geo)
            if "background" in doc:
                try:
                    canvas.clear(C.parse_color(doc["background"]))
                except (TypeError, ValueError) as exc:
                    raise ValueError(f"--strokes: background: {exc}") from None
            painted = 0
            for i, s in enumerate(doc["strokes"]):
                try:
                    pts = np.asarray(s["points"], dtype=np.float64)
                except (TypeError, ValueError):
                    pts = None  # strings, nested lists of different lengths, ...
                if pts is None or pts.ndim != 2 or pts.shape[1:] != (2,) or len(pts) < 1:
                    raise ValueError(f"--strokes: strokes[{i}]: points: expected a list of [x, y] pairs of numbers")
                try:
                    parts = target.screen_to_canvas(pts, canvas) if doc.get("space") == "screen" else [pts]
                    for part in parts:
                        painted += C.draw_stroke(canvas, part, width=s.get("width", 4.0),
                                                 color=s.get("color", "#ff3030"))
                except (TypeError, ValueError) as exc:
                    raise ValueError(f"--strokes: strokes[{i}]: {exc}") from None
            if painted == 0:
                info("canvas: no stroke touches the canvas (nothing drawn)")
            img = target.render([canvas])
            _note_unseen(target, img)
            _write_still(plan, out, img, face_folder)
            info(f"canvas: {len(doc['strokes'])} stroke(s), {painted} canvas pixels painted -> {out}")
        else:
            n = _run_video(args, plan, out, target, geo, video_file)
            info(f"canvas: {n} video frame(s) -> {out}")
        plan.commit()
    return 0


def _write_still(plan, out, img, face_folder):
    if face_folder:
        from panorama.directions import FACE_FILE_NAMES
        from panorama.layouts import unpack_faces

        for name, face in zip(FACE_FILE_NAMES, unpack_faces(img, "list")):
            _write(out, face, plan, f"{name}.png")
    else:
        _write(out, img, plan)


def _run_video(args, plan, out, target, geo, video_file) -> int:
    import cv2
    import numpy as np

    import ibr.canvas as C
    from commands._common import image_for, progress

    src = C.VideoSource(args.video)
    try:
        res = args.resolution or (src.size if not args.power_of_two else (C.power_of_two_size(*src.size),) * 2)
        canvas = C.Canvas(resolution=res, name="video", **geo)
        total = src.frame_count if src.frame_count > 0 else (args.frames or 0)
        if args.frames is not None:
            total = min(total, args.frames) if total > 0 else args.frames
        writer = None
        n = 0

        def frames():
            while args.frames is None or n < args.frames:
                if not src.read_into(canvas):
                    return
                yield n

        for _ in progress(frames(), max(total, 1), "canvas"):
            img = target.render([canvas])
            if video_file:
                if img.ndim != 3 or img.shape[2] != 3:
                    raise ValueError("-o: a video file needs an RGB scene")
                frame = image_for(out.with_suffix(".png"), img)
                if writer is None:
                    fourcc = cv2.VideoWriter_fourcc(*("MJPG" if out.suffix.lower() == ".avi" else "mp4v"))
                    fps = args.fps or src.fps or 25.0
                    writer = cv2.VideoWriter(str(plan.stage(out)), fourcc, fps, (frame.shape[1], frame.shape[0]))
                    if not writer.isOpened():
                        raise OSError(f"-o: OpenCV cannot write a video to {out}")
                writer.write(np.ascontiguousarray(frame[..., ::-1]))
            else:
                _write(out, img, plan, f"frame_{n:04d}.png")
            n += 1
        if writer is not None:
            writer.release()
        if n == 0:
            raise ValueError(f"--video: no frame decoded from {args.video}")
        return n
    finally:
        src.close()
