"""Row bands on a thread pool: serial numba kernels on every core (issue #13, cold start).

A kernel compiled with ``parallel=True`` takes two to three times longer to compile than the same
loop compiled serially (``sample_composite2``: 3.2 s against 1.2 s), and a fresh install pays that
on its first command. The kernels of the per-frame path are therefore compiled serially with
``nogil=True`` and take a half-open range of rows (or bands) ``[start, stop)``;
:func:`run_bands` splits ``[0, n)`` into pieces that the calling thread and the pool's threads
take in turn. Each piece owns its rows, so there are no write races. One task is submitted per
extra thread (a submission costs ~0.1 ms of wake-ups); finer pieces than threads balance uneven
work (the rasterizer's bands: 8 pieces on 2 threads).
"""

from __future__ import annotations

import itertools
import os
from concurrent.futures import ThreadPoolExecutor

__all__ = ["run_bands", "thread_count"]

_POOL: ThreadPoolExecutor | None = None


def thread_count() -> int:
    """Threads used: numba's thread count (``NUMBA_NUM_THREADS``), else the CPUs available."""
    try:
        import numba

        return max(1, int(numba.config.NUMBA_NUM_THREADS))
    except Exception:  # noqa: BLE001 - numba missing or odd: fall back to the CPU count
        return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1))


def _pool() -> ThreadPoolExecutor:
    global _POOL
    if _POOL is None:
        _POOL = ThreadPoolExecutor(max_workers=max(1, thread_count() - 1), thread_name_prefix="ibr-bands")
    return _POOL


def run_bands(kernel, n: int, *args, min_rows: int = 16, pieces_per_thread: int = 1) -> None:
    """Run ``kernel(start, stop, *args)`` over ``[0, n)`` in pieces of at least ``min_rows``.

    ``kernel`` must release the GIL (``@njit(nogil=True)``, or a Python function whose work is
    in such kernels and OpenCV calls, which release it too) and write only its own rows. With
    ``pieces_per_thread`` > 1 the pieces are taken in turn by whichever thread is free (uneven
    pieces, e.g. bands of a rasterizer with more quads at the top, balance out); one task per
    extra thread is submitted either way, the calling thread works too. Exceptions of any piece
    are raised here.
    """
    threads = thread_count()
    pieces = max(1, min(threads * max(1, pieces_per_thread), n // max(1, min_rows)))
    if threads == 1 or pieces == 1:
        kernel(0, n, *args)
        return
    bounds = [n * i // pieces for i in range(pieces + 1)]
    order = itertools.count()  # next() is atomic under the GIL: each piece is taken once

    def work():
        for i in iter(lambda: next(order), None):
            if i >= pieces:
                return
            kernel(bounds[i], bounds[i + 1], *args)

    futures = [_pool().submit(work) for _ in range(min(threads, pieces) - 1)]
    try:
        work()
    finally:
        for f in futures:
            f.result()
