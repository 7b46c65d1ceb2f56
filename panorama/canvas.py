"""Virtual canvases in photospheres: equirect/cubemap compositing, picking, the viewer's store.

Builds on :mod:`ibr.canvas` (the canvas, its exact mapping, picking and the homography
compositor) for the spherical targets of :mod:`panorama`:

* **Cube faces** are 90-degree pinhole cameras (:func:`face_camera`), so a canvas goes into each
  face by one homography, exactly as into any perspective view (:func:`view_camera`).
* **Equirect images** get per-pixel rays (:func:`ibr.canvas.composite_rays_into`), a block of
  rows at a time.
* **Picking**: an equirect pixel or a pixel of a perspective view of the panorama -> ray from the
  panorama's centre -> nearest canvas in front of the scene's range (if a range map is given).
* **The store**: canvases placed in ``ibr view --serve`` are kept in a small JSON file next to the
  panorama (:func:`store_path`: ``room.png`` -> ``room.canvas.json``, images it uses in
  ``room.canvas-images/``), loaded on start, rebuilt into :class:`~ibr.canvas.Canvas` objects by
  :func:`canvases_from_store`; :func:`serve_canvas_site` serves the viewer page with
  ``canvas.js`` (click to place an image, drag to draw) and accepts the page's saves.

Frames: world = the panorama's frame (x right, y down, z forward; up = -y); longitude 0 = +z
growing toward +x; pixel centres at integers (:mod:`panorama.directions`). Depth for occlusion:
range along the ray for equirect images, planar z per face for cube faces.

Store format (version 1)::

    {"version": 1, "canvases": [
      {"kind": "image", "image": "room.canvas-images/poster.png",
       "center": [x, y, z], "normal": [x, y, z], "up": [x, y, z], "size": [w, h]},
      {"kind": "strokes", "center": [...], "normal": [...], "up": [...], "size": [w, h],
       "resolution": [W, H], "strokes": [{"points": [[x, y], ...], "width": 4, "color": "#ff3030"}]}
    ]}

``image`` is relative to the JSON's folder (no ``..``); stroke points are canvas pixels.
"""

from __future__ import annotations

import functools
import http.server
import json
import math
import os
import re
import shutil
import threading
from pathlib import Path

import numpy as np

from ibr.base.camera import Camera
from ibr.base.validate import check_choice, check_finite_scalar, check_keys, check_number, check_relative_path
from ibr.canvas import Canvas, canvas_from_image, composite_into, composite_rays_into, draw_stroke, parse_color
from ibr.canvas.pick import Pick, pick_rays
from ibr.canvas.plane import MAX_TEXELS

from .directions import (WORLD_FROM_FACE, direction_from_equirect_pixel, equirect_pixel_from_direction,
                         world_from_view)
from .layouts import LAYOUTS, canonical_layout, layout_faces, unpack_faces
from .viewer import _SiteHandler

__all__ = [
    "STORE_VERSION",
    "canvases_from_store",
    "composite_cubemap",
    "composite_equirect",
    "composite_panorama",
    "composite_perspective",
    "empty_store",
    "face_camera",
    "load_store",
    "pick_equirect",
    "pick_view",
    "save_store",
    "serve_canvas_site",
    "store_image_dir",
    "store_path",
    "view_camera",
    "write_canvas_site",
]

STORE_VERSION = 1
_MAX_STORE_BYTES = 4 << 20      # a store is small: geometry, file names and stroke points
_MAX_UPLOAD_BYTES = 32 << 20    # one image placed from the page
_MAX_CANVASES = 256


# ----------------------------------------------------------------------------- cameras
def face_camera(face: int, face_size: int, *, origin=(0.0, 0.0, 0.0)) -> Camera:
    """The 90-degree pinhole camera of cube face ``face`` (0..5 in +x -x +y -y +z -z order).

    ``fx = fy = S/2``, ``cx = cy = (S - 1)/2``: face pixel (i, j) looks along
    ``right * a + down * b + forward`` with ``a = 2 (i + 1/2)/S - 1`` (:mod:`panorama.directions`).
    """
    f = int(face)
    if not 0 <= f < 6:
        raise ValueError(f"face: expected 0..5, got {face!r}")
    s = check_number("face_size", face_size, integer=True, minimum=1)
    pose = np.eye(4)
    pose[:3, :3] = WORLD_FROM_FACE[f]
    pose[:3, 3] = np.asarray(origin, dtype=np.float64)
    return Camera(s / 2, s / 2, (s - 1) / 2, (s - 1) / 2, s, s, pose)


def view_camera(yaw_deg: float, pitch_deg: float, roll_deg: float, fov_deg: float, width: int, height: int,
                *, origin=(0.0, 0.0, 0.0)) -> Camera:
    """The pinhole camera of :func:`panorama.perspective` (``Camera.from_fov`` with the
    ``world_from_view`` rotation), at ``origin``."""
    pose = np.eye(4)
    pose[:3, :3] = world_from_view(yaw_deg, pitch_deg, roll_deg)
    pose[:3, 3] = np.asarray(origin, dtype=np.float64)
    return Camera.from_fov(width, height, hfov_deg=fov_deg, world_from_cam=pose)


# ----------------------------------------------------------------------------- compositing
def composite_equirect(pano, canvases, *, origin=(0.0, 0.0, 0.0), rng=None, depth_tol: float = 1e-3,
                       antialias: bool = True, block_rows: int = 64) -> np.ndarray:
    """A copy of the equirect image ``pano`` (H, 2H[, C]) with ``canvases`` drawn in.

    ``rng`` (H, 2H) is the scene's range along each ray (NaN = nothing): canvas points farther
    are hidden. Rays start at ``origin`` through every pixel centre.
    """
    from .convert import check_equirect

    img = np.array(check_equirect("pano", pano), copy=True)
    h, w = img.shape[:2]
    if rng is not None:
        rng = check_equirect("rng", rng, depth=True)
        if rng.shape != (h, w):
            raise ValueError(f"rng: expected shape {(h, w)}, got {rng.shape}")
    o = np.asarray(origin, dtype=np.float64)
    u = np.arange(w, dtype=np.float64)
    step = max(1, int(block_rows))
    for v0 in range(0, h, step):
        v1 = min(h, v0 + step)
        vv, uu = np.meshgrid(np.arange(v0, v1, dtype=np.float64), u, indexing="ij")
        dirs = direction_from_equirect_pixel(uu, vv, w, h)
        block = img[v0:v1]
        composite_rays_into(block, o, dirs, canvases, rng=None if rng is None else rng[v0:v1],
                            depth_tol=depth_tol, antialias=antialias)
    return img


def composite_cubemap(cube, canvases, *, layout: str = "list", origin=(0.0, 0.0, 0.0), depth=None,
                      depth_tol: float = 1e-3, antialias: bool = True):
    """A copy of the cubemap ``cube`` (in ``layout``) with ``canvases`` drawn into every face, one
    homography per canvas and face. ``depth``: planar z faces (same layout) for occlusion."""
    faces = [np.array(f, copy=True) for f in unpack_faces(cube, layout)]
    zfaces = None if depth is None else [np.asarray(z, dtype=np.float32) for z in unpack_faces(depth, layout)]
    s = faces[0].shape[0]
    for f in range(6):
        composite_into(faces[f], face_camera(f, s, origin=origin), canvases,
                       depth=None if zfaces is None else zfaces[f], depth_tol=depth_tol, antialias=antialias)
    return layout_faces(np.stack(faces), canonical_layout(layout))


def composite_panorama(pano, canvases, *, layout: str, **kwargs):
    """:func:`composite_equirect` for ``layout='equirect'``, else :func:`composite_cubemap`."""
    if layout == "equirect":
        return composite_equirect(pano, canvases, **kwargs)
    check_choice("layout", canonical_layout(layout), LAYOUTS)
    if "rng" in kwargs:
        raise ValueError("rng: range maps are for equirect panoramas; give planar z faces as depth=")
    return composite_cubemap(pano, canvases, layout=layout, **kwargs)


def composite_perspective(pano, canvases, *, yaw_deg: float, pitch_deg: float, roll_deg: float = 0.0,
                          fov_deg: float, width: int, height: int, layout: str | None = None,
                          origin=(0.0, 0.0, 0.0), antialias: bool = True) -> np.ndarray:
    """:func:`panorama.perspective` of ``pano`` with ``canvases`` composited by their homography
    into the same view (the library's reference for what the viewer page shows)."""
    from .convert import perspective

    view = perspective(pano, yaw_deg=yaw_deg, pitch_deg=pitch_deg, roll_deg=roll_deg, fov_deg=fov_deg,
                       width=width, height=height, layout=layout)
    view = np.array(view, copy=True)
    cam = view_camera(yaw_deg, pitch_deg, roll_deg, fov_deg, width, height, origin=origin)
    composite_into(view, cam, canvases, antialias=antialias)
    return view


# ----------------------------------------------------------------------------- picking
def _pick(canvases, origin, d, scene):
    items = [canvases] if isinstance(canvases, Canvas) else list(canvases)
    index, xy, dist = pick_rays(items, origin, d[None], scene_distance=scene)
    if index[0] < 0:
        return None
    unit = d / np.linalg.norm(d)
    return Pick(int(index[0]), items[index[0]], xy[0], np.asarray(origin, float) + dist[0] * unit, float(dist[0]))


def pick_equirect(u: float, v: float, width: int, height: int, canvases, *, origin=(0.0, 0.0, 0.0),
                  rng=None) -> Pick | None:
    """The canvas under equirect pixel (u, v) (centres at integers) of a ``width x height``
    panorama seen from ``origin``, or ``None``. ``rng`` (H, W): scene range for occlusion
    (nearest pixel)."""
    u = check_finite_scalar("u", u)
    v = check_finite_scalar("v", v)
    d = direction_from_equirect_pixel(u, v, width, height)
    scene = None
    if rng is not None:
        r = np.asarray(rng)
        iu = int(math.floor(u + 0.5)) % width
        iv = min(max(int(math.floor(v + 0.5)), 0), height - 1)
        scene = np.array([float(r[iv, iu])])
    return _pick(canvases, np.asarray(origin, float), d, scene)


def pick_view(u: float, v: float, canvases, *, yaw_deg: float, pitch_deg: float, roll_deg: float = 0.0,
              fov_deg: float, width: int, height: int, origin=(0.0, 0.0, 0.0)) -> Pick | None:
    """The canvas under pixel (u, v) of the perspective view :func:`view_camera` of the panorama
    (what the viewer page shows), or ``None``."""
    from ibr.canvas import pick_pixel

    cam = view_camera(yaw_deg, pitch_deg, roll_deg, fov_deg, width, height, origin=origin)
    return pick_pixel(cam, u, v, canvases)


def equirect_pixel_of(point, width: int, height: int, *, origin=(0.0, 0.0, 0.0)) -> tuple[float, float]:
    """Equirect pixel (u, v) where a world point appears (for round trips and tests)."""
    d = np.asarray(point, dtype=np.float64) - np.asarray(origin, dtype=np.float64)
    u, v = equirect_pixel_from_direction(d, width, height)
    return float(u), float(v)


# ----------------------------------------------------------------------------- the store
def store_path(pano_path) -> Path:
    """The canvas store of a panorama: ``room.png`` -> ``room.canvas.json``; a face folder
    ``faces/`` -> ``faces.canvas.json`` beside it."""
    p = Path(pano_path)
    stem = p.name if p.is_dir() else p.stem
    return p.with_name(f"{stem}.canvas.json")


def store_image_dir(store) -> Path:
    """Folder for images placed from the page: ``room.canvas.json`` -> ``room.canvas-images/``."""
    s = Path(store)
    name = s.name[: -len(".canvas.json")] if s.name.endswith(".canvas.json") else s.stem
    return s.with_name(f"{name}.canvas-images")


def empty_store() -> dict:
    return {"version": STORE_VERSION, "canvases": []}


_GEOMETRY_KEYS = ("center", "normal", "up", "size")
_KINDS = {
    "image": ("kind", "image") + _GEOMETRY_KEYS + ("resolution",),
    "strokes": ("kind",) + _GEOMETRY_KEYS + ("resolution", "strokes", "background"),
}
_STROKE_KEYS = ("points", "width", "color")


def _vector(where: str, value, n: int) -> list[float]:
    if not isinstance(value, list) or len(value) != n:
        raise ValueError(f"{where}: expected a list of {n} numbers, got {value!r}"[:300])
    return [float(check_number(f"{where}[{i}]", x)) for i, x in enumerate(value)]


def _check_entry(i: int, e) -> dict:
    where = f"canvases[{i}]"
    if not isinstance(e, dict):
        raise TypeError(f"{where}: expected a JSON object, got {type(e).__name__}")
    kind = e.get("kind")
    if kind not in _KINDS:
        raise ValueError(f"{where}: kind: expected 'image' or 'strokes', got {kind!r}")
    check_keys(where, e, _KINDS[kind], required=("kind",) + _GEOMETRY_KEYS + (("image",) if kind == "image" else ()))
    out = {"kind": kind}
    for k in ("center", "normal", "up"):
        out[k] = _vector(f"{where}: {k}", e[k], 3)
    out["size"] = _vector(f"{where}: size", e["size"], 2)
    if "resolution" in e:
        r = e["resolution"]
        if not isinstance(r, list) or len(r) != 2:
            raise ValueError(f"{where}: resolution: expected [W, H], got {r!r}")
        out["resolution"] = [check_number(f"{where}: resolution[{j}]", x, integer=True, minimum=1, maximum=8192)
                             for j, x in enumerate(r)]
    # the geometry must make a valid canvas (zero normal, zero size, up parallel to normal)
    try:
        Canvas(out["center"], out["normal"], out["size"], up=out["up"], resolution=(1, 1))
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None
    if kind == "image":
        out["image"] = check_relative_path(f"{where}: image", e["image"])
    else:
        strokes = e.get("strokes", [])
        if not isinstance(strokes, list):
            raise ValueError(f"{where}: strokes: expected a list, got {type(strokes).__name__}")
        out["strokes"] = []
        for j, s in enumerate(strokes):
            sw = f"{where}: strokes[{j}]"
            check_keys(sw, s, _STROKE_KEYS, required=("points",))
            pts = s["points"]
            if not isinstance(pts, list) or not pts or len(pts) > 100000:
                raise ValueError(f"{sw}: points: expected a non-empty list of [x, y] pairs")
            pts = [_vector(f"{sw}: points[{k}]", p, 2) for k, p in enumerate(pts)]
            width = float(check_number(f"{sw}: width", s.get("width", 4.0), minimum=0, exclusive_minimum=True,
                                       maximum=4096))
            color = s.get("color", "#ff3030")
            try:
                parse_color(color)
            except (TypeError, ValueError) as exc:
                raise ValueError(f"{sw}: {exc}") from None
            out["strokes"].append({"points": pts, "width": width, "color": color})
        if "background" in e:
            try:
                parse_color(e["background"])
            except (TypeError, ValueError) as exc:
                raise ValueError(f"{where}: background: {exc}") from None
            out["background"] = e["background"]
    return out


def check_store(doc) -> dict:
    """Validate a store document strictly (unknown keys refused, numbers checked, geometry
    non-degenerate, image paths relative); return a normalized copy."""
    check_keys("canvas store", doc, ("version", "canvases"), required=("version", "canvases"))
    if doc["version"] != STORE_VERSION:
        raise ValueError(f"canvas store: version: expected {STORE_VERSION}, got {doc['version']!r}")
    items = doc["canvases"]
    if not isinstance(items, list):
        raise ValueError(f"canvas store: canvases: expected a list, got {type(items).__name__}")
    if len(items) > _MAX_CANVASES:
        raise ValueError(f"canvas store: canvases: at most {_MAX_CANVASES}, got {len(items)}")
    return {"version": STORE_VERSION, "canvases": [_check_entry(i, e) for i, e in enumerate(items)]}


def load_store(path) -> dict:
    """The store at ``path`` (validated), or an empty store when the file does not exist yet."""
    p = Path(path)
    if not p.exists():
        return empty_store()
    if p.stat().st_size > _MAX_STORE_BYTES:
        raise ValueError(f"canvas store: {p} is larger than {_MAX_STORE_BYTES >> 20} MiB")
    try:
        doc = json.loads(p.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"canvas store: {p} is not valid JSON ({exc})") from None
    try:
        return check_store(doc)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{p}: {exc}") from None


def save_store(path, doc) -> dict:
    """Validate ``doc`` and write it atomically to ``path``; return the normalized document."""
    from ibr.io import atomic_path

    clean = check_store(doc)
    text = json.dumps(clean, indent=1)
    if len(text) > _MAX_STORE_BYTES:
        raise ValueError(f"canvas store: the document is larger than {_MAX_STORE_BYTES >> 20} MiB")
    with atomic_path(Path(path)) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return clean


def canvases_from_store(doc, base_dir) -> list[Canvas]:
    """Build the canvases of a (validated) store: images read relative to ``base_dir`` (the JSON's
    folder), strokes drawn onto a transparent (or ``background``) buffer."""
    from ibr.io import read_image

    out = []
    for i, e in enumerate(check_store(doc)["canvases"]):
        geo = dict(center=e["center"], normal=e["normal"], size=e["size"], up=e["up"])
        if e["kind"] == "image":
            img = read_image(Path(base_dir) / e["image"], what=f"canvases[{i}]: image")
            c = canvas_from_image(img, resolution=e.get("resolution"), name=f"image {i}", **geo)
        else:
            res = e.get("resolution")
            c = Canvas(geo["center"], geo["normal"], geo["size"], up=geo["up"], resolution=res, name=f"strokes {i}")
            if "background" in e:
                c.clear(parse_color(e["background"]))
            for s in e["strokes"]:
                draw_stroke(c, np.array(s["points"]), width=s["width"], color=s["color"])
        out.append(c)
    return out


# ----------------------------------------------------------------------------- the viewer site
WEB_DIR = Path(__file__).with_name("web")
_UPLOAD_NAME = re.compile(r"^[A-Za-z0-9_-]{1,64}\.(png|jpg|jpeg)$")


def write_canvas_site(folder) -> Path:
    """Copy ``canvas.js`` (the click-to-place UI) into a viewer site written by
    :func:`panorama.viewer.write_site` and let its page load it; return the script's path."""
    from .viewer import copy_page

    dst = Path(folder) / "canvas.js"
    shutil.copyfile(WEB_DIR / "canvas.js", dst)
    copy_page(folder, canvas=True)
    return dst


class _CanvasHandler(_SiteHandler):
    """The viewer site's files (:data:`panorama.viewer.SITE_FILES` and ``canvas.js``, nothing
    else of the folder), plus the canvas store:

    * ``GET /canvas-store.json`` -- the store (``{"version": 1, "canvases": []}`` when empty);
    * ``GET /canvas-files/<path>`` -- an image the store names (relative to its folder), nothing else;
    * ``POST /canvas-store.json`` -- replace the store (validated, written atomically);
    * ``POST /canvas-images/<name>`` -- add a PNG/JPEG image (decoded to check it, <= 32 MiB).
    """

    store: Path = Path("canvas.json")
    lock = threading.Lock()

    def send_head(self):
        name = self.path.split("?", 1)[0].split("#", 1)[0].lstrip("/")
        if name == "canvas.js":
            return http.server.SimpleHTTPRequestHandler.send_head(self)
        return super().send_head()

    def _reply(self, code: int, body: bytes, ctype: str = "application/json") -> None:
        self.send_response(code)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.wfile.write(body)

    def _error(self, code: int, message: str) -> None:
        self._reply(code, json.dumps({"error": message}).encode())

    def do_GET(self):  # noqa: N802 - http.server's naming
        path = self.path.split("?", 1)[0]
        if path == "/canvas-store.json":
            try:
                doc = load_store(self.store)
            except (OSError, ValueError) as exc:
                return self._error(500, str(exc))
            return self._reply(200, json.dumps(doc).encode())
        if path.startswith("/canvas-files/"):
            from urllib.parse import unquote

            rel = unquote(path[len("/canvas-files/"):])
            try:
                named = {e["image"] for e in load_store(self.store)["canvases"] if e["kind"] == "image"}
            except (OSError, ValueError) as exc:
                return self._error(500, str(exc))
            f = self.store.parent / rel
            if rel not in named or not f.is_file():  # only the images the store names are served
                return self._error(404, f"no canvas image {rel!r} in the store")
            ctype = "image/png" if rel.lower().endswith(".png") else "image/jpeg"
            return self._reply(200, f.read_bytes(), ctype)
        return super().do_GET()

    def _body(self) -> bytes | None:
        try:
            n = int(self.headers.get("Content-Length", ""))
        except ValueError:
            self._error(411, "Content-Length required")
            return None
        limit = _MAX_UPLOAD_BYTES if self.path.startswith("/canvas-images/") else _MAX_STORE_BYTES
        if n < 0 or n > limit:
            self._error(413, f"body of {n} bytes exceeds {limit} bytes")
            return None
        return self.rfile.read(n)

    def do_POST(self):  # noqa: N802
        path = self.path.split("?", 1)[0]
        if path == "/canvas-store.json":
            body = self._body()
            if body is None:
                return None
            try:
                doc = json.loads(body.decode("utf-8"))
                with self.lock:
                    clean = _save_checked(self.store, doc)
            except (UnicodeDecodeError, json.JSONDecodeError) as exc:
                return self._error(400, f"not JSON: {exc}")
            except (OSError, TypeError, ValueError) as exc:
                return self._error(400, str(exc))
            return self._reply(200, json.dumps(clean).encode())
        if path.startswith("/canvas-images/"):
            name = path[len("/canvas-images/"):]
            if not _UPLOAD_NAME.match(name):
                return self._error(400, f"image name {name!r}: expected letters, digits, '-' or '_' and .png/.jpg")
            body = self._body()
            if body is None:
                return None
            import cv2

            img = cv2.imdecode(np.frombuffer(body, np.uint8), cv2.IMREAD_UNCHANGED) if body else None
            if img is None or img.shape[0] * img.shape[1] > MAX_TEXELS:
                return self._error(400, f"image {name!r}: not a decodable PNG/JPEG within {MAX_TEXELS} pixels")
            folder = store_image_dir(self.store)
            with self.lock:
                folder.mkdir(exist_ok=True)
                tmp = folder / f".{name}.{os.getpid()}.tmp"
                tmp.write_bytes(body)
                os.replace(tmp, folder / name)
            rel = f"{folder.name}/{name}"
            return self._reply(200, json.dumps({"image": rel, "width": img.shape[1], "height": img.shape[0]}).encode())
        return self._error(404, f"cannot POST to {path}")


def _save_checked(store: Path, doc) -> dict:
    clean = check_store(doc)
    for i, e in enumerate(clean["canvases"]):  # an image entry must name an existing file
        if e["kind"] == "image" and not (store.parent / e["image"]).is_file():
            raise ValueError(f"canvases[{i}]: image: {e['image']!r} does not exist next to {store.name}")
    return save_store(store, clean)


def serve_canvas_site(folder, store, *, port: int = 0) -> http.server.ThreadingHTTPServer:
    """Serve a viewer site (``index.html`` + faces + ``canvas.js``) on 127.0.0.1 with the canvas
    store ``store`` (a ``*.canvas.json`` path; created on the first save). Returns the running
    server (``shutdown()`` stops it)."""
    folder = Path(folder)
    if not (folder / "index.html").is_file():
        raise FileNotFoundError(f"folder: {folder} has no index.html (write it with write_site)")
    port = check_number("port", port, integer=True, minimum=0, maximum=65535)
    load_store(store)  # a broken store is reported before serving
    handler_cls = type("CanvasHandler", (_CanvasHandler,), {"store": Path(store).resolve(),
                                                            "lock": threading.Lock()})
    handler = functools.partial(handler_cls, directory=str(folder))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", port), handler)
    threading.Thread(target=server.serve_forever, daemon=True, name="panorama-canvas-viewer").start()
    return server
