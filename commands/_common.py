"""Helpers shared by the subcommands: progress output and user-facing messages."""

from __future__ import annotations

import sys
import time
from typing import Iterable, Iterator, TypeVar

T = TypeVar("T")


def info(message: str) -> None:
    """Print a progress or result line to stderr (stdout stays clean for data)."""
    print(message, file=sys.stderr, flush=True)


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
