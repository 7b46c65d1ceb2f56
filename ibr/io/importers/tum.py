"""TUM RGB-D benchmark sequences -> frames.

Files (https://cvg.cit.tum.de/data/datasets/rgbd-dataset/file_formats): ``rgb.txt`` and
``depth.txt`` (``timestamp filename`` per line, ``#`` comments), ``groundtruth.txt``
(``timestamp tx ty tz qx qy qz qw``: the colour camera's optical centre and orientation in the
world, i.e. ``world_from_cam`` with camera axes as ours). Depth PNGs hold 5000 codes per metre
(0 = no reading). Each colour frame takes the depth frame nearest in time and the pose nearest in
time, each within ``tolerance`` seconds (0.02 s, as the benchmark's ``associate.py``); frames
without both are dropped and reported. Intrinsics: the ROS default the benchmark recommends,
fx = fy = 525, cx = 319.5, cy = 239.5 (640 x 480, integer pixel centres as ours), or given; the
size is read from the first colour image.
"""

from __future__ import annotations

import bisect
import math
from pathlib import Path

import numpy as np

from ...base.camera import Camera
from .common import Frame, ImportReport
from .conventions import rotation_from_quaternion

__all__ = ["TUM_DEPTH_SCALE", "TUM_INTRINSICS", "associate", "read_tum"]

#: Metres per depth code of the benchmark's PNGs.
TUM_DEPTH_SCALE = 1.0 / 5000.0
#: (fx, fy, cx, cy) of the ROS default calibration for 640 x 480.
TUM_INTRINSICS = (525.0, 525.0, 319.5, 239.5)


def _table(path: Path, ncols: int) -> list[tuple[float, list[str]]]:
    if not path.is_file():
        raise FileNotFoundError(f"tum: missing {path}")
    rows = []
    for n, line in enumerate(path.read_text().splitlines(), 1):
        s = line.strip()
        if not s or s.startswith("#"):
            continue
        parts = s.split()
        if len(parts) != ncols:
            raise ValueError(f"tum {path.name} line {n}: expected {ncols} columns, got {len(parts)}: {s!r}")
        try:
            t = float(parts[0])
        except ValueError:
            t = math.nan
        if not math.isfinite(t):  # a NaN time matched nothing and its frame was dropped quietly
            raise ValueError(f"tum {path.name} line {n}: bad timestamp {parts[0]!r}")
        rows.append((t, parts[1:]))
    rows.sort(key=lambda r: r[0])
    return rows


def associate(times: list[float], others: list[float], tolerance: float) -> list[int | None]:
    """For each time, the index of the nearest of ``others`` (sorted) within ``tolerance``, else None."""
    out = []
    for t in times:
        i = bisect.bisect_left(others, t)
        best = min((j for j in (i - 1, i) if 0 <= j < len(others)), key=lambda j: abs(others[j] - t), default=None)
        out.append(best if best is not None and abs(others[best] - t) <= tolerance else None)
    return out


def read_tum(folder, *, intrinsics=TUM_INTRINSICS, size=None, tolerance: float = 0.02,
             report: ImportReport | None = None, depth_scale: float | None = None) -> list[Frame]:
    """Frames of a TUM RGB-D sequence folder (see the module docstring), in time order;
    ``depth_scale`` (scene units per depth code) replaces the benchmark's 1/5000 m."""
    folder = Path(folder)
    if not (isinstance(tolerance, (int, float)) and tolerance > 0):
        raise ValueError(f"tolerance: expected a positive number of seconds, got {tolerance!r}")
    rgb = _table(folder / "rgb.txt", 2)
    depth = _table(folder / "depth.txt", 2)
    gt = _table(folder / "groundtruth.txt", 8)
    d_idx = associate([t for t, _ in rgb], [t for t, _ in depth], tolerance)
    g_idx = associate([t for t, _ in rgb], [t for t, _ in gt], tolerance)
    fx, fy, cx, cy = (float(x) for x in intrinsics)
    frames = []
    for (t, (name,)), di, gi in zip(rgb, d_idx, g_idx):
        if di is None or gi is None:
            if report is not None:
                what = " and ".join(w for w, i in (("depth", di), ("pose", gi)) if i is None)
                report.dropped.append((name, f"no {what} within {tolerance:g} s of t = {t:.6f}"))
            continue
        try:
            tx, ty, tz, qx, qy, qz, qw = (float(x) for x in gt[gi][1])
        except ValueError:
            raise ValueError(f"tum groundtruth.txt: bad numbers at t = {gt[gi][0]}") from None
        pose = np.eye(4)
        try:
            pose[:3, :3] = rotation_from_quaternion(qw, qx, qy, qz)
        except ValueError as exc:
            raise ValueError(f"tum groundtruth.txt: the pose at t = {gt[gi][0]}: {exc}") from None
        pose[:3, 3] = (tx, ty, tz)
        if not np.isfinite(pose).all():
            raise ValueError(f"tum groundtruth.txt: the pose at t = {gt[gi][0]}: expected finite numbers")
        color, dpath = folder / name, folder / depth[di][1][0]
        for p, listed in ((color, "rgb.txt"), (dpath, "depth.txt")):  # the list file that names it
            if not p.is_file():
                raise FileNotFoundError(f"tum: {p} (listed in {folder / listed}) is missing")
        if size is None:  # the benchmark's 640 x 480, or whatever the images are
            from ..images import read_image

            h, w = read_image(color, what="tum colour").shape[:2]
            size = (w, h)
            if tuple(float(x) for x in intrinsics) == TUM_INTRINSICS and size != (640, 480):
                raise ValueError(f"intrinsics: the default TUM calibration is for 640 x 480 images, these are "
                                 f"{w} x {h} ({color.name}); give the camera's fx fy cx cy")
        try:
            cam = Camera(fx, fy, cx, cy, int(size[0]), int(size[1]), pose)
        except ValueError as exc:  # a focal length <= 0 from --intrinsics, ...
            raise ValueError(f"tum: the camera of {name}: {exc}") from None
        frames.append(Frame(f"tum_{t:.6f}".replace(".", "_"), color, cam, dpath,
                            TUM_DEPTH_SCALE if depth_scale is None else depth_scale))
    if not frames:
        raise ValueError(f"tum: no colour frame of {folder} has both a depth frame and a pose within "
                         f"{tolerance:g} s")
    return frames
