"""NeRF-style ``transforms.json`` (Blender synthetic / instant-ngp / nerfstudio) <-> view files.

Reads ``camera_angle_x`` (and ``camera_angle_y``) or ``fl_x``/``fl_y``/``cx``/``cy``, the size
``w``/``h`` (or the first image's), per-frame ``transform_matrix`` (camera-to-world, OpenGL camera
axes: :func:`~ibr.io.importers.conventions.ours_from_gl`) and ``file_path`` (relative to the
file; without extension as in the Blender synthetic scenes, then ``.png``); per-frame intrinsics
override the top-level ones. Depth: per-frame ``depth_file_path`` (nerfstudio) or ``depth_path``,
planar z in scene units times ``depth_unit_scale_factor`` (nerfstudio, e.g. 0.001 for millimetre
PNGs) or ``integer_depth_scale`` (instant-ngp: scene units per integer code).

Principal point: these files measure ``cx`` in continuous pixels (centre of the top-left pixel at
0.5), ours at integers: ``cx_ours = cx - 0.5``; without ``cx`` the image centre ``w / 2``.
Distortion (``k1``, ``k2``, ``p1``, ``p2``, ...) must be zero: undistort first (or import COLMAP).
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path

import numpy as np

from ...base.camera import Camera
from ..images import atomic_path, read_image
from ..view_files import load_view, named_files, read_json
from .common import SEQUENCE_FORMAT, Frame, ImportReport, check_foreign_keys
from .conventions import gl_from_ours, ours_from_gl

__all__ = ["read_transforms", "write_transforms"]

_INTRINSIC_KEYS = ("camera_angle_x", "camera_angle_y", "fl_x", "fl_y", "cx", "cy", "w", "h")
_DISTORTION_KEYS = ("k1", "k2", "k3", "k4", "p1", "p2")
_TOP_KEYS = _INTRINSIC_KEYS + _DISTORTION_KEYS + ("frames", "camera_model", "depth_unit_scale_factor",
                                                    "integer_depth_scale")
_FRAME_KEYS = _INTRINSIC_KEYS + _DISTORTION_KEYS + ("file_path", "transform_matrix", "depth_file_path", "depth_path")


def _number(where: str, doc: dict, key: str, *, positive: bool = True) -> float:
    v = doc[key]
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or (positive and v <= 0):
        raise ValueError(f"{where}: {key!r} must be a {'positive ' if positive else ''}finite number, got {v!r}")
    return float(v)


def _camera(where: str, top: dict, frame: dict, size: tuple[int, int] | None, pose) -> Camera:
    # a frame's own focal length, given either way, replaces the top level's for that axis
    shadowed = {k for axis in (("fl_x", "camera_angle_x"), ("fl_y", "camera_angle_y"))
                if any(a in frame for a in axis) for k in axis}
    d = {**{k: top[k] for k in _INTRINSIC_KEYS + _DISTORTION_KEYS if k in top and k not in shadowed},
         **{k: frame[k] for k in _INTRINSIC_KEYS + _DISTORTION_KEYS if k in frame}}
    for k in _DISTORTION_KEYS:
        if k in d and _number(where, d, k, positive=False) != 0.0:
            raise ValueError(f"{where}: distortion {k} = {d[k]} is not supported; undistort the images first "
                             f"(or import the COLMAP model, whose OPENCV cameras are undistorted on import)")
    if "w" in d and "h" in d:
        w, h = _number(where, d, "w"), _number(where, d, "h")
    elif size is not None:
        w, h = size
    else:
        raise ValueError(f"{where}: no image size ('w' and 'h') and no image to read it from")
    if int(w) != w or int(h) != h:
        raise ValueError(f"{where}: 'w' and 'h' must be whole pixels, got {w} x {h}")
    if "fl_x" in d:
        fx = _number(where, d, "fl_x")
        fy = _number(where, d, "fl_y") if "fl_y" in d else fx
    elif "camera_angle_x" in d:
        fx = 0.5 * w / math.tan(0.5 * _angle(where, d, "camera_angle_x"))
        if "fl_y" in d:  # an explicit fy beside the angle (was ignored: fy = fx)
            fy = _number(where, d, "fl_y")
        elif "camera_angle_y" in d:
            fy = 0.5 * h / math.tan(0.5 * _angle(where, d, "camera_angle_y"))
        else:
            fy = fx
    else:
        raise ValueError(f"{where}: no focal length ('fl_x' or 'camera_angle_x')")
    cx = (_number(where, d, "cx", positive=False) if "cx" in d else 0.5 * w) - 0.5
    cy = (_number(where, d, "cy", positive=False) if "cy" in d else 0.5 * h) - 0.5
    return Camera(fx, fy, cx, cy, int(w), int(h), pose)


def _angle(where: str, d: dict, key: str) -> float:
    """A field-of-view angle in radians, 0 < angle < pi (a larger one gave a negative focal length
    blamed on fx/fy)."""
    a = _number(where, d, key)
    if not a < math.pi:
        raise ValueError(f"{where}: {key!r} must be below pi (radians), got {a}")
    return a


def _resolve(base: Path, name, where: str, key: str) -> Path:
    if not isinstance(name, str) or not name:
        raise ValueError(f"{where}: {key!r} must be a file name, got {name!r}")
    p = base / name
    if p.suffix == "" or not p.exists():
        for ext in (".png", ".jpg", ".jpeg", ".exr", ".tif"):
            if p.with_name(p.name + ext).is_file():
                return p.with_name(p.name + ext)
    if not p.is_file():
        raise FileNotFoundError(f"{where}: {key!r} refers to a missing file {p}")
    return p


def read_transforms(path, report: ImportReport | None = None, *, depth_scale: float | None = None) -> list[Frame]:
    """Frames of a ``transforms.json`` (see the module docstring), in file order.
    ``depth_scale`` (scene units per stored depth unit), when given, replaces the file's
    ``depth_unit_scale_factor`` / ``integer_depth_scale``."""
    path = Path(path)
    top = read_json(path, "transforms")
    if not isinstance(top, dict) or not isinstance(top.get("frames"), list):
        raise ValueError(f"transforms: {path} has no 'frames' list")
    if not top["frames"]:  # (was reported as having no list at all)
        raise ValueError(f"transforms: {path}: 'frames' is an empty list; no frame to import")
    check_foreign_keys(f"transforms {path.name}", top, _TOP_KEYS, report)
    model = top.get("camera_model", "OPENCV")
    if model not in ("OPENCV", "PINHOLE", "SIMPLE_PINHOLE"):
        raise ValueError(f"transforms {path.name}: camera_model {model!r} is not supported (pinhole cameras only)")
    scale = None
    if "depth_unit_scale_factor" in top:
        scale = _number(f"transforms {path.name}", top, "depth_unit_scale_factor")
    elif "integer_depth_scale" in top:
        scale = _number(f"transforms {path.name}", top, "integer_depth_scale")
    if depth_scale is not None:
        scale = depth_scale
    frames, size = [], None
    for i, fr in enumerate(top["frames"]):
        where = f"transforms {path.name}: frames[{i}]"
        if not isinstance(fr, dict):
            raise ValueError(f"{where}: expected an object, got {fr!r}")
        check_foreign_keys(where, fr, _FRAME_KEYS, report)
        if "transform_matrix" not in fr:
            raise ValueError(f"{where}: no 'transform_matrix' (camera-to-world pose)")
        if "file_path" not in fr:
            raise ValueError(f"{where}: no 'file_path'")
        rows = fr["transform_matrix"]
        if not (isinstance(rows, list) and all(isinstance(r, list) and all(
                isinstance(x, (int, float)) and not isinstance(x, bool) for x in r) for r in rows)):
            raise ValueError(f"{where}: bad 'transform_matrix': expected rows of numbers (JSON arrays), got {rows!r:.80}")
        try:
            pose = ours_from_gl(np.asarray(rows, np.float64))
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{where}: bad 'transform_matrix': {exc}") from None
        color = _resolve(path.parent, fr["file_path"], where, "file_path")
        if not any(k in fr or k in top for k in ("w", "h")) and size is None:
            img = read_image(color, what=f"{where}: 'file_path'")
            size = (img.shape[1], img.shape[0])
        dkey = "depth_file_path" if "depth_file_path" in fr else ("depth_path" if "depth_path" in fr else None)
        depth = _resolve(path.parent, fr[dkey], where, dkey) if dkey else None
        try:
            cam = _camera(where, top, fr, size, pose)
        except (TypeError, ValueError) as exc:
            msg = str(exc)
            raise ValueError(msg if msg.startswith(where) else f"{where}: {msg}") from None
        name = Path(fr["file_path"]).stem.removesuffix("_color") or f"frame_{i:04d}"
        frames.append(Frame(name, color, cam, depth, scale if depth is not None else None))
    return frames


def _expand(paths) -> list[Path]:
    """View files in order; a sequence manifest (``"format": "ibr-sequence"``) stands for its views;
    a view named twice (e.g. directly and through the manifest) is taken once."""
    out: list[Path] = []
    for p in map(Path, paths):
        try:
            doc = json.loads(p.read_text())
        except (OSError, ValueError):
            doc = None
        if isinstance(doc, dict) and doc.get("format") == SEQUENCE_FORMAT:
            names = doc.get("views")  # as ibr.sequence.load_sequence checks it (io may not import it)
            if not isinstance(names, list) or not names or not all(isinstance(n, str) and n for n in names):
                raise ValueError(f"sequence file {p}: 'views' must be a non-empty list of view file names, got {names!r}")
            items = [p.parent / n for n in names]
        else:
            items = [p]
        for q in items:
            if q.resolve() not in {o.resolve() for o in out}:
                out.append(q)
    return out


def write_transforms(view_paths, out, *, base=None) -> list[str]:
    """Write ``transforms.json`` (instant-ngp / nerfstudio) for view files, so data moves on to NeRF
    and 3DGS tools; return notes on what could not be carried over.

    Paths are relative to ``base`` (default ``out``'s folder: where the file will live);
    intrinsics are top-level when every view shares them, else per frame; depth goes in as
    ``depth_file_path`` when the view stores planar z as a float EXR (``depth_unit_scale_factor``
    1); a view whose depth file uses another encoding gets no depth (noted).
    """
    out = Path(out)
    base = Path(base) if base is not None else out.parent
    frames, cams, notes = [], [], []
    inputs = {Path(p).resolve() for p in view_paths}  # never written over: manifests, views, their images
    for vp in _expand(view_paths):
        view = load_view(vp)
        doc = json.loads(vp.read_text())
        inputs |= {vp.resolve()} | {f.resolve() for _, f in named_files(vp, doc)}
        cam = view.camera
        cams.append(cam)
        fr = {"file_path": os.path.relpath(vp.parent / doc["color"], base),
              "transform_matrix": gl_from_ours(cam.world_from_cam).tolist(),
              "fl_x": cam.fx, "fl_y": cam.fy, "cx": cam.cx + 0.5, "cy": cam.cy + 0.5, "w": cam.width, "h": cam.height}
        depth = doc.get("depth")
        if view.depth is not None:
            plain = (depth.get("encoding", "z") == "z" and "scale" not in depth and "channel" not in depth
                     and depth["path"].lower().endswith(".exr"))
            if plain:
                fr["depth_file_path"] = os.path.relpath(vp.parent / depth["path"], base)
            else:
                notes.append(f"{vp.name}: depth stored as {depth.get('encoding', 'z')!r} "
                             f"({depth['path']}) is not planar float z; exported without depth")
        frames.append(fr)
    if len({(c.fx, c.fy, c.cx, c.cy, c.width, c.height) for c in cams}) == 1:  # shared intrinsics: top level
        c = cams[0]
        top = {"fl_x": c.fx, "fl_y": c.fy, "cx": c.cx + 0.5, "cy": c.cy + 0.5, "w": c.width, "h": c.height,
               "camera_angle_x": 2 * math.atan(0.5 * c.width / c.fx), "camera_model": "OPENCV"}
        for fr in frames:
            for k in ("fl_x", "fl_y", "cx", "cy", "w", "h"):
                del fr[k]
    else:
        top = {"camera_model": "OPENCV"}
    top["frames"] = frames
    if any("depth_file_path" in fr for fr in frames):
        top["depth_unit_scale_factor"] = 1.0
    if out.resolve() in inputs:
        raise ValueError(f"out: {out} is one of the inputs (a view file, a manifest or an image they name); "
                         "choose another file")
    with atomic_path(out) as tmp:  # nothing half-written: renamed into place once complete
        tmp.write_text(json.dumps(top, indent=2) + "\n")
    return notes
