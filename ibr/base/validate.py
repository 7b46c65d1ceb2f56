"""Argument checks shared by every public function.

Every check raises ``ValueError`` (or ``TypeError`` for a wrong kind of object) whose
message names the argument, what was expected and what was received, so that a user
can fix the call without reading the source.
"""

from __future__ import annotations

import difflib
import math
from typing import Any, Iterable

import numpy as np

__all__ = [
    "COLOR_DTYPES",
    "MAX_IMAGE_BYTES",
    "MAX_IMAGE_PIXELS",
    "MAX_IMAGE_SIDE",
    "CAMERA_KEYS",
    "check_array",
    "check_camera_dict",
    "check_choice",
    "check_color",
    "check_finite_scalar",
    "check_flag",
    "check_image",
    "check_image_size",
    "check_keys",
    "check_near_far",
    "check_number",
    "check_positive",
    "check_relative_path",
    "check_unit_vector",
    "nearest_name",
]

#: Image-size ceilings, checked before anything of that size is allocated (camera files, image
#: files, output sizes on the command line): at most 32768 px a side, 2**27 pixels (134 M, e.g.
#: a 16384 x 8192 panorama) and 2 GiB for one array (e.g. 2**27 px of float32 RGBA).
MAX_IMAGE_SIDE = 32768
MAX_IMAGE_PIXELS = 2**27
MAX_IMAGE_BYTES = 2**31

#: Colour dtypes a View (and every colour input) accepts.
COLOR_DTYPES = ("uint8", "uint16", "float32", "float64")


def check_array(
    name: str,
    value,
    *,
    ndim: int | Iterable[int] | None = None,
    shape: tuple | None = None,
    dtype_kind: str | None = None,
) -> np.ndarray:
    """Return ``value`` as an ndarray after checking its rank, shape and dtype kind.

    Parameters
    ----------
    name : str
        Argument name used in the error message.
    ndim : int or iterable of int, optional
        Allowed numbers of dimensions.
    shape : tuple, optional
        Expected shape; ``None`` entries match any length. Its length must equal ``ndim``.
    dtype_kind : str, optional
        Allowed numpy dtype kinds, e.g. ``"fiu"`` for float, signed and unsigned int.
    """
    if value is None:
        raise TypeError(f"{name}: expected an array, got None")
    arr = np.asarray(value)
    if arr.dtype == object:
        raise TypeError(f"{name}: expected a numeric array, got dtype object")
    if ndim is not None:
        allowed = (ndim,) if isinstance(ndim, int) else tuple(ndim)
        if arr.ndim not in allowed:
            raise ValueError(
                f"{name}: expected {' or '.join(map(str, allowed))} dimensions, "
                f"got shape {arr.shape}"
            )
    if shape is not None:
        ok = arr.ndim == len(shape) and all(
            want is None or want == got for want, got in zip(shape, arr.shape)
        )
        if not ok:
            want = "(" + ", ".join("N" if s is None else str(s) for s in shape) + ")"
            raise ValueError(f"{name}: expected shape {want}, got {arr.shape}")
    if dtype_kind is not None and arr.dtype.kind not in dtype_kind:
        raise ValueError(f"{name}: expected dtype of kind {dtype_kind!r}, got {arr.dtype}")
    return arr


def check_image(name: str, value, *, channels: Iterable[int] | None = None) -> np.ndarray:
    """Check an image array of shape (H, W) or (H, W, C) with a numeric dtype.

    ``channels`` restricts C (``1`` also admits a 2-D array). Returns the array unchanged.
    """
    arr = check_array(name, value, ndim=(2, 3), dtype_kind="fiub")
    if arr.shape[0] < 1 or arr.shape[1] < 1:
        raise ValueError(f"{name}: image must be at least 1x1, got shape {arr.shape}")
    if channels is not None:
        allowed = tuple(channels)
        c = 1 if arr.ndim == 2 else arr.shape[2]
        if c not in allowed:
            raise ValueError(
                f"{name}: expected {' or '.join(map(str, allowed))} channels, got shape {arr.shape}"
            )
    return arr


def check_finite_scalar(name: str, value) -> float:
    """Return ``value`` as a finite float or raise naming ``name``. A bool or a string is no
    number (``float(True)`` and ``float("0.5")`` would pass); an integer too large for a float is
    not finite."""
    if isinstance(value, (bool, np.bool_, str, bytes)):
        raise TypeError(f"{name}: expected a real number, got {value!r}")
    try:
        out = float(value)
    except OverflowError:
        raise ValueError(f"{name}: expected a finite number, got an integer of {len(str(value))} digits") from None
    except (TypeError, ValueError):
        raise TypeError(f"{name}: expected a real number, got {value!r}") from None
    if not np.isfinite(out):
        raise ValueError(f"{name}: expected a finite number, got {value!r}")
    return out


def check_flag(name: str, value) -> bool:
    """Return ``value`` as a bool if it is one (Python or numpy), or raise a TypeError naming ``name``
    (a string or a number is no flag: ``"no"`` would be true)."""
    if not isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name}: expected True or False, got {value!r}")
    return bool(value)


def check_positive(name: str, value, *, allow_inf: bool = False) -> float:
    """Return ``value`` as a float > 0 (optionally allowing +inf) or raise naming ``name``."""
    if allow_inf and isinstance(value, (int, float, np.integer, np.floating)) and np.isposinf(value):
        return float("inf")
    out = check_finite_scalar(name, value)
    if out <= 0:
        raise ValueError(f"{name}: expected a positive number, got {value!r}")
    return out


#: The keyword options of ``ibr.build_mesh`` (``mesh_options`` of the renderers).
MESH_OPTIONS = ("threshold", "max_error_px", "method", "baseline", "near", "far", "min_band", "quantization")


def check_mesh_options(mesh_options) -> dict:
    """``mesh_options`` (options of ``ibr.build_mesh``, :data:`MESH_OPTIONS`) as a new dict
    (None -> {}), or a TypeError / ValueError naming it (an unknown key with the nearest valid
    name: a misspelt key reached build_mesh as "unexpected keyword argument")."""
    if mesh_options is None:
        return {}
    if not isinstance(mesh_options, dict):
        raise TypeError(f"mesh_options: expected a dict of ibr.build_mesh options, got {type(mesh_options).__name__}")
    check_keys("mesh_options", mesh_options, MESH_OPTIONS)
    return dict(mesh_options)


def check_choice(name: str, value, choices: Iterable[str]) -> str:
    """Check that ``value`` is one of ``choices`` and list the valid ones if not."""
    choices = tuple(choices)
    if value not in choices:
        raise ValueError(f"{name}: expected one of {', '.join(map(repr, choices))}, got {value!r}")
    return value


def check_near_far(near, far) -> tuple[float, float]:
    """Return (near, far) as floats with 0 < near < far (far may be +inf), or raise naming them."""
    n = check_positive("near", near)
    f = check_positive("far", far, allow_inf=True)
    if not f > n:
        raise ValueError(f"far: expected far > near, got near={near!r}, far={far!r}")
    return n, f


def check_unit_vector(name: str, value) -> np.ndarray:
    """Return the 3-vector ``value`` normalized to unit length (float64), or raise naming ``name``
    when it is not a finite, non-zero 3-vector."""
    a = check_array(name, value, shape=(3,), dtype_kind="fiu").astype(np.float64)
    n = np.linalg.norm(a)
    if not np.isfinite(n) or n == 0:
        raise ValueError(f"{name}: expected a finite non-zero 3-vector, got {a.tolist()}")
    return a / n


# --------------------------------------------------------------------------- schemas and limits
def nearest_name(name, valid: Iterable[str]) -> str | None:
    """The valid name closest to ``name`` (difflib ratio >= 0.6, else a case-insensitive prefix
    or substring match), or None."""
    valid = list(valid)
    if not isinstance(name, str):
        return None
    hit = difflib.get_close_matches(name, valid, n=1, cutoff=0.6)
    if hit:
        return hit[0]
    low = name.lower()
    for v in valid:
        if low and (v.lower().startswith(low) or low in v.lower() or v.lower() in low):
            return v
    return None


#: Names other tools use for a key of ours (suggested when a file uses them).
KEY_ALIASES = {
    "pose": "world_from_cam", "extrinsics": "world_from_cam", "cam_to_world": "world_from_cam",
    "camera_to_world": "world_from_cam", "c2w": "world_from_cam", "transform": "world_from_cam",
    "transform_matrix": "world_from_cam", "matrix": "world_from_cam", "w": "width", "h": "height",
    "focal": "fx", "f": "fx", "image": "color", "colour": "color", "rgb": "color", "file": "path",
    "filename": "path", "z": "depth",
}


def check_keys(where: str, doc: dict, allowed: Iterable[str], *, required: Iterable[str] = ()) -> None:
    """Refuse unknown keys of a JSON object (suggesting the nearest valid name) and missing ones.

    Raises ``ValueError``: ``"<where>: unknown key 'pose' (did you mean 'world_from_cam'?); allowed:
    ..."`` or ``"<where>: missing key(s) ..."``. Suggestions come from :func:`nearest_name` over
    the allowed keys not yet present, or from :data:`KEY_ALIASES` (names other tools use).
    """
    allowed = tuple(allowed)
    if not isinstance(doc, dict):
        raise TypeError(f"{where}: expected a JSON object, got {type(doc).__name__}")
    for key in doc:
        if key not in allowed:
            absent = [a for a in allowed if a not in doc]
            alias = KEY_ALIASES.get(key.lower()) if isinstance(key, str) else None
            near = nearest_name(key, absent) or (alias if alias in allowed else None)
            hint = f" (did you mean {near!r}?)" if near else ""
            raise ValueError(f"{where}: unknown key {key!r}{hint}; allowed: {', '.join(allowed)}")
    missing = [k for k in required if k not in doc]
    if missing:
        raise ValueError(f"{where}: missing key(s) {', '.join(missing)}")


def check_number(where: str, value, *, integer: bool = False, minimum: float | None = None,
                 maximum: float | None = None, exclusive_minimum: bool = False,
                 allow_inf: bool = False) -> Any:
    """A JSON number checked for type (not bool, not string), finiteness and range.

    ``integer`` requires an integral value (``3`` or ``3.0``) and returns an int. ``allow_inf``
    admits +inf (for a far plane), as a float or the strings ``"inf"``/``"Infinity"``.
    Raises ``TypeError`` for a wrong type, ``ValueError`` for a bad value; messages start with
    ``where`` and give the received value.
    """
    if allow_inf and (isinstance(value, str) and value.lower() in ("inf", "+inf", "infinity")
                      or (isinstance(value, (float, np.floating)) and value == math.inf)):
        value = math.inf
    elif isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
        kind = "an integer" if integer else "a number"
        raise TypeError(f"{where}: expected {kind}, got {value!r} ({type(value).__name__})")
    else:
        try:
            finite = math.isfinite(value)
        except OverflowError:  # an int too large for a float (a 401-digit width in a JSON file)
            finite = False
        if not finite:
            shown = (f"an integer of {len(str(abs(value)))} digits" if isinstance(value, (int, np.integer))
                     else repr(value))
            raise ValueError(f"{where}: expected a finite number, got {shown}")
    if integer:
        if value != math.floor(value):
            raise ValueError(f"{where}: expected an integer, got {value!r}")
        value = int(value)
    if minimum is not None and (value < minimum or (exclusive_minimum and value == minimum)):
        want = ("a positive number" if exclusive_minimum and minimum == 0 else
                f"a number {'>' if exclusive_minimum else '>='} {minimum:g}")
        raise ValueError(f"{where}: expected {want}, got {value!r}")
    if maximum is not None and value > maximum:
        raise ValueError(f"{where}: expected a number <= {maximum:g}, got {value!r}")
    return value


def check_image_size(name: str, width, height, *, channels: int = 1, itemsize: int = 4) -> tuple[int, int]:
    """Check an image size against the ceilings before allocating it; return ``(width, height)``.

    Ceilings: :data:`MAX_IMAGE_SIDE` px a side, :data:`MAX_IMAGE_PIXELS` pixels and
    :data:`MAX_IMAGE_BYTES` bytes for ``channels`` values of ``itemsize`` bytes per pixel.
    """
    w = check_number(f"{name}: width", width, integer=True, minimum=1)
    h = check_number(f"{name}: height", height, integer=True, minimum=1)
    if w > MAX_IMAGE_SIDE or h > MAX_IMAGE_SIDE:
        raise ValueError(f"{name}: {w}x{h} exceeds the ceiling of {MAX_IMAGE_SIDE} px a side")
    if w * h > MAX_IMAGE_PIXELS:
        raise ValueError(f"{name}: {w}x{h} = {w * h} pixels exceeds the ceiling of {MAX_IMAGE_PIXELS} pixels")
    nbytes = w * h * int(channels) * int(itemsize)
    if nbytes > MAX_IMAGE_BYTES:
        raise ValueError(f"{name}: {w}x{h}x{channels} of {itemsize}-byte values = {nbytes / 2**30:.2f} GiB "
                         f"exceeds the ceiling of {MAX_IMAGE_BYTES / 2**30:g} GiB per image")
    return w, h


def check_color(name: str, value, *, channels: Iterable[int] | None = (1, 3, 4)) -> np.ndarray:
    """A colour image: (H, W), (H, W, 3) or (H, W, 4) (``channels``; None: any number) of uint8,
    uint16, float32 or float64 (the dtypes OpenCV's resize, remap and warps have kernels for)."""
    arr = check_image(name, value, channels=channels)
    if arr.dtype.name not in COLOR_DTYPES:
        raise TypeError(f"{name}: expected a colour dtype {', '.join(COLOR_DTYPES)}, got {arr.dtype}")
    return arr


def check_relative_path(name: str, value) -> str:
    """A file name relative to a view file's folder: a non-empty string, not absolute, with no
    ``..`` part (a view file never names a file outside its own folder tree)."""
    from pathlib import PurePosixPath, PureWindowsPath

    if not isinstance(value, str) or not value.strip():
        raise ValueError(f"{name}: expected a relative file name, got {value!r}")
    if "\x00" in value:
        raise ValueError(f"{name}: file name contains a NUL character: {value!r}")
    for flavour in (PurePosixPath, PureWindowsPath):
        p = flavour(value)
        if p.is_absolute() or p.anchor or ".." in p.parts:
            raise ValueError(f"{name}: expected a file name inside the view file's folder "
                             f"(relative, no '..'), got {value!r}")
    return value


#: Keys of a camera object (view files, bare camera files, time-warp pose lists).
CAMERA_KEYS = ("width", "height", "fx", "fy", "cx", "cy", "world_from_cam")
#: Range of the intrinsics in a camera object, in pixels (finite, fx and fy > 0).
MAX_FOCAL_PX = 1e9
MAX_PRINCIPAL_PX = 1e9


def check_camera_dict(d, where: str = "camera") -> dict:
    """Check a camera JSON object strictly and return its values as Python numbers.

    Keys: ``width``, ``height`` (integers >= 1 within the image-size ceilings), ``fx``, ``fy``
    (0 < f <= 1e9 px), ``cx``, ``cy`` (|c| <= 1e9 px), optional ``world_from_cam`` (4 rows of 4
    finite numbers; identity when absent). Unknown keys are refused with the nearest valid name
    (messages start with ``where``); bad values are named by their key (``fx: expected ...``).
    The pose's rotation block is checked by :class:`~ibr.base.camera.Camera` itself.
    """
    check_keys(where, d, CAMERA_KEYS, required=CAMERA_KEYS[:6])
    out: dict[str, Any] = {}
    for k in ("width", "height"):
        out[k] = check_number(k, d[k], integer=True, minimum=1)
    check_image_size("width x height", out["width"], out["height"])
    for k in ("fx", "fy"):
        out[k] = float(check_number(k, d[k], minimum=0, exclusive_minimum=True,
                                    maximum=MAX_FOCAL_PX))
    for k in ("cx", "cy"):
        out[k] = float(check_number(k, d[k], minimum=-MAX_PRINCIPAL_PX, maximum=MAX_PRINCIPAL_PX))
    pose = d.get("world_from_cam")
    if pose is None and "world_from_cam" not in d:
        out["world_from_cam"] = np.eye(4)
        return out
    rows = pose.tolist() if isinstance(pose, np.ndarray) else pose
    if not isinstance(rows, (list, tuple)) or len(rows) != 4 or not all(
            isinstance(r, (list, tuple)) and len(r) == 4 for r in rows):
        raise ValueError(f"world_from_cam: must be a 4x4 matrix (4 rows of 4 numbers), got {pose!r}"[:300])
    out["world_from_cam"] = np.array(
        [[check_number(f"world_from_cam[{i}][{j}]", v) for j, v in enumerate(r)]
         for i, r in enumerate(rows)], dtype=np.float64)
    return out
