"""Benchmark of the adaptive quad mesh (issue 3): quads, one-pixel share, time, error.

Run from the repository root::

    python benchmarks/bench_mesh.py            # all scenes, incl. a 1920x1080 render (cached)
    python benchmarks/bench_mesh.py --quick    # skip the 1920x1080 scene and the sweep plot
    python benchmarks/bench_mesh.py --timing --repeats 41 --baseline HEAD~2
                                               # timing targets only (room 512x512, 1920x1080),
                                               # this tree against a git revision, same run

For every scene (synthetic room / clutter / grazing from ``ibr.synth``, the Middlebury
motorcycle, and the room at 512x512 and 1920x1080 for the timing targets) and every method and
level of detail it prints: quads (and % of pixels), the share of one-pixel quads, the median
time of z' + Δ²/break edges + split (numba caches warm), that time as a ratio to
``cv2.Laplacian`` on the same float32 depth measured in the same run, and the mesh error
against the input depth: max and 99th-percentile reprojection error in pixels for a camera
move of one baseline (f · b · |Δ(1/z)|, b = 5% of the median depth, the default of
``build_mesh``) and max relative depth error |Δz|/z.

Targets (issue 3): 512x512 in <= 5 ms, 1920x1080 in <= 25 ms; room <= 0.5% of pixels as quads;
motorcycle <= 10% of pixels at the default bound (<= 0.5 px for one baseline).

Writes ``benchmarks/results/mesh_quads_vs_error.png`` (copied to ``docs/img/``) and
``benchmarks/results/mesh_motorcycle_segmentation.png`` (crop copied to ``docs/img/``).
"""

from __future__ import annotations

import argparse
import atexit
import importlib
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import cv2  # noqa: E402
from benchmarks._timing import median_ms, paired_ms  # noqa: E402

from ibr.mesh import segment as S  # noqa: E402
from ibr.mesh.quad_mesh import _mesh_from_segmentation, segmentation_image  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
DOCS = ROOT / "docs" / "img"


def room_view(width: int, height: int):
    """The room scene rendered at another size (1920x1080 depth cached in benchmarks/results)."""
    from ibr import synth
    from ibr.base.view import View

    cam, _ = synth.scene_cameras("room", width=width, height=height)
    cache = RESULTS / f"room_{width}x{height}_depth.npy"
    if cache.exists():
        depth = np.load(cache)
    else:
        depth = synth.render(synth.make_scene("room"), cam).depth
        if width * height > 10**6:
            np.save(cache, depth)
    return View(np.zeros((*depth.shape, 3), np.uint8), depth, cam, f"room{width}x{height}")


def load_scenes(quick: bool):
    from ibr import synth
    from ibr.io.middlebury import motorcycle_views

    scenes = {}
    for name in ("room", "clutter", "grazing"):
        cam, _ = synth.scene_cameras(name)
        scenes[name] = synth.render(synth.make_scene(name), cam)
    scenes["motorcycle"] = motorcycle_views()[0]
    cam, _ = synth.scene_cameras("room", width=512, height=512)
    scenes["room 512x512"] = synth.render(synth.make_scene("room"), cam)
    if not quick:
        scenes["room 1920x1080"] = room_view(1920, 1080)
    return scenes


def mesh_errors(view, seg):
    mesh = _mesh_from_segmentation(view.camera, view.depth, seg, time.perf_counter())
    z = view.depth.astype(np.float64)
    ok = mesh.quad_of_pixel >= 0
    h, w = z.shape
    v, u = np.mgrid[0:h, 0:w]
    p = mesh.inv_depth_planes[mesh.quad_of_pixel[ok]]
    q = p[:, 0] * u[ok] + p[:, 1] * v[ok] + p[:, 2]
    dq = np.abs(q - 1 / z[ok])
    baseline = S.DEFAULT_BASELINE_FRACTION * float(np.nanmedian(z))
    f = max(view.camera.fx, view.camera.fy)
    px = f * baseline * dq
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.abs(1 / q - z[ok]) / z[ok]
    return mesh, float(px.max()), float(np.percentile(px, 99)), float(np.nanmax(rel))


SETTINGS = [
    ("paper", {"threshold": 2.0**11}, "T=2^11"),
    ("paper", {"threshold": 2.0**15}, "T=2^15"),
    ("paper", {"threshold": 2.0**18}, "T=2^18"),
    ("paper", {"max_error_px": 0.5}, "T(0.5px)"),
    ("separate", {"threshold": 2.0**15}, "T=2^15"),
    ("separate", {"max_error_px": 0.5}, "T(0.5px)"),
    ("edge", {"threshold": 2.0**15}, "T=2^15"),
    ("edge", {"max_error_px": 0.25}, "0.25px"),
    ("edge", {"max_error_px": 0.5}, "0.5px*"),
    ("edge", {"max_error_px": 1.0}, "1px"),
    ("edge", {"max_error_px": 2.0}, "2px"),
]


def table(scenes, repeats):
    rows = []
    header = (f"{'scene':<15} {'method':<9} {'LOD':<9} {'quads':>7} {'%px':>7} {'1px':>6} "
              f"{'ms':>7} {'x cv2.Lap':>9} {'max px':>8} {'p99 px':>7} {'max dz/z':>9}")
    print(header)
    print("-" * len(header))
    for name, view in scenes.items():
        z = view.depth
        zf = np.nan_to_num(z).astype(np.float32)
        lap = median_ms(lambda: cv2.Laplacian(zf, cv2.CV_32F), repeats)
        for method, kw, label in SETTINGS:
            if name.startswith("room ") and not (method == "edge" and label == "0.5px*") and not (
                method == "paper" and label == "T=2^15"
            ):
                continue  # timing-only scenes: the default and the literal method
            seg = S.segment(z, camera=view.camera, method=method, **kw)
            ms = median_ms(lambda: S.segment(z, camera=view.camera, method=method, **kw), repeats)
            mesh, pxmax, px99, rel = mesh_errors(view, seg)
            n = z.size
            row = dict(scene=name, method=method, lod=label, quads=len(mesh), share=len(mesh) / n,
                       one=mesh.one_pixel_share, ms=ms, ratio=ms / lap, pxmax=pxmax, px99=px99, rel=rel,
                       lap_ms=lap)
            rows.append(row)
            print(f"{name:<15} {method:<9} {label:<9} {row['quads']:>7} {row['share']:>7.2%} {row['one']:>6.1%} "
                  f"{ms:>7.2f} {row['ratio']:>9.1f} {pxmax:>8.3f} {px99:>7.3f} {rel:>9.2e}")
        print(f"{'':<15} cv2.Laplacian float32 on the same depth: {lap:.3f} ms")
    return rows


def sweep_plot(scenes):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = ["motorcycle", "room", "clutter"]
    fig, axes = plt.subplots(1, len(names), figsize=(4.2 * len(names), 3.6))
    for ax, name in zip(axes, names):
        view = scenes[name]
        z = view.depth
        for method, style in (("paper", "o-"), ("separate", "s-"), ("edge", "^-")):
            xs, ys = [], []
            if method == "edge":
                params = [{"max_error_px": e} for e in (0.1, 0.2, 0.35, 0.5, 0.7, 1.0, 1.5, 2.0, 3.0, 4.0)]
            else:
                params = [{"threshold": 2.0**k} for k in range(10, 22)]
            for kw in params:
                seg = S.segment(z, camera=view.camera, method=method, **kw)
                _, pxmax, px99, _ = mesh_errors(view, seg)
                xs.append(px99)
                ys.append(100 * len(seg.rects) / z.size)
            ax.loglog(xs, ys, style, ms=3, label=method + (" (default)" if method == "edge" else ""))
        ax.axvline(0.5, color="gray", lw=0.8, ls="--")
        ax.set_title(name)
        ax.set_xlabel("99th pct reprojection error [px], one baseline")
        ax.set_ylabel("quads [% of pixels]")
        ax.grid(True, which="both", lw=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    out = RESULTS / "mesh_quads_vs_error.png"
    fig.savefig(out, dpi=90)
    shutil.copy(out, DOCS / out.name)
    print(f"wrote {out} (copied to docs/img)")


def segmentation_figure(scenes):
    view = scenes["motorcycle"]
    panels = []
    for method, kw in (("paper", {"threshold": 2.0**15}), ("edge", {})):
        seg = S.segment(view.depth, camera=view.camera, method=method, **kw)
        mesh = _mesh_from_segmentation(view.camera, view.depth, seg, time.perf_counter())
        img = segmentation_image(mesh, view.color)
        crop = img[140:290, 200:410]
        crop = np.repeat(np.repeat(crop, 2, 0), 2, 1)
        label = f"{method} {'2^15' if kw else '0.5 px'}: {len(mesh)} quads, {mesh.one_pixel_share:.0%} one-pixel"
        crop[:26] = 0
        cv2.putText(crop, label, (6, 18), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (255, 255, 255), 1, cv2.LINE_AA)
        panels.append(crop)
        full = RESULTS / f"mesh_motorcycle_{method}.png"
        cv2.imwrite(str(full), img[..., ::-1])
    pic = np.concatenate([panels[0], np.full((panels[0].shape[0], 6, 3), 255, np.uint8), panels[1]], 1)
    out = RESULTS / "mesh_motorcycle_segmentation.png"
    cv2.imwrite(str(out), pic[..., ::-1], [cv2.IMWRITE_PNG_COMPRESSION, 9])
    shutil.copy(out, DOCS / out.name)
    print(f"wrote {out} (copied to docs/img)")


def baseline_segment(rev: str):
    """``segment`` of the ``ibr`` package at git revision ``rev``, imported from a temporary copy
    (as package ``ibr_<rev>``) so that both versions run in one process."""
    tmp = Path(tempfile.mkdtemp(prefix="bench_mesh_"))
    atexit.register(shutil.rmtree, tmp, ignore_errors=True)
    tar = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "ibr"], check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(tmp)], input=tar, check=True)
    name = "ibr_" + "".join(c if c.isalnum() else "_" for c in rev)
    (tmp / "ibr").rename(tmp / name)
    sys.path.insert(0, str(tmp))
    try:  # ibr.mesh.segment since the stage layout (#9); ibr.segment before
        return importlib.import_module(f"{name}.mesh.segment").segment
    except ModuleNotFoundError:
        return importlib.import_module(f"{name}.segment").segment


def timing_table(repeats: int, baseline: str | None):
    """Timing targets of issue 3: the default segmentation of the room at 512x512 and 1920x1080,
    median ms and the median of paired ratios to ``cv2.Laplacian`` on the same float32 depth;
    with ``baseline`` also that git revision's ``segment`` (same run) and whether the rects agree."""
    versions = {"this tree": S.segment}
    if baseline:
        versions[baseline] = baseline_segment(baseline)
    header = f"{'scene':<15} {'code':<12} {'quads':>6} {'ms':>7} {'x cv2.Lap':>9} {'same rects':>10}"
    print(header)
    print("-" * len(header))
    for w, h in ((512, 512), (1920, 1080)):
        view = room_view(w, h)
        z = view.depth
        zf = np.nan_to_num(z).astype(np.float32)
        ref = S.segment(z, camera=view.camera).rects
        for code, seg_fn in versions.items():
            rects = seg_fn(z, camera=view.camera).rects
            ms, ratio = paired_ms(lambda: seg_fn(z, camera=view.camera), lambda: cv2.Laplacian(zf, cv2.CV_32F), repeats)
            same = "yes" if np.array_equal(rects, ref) else "NO"
            print(f"{f'room {w}x{h}':<15} {code:<12} {len(rects):>6} {ms:>7.2f} {ratio:>9.1f} {same:>10}")
        lap = median_ms(lambda: cv2.Laplacian(zf, cv2.CV_32F), repeats)
        print(f"{'':<15} cv2.Laplacian float32 on the same depth: {lap:.3f} ms")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the 1920x1080 scene and the plots")
    ap.add_argument("--repeats", type=int, default=9)
    ap.add_argument("--timing", action="store_true", help="only the timing targets (room 512x512, 1920x1080)")
    ap.add_argument("--baseline", metavar="REV", help="with --timing: also time ibr.segment at this git revision")
    args = ap.parse_args(argv)
    RESULTS.mkdir(parents=True, exist_ok=True)
    DOCS.mkdir(parents=True, exist_ok=True)
    if args.timing:
        print(f"single-threaded kernels; repeats {args.repeats}; medians, ratios paired per repeat\n")
        timing_table(args.repeats, args.baseline)
        return 0
    scenes = load_scenes(args.quick)
    print(f"numba threads: single-threaded kernels; repeats {args.repeats}; medians\n")
    table(scenes, args.repeats)
    if not args.quick:
        sweep_plot(scenes)
        segmentation_figure(scenes)
    return 0


if __name__ == "__main__":
    sys.exit(main())
