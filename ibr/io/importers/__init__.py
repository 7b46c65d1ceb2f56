"""Importers: other tools' RGB-D data -> ibr view files (and back out to NeRF's transforms.json).

In: a NeRF-style ``transforms.json`` (:mod:`.nerf`), a COLMAP text model (:mod:`.colmap`), a TUM
RGB-D sequence folder (:mod:`.tum`); Blender renders come out as view files directly from the
script users run inside Blender (:mod:`.blender_script`, ``ibr import blender --script``).
Out: ``<name>.json`` view files (PNG colour, float EXR planar z) in a folder, plus a sequence
manifest when there are several frames; :func:`export_nerf` writes ``transforms.json``.
Conventions, once: :mod:`.conventions` (``docs/import.md`` has a worked number per format).
"""

from __future__ import annotations

from pathlib import Path

from .common import Frame, ImportReport, write_views
from .nerf import write_transforms as export_nerf

__all__ = ["FORMATS", "Frame", "ImportReport", "blender_script_path", "export_nerf", "import_views", "read_frames"]

#: Formats ``import_views`` reads, and what SRC is for each.
FORMATS = {"nerf": "a transforms.json file", "colmap": "a COLMAP text model folder (cameras.txt, images.txt)",
           "tum": "a TUM RGB-D sequence folder (rgb.txt, depth.txt, groundtruth.txt)"}


def blender_script_path() -> Path:
    """The script to run inside Blender (``blender -b scene.blend --python PATH -- --out DIR``)."""
    return Path(__file__).with_name("blender_script.py")


def read_frames(fmt: str, src, *, images=None, depth=None, depth_scale: float | None = None,
                intrinsics=None, tolerance: float = 0.02, report: ImportReport | None = None,
                labels: dict | None = None) -> list[Frame]:
    """Frames of ``src`` in format ``fmt`` (one of :data:`FORMATS`), nothing written.

    ``images``: COLMAP's image folder (default: ``src/../images`` or ``src/../../images``, the
    first that exists: ``project/sparse`` or ``project/sparse/0`` beside ``project/images``);
    ``depth``: COLMAP depth folder (an image without a depth map there is skipped and reported);
    ``depth_scale``: scene units per stored depth unit (every format; for nerf it replaces the
    file's own factor, for tum the benchmark's 1/5000 m); ``intrinsics``: TUM ``(fx, fy, cx,
    cy)``; ``tolerance``: TUM time association in seconds; ``labels``: how messages name
    ``images`` / ``depth`` (``ibr import`` passes its options, ``--images`` / ``--depth``).
    """
    src = Path(src)
    if depth_scale is not None:
        from ...base.validate import check_positive

        depth_scale = check_positive("depth_scale", depth_scale)
    if fmt == "nerf":
        from .nerf import read_transforms

        return read_transforms(src, report, depth_scale=depth_scale)
    if fmt == "colmap":
        from .colmap import read_colmap

        return read_colmap(src, images, depth_dir=depth, depth_scale=depth_scale, report=report, labels=labels)
    if fmt == "tum":
        from .tum import TUM_INTRINSICS, read_tum

        return read_tum(src, intrinsics=intrinsics or TUM_INTRINSICS, tolerance=tolerance, report=report,
                        depth_scale=depth_scale)
    raise ValueError(f"format: expected one of {', '.join(FORMATS)}, got {fmt!r}")


def import_views(fmt: str, src, out, *, sequence_name: str | None = None, progress=None, **options) -> ImportReport:
    """Read ``src`` (format ``fmt``) and write view files into the folder ``out``, and a sequence
    manifest ``<sequence_name or fmt>.json`` when there are several frames; return the report.

    The whole source (every frame's entry, file names, cameras) is checked before the first file is
    written; a frame whose images then fail to load raises, naming the file, after the frames before
    it were written (``ibr import`` stages its output, so the command leaves nothing behind).
    """
    if fmt not in FORMATS:
        from ...base.validate import nearest_name

        near = nearest_name(fmt, FORMATS)
        raise ValueError(f"format: unknown {fmt!r}{f' (did you mean {near!r}?)' if near else ''}; "
                         f"expected one of {', '.join(FORMATS)}")
    report = ImportReport()
    frames = read_frames(fmt, src, report=report, **options)
    return write_views(frames, Path(out), report, sequence_name=sequence_name or fmt, progress=progress)
