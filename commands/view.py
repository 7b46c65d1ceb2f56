"""``ibr view``: perspective views, turning tours and a local WebGL viewer of a panorama."""

from __future__ import annotations

import tempfile
import time
from pathlib import Path

from ._common import info, progress

HELP = "render a perspective view of a panorama (equirect, cubemap or face folder), a tour, or serve a web viewer"


def add_arguments(parser) -> None:
    parser.add_argument("pano", help="equirect image (2:1), cubemap image (horizon, vstrip, dice) or "
                        "a folder of px/nx/py/ny/pz/nz face files")
    parser.add_argument("-o", "--output", default=None,
                        help="view image (.png/.jpg/.tif/.exr); with --tour a .gif/.mp4 (frames go "
                        "to <stem>_frames/) or a folder for frames only")
    parser.add_argument("--layout", default=None, help="layout of PANO (default: from its shape)")
    parser.add_argument("--yaw", type=float, default=0.0,
                        help="degrees, longitude of the view centre (0 = +z, 90 = +x, right)")
    parser.add_argument("--pitch", type=float, default=0.0, help="degrees, +90 looks straight up")
    parser.add_argument("--roll", type=float, default=0.0, help="degrees, camera turned clockwise")
    parser.add_argument("--fov", type=float, default=90.0, help="horizontal field of view, degrees")
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--height", type=int, default=720)
    parser.add_argument("--tour", type=int, default=None, metavar="N",
                        help="write N frames turning once around (yaw from --yaw)")
    parser.add_argument("--fps", type=float, default=12.0, help="tour frame rate (GIF/mp4)")
    parser.add_argument("--serve", action="store_true",
                        help="serve a WebGL viewer on http://127.0.0.1:PORT (Ctrl-C stops)")
    parser.add_argument("--port", type=int, default=8000, help="port for --serve (0 = any free)")
    parser.add_argument("--site", default=None,
                        help="folder for the viewer's page and faces (default: a temporary folder)")
    parser.add_argument("--face-size", type=int, default=None, help="face size for --serve")


def _write_animation(path: Path, frames, fps: float) -> None:
    import cv2
    import numpy as np
    from ibr.io import atomic_path

    bgr = [np.ascontiguousarray(f[..., ::-1]) for f in frames]
    with atomic_path(path) as tmp:
        if path.suffix.lower() == ".gif":
            anim = cv2.Animation()
            anim.frames = bgr
            anim.durations = [int(round(1000 / fps))] * len(bgr)
            anim.loop_count = 0
            if not cv2.imwriteanimation(str(tmp), anim):
                raise OSError(f"{path}: OpenCV could not write the GIF")
        else:
            h, w = bgr[0].shape[:2]
            writer = cv2.VideoWriter(str(tmp), cv2.VideoWriter_fourcc(*"mp4v"), fps, (w, h))
            if not writer.isOpened():
                raise OSError(f"{path}: OpenCV cannot write video with this extension")
            for f in bgr:
                writer.write(f)
            writer.release()


def run(args) -> int:
    import panorama
    from ibr.io import write_image
    from panorama.files import read_panorama
    from panorama.viewer import serve, site_url, to_uint8, tour_views, write_site

    pano, layout = read_panorama(args.pano, layout=args.layout)
    if args.serve:
        folder = Path(args.site) if args.site else Path(tempfile.mkdtemp(prefix="ibr-view-"))
        write_site(folder, pano, layout=layout, face_size=args.face_size)
        server = serve(folder, port=args.port)
        info(f"view: serving {folder} at "
             f"{site_url(server, yaw_deg=args.yaw, pitch_deg=args.pitch, roll_deg=args.roll, fov_deg=args.fov)}"
             " (127.0.0.1 only; Ctrl-C stops)")
        try:
            while True:
                time.sleep(3600)
        except KeyboardInterrupt:
            info("view: stopped")
        finally:
            server.shutdown()
        return 0
    if args.output is None:
        raise ValueError("-o/--output: required unless --serve is given")
    out = Path(args.output)
    if args.tour is not None:
        if args.tour < 1:
            raise ValueError(f"--tour: expected a positive number of frames, got {args.tour}")
        frames_dir = out if out.suffix == "" else out.with_name(out.stem + "_frames")
        frames_dir.mkdir(parents=True, exist_ok=True)
        frames = []
        views = tour_views(pano, args.tour, pitch_deg=args.pitch, fov_deg=args.fov, width=args.width,
                           height=args.height, layout=layout, start_yaw_deg=args.yaw)
        for k, view in enumerate(progress(views, args.tour, "tour")):
            frame = to_uint8(view)
            write_image(frames_dir / f"frame_{k:04d}.png", frame)
            frames.append(frame)
        if out.suffix:
            _write_animation(out, frames, args.fps)
        info(f"view: {args.tour} frames in {frames_dir}" + (f", animation {out}" if out.suffix else ""))
        return 0
    view = panorama.perspective(pano, yaw_deg=args.yaw, pitch_deg=args.pitch, roll_deg=args.roll,
                                fov_deg=args.fov, width=args.width, height=args.height, layout=layout)
    if out.suffix.lower() in (".jpg", ".jpeg") or (out.suffix.lower() == ".png" and view.dtype.kind == "f"):
        view = to_uint8(view)
    write_image(out, view)
    info(f"view: yaw {args.yaw:g} pitch {args.pitch:g} roll {args.roll:g} fov {args.fov:g} -> {out}")
    return 0
