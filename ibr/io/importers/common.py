"""What every importer shares: a frame record, strict-but-tolerant key checks, the import report,
and writing view files (and a sequence manifest) into the output folder."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

from ...base.camera import Camera
from ...base.view import View
from ..images import read_depth, read_image
from ..view_files import save_view

__all__ = ["Frame", "ImportReport", "check_foreign_keys", "write_views"]

#: The sequence manifest format of ``ibr.sequence`` (``docs/sequences.md``), written here for
#: imports of many frames (``ibr.io`` may not import ``ibr.sequence``).
SEQUENCE_FORMAT = "ibr-sequence"


@dataclass
class Frame:
    """One imported frame: where its images are and its camera (our conventions)."""

    name: str
    color: Path
    camera: Camera
    depth: Path | None = None
    depth_scale: float | None = None  # scene units per stored unit (integer files need it)
    depth_channel: str | None = None
    undistort: Callable[[np.ndarray], np.ndarray] | None = None  # applied to colour and depth
    depth_reader: Callable[[Path], np.ndarray] | None = None  # a tool's own depth format (COLMAP .bin)


@dataclass
class ImportReport:
    """What an import did: frames written, frames dropped and why, keys ignored."""

    written: list[Path] = field(default_factory=list)
    dropped: list[tuple[str, str]] = field(default_factory=list)
    ignored_keys: list[str] = field(default_factory=list)
    sequence: Path | None = None
    listed: int | None = None  # how many entries the source listed (default: written + dropped)
    unit: str = "frames"       # what the source lists ("images" for COLMAP)

    def lines(self) -> list[str]:
        out = [f"{len(self.written)} view file(s) written"
               + (f", sequence {self.sequence.name}" if self.sequence else "")]
        if self.dropped:  # how many of how many, and why each
            total = self.listed if self.listed is not None else len(self.written) + len(self.dropped)
            head = f"{len(self.dropped)} of {total} {self.unit} skipped"
            if len(self.dropped) == 1:
                out.append(f"{head}: {self.dropped[0][0]}: {self.dropped[0][1]}")
            else:
                out += [f"{head}:"] + [f"  {name}: {why}" for name, why in self.dropped]
        if self.ignored_keys:
            out.append("ignored keys (not used by ibr): " + ", ".join(sorted(set(self.ignored_keys))))
        return out


#: How alike (difflib ratio) an unknown key must be to one we read to count as its misspelling.
#: 0.85 refuses "transfrom_matrix", "fil_path", "cam_angle_x" and keeps other tools' own keys
#: such as nerfstudio's "ply_file_path", "mask_path", "depth_unit_scale" or "camera_id".
NEAR_MISS = 0.85


def _one_edit(a: str, b: str) -> bool:
    """``a`` is ``b`` with one character added (``cxx``, ``fl_yy`` for ``cx``, ``fl_y``); a changed
    character is not (other tools' ``fx`` would read as ``cx``), nor a shorter ``a``."""
    return len(a) == len(b) + 1 and any(a[:i] + a[i + 1:] == b for i in range(len(a)))


def check_foreign_keys(where: str, doc: dict, used: Iterable[str], report: ImportReport | None) -> None:
    """Other tools' files carry keys we do not need (ignored, and listed in the report); a key
    that is a near miss of one we read (:data:`NEAR_MISS`) is a misspelling and refused."""
    import difflib

    used = tuple(used)
    for key in doc:
        if key in used:
            continue
        ratio, near = max((difflib.SequenceMatcher(None, str(key), u).ratio(), u) for u in used if len(u) >= 5)
        if ratio < NEAR_MISS:  # short keys (fl_y, cx): one letter added or changed is a misspelling
            near = next((u for u in used if 2 <= len(u) < 5 and _one_edit(str(key), u)), None)
        if near is not None:
            raise ValueError(f"{where}: unknown key {key!r} (did you mean {near!r}?)")
        if report is not None:
            report.ignored_keys.append(key)


def _load_frame(f: Frame) -> View:
    color = read_image(f.color, what=f"{f.name}: colour")
    depth = None
    if f.depth is not None:
        if f.depth_reader is not None:
            depth = f.depth_reader(f.depth) * np.float32(1.0 if f.depth_scale is None else f.depth_scale)
        else:
            depth = read_depth(f.depth, scale=f.depth_scale, channel=f.depth_channel, what=f"{f.name}: depth")
        if depth.shape != color.shape[:2]:
            raise ValueError(f"{f.name}: depth {f.depth.name} is {depth.shape[1]}x{depth.shape[0]} but colour "
                             f"{f.color.name} is {color.shape[1]}x{color.shape[0]}")
    if color.shape[:2] != f.camera.shape:
        raise ValueError(f"{f.name}: colour {f.color.name} is {color.shape[1]}x{color.shape[0]} but its camera is "
                         f"{f.camera.width}x{f.camera.height}")
    if f.undistort is not None:
        color = f.undistort(color)
        depth = None if depth is None else f.undistort(depth)
    return View(color, depth, f.camera, f.name)


def is_sequence_manifest(path) -> bool:
    """Whether ``path`` is an ``ibr-sequence`` manifest (as an earlier import wrote it)."""
    from ..view_files import json_format

    return json_format(path) == SEQUENCE_FORMAT


def check_sequence_name(name, frame_names) -> None:
    """``name`` of an import's sequence manifest (``<name>.json`` in the output folder): a plain
    file name (``../../transforms`` wrote over the input), and no frame's name (``r_0`` replaced
    that frame's view file). ``None`` writes no manifest."""
    if name is None:
        return
    if (not isinstance(name, str) or not name or name in (".", "..") or "/" in name or "\\" in name
            or Path(name).name != name):
        raise ValueError(f"--name: expected a plain file name for the sequence manifest, got {name!r}")
    if name in frame_names:
        raise ValueError(f"--name: {name!r}.json would replace the view file of the frame {name!r}; choose another name")


def write_views(frames: list[Frame], folder: Path, report: ImportReport, *, sequence_name: str | None = None,
                progress=None) -> ImportReport:
    """Load every frame and write ``<name>.json`` (+ PNG colour, EXR depth) into ``folder``; with
    more than one frame and ``sequence_name``, also ``<sequence_name>.json``, a sequence manifest
    in the frames' order. With one frame, an earlier import's manifest of that name in ``folder``
    is removed (it listed the earlier frames: a stale sequence beside the new view)."""
    folder = Path(folder)
    names = [f.name for f in frames]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})[0]
        raise ValueError(f"frames: two frames would be written as {dup!r}.json")
    if len(frames) > 1:
        check_sequence_name(sequence_name, names)
    folder.mkdir(parents=True, exist_ok=True)
    for k, f in enumerate(frames):
        view = _load_frame(f)
        path = folder / f"{f.name}.json"
        save_view(view, path)
        report.written.append(path)
        if progress is not None:
            progress(k + 1, len(frames))
    if sequence_name and len(frames) > 1:
        seq = folder / f"{sequence_name}.json"
        doc = {"format": SEQUENCE_FORMAT, "version": 1, "name": sequence_name,
               "views": [p.name for p in report.written]}
        seq.write_text(json.dumps(doc, indent=2) + "\n")
        report.sequence = seq
    elif sequence_name and is_sequence_manifest(folder / f"{sequence_name}.json") \
            and f"{sequence_name}.json" not in {p.name for p in report.written}:
        (folder / f"{sequence_name}.json").unlink()
    return report
