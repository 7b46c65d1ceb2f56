"""Sequence files: RGB-D frames in time order, as a JSON manifest or a folder of numbered views.

Two ways to name a sequence with one path:

* a **manifest**, a JSON document::

      {"format": "ibr-sequence", "version": 1, "name": "room_walk", "fps": 10,
       "views": ["room_key_0000.json", "room_key_0001.json", ...],
       "ground_truth": {"sequence": "room_truth.json", "factor": 4}}

  ``views`` are view files (``docs/files.md``) in time order, relative to the manifest;
  ``fps`` (optional) is the frame rate of the views; ``ground_truth`` (optional) names another
  sequence holding the exact frames of an up-conversion by ``factor`` (written by
  ``ibr samples --sequence``), which ``ibr interpolate`` scores against;
* a **folder** of view files named ``<prefix>_<NNNN>.json`` (any number of digits), taken in the
  order of the number. All numbered views of the folder must share one prefix.

:func:`load_sequence` reads either into a :class:`Sequence` (paths only; nothing is decoded),
:func:`iter_views` loads the views one at a time, :func:`save_sequence` writes views and a
manifest, :func:`referenced_files` lists every file a view, manifest or folder depends on (for
checksums of batch inputs).
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Iterator

from ..base.validate import check_keys
from ..base.view import View
from ..io.images import atomic_path
from ..io.view_files import VIEW_FORMAT, load_view, save_view

__all__ = [
    "SEQUENCE_FORMAT",
    "SEQUENCE_VERSION",
    "Sequence",
    "is_sequence",
    "iter_views",
    "load_sequence",
    "referenced_files",
    "save_sequence",
]

SEQUENCE_FORMAT = "ibr-sequence"
SEQUENCE_VERSION = 1

#: Keys of a manifest and of its ``ground_truth`` object (any other key is refused, never ignored).
MANIFEST_KEYS = ("format", "version", "name", "fps", "views", "ground_truth")
GROUND_TRUTH_KEYS = ("sequence", "factor")

_NUMBERED = re.compile(r"^(?P<prefix>.+)_(?P<number>\d+)\.json$")


@dataclass(frozen=True)
class Sequence:
    """View files in time order.

    Attributes
    ----------
    views : tuple of Path
        View files (JSON), first frame first.
    source : Path
        The manifest or folder the sequence was read from.
    name : str
        Manifest ``name``, or the folder's common prefix.
    fps : float or None
        Frame rate of the views, when the manifest gives one.
    truth : Path or None
        Ground-truth sequence of an up-conversion (manifest ``ground_truth.sequence``).
    truth_factor : int or None
        Its up-conversion factor.
    """

    views: tuple
    source: Path
    name: str = "sequence"
    fps: float | None = None
    truth: Path | None = None
    truth_factor: int | None = None

    def __len__(self) -> int:
        return len(self.views)


def _read_json(path: Path):
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return None


def is_sequence(path) -> bool:
    """True when ``path`` is a folder or a JSON file whose ``format`` is ``"ibr-sequence"``."""
    p = Path(path)
    if p.is_dir():
        return True
    if p.suffix.lower() != ".json" or not p.is_file():
        return False
    doc = _read_json(p)
    return isinstance(doc, dict) and doc.get("format") == SEQUENCE_FORMAT


def _numbered_views(folder: Path) -> tuple[list[Path], str]:
    found: dict[str, list[tuple[int, Path]]] = {}
    for p in folder.iterdir():
        m = _NUMBERED.match(p.name)
        if m and p.is_file():
            found.setdefault(m["prefix"], []).append((int(m["number"]), p))
    if not found:
        raise ValueError(f"sequence folder {folder}: no view files named <prefix>_<NNNN>.json")
    if len(found) > 1:
        raise ValueError(f"sequence folder {folder}: numbered views of several prefixes "
                         f"({', '.join(sorted(found))}); give a manifest that lists the views instead")
    prefix, items = next(iter(found.items()))
    items.sort()
    numbers = [n for n, _ in items]
    if len(set(numbers)) != len(numbers):
        raise ValueError(f"sequence folder {folder}: two views with the same number (e.g. _01 and _001)")
    return [p for _, p in items], prefix


def _is_frame_rate(fps) -> bool:
    """A positive finite number of frames per second (not a bool)."""
    return not isinstance(fps, bool) and isinstance(fps, (int, float)) and 0 < fps < math.inf


def load_sequence(path) -> Sequence:
    """Read a sequence manifest or a folder of numbered view files (see the module docstring).

    Only the paths are read; the view files are validated when loaded (:func:`iter_views`).

    Raises
    ------
    FileNotFoundError
        ``path`` or a listed view file does not exist.
    ValueError
        Not a sequence manifest, bad schema, fewer than one view, a folder without (or with
        ambiguous) numbered views.
    """
    p = Path(path)
    if p.is_dir():
        views, prefix = _numbered_views(p)
        return Sequence(tuple(views), p, prefix)
    if not p.is_file():
        raise FileNotFoundError(f"sequence: {p} does not exist (expected a sequence manifest or a folder of views)")
    doc = _read_json(p)
    where = f"sequence file {p}"
    if not isinstance(doc, dict) or doc.get("format") != SEQUENCE_FORMAT:
        got = doc.get("format") if isinstance(doc, dict) else type(doc).__name__
        raise ValueError(f"{where}: expected a JSON object with 'format': {SEQUENCE_FORMAT!r}, got {got!r}")
    if doc.get("version") != SEQUENCE_VERSION:
        raise ValueError(f"{where}: unsupported 'version' {doc.get('version')!r} (this reader knows {SEQUENCE_VERSION})")
    check_keys(where, doc, MANIFEST_KEYS)  # a misspelt 'fps' or 'ground_truth' is refused, never ignored
    names = doc.get("views")
    if not isinstance(names, list) or not names or not all(isinstance(n, str) and n for n in names):
        raise ValueError(f"{where}: 'views' must be a non-empty list of view file names, got {names!r}")
    views = tuple(p.parent / n for n in names)
    for i, v in enumerate(views):
        if not v.is_file():
            raise FileNotFoundError(f"{where}: 'views[{i}]' refers to a missing file {v}")
    fps = doc.get("fps")
    if fps is not None and not _is_frame_rate(fps):
        raise ValueError(f"{where}: 'fps' must be a positive finite number, got {fps!r}")
    truth = factor = None
    gt = doc.get("ground_truth")
    if gt is not None:
        if not isinstance(gt, dict) or not isinstance(gt.get("sequence"), str):
            raise ValueError(f"{where}: 'ground_truth' must be an object with a 'sequence' file name, got {gt!r}")
        check_keys(f"{where}: 'ground_truth'", gt, GROUND_TRUTH_KEYS)
        factor = gt.get("factor")
        if isinstance(factor, bool) or not isinstance(factor, int) or factor < 1:
            raise ValueError(f"{where}: 'ground_truth.factor' must be an integer >= 1, got {factor!r}")
        truth = p.parent / gt["sequence"]
    name = doc.get("name", p.stem)
    return Sequence(views, p, str(name), None if fps is None else float(fps), truth, factor)


def iter_views(sequence: "Sequence | str | Path") -> Iterator[View]:
    """Load the views of a sequence one at a time (first frame first)."""
    seq = sequence if isinstance(sequence, Sequence) else load_sequence(sequence)
    for p in seq.views:
        yield load_view(p)


def _manifest_text(doc: dict) -> str:
    return json.dumps(doc, indent=2, allow_nan=False) + "\n"


def save_sequence(views: Iterable[View], manifest, *, name: str | None = None, fps: float | None = None,
                  ground_truth: dict | None = None) -> Path:
    """Write views as ``<stem>_<NNNN>.json`` view files beside ``manifest`` and the manifest last.

    Parameters
    ----------
    views : iterable of View
        Frames in time order (written one at a time, so a generator keeps memory flat).
    manifest : str or Path
        The ``.json`` manifest to write; its folder must exist. View ``i`` is written as
        ``<manifest stem>_<i:04d>.json`` with its color and depth files (more digits for more
        than 10000 views in a list, so that the names sort in order; :func:`ibr.io.outputs.number_width`).
    name, fps, ground_truth
        Manifest fields (module docstring); ``ground_truth`` as ``{"sequence": ..., "factor": F}``.

    Returns
    -------
    Path of the manifest. Every file is written atomically; the manifest, written last, only
    exists once every view it lists does.
    """
    manifest = Path(manifest)
    if manifest.suffix.lower() != ".json":
        raise ValueError(f"manifest: a sequence manifest must end in .json, got {manifest}")
    if not manifest.parent.is_dir():
        raise FileNotFoundError(f"manifest: output folder {manifest.parent} does not exist")
    # checked before any view is written (a NaN fps failed in json.dumps after every view file)
    if fps is not None and not _is_frame_rate(fps):
        raise ValueError(f"fps: expected a positive finite frame rate, got {fps!r}")
    if name is not None and not isinstance(name, str):
        raise TypeError(f"name: expected a string, got {type(name).__name__}")
    if ground_truth is not None:
        check_keys("ground_truth", ground_truth, GROUND_TRUTH_KEYS, required=GROUND_TRUTH_KEYS)
        gf = ground_truth["factor"]
        if not isinstance(ground_truth["sequence"], str) or isinstance(gf, bool) or not isinstance(gf, int) or gf < 1:
            raise ValueError(f"ground_truth: expected {{'sequence': file name, 'factor': integer >= 1}}, "
                             f"got {ground_truth!r}")
    from ibr.io.outputs import number_width

    names = []
    digits = number_width(len(views)) if hasattr(views, "__len__") else 4  # (a generator: 4)
    for i, view in enumerate(views):
        path = manifest.parent / f"{manifest.stem}_{i:0{digits}d}.json"
        save_view(view, path)
        names.append(path.name)
    if not names:
        raise ValueError("views: expected at least one view, got none")
    doc = {"format": SEQUENCE_FORMAT, "version": SEQUENCE_VERSION, "name": name or manifest.stem}
    if fps is not None:
        doc["fps"] = float(fps)
    doc["views"] = names
    if ground_truth is not None:
        doc["ground_truth"] = dict(ground_truth)
    with atomic_path(manifest) as tmp:
        tmp.write_text(_manifest_text(doc), encoding="utf-8")
    return manifest


def referenced_files(path) -> list[Path]:
    """Every file ``path`` stands for: itself, and what a view file, sequence manifest or folder names.

    A view file adds its color and depth files; a sequence manifest adds its views (and theirs)
    and its ground-truth sequence; a folder adds every file in it (recursively). Missing
    references are skipped (the loader reports them). Paths come back sorted and unique.
    """
    out: set[Path] = set()

    def visit(p: Path, depth: int) -> None:
        if p in out or depth > 4:
            return
        if p.is_dir():
            for child in sorted(p.rglob("*")):
                if child.is_file() and not any(part.startswith(".") for part in child.relative_to(p).parts):
                    out.add(child)
            return
        if not p.is_file():
            return
        out.add(p)
        if p.suffix.lower() != ".json":
            return
        doc = _read_json(p)
        if not isinstance(doc, dict):
            return
        if doc.get("format") == VIEW_FORMAT:
            refs = [doc.get("color")]
            if isinstance(doc.get("depth"), dict):
                refs.append(doc["depth"].get("path"))
            for r in refs:
                if isinstance(r, str) and r:
                    visit(p.parent / r, depth + 1)
        elif doc.get("format") == SEQUENCE_FORMAT:
            for r in doc.get("views") or []:
                if isinstance(r, str) and r:
                    visit(p.parent / r, depth + 1)
            gt = doc.get("ground_truth")
            if isinstance(gt, dict) and isinstance(gt.get("sequence"), str):
                visit(p.parent / gt["sequence"], depth + 1)

    visit(Path(path), 0)
    return sorted(out)
