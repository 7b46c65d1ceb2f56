"""Helpers shared by the subcommands: progress output and user-facing messages."""

from __future__ import annotations

import functools
import sys
import time
from pathlib import Path
from typing import Iterable, Iterator, TypeVar

T = TypeVar("T")


def info(message: str) -> None:
    """Print a progress or result line to stderr (stdout stays clean for data)."""
    print(message, file=sys.stderr, flush=True)


def counted(n: int, noun: str) -> str:
    """``"1 frame"``, ``"3 frames"``: ``n`` and the noun, plural (with an s) unless ``n`` is 1."""
    return f"{n} {noun}{'' if n == 1 else 's'}"


def holes_summary(rendering) -> str:
    """``holes 0.124% (filled 0.124%, and 0.069% covered pixels beside them recoloured)`` for an
    :class:`ibr.Rendering`: the share of pixels no source covered, how many of them the fill
    wrote, and the covered pixels it recoloured beside them (``Rendering.filled``: a silhouette's
    mixed colour left where the foreground moved away, a stray sample torn from its neighbours),
    so that more filled than hole pixels does not read as a mistake; ``(not filled)`` with
    ``--fill none``."""
    holes, filled = rendering.holes, rendering.filled
    text = f"holes {holes.mean():.3%}"
    if not filled.any():
        return text + (" (not filled)" if holes.any() else "")
    rim = (filled & ~holes).mean()
    text += f" (filled {(filled & holes).mean():.3%}"
    return text + (f", and {rim:.3%} covered pixels beside them recoloured)" if rim else ")")


def invented(rendering) -> tuple[float, float]:
    """(holes, filled): the shares of an :class:`ibr.Rendering`'s pixels that no source covered,
    and of those the fill wrote (invented: a guess from the nearby background)."""
    holes, filled = rendering.holes, rendering.filled
    return float(holes.mean()), float((holes & filled).mean())


def invented_warning(command: str, shares, what: str = "the output", hint: str = "") -> str | None:
    """A warning line when more than half of a rendering is holes (no source pixel lands there: a
    target camera that sees little of the sources, e.g. a far wider one or one turned away), else
    None: ``"warp: WARNING: the output is 98.7% invented by the hole fill (...)"``, or ``is ...
    holes`` where no fill wrote them (``--fill none``: black).

    Parameters
    ----------
    command : str
        The line's prefix (``"warp"``, ``"interpolate"``).
    shares : sequence of (label, holes, filled)
        Per rendering, a label (``"frame 3 (t=0.500)"``) and :func:`invented`'s two shares; with
        several, the line counts those over half holes and names the worst.
    what : str
        What a single rendering is called in the line.
    hint : str
        What to check, ending the line (e.g. ``"is --to the camera you meant?"``).
    """
    shares = list(shares)
    over = [s for s in shares if s[1] > 0.5]
    if not over:
        return None
    label, holes, filled = max(over, key=lambda s: s[1])
    where = (f"{len(over)} of {len(shares)} frames {'is' if len(over) == 1 else 'are'} mostly guessed; {label} is"
             if len(shares) > 1 else f"{what} is")
    if filled > 0:
        return (f"{command}: WARNING: {where} {filled:.1%} invented by the hole fill (no source pixel lands "
                "there; the fill is a guess from the nearby background, not the scene)" + (f"; {hint}" if hint else ""))
    return (f"{command}: WARNING: {where} {holes:.1%} holes (no source pixel lands there; left black "
            "without a fill)" + (f"; {hint}" if hint else ""))


def check_source_depth(what: str, path, view, purpose: str = "so it cannot be a source") -> None:
    """Refuse a source view whose depth has no valid pixel (all NaN: zero, negative or infinite
    values are made NaN when a view file is read) as the library does (``ibr.warp`` /
    ``ibr.interpolate``: "view 'room_a': the depth has no valid pixel ..."), naming the option
    ``what`` and the file ``path`` the user gave rather than the view's ``name`` (which need not be
    the file's: a copy of room_a.json with another depth is still 'room_a'). A view without depth
    is left to the command's own check."""
    import numpy as np

    from ibr.base.view import no_valid_depth_message

    if view.depth is not None and not np.isfinite(view.depth).any():
        raise ValueError(no_valid_depth_message(f"{what}: {path}", f", {purpose}"))


def progress(items: Iterable[T], total: int, label: str) -> Iterator[T]:
    """Yield ``items`` while drawing a one-line progress bar on stderr.

    Draws on a terminal only; when stderr is not a TTY (CI, logs) it prints one line per item.
    """
    tty = sys.stderr.isatty()
    start = time.perf_counter()
    for i, item in enumerate(items, 1):
        yield item
        elapsed = time.perf_counter() - start
        if tty:
            width = 30
            filled = int(width * i / max(total, 1))
            bar = "#" * filled + "-" * (width - filled)
            eta = elapsed / i * (total - i)
            sys.stderr.write(f"\r{label} [{bar}] {i}/{total}  {elapsed:.1f}s elapsed, {eta:.1f}s left")
            if i == total:
                sys.stderr.write("\n")
            sys.stderr.flush()
        else:
            info(f"{label} {i}/{total} ({elapsed:.1f}s)")


# --------------------------------------------------------------------------- parse-time ranges
# argparse ``type=`` callables: a bad value is a usage error (exit 2) naming the option, before any
# file is read or written (#12).
def _number(text: str, kind):
    import argparse
    import math

    try:
        value = kind(text)
    except (TypeError, ValueError):
        raise argparse.ArgumentTypeError(f"expected {'an integer' if kind is int else 'a number'}, "
                                         f"got {text!r}") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
    return value


def number_in(lo=None, hi=None, *, integer: bool = False, lo_open: bool = False, hi_open: bool = False,
              what: str = ""):
    """An argparse type: a finite number (or integer) in [lo, hi] (``lo_open``/``hi_open``: that
    end excluded)."""
    import argparse

    def parse(text: str):
        value = _number(text, int if integer else float)
        if ((lo is not None and (value < lo or (lo_open and value == lo)))
                or (hi is not None and (value > hi or (hi_open and value == hi)))):
            lo_s = "" if lo is None else f"{'>' if lo_open else '>='} {lo:g}"
            hi_s = "" if hi is None else f"{'<' if hi_open else '<='} {hi:g}"
            rng = " and ".join(x for x in (lo_s, hi_s) if x)
            raise argparse.ArgumentTypeError(f"expected {what or ('an integer' if integer else 'a number')} "
                                             f"{rng}, got {text}")
        return value

    parse.__name__ = "integer" if integer else "number"
    return parse


def _max_side():
    from ibr.base.validate import MAX_IMAGE_SIDE

    return MAX_IMAGE_SIDE


finite_float = number_in()
positive_float = number_in(0, lo_open=True, what="a positive number")
nonnegative_float = number_in(0, what="a number")
positive_int = number_in(1, integer=True, what="an integer")
nonnegative_int = number_in(0, integer=True, what="an integer")
#: An image side in pixels: 1 .. MAX_IMAGE_SIDE (the pixel and byte ceilings are checked later,
#: when the other side and the channels are known).
image_side = number_in(1, _max_side(), integer=True, what="a size in pixels")
#: A TCP port: 1..65535, or 0 for any free port.
port_number = number_in(0, 65535, integer=True, what="a port (0 = any free one)")
#: Frame rates for videos and animations.
frame_rate = number_in(0, 1000, lo_open=True, what="a frame rate")
#: Frame counts (every frame is kept in memory for videos and contact sheets).
frame_count = number_in(1, 100000, integer=True, what="a number of frames")


class terminate_as_interrupt:
    """Context manager: while active (main thread only), SIGTERM raises KeyboardInterrupt, so the
    ``finally`` blocks that clean up temporary folders run for ``kill`` as they do for Ctrl-C."""

    def __enter__(self):
        import signal
        import threading

        self._old = None
        if threading.current_thread() is threading.main_thread():
            def _raise(signum, frame):
                raise KeyboardInterrupt(f"terminated (signal {signum})")

            self._old = signal.signal(signal.SIGTERM, _raise)
        return self

    def __exit__(self, *exc):
        import signal

        if self._old is not None:
            signal.signal(signal.SIGTERM, self._old)
        return False


def image_for(path, img, what: str = "-o"):
    """``img`` in a dtype the file format of ``path`` stores, so that any colour can be written to
    any advertised extension: float [0, 1] becomes uint8 for .png / .jpg (clipped, rounded; an
    HDR colour's highlights clip), uint16 becomes uint8 for .jpg (which also drops an alpha
    channel), uint8 / uint16 become float32 [0, 1] for .exr / .pfm (float64: float32 there and for
    .tif); anything else is returned as is. A one-channel float depth or range map (median
    above 1, or values below 0: :func:`ibr.io.images.check_unit_colour`) is refused for .png /
    .jpg, naming ``what``: clipped it would be all white."""
    import numpy as np

    ext = Path(path).suffix.lower()
    a = np.asarray(img)
    if ext in (".jpg", ".jpeg") and a.ndim == 3 and a.shape[2] in (2, 4):  # JPEG holds no alpha
        a = a[..., : a.shape[2] - 1]
    if ext in (".png", ".jpg", ".jpeg") and a.dtype.kind == "f":
        from ibr.io.images import check_unit_colour

        check_unit_colour(what, a, Path(path).name)
        return np.clip(np.rint(np.nan_to_num(a) * 255.0), 0, 255).astype(np.uint8)
    if ext in (".jpg", ".jpeg") and a.dtype == np.uint16:
        return ((a.astype(np.uint32) + 128) // 257).astype(np.uint8)
    if ext in (".exr", ".pfm", ".tif", ".tiff") and a.dtype == np.float64:
        return a.astype(np.float32)
    if ext in (".exr", ".pfm") and a.dtype.kind == "u":
        return a.astype(np.float32) / np.float32(np.iinfo(a.dtype).max)
    return a


def read_panorama_arg(path, layout, option: str):
    """panorama.files.read_panorama, its layout hint naming the command's ``option`` (was the
    library's ``layout=``)."""
    from panorama.files import read_panorama

    try:
        return read_panorama(path, layout=layout)
    except ValueError as exc:
        raise ValueError(str(exc).replace("pass layout=", f"pass {option}")) from None


def face_file_patterns(ext: str | None = None) -> tuple[str, ...]:
    """The file names of a folder of cube faces (px.png .. nz.exr, every image extension, and
    ``ext`` as the user spelt it, e.g. .PNG), for an output plan's frame folder: exactly these,
    not a user's px.txt or pz.backup.png."""
    from ibr.io.outputs import IMAGE_EXTS
    from panorama.directions import FACE_FILE_NAMES

    exts = IMAGE_EXTS + ((ext,) if ext and ext not in IMAGE_EXTS else ())
    # '[pP][nN][gG]': an earlier run's px.PNG is replaced by px.png too
    anycase = tuple("." + "".join(f"[{c.lower()}{c.upper()}]" if c.isalpha() else c for c in e[1:]) for e in exts)
    return tuple(dict.fromkeys(f"{n}{e}" for n in FACE_FILE_NAMES for e in anycase))


def note_first_run(*modules: str, warm: str = "frame", announce: bool = True) -> bool:
    """Whether numba has kernels of ``modules`` (kernel modules, e.g.
    ``"ibr.render._raster_kernels"``) to compile: a module without a cache index numba would
    load (:func:`_stale_kernels`: none, or only ones for an older source, an update); then start
    compiling the kernels ``warm`` names ("frame": the rasterizer and the hole fill's pull-push;
    "stitch" / "stitch-ods": the ray rasterizer's setup, the plane fit, the blend's accumulation
    and the panorama's hole fill; "mesh": the segmentation's plane tests and plane fit) in a
    second process (:mod:`ibr.render.warmup`) and, with ``announce``, say so (once). The answer
    is kept for the rest of the command (:func:`forget_first_run` at the start of the next): the
    CLI asks first, quietly, before the command's imports and input checks (:func:`cli.main`);
    the command asks again after its checks, and only then is the line printed."""
    key = (modules, warm)
    if key not in _FIRST_RUN_NOTED:
        _FIRST_RUN_NOTED[key] = _note_first_run(modules, warm)
    if _FIRST_RUN_NOTED[key] and announce and key not in _FIRST_RUN_SAID:
        _FIRST_RUN_SAID.add(key)
        info("compiling the numba kernels (a first run, or new sources: 5-15 s on two cores, once; "
             "later runs load them from the cache)")
    return _FIRST_RUN_NOTED[key]


_FIRST_RUN_NOTED: dict = {}  # (modules, warm) -> note_first_run's answer for this command
_FIRST_RUN_SAID: set = set()  # the keys whose line was printed


def forget_first_run() -> None:
    """Start a new command: the next :func:`note_first_run` looks at the cache again."""
    _FIRST_RUN_NOTED.clear()
    _FIRST_RUN_SAID.clear()


def _note_first_run(modules, warm: str) -> bool:
    import os

    if os.environ.get("NUMBA_DISABLE_JIT"):
        return False  # no compilation: nothing to say
    if not any(_stale_kernels(name) for name in modules):
        return False
    from ibr.base.first_run import start_helper

    start_helper(warm)
    return True


def _stale_kernels(name: str) -> bool:
    """Whether kernel module ``name`` has no numba cache index that numba would load: none written
    by this numba for the source as it is now, in the folder numba caches it in
    (:func:`_numba_cache_dir`). numba 0.68 stamps an index with the SHA-256 of the source's bytes
    (a source touched but unchanged, e.g. by a git checkout, stays cached), earlier versions with
    the source's (mtime, size); both are recognized. False when that cannot be told (a module in
    a zip file)."""
    import hashlib
    import importlib.util

    spec = importlib.util.find_spec(name)
    if spec is None or spec.origin is None:
        return False
    path = Path(spec.origin)
    try:
        st = path.stat()
        fresh = (hashlib.sha256(path.read_bytes()).digest(), (st.st_mtime, st.st_size))
        cache = _numba_cache_dir(path)
        indexes = list(cache.glob(f"{path.stem}.*.nbi")) if cache is not None and cache.is_dir() else []
    except OSError:
        return False
    return not any(_index_stamp(p) in fresh for p in indexes)


def _index_stamp(index: Path):
    """The source stamp of numba cache index ``index`` (numba.core.caching.IndexDataCacheFile: the
    numba version, pickled, then the pickled (stamp, overloads)); None when it was written by
    another numba version or cannot be read. The overloads are read without importing the
    classes they name (numba's types: importing numba here cost every run 0.15 s before the
    first-run helper could start)."""
    import pickle

    class Unresolved(pickle.Unpickler):
        def find_class(self, module, name):
            return _Placeholder

    try:
        with open(index, "rb") as f:
            if pickle.load(f) != _numba_version():
                return None
            stamp, _ = Unresolved(f).load()
    except Exception:  # noqa: BLE001 - a truncated or foreign file: not an index numba would load
        return None
    return stamp


class _Placeholder:
    """Stands for any class an index names (built, never used)."""

    def __init__(self, *args, **kwargs):
        pass

    def __setstate__(self, state):
        pass


@functools.lru_cache(maxsize=None)
def _numba_version() -> str:
    """numba's version from its installed metadata (read once: each lookup scans the
    distributions, ~10 ms), without importing numba."""
    import importlib.metadata

    return importlib.metadata.version("numba")


def _numba_cache_dir(path: Path) -> Path | None:
    """The folder numba's cache locators choose for the kernels of source file ``path``, in their
    order: ``NUMBA_CACHE_DIR/<folder>_<sha1 of the folder>``, else ``__pycache__`` beside it when
    that is writable, else numba's user-wide cache folder (``~/.cache/numba/<folder>_<sha1>`` on
    Linux)."""
    import hashlib
    import os

    folder = os.path.dirname(os.path.abspath(str(path)))
    sub = f"{os.path.basename(folder)}_{hashlib.sha1(folder.encode()).hexdigest()}"
    cache_dir = os.environ.get("NUMBA_CACHE_DIR")
    if cache_dir:
        return Path(cache_dir) / sub
    in_tree = Path(folder) / "__pycache__"
    if (in_tree.is_dir() and os.access(in_tree, os.W_OK)) or (not in_tree.exists() and os.access(folder, os.W_OK)):
        return in_tree
    from numba.misc.appdirs import AppDirs  # numba's own choice of the user-wide folder

    return Path(AppDirs(appname="numba", appauthor=False).user_cache_dir) / sub
