"""``ibr timewarp``: re-project a rendered RGB-D frame to a list of newer head poses.

``poses.json`` holds a list (or ``{"poses": [...]}``) of 4x4 camera-to-world matrices, or of
camera objects in the view-file schema (``fx, fy, cx, cy, width, height, world_from_cam``).
Matrices use the view's intrinsics shrunk by ``--margin`` pixels on every side (the view is a
guard-band render larger than the display). Rotations are warped by the exact homography with
edge replication; moved poses through the renderer with depth (``--mode auto``).
"""

from __future__ import annotations

HELP = "time-warp a rendered frame to new head poses (rotation homography, depth warp, guard band)"


def add_arguments(parser) -> None:
    from commands._common import nonnegative_int

    parser.add_argument("view", metavar="VIEW.json", help="rendered frame (guard-band render) as a view file")
    parser.add_argument("--poses", required=True, metavar="POSES.json", help="new head poses")
    parser.add_argument("--margin", type=nonnegative_int, default=0, metavar="PX",
                        help="guard band of the view on every side, cropped from the output (default: 0)")
    parser.add_argument("--mode", choices=("auto", "rotation", "depth"), default="auto",
                        help="auto: homography for pure rotations, depth warp when the head moved")
    parser.add_argument("-o", "--out", required=True, metavar="DIR", help="output folder (frame_0000.png, ...; frames of an earlier run there are replaced, "
                             "other files left alone)")


def load_cameras(path, display):
    import json
    from pathlib import Path

    import numpy as np

    from ibr.base.camera import Camera

    p = Path(path)
    if not p.is_file():
        raise FileNotFoundError(f"--poses: {p} does not exist")
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"--poses: {p} is not valid JSON ({exc})") from None
    if isinstance(doc, dict):
        from ibr.base.validate import check_keys

        check_keys(f"--poses: {p}", doc, ("poses",), required=("poses",))  # "pose": nearest name, never ignored
    items = doc.get("poses") if isinstance(doc, dict) else doc
    if not isinstance(items, list) or not items:
        raise ValueError(f"--poses: expected a non-empty list of poses in {p}")
    cams = []
    for i, item in enumerate(items):
        try:
            if isinstance(item, dict):
                cams.append(Camera.from_dict(item))  # strict: unknown keys refused (#12)
            else:
                from ibr.base.validate import check_number

                if not (isinstance(item, list) and len(item) == 4
                        and all(isinstance(r, list) and len(r) == 4 for r in item)):
                    raise ValueError(f"expected a 4x4 matrix or a camera object, got {str(item)[:80]}")
                m = np.array([[check_number(f"[{r}][{c}]", v) for c, v in enumerate(row)]
                              for r, row in enumerate(item)], dtype=float)
                cams.append(display.with_pose(m))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"--poses: {p}: pose {i}: {exc}") from None
    return cams


def run(args) -> int:
    from dataclasses import replace

    from commands._common import image_for, info, progress
    from ibr.io import load_view, write_image
    from ibr.io.outputs import OutputPlan, number_width
    from ibr.stereo.timewarp import timewarp, timewarp_mode

    with OutputPlan("ibr timewarp", log=info) as plan:
        plan.add_view_input("VIEW", args.view)
        plan.add_input("--poses", args.poses)
        out = plan.add_folder("-o", args.out, ("frame_#.png",))
        plan.check()  # every output checked before any work (#12)
        view = load_view(args.view)
        m = args.margin
        cam = view.camera
        if m < 0 or 2 * m >= min(cam.width, cam.height):
            raise ValueError(f"--margin: expected 0 <= margin < half the view size, got {m}")
        display = replace(cam, cx=cam.cx - m, cy=cam.cy - m, width=cam.width - 2 * m, height=cam.height - 2 * m)
        cams = load_cameras(args.poses, display)
        if view.depth is None:  # a pose that needs depth is found before any frame is warped
            moved = next((i for i, c in enumerate(cams) if timewarp_mode(view.camera, c, mode=args.mode) == "depth"),
                         None)
            if moved is not None:
                try:
                    view.require_depth("a depth time-warp")
                except ValueError as exc:  # the library's words, without its "view 'name': "
                    raise ValueError(f"VIEW: {args.view}: pose {moved} of --poses "
                                     + ("moves the head: " if args.mode == "auto" else "(--mode depth): ")
                                     + str(exc).removeprefix(f"view {view.name!r}: ")
                                     + ("; give a view with depth or --mode rotation" if args.mode == "auto" else "")
                                     ) from None
        for i, c in progress(enumerate(cams), len(cams), "timewarp"):
            fr = timewarp(view, c, mode=args.mode)
            path = plan.stage(out, f"frame_{i:0{number_width(len(cams))}d}.png")
            write_image(path, image_for(path, fr.color))
            if fr.outside.any():
                info(f"timewarp: frame {i}: {fr.outside.mean():.1%} beyond the guard band (edge replicated)")
        plan.commit()
    info(f"timewarp: wrote {len(cams)} frames to {out}")
    return 0
