"""Timing helper shared by the benchmark scripts (never used by tests: tests do not time)."""

from __future__ import annotations

import time

import numpy as np


def median_seconds(fn, repeats: int, *, warm: bool = True) -> float:
    """Median wall time of ``fn()`` over ``repeats`` calls, in seconds.

    With ``warm`` one untimed call runs first (numba cache load, allocator, OpenCV threads).
    Report results as ratios to a baseline timed in the same run: the machine is shared.
    """
    if warm:
        fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def median_ms(fn, repeats: int, *, warm: bool = True) -> float:
    """:func:`median_seconds` in milliseconds."""
    return 1e3 * median_seconds(fn, repeats, warm=warm)
