"""COLMAP text models (``cameras.txt``, ``images.txt``) and depth maps -> frames.

``cameras.txt``: ``CAMERA_ID MODEL WIDTH HEIGHT PARAMS...`` with models SIMPLE_PINHOLE
(``f cx cy``), PINHOLE (``fx fy cx cy``) and OPENCV (``fx fy cx cy k1 k2 p1 p2``: the images and
depth maps are undistorted on import with ``cv2.undistort``, keeping the same K).
``images.txt``: two lines per image, ``IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME`` (the
world-to-camera rotation and translation, camera axes as ours) and the 2-D points (ignored).
Principal points are continuous pixel coordinates (top-left pixel centre at 0.5): ours = cx - 0.5.

Depth: ``depth_dir`` holding, per image ``NAME``, COLMAP's dense ``NAME.geometric.bin`` or
``NAME.photometric.bin`` (``width&height&channels&`` then float32 in column-major order; planar z,
0 = none) or an image ``<stem>.exr``/``.png``/``.tif`` (planar z, times ``depth_scale``).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ...base.camera import Camera
from .common import Frame, ImportReport
from .conventions import pose_from_world_to_camera, rotation_from_quaternion

__all__ = ["MODELS", "image_dir_candidates", "read_colmap", "read_colmap_depth"]

#: Depth image extensions looked for beside ``<stem>`` in the depth folder.
DEPTH_EXTS = (".exr", ".png", ".tif", ".tiff", ".pfm")
#: Supported camera models and their parameter counts.
MODELS = {"SIMPLE_PINHOLE": 3, "PINHOLE": 4, "OPENCV": 8}


def _lines(path: Path):
    if not path.is_file():
        binary = path.with_suffix(".bin")
        hint = (f"; {binary.name} is there: a binary model, convert it with `colmap model_converter --input_path "
                f"{path.parent} --output_path {path.parent} --output_type TXT`" if binary.is_file() else "")
        raise FileNotFoundError(f"colmap: missing {path}{hint}")
    for n, line in enumerate(path.read_text().splitlines(), 1):
        yield n, line


def read_cameras(path: Path) -> dict[int, tuple[str, int, int, list[float]]]:
    cams = {}
    for n, line in _lines(path):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        parts = s.split()
        where = f"colmap {path.name} line {n}"
        if len(parts) < 4:
            raise ValueError(f"{where}: expected CAMERA_ID MODEL WIDTH HEIGHT PARAMS..., got {s!r}")
        model = parts[1]
        if model not in MODELS:
            raise ValueError(f"{where}: camera {parts[0]} has model {model!r}, not supported "
                             f"(supported: {', '.join(MODELS)}; undistort other models with COLMAP first)")
        try:
            cid, w, h = int(parts[0]), int(parts[2]), int(parts[3])
            params = [float(x) for x in parts[4:]]
        except ValueError:
            raise ValueError(f"{where}: bad numbers in {s!r}") from None
        if len(params) != MODELS[model]:
            raise ValueError(f"{where}: {model} takes {MODELS[model]} parameters, got {len(params)}")
        if cid in cams:  # the later line silently replaced the first
            raise ValueError(f"{where}: camera id {cid} is defined twice")
        cams[cid] = (model, w, h, params)
    return cams


def _intrinsics(model: str, params: list[float]):
    if model == "SIMPLE_PINHOLE":
        f, cx, cy = params
        return f, f, cx, cy, None
    fx, fy, cx, cy = params[:4]
    dist = np.array(params[4:8]) if model == "OPENCV" else None
    return fx, fy, cx, cy, dist


def _undistorter(k: np.ndarray, dist: np.ndarray):
    import cv2

    def undistort(img: np.ndarray) -> np.ndarray:
        if img.dtype.kind == "f" and img.ndim == 2:  # depth: nearest, so no depth is invented at edges
            h, w = img.shape
            m1, m2 = cv2.initUndistortRectifyMap(k, dist, None, k, (w, h), cv2.CV_32FC1)
            return cv2.remap(img, m1, m2, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT, borderValue=np.nan)
        return cv2.undistort(img, k, dist)

    return undistort


def read_colmap_depth(path) -> np.ndarray:
    """(H, W) float32 of a COLMAP dense depth map ``*.bin`` (0 -> NaN)."""
    path = Path(path)
    raw = path.read_bytes()
    head = raw.split(b"&", 3)
    try:
        w, h, c = int(head[0]), int(head[1]), int(head[2])
    except (ValueError, IndexError):
        raise ValueError(f"colmap depth: {path} does not start with 'width&height&channels&'") from None
    if w < 1 or h < 1 or c != 1 or len(head[3]) % 4:  # numpy's reshape/frombuffer messages named no file
        raise ValueError(f"colmap depth: {path}: header {w}x{h}x{c} with {len(head[3])} bytes of float32 data; "
                         "expected a positive width and height, one channel and whole float32 values")
    data = np.frombuffer(head[3], np.float32)
    if data.size != w * h * c:
        raise ValueError(f"colmap depth: {path} holds {data.size} values, header says {w}x{h}x{c}")
    z = data.reshape((w, h), order="F").T.copy()
    z[~(z > 0)] = np.nan
    return z


def _named(labels, key: str, value=None) -> str:
    """How messages name the argument ``key`` (``images`` or ``depth``): as the caller's user wrote
    it (``labels``, e.g. ``{"depth": "--depth"}`` from ``ibr import``), else the library's words."""
    option = (labels or {}).get(key)
    if option:
        return option if value is None else f"{option} {value}"
    return key if value is None else f"the {key} folder {value}"


def image_dir_candidates(model_dir) -> list[Path]:
    """Where COLMAP projects keep the images of a model folder ``SRC``: ``SRC/../images``
    (``project/sparse`` + ``project/images``) and ``SRC/../../images`` (``project/sparse/0``, as
    COLMAP's mapper writes it), in that order."""
    model_dir = str(model_dir)
    out: list[Path] = []
    for up in ("..", "../.."):
        p = Path(os.path.normpath(os.path.join(model_dir, up, "images")))
        if p not in out:
            out.append(p)
    return out


def _depth_candidates(name: str) -> str:
    stem = Path(name).stem
    return f"{name}.geometric.bin, {name}.photometric.bin or {stem}{{{','.join(DEPTH_EXTS)}}}"


def read_colmap(model_dir, image_dir=None, *, depth_dir=None, depth_scale: float | None = None,
                report: ImportReport | None = None, labels: dict | None = None) -> list[Frame]:
    """Frames of a COLMAP text model (see the module docstring), in ``images.txt`` order.

    ``image_dir`` ``None``: the first existing folder of :func:`image_dir_candidates`. An image
    without a depth map in ``depth_dir`` is skipped (``report.dropped``, with where it looked);
    none with one is an error. ``labels`` names ``images`` / ``depth`` in messages as the caller's
    user wrote them (``ibr import``: ``{"images": "--images", "depth": "--depth"}``)."""
    model_dir = Path(model_dir)
    for key, folder in (("images", image_dir), ("depth", depth_dir)):  # a wrong folder, up front
        if folder is not None and not Path(folder).is_dir():
            what = "is not a folder" if Path(folder).exists() else "does not exist"
            raise FileNotFoundError(f"{_named(labels, key)}: {folder} {what} (expected the folder of "
                                    f"{'the images images.txt names' if key == 'images' else 'depth maps'})")
    cams = read_cameras(model_dir / "cameras.txt")
    if image_dir is None:
        tried = image_dir_candidates(model_dir)
        image_dir = next((d for d in tried if d.is_dir()), None)
        if image_dir is None:
            raise FileNotFoundError(f"colmap: no image folder beside {model_dir} (tried {', '.join(map(str, tried))}); "
                                    f"pass {_named(labels, 'images', 'DIR') if (labels or {}).get('images') else 'images=DIR'}")
    image_dir = Path(image_dir)
    frames, skipped = [], []
    lines = [(n, l.strip()) for n, l in _lines(model_dir / "images.txt") if not l.strip().startswith("#")]
    k = 0
    while k < len(lines):
        n, s = lines[k]
        if not s:
            k += 1
            continue
        parts = s.split()
        where = f"colmap images.txt line {n}"
        if len(parts) < 10:
            raise ValueError(f"{where}: expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME, got {s!r}")
        try:
            qw, qx, qy, qz, tx, ty, tz = (float(x) for x in parts[1:8])
            cid = int(parts[8])
        except ValueError:
            raise ValueError(f"{where}: bad numbers in {s!r}") from None
        name = " ".join(parts[9:])
        if k + 1 < len(lines):  # the POINTS2D line follows (possibly empty): X Y POINT3D_ID triples
            pn, ps = lines[k + 1]
            try:
                points = [float(x) for x in ps.split()]
            except ValueError:
                points = None
            if points is None or len(points) % 3:
                raise ValueError(f"colmap images.txt line {pn}: expected the POINTS2D line of image {name!r} "
                                 f"(X Y POINT3D_ID triples, or empty), got {ps[:60]!r}")
        k += 2
        if cid not in cams:
            raise ValueError(f"{where}: image {name!r} uses camera {cid}, which cameras.txt does not define")
        model, w, h, params = cams[cid]
        try:  # a zero or non-finite quaternion, a NaN translation, a focal length <= 0, width 0
            fx, fy, cx, cy, dist = _intrinsics(model, params)
            pose = pose_from_world_to_camera(rotation_from_quaternion(qw, qx, qy, qz), (tx, ty, tz))
            cam = Camera(fx, fy, cx - 0.5, cy - 0.5, w, h, pose)
        except ValueError as exc:  # the file and line, not only the value (#12)
            raise ValueError(f"{where}: image {name!r} (camera {cid}): {exc}") from None
        color = image_dir / name
        if not color.is_file():
            raise FileNotFoundError(f"{where}: image {name!r} is not in {image_dir}")
        depth, scale = None, depth_scale
        if depth_dir is not None:
            depth = _depth_file(Path(depth_dir), name)
            if depth is None:
                skipped.append(name)
                if report is not None:
                    report.dropped.append((name, f"no depth map in {_named(labels, 'depth', depth_dir)} "
                                                 f"(looked for {_depth_candidates(name)})"))
                continue
        undistort = None
        if dist is not None and np.any(dist != 0):
            kk = np.array([[fx, 0, cx - 0.5], [0, fy, cy - 0.5], [0, 0, 1]])
            undistort = _undistorter(kk, dist)
        reader = read_colmap_depth if depth is not None and depth.suffix == ".bin" else None
        frames.append(Frame(Path(name).stem, color, cam, depth, scale, None, undistort, reader))
    if report is not None:
        report.listed, report.unit = len(frames) + len(skipped), "images"
    if not frames and skipped:  # every image skipped: say why, for the first
        raise FileNotFoundError(f"colmap: none of the {len(skipped)} image(s) of {model_dir / 'images.txt'} has a depth "
                                f"map in {_named(labels, 'depth', depth_dir)} (for {skipped[0]} it looked for "
                                f"{_depth_candidates(skipped[0])})")
    if not frames:
        raise ValueError(f"colmap: {model_dir / 'images.txt'} lists no image")
    return frames


def _depth_file(folder: Path, name: str) -> Path | None:
    for cand in (folder / f"{name}.geometric.bin", folder / f"{name}.photometric.bin"):
        if cand.is_file():
            return cand
    stem = Path(name).stem
    for ext in DEPTH_EXTS:
        if (folder / (stem + ext)).is_file():
            return folder / (stem + ext)
    return None
