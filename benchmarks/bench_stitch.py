"""Stitched panoramas and ODS (issue #20): accuracy against the ray-traced truth, the two baselines,
seams, vertical disparity, and speed -- all measured in one run.

    python benchmarks/bench_stitch.py                 # accuracy at 1024 x 512, speed at 4096 x 2048
    python benchmarks/bench_stitch.py --quick         # 512 x 256, fewer rows (about a minute)

Scene: ``ibr.synth`` "capture" (a hall around the origin, objects from 0.5 m to 20 m). Sources:
six cube-face views at the capture point, and a ring rig of 8 outward cameras (radius 0.1 m,
110 x 110 degrees). Sources and truth are rendered with 3 x 3 supersampled colour and exact depth
and cached under benchmarks/results/cache/. PSNR (peak 1) over pixels some source saw.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))

from _timing import median_seconds  # noqa: E402

from ibr.base.view import View  # noqa: E402
from ibr.render.ray_raster import rasterize_mesh_rays  # noqa: E402
from ibr.render.rasterize import rasterize_mesh  # noqa: E402
from ibr.render.view_synthesis import source_mesh  # noqa: E402
from ibr.synth import make_scene, render  # noqa: E402
from panorama.stitch import cube_rig, equirect_camera, ods_cameras, ods_from_panorama, ring_rig, stitch_rgbd  # noqa: E402
from panorama.stitch.baselines import slit_boundaries, slit_stitch, strip_stitch  # noqa: E402
from panorama.synth import render_spherical  # noqa: E402

CACHE = HERE / "results" / "cache"
SS = 3


def psnr(a, b, mask) -> float:
    d = (np.asarray(a, np.float64) - np.asarray(b, np.float64))[mask]
    return float(10 * np.log10(1.0 / max(np.mean(d * d), 1e-20)))


def mse(a, b, mask) -> float:
    d = (np.asarray(a, np.float64) - np.asarray(b, np.float64))[mask]
    return float(np.mean(d * d)) if d.size else float("nan")


def _cached(name, make):
    CACHE.mkdir(parents=True, exist_ok=True)
    path = CACHE / f"{name}.npz"
    if path.exists():
        z = np.load(path)
        return tuple(z[k] for k in sorted(z.files))
    out = make()
    np.savez(path, **{f"a{i}": a for i, a in enumerate(out)})
    return out


def sources(scene, rig: str, face: int):
    if rig == "cube":
        cams = cube_rig(face)
    else:
        cams = ring_rig(8, radius=0.1, width=face, height=face, hfov_deg=110.0)
    views = []
    for i, cam in enumerate(cams):
        c, z = _cached(f"{rig}{face}_{i}", lambda cam=cam: (lambda v: (v.color, v.depth))(render(scene, cam, supersample=SS)))
        views.append(View(c, z, cam, f"{rig}{i}"))
    return views


def truth(scene, camera):
    key = f"truth_{camera.eye}_{camera.width}"
    return _cached(key, lambda: render_spherical(scene, camera, supersample=SS))


def band_mask(winner, holes, radius):
    """Pixels within ``radius`` px of a change of winning source (both sides), covered only."""
    w = winner.astype(np.int32)
    edge = np.zeros(w.shape, bool)
    edge[:, 1:] |= w[:, 1:] != w[:, :-1]
    edge[:, :-1] |= w[:, 1:] != w[:, :-1]
    edge[1:] |= w[1:] != w[:-1]
    edge[:-1] |= w[1:] != w[:-1]
    edge &= ~holes
    k = cv2.getStructuringElement(cv2.MORPH_RECT, (2 * radius + 1, 2 * radius + 1))
    return cv2.dilate(edge.astype(np.uint8), k).astype(bool) & ~holes


def column_band(width, height, cols, radius):
    m = np.zeros((height, width), bool)
    for c in cols:
        lo, hi = int(math.ceil(c - radius)), int(math.floor(c + radius))
        for u in range(lo, hi + 1):
            m[:, u % width] = True
    return m


def accuracy(args, rows):
    scene = make_scene("capture")
    w = args.width
    eq = equirect_camera(w)
    left, right = ods_cameras(w)
    t_mono = truth(scene, eq)
    t_eyes = [truth(scene, c) for c in (left, right)]
    lat = eq.lat(np.arange(w // 2))[:, None] * np.ones((1, w))
    below_fade = np.abs(lat) <= math.radians(60.0)
    # ceiling: the truth resampled once (half a pixel to the right) against itself
    h = w // 2
    mu, mv = np.meshgrid(np.arange(w, dtype=np.float32) + 0.5, np.arange(h, dtype=np.float32))
    shifted = cv2.remap(t_mono[0], mu, mv, cv2.INTER_LINEAR, borderMode=cv2.BORDER_WRAP)
    rows.append(("ceiling: mono truth vs itself shifted 0.5 px", f"{psnr(shifted, t_mono[0], np.ones((h, w), bool)):.2f} dB", ""))
    results = {}
    for rig, face in (("cube", args.face), ("ring", args.face)):
        views = sources(scene, rig, face)
        r = stitch_rgbd(views, eq)
        cov = ~r.holes
        band = band_mask(r.winner, r.holes, 4)
        interior = cov & ~band
        rows.append((f"mono from {rig} ({len(views)} views)", f"{psnr(r.color, t_mono[0], cov):.2f} dB",
                     f"seen {cov.mean():.1%}; seam band/interior MSE {mse(r.color, t_mono[0], band) / mse(r.color, t_mono[0], interior):.2f}"))
        for cam, tr in zip((left, right), t_eyes):
            e = stitch_rgbd(views, cam)
            cov = ~e.holes
            band = band_mask(e.winner, e.holes, 4)
            ratio = mse(e.color, tr[0], band) / mse(e.color, tr[0], cov & ~band)
            results[(rig, cam.eye)] = (e, tr)
            rows.append((f"ODS {cam.eye} from {rig}", f"{psnr(e.color, tr[0], cov):.2f} dB",
                         f"seen {cov.mean():.1%}; seam band/interior MSE {ratio:.2f}"))
    # one centre RGB-D panorama (the mono truth) -> ODS
    pair = ods_from_panorama(t_mono[0], t_mono[1], fill="background")
    for e, tr in zip(pair.eyes, t_eyes):
        cov = ~e.holes
        rows.append((f"ODS {e.camera.eye} from one centre RGB-D panorama", f"{psnr(e.color, tr[0], cov):.2f} dB",
                     f"disoccluded {e.holes.mean():.2%}; with fill {psnr(e.color, tr[0], np.ones_like(cov)):.2f} dB"))
    # baselines on the ring, per eye, below the fade (slits cannot reach the poles)
    ring = sources(scene, "ring", args.face)
    for cam, tr in zip((left, right), t_eyes):
        ours, _ = results[("ring", cam.eye)]
        m_ours = ~ours.holes & below_fade
        p_ours = psnr(ours.color, tr[0], m_ours)
        strip = strip_stitch(ring, cam)
        m = ~strip.holes & below_fade & ~ours.holes
        rows.append((f"strip stitching without depth, {cam.eye}", f"{psnr(strip.color, tr[0], m):.2f} dB",
                     f"ours {psnr(ours.color, tr[0], m):.2f} dB on the same pixels: {psnr(ours.color, tr[0], m) - psnr(strip.color, tr[0], m):+.2f} dB"))
        for n in args.slits:
            t0 = time.perf_counter()
            sl = slit_stitch(ring, cam, n)
            dt = time.perf_counter() - t0
            m = ~sl.holes & below_fade & ~ours.holes
            bands = column_band(w, h, slit_boundaries(n, w), 2) & m
            inter = m & ~bands
            rows.append((f"mesh slits N={n}, {cam.eye}", f"{psnr(sl.color, tr[0], m):.2f} dB",
                         f"ours {psnr(ours.color, tr[0], m):.2f} dB ({psnr(ours.color, tr[0], m) - psnr(sl.color, tr[0], m):+.2f}); "
                         f"slit-boundary band/interior MSE {mse(sl.color, tr[0], bands) / mse(sl.color, tr[0], inter):.2f} "
                         f"(ours {mse(ours.color, tr[0], bands) / mse(ours.color, tr[0], inter):.2f}); {dt:.2f} s"))
        rows.append((f"ours, {cam.eye}, |lat| <= 60", f"{p_ours:.2f} dB", ""))
    # vertical disparity: points from the left eye's depth, projected into both eyes
    e, _ = results[("ring", "left")]
    o, d = left.rays_world()
    pts = (o + d * e.depth[..., None])[~e.holes]
    _, vl, _ = left.project(pts)
    _, vr, _ = right.project(pts)
    lat_pts = lat[~e.holes]
    dv = np.abs(vr - vl)
    rows.append(("vertical disparity, |lat| < 60 / all", f"{np.nanmax(dv[np.abs(lat_pts) < math.radians(60)]):.2e} px",
                 f"max over all seen points {np.nanmax(dv):.2e} px"))
    pole = np.abs(lat) >= math.radians(80.0)
    el, er = results[("cube", "left")][0], results[("cube", "right")][0]
    m = pole & ~el.holes & ~er.holes
    rows.append(("poles (|lat| >= 80): left vs right eye", f"{np.abs(el.color.astype(np.float64) - er.color)[m].max():.2e}",
                 "max abs colour difference"))


def speed(args, rows):
    scene = make_scene("capture")
    w = args.speed_width
    ring = sources(scene, "ring", args.face)
    for v in ring:
        source_mesh(v)  # cached meshes
    eq = equirect_camera(w)
    left, right = ods_cameras(w)
    t_mono = median_seconds(lambda: stitch_rgbd(ring, eq), args.repeats)
    t_ods = median_seconds(lambda: (stitch_rgbd(ring, left), stitch_rgbd(ring, right)), args.repeats)
    rows.append((f"mono {w}x{w // 2} from 8 views (cached meshes)", f"{t_mono:.3f} s", "target <= 0.6 s"))
    rows.append((f"ODS both eyes {w}x{w // 2} from 8 views", f"{t_ods:.3f} s", "target <= 1.5 s"))
    # per covered pixel: ray path vs pinhole path, same mesh, same number of target pixels
    v = ring[0]
    mesh = source_mesh(v)
    pin = v.camera.resized(*(2 * np.array(v.camera.shape[::-1])))
    t_pin = median_seconds(lambda: rasterize_mesh(mesh, pin), args.repeats)
    n_pin = rasterize_mesh(mesh, pin).coverage.sum()
    t_ray = median_seconds(lambda: rasterize_mesh_rays(mesh, eq), args.repeats)
    n_ray = rasterize_mesh_rays(mesh, eq).coverage.sum()
    per_pin, per_ray = t_pin / n_pin * 1e9, t_ray / n_ray * 1e9
    rows.append(("rasterize per covered pixel: ray / pinhole", f"{per_ray / per_pin:.2f}x",
                 f"{per_ray:.1f} ns vs {per_pin:.1f} ns (target <= 3x)"))
    for n in args.slits[-1:]:
        t_slit = median_seconds(lambda: slit_stitch(ring, left, n), 1, warm=False)
        t_eye = median_seconds(lambda: stitch_rgbd(ring, left), 1)
        rows.append((f"one eye {w}: mesh slits N={n} / ours", f"{t_slit / t_eye:.1f}x", f"{t_slit:.2f} s vs {t_eye:.2f} s"))


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="512 x 256 accuracy, 2048 x 1024 speed")
    p.add_argument("--width", type=int, default=1024, help="equirect width for the accuracy runs")
    p.add_argument("--speed-width", type=int, default=4096)
    p.add_argument("--face", type=int, default=512, help="source image size")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--slits", type=int, nargs="+", default=[8, 16, 32, 64])
    p.add_argument("--skip-speed", action="store_true")
    p.add_argument("--skip-accuracy", action="store_true")
    args = p.parse_args(argv)
    if args.quick:
        args.width, args.speed_width, args.face, args.repeats, args.slits = 512, 2048, 256, 1, [8, 16]
    rows = []
    if not args.skip_accuracy:
        accuracy(args, rows)
    if not args.skip_speed:
        speed(args, rows)
    wid = max(len(r[0]) for r in rows)
    print(f"{'measure':<{wid}}  {'value':>12}  notes")
    for name, val, note in rows:
        print(f"{name:<{wid}}  {val:>12}  {note}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
