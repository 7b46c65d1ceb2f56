"""Marks of the first-run helper process: which groups of numba kernels it has cached (#13).

On a first run (an empty numba cache) the CLI starts ``python -m ibr.render.warmup KIND DIR``
(:func:`start_helper`), which compiles some kernels into numba's on-disk cache while the main
process compiles others, and touches ``DIR/<group>`` as each group lands. Code about to call a
group's first kernel calls :func:`await_kernels` first: on a first run it waits for the helper's
mark instead of compiling the same kernels a second time on the other core; on every other run
(no helper) it returns at once. Here in ``ibr.base`` so that every stage can await (the helper's
own code lives in :mod:`ibr.render.warmup`).
"""

from __future__ import annotations

import atexit
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .validate import check_choice

__all__ = ["GROUPS", "HELPER_OPT", "MAX_WAIT_S", "await_kernels", "mark", "start_helper"]

_STARTED: list = []  # (helper process, marker directory, groups it marks, owner pid) once started
#: The kernel groups each kind of helper marks (a group of the other kind is not waited for).
GROUPS = {"frame": ("raster", "fill"),
          "stitch": ("ray-setup", "plane-fit", "blend", "background-fill"),
          "stitch-ods": ("ray-setup", "plane-fit", "blend", "row-fill"),
          "mesh": ("segment", "plane-fit")}
_ALL_GROUPS = tuple(sorted({g for groups in GROUPS.values() for g in groups}))
_READY: set = set()  # groups this process no longer waits for
#: LLVM optimization level of the kernels the "frame" helper compiles (the rasterizer and the
#: fill; numba's default is 3). -O2 compiles them 0.2-0.45 s faster (the helper
#: alone: 4.0-4.2 -> 3.8 s, fresh caches), and their frames run as fast (paired runs, each from
#: its own cache: 512² and 1080p two-source frames, the motorcycle warp within noise). The results
#: are bit-identical (no fast-math in the rasterizer or the fill; the plane fit's re-associated
#: moments vectorize alike at -O2 and -O3: its planes on random data and a whole frame compared,
#: tests/test_warmup.py). The other helpers (the blend's fast-math kernels) keep numba's default;
#: a user's NUMBA_OPT wins.
HELPER_OPT = {"frame": "2"}
#: The longest wait for one group (s): the helper takes ~8 s in all; past this the main process
#: compiles the kernels itself (an overloaded machine, a helper stuck on its imports).
MAX_WAIT_S = 15.0


def mark(marks: Path | None, group: str) -> None:
    """In the helper: say that ``group``'s kernels are in the cache (``marks`` None: no one asked)."""
    if marks is not None:
        try:
            (marks / group).touch()
        except OSError:  # the main process has gone (and removed the directory): nobody waits
            pass


def await_kernels(group: str) -> None:
    """Wait until the first-run helper has cached kernel group ``group`` (:data:`GROUPS`), while it
    runs and at most :data:`MAX_WAIT_S`; at once when no helper was started
    (every run but a first one) or the group was awaited before."""
    if group not in _ALL_GROUPS:  # checked on every run, so that a misspelt group shows at once
        check_choice("group", group, _ALL_GROUPS)
    if not _STARTED or group in _READY:
        return
    proc, marks, groups, owner = _STARTED[0]
    if group not in groups or os.getpid() != owner:  # not this helper's, or a forked child
        return
    deadline = time.monotonic() + MAX_WAIT_S
    while not (marks / group).exists() and proc.poll() is None and time.monotonic() < deadline:
        time.sleep(0.005)
    _READY.add(group)


def start_helper(kind: str = "frame") -> None:
    """Start the helper process for ``kind`` (a key of :data:`GROUPS`: "frame" for the
    rasterizer and the fill (at -O2, :data:`HELPER_OPT`), "stitch" / "stitch-ods" for the ray rasterizer's setup,
    the plane fit, the blend's accumulation and the mono / ODS panorama's hole fill, "mesh" for
    the segmentation's plane tests and plane fit) once per process (quietly; killed at exit if
    still running)."""
    check_choice("kind", kind, tuple(GROUPS))
    if _STARTED or os.environ.get("NUMBA_DISABLE_JIT") or os.environ.get("IBR_NO_WARMUP"):
        return
    marks = Path(tempfile.mkdtemp(prefix="ibr-warmup-"))
    try:
        env = dict(os.environ)
        if kind in HELPER_OPT:
            env.setdefault("NUMBA_OPT", HELPER_OPT[kind])
        proc = subprocess.Popen([sys.executable, "-m", "ibr.render.warmup", kind, str(marks)], env=env,
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    except OSError:
        shutil.rmtree(marks, ignore_errors=True)
        return
    _STARTED.append((proc, marks, GROUPS.get(kind, ()), os.getpid()))
    atexit.register(_stop, proc, marks, os.getpid())


def _stop(proc, marks: Path, owner: int) -> None:
    if os.getpid() != owner:  # a forked child exiting: the helper and its marks are the parent's
        return
    if proc.poll() is None:
        proc.kill()
        proc.wait()
    shutil.rmtree(marks, ignore_errors=True)
