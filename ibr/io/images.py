"""Image and depth files: read/write through OpenImageIO (PFM with numpy), atomic writes.

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

Writing is atomic: every output goes to a temporary name in the destination folder and is
renamed onto its final name only when it has been written completely (:func:`atomic_path`).
Reading checks the image-size ceilings (:data:`ibr.base.validate.MAX_IMAGE_PIXELS`, ``MAX_IMAGE_BYTES``)
from the header, before any pixel is allocated. Commands stage all their outputs together with
:class:`ibr.io.outputs.OutputPlan`.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import tempfile
from pathlib import Path
from typing import Iterator

import numpy as np

from ..base import depth as _depth
from ..base.validate import check_choice, check_image, check_image_size, nearest_name

__all__ = [
    "DEPTH_CHANNEL_NAMES",
    "atomic_path",
    "check_unit_colour",
    "check_write_dtype",
    "depth_channel_names",
    "read_depth",
    "read_image",
    "read_pfm",
    "write_depth",
    "write_image",
    "write_pfm",
]

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
    check_image_size(f"pfm {path}", w, h, channels=c, itemsize=4)  # before allocating (#12)
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
        return _read_pfm_named(path, what)
    oiio = _oiio()
    config = oiio.ImageSpec()
    config.attribute("oiio:UnassociatedAlpha", 1)  # return RGBA as stored, not premultiplied
    inp = oiio.ImageInput.open(str(path), config)
    if inp is None:
        raise ValueError(f"{what}: cannot read {path}: {_one_line(oiio.geterror()) or 'unknown format'}")
    try:
        spec = inp.spec()
        # the size ceilings, before the pixels are allocated (#12)
        check_image_size(f"{what} {path}", spec.width, spec.height, channels=max(1, spec.nchannels),
                         itemsize=max(4, spec.format.size()))
        pixels = inp.read_image(0, 0, 0, inp.spec().nchannels, oiio.UNKNOWN)
        err = inp.geterror() if inp.has_error else ""
    finally:
        inp.close()
    if pixels is None or err or not isinstance(pixels, np.ndarray):
        raise ValueError(f"{what}: corrupt or unreadable image {path}: {_one_line(err or oiio.geterror())}")
    if pixels.dtype in (np.float16, np.float64):
        pixels = pixels.astype(np.float32)
    elif pixels.dtype == np.int8 or pixels.dtype == np.int16 or pixels.dtype == np.int32:
        raise ValueError(f"{what}: {path} stores signed integers ({pixels.dtype}); not supported")
    if pixels.ndim == 3 and pixels.shape[2] == 1:
        pixels = pixels[..., 0]
    return np.ascontiguousarray(pixels)


def _read_pfm_named(path: Path, what: str) -> np.ndarray:
    """:func:`read_pfm`'s pixels; a bad file's message starts with ``what`` (e.g. the view file's key)."""
    try:
        return read_pfm(path)[0]
    except ValueError as exc:
        raise ValueError(f"{what}: {exc}") from None


def _one_line(message) -> str:
    """OpenImageIO's error text on one line (#12: errors are one line), each distinct line once: a
    truncated PNG gave "Read error: hit end of file in png reader", "PNG read error: IDAT: Read
    error: hit end of file in png reader" and "PNG library error"; a line contained in another is
    left out, the others are joined by "; "."""
    lines = [" ".join(line.split()) for line in str(message or "").splitlines()]
    lines = [line for line in lines if line]
    kept = [line for i, line in enumerate(lines)
            if not any(line != other and line in other for other in lines) and line not in lines[:i]]
    return "; ".join(kept)


def check_unit_colour(what: str, img, into: str, advice: str = "write it to .exr, .tif or .pfm") -> None:
    """Refuse a one-channel float image that is a depth or range map, not a grey image, before it
    is stored as 8-bit grey levels (``into``: the file or faces it was going to): most of its
    finite values (the median) lie above 1, or some below 0, by more than half an 8-bit step.
    Clipped, it would be all white. A grey HDR image (highlights above 1) and colour (three or four
    channels) clip as usual. Raises ValueError naming ``what``, ending with ``advice``."""
    got = _depth_like(img)
    if got is not None:
        lo, hi, typical = got
        raise ValueError(f"{what}: {into} would hold 8-bit grey levels 0-1, but this one-channel float image "
                         f"holds {lo:.4g} to {hi:.4g}, median {typical:.4g} (a depth or range map); {advice}")


def _depth_like(img) -> tuple[float, float, float] | None:
    """(min, max, median) of the finite values of a one-channel float image that holds depth or
    range rather than grey levels (the median above 1, or some value below 0, by more than half an
    8-bit step), else None (:func:`check_unit_colour`'s test)."""
    a = np.asarray(img)
    if a.dtype.kind != "f" or not (a.ndim == 2 or (a.ndim == 3 and a.shape[2] == 1)):
        return None
    finite = a[np.isfinite(a)]
    if not finite.size:
        return None
    typical = float(np.median(finite[:: max(1, finite.size // 100_000)]))  # a sample: 8 Mpx took 0.1 s
    lo = float(finite.min())
    if typical > 1 + 0.5 / 255 or lo < -0.5 / 255:
        return lo, float(finite.max()), typical
    return None


def check_write_dtype(name: str, path, dtype) -> str:
    """Refuse (ValueError naming ``name``) writing pixels of ``dtype`` to ``path``'s format (e.g.
    uint8 into an EXR): what :func:`write_image` refuses, for a command to check before its work.
    Returns the lower-case extension."""
    path, dtype = Path(path), np.dtype(dtype)
    ext = path.suffix.lower()
    if ext not in _WRITE_DTYPES:
        raise ValueError(f"{name}: unsupported extension {ext!r} for {path}; expected one of "
                         f"{', '.join(_WRITE_DTYPES)}")
    if dtype.name not in _WRITE_DTYPES[ext]:
        raise ValueError(f"{name}: a {ext} file stores {' or '.join(_WRITE_DTYPES[ext])}, got {dtype} "
                         f"(convert the array or choose another extension)")
    return ext


#: zlib level of written PNGs: a 512x384 frame took 53 ms at OIIO's default 6 (three of them were
#: a tenth of a warm `ibr interpolate`, #13), 23 ms at 4, for 261 kB instead of 250 kB.
PNG_COMPRESSION_LEVEL = 4


def write_image(path, array) -> None:
    """Write an image atomically; the format follows the extension and the dtype is preserved.

    ``.png``: uint8 or uint16; ``.jpg``: uint8 (quality 95, lossy); ``.tif``: uint8, uint16,
    uint32, float32; ``.exr``: float32 (NaN and inf kept), float16, uint32; ``.pfm``: float32.
    Arrays are (H, W) or (H, W, C) with row 0 at the top. Any other combination raises
    ``ValueError`` before anything is written.
    """
    path = Path(path)
    arr = check_image("array", array)
    ext = check_write_dtype("array", path, arr.dtype)
    if ext == ".pfm":
        write_pfm(path, arr)
        return
    if arr.ndim == 2:
        arr = arr[..., None]
    if ext in (".jpg", ".jpeg") and arr.shape[2] not in (1, 3):  # JPEG would drop alpha silently
        raise ValueError(f"array: a JPEG file holds 1 or 3 channels, got {arr.shape[2]} for {path.name} "
                         "(write .png or .tif to keep them all)")
    oiio = _oiio()
    typedesc = {"uint8": oiio.UINT8, "uint16": oiio.UINT16, "uint32": oiio.UINT32,
                "float16": oiio.HALF, "float32": oiio.FLOAT}[arr.dtype.name]
    h, w, c = arr.shape
    with atomic_path(path) as tmp:
        out = oiio.ImageOutput.create(str(tmp))
        if out is None:
            raise ValueError(f"array: cannot create a writer for {path}: {_one_line(oiio.geterror())}")
        spec = oiio.ImageSpec(w, h, c, typedesc)
        spec.attribute("oiio:UnassociatedAlpha", 1)  # RGBA arrays are straight (not premultiplied)
        if ext in (".jpg", ".jpeg"):
            spec.attribute("Compression", "jpeg:95")
        if ext == ".png":  # zlib level 4: 2.3x faster to write than OIIO's default 6, files ~5 % larger
            spec.attribute("png:compressionLevel", PNG_COMPRESSION_LEVEL)
        try:
            if not out.open(str(tmp), spec):
                raise OSError(f"{path}: cannot open for writing: {_one_line(out.geterror())}")
            written = out.write_image(np.ascontiguousarray(arr))
            error = out.geterror()  # OIIO's PNG writer reports a short write (a full disk) only here
            if not written or error:
                raise OSError(f"{path}: write failed: {_one_line(error)}")
        finally:
            closed = out.close()
        error = out.geterror()  # read (and cleared) either way: TIFF's close notes a harmless Exif message
        if not closed:  # nothing is renamed into place: atomic_path drops the temporary file
            raise OSError(f"{path}: write failed when closing the file: {_one_line(error)}")


# --------------------------------------------------------------------------- depth files
#: Channel names other tools give a depth pass, tried in this order (case-insensitive, also after
#: a layer prefix) when a file has several channels and none is named: Blender's multilayer render
#: output (``ViewLayer.Depth.Z``), a plain ``Z``/``depth`` channel, ``Depth.V`` (Blender's File
#: Output node, multilayer, slot "Depth"), ``distance.Y`` (Nuke-style layer.channel names).
#: Stored float depth equal to this is "no surface" (Blender's Cycles Z pass writes exactly 1e10
#: there; other huge values stay errors of the view's depth range).
BACKGROUND_DEPTH = 1e10
#: The largest half float: EEVEE's Z pass (half precision) saturates there where there is no surface.
HALF_MAX = 65504.0

DEPTH_CHANNEL_NAMES = ("Depth.Z", "Z", "depth", "Depth", "depth.V", "depth.Y", "distance.Y", "Y", "V")


def depth_channel_names(path, *, what: str = "depth") -> list[str]:
    """Channel names of an image file (``R``, ``G``, ... for plain images)."""
    path = Path(path)
    _require_file(path, what)
    if path.suffix.lower() == ".pfm":
        return ["Y"] if _read_pfm_named(path, what).ndim == 2 else ["R", "G", "B"]
    oiio = _oiio()
    inp = oiio.ImageInput.open(str(path))
    if inp is None:
        raise ValueError(f"{what}: cannot read {path}: {_one_line(oiio.geterror()) or 'unknown format'}")
    try:
        return list(inp.spec().channelnames)
    finally:
        inp.close()


def _pick_depth_channel(names: list[str], channel: str | None, path: Path, what: str) -> int | None:
    """Index of the depth channel among ``names``; None = decide from the pixels (R = G = B)."""
    if channel is not None:
        if channel in names:
            return names.index(channel)
        tails = [i for i, n in enumerate(names) if n.endswith("." + channel)]
        if len(tails) == 1:
            return tails[0]
        tails = {n.split(".", 1)[1]: n for n in names if "." in n}  # "Depth.Z" of "ViewLayer.Depth.Z"
        near = nearest_name(channel, names) or tails.get(nearest_name(channel, tails) or "")
        raise ValueError(f"{what}: {path} has no channel {channel!r}"
                         f"{f' (did you mean {near!r}?)' if near else ''}; it has {', '.join(names)}")
    if len(names) == 1:
        return 0
    low = [n.lower() for n in names]
    for want in (w.lower() for w in DEPTH_CHANNEL_NAMES):  # "ViewLayer.Depth.Z" ends with ".depth.z"
        hits = [i for i, n in enumerate(low) if n == want or n.endswith("." + want)]
        if len(hits) == 1:
            return hits[0]
    return None


def _depth_array(path: Path, channel: str | None, what: str, name_it: str = "") -> np.ndarray:
    """(H, W) stored depth values: the named channel, the one depth-named channel, or the one
    value of an RGB(A) file whose colour channels agree (Blender's File Output node writes
    R = G = B = Z). ``name_it``: how the caller's user names a channel (a view file's "channel"
    key), added to the errors of a file whose depth channel cannot be told."""
    names = depth_channel_names(path, what=what)
    a = read_image(path, what=what)
    if a.ndim == 2:
        if channel is not None:
            _pick_depth_channel(names[:1], channel, path, what)  # a wrong name is still an error
        return a
    k = _pick_depth_channel(names, channel, path, what)
    if k is not None:
        return np.ascontiguousarray(a[..., k])
    colour = [i for i, n in enumerate(names) if n.split(".")[-1] in ("R", "G", "B")]
    if len(colour) < 2:
        raise ValueError(f"{what}: {path} has {len(names)} channels ({', '.join(names)}) and none is a depth "
                         f"channel{name_it}")
    first = a[..., colour[0]]
    for i in colour[1:]:
        same = (a[..., i] == first) | (np.isnan(a[..., i]) & np.isnan(first)) if a.dtype.kind == "f" \
            else a[..., i] == first
        if not np.all(same):
            bad = int((~same).sum())
            raise ValueError(f"{what}: {path} has {len(names)} channels ({', '.join(names)}) whose values "
                             f"differ at {bad} pixel(s) ({names[colour[0]]} vs {names[i]}): a colour image, not a "
                             f"depth pass?{name_it}")
    return np.ascontiguousarray(first)


def read_depth(path, *, scale: float | None = None, channel: str | None = None,
               what: str = "depth", blender_markers: bool = True, name_channel: str = "channel=") -> np.ndarray:
    """Read a depth (or disparity, or any per-pixel scalar) file as float32, as tools write them.

    Parameters
    ----------
    path : str or Path
        Float ``.exr``/``.tif``/``.pfm`` (values as stored; NaN, +-inf, exactly 1e10 and 65504 --
        Blender's background, Cycles / EEVEE -- become NaN) or integer
        ``.png``/``.tif`` (``value = code * scale``, code 0 becomes NaN). Single channel; or RGB(A)
        whose colour channels agree (Blender's File Output node: R = G = B = Z); or several named
        channels, of which ``channel`` or the one named like a depth pass
        (:data:`DEPTH_CHANNEL_NAMES`, e.g. Blender's multilayer ``ViewLayer.Depth.Z``) is taken.
    scale : float, optional
        Scene units per stored unit. Required for integer files (``0.001`` for millimetre PNGs of
        depth cameras, ``1/5000`` for TUM RGB-D); multiplies float files (default 1).
    channel : str, optional
        Channel name (exact, or the part after the last layer dot: ``"Depth.Z"`` finds
        ``ViewLayer.Depth.Z``).
    blender_markers : bool
        Read 1e10 and 65504 as "no surface" (depth passes); False for stored values that are no
        depth pass (disparity, window depth, z'), where 65504 is a value like any other.
    name_channel : str
        How the caller's user names a channel, suggested when a file's depth channel cannot be
        told ("" when there is no way: a CLI option without a channel).

    Returns
    -------
    (H, W) float32, row 0 at the top, NaN where invalid.
    """
    if channel is not None and (not isinstance(channel, str) or not channel):
        raise ValueError(f"{what}: channel must be a non-empty string, got {channel!r}")
    if scale is not None and not (isinstance(scale, (int, float)) and math.isfinite(scale) and scale > 0):
        raise ValueError(f"{what}: scale must be a positive number, got {scale!r}")
    name_it = f"; name the depth channel with {name_channel}" if name_channel else ""
    return _depth_values(_depth_array(Path(path), channel, what, name_it), path, scale=scale, what=what,
                        blender_markers=blender_markers)


def _depth_values(a: np.ndarray, path, *, scale: float | None = None, what: str = "depth",
                 blender_markers: bool = True) -> np.ndarray:
    """The stored array ``a`` of the depth file ``path`` as :func:`read_depth` returns it
    (integer codes times ``scale``, code 0 NaN; floats with their invalid values NaN)."""
    if a.dtype.kind in "ui":
        if scale is None:
            raise ValueError(f"{what}: {path} stores integer codes ({a.dtype}); give `scale` "
                             f"(scene units per code)")
        out = a.astype(np.float64) * scale
        out[a == 0] = np.nan
        return out.astype(np.float32)
    out = a.astype(np.float32)
    # Blender's Z pass where there is no surface: 1e10 (Cycles), the half-float maximum (EEVEE)
    invalid = ~np.isfinite(out)
    if blender_markers:
        invalid |= (out == BACKGROUND_DEPTH) | (out == HALF_MAX)
    out[invalid] = np.nan
    return out * np.float32(1.0 if scale is None else scale)


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
