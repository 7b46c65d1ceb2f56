"""``ibr view``: perspective views, turning tours and a local WebGL viewer of a panorama."""

from __future__ import annotations

import shutil
import tempfile
import time
from pathlib import Path

from ._common import info, progress, terminate_as_interrupt

#: What ``--layout`` takes: panorama.files.read_panorama's layouts of one image (panorama.layouts'
#: single-image LAYOUTS and their aliases), listed here so that building the parser imports no
#: panorama code; tests/test_cli_audit.py checks it against panorama.layouts.
PANO_LAYOUTS = ("auto", "equirect", "horizon", "vstrip", "dice", "hstrip", "exr", "cross", "hcross")

HELP = "render a perspective view of a panorama (equirect, cubemap or face folder), a tour, or serve a web viewer"


def add_arguments(parser) -> None:
    from ._common import finite_float, frame_count, frame_rate, image_side, number_in, port_number, positive_float

    parser.add_argument("pano", help="equirect image (2:1), cubemap image (horizon, vstrip, dice) or "
                        "a folder of px/nx/py/ny/pz/nz face files; with --serve/--site also a tour file "
                        "(.json: scenes and hotspots, docs/viewer.md)")
    parser.add_argument("-o", "--output", default=None,
                        help="view image (.png/.jpg/.tif/.exr); with --tour a .gif/.mp4 (frames go "
                        "to <stem>_frames/) or a folder for frames only")
    parser.add_argument("--layout", default=None, choices=PANO_LAYOUTS, metavar="LAYOUT",
                        help=f"layout of PANO: {', '.join(PANO_LAYOUTS)} (default: from its shape)")
    # defaults None: an option given where it has no effect is refused (run); _DEFAULTS fills them in
    parser.add_argument("--yaw", type=finite_float, default=None,
                        help="degrees, longitude of the view centre (0 = +z, 90 = +x, right; default: 0); "
                        "with --serve the page's first view")
    parser.add_argument("--pitch", type=finite_float, default=None, help="degrees, +90 looks straight up (default: 0)")
    parser.add_argument("--roll", type=finite_float, default=None, help="degrees, camera turned clockwise")
    parser.add_argument("--fov", type=number_in(0, 180, lo_open=True, hi_open=True, what="an angle"), default=None,
                        help="horizontal field of view, degrees (0 < fov < 180; default: 90)")
    parser.add_argument("--width", type=image_side, default=None,
                        help="still or tour width in pixels (default: 1280)")
    parser.add_argument("--height", type=image_side, default=None,
                        help="still or tour height in pixels (default: 720)")
    parser.add_argument("--tour", type=frame_count, default=None, metavar="N",
                        help="write N frames turning once around (yaw from --yaw)")
    parser.add_argument("--fps", type=frame_rate, default=None,
                        help="frame rate of a --tour animation (.gif/.mp4; default: 12)")
    parser.add_argument("--serve", action="store_true",
                        help="serve a WebGL viewer on http://127.0.0.1:PORT (Ctrl-C stops; a temporary "
                        "site folder is removed on exit)")
    parser.add_argument("--port", type=port_number, default=None,
                        help="port for --serve (1..65535, 0 = any free; default: 8000)")
    parser.add_argument("--site", default=None,
                        help="folder for the viewer's page and faces (default: a temporary folder); "
                        "must be new or empty unless --force, in an existing folder")
    parser.add_argument("--force", action="store_true",
                        help="with --site: use a non-empty folder, replacing only the viewer's files there")
    parser.add_argument("--face-size", type=image_side, default=None, help="face size for --serve/--site")
    parser.add_argument("--tiles", action="store_true",
                        help="with --serve/--site: a multires tile pyramid (512-px tiles, faces up to 8192 px) "
                        "that the page loads as the view needs it: large panoramas open fast")
    parser.add_argument("--depth", default=None, metavar="DEPTH",
                        help="with --serve/--site: range along each ray for an equirect PANO (what ibr stitch "
                        "writes as <stem>_depth.exr); the page draws the scene as quad meshes and shows "
                        "parallax when you move (keys w a s d q e, shift-drag)")
    parser.add_argument("--head-box", type=positive_float, default=None,
                        help="with --depth: how far the viewpoint may move from the centre, scene units "
                        "(the meshes' level of detail is chosen for this move; default: 0.1)")
    parser.add_argument("--stereo", choices=("none", "top-bottom", "sbs"), default="none",
                        help="PANO is an ODS pair (ibr stitch --stereo ods): left eye on top (top-bottom) or "
                        "left | right (sbs); stills and tours show both eyes as --stereo-out; --serve/--site "
                        "writes both eyes and the page offers mono / anaglyph / side by side")
    parser.add_argument("--stereo-out", choices=("anaglyph", "sbs"), default=None,
                        help="with --stereo: how a still/tour shows the eyes (with --serve: the page's first "
                        "mode): red-cyan anaglyph (default) or side by side")


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


def _read_mono(args):
    """(pano, layout) of a mono PANO; an image of no cube layout that an ODS pair's shape fits
    (1:1 top-bottom, 4:1 side by side) is pointed to ``--stereo``."""
    import re

    from commands._common import read_panorama_arg

    try:
        return read_panorama_arg(args.pano, args.layout, "--layout")
    except ValueError as exc:
        size = re.search(r"cannot tell the layout of a (\d+) x (\d+) image", str(exc))
        pair = {1: "top-bottom", 4: "sbs"}.get(int(size[1]) // int(size[2])) if size and \
            int(size[1]) % int(size[2]) == 0 else None
        if pair is None:
            raise
        raise ValueError(f"{exc}; or, if it is an ODS pair (ibr stitch --stereo ods), --stereo {pair}") from None


def split_stereo(pano, mode: str):
    """(left, right) equirect eyes of an ODS pair packed ``top-bottom`` or ``sbs`` (PANO's message)."""
    from panorama.viewer import split_stereo as split

    try:
        return split(pano, mode)
    except ValueError as exc:
        raise ValueError(str(exc).replace("pano:", "PANO:", 1).replace("stereo panorama", "--stereo panorama")) from None


def _show_pair(left, right, how: str):
    from ibr.stereo.pair import pack_stereo

    return pack_stereo(left, right, "anaglyph" if how == "anaglyph" else "sbs")


def _serve(args, pano, layout, depth=None) -> int:
    from ibr.io.outputs import OutputPlan
    from panorama.viewer import SITE_EXTRA_PATTERNS, SITE_FILES, check_site_folder, serve, site_url, write_site

    temporary = args.site is None
    with terminate_as_interrupt():
        if temporary:
            folder = Path(tempfile.mkdtemp(prefix="ibr-view-"))
        else:
            folder = Path(args.site)
        server = None
        try:
            stereo = None if args.stereo == "none" else args.stereo
            tour = pano if layout == "tour" else None

            def write(to):
                try:
                    if tour is not None:
                        from panorama.tour import write_tour_site

                        write_tour_site(to, tour, face_size=args.face_size, force=True)
                    else:
                        write_site(to, pano, layout=layout, face_size=args.face_size, stereo=stereo,
                                   tiles=args.tiles, depth=depth, head_box=args.head_box)
                except ValueError as exc:  # the library's face_size: is the user's --face-size
                    raise ValueError(str(exc).replace("face_size:", "--face-size:", 1)) from None

            if temporary:
                write(folder)
            else:
                with OutputPlan("ibr view", log=info) as plan:
                    plan.add_input("PANO", args.pano)
                    if args.depth is not None:
                        plan.add_input("--depth", args.depth)
                    if tour is not None:  # each scene's panorama (a file, or a folder of faces) is an input
                        from panorama.tour import load_tour

                        for sid, sc in load_tour(tour)["scenes"].items():
                            plan.add_input(f"scene {sid!r} panorama", sc["panorama"])
                    site = plan.add_folder("--site", folder, SITE_FILES + SITE_EXTRA_PATTERNS)
                    plan.check()
                    write(plan.stage(site))
                    plan.commit()
            if not args.serve:
                info(f"view: wrote the viewer site {folder} (any static web server can host it)")
                return 0
            if tour is not None:
                server = serve(folder, port=args.port)
            else:
                from panorama.canvas import serve_canvas_site, store_path, write_canvas_site  # canvases (#14)

                write_canvas_site(folder)
                server = serve_canvas_site(folder, store_path(args.pano), port=args.port)
                info(f"view: click-to-place canvases are stored in {store_path(args.pano)}")
            mode = None if stereo is None else ("sbs" if args.stereo_out == "sbs" else "anaglyph")
            info(f"view: serving {folder} at "
                 f"{site_url(server, yaw_deg=args.yaw, pitch_deg=args.pitch, roll_deg=args.roll, fov_deg=args.fov, mode=mode)}"
                 " (127.0.0.1 only; Ctrl-C stops)")
            while True:
                time.sleep(3600)
        except KeyboardInterrupt:
            info("view: stopped")
        finally:
            if server is not None:
                server.shutdown()
                server.server_close()
            if temporary:
                shutil.rmtree(folder, ignore_errors=True)
                info(f"view: removed the temporary site {folder}")
    return 0


def _read_site_depth(args, pano, layout):
    """The --depth range map, checked against PANO before anything is written."""
    from ibr.io import read_depth
    from panorama.viewer import check_depth_site

    if args.stereo != "none" or args.tiles or Path(args.pano).suffix.lower() == ".json":
        raise ValueError("--depth: parallax from depth is for one mono panorama without --tiles or --stereo")
    depth = read_depth(args.depth, what="--depth", name_channel="")
    try:
        check_depth_site(pano, layout, None, False, depth)
    except ValueError as exc:
        raise ValueError(str(exc).replace("depth:", "--depth:", 1).replace("pano", "PANO")) from None
    return depth


#: Defaults of the options whose argparse default is None (so that run can tell a given option).
_DEFAULTS = {"yaw": 0.0, "pitch": 0.0, "roll": 0.0, "fov": 90.0, "width": 1280, "height": 720, "fps": 12.0,
             "port": 8000, "head_box": 0.1, "stereo_out": "anaglyph"}


def _option(name: str) -> str:
    return {"output": "-o"}.get(name, "--" + name.replace("_", "-"))


def _refuse_unused(args) -> None:
    """Refuse an option given where it has no effect (it used to be ignored, exit 0); then fill in
    the defaults of :data:`_DEFAULTS`."""
    web = args.serve or args.site is not None
    tour_file = Path(args.pano).suffix.lower() == ".json"
    animation = args.tour is not None and args.output is not None and Path(args.output).suffix != ""
    unused = []  # (option names, why)
    if web:
        unused += [(("output", "tour"), "not used with --serve/--site (the viewer goes to --site or a temporary "
                    "folder); drop --serve/--site for a still or a tour"),
                   (("width", "height"), "not used with --serve/--site (the page fills the browser window)")]
        if not args.serve:
            unused += [(("yaw", "pitch", "roll", "fov"), "only with --serve (the page's first view) or for a "
                        "still/tour; --site alone stores no view"),
                       (("port",), "only with --serve")]
        if tour_file:
            unused += [(("layout", "tiles", "depth", "head_box"), "not used for a tour file (its scenes are "
                        "read as they are)")]
    else:
        unused += [(("tiles", "face_size"), "only with --serve/--site (the web viewer)"),
                   (("port",), "only with --serve")]
    if args.depth is None:
        unused += [(("head_box",), "only with --depth")]
    if not animation:
        unused += [(("fps",), "only with --tour and an animation -o (.gif/.mp4)")]
    if args.stereo == "none":
        unused += [(("stereo_out",), "only with --stereo (an ODS pair)")]
    elif web and not args.serve:
        unused += [(("stereo_out",), "only with --serve (the page's first mode) or for a still/tour")]
    for names, why in unused:
        for name in names:
            if getattr(args, name) is not None and getattr(args, name) is not False:  # 0 is given
                raise ValueError(f"{_option(name)}: {why}")
    if args.stereo != "none" and args.layout not in (None, "auto", "equirect"):
        raise ValueError("--layout: a --stereo panorama is an equirect pair; --layout is not used")
    if args.stereo != "none" and args.tiles:
        raise ValueError("--tiles: tile pyramids are for mono panoramas; not with --stereo")
    for name, value in _DEFAULTS.items():
        if getattr(args, name) is None:
            setattr(args, name, value)


def _check_fov(args) -> None:
    """A field of view so narrow that the focal length passes the camera's ceiling, named as --fov."""
    import math

    from ibr.base.validate import MAX_FOCAL_PX

    if args.width / (2 * math.tan(math.radians(args.fov) / 2)) > MAX_FOCAL_PX:
        least = math.degrees(2 * math.atan(args.width / (2 * MAX_FOCAL_PX)))
        raise ValueError(f"--fov: expected at least {least:.3g} degrees at --width {args.width} (a focal length "
                         f"of at most {MAX_FOCAL_PX:g} pixels), got {args.fov:g}")


def _check_site(site, force):
    """--site: a new or empty folder (or --force); created with its parents, as every folder output."""
    from panorama.viewer import check_site_folder

    try:
        check_site_folder(site, force=force)
    except (NotADirectoryError, FileExistsError) as exc:
        raise type(exc)(str(exc).replace("site:", "--site:", 1).replace(" (force=True)", "")) from None


def run(args) -> int:
    import panorama
    from commands._common import image_for
    from ibr.io import write_image
    from ibr.io.outputs import ANIMATION_EXTS, IMAGE_EXTS, OutputPlan, number_width
    from commands._common import read_panorama_arg
    from ibr.io.images import check_unit_colour
    from panorama.viewer import to_uint8, tour_views

    _refuse_unused(args)
    if args.serve or args.site is not None:
        if args.site is not None:
            _check_site(args.site, args.force)  # before reading anything (#12)
        elif args.force:
            raise ValueError("--force: only with --site")
        if Path(args.pano).suffix.lower() == ".json":  # a tour of several panoramas (panorama.tour)
            from panorama.tour import load_tour

            if args.stereo != "none":
                raise ValueError("--stereo: a tour's scenes are mono panoramas; view a stereo panorama on its own")

            load_tour(args.pano)  # every scene, hotspot and link checked before the site is written
            return _serve(args, Path(args.pano), "tour")
        if args.stereo != "none":
            from ibr.io import read_image

            pano, layout = read_image(args.pano, what="PANO"), "equirect"
            split_stereo(pano, args.stereo)  # the packing is checked before the site is written
        else:
            pano, layout = read_panorama_arg(args.pano, args.layout, "--layout")
            check_unit_colour("PANO", pano, "the viewer's 8-bit faces",
                              "a range map is the --depth of a colour PANO")
        depth = _read_site_depth(args, pano, layout) if args.depth is not None else None
        return _serve(args, pano, layout, depth)
    if args.depth is not None:
        raise ValueError("--depth: parallax from depth is shown by the web viewer: add --serve or --site DIR")
    if args.force:
        raise ValueError("--force: only with --site")
    if Path(args.pano).suffix.lower() == ".json":
        raise ValueError(f"PANO: {args.pano} is a tour file; tours are shown by the web viewer: add --serve or --site DIR")
    if args.output is None:
        raise ValueError("-o/--output: required unless --serve is given")
    _check_fov(args)
    out = Path(args.output)
    with OutputPlan("ibr view", log=info) as plan:
        plan.add_input("PANO", args.pano)
        if args.tour is not None:
            frames_dir = out if out.suffix == "" else out.with_name(out.stem + "_frames")
            frames = plan.add_folder("-o (tour frames)", frames_dir, ("frame_#.png",))
            anim = plan.add_file("-o", out, ANIMATION_EXTS) if out.suffix else None
        else:
            image = plan.add_file("-o", out, IMAGE_EXTS)
        plan.check()  # every output checked before any work (#12)
        if args.stereo != "none":
            from ibr.io import read_image

            eyes = split_stereo(read_image(args.pano, what="PANO"), args.stereo)
            pano, layout = eyes[0], "equirect"
        else:
            eyes, (pano, layout) = None, _read_mono(args)
            eight_bit = args.tour is not None or out.suffix.lower() in (".png", ".jpg", ".jpeg")
            if eight_bit:  # before any view is rendered
                tour = args.tour is not None
                check_unit_colour("PANO", pano, "the tour's frames" if tour else out.name,
                                  f"view {'a still of ' if tour else ''}it to .exr, .tif or .pfm")
        if args.tour is not None:
            kept = []
            kw = dict(pitch_deg=args.pitch, roll_deg=args.roll, fov_deg=args.fov, width=args.width,
                      height=args.height, layout=layout, start_yaw_deg=args.yaw)
            if eyes is None:
                views = tour_views(pano, args.tour, **kw)
            else:
                views = (_show_pair(to_uint8(a), to_uint8(b), args.stereo_out)
                         for a, b in zip(tour_views(eyes[0], args.tour, **kw), tour_views(eyes[1], args.tour, **kw)))
            for k, view in enumerate(progress(views, args.tour, "tour")):
                frame = to_uint8(view)
                write_image(plan.stage(frames, f"frame_{k:0{number_width(args.tour)}d}.png"), frame)
                if anim:  # only an animation needs the frames in memory (1000 large frames did not fit)
                    kept.append(frame)
            if anim:
                _write_animation(plan.stage(anim), kept, args.fps)
            plan.commit()
            info(f"view: {args.tour} frames in {frames_dir}" + (f", animation {out}" if anim else ""))
            return 0
        kw = dict(yaw_deg=args.yaw, pitch_deg=args.pitch, roll_deg=args.roll, fov_deg=args.fov, width=args.width,
                  height=args.height, layout=layout)
        if eyes is None:
            view = panorama.perspective(pano, **kw)
        else:  # an ODS pair: each eye's view, shown as anaglyph or side by side
            view = _show_pair(to_uint8(panorama.perspective(eyes[0], **kw)),
                              to_uint8(panorama.perspective(eyes[1], **kw)), args.stereo_out)
        write_image(plan.stage(image), image_for(image, view))  # uint8 for .png / .jpg, float for .exr
        plan.commit()
    info(f"view: yaw {args.yaw:g} pitch {args.pitch:g} roll {args.roll:g} fov {args.fov:g} -> {out}")
    return 0
