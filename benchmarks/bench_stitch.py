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

from _timing import median_seconds, paired_ms  # noqa: E402

from ibr.base.camera import Camera  # noqa: E402
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


def depth_edges(rng, radius):
    """Pixels within ``radius`` px of a depth discontinuity of the truth (|d log range| > 0.05)."""
    lr = np.log(rng)
    g = np.zeros(rng.shape, bool)
    g[:, 1:] |= np.abs(np.diff(lr, axis=1)) > 0.05
    g[1:] |= np.abs(np.diff(lr, axis=0)) > 0.05
    k = np.ones((2 * radius + 1, 2 * radius + 1), np.uint8)
    return cv2.dilate(g.astype(np.uint8), k).astype(bool)


def seam_ratio(color, tr, winner, holes):
    """(raw, away from depth edges) MSE ratio of the +-4 px band around winner changes to the rest.

    Winner changes at occlusion boundaries are silhouettes, not seams between sources: the second
    figure leaves out pixels within 4 px of the truth's depth edges from both band and interior."""
    band = band_mask(winner, holes, 4)
    cov = ~holes
    raw = mse(color, tr[0], band) / mse(color, tr[0], cov & ~band)
    e = depth_edges(tr[1], 4)
    clean = mse(color, tr[0], band & ~e) / mse(color, tr[0], cov & ~band & ~e)
    return raw, clean


def exact_geometry_resample(views, camera, tr):
    """Ceiling of any method that resamples the sources once: each target pixel's true surface
    point (the truth's range along its ray) projected into every source that sees it (depth
    within 1 %), sampled bilinearly, averaged with the 16-px border feather. Returns (colour,
    mask of pixels some source sees)."""
    o, d = camera.rays_world()
    pts = (o + tr[1][..., None] * d).reshape(-1, 3)
    acc = np.zeros(tr[0].shape, np.float64)
    acc_w = np.zeros(tr[1].shape)
    for v in views:
        uv, z = v.camera.project(pts)
        uv = uv.reshape(*tr[1].shape, 2).astype(np.float32)
        z = z.reshape(tr[1].shape)
        col = cv2.remap(v.color.astype(np.float32), uv[..., 0], uv[..., 1], cv2.INTER_LINEAR,
                        borderMode=cv2.BORDER_REPLICATE)
        zs = cv2.remap(v.depth.astype(np.float32), uv[..., 0], uv[..., 1], cv2.INTER_NEAREST,
                       borderMode=cv2.BORDER_REPLICATE)
        hh, ww = v.depth.shape
        border = np.minimum(np.minimum(uv[..., 0] + 0.5, ww - 0.5 - uv[..., 0]),
                            np.minimum(uv[..., 1] + 0.5, hh - 0.5 - uv[..., 1]))
        with np.errstate(invalid="ignore"):
            seen = (border > 0) & (z > 0) & (np.abs(zs - z) < 0.01 * z)
        wt = np.where(seen, np.clip(border / 16.0, 1e-3, 1.0), 0.0)
        acc += np.where(seen[..., None], wt[..., None] * col, 0.0)
        acc_w += wt
    return acc / np.maximum(acc_w, 1e-12)[..., None], acc_w > 0


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
    for rig, face in (("cube", args.face), ("ring", args.face), ("ring", args.ring_fine)):
        views = sources(scene, rig, face)
        r = stitch_rgbd(views, eq)
        cov = ~r.holes
        off = cov & ~depth_edges(t_mono[1], 1)
        raw, clean = seam_ratio(r.color, t_mono, r.winner, r.holes)
        rows.append((f"mono from {rig} ({len(views)} views of {face}^2)", f"{psnr(r.color, t_mono[0], cov):.2f} dB",
                     f"seen {cov.mean():.1%}; off +-1 px of depth edges {psnr(r.color, t_mono[0], off):.2f} dB; "
                     f"seam band/interior MSE {clean:.2f} (incl. silhouettes {raw:.2f})"))
        ceil_col, ceil_seen = exact_geometry_resample(views, eq, t_mono)
        both = ceil_seen & ~r.holes
        rows.append((f"  ceiling: {rig} sources resampled once at the exact geometry",
                     f"{psnr(ceil_col, t_mono[0], both):.2f} dB", f"ours {psnr(r.color, t_mono[0], both):.2f} dB on the same pixels"))
        for cam, tr in zip((left, right), t_eyes):
            e = stitch_rgbd(views, cam)
            cov = ~e.holes
            raw, clean = seam_ratio(e.color, tr, e.winner, e.holes)
            results[(rig, face, cam.eye)] = (e, tr)
            rows.append((f"ODS {cam.eye} from {rig} {face}^2", f"{psnr(e.color, tr[0], cov):.2f} dB",
                         f"seen {cov.mean():.1%}; seam band/interior MSE {clean:.2f} (incl. silhouettes {raw:.2f})"))
    # what no ring camera saw (the polar caps): the directional fill against the panorama fill
    from ibr.render.fill import fill_background
    from panorama.stitch.fill import fill_panorama

    for eye in ("left", "right"):
        e, tr = results[("ring", args.face, eye)]
        if e.holes.any():
            old, _, _ = fill_background(e.color, e.depth, e.holes)
            new, _, _ = fill_panorama(e.color, e.depth, e.holes)
            rows.append((f"ODS {eye} from ring {args.face}^2, unseen {e.holes.mean():.1%}: panorama fill",
                         f"{psnr(new, tr[0], e.holes):.2f} dB", f"directional fill {psnr(old, tr[0], e.holes):.2f} dB "
                         "on the same hole pixels (streaks in the caps)"))
    # one centre RGB-D panorama (the mono truth) -> ODS
    pair = ods_from_panorama(t_mono[0], t_mono[1], fill="background")
    for e, tr in zip(pair.eyes, t_eyes):
        cov = ~e.holes
        rows.append((f"ODS {e.camera.eye} from one centre RGB-D panorama", f"{psnr(e.color, tr[0], cov):.2f} dB",
                     f"disoccluded {e.holes.mean():.2%}; with fill {psnr(e.color, tr[0], np.ones_like(cov)):.2f} dB"))
    # baselines on the ring, per eye, below the fade (slits cannot reach the poles)
    ring = sources(scene, "ring", args.face)
    for cam, tr in zip((left, right), t_eyes):
        ours, _ = results[("ring", args.face, cam.eye)]
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
    e, _ = results[("ring", args.face, "left")]
    o, d = left.rays_world()
    pts = (o + d * e.depth[..., None])[~e.holes]
    _, vl, _ = left.project(pts)
    _, vr, _ = right.project(pts)
    lat_pts = lat[~e.holes]
    dv = np.abs(vr - vl)
    rows.append(("vertical disparity, |lat| < 60 / all", f"{np.nanmax(dv[np.abs(lat_pts) < math.radians(60)]):.2e} px",
                 f"max over all seen points {np.nanmax(dv):.2e} px"))
    pole = np.abs(lat) >= math.radians(80.0)
    el, er = results[("cube", args.face, "left")][0], results[("cube", args.face, "right")][0]
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
    img = np.random.default_rng(0).random((w // 2, w, 3), dtype=np.float32)
    mx, my = np.meshgrid(np.arange(w, dtype=np.float32) + 0.3, np.arange(w // 2, dtype=np.float32) + 0.3)
    t_remap = median_seconds(lambda: cv2.remap(img, mx, my, cv2.INTER_LINEAR), args.repeats)
    t_mono = median_seconds(lambda: stitch_rgbd(ring, eq), args.repeats)
    t_ods = median_seconds(lambda: (stitch_rgbd(ring, left), stitch_rgbd(ring, right)), args.repeats)
    rows.append((f"baseline: one cv2.remap of {w}x{w // 2} RGB float32", f"{t_remap * 1e3:.1f} ms", ""))
    rows.append((f"mono {w}x{w // 2} from 8 views (cached meshes)", f"{t_mono:.3f} s",
                 f"{t_mono / t_remap:.0f}x one remap; target <= 0.6 s"))
    rows.append((f"ODS both eyes {w}x{w // 2} from 8 views", f"{t_ods:.3f} s",
                 f"{t_ods / t_remap:.0f}x one remap; target <= 1.5 s"))
    # per covered pixel: ray path vs pinhole path, same mesh, same angular resolution: the pinhole
    # target sits at the rig centre, looks where the source looks, with f = W / 2 pi px per radian
    v = ring[0]
    mesh = source_mesh(v)
    f = w / (2 * math.pi)
    size = int(2 * f * math.tan(math.radians(55.0)))
    pose = v.camera.world_from_cam.copy()
    pose[:3, 3] = 0.0
    pin = Camera(f, f, (size - 1) / 2, (size - 1) / 2, size, size, pose)
    n_pin = rasterize_mesh(mesh, pin).coverage.sum()
    n_ray = rasterize_mesh_rays(mesh, eq).coverage.sum()
    # the ray path as the stitcher runs it (only the region the quads can reach is written), and as
    # a standalone full-frame call (also marks the other ~84 % of the equirect uncovered)
    for label, kw in (("ray path as stitched (quads' region)", {"_region": []}), ("ray path, full frame", {})):
        ms_ray, ratio = paired_ms(lambda: rasterize_mesh_rays(mesh, eq, **kw), lambda: rasterize_mesh(mesh, pin),
                                  max(5, 3 * args.repeats))
        per_ray = ms_ray * 1e6 / n_ray
        per_ratio = ratio * n_pin / n_ray
        rows.append((f"per covered pixel, {label} / pinhole", f"{per_ratio:.2f}x",
                     f"{per_ray:.1f} ns vs {per_ray / per_ratio:.1f} ns, paired (target <= 3x)"))
    for n in args.slits[-1:]:
        t_slit = median_seconds(lambda: slit_stitch(ring, left, n), 1, warm=False)
        t_eye = median_seconds(lambda: stitch_rgbd(ring, left), 1)
        rows.append((f"one eye {w}: mesh slits N={n} / ours", f"{t_slit / t_eye:.1f}x", f"{t_slit:.2f} s vs {t_eye:.2f} s"))


def figure(args, path):
    """Picture: left-eye crops at a near object -- truth, ours, mesh slits N=8, strip stitching --
    and the top-bottom ODS pair of the ring below them."""
    scene = make_scene("capture")
    w = args.width
    left, right = ods_cameras(w)
    ring = sources(scene, "ring", args.face)
    tr = truth(scene, left)[0]
    ours = stitch_rgbd(ring, left).color
    slit = slit_stitch(ring, left, 8).color
    strip = strip_stitch(ring, left).color
    h = w // 2
    v0, v1, u0, u1 = int(0.42 * h), int(0.60 * h), int(0.60 * w), int(0.72 * w)  # a slit boundary at 0.625 w
    def label(img, text):
        img = np.repeat(np.repeat(img, 2, 0), 2, 1)  # 2x nearest: see the pixels
        img = np.ascontiguousarray((np.clip(img, 0, 1) * 255).astype(np.uint8))
        cv2.putText(img, text, (6, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.55, (255, 255, 255), 2, cv2.LINE_AA)
        return img
    crops = [label(a[v0:v1, u0:u1], t) for a, t in ((tr, "truth"), (ours, "ours (ray camera)"),
                                                    (slit, "mesh slits N=8"), (strip, "strips, no depth"))]
    top = np.concatenate([np.concatenate(crops[:2], 1), np.concatenate(crops[2:], 1)], 0)
    pair = np.concatenate([ours, stitch_rgbd(ring, right).color], 0)
    pair = cv2.resize(np.clip(pair, 0, 1), (top.shape[1], top.shape[1]), interpolation=cv2.INTER_AREA)
    out = np.concatenate([top, (pair * 255).astype(np.uint8)], 0)
    cv2.imwrite(str(path), out[..., ::-1])
    print(f"wrote {path}")


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="512 x 256 accuracy, 2048 x 1024 speed")
    p.add_argument("--width", type=int, default=1024, help="equirect width for the accuracy runs")
    p.add_argument("--speed-width", type=int, default=4096)
    p.add_argument("--face", type=int, default=512, help="source image size")
    p.add_argument("--ring-fine", type=int, default=736,
                   help="ring source size at the cube faces' angular resolution (256 px/rad at 110 deg)")
    p.add_argument("--repeats", type=int, default=3)
    p.add_argument("--slits", type=int, nargs="+", default=[8, 16, 32, 64])
    p.add_argument("--skip-speed", action="store_true")
    p.add_argument("--skip-accuracy", action="store_true")
    p.add_argument("--figure", metavar="PNG", help="also write the comparison picture (docs/img/stitch_ods.png)")
    args = p.parse_args(argv)
    if args.quick:
        args.width, args.speed_width, args.face, args.repeats, args.slits = 512, 2048, 256, 1, [8, 16]
    rows = []
    if args.figure:
        figure(args, args.figure)
    if not args.skip_accuracy:
        accuracy(args, rows)
    if not args.skip_speed:
        speed(args, rows)
    if not rows:
        return 0
    wid = max(len(r[0]) for r in rows)
    print(f"{'measure':<{wid}}  {'value':>12}  notes")
    for name, val, note in rows:
        print(f"{name:<{wid}}  {val:>12}  {note}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
