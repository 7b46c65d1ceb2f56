"""numba for the kernel modules, loaded without its BLAS probe (issue #13, cold start).

The first time numba compiles or loads a kernel it imports ``numba.np.arraymath``, whose
``_check_blas`` imports ``scipy.linalg`` (0.08-0.14 s on the 2-core machine, on every command's
critical path and again in the first-run helper) only to decide whether inner products inside
``np.correlate`` / ``np.convolve`` kernels call BLAS or a plain loop. No kernel of ``ibr`` or
``panorama`` uses those. :func:`_load_arraymath_without_blas_probe` answers the probe "no BLAS"
while that one module loads and then lets ``scipy.linalg`` import normally again, so ``np.dot`` and
``np.linalg`` inside a kernel still find BLAS (numba imports it when it compiles them), and any other
code may import ``scipy.linalg`` as usual. Kernel modules take ``njit`` and ``prange`` from here.
"""

from __future__ import annotations

import sys

__all__ = ["njit", "prange"]

_BLAS_PROBE = "scipy.linalg.cython_blas"  # the module numba.np.linalg.ensure_blas imports


def _load_arraymath_without_blas_probe() -> None:
    """Import ``numba.np.arraymath`` with its BLAS probe failing at once (unless either module
    is loaded already); ``scipy.linalg`` is importable as before afterwards."""
    if "numba.np.arraymath" in sys.modules or _BLAS_PROBE in sys.modules:
        return
    sys.modules[_BLAS_PROBE] = None  # an import of it raises ModuleNotFoundError, loading nothing
    try:
        import numba.np.arraymath  # noqa: F401
    finally:
        del sys.modules[_BLAS_PROBE]


_load_arraymath_without_blas_probe()

from numba import njit, prange  # noqa: E402
