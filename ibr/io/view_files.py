"""The view file: one JSON sidecar that makes one path describe one RGB-D view.

::

    {"format": "ibr-view", "version": 1, "name": "room_a",
     "color": "room_a_color.png",
     "depth": {"path": "room_a_depth.exr", "encoding": "z"},
     "camera": {"width": 256, "height": 192, "fx": 200.0, "fy": 200.0,
                "cx": 127.5, "cy": 95.5, "world_from_cam": [[1, 0, 0, 0], ...]}}

Paths are relative to the JSON file. ``depth`` may be ``null`` (color and camera only).
Pixel convention of ``camera``: pixel (u, v) = (column, row) has its center at integer
coordinates, so a centered principal point of a 256-wide image is ``cx = 127.5``.
:func:`load_view` converts every supported depth encoding (:data:`DEPTH_ENCODINGS`) to planar z
(float32, NaN invalid) with :mod:`ibr.base.depth`. The full schema is in ``docs/files.md``.
"""

from __future__ import annotations

import contextlib
import json
import math
import re
from pathlib import Path
from typing import Any

import numpy as np

from ..base import depth as _depth
from ..base.camera import Camera
from ..base.validate import check_keys, check_relative_path, nearest_name
from ..base.view import View
from .images import (_depth_array, _depth_values, _require_file, atomic_path, check_write_dtype, read_image,
                     write_depth, write_image)

__all__ = ["DEPTH_ENCODINGS", "VIEW_FORMAT", "VIEW_KEYS", "VIEW_VERSION", "json_format", "load_camera", "load_view",
           "save_view", "view_to_dict"]

VIEW_FORMAT = "ibr-view"
VIEW_VERSION = 1

#: Depth encodings of a view file: required and optional parameters of each.
#: ``scale`` (optional everywhere except the fixed-point codes) multiplies the stored values;
#: it is required for integer files such as 16-bit PNG. ``step`` (z, range, disparity): stored units
#: per quantization code (integer files default to 1; see ``ibr.base.depth.DepthQuantization``).
#: See :mod:`ibr.base.depth` for the formulas.
DEPTH_ENCODINGS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "z": ((), ("scale", "step")),
    "range": ((), ("scale", "step")),
    "disparity": (("baseline", "focal_px", "doffs"), ("scale", "step")),
    "window": (("near", "far"), ("far_is_empty",)),
    "reversed": (("near", "far"), ("far_is_empty",)),
    "zprime": (("near", "far"), ("far_is_empty",)),
    "fixed16": (("near", "far"), ("far_is_empty",)),
    "fixed24": (("near", "far"), ("far_is_empty",)),
}

_FIXED_BITS = {"fixed16": 16, "fixed24": 24}
#: Stored range of the window-like encodings: [0, top]; anything else is not such a buffer.
_WINDOW_RANGES = {"window": 1.0, "reversed": 1.0, "zprime": _depth.ZPRIME_SCALE}
#: Their decoders (stored -> planar z) and encoders (planar z -> stored), near/far as keywords.
_WINDOW_DECODE = {"window": _depth.z_from_window, "reversed": _depth.z_from_reversed, "zprime": _depth.z_from_zprime}
_WINDOW_ENCODE = {"window": _depth.window_from_z, "reversed": _depth.reversed_from_z, "zprime": _depth.zprime_from_z}

#: Top-level keys of a view file (anything else is refused, with the nearest valid name).
VIEW_KEYS = ("format", "version", "name", "color", "depth", "camera")


# --------------------------------------------------------------------------- view files
def json_format(path) -> str | None:
    """The ``"format"`` of the JSON object in file ``path`` (``"ibr-view"``, ``"ibr-rig"``,
    ``"ibr-sequence"`` ...), or None when it is no readable JSON object with one."""
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    return doc.get("format") if isinstance(doc, dict) else None


def read_json(path, what: str):
    """The JSON document of a file; ``FileNotFoundError`` / ``ValueError`` name ``what`` and the
    path (shared by view, tour and other tools' files)."""
    path = Path(path)
    _require_file(path, what)
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise _not_json(what, path, exc) from None


def _not_json(what: str, path: Path, exc) -> ValueError:
    """The error for a file that does not parse as JSON; an image or a video (by its extension)
    is named as one (`ibr stereo photo.png` said "'utf-8' codec can't decode byte 0x89")."""
    from .outputs import ANIMATION_EXTS, IMAGE_EXTS

    kind = {**dict.fromkeys(IMAGE_EXTS + (".bmp", ".webp"), "an image"), **dict.fromkeys(ANIMATION_EXTS, "a video")}
    got = kind.get(path.suffix.lower())
    if got:
        return ValueError(f"{what} {path}: {got}, not a JSON file (a view file is .json: it names the colour and "
                          "depth images and the camera)")
    return ValueError(f"{what} {path}: not valid JSON ({exc})")


def _param(params: dict, key: str, where: str, *, allow_inf: bool = False) -> float:
    value = params[key]
    if allow_inf and (value == math.inf or (isinstance(value, str) and value.lower() in ("inf", "infinity"))):
        return math.inf  # JSON has no inf: accept "inf" (what save_view writes) or Python's Infinity
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{where}: parameter {key!r} must be a finite number, got {value!r}")
    return float(value)


def _check_depth_params(encoding, params: dict, where: str, encoding_where: str | None = None) -> dict:
    """``params`` of depth ``encoding`` checked; errors name ``where`` (``encoding_where`` for an
    unknown encoding, when it is another argument: save_view's ``depth_encoding``)."""
    if not isinstance(encoding, str) or encoding not in DEPTH_ENCODINGS:
        near = nearest_name(encoding, DEPTH_ENCODINGS)
        raise ValueError(f"{encoding_where or where}: unknown depth encoding {encoding!r}"
                         f"{f' (did you mean {near!r}?)' if near else ''}; "
                         f"expected one of {', '.join(map(repr, DEPTH_ENCODINGS))}")
    required, optional = DEPTH_ENCODINGS[encoding]
    unknown = sorted(set(params) - set(required) - set(optional), key=str)
    if unknown:  # before "missing": a misspelled key is the likelier mistake (#12)
        near = nearest_name(unknown[0], [k for k in required + optional if k not in params])
        hint = f" (did you mean {near!r}?)" if near else ""
        raise ValueError(f"{where}: unknown parameter(s) {', '.join(map(str, unknown))}{hint} for encoding "
                         f"{encoding!r} (allowed: {', '.join(required + optional) or 'none'})")
    missing = [k for k in required if k not in params]
    if missing:
        raise ValueError(f"{where}: encoding {encoding!r} needs parameter(s) {', '.join(missing)}")
    out: dict[str, Any] = {}
    for k in required + optional:
        if k not in params:
            continue
        if k == "far_is_empty":
            if not isinstance(params[k], bool):
                raise ValueError(f"{where}: parameter 'far_is_empty' must be true or false, got {params[k]!r}")
            out[k] = params[k]
        else:
            out[k] = _param(params, k, where, allow_inf=(k == "far"))
    if "near" in out:
        if not out["near"] > 0 or not out["far"] > out["near"]:
            raise ValueError(f"{where}: need 0 < near < far, got near={out['near']}, far={out['far']}")
        if encoding in _FIXED_BITS and math.isinf(out["far"]):
            raise ValueError(f"{where}: encoding {encoding!r} needs a finite far plane")
    for k in ("baseline", "focal_px", "scale", "step"):
        if k in out and not out[k] > 0:
            raise ValueError(f"{where}: parameter {k!r} must be positive, got {out[k]}")
    return out


def _decode_depth(stored: np.ndarray, encoding: str, p: dict, camera: Camera) -> np.ndarray:
    """Stored depth values -> planar z (float32, NaN invalid)."""
    if encoding == "z":
        return stored
    if encoding == "range":
        return _depth.z_from_range(stored, camera)
    if encoding == "disparity":
        return _depth.z_from_disparity(stored, baseline=p["baseline"], focal_px=p["focal_px"], doffs=p["doffs"])
    nf = {"near": p["near"], "far": p["far"]}
    if encoding in _WINDOW_RANGES:
        z = _WINDOW_DECODE[encoding](stored, **nf)
        if p.get("far_is_empty", False):  # opt-in: a cleared buffer's far value is no depth, not a wall
            z[_at_far(stored, encoding)] = np.nan
        return z
    bits = _FIXED_BITS[encoding]
    return _depth.z_from_fixed(stored, bits=bits, far_is_empty=p.get("far_is_empty", True), **nf)


def _encode_depth(z: np.ndarray, encoding: str, p: dict, camera: Camera) -> np.ndarray:
    """Planar z -> values to store (float32, or integer codes for the fixed encodings)."""
    if encoding == "z":
        return z.astype(np.float32)
    if encoding == "range":
        return _depth.range_from_z(z, camera)
    if encoding == "disparity":
        return _depth.disparity_from_z(z, baseline=p["baseline"], focal_px=p["focal_px"], doffs=p["doffs"])
    nf = {"near": p["near"], "far": p["far"]}
    valid = _depth.valid_mask(z)
    if encoding in _FIXED_BITS or encoding in _WINDOW_RANGES:
        with np.errstate(invalid="ignore"):
            outside = valid & ((z < nf["near"]) | (z > nf["far"]))
        if outside.any():
            raise ValueError(f"depth: {int(outside.sum())} valid pixel(s) lie outside [near, far] = "
                             f"[{nf['near']}, {nf['far']}] and cannot be stored as {encoding!r}")
    if encoding in _WINDOW_RANGES:
        stored = _WINDOW_ENCODE[encoding](z, **nf).astype(np.float32)
        if p.get("far_is_empty", False):
            with np.errstate(invalid="ignore"):  # at the far plane (to float precision) or stored as its value
                at_far = valid & (_at_far(stored, encoding) | (z >= nf["far"] * (1 - 1e-6)))
            if np.any(at_far):
                raise ValueError(f"depth: valid pixels lie at the far plane, whose {encoding} value reads back "
                                 "as empty with far_is_empty=true; move far out or set far_is_empty=false")
        return stored
    bits = _FIXED_BITS[encoding]
    if not p.get("far_is_empty", True) and not valid.all():
        raise ValueError(f"depth: {int((~valid).sum())} pixel(s) have no depth, but with far_is_empty=false every "
                         f"{bits}-bit code is a depth (they would read back at the far plane); "
                         "set far_is_empty=true")
    q = _depth.fixed_from_z(z, bits=bits, **nf)
    if p.get("far_is_empty", True) and np.any(valid & (q == 2**bits - 1)):
        raise ValueError(f"depth: valid pixels quantize to the far code of a {bits}-bit buffer, which "
                         f"reads back as empty; move far out or set far_is_empty=false")
    return q


def _at_far(stored: np.ndarray, encoding: str) -> np.ndarray:
    """Where a window-like buffer holds its far (cleared) value: window 1, reversed 0, zprime 2^24."""
    return stored <= 0 if encoding == "reversed" else stored >= _WINDOW_RANGES[encoding]


def _read_stored_depth(path: Path, encoding: str, p: dict, where: str,
                       channel: str | None = None) -> tuple[np.ndarray, bool]:
    """The depth file's values as stored (fixed codes) or scaled (:func:`read_depth`), and whether
    the file holds integer codes (whatever its extension: a uint16 TIFF as a 16-bit PNG)."""
    raw = _depth_array(path, channel, where, "; name the depth channel with the view file's \"channel\" key")
    if encoding in _FIXED_BITS:
        if raw.dtype.kind == "f":  # codes stored in a float file must be integers
            if not np.all(np.isfinite(raw) & (raw == np.rint(raw)) & (raw >= 0)):
                raise ValueError(f"{where}: {path} must hold non-negative integer codes for {encoding!r}")
            return raw.astype(np.uint32), True
        return raw, True
    # Blender's "no surface" values (1e10, 65504) only in depth passes, not in z' or disparities
    return (_depth_values(raw, path, scale=p.get("scale"), what=where, blender_markers=encoding in ("z", "range")),
            raw.dtype.kind in "ui")


def named_files(path, doc) -> list[tuple[str, Path]]:
    """The image files a view file's document ``doc`` names, as (key, path) pairs: ``'color'``
    and ``'depth.path'``, relative to the view file ``path``. Only peeks: entries that are not
    non-empty strings are skipped (:func:`load_view` reports them)."""
    refs = [("'color'", doc.get("color"))]
    if isinstance(doc.get("depth"), dict):
        refs.append(("'depth.path'", doc["depth"].get("path")))
    return [(key, Path(path).parent / rel) for key, rel in refs if isinstance(rel, str) and rel]


def camera_without_pose(doc) -> bool:
    """Whether the document ``doc`` of a view file, a bare camera JSON or a wrapped one
    (``{"camera": {...}}``) has a camera object without ``world_from_cam``: a valid file whose
    camera :func:`load_view` / :func:`load_camera` place at the world origin looking down +z
    (the identity pose). Only peeks, as :func:`named_files`: anything else is False."""
    if not isinstance(doc, dict):
        return False
    cam = doc.get("camera") if ("format" in doc or isinstance(doc.get("camera"), dict)) else doc
    return isinstance(cam, dict) and "fx" in cam and "world_from_cam" not in cam


#: The note a command prints for a view or camera file without a pose (``{path}``: the file).
NO_POSE_NOTE = "note: {path} has no world_from_cam: camera at the origin looking down +z (the identity pose)"


def _json_number(x: float):
    return "inf" if isinstance(x, float) and math.isinf(x) else x


def _not_a_file(path: Path) -> str:
    """How a view file's reference that is no file is described: a folder or a missing file."""
    return f"a folder, not an image file: {path}" if path.is_dir() else f"a missing file {path}"


def load_view(path) -> View:
    """Load a view file (JSON sidecar + color + optional depth) as a :class:`~ibr.base.view.View`.

    Depth of any encoding in :data:`DEPTH_ENCODINGS` is converted to planar z (float32, NaN
    where invalid). The camera uses the pixel-center convention (pixel (u, v) has its center at
    integer coordinates; a centered cx of a 741-wide image is 370.0).

    Raises
    ------
    FileNotFoundError
        The JSON file, or a file it references (the message names the key: ``color`` or
        ``depth.path``), does not exist.
    ValueError
        Invalid JSON or schema, unknown encoding, missing or bad parameters, corrupt images,
        color/depth size mismatch, camera size different from the image size, impossible
        camera values (fx <= 0, a pose whose rotation block is not a rotation, ...).
    """
    path = Path(path)
    doc = read_json(path, "view file")
    where = f"view file {path}"
    if not isinstance(doc, dict):
        raise ValueError(f"{where}: expected a JSON object, got {type(doc).__name__}")
    if doc.get("format") != VIEW_FORMAT:
        raise ValueError(f"{where}: 'format' must be {VIEW_FORMAT!r}, got {doc.get('format')!r}")
    check_keys(where, doc, VIEW_KEYS)  # unknown keys ("dpeth", "pose") are refused, never ignored (#12)
    _check_version(where, doc)
    for key in ("color", "camera"):
        if key not in doc:
            raise ValueError(f"{where}: missing key {key!r}")
    if not isinstance(doc["color"], str) or not doc["color"]:
        raise ValueError(f"{where}: 'color' must be a relative file name, got {doc['color']!r}")
    check_relative_path(f"{where}: 'color'", doc["color"])
    name = doc.get("name", path.stem)
    if not isinstance(name, str):
        raise ValueError(f"{where}: 'name' must be a string, got {name!r}")

    try:
        camera = Camera.from_dict(doc["camera"])
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: bad 'camera': {exc}") from None

    color_path = path.parent / doc["color"]
    if not color_path.is_file():
        raise FileNotFoundError(f"{where}: 'color' refers to {_not_a_file(color_path)}")
    color = read_image(color_path, what=f"{where}: 'color'")
    if color.ndim == 3 and color.shape[2] not in (3, 4):
        raise ValueError(f"{where}: 'color' {color_path} has {color.shape[2]} channels; expected 1, 3 or 4")
    if color.shape[:2] != camera.shape:
        raise ValueError(f"{where}: camera size {camera.width}x{camera.height} does not match the color "
                         f"image {color_path.name} ({color.shape[1]}x{color.shape[0]})")

    z = None
    spec = doc.get("depth")
    if spec is not None:
        dwhere = f"{where}: 'depth'"
        if isinstance(spec, dict):  # a misspelt 'path' / 'encoding' / 'channel' named, with the nearest
            enc = spec.get("encoding", "z")
            params = (DEPTH_ENCODINGS[enc][0] + DEPTH_ENCODINGS[enc][1]
                      if isinstance(enc, str) and enc in DEPTH_ENCODINGS else ())
            known = ("path", "encoding", "channel") + tuple(params)
            unknown = [k for k in spec if k not in known]
            if unknown:
                near = nearest_name(str(unknown[0]), [k for k in known if k not in spec])
                if near in ("path", "encoding", "channel"):  # an encoding parameter is named below
                    raise ValueError(f"{dwhere}: unknown key {unknown[0]!r} (did you mean {near!r}?)")
        if not isinstance(spec, dict) or not isinstance(spec.get("path"), str) or not spec["path"]:
            raise ValueError(f"{dwhere} must be null or an object with a 'path' string, got {spec!r}")
        check_relative_path(f"{dwhere}: 'path'", spec["path"])
        encoding = spec.get("encoding", "z")
        channel = spec.get("channel")
        if channel is not None and (not isinstance(channel, str) or not channel):
            raise ValueError(f"{dwhere}: 'channel' must be a channel name such as \"ViewLayer.Depth.Z\", got {channel!r}")
        params = {k: v for k, v in spec.items() if k not in ("path", "encoding", "channel")}
        p = _check_depth_params(encoding, params, dwhere)
        depth_path = path.parent / spec["path"]
        if not depth_path.is_file():
            raise FileNotFoundError(f"{where}: 'depth.path' refers to {_not_a_file(depth_path)}")
        stored, integer = _read_stored_depth(depth_path, encoding, p, f"{where}: 'depth.path'", channel)
        top = _WINDOW_RANGES.get(encoding, 2.0 ** _FIXED_BITS.get(encoding, 0) - 1)
        if top > 0:  # a value outside would silently become a hole (a planar-z file, e.g.)
            with np.errstate(invalid="ignore"):
                out = np.isfinite(stored) & ((stored < 0) | (stored > top))
            if out.any():
                raise ValueError(f"{where}: 'depth.path' {depth_path.name}: {int(out.sum())} value(s) outside "
                                 f"[0, {top:g}] for encoding {encoding!r} (range {float(np.nanmin(stored)):.6g}.."
                                 f"{float(np.nanmax(stored[np.isfinite(stored)])):.6g}); is the encoding right?")
        if stored.shape != color.shape[:2]:
            raise ValueError(f"{where}: depth {depth_path.name} is {stored.shape[1]}x{stored.shape[0]} but color "
                             f"{color_path.name} is {color.shape[1]}x{color.shape[0]}")
        z = _depth.sanitize_depth(_decode_depth(stored, encoding, p, camera))[0]
    try:
        view = View(color, z, camera, name)
    except (TypeError, ValueError) as exc:  # e.g. depths outside DEPTH_RANGE: name the file (#12)
        raise type(exc)(f"{where}: {exc}") from None
    if z is not None:  # the encoding's quantization step ('step' stored units per code), for build_mesh (#11)
        _depth.set_quantization(view, _depth.DepthQuantization.from_encoding(
            encoding, p, integer=integer))
    return view


def _check_version(where: str, doc: dict) -> None:
    version = doc.get("version")
    if isinstance(version, bool) or version != VIEW_VERSION:
        raise ValueError(f"{where}: unsupported 'version' {version!r} (this reader knows {VIEW_VERSION})")


def load_camera(path, *, what: str = "camera file") -> Camera:
    """A :class:`~ibr.base.camera.Camera` from a view file (its camera; colour and depth are not
    read) or from a bare camera JSON object, optionally wrapped as ``{"camera": {...}}``.

    The camera object is checked strictly (:func:`ibr.base.validate.check_camera_dict`): unknown
    keys such as ``"pose"`` are refused with the nearest valid name, never ignored.

    Raises
    ------
    FileNotFoundError
        No such file. ``ValueError`` for invalid JSON or a bad camera (the message starts with ``what``).
    """
    path = Path(path)
    _require_file(path, what)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise _not_json(what, path, exc) from None
    where = f"{what} {path}"
    if isinstance(doc, dict) and "format" in doc:
        if doc["format"] != VIEW_FORMAT:
            raise ValueError(f"{where}: 'format' must be {VIEW_FORMAT!r}, got {doc['format']!r}")
        check_keys(where, doc, VIEW_KEYS)
        _check_version(where, doc)  # as load_view: a newer file's camera may mean something else
        if "camera" not in doc:
            raise ValueError(f"{where}: missing key 'camera'")
        doc = doc["camera"]
    elif isinstance(doc, dict) and isinstance(doc.get("camera"), dict):
        check_keys(where, doc, ("camera", "name"))
        doc = doc["camera"]
    try:
        return Camera.from_dict(doc)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: {exc}") from None


def view_to_dict(view: View, *, color_name: str, depth_name: str | None,
                 depth_encoding: str = "z", depth_params: dict | None = None) -> dict:
    """The JSON document of a view file (no I/O); see :func:`save_view`."""
    doc: dict[str, Any] = {"format": VIEW_FORMAT, "version": VIEW_VERSION, "name": view.name, "color": color_name}
    if view.depth is None or depth_name is None:
        doc["depth"] = None
    else:
        doc["depth"] = {"path": depth_name, "encoding": depth_encoding,
                        **{k: _json_number(v) for k, v in (depth_params or {}).items()}}
    doc["camera"] = view.camera.to_dict()
    return doc


def _default_color_ext(dtype: np.dtype) -> str:
    return ".png" if dtype in (np.uint8, np.uint16) else ".exr"


def _default_depth_ext(encoding: str) -> str:
    return ".png" if encoding == "fixed16" else ".exr"


#: A JSON string literal (skipped as a whole) or a list of numbers (put on one line).
_STRING_OR_NUMBER_LIST = re.compile(r'"(?:[^"\\]|\\.)*"|\[[-+0-9.eE,\s]*\]')


def _dumps(doc: dict) -> str:
    """Indented JSON with every list of numbers on one line (readable 4x4 poses); brackets inside
    strings (names, file names) are left as they are."""
    def one_line(m):
        t = m.group(0)
        return t if t.startswith('"') else re.sub(r"\s+", " ", t).replace("[ ", "[").replace(" ]", "]")

    return _STRING_OR_NUMBER_LIST.sub(one_line, json.dumps(doc, indent=2, allow_nan=False)) + "\n"


def save_view(view: View, path, *, color_name: str | None = None, depth_name: str | None = None,
              depth_encoding: str = "z", depth_params: dict | None = None) -> Path:
    """Write a view file: color image, depth image (if the view has depth) and the JSON sidecar.

    Parameters
    ----------
    view : View
    path : str or Path
        The ``.json`` file to write. Color and depth go next to it.
    color_name, depth_name : str, optional
        File names relative to the JSON's folder (no absolute path, no ``..``). Defaults: ``<stem>_color.png`` (uint8/uint16
        color) or ``<stem>_color.exr`` (float32), and ``<stem>_depth.exr`` (``.png`` for
        ``fixed16``).
    depth_encoding : str
        One of :data:`DEPTH_ENCODINGS`; default ``"z"`` (planar z as float EXR, lossless).
    depth_params : dict, optional
        Parameters of the encoding (e.g. ``{"near": 0.1, "far": 100}`` for ``"fixed24"``;
        ``{"scale": 0.001}`` for a 16-bit PNG of z in millimetre codes).

    Returns
    -------
    Path of the JSON file.

    All three files are written to temporary names first and renamed into place only after all
    of them succeeded, so a failure leaves every existing file untouched.
    """
    if not isinstance(view, View):
        raise TypeError(f"view: expected an ibr View, got {type(view).__name__}")
    path = Path(path)
    if path.suffix.lower() != ".json":
        raise ValueError(f"path: a view file must end in .json, got {path}")
    folder = path.parent
    if not folder.is_dir():
        raise FileNotFoundError(f"path: output folder {folder} does not exist")
    params = _check_depth_params(depth_encoding, dict(depth_params or {}), "depth_params", "depth_encoding")
    stem = path.stem
    color_name = color_name or f"{stem}_color{_default_color_ext(view.color.dtype)}"
    check_relative_path("color_name", color_name)  # never write outside the JSON's folder (#12)
    names = [path.name, color_name]
    if view.depth is not None:
        depth_name = depth_name or f"{stem}_depth{_default_depth_ext(depth_encoding)}"
        check_relative_path("depth_name", depth_name)
        names.append(depth_name)
    resolved = [(folder / n).resolve() for n in names]
    if len(set(resolved)) != len(resolved):
        raise ValueError(f"color_name/depth_name: the JSON, color and depth files must be distinct, got {names}")

    color = view.color
    if color.dtype == np.float64:
        color = color.astype(np.float32)
    check_write_dtype("color", folder / color_name, color.dtype)
    stored = None
    if view.depth is not None:
        stored = _encode_depth(view.depth, depth_encoding, params, view.camera)
        if depth_encoding in _FIXED_BITS:
            if depth_encoding == "fixed24" and Path(depth_name).suffix.lower() == ".png":
                raise ValueError("depth_name: 24-bit codes do not fit a PNG; use .exr or .tif")
            check_write_dtype("depth", folder / depth_name, stored.dtype)
        elif Path(depth_name).suffix.lower() == ".png":
            if "scale" not in params:
                raise ValueError(f"depth_params: a 16-bit PNG depth ({depth_name}) needs a 'scale'")
            bad = np.isfinite(stored) & (stored <= 0)
            if bad.any():  # PNG code 0 means "no depth": these pixels would read back as holes
                why = f" for doffs={params.get('doffs')!r}" if depth_encoding == "disparity" else ""
                raise ValueError(f"depth: {int(bad.sum())} pixel(s) store non-positive {depth_encoding} values "
                                 f"(down to {float(stored[bad].min()):.6g}{why}), which a 16-bit PNG "
                                 f"({depth_name}) cannot hold; use .exr or .pfm")

    doc = view_to_dict(view, color_name=Path(color_name).as_posix(),
                       depth_name=None if stored is None else Path(depth_name).as_posix(),
                       depth_encoding=depth_encoding, depth_params=params)
    text = _dumps(doc)
    with contextlib.ExitStack() as stack:
        # Everything is written to temporary names; renames happen when the stack unwinds
        # without an exception (JSON first, then depth, then color).
        tmp_color = stack.enter_context(atomic_path(folder / color_name))
        write_image(tmp_color, color)
        if stored is not None:
            tmp_depth = stack.enter_context(atomic_path(folder / depth_name))
            if depth_encoding in _FIXED_BITS:
                write_image(tmp_depth, stored)
            else:
                write_depth(tmp_depth, stored, scale=params.get("scale"))
        tmp_json = stack.enter_context(atomic_path(path))
        tmp_json.write_text(text, encoding="utf-8")
    return path
