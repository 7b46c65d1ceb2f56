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


def paired_ms(fn, base_fn, repeats: int) -> tuple[float, float]:
    """(median ms of ``fn``, median of the per-repeat ratios fn / base_fn), the two timed back to
    back in every repeat so that load bursts on the shared machine hit both alike."""
    fn(), base_fn()
    ts, ratios = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        base_fn()
        t1 = time.perf_counter()
        fn()
        t2 = time.perf_counter()
        ts.append(t2 - t1)
        ratios.append((t2 - t1) / (t1 - t0))
    return float(np.median(ts) * 1e3), float(np.median(ratios))


def report(rows, header, results_file) -> None:
    """Print ``rows`` (tuples of strings) under ``header`` (same length) with aligned columns and
    write them to ``results_file`` (``|``-separated), creating its folder."""
    from pathlib import Path

    widths = [max(len(str(x)) for x in col) for col in zip(header, *rows)]
    for row in (header, *rows):
        print("  ".join(str(x).ljust(w) for x, w in zip(row, widths)).rstrip())
    path = Path(results_file)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(" | ".join(map(str, r)) for r in rows) + "\n")
