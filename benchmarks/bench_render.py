"""Speed against error of new-view rendering (issue 4): quad-mesh inverse warp vs forward splat vs
``cv2.warpFrame``, over levels of detail, compositing modes, footprints and fills.

Run from the repository root (``pip install -e ".[bench]"``)::

    python benchmarks/bench_render.py           # full: t = 0.25/0.5/0.75, LOD sweep, 512^2 and 1080p timing
    python benchmarks/bench_render.py --quick   # t = 0.5 only, short sweep, no 1080p (also: ibr bench)

Scenes: the bundled synthetic pairs (room, clutter, grazing; two sources, ground truth from
``samples/data``) and the Middlebury motorcycle (the left view warped to the right camera, compared
with the real right photograph over the pixels each method covers).

Columns: mesh build time (both sources, once per pair) and per-frame time with cached meshes are
reported separately (medians of repeats, numba caches warm); ``x warpFrame`` is the median of the
per-repeat ratios of the frame time to ``cv2.warpFrame`` on the same sources, timed back to back in
each repeat (two warpFrame calls plus the same compositing for the two-source scenes); PSNR over covered pixels (before filling), PSNR
and SSIM of the whole frame after the default fill (skimage.metrics), holes = pixels no source
covered.

Timing targets (issue 4): 512x512 two-source frame <= 8 ms with cached meshes, 1920x1080 <= 60 ms;
mesh build + one frame at 512x512 <= 15 ms.

Writes ``benchmarks/results/render_speed_vs_error.png`` (copied to ``docs/img/``).
"""

from __future__ import annotations

import argparse
import shutil
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import cv2  # noqa: E402
from skimage.metrics import structural_similarity  # noqa: E402

from ibr.render.composite import composite, viewpoint_weights  # noqa: E402
from benchmarks._timing import median_ms, paired_ms  # noqa: E402
from ibr.render.view_synthesis import interpolate, source_mesh, warp  # noqa: E402
from ibr.io import load_view  # noqa: E402
from ibr.render.rasterize import Layer  # noqa: E402
from ibr.base.view import View  # noqa: E402
from samples import DATA_DIR  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
DOCS = ROOT / "docs" / "img"


def psnr(a, b, mask=None) -> float:
    d = (a.astype(np.float64) - b.astype(np.float64)) ** 2
    d = d[mask] if mask is not None else d
    return float(10 * np.log10(255.0**2 / max(d.mean(), 1e-12)))


def ssim(a, b) -> float:
    return float(structural_similarity(b, a, channel_axis=-1, data_range=255))


# ----------------------------------------------------------------------------- cv2.warpFrame
def warpframe_layer(view: View, camera) -> Layer:
    """``cv2.warpFrame`` (OpenCV 5 rgbd) of one source into ``camera`` as a Layer.

    warpFrame takes one intrinsic matrix for both images; a target with another principal point
    (the Middlebury right camera, cx + doffs) is handled exactly by folding the difference into
    the 3x4 ``Rt`` as a shear: ``u' = fx (X' + (dcx / fx) Z') / Z' + cx``.
    """
    src = view.camera
    if (camera.fx, camera.fy, camera.shape) != (src.fx, src.fy, src.shape):
        raise ValueError("warpframe_layer: target must share fx, fy and size with the source")
    rt = camera.cam_from_world @ src.world_from_cam
    rt[0, :3] += (camera.cx - src.cx) / src.fx * rt[2, :3]
    rt[0, 3] += (camera.cx - src.cx) / src.fx * rt[2, 3]
    rt[1, :3] += (camera.cy - src.cy) / src.fy * rt[2, :3]
    rt[1, 3] += (camera.cy - src.cy) / src.fy * rt[2, 3]
    depth = np.nan_to_num(view.depth, nan=0.0).astype(np.float32)
    img = np.ascontiguousarray(view.color[..., ::-1])  # RGB -> BGR (warpFrame is channel-agnostic)
    wd, wi, wm = cv2.warpFrame(depth, img, None, rt, src.K)
    cov = wm > 0
    z = np.where(cov, wd, np.nan).astype(np.float32)
    return Layer(wi[..., ::-1].astype(np.float32), z, cov)


def warpframe_pair(a: View, b: View, camera):
    la, lb = warpframe_layer(a, camera), warpframe_layer(b, camera)
    w = viewpoint_weights(camera, [a.camera, b.camera])
    return composite([la, lb], w, dtype=np.uint8)


# ----------------------------------------------------------------------------- synthetic pairs
MESH_LODS = [  # (label, build_mesh options); the default is max_error_px=0.5 for a 5% baseline
    ("mesh 0.05px (finest)", {"max_error_px": 0.05}),
    ("mesh 0.5px (default)", {}),
    ("mesh 2px", {"max_error_px": 2.0}),
    ("mesh paper T=2^15", {"method": "paper", "threshold": 2.0**15}),
]


def bench_pair(name, a, b, truths, repeats, quick):
    rows = []
    ts = sorted(truths)
    cams = [truths[t].camera for t in ts]

    def score(results):
        p_cov = np.mean([psnr(r.color, truths[t].color, ~r.holes) for r, t in zip(results, ts)])
        holes = np.mean([r.hole_fraction for r in results])
        return p_cov, holes

    def full_scores(results):
        return (np.mean([psnr(r.color, truths[t].color) for r, t in zip(results, ts)]),
                np.mean([ssim(r.color, truths[t].color) for r, t in zip(results, ts)]))

    # baseline: cv2.warpFrame of both sources + the same blend
    wf_ms = median_ms(lambda: warpframe_pair(a, b, cams[0]), repeats)
    wf = [warpframe_pair(a, b, c) for c in cams]
    wf_p = np.mean([psnr(c.color, truths[t].color, c.coverage) for c, t in zip(wf, ts)])
    wf_h = np.mean([1 - c.coverage.mean() for c in wf])
    rows.append(dict(scene=name, method="cv2.warpFrame x2 + blend", build_ms=0.0, frame_ms=wf_ms, ratio=1.0,
                     psnr_cov=wf_p, psnr=float("nan"), ssim=float("nan"), holes=wf_h))

    lods = MESH_LODS[:2] if quick else MESH_LODS
    variants = [(label, dict(mesh_options=opts)) for label, opts in lods]
    variants += [
        ("mesh, seed compositing (front)", dict(composite_mode="front")),
        ("mesh, footprint surface", dict(footprint="surface")),
        ("mesh, bicubic", dict(interpolation="cubic")),
        ("forward splat (inverse)", dict(method="forward", splat="inverse")),
        ("forward splat (nearest)", dict(method="forward", splat="nearest")),
    ]
    for label, kw in variants:
        opts = kw.get("mesh_options", {})
        build_ms = 0.0
        if kw.get("method", "mesh") == "mesh":
            fa, fb = View(a.color, a.depth, a.camera, a.name), View(b.color, b.depth, b.camera, b.name)
            t0 = time.perf_counter()
            source_mesh(fa, **opts), source_mesh(fb, **opts)
            build_ms = (time.perf_counter() - t0) * 1e3
            a_, b_ = fa, fb
        else:
            a_, b_ = a, b
        frame_ms, ratio = paired_ms(lambda: interpolate(a_, b_, cams[0], fill="none", **kw),
                                    lambda: warpframe_pair(a, b, cams[0]), repeats)
        res = [interpolate(a_, b_, c, fill="none", **kw) for c in cams]
        p_cov, holes = score(res)
        filled = [interpolate(a_, b_, c, fill="inpaint", **kw) for c in cams]
        p_all, s_all = full_scores(filled)
        rows.append(dict(scene=name, method=label, build_ms=build_ms, frame_ms=frame_ms, ratio=ratio,
                         psnr_cov=p_cov, psnr=p_all, ssim=s_all, holes=holes))
    # fills on the sequence (previous frame vs background fill), default mesh
    for fill in ("previous", "inpaint"):
        seq = interpolate(a, b, cams, fill=fill)
        p_all = np.mean([psnr(r.color, truths[t].color) for r, t in zip(seq, ts)])
        rows.append(dict(scene=name, method=f"mesh, sequence fill={fill}", build_ms=float("nan"),
                         frame_ms=float("nan"), ratio=float("nan"), psnr_cov=float("nan"), psnr=p_all,
                         ssim=float("nan"), holes=float("nan")))
    return rows


def bench_motorcycle(repeats):
    from ibr.io.middlebury import motorcycle_views

    left, right = motorcycle_views()
    rows = []
    wf_ms = median_ms(lambda: warpframe_layer(left, right.camera), repeats)
    wl = warpframe_layer(left, right.camera)
    wf_p = psnr(wl.color, right.color, wl.coverage)
    rows.append(dict(scene="motorcycle L->R", method="cv2.warpFrame", build_ms=0.0, frame_ms=wf_ms, ratio=1.0,
                     psnr_cov=wf_p, psnr=float("nan"), ssim=float("nan"), holes=1 - wl.coverage.mean()))
    variants = [(label, dict(mesh_options=opts)) for label, opts in MESH_LODS[:2]]
    variants += [
        ("mesh 0.5px at the real baseline", dict(mesh_options={"baseline": 0.193001})),
        ("mesh, footprint surface", dict(footprint="surface")),
        ("forward splat (inverse)", dict(method="forward", splat="inverse")),
        ("forward splat (nearest)", dict(method="forward", splat="nearest")),
    ]
    for label, kw in variants:
        build_ms = 0.0
        src = left
        if kw.get("method", "mesh") == "mesh":
            src = View(left.color, left.depth, left.camera, left.name)
            t0 = time.perf_counter()
            source_mesh(src, **kw.get("mesh_options", {}))
            build_ms = (time.perf_counter() - t0) * 1e3
        frame_ms, ratio = paired_ms(lambda: warp(src, right.camera, fill="none", **kw),
                                    lambda: warpframe_layer(left, right.camera), repeats)
        r = warp(src, right.camera, fill="none", **kw)
        rows.append(dict(scene="motorcycle L->R", method=label, build_ms=build_ms, frame_ms=frame_ms,
                         ratio=ratio, psnr_cov=psnr(r.color, right.color, ~r.holes), psnr=float("nan"),
                         ssim=float("nan"), holes=r.hole_fraction))
    # the same, with mixed (averaged) edge disparities snapped to their color-matched side
    # (ibr.middlebury.snap_mixed_disparity), for the baseline and the default mesh alike
    sl, _ = motorcycle_views(mixed="snap")
    wl = warpframe_layer(sl, right.camera)
    rows.append(dict(scene="motorcycle L->R", method="cv2.warpFrame, mixed snapped", build_ms=0.0,
                     frame_ms=median_ms(lambda: warpframe_layer(sl, right.camera), repeats), ratio=1.0,
                     psnr_cov=psnr(wl.color, right.color, wl.coverage), psnr=float("nan"), ssim=float("nan"),
                     holes=1 - wl.coverage.mean()))
    t0 = time.perf_counter()
    source_mesh(sl)
    build_ms = (time.perf_counter() - t0) * 1e3
    frame_ms, ratio = paired_ms(lambda: warp(sl, right.camera, fill="none"),
                                lambda: warpframe_layer(sl, right.camera), repeats)
    r = warp(sl, right.camera, fill="none")
    rows.append(dict(scene="motorcycle L->R", method="mesh 0.5px, mixed snapped", build_ms=build_ms,
                     frame_ms=frame_ms, ratio=ratio, psnr_cov=psnr(r.color, right.color, ~r.holes),
                     psnr=float("nan"), ssim=float("nan"), holes=r.hole_fraction))
    return rows


# ----------------------------------------------------------------------------- timing targets
def room_pair(width, height):
    """Room scene pair rendered at another size (ray traced once, cached in benchmarks/results)."""
    from ibr import synth

    cam_a, cam_b = synth.scene_cameras("room", width=width, height=height)
    views = []
    for tag, cam in (("a", cam_a), ("b", cam_b)):
        cache = RESULTS / f"render_room_{width}x{height}_{tag}.npz"
        if cache.exists():
            d = np.load(cache)
            views.append(View(d["color"], d["depth"], cam, f"room_{tag}"))
            continue
        v = synth.render(synth.make_scene("room"), cam)
        color = (np.clip(v.color, 0, 1) * 255 + 0.5).astype(np.uint8)
        RESULTS.mkdir(parents=True, exist_ok=True)
        np.savez(cache, color=color, depth=v.depth)
        views.append(View(color, v.depth, cam, f"room_{tag}"))
    return views


def bench_sizes(sizes, repeats):
    from ibr.base.camera import interpolate_cameras
    from ibr.mesh.quad_mesh import build_mesh

    rows = []
    for w, h in sizes:
        a, b = room_pair(w, h)
        cam = interpolate_cameras(a.camera, b.camera, 0.5)
        source_mesh(a), source_mesh(b)
        frame = median_ms(lambda: interpolate(a, b, cam, fill="none"), repeats)
        frame_fill = median_ms(lambda: interpolate(a, b, cam), repeats)
        build = median_ms(lambda: (build_mesh(a), build_mesh(b)), repeats)
        build1 = median_ms(lambda: build_mesh(a), repeats)

        def cold_one():  # mesh build + one frame from a fresh view object (one source)
            fresh = View(a.color, a.depth, a.camera, "fresh")
            warp(fresh, cam, fill="none")

        def cold_two():
            fa = View(a.color, a.depth, a.camera, "fa")
            fb = View(b.color, b.depth, b.camera, "fb")
            interpolate(fa, fb, cam, fill="none")

        wf = median_ms(lambda: warpframe_pair(a, b, cam), repeats)
        rows.append(dict(size=f"{w}x{h}", frame_ms=frame, frame_fill_ms=frame_fill, build2_ms=build,
                         build1_ms=build1, cold1_ms=median_ms(cold_one, repeats),
                         cold2_ms=median_ms(cold_two, repeats), warpframe_ms=wf))
    return rows


# ----------------------------------------------------------------------------- output
def print_table(rows):
    head = f"{'scene':<17} {'method':<34} {'build ms':>8} {'frame ms':>8} {'x warpF':>7} {'PSNR cov':>8} " \
           f"{'PSNR all':>8} {'SSIM':>6} {'holes':>7}"
    print(head)
    print("-" * len(head))
    for r in rows:
        def f(x, fmt):  # not measured for this row: a dash, so the columns stay readable
            return format("-", ">" + fmt.split(".")[0]) if not np.isfinite(x) else format(x, fmt)
        holes = f"{f(100 * r['holes'], '6.2f')}%" if np.isfinite(r["holes"]) else f(r["holes"], "7.2f")
        print(f"{r['scene']:<17} {r['method']:<34} {f(r['build_ms'], '8.1f')} {f(r['frame_ms'], '8.1f')} "
              f"{f(r['ratio'], '7.2f')} {f(r['psnr_cov'], '8.2f')} {f(r['psnr'], '8.2f')} {f(r['ssim'], '6.4f')} "
              f"{holes}")


def plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    fig, axes = plt.subplots(1, len(scenes), figsize=(4.2 * len(scenes), 3.6), squeeze=False)
    for ax, scene in zip(axes[0], scenes):
        for r in rows:
            if r["scene"] != scene or not np.isfinite(r["frame_ms"]):
                continue
            marker = "s" if "warpFrame" in r["method"] else ("^" if "forward" in r["method"] else "o")
            ax.scatter(r["frame_ms"], r["psnr_cov"], marker=marker, s=30 + 300 * r["holes"])
            ax.annotate(r["method"].replace("mesh, ", ""), (r["frame_ms"], r["psnr_cov"]), fontsize=6,
                        xytext=(3, 2), textcoords="offset points")
        ax.set_title(scene, fontsize=9)
        ax.set_xlabel("ms per frame (median, cached meshes)", fontsize=8)
        ax.set_ylabel("PSNR over covered pixels (dB)", fontsize=8)
        ax.grid(alpha=0.3)
        ax.tick_params(labelsize=7)
    fig.suptitle("speed vs error (marker size ~ hole share; o mesh, ^ forward splat, s cv2.warpFrame)", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="t = 0.5 only, 2 LODs, no 1080p, 5 repeats")
    ap.add_argument("--repeats", type=int, default=15, help="timing repeats (median), default %(default)s")
    ap.add_argument("--no-plot", action="store_true", help="skip the matplotlib figure")
    args = ap.parse_args(argv)
    repeats = 5 if args.quick else args.repeats
    import numba

    print(f"threads: numba {numba.get_num_threads()}, OpenCV {cv2.getNumThreads()}; medians of {repeats} repeats")
    rows = []
    for name in ("room", "clutter", "grazing"):
        a = load_view(DATA_DIR / f"{name}_a.json")
        b = load_view(DATA_DIR / f"{name}_b.json")
        ts = (0.5,) if args.quick else (0.25, 0.5, 0.75)
        truths = {t: load_view(DATA_DIR / f"{name}_t{round(t * 100):03d}.json") for t in ts}
        rows += bench_pair(name, a, b, truths, repeats, args.quick)
    rows += bench_motorcycle(repeats)
    print_table(rows)

    sizes = [(512, 512)] if args.quick else [(512, 512), (1920, 1080)]
    print()
    print(f"{'size':<10} {'frame ms':>8} {'+fill ms':>8} {'build 2 ms':>10} {'build 1 ms':>10} "
          f"{'build+frame 1 src':>17} {'build+frame 2 src':>17} {'warpFrame x2 ms':>15}")
    for r in bench_sizes(sizes, repeats):
        print(f"{r['size']:<10} {r['frame_ms']:8.2f} {r['frame_fill_ms']:8.2f} {r['build2_ms']:10.2f} "
              f"{r['build1_ms']:10.2f} {r['cold1_ms']:17.2f} {r['cold2_ms']:17.2f} {r['warpframe_ms']:15.2f}")
    if not args.no_plot:
        RESULTS.mkdir(parents=True, exist_ok=True)
        out = RESULTS / "render_speed_vs_error.png"
        plot(rows, out)
        if not args.quick:
            DOCS.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(out, DOCS / out.name)
        print(f"\nwrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
