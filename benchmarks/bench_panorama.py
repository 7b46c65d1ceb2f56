"""Benchmark ``panorama`` against py360convert 1.0.4 and a bare ``cv2.remap`` (same run).

Run:  python benchmarks/bench_panorama.py [--quick] [--repeats N]

Accuracy: an analytic RGB function on the sphere sampled exactly at pixel centres (project
convention, panorama/directions.py) is the ground truth for every output; PSNR with peak 1.
Seam band: the one-texel ring along every face edge (e2c) or the equirect pixels whose sample
falls within one texel of a face edge (c2e). Seam step ratio: the step between the two texels
that meet at the +z/+x seam divided by the true step there (1 = right, 0 = a repeated texel).
Round trips: e2c then c2e of a photograph (Middlebury motorcycle, bundled with scikit-image,
cropped to 2:1 at native resolution) and of the synthetic "room" scene rendered by
panorama.synth (|latitude| < 60 deg). Speed: medians of warm calls (caches filled on both
sides), ratios against py360convert and against one bare cv2.remap with our cached maps; the
first (cold) call is reported too. Writes benchmarks/results/panorama.png.
"""

from __future__ import annotations

import argparse
import itertools
import math
import os
import statistics
import sys
import time
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import panorama as P  # noqa: E402
from panorama import maps as M  # noqa: E402
from panorama.directions import equirect_directions, face_directions, face_pixel_from_direction  # noqa: E402
from panorama.sampling import pad_faces  # noqa: E402

try:
    import py360convert as py360
    from py360convert import utils as py360_utils
except ImportError:  # pragma: no cover - bench extra
    py360 = None

OURS_FROM_PY360 = {"F": 4, "R": 0, "B": 5, "L": 1, "U": 3, "D": 2}  # py360 key -> our face index


def sphere_fn(d, k=1.0):
    """Analytic RGB on the unit sphere; ``k`` scales the frequencies (k = 10: ~7 deg period)."""
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    return np.stack([0.5 + 0.3 * np.sin(k * (5 * d[..., 0] + 2 * d[..., 1])),
                     0.5 + 0.3 * np.cos(k * (4 * d[..., 1] - 3 * d[..., 2])),
                     0.5 + 0.2 * np.sin(k * d[..., 0] * d[..., 2])], axis=-1).astype(np.float32)


def psnr(a, b, peak=1.0):
    mse = np.mean((np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2)
    return float("inf") if mse == 0 else 10 * math.log10(peak * peak / mse)


def timeit_interleaved(fns, repeats):
    """Median time of each function, called round-robin so that machine noise hits all alike."""
    for fn in fns:
        fn()
    times = [[] for _ in fns]
    for _ in range(repeats):
        for k, fn in enumerate(fns):
            t = time.perf_counter()
            fn()
            times[k].append(time.perf_counter() - t)
    return [statistics.median(t) for t in times]


def cold(fn, clear):
    clear()
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def clear_ours():
    for f in (M.cube_face_map, M.equirect_map, M.perspective_map):
        f.cache_clear()
    from panorama import directions, layouts, sampling
    directions.face_directions.cache_clear()
    directions.equirect_directions.cache_clear()
    layouts.layout_index_maps.cache_clear()
    sampling._border_taps.cache_clear()


def clear_py360():
    for name in ("xyzcube", "equirect_uvgrid", "equirect_facetype"):
        getattr(py360_utils, name).cache_clear()
    py360_utils.EquirecSampler.from_cubemap.cache_clear()
    py360_utils.EquirecSampler.from_perspective.cache_clear()
    py360_utils.CubeFaceSampler.from_equirec.cache_clear()


def py360_faces(d):
    """py360convert dict F R B L U D -> our (6, S, S, C) stack."""
    out = [None] * 6
    for k, v in d.items():
        out[OURS_FROM_PY360[k]] = v
    return np.stack(out)


def seam_stats(err_faces):
    s = err_faces.shape[1]
    band = np.zeros((s, s), bool)
    band[[0, -1]] = band[:, [0, -1]] = True
    e = err_faces.max(-1)
    return float(np.sqrt(np.mean(e[:, band] ** 2)) / np.sqrt(np.mean(e[:, ~band] ** 2)))


def seam_step_ratio(faces, truth):
    # +z (index 4) right column meets +x (index 0) left column
    got = faces[0][:, 0] - faces[4][:, -1]
    want = truth[0][:, 0] - truth[4][:, -1]
    sel = np.abs(want) > 1e-4
    return float(np.median(got[sel] / want[sel]))


def photo_equirect():
    from skimage.data import stereo_motorcycle
    left = stereo_motorcycle()[0]  # (500, 741, 3) uint8, a real photograph
    h = 368
    return np.ascontiguousarray(left[66:66 + h, 2:2 + 2 * h])  # 736 x 368, 2:1, native pixels


RESULTS = Path(__file__).resolve().parent / "results"  # `ibr bench --out DIR` points this elsewhere


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="1024x512 / 256 px faces, 3 repeats")
    ap.add_argument("--repeats", type=int, default=9)
    ap.add_argument("--speed-only", action="store_true", help="skip the accuracy and round-trip part")
    args = ap.parse_args(argv)
    if py360 is None:
        sys.exit("install the bench extra: pip install -e '.[bench]'")
    W, H, S = (1024, 512, 256) if args.quick else (4096, 2048, 1024)
    PW, PH = (480, 270) if args.quick else (1920, 1080)
    reps = 3 if args.quick else args.repeats
    print(f"cv2 {cv2.__version__}, threads {cv2.getNumThreads()}, cpus {os.cpu_count()}, "
          f"py360convert {getattr(py360, '__version__', '1.0.4')}")
    rows = {}

    # ---------------------------------------------------------------- accuracy
    _, u, v = face_pixel_from_direction(equirect_directions(W, H), S)
    seam = (u < 0.5) | (u > S - 1.5) | (v < 0.5) | (v > S - 1.5)
    yaw, pitch, fov = 30.0, 20.0, 90.0
    vfov = math.degrees(2 * math.atan(math.tan(math.radians(fov) / 2) * PH / PW))

    def ratio(err):
        e = err.max(-1)
        return float(np.sqrt(np.mean(e[seam] ** 2)) / np.sqrt(np.mean(e[~seam] ** 2)))

    for kf, tag in ((1.0, "k=1"), (10.0, "k=10")) if not args.speed_only else ((10.0, "k=10"),):
        eq = sphere_fn(equirect_directions(W, H), kf)
        truth_faces = sphere_fn(face_directions(S), kf)
        ours = np.stack(P.equirect_to_cubemap(eq, S, layout="list"))
        theirs = py360_faces(py360.e2c(eq, face_w=S, cube_format="dict"))
        rows[f"e2c {tag}"] = dict(ours_db=psnr(ours, truth_faces), py_db=psnr(theirs, truth_faces),
                                  ours_seam=seam_stats(np.abs(ours - truth_faces)),
                                  py_seam=seam_stats(np.abs(theirs - truth_faces)),
                                  ours_step=seam_step_ratio(ours, truth_faces),
                                  py_step=seam_step_ratio(theirs, truth_faces))
        cube_in = [f for f in truth_faces]
        ours_e = P.cubemap_to_equirect(cube_in, W, H, layout="list")
        py_dict = {k: truth_faces[i] for k, i in OURS_FROM_PY360.items()}
        theirs_e = py360.c2e(py_dict, H, W, cube_format="dict")
        rows[f"c2e {tag}"] = dict(ours_db=psnr(ours_e, eq), py_db=psnr(theirs_e, eq),
                                  ours_seam=ratio(np.abs(ours_e - eq)),
                                  py_seam=ratio(np.abs(theirs_e - eq)))
        truth_p = sphere_fn(M.perspective_rays(yaw, pitch, 0.0, fov, PW, PH), kf)
        ours_p = P.perspective(eq, yaw_deg=yaw, pitch_deg=pitch, fov_deg=fov, width=PW, height=PH)
        theirs_p = py360.e2p(eq, fov_deg=(fov, vfov), u_deg=yaw, v_deg=pitch, out_hw=(PH, PW))
        ours_pc = P.perspective(cube_in, yaw_deg=yaw, pitch_deg=pitch, fov_deg=fov, width=PW, height=PH)
        rows[f"e2p {tag}"] = dict(ours_db=psnr(ours_p, truth_p), py_db=psnr(theirs_p, truth_p))
        rows[f"c2p {tag}"] = dict(ours_db=psnr(ours_pc, truth_p), py_db=float("nan"))

    # ---------------------------------------------------------------- round trips
    if not args.speed_only:
        photo = photo_equirect()
        ph, pw = photo.shape[:2]
        ps = pw // 4
        rt_ours = P.cubemap_to_equirect(P.equirect_to_cubemap(photo, ps, layout="list"), pw, ph, layout="list")
        rt_py = py360.c2e(py360.e2c(photo, face_w=ps, cube_format="dice"), ph, pw, cube_format="dice")
        rows["photo round trip"] = dict(ours_db=psnr(rt_ours, photo, 255), py_db=psnr(rt_py, photo, 255))

        from ibr.synth import make_scene, scene_cameras
        from panorama.synth import render_equirect
        sw = 512 if args.quick else 1024
        scene_eq, _ = render_equirect(make_scene("room"), sw, sw // 2,
                                      origin=scene_cameras("room")[0].position, supersample=3)
        band = slice(sw // 12, sw // 2 - sw // 12)  # |lat| < 60 deg
        for label, fs in (("W/pi", math.ceil(sw / math.pi)), ("0.4W", int(0.4 * sw))):
            rt = P.cubemap_to_equirect(P.equirect_to_cubemap(scene_eq, fs, layout="list"), sw, sw // 2, layout="list")
            rt_py_s = py360.c2e(py360.e2c(scene_eq, face_w=fs, cube_format="dice"), sw // 2, sw, cube_format="dice")
            rows[f"scene round trip S={label}"] = dict(ours_db=psnr(rt[band], scene_eq[band]),
                                                       py_db=psnr(rt_py_s[band], scene_eq[band]))

    # ---------------------------------------------------------------- speed
    img8 = np.rint(eq * 255).astype(np.uint8)
    faces8 = [np.rint(f * 255).astype(np.uint8) for f in truth_faces]
    py_faces8 = {k: faces8[i] for k, i in OURS_FROM_PY360.items()}
    speed = {}

    def bare(smap, src):
        return lambda: cv2.remap(src, smap.map_x, smap.map_y, cv2.INTER_LINEAR,
                                 borderMode=cv2.BORDER_WRAP if not smap.pad else cv2.BORDER_REPLICATE)

    new_yaw = itertools.count(start=yaw + 0.37, step=1.37)  # never a cached view
    cases = {
        f"e2c {W}x{H} -> {S}^2 (list)": (
            lambda: P.equirect_to_cubemap(img8, S, layout="list"),
            lambda: py360.e2c(img8, face_w=S, cube_format="list"),
            bare(M.cube_face_map("list", S, H, W), img8)),
        f"e2c {W}x{H} -> {S}^2 (horizon)": (
            lambda: P.equirect_to_cubemap(img8, S, layout="horizon"),
            lambda: py360.e2c(img8, face_w=S, cube_format="horizon"),
            bare(M.cube_face_map("horizon", S, H, W), img8)),
        f"e2p {W}x{H} -> {PW}x{PH}": (
            lambda: P.perspective(img8, yaw_deg=yaw, pitch_deg=pitch, fov_deg=fov, width=PW, height=PH),
            lambda: py360.e2p(img8, fov_deg=(fov, vfov), u_deg=yaw, v_deg=pitch, out_hw=(PH, PW)),
            bare(M.perspective_map(yaw, pitch, 0.0, fov, PW, PH, "equirect", H, W), img8)),
        f"e2p {W}x{H} -> {PW}x{PH}, new yaw": (  # a tour / a viewer: new maps every call
            lambda: P.perspective(img8, yaw_deg=next(new_yaw), pitch_deg=pitch, fov_deg=fov, width=PW, height=PH),
            lambda: py360.e2p(img8, fov_deg=(fov, vfov), u_deg=next(new_yaw), v_deg=pitch, out_hw=(PH, PW)),
            bare(M.perspective_map(yaw, pitch, 0.0, fov, PW, PH, "equirect", H, W), img8)),
        f"c2e {S}^2 -> {W}x{H}": (
            lambda: P.cubemap_to_equirect(faces8, W, H, layout="list"),
            lambda: py360.c2e(py_faces8, H, W, cube_format="dict"),
            bare(M.equirect_map(W, H, "cube", S), pad_faces(faces8))),
    }
    for name, (f_ours, f_py, f_bare) in cases.items():
        cold_ours = cold(f_ours, clear_ours)
        cold_py = cold(f_py, clear_py360)
        t_ours, t_py, t_bare = timeit_interleaved([f_ours, f_py, f_bare], reps)
        speed[name] = dict(ours=t_ours, py=t_py, bare=t_bare, cold_ours=cold_ours, cold_py=cold_py)

    # ---------------------------------------------------------------- report
    print(f"\nAccuracy vs analytic sphere function ({W}x{H} equirect, {S}^2 faces, {PW}x{PH} view), PSNR dB")
    print(f"{'case':28s} {'ours':>8s} {'py360':>8s}  {'seam/interior rms (ours, py360)':>32s}  {'seam step (ours, py360)':>24s}")
    for k, r in rows.items():
        seam_txt = f"{r['ours_seam']:.2f}, {r['py_seam']:.2f}" if "ours_seam" in r else ""
        step_txt = f"{r['ours_step']:.2f}, {r['py_step']:.2f}" if "ours_step" in r else ""
        print(f"{k:28s} {r['ours_db']:8.1f} {r['py_db']:8.1f}  {seam_txt:>32s}  {step_txt:>24s}")
    print(f"\nSpeed, uint8 RGB, median of {reps} warm calls (ms); ratios: py360/ours (higher = ours "
          f"faster), ours/bare cv2.remap (1.0 = no overhead)")
    print(f"{'case':34s} {'ours':>8s} {'py360':>8s} {'bare':>8s} {'py/ours':>8s} {'ours/bare':>9s} "
          f"{'cold ours':>10s} {'cold py':>8s}")
    for k, r in speed.items():
        print(f"{k:34s} {r['ours'] * 1e3:8.1f} {r['py'] * 1e3:8.1f} {r['bare'] * 1e3:8.1f} "
              f"{r['py'] / r['ours']:8.2f} {r['ours'] / r['bare']:9.2f} {r['cold_ours'] * 1e3:10.0f} "
              f"{r['cold_py'] * 1e3:8.0f}")

    out_dir = RESULTS
    out_dir.mkdir(parents=True, exist_ok=True)
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return 0
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(10, 3.6))
    keys = [k for k in rows if not math.isnan(rows[k]["py_db"])]
    x = np.arange(len(keys))
    a1.bar(x - 0.2, [rows[k]["ours_db"] for k in keys], 0.4, label="panorama")
    a1.bar(x + 0.2, [rows[k]["py_db"] for k in keys], 0.4, label="py360convert 1.0.4")
    a1.set_xticks(x, [k.replace("round trip", "rt") for k in keys], fontsize=7, rotation=35, ha="right")
    a1.set_ylabel("PSNR (dB)")
    a1.set_title("accuracy (higher is better)")
    a1.legend(fontsize=7)
    ks = list(speed)
    x = np.arange(len(ks))
    a2.bar(x - 0.27, [speed[k]["ours"] * 1e3 for k in ks], 0.27, label="panorama")
    a2.bar(x, [speed[k]["bare"] * 1e3 for k in ks], 0.27, label="bare cv2.remap")
    a2.bar(x + 0.27, [speed[k]["py"] * 1e3 for k in ks], 0.27, label="py360convert")
    a2.set_xticks(x, [k.split(" ")[0] + "\n" + k.split("(")[-1].rstrip(")") if "(" in k else k.split(" ")[0]
                      for k in ks], fontsize=7)
    a2.set_ylabel("ms (warm, median)")
    a2.set_title("speed, uint8 RGB (lower is better)")
    a2.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out_dir / "panorama.png", dpi=110)
    print(f"\nfigure: {out_dir / 'panorama.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
