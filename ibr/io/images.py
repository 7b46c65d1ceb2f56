"""Image, depth and view files: read/write through OpenImageIO, atomic writes, the view file.

Formats
-------
color   ``.png`` (uint8, uint16), ``.jpg``/``.jpeg`` (uint8), ``.tif``/``.tiff`` (uint8, uint16,
        uint32, float32), ``.exr`` (float32, float16 read as float32, uint32), ``.pfm`` (float32).
        Arrays come back with the stored dtype, shape (H, W, C) or (H, W) for one channel.
depth   float ``.exr``/``.tif``/``.pfm`` hold values directly (NaN or inf = invalid); a 16-bit
        ``.png`` holds integer codes with ``value = code * scale`` (``scale`` in scene units per
        code, e.g. 0.001 for millimetres when the scene unit is the metre) and code 0 = invalid.
PFM     Portable float map as used by Middlebury: header ``Pf`` (1 channel) or ``PF`` (3),
        ``W H``, then a scale whose *sign* gives the byte order (negative = little-endian);
        rows are stored **bottom-to-top**. Read and written here with numpy, because
        OpenImageIO 3.2 writes PFM bottom-to-top but reads it back without flipping.

View file
---------
A small JSON sidecar that makes one path describe one RGB-D view (README section "io")::

    {"format": "ibr-view", "version": 1, "name": "room_a",
     "color": "room_a_color.png",
     "depth": {"path": "room_a_depth.exr", "encoding": "z"},
     "camera": {"width": 256, "height": 192, "fx": 200.0, "fy": 200.0,
                "cx": 127.5, "cy": 95.5, "world_from_cam": [[1, 0, 0, 0], ...]}}

Paths are relative to the JSON file. ``depth`` may be ``null`` (color and camera only).
Pixel convention of ``camera``: pixel (u, v) = (column, row) has its center at integer
coordinates, so a centered principal point of a 256-wide image is ``cx = 127.5``.
:func:`load_view` converts every supported depth encoding (:data:`DEPTH_ENCODINGS`) to planar z
(float32, NaN invalid) with :mod:`ibr.depth`.

Writing is atomic: every output goes to a temporary name in the destination folder and is
renamed onto its final name only when it has been written completely (:func:`atomic_path`).
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import tempfile
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from . import depth as _depth
from ._validate import check_choice, check_image
from .camera import Camera
from .view import View

__all__ = [
    "DEPTH_ENCODINGS",
    "VIEW_FORMAT",
    "VIEW_VERSION",
    "atomic_path",
    "load_view",
    "read_depth",
    "read_image",
    "read_pfm",
    "save_view",
    "view_to_dict",
    "write_depth",
    "write_image",
    "write_pfm",
]

VIEW_FORMAT = "ibr-view"
VIEW_VERSION = 1

#: Depth encodings of a view file: required and optional parameters of each.
#: ``scale`` (optional everywhere except the fixed-point codes) multiplies the stored values;
#: it is required for integer files such as 16-bit PNG. See :mod:`ibr.depth` for the formulas.
DEPTH_ENCODINGS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "z": ((), ("scale",)),
    "range": ((), ("scale",)),
    "disparity": (("baseline", "focal_px", "doffs"), ("scale",)),
    "window": (("near", "far"), ()),
    "reversed": (("near", "far"), ()),
    "zprime": (("near", "far"), ()),
    "fixed16": (("near", "far"), ("far_is_empty",)),
    "fixed24": (("near", "far"), ("far_is_empty",)),
}

_FIXED_BITS = {"fixed16": 16, "fixed24": 24}

# Dtypes each writer accepts, by extension.
_WRITE_DTYPES = {
    ".png": ("uint8", "uint16"),
    ".jpg": ("uint8",),
    ".jpeg": ("uint8",),
    ".tif": ("uint8", "uint16", "uint32", "float32"),
    ".tiff": ("uint8", "uint16", "uint32", "float32"),
    ".exr": ("float32", "float16", "uint32"),
    ".pfm": ("float32",),
}

_UMASK = os.umask(0)
os.umask(_UMASK)


# --------------------------------------------------------------------------- atomic writes
@contextlib.contextmanager
def atomic_path(path) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; rename it onto ``path`` if the block succeeds.

    The temporary name lives in the same folder (so the final ``os.replace`` is atomic) and keeps
    the extension (so format-by-extension writers such as OpenImageIO pick the right format):
    ``out/a.png`` -> ``out/.a-k3j2x.tmp.png``. If the block raises, or leaves no file behind, the
    temporary file is removed and ``path`` is left untouched (an existing file is not modified).

    Raises
    ------
    FileNotFoundError
        If the destination folder does not exist.
    IsADirectoryError
        If ``path`` is an existing folder.
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    if not folder.is_dir():
        raise FileNotFoundError(f"{path}: output folder {folder} does not exist")
    if path.is_dir():
        raise IsADirectoryError(f"{path}: is a folder, expected a file path")
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=f".tmp{path.suffix}", dir=folder)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        if not tmp.exists():
            raise OSError(f"{path}: nothing was written")
        mode = path.stat().st_mode & 0o777 if path.exists() else 0o666 & ~_UMASK
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp.unlink()
        raise


# --------------------------------------------------------------------------- PFM
_PFM_HEADER = re.compile(rb"\A(P[Ff])\s+(\d+)\s+(\d+)\s+([-+]?[0-9.]+(?:[eE][-+]?\d+)?)\s")


def read_pfm(path) -> tuple[np.ndarray, float]:
    """Read a portable float map; return ``(array, scale)``.

    The array is float32, (H, W) for ``Pf`` or (H, W, 3) for ``PF``, with row 0 at the **top**
    (the file stores rows bottom-to-top; they are flipped here). ``scale`` is the absolute value
    of the header scale; its sign only encodes the byte order (negative = little-endian).
    """
    path = Path(path)
    _require_file(path, "pfm")
    data = path.read_bytes()
    m = _PFM_HEADER.match(data)
    if m is None:
        raise ValueError(f"{path}: not a PFM file (expected a 'Pf' or 'PF' header)")
    kind, w, h, s = m.group(1), int(m.group(2)), int(m.group(3)), float(m.group(4))
    if w < 1 or h < 1 or s == 0 or not math.isfinite(s):
        raise ValueError(f"{path}: bad PFM header (width {w}, height {h}, scale {s})")
    c = 3 if kind == b"PF" else 1
    n = w * h * c * 4
    body = data[m.end():]
    if len(body) < n:
        raise ValueError(f"{path}: truncated PFM file ({len(body)} bytes of pixel data, expected {n})")
    dtype = np.dtype("<f4") if s < 0 else np.dtype(">f4")
    a = np.frombuffer(body[:n], dtype=dtype).reshape((h, w, c) if c == 3 else (h, w))
    return np.ascontiguousarray(a[::-1]).astype(np.float32), abs(s)


def write_pfm(path, array, *, scale: float = 1.0, byteorder: str = "little") -> None:
    """Write a portable float map atomically (rows bottom-to-top, as the format requires).

    ``array`` is (H, W) or (H, W, 1) for ``Pf``, (H, W, 3) for ``PF``; any float or integer
    dtype is stored as float32. NaN is written as +inf, the Middlebury marker for "no value".
    """
    a = check_image("array", array, channels=(1, 3))
    if a.dtype.kind not in "fiu":
        raise ValueError(f"array: expected a numeric dtype, got {a.dtype}")
    check_choice("byteorder", byteorder, ("little", "big"))
    if not (math.isfinite(scale) and scale > 0):
        raise ValueError(f"scale: expected a positive number, got {scale!r}")
    if a.ndim == 3 and a.shape[2] == 1:
        a = a[..., 0]
    a = np.where(np.isnan(a), np.inf, a).astype(np.float32) if a.dtype.kind == "f" else a.astype(np.float32)
    h, w = a.shape[:2]
    header = f"{'PF' if a.ndim == 3 else 'Pf'}\n{w} {h}\n{-scale if byteorder == 'little' else scale:.6g}\n"
    body = np.ascontiguousarray(a[::-1]).astype("<f4" if byteorder == "little" else ">f4").tobytes()
    with atomic_path(path) as tmp:
        tmp.write_bytes(header.encode("ascii") + body)


# --------------------------------------------------------------------------- images
def _require_file(path: Path, what: str) -> None:
    if not path.exists():
        raise FileNotFoundError(f"{what}: file not found: {path}")
    if path.is_dir():
        raise IsADirectoryError(f"{what}: expected a file, got the folder {path}")


def _oiio():
    import OpenImageIO as oiio  # imported lazily: keeps `import ibr` fast

    return oiio


def read_image(path, *, what: str = "image") -> np.ndarray:
    """Read an image with the dtype it is stored in.

    Parameters
    ----------
    path : str or Path
        ``.png``, ``.jpg``, ``.tif``, ``.exr``, ``.pfm`` or any format OpenImageIO reads.
    what : str
        Name used in error messages (e.g. the view-file key that referenced the file).

    Returns
    -------
    ndarray
        (H, W, C) or (H, W) for a single channel; uint8, uint16, uint32 or float32 (half and
        double are returned as float32). Row 0 is the top row, column 0 the left column.

    Raises
    ------
    FileNotFoundError
        Missing file. ``ValueError`` for an unreadable or corrupt file.
    """
    path = Path(path)
    _require_file(path, what)
    if path.suffix.lower() == ".pfm":
        return read_pfm(path)[0]
    oiio = _oiio()
    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)  # return RGBA as stored, not premultiplied
    inp = oiio.ImageInput.open(str(path), config)
    if inp is None:
        raise ValueError(f"{what}: cannot read {path}: {oiio.geterror() or 'unknown format'}")
    try:
        pixels = inp.read_image(0, 0, 0, inp.spec().nchannels, oiio.UNKNOWN)
        err = inp.geterror() if inp.has_error else ""
    finally:
        inp.close()
    if pixels is None or err or not isinstance(pixels, np.ndarray):
        raise ValueError(f"{what}: corrupt or unreadable image {path}: {err or oiio.geterror()}")
    if pixels.dtype in (np.float16, np.float64):
        pixels = pixels.astype(np.float32)
    elif pixels.dtype == np.int8 or pixels.dtype == np.int16 or pixels.dtype == np.int32:
        raise ValueError(f"{what}: {path} stores signed integers ({pixels.dtype}); not supported")
    if pixels.ndim == 3 and pixels.shape[2] == 1:
        pixels = pixels[..., 0]
    return np.ascontiguousarray(pixels)


def _check_write_dtype(path: Path, arr: np.ndarray, name: str) -> str:
    ext = path.suffix.lower()
    if ext not in _WRITE_DTYPES:
        raise ValueError(f"{name}: unsupported extension {ext!r} for {path}; expected one of "
                         f"{', '.join(_WRITE_DTYPES)}")
    if arr.dtype.name not in _WRITE_DTYPES[ext]:
        raise ValueError(f"{name}: a {ext} file stores {' or '.join(_WRITE_DTYPES[ext])}, got {arr.dtype} "
                         f"(convert the array or choose another extension)")
    return ext


def write_image(path, array) -> None:
    """Write an image atomically; the format follows the extension and the dtype is preserved.

    ``.png``: uint8 or uint16; ``.jpg``: uint8 (quality 95, lossy); ``.tif``: uint8, uint16,
    uint32, float32; ``.exr``: float32 (NaN and inf kept), float16, uint32; ``.pfm``: float32.
    Arrays are (H, W) or (H, W, C) with row 0 at the top. Any other combination raises
    ``ValueError`` before anything is written.
    """
    path = Path(path)
    arr = check_image("array", array)
    ext = _check_write_dtype(path, arr, "array")
    if ext == ".pfm":
        write_pfm(path, arr)
        return
    if arr.ndim == 2:
        arr = arr[..., None]
    oiio = _oiio()
    typedesc = {"uint8": oiio.UINT8, "uint16": oiio.UINT16, "uint32": oiio.UINT32,
                "float16": oiio.HALF, "float32": oiio.FLOAT}[arr.dtype.name]
    h, w, c = arr.shape
    with atomic_path(path) as tmp:
        out = oiio.ImageOutput.create(str(tmp))
        if out is None:
            raise ValueError(f"array: cannot create a writer for {path}: {oiio.geterror()}")
        spec = oiio.ImageSpec(w, h, c, typedesc)
        spec.attribute("oiio:UnassociatedAlpha", 1)  # RGBA arrays are straight (not premultiplied)
        if ext in (".jpg", ".jpeg"):
            spec.attribute("Compression", "jpeg:95")
        try:
            if not out.open(str(tmp), spec):
                raise OSError(f"{path}: cannot open for writing: {out.geterror()}")
            if not out.write_image(np.ascontiguousarray(arr)):
                raise OSError(f"{path}: write failed: {out.geterror()}")
        finally:
            out.close()


# --------------------------------------------------------------------------- depth files
def read_depth(path, *, scale: float | None = None, what: str = "depth") -> np.ndarray:
    """Read a single-channel depth (or disparity, or any per-pixel scalar) file as float32.

    Parameters
    ----------
    path : str or Path
        Float ``.exr``/``.tif``/``.pfm`` (values as stored; NaN and +-inf become NaN) or integer
        ``.png``/``.tif`` (``value = code * scale``, code 0 becomes NaN).
    scale : float, optional
        Scene units per stored unit. Required for integer files; multiplies float files (default 1).

    Returns
    -------
    (H, W) float32, row 0 at the top, NaN where invalid.
    """
    a = read_image(path, what=what)
    if a.ndim != 2:
        raise ValueError(f"{what}: expected a single-channel depth image, {path} has {a.shape[2]} channels")
    if scale is not None and not (isinstance(scale, (int, float)) and math.isfinite(scale) and scale > 0):
        raise ValueError(f"{what}: scale must be a positive number, got {scale!r}")
    if a.dtype.kind in "ui":
        if scale is None:
            raise ValueError(f"{what}: {path} stores integer codes ({a.dtype}); give `scale` "
                             f"(scene units per code)")
        out = a.astype(np.float64) * scale
        out[a == 0] = np.nan
        return out.astype(np.float32)
    out = a.astype(np.float32) * np.float32(1.0 if scale is None else scale)
    out[~np.isfinite(out)] = np.nan
    return out


def write_depth(path, z, *, scale: float | None = None) -> None:
    """Write a depth (or other per-pixel scalar) map atomically.

    Parameters
    ----------
    path : str or Path
        ``.exr``/``.tif`` (float32, NaN kept), ``.pfm`` (float32, NaN written as inf) or
        ``.png`` (16-bit codes ``round(z / scale)``, 0 for NaN / non-positive values).
    z : (H, W) array
        Values in scene units, NaN where invalid.
    scale : float, optional
        Scene units per stored unit; required for ``.png``. For float files the stored value is
        ``z / scale`` (default 1), so :func:`read_depth` with the same scale returns ``z``.

    Raises
    ------
    ValueError
        For a 16-bit PNG whose valid values would fall outside codes 1..65535 (they would be lost
        or clipped); for a bad shape, dtype or extension. Nothing is written in that case.
    """
    path = Path(path)
    z = check_image("z", z, channels=(1,))
    z = z.reshape(z.shape[:2]).astype(np.float64)
    ext = path.suffix.lower()
    if scale is not None and not (math.isfinite(scale) and scale > 0):
        raise ValueError(f"scale: expected a positive number, got {scale!r}")
    if ext == ".png":
        if scale is None:
            raise ValueError(f"scale: a 16-bit PNG depth needs `scale` (scene units per code), got None")
        valid = _depth.valid_mask(z)
        codes = np.zeros(z.shape, np.float64)
        codes[valid] = np.rint(z[valid] / scale)
        if valid.any():
            lo, hi = codes[valid].min(), codes[valid].max()
            if lo < 1 or hi > 65535:
                raise ValueError(
                    f"z: values {np.nanmin(z[valid]):.6g}..{np.nanmax(z[valid]):.6g} with scale {scale} give "
                    f"codes {lo:.0f}..{hi:.0f}; a 16-bit PNG holds 1..65535 (0 = invalid)")
        write_image(path, codes.astype(np.uint16))
    elif ext in (".exr", ".tif", ".tiff", ".pfm"):
        write_image(path, (z / (1.0 if scale is None else scale)).astype(np.float32))
    else:
        raise ValueError(f"path: depth files are .exr, .tif, .pfm or .png, got {path}")


# --------------------------------------------------------------------------- view files
def _param(params: dict, key: str, where: str, *, allow_inf: bool = False) -> float:
    value = params[key]
    if allow_inf and (value == math.inf or (isinstance(value, str) and value.lower() in ("inf", "infinity"))):
        return math.inf  # JSON has no inf: accept "inf" (what save_view writes) or Python's Infinity
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{where}: parameter {key!r} must be a finite number, got {value!r}")
    return float(value)


def _check_depth_params(encoding, params: dict, where: str) -> dict:
    if encoding not in DEPTH_ENCODINGS:
        raise ValueError(f"{where}: unknown depth encoding {encoding!r}; expected one of "
                         f"{', '.join(map(repr, DEPTH_ENCODINGS))}")
    required, optional = DEPTH_ENCODINGS[encoding]
    missing = [k for k in required if k not in params]
    if missing:
        raise ValueError(f"{where}: encoding {encoding!r} needs parameter(s) {', '.join(missing)}")
    unknown = sorted(set(params) - set(required) - set(optional))
    if unknown:
        raise ValueError(f"{where}: unknown parameter(s) {', '.join(unknown)} for encoding {encoding!r} "
                         f"(allowed: {', '.join(required + optional) or 'none'})")
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
    for k in ("baseline", "focal_px", "scale"):
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
    if encoding == "window":
        return _depth.z_from_window(stored, **nf)
    if encoding == "reversed":
        return _depth.z_from_reversed(stored, **nf)
    if encoding == "zprime":
        return _depth.z_from_zprime(stored, **nf)
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
    if encoding in _FIXED_BITS or encoding in ("window", "zprime"):
        with np.errstate(invalid="ignore"):
            outside = valid & ((z < nf["near"]) | (z > nf["far"]))
        if outside.any():
            raise ValueError(f"depth: {int(outside.sum())} valid pixel(s) lie outside [near, far] = "
                             f"[{nf['near']}, {nf['far']}] and cannot be stored as {encoding!r}")
    if encoding == "window":
        return _depth.window_from_z(z, **nf).astype(np.float32)
    if encoding == "reversed":
        return _depth.reversed_from_z(z, **nf).astype(np.float32)
    if encoding == "zprime":
        return _depth.zprime_from_z(z, **nf).astype(np.float32)
    bits = _FIXED_BITS[encoding]
    q = _depth.fixed_from_z(z, bits=bits, **nf)
    if p.get("far_is_empty", True) and np.any(valid & (q == 2**bits - 1)):
        raise ValueError(f"depth: valid pixels quantize to the far code of a {bits}-bit buffer, which "
                         f"reads back as empty; move far out or set far_is_empty=false")
    return q


def _read_stored_depth(path: Path, encoding: str, p: dict, where: str) -> np.ndarray:
    if encoding in _FIXED_BITS:
        raw = read_image(path, what=where)
        if raw.ndim != 2:
            raise ValueError(f"{where}: expected a single-channel depth image, {path} has {raw.shape[2]} channels")
        if raw.dtype.kind == "f":  # codes stored in a float file must be integers
            if not np.all(np.isfinite(raw) & (raw == np.rint(raw)) & (raw >= 0)):
                raise ValueError(f"{where}: {path} must hold non-negative integer codes for {encoding!r}")
            raw = raw.astype(np.uint32)
        return raw
    return read_depth(path, scale=p.get("scale"), what=where)


def _json_number(x: float):
    return "inf" if isinstance(x, float) and math.isinf(x) else x


def load_view(path) -> View:
    """Load a view file (JSON sidecar + color + optional depth) as a :class:`~ibr.view.View`.

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
    _require_file(path, "view file")
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"view file {path}: not valid JSON ({exc})") from None
    where = f"view file {path}"
    if not isinstance(doc, dict):
        raise ValueError(f"{where}: expected a JSON object, got {type(doc).__name__}")
    if doc.get("format") != VIEW_FORMAT:
        raise ValueError(f"{where}: 'format' must be {VIEW_FORMAT!r}, got {doc.get('format')!r}")
    if doc.get("version") != VIEW_VERSION:
        raise ValueError(f"{where}: unsupported 'version' {doc.get('version')!r} (this reader knows {VIEW_VERSION})")
    for key in ("color", "camera"):
        if key not in doc:
            raise ValueError(f"{where}: missing key {key!r}")
    if not isinstance(doc["color"], str) or not doc["color"]:
        raise ValueError(f"{where}: 'color' must be a relative file name, got {doc['color']!r}")
    name = doc.get("name", path.stem)
    if not isinstance(name, str):
        raise ValueError(f"{where}: 'name' must be a string, got {name!r}")

    try:
        camera = Camera.from_dict(doc["camera"])
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{where}: bad 'camera': {exc}") from None

    color_path = path.parent / doc["color"]
    if not color_path.is_file():
        raise FileNotFoundError(f"{where}: 'color' refers to a missing file {color_path}")
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
        if not isinstance(spec, dict) or not isinstance(spec.get("path"), str) or not spec["path"]:
            raise ValueError(f"{dwhere} must be null or an object with a 'path' string, got {spec!r}")
        encoding = spec.get("encoding", "z")
        params = {k: v for k, v in spec.items() if k not in ("path", "encoding")}
        p = _check_depth_params(encoding, params, dwhere)
        depth_path = path.parent / spec["path"]
        if not depth_path.is_file():
            raise FileNotFoundError(f"{where}: 'depth.path' refers to a missing file {depth_path}")
        stored = _read_stored_depth(depth_path, encoding, p, f"{where}: 'depth.path'")
        if stored.shape != color.shape[:2]:
            raise ValueError(f"{where}: depth {depth_path.name} is {stored.shape[1]}x{stored.shape[0]} but color "
                             f"{color_path.name} is {color.shape[1]}x{color.shape[0]}")
        z = _depth.sanitize_depth(_decode_depth(stored, encoding, p, camera))[0]
    return View(color, z, camera, name)


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


def _dumps(doc: dict) -> str:
    """Indented JSON with every list of numbers on one line (readable 4x4 poses)."""
    text = json.dumps(doc, indent=2, allow_nan=False)
    return re.sub(r"\[[-+0-9.eE,\s]*\]", lambda m: re.sub(r"\s+", " ", m.group(0)).replace("[ ", "[").replace(" ]", "]"), text) + "\n"


def save_view(view: View, path, *, color_name: str | None = None, depth_name: str | None = None,
              depth_encoding: str = "z", depth_params: dict | None = None) -> Path:
    """Write a view file: color image, depth image (if the view has depth) and the JSON sidecar.

    Parameters
    ----------
    view : View
    path : str or Path
        The ``.json`` file to write. Color and depth go next to it.
    color_name, depth_name : str, optional
        File names relative to the JSON's folder. Defaults: ``<stem>_color.png`` (uint8/uint16
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
    params = _check_depth_params(depth_encoding, dict(depth_params or {}), "depth_params")
    stem = path.stem
    color_name = color_name or f"{stem}_color{_default_color_ext(view.color.dtype)}"
    names = [path.name, color_name]
    if view.depth is not None:
        depth_name = depth_name or f"{stem}_depth{_default_depth_ext(depth_encoding)}"
        names.append(depth_name)
    resolved = [(folder / n).resolve() for n in names]
    if len(set(resolved)) != len(resolved):
        raise ValueError(f"color_name/depth_name: the JSON, color and depth files must be distinct, got {names}")

    color = view.color
    if color.dtype == np.float64:
        color = color.astype(np.float32)
    _check_write_dtype(folder / color_name, color, "color")
    stored = None
    if view.depth is not None:
        stored = _encode_depth(view.depth, depth_encoding, params, view.camera)
        if depth_encoding in _FIXED_BITS:
            if depth_encoding == "fixed24" and Path(depth_name).suffix.lower() == ".png":
                raise ValueError("depth_name: 24-bit codes do not fit a PNG; use .exr or .tif")
            _check_write_dtype(folder / depth_name, stored, "depth")
        elif Path(depth_name).suffix.lower() == ".png" and "scale" not in params:
            raise ValueError(f"depth_params: a 16-bit PNG depth ({depth_name}) needs a 'scale'")

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
