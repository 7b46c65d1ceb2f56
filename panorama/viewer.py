"""Photosphere viewer: turning tours and a local WebGL page fed by cube faces.

* :func:`tour_views` renders N perspective views turning once around the vertical axis.
* :func:`write_site` writes the static page (``panorama/web/index.html``) next to six 8-bit face
  files ``px.png .. nz.png`` (canonical orientation, :mod:`panorama.directions`) and
  ``viewer.json``; for a stereo (ODS) panorama also the right eye's ``px_r.png .. nz_r.png``, and
  the page offers mono / red-cyan anaglyph / side-by-side (phone headsets) with a button, the
  ``m`` key or ``?mode=``.
* :func:`serve` serves such a folder on 127.0.0.1 only (``http.server``) from a background
  thread; the caller stops it with ``server.shutdown()``. Only the page and the six faces are
  served, never other files that happen to be in the folder.
* :func:`check_site_folder` is the rule for a user-named site folder: new or empty, unless
  ``force`` (then only the viewer's own files in it are replaced).

The page renders every pixel's ray exactly like :func:`panorama.perspective` (pixel centres at
integers, ``fov`` across the full width) and takes ``?yaw=&pitch=&roll=&fov=`` in the URL;
drag to look, scroll to zoom.
"""

from __future__ import annotations

import functools
import http.server
import json
import re
import shutil
import threading
from pathlib import Path

import cv2
import numpy as np

from ibr.base.validate import MAX_IMAGE_SIDE

from .convert import equirect_to_cubemap, perspective
from .directions import FACE_FILE_NAMES
from ibr.io import write_image
from ibr.io.images import check_unit_colour
from .layouts import unpack_faces

__all__ = ["SITE_FILES", "STEREO_LAYOUTS", "VIEW_MODES", "WEB_DIR", "check_depth_site", "check_site_folder", "serve",
           "site_url", "split_stereo", "to_uint8", "tour_views", "write_site"]

WEB_DIR = Path(__file__).with_name("web")
#: The files of a viewer site: what write_site writes and the only files serve() serves.
_FACES = FACE_FILE_NAMES  # px, nx, py, ny, pz, nz
SITE_FILES = (("index.html", "viewer.json", "mesh.bin") + tuple(f"{n}.png" for n in _FACES)
              + tuple(f"{n}_r.png" for n in _FACES))
#: Largest cube face the site writes: 4096 px is the safe WebGL cube-map size on phones (the page
#: also checks its own device's MAX_CUBE_MAP_TEXTURE_SIZE and says so instead of a black page).
MAX_FACE_SIZE = 4096
#: (yaw, pitch) of each face (px nx py ny pz nz) as a 90-degree perspective view: the same rays
FACE_VIEWS = ((90.0, 0.0), (-90.0, 0.0), (0.0, -90.0), (0.0, 90.0), (0.0, 0.0), (180.0, 0.0))
#: Largest face of a tile pyramid: levels finer than a device's cube limit are drawn as their
#: tiles (textured quads), so a 16384-wide panorama keeps its own resolution (faces of 8192 px).
MAX_TILED_FACE_SIZE = 8192
#: How a stereo panorama packs its eyes (what ``ibr stitch --stereo ods --layout`` writes).
STEREO_LAYOUTS = ("top-bottom", "sbs")
#: What the page shows of a stereo panorama (``?mode=``); mono panoramas show "mono" only.
VIEW_MODES = ("mono", "anaglyph", "sbs")


def split_stereo(pano, layout: str):
    """(left, right) equirect eyes of an ODS pair packed ``"top-bottom"`` (left eye on top: each
    eye W x W/2, so the image is square) or ``"sbs"`` (left | right: 4:1)."""
    if layout not in STEREO_LAYOUTS:
        raise ValueError(f"stereo: expected one of {', '.join(STEREO_LAYOUTS)}, got {layout!r}")
    a = np.asarray(pano) if isinstance(pano, np.ndarray) else None
    if a is None or a.ndim not in (2, 3):
        raise ValueError("pano: a stereo panorama must be one packed equirect image (not cube faces)")
    h, w = a.shape[:2]
    if layout == "top-bottom":
        if h % 2 or w != h:
            raise ValueError(f"pano: a top-bottom ODS pair of 2:1 eyes is square (W = H, H even), got {w}x{h}")
        return a[: h // 2], a[h // 2:]
    if w % 2 or w != 4 * h:
        raise ValueError(f"pano: a side-by-side ODS pair of 2:1 eyes is 4:1 (W = 4 H), got {w}x{h}")
    return a[:, : w // 2], a[:, w // 2:]


def check_site_folder(folder, *, force: bool = False) -> Path:
    """Refuse a site folder that is an existing file, or a non-empty folder unless ``force``.

    Raises ``NotADirectoryError`` or ``FileExistsError`` (whose message says to use ``--force`` /
    ``force=True``); with ``force`` only :data:`SITE_FILES` in the folder are replaced.
    """
    folder = Path(folder)
    if folder.exists() and not folder.is_dir():
        raise NotADirectoryError(f"site: {folder} exists and is not a folder")
    if folder.is_dir() and not force:
        others = sorted(p.name for p in folder.iterdir())
        if others:
            raise FileExistsError(
                f"site: {folder} is not empty ({len(others)} entries, e.g. {others[0]!r}); choose a new or empty "
                "folder, or pass --force (force=True) to replace only its viewer files (index.html, px.png..nz.png)")
    return folder


def to_uint8(img: np.ndarray) -> np.ndarray:
    """8-bit copy for display: uint16 scaled by 1/257, floats clipped to [0, 1] and scaled by 255."""
    if img.dtype == np.uint8:
        return img
    if img.dtype == np.uint16:
        return ((img.astype(np.uint32) + 128) // 257).astype(np.uint8)
    if img.dtype.kind == "f":
        return np.clip(np.rint(np.nan_to_num(img) * 255.0), 0, 255).astype(np.uint8)
    raise TypeError(f"image: cannot display dtype {img.dtype}")


def tour_views(pano, n: int, *, pitch_deg: float = 0.0, fov_deg: float = 90.0, width: int = 640,
               height: int = 360, layout: str | None = None, start_yaw_deg: float = 0.0, roll_deg: float = 0.0):
    """Yield ``n`` perspective views at yaw = start + 360 k / n (k = 0..n-1), each at ``pitch_deg``
    and ``roll_deg``."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"n: expected a positive integer number of frames, got {n!r}")
    for k in range(n):
        yield perspective(pano, yaw_deg=start_yaw_deg + 360.0 * k / n, pitch_deg=pitch_deg, roll_deg=roll_deg,
                          fov_deg=fov_deg, width=width, height=height, layout=layout)


def write_site(folder, pano, *, layout: str | None = None, face_size: int | None = None,
               force: bool = False, stereo: str | None = None, tiles: bool = False, depth=None,
               head_box: float = 0.1) -> Path:
    """Write ``index.html``, ``viewer.json`` and the faces into ``folder``; return the page's path.

    ``pano`` is an equirect image (converted to faces of ``face_size``, default width / pi rounded
    up to a power of two, capped at 2048: the page mipmaps the faces, which WebGL1 allows only for
    power-of-two sizes) or a cubemap in ``layout``. With ``stereo``
    (``"top-bottom"`` or ``"sbs"``, :data:`STEREO_LAYOUTS`) ``pano`` is a packed ODS pair: the left
    eye goes to ``px.png .. nz.png``, the right eye to ``px_r.png .. nz_r.png``. ``folder`` must
    be new or empty unless ``force`` (:func:`check_site_folder`). With ``tiles`` the faces (default
    the panorama's own resolution, up to 8192 px) become a multires pyramid
    (:mod:`panorama.tiles`): base faces of 512 px, then levels of 512-px tiles the page loads as
    the view needs them. With ``depth`` (an (H, 2H) float range map of an equirect ``pano``,
    scene units, NaN = none) the site also holds ``mesh.bin``, the quad meshes of the six faces
    (:mod:`panorama.face_meshes`, level of detail for a move of ``head_box``), and the page shows
    motion parallax when the viewpoint moves; face pixels without depth get alpha 0 (drawn at
    infinity).
    """
    if tiles and stereo is not None:
        raise ValueError("tiles: tile pyramids are for mono panoramas (a stereo pair holds two face sets)")
    if depth is not None:
        check_depth_site(pano, layout, stereo, tiles, depth)
    check_unit_colour("pano", pano, "the site's faces", "a range map is the depth of a colour panorama (depth=, --depth)")
    eyes = split_stereo(pano, stereo) if stereo is not None else (pano,)
    largest = MAX_TILED_FACE_SIZE if tiles else MAX_FACE_SIZE
    if face_size is not None and face_size > largest:
        raise ValueError(f"face_size: {face_size} px faces exceed what phones and many GPUs show "
                         f"({largest} px per {'tiled face' if tiles else 'cube face; more with --tiles'}); "
                         f"choose --face-size <= {largest}")
    folder = check_site_folder(folder, force=force)
    if tiles and face_size is None:  # the panorama's own resolution, a power of two, <= 8192
        face_size = _pow2_face_size(_equirect_width(pano, layout), 512, MAX_TILED_FACE_SIZE)
    faces_per_eye = [_faces(eye, layout, face_size) for eye in eyes]  # all converted before writing
    config = {"stereo": stereo is not None}
    if depth is not None:
        mesh_bytes, faces_per_eye[0] = _depth_mesh(pano, depth, faces_per_eye[0], head_box)
        config["mesh"] = {"file": "mesh.bin", "head_box": float(head_box), "bytes": len(mesh_bytes)}
    folder.mkdir(parents=True, exist_ok=True)
    if tiles:
        from .tiles import TILE, write_tiles

        top = faces_per_eye[0]
        config["tiles"] = write_tiles(folder, top, _FACES, TILE, write_image)
        faces_per_eye = [[cv2.resize(f, (TILE, TILE), interpolation=cv2.INTER_AREA) if f.shape[0] != TILE else f
                          for f in top]]
    if depth is not None:
        (folder / "mesh.bin").write_bytes(mesh_bytes)
    for faces, suffix in zip(faces_per_eye, ("", "_r")):
        for name, face in zip(_FACES, faces):
            write_image(folder / f"{name}{suffix}.png", face)
    (folder / "viewer.json").write_text(json.dumps(config) + "\n")
    return copy_page(folder)


#: The page's tag for the canvas UI (``canvas.js``): kept only in sites that
#: :func:`panorama.canvas.write_canvas_site` completes for ``ibr view PANO --serve`` (the UI
#: saves through that server); a static site asked for a file it does not have (a 404 on every load).
CANVAS_SCRIPT_TAG = '<script src="canvas.js"></script>'


def copy_page(folder, *, canvas: bool = False) -> Path:
    """Write the viewer page into a site ``folder``; return its path. ``canvas``: keep the tag
    that loads the canvas UI (:data:`CANVAS_SCRIPT_TAG`; only sites served with their canvas
    store have ``canvas.js``)."""
    from ibr.io import atomic_path

    page = Path(folder) / "index.html"
    html = (WEB_DIR / "index.html").read_text(encoding="utf-8")
    if CANVAS_SCRIPT_TAG not in html:
        raise RuntimeError(f"{WEB_DIR / 'index.html'}: no {CANVAS_SCRIPT_TAG} (the page and viewer.py disagree)")
    if not canvas:
        html = html.replace(CANVAS_SCRIPT_TAG, "")
    with atomic_path(page) as tmp:  # write_canvas_site rewrites the page of a finished site
        tmp.write_text(html, encoding="utf-8")
    return page


def check_depth_site(pano, layout, stereo, tiles, depth) -> None:
    """Refuse what a depth site cannot show: one mono equirect ``pano`` and a float range map
    ``depth`` of its shape (positive, NaN where there is none)."""
    if stereo is not None or tiles:
        raise ValueError("depth: parallax from depth is for a mono panorama without tiles "
                         "(drop --stereo / --tiles, or the depth)")
    if not (isinstance(pano, np.ndarray) and pano.ndim in (2, 3) and pano.shape[1] == 2 * pano.shape[0]) \
            or layout not in (None, "equirect"):
        raise ValueError("depth: give the panorama as an equirect image (W = 2 H), the grid of its range map")
    rng = np.asarray(depth)
    if rng.shape != pano.shape[:2]:
        raise ValueError(f"depth: expected shape {pano.shape[:2]} (the panorama's), got {rng.shape}")
    if rng.dtype.kind != "f":
        raise TypeError(f"depth: expected a float range map, got dtype {rng.dtype}")
    with np.errstate(invalid="ignore"):
        if np.any(rng <= 0) or np.all(np.isnan(rng)):
            raise ValueError("depth: expected positive ranges along the rays (NaN where there is none), "
                             "got values <= 0 or no depth at all")


def _depth_mesh(pano, depth, faces, head_box):
    """(mesh.bin bytes, faces with alpha 0 where a face pixel has no depth)."""
    from .face_meshes import face_meshes, pack_face_meshes

    meshes = face_meshes(pano, np.asarray(depth), face_size=faces[0].shape[0], head_box=head_box)
    out = []
    for face, mesh in zip(faces, meshes):
        rgb = face if face.ndim == 3 else np.repeat(face[..., None], 3, -1)
        alpha = np.where(mesh.quad_of_pixel >= 0, 255, 0).astype(np.uint8)
        out.append(np.dstack([rgb[..., :3], alpha]))
    return pack_face_meshes(meshes), out


def _pow2_face_size(width: int, smallest: int, largest: int) -> int:
    """Faces for a ``width``-wide equirect: the power of two >= width / pi (its own resolution),
    within [smallest, largest]."""
    return int(min(largest, 2 ** int(np.ceil(np.log2(max(width / np.pi, smallest))))))


def _faces(pano, layout, face_size):
    """Six uint8 faces (px, nx, py, ny, pz, nz) of an equirect image or a cubemap."""
    if _is_equirect(pano, layout):
        if face_size is None:  # a power of two (mipmaps on WebGL1 too), >= width / pi, <= 2048
            face_size = _pow2_face_size(pano.shape[1], 8, 2048)
        faces = (equirect_to_cubemap(pano, face_size, layout="list") if 6 * face_size <= MAX_IMAGE_SIDE
                 else [perspective(pano, yaw_deg=y, pitch_deg=p, fov_deg=90.0, width=face_size, height=face_size)
                       for y, p in FACE_VIEWS])  # one face at a time: six 8192-px faces exceed one image
    else:
        from .convert import detect_layout
        faces = unpack_faces(pano, layout or detect_layout(pano))
        s = faces[0].shape[0]
        if face_size is None:  # as for an equirect: a power of two (WebGL1 mipmaps), >= the faces', <= 2048
            face_size = _pow2_face_size(int(np.floor(np.pi * s)), 8, 2048)
        if s != face_size:  # (face_size was ignored here: 600-px faces stayed 600, 4100-px ones passed the limit)
            interp = cv2.INTER_AREA if face_size < s else cv2.INTER_LINEAR
            faces = [cv2.resize(np.ascontiguousarray(f), (face_size, face_size), interpolation=interp) for f in faces]
    return [to_uint8(np.ascontiguousarray(f)) for f in faces]


def _is_equirect(pano, layout) -> bool:
    """Whether ``pano`` is an equirect image: so declared, or undeclared and 2:1."""
    return layout == "equirect" or (layout is None and isinstance(pano, np.ndarray)
                                    and pano.ndim >= 2 and pano.shape[1] == 2 * pano.shape[0])


def _equirect_width(pano, layout) -> int:
    """The width of an equirect ``pano``, or of the equirect matching a cubemap's faces (pi S)."""
    if _is_equirect(pano, layout):
        return int(pano.shape[1])
    from .convert import detect_layout
    s = unpack_faces(pano, layout or detect_layout(pano))[0].shape[0]
    return int(np.floor(np.pi * s))


#: File-name patterns (``#``: digits) of the site files beyond SITE_FILES, for an output plan:
#: a tour scene's faces and the tiles, not a user's scene-my-holiday.png or tile-notes.png.
SITE_EXTRA_PATTERNS = (tuple(f"scene-*-{n}.png" for n in _FACES) + tuple(f"tile-#-{n}-#-#.png" for n in _FACES))
#: Site files beyond SITE_FILES: a tour scene's faces (``panorama.tour``), scene-<id>-px.png .., and tiles
_EXTRA_SITE_FILE = re.compile(r"^scene-[A-Za-z0-9][A-Za-z0-9_-]{0,63}-(px|nx|py|ny|pz|nz)\.png$"
                        r"|^tile-[0-9]{1,2}-(px|nx|py|ny|pz|nz)-[0-9]{1,3}-[0-9]{1,3}\.png$")  # and tiles


class _SiteHandler(http.server.SimpleHTTPRequestHandler):
    """Serves only the viewer's own files (:data:`SITE_FILES`, a tour's scene faces); anything
    else is 404 (#12)."""

    quiet = True

    def send_head(self):
        name = self.path.split("?", 1)[0].split("#", 1)[0].lstrip("/") or "index.html"
        if name not in SITE_FILES and not _EXTRA_SITE_FILE.match(name):
            self.send_error(404, "Not part of the viewer site")
            return None
        return super().send_head()

    def log_message(self, format, *args):  # noqa: A002 - http.server's signature
        if not self.quiet:
            super().log_message(format, *args)


class _LoudSiteHandler(_SiteHandler):
    quiet = False


def serve(folder, *, port: int = 0, quiet: bool = True) -> http.server.ThreadingHTTPServer:
    """Serve ``folder`` on http://127.0.0.1:<port>/ from a daemon thread (port 0 = any free one).

    Returns the running server; ``server.server_address[1]`` is the port, ``server.shutdown()``
    stops it. Only the loopback interface is bound, and only :data:`SITE_FILES` are served.
    """
    folder = Path(folder)
    if not (folder / "index.html").is_file():
        raise FileNotFoundError(f"folder: {folder} has no index.html (write it with write_site)")
    if isinstance(port, bool) or not isinstance(port, (int, np.integer)) or not 0 <= port <= 65535:
        raise ValueError(f"port: expected 1..65535 (or 0 for any free port), got {port!r}")
    handler = functools.partial(_SiteHandler if quiet else _LoudSiteHandler, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", int(port)), handler)
    threading.Thread(target=server.serve_forever, daemon=True, name="panorama-viewer").start()
    return server


def site_url(server, *, yaw_deg=0.0, pitch_deg=0.0, roll_deg=0.0, fov_deg=90.0, hud=True,
             mode: str | None = None) -> str:
    """URL of the page served by ``server`` at a given view (``mode``: one of :data:`VIEW_MODES`;
    ``fov_deg`` is across each eye's image, i.e. across half the page in ``"sbs"``)."""
    if mode is not None and mode not in VIEW_MODES:
        raise ValueError(f"mode: expected one of {', '.join(VIEW_MODES)}, got {mode!r}")
    port = server.server_address[1]
    return (f"http://127.0.0.1:{port}/index.html?yaw={yaw_deg:g}&pitch={pitch_deg:g}"
            f"&roll={roll_deg:g}&fov={fov_deg:g}" + ("" if hud else "&hud=0") + (f"&mode={mode}" if mode else ""))
