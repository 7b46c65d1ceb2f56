"""Argument checks shared by every public function.

Every check raises ``ValueError`` (or ``TypeError`` for a wrong kind of object) whose
message names the argument, what was expected and what was received, so that a user
can fix the call without reading the source.
"""

from __future__ import annotations

from typing import Iterable

import numpy as np

__all__ = [
    "check_array",
    "check_choice",
    "check_finite_scalar",
    "check_image",
    "check_near_far",
    "check_positive",
    "check_unit_vector",
]


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
    """Return ``value`` as a finite float or raise naming ``name``."""
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise TypeError(f"{name}: expected a real number, got {value!r}") from None
    if not np.isfinite(out):
        raise ValueError(f"{name}: expected a finite number, got {value!r}")
    return out


def check_positive(name: str, value, *, allow_inf: bool = False) -> float:
    """Return ``value`` as a float > 0 (optionally allowing +inf) or raise naming ``name``."""
    if allow_inf and value is not None and np.isposinf(float(value)):
        return float("inf")
    out = check_finite_scalar(name, value)
    if out <= 0:
        raise ValueError(f"{name}: expected a positive number, got {value!r}")
    return out


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
