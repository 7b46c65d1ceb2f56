"""ibr.base.jit: numba loaded without its BLAS probe (scipy.linalg), BLAS still there when asked."""

import subprocess
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_kernels_load_without_scipy_linalg_and_blas_still_works():
    # a fresh interpreter: pytest's own process may have loaded numba's numpy support already
    script = textwrap.dedent("""
        import sys
        import numpy as np
        import ibr.render._fill_kernels  # a kernel module: loads numba through ibr.base.jit
        assert "numba.np.arraymath" in sys.modules
        skipped = "scipy.linalg" not in sys.modules
        import scipy.linalg, scipy.linalg.cython_blas  # importable as usual afterwards
        from ibr.base.jit import njit

        @njit
        def dot(a, b):
            return np.dot(a, b)

        a = np.arange(12.0).reshape(3, 4)
        b = np.linspace(-1.0, 2.0, 8).reshape(4, 2)
        print(skipped, float(np.abs(dot(a, b) - a @ b).max()))
    """)
    out = subprocess.run([sys.executable, "-c", script], cwd=ROOT, capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0, out.stderr
    skipped, err = out.stdout.split()
    assert skipped == "True"  # scipy.linalg was not imported by loading the kernels
    assert float(err) < 1e-12  # np.dot in a kernel compiled against BLAS and is right
