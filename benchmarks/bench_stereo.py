"""Benchmarks and reports of the stereo / HMD part: speed, lens inverse error, time-warp up-conversion.

Run on demand::

    python benchmarks/bench_stereo.py                 # everything
    python benchmarks/bench_stereo.py --only speed    # speed | lens | upconvert

* ``speed``: stereo pair at 1920x1080 (method 2 and method 1), anaglyph composition (channels and
  Dubois), pre-distortion, one time-warp step -- each as a ratio against ``cv2.remap`` of the
  same image measured in the same run (medians of repeats; the machine is shared and noisy).
* ``lens``: error of the seed's closed-form inverse (eq. 7.17 completed as r_d (1 - N/D)) and of
  a 1024-entry lookup table against the exact Newton inverse, over the lens range.
* ``upconvert``: 10 rendered frames per second warped to 60 displayed, per-frame PSNR against
  fully rendered frames, for a pure head turn and a turn with head translation.

Figures go to ``benchmarks/results/``; the ones worth showing are copied to ``docs/img/``.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import time
from pathlib import Path

import cv2
import numpy as np
from scipy.ndimage import maximum_filter1d

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks._timing import median_seconds as median_time  # noqa: E402
from ibr import synth  # noqa: E402
from ibr.stereo.lens import RadialDistortion, distortion_maps, predistort  # noqa: E402
from ibr.stereo.stereo_camera import auto_stereo  # noqa: E402
from ibr.stereo.pair import anaglyph, dubois_anaglyph, stereo_pair  # noqa: E402
from ibr.stereo.timewarp import guard_band_camera, rotation_maps, upconvert, warp_rotation  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
DOCS = ROOT / "docs" / "img"


def _rotated(cam, yaw=0.0, pitch=0.0, roll=0.0):
    from scipy.spatial.transform import Rotation

    pose = cam.world_from_cam.copy()
    pose[:3, :3] = pose[:3, :3] @ Rotation.from_euler("yxz", [yaw, pitch, roll], degrees=True).as_matrix()
    return cam.with_pose(pose)


# ---------------------------------------------------------------------- speed
def bench_speed(repeats: int) -> list[tuple[str, float, float]]:
    w, h = 1920, 1080
    scene = synth.make_scene("room")
    cam, _ = synth.scene_cameras("room", width=w, height=h)
    t0 = time.perf_counter()
    view = synth.render(scene, cam)
    print(f"(source render {w}x{h}: {time.perf_counter() - t0:.1f} s, not timed below)")
    color = view.color  # float32 RGB
    color8 = (color * 255).round().astype(np.uint8)
    e, f = auto_stereo(view.depth)

    # baselines: cv2.remap of the same image with a generic float map (a 0.3 px shift)
    v, u = np.mgrid[0:h, 0:w].astype(np.float32)
    mx, my = u + 0.3, v + 0.2
    base_f = median_time(lambda: cv2.remap(color, mx, my, cv2.INTER_LINEAR), repeats)
    base_8 = median_time(lambda: cv2.remap(color8, mx, my, cv2.INTER_LINEAR), repeats)

    pair = stereo_pair(view, e=e, f=f)
    lens = RadialDistortion(0.22, 0.24, 1.5)
    lmx, lmy = distortion_maps(w, h, lens)
    band = guard_band_camera(cam, margin_px=64)
    band_img = cv2.copyMakeBorder(color, 64, 64, 64, 64, cv2.BORDER_REFLECT)
    dst = _rotated(cam, 2.0, -1.0, 0.5)

    rows = [
        ("cv2.remap float32 RGB (baseline)", base_f, base_f),
        ("cv2.remap uint8 RGB (baseline)", base_8, base_8),
        ("stereo pair, method 2 (both eyes + fill)", median_time(lambda: stereo_pair(view, e=e, f=f), repeats), base_f),
        ("stereo pair, method 1 mesh (both eyes + fill)",
         median_time(lambda: stereo_pair(view, e=e, f=f, method="mesh"), max(1, repeats // 2)), base_f),
        ("anaglyph by channels, uint8", median_time(lambda: anaglyph(color8, color8), repeats), base_8),
        ("Dubois anaglyph, uint8", median_time(lambda: dubois_anaglyph(color8, color8), max(1, repeats // 2)), base_8),
        ("pre-distortion, maps cached (1 remap)",
         median_time(lambda: cv2.remap(pair.left, lmx, lmy, cv2.INTER_LINEAR), repeats), base_f),
        ("pre-distortion incl. maps (predistort)", median_time(lambda: predistort(pair.left, lens), repeats), base_f),
        ("pre-distortion, chromatic (3 maps)",
         median_time(lambda: predistort(pair.left, (RadialDistortion(0.23, 0.24), lens, RadialDistortion(0.21, 0.24))),
                     max(1, repeats // 2)), base_f),
        ("time-warp step (warpPerspective + band mask)", median_time(lambda: warp_rotation(band_img, band, dst), repeats), base_f),
        ("time-warp, explicit maps (fallback path)", median_time(lambda: rotation_maps(band, dst), repeats), base_f),
    ]
    print(f"\n{'operation at 1920x1080':48s} {'median ms':>10s} {'x remap':>8s}")
    for name, t, b in rows:
        print(f"{name:48s} {t * 1e3:10.2f} {t / b:8.2f}")
    return rows


# ---------------------------------------------------------------------- lens
def report_lens(plt) -> None:
    cases = [("c1=0.22, c2=0.24 (HMD pincushion)", RadialDistortion(0.22, 0.24, 1.2)),
             ("c1=0.10, c2=0.02 (mild)", RadialDistortion(0.10, 0.02, 1.2)),
             ("c1=-0.20, c2=0.03 (barrel)", RadialDistortion(-0.20, 0.03, 1.2))]
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    print(f"\n{'lens':36s} {'|approx err| at r_u = 0.25  0.5   0.75  1.0':>46s} {'LUT max':>9s} {'Newton max':>11s}")
    for (label, lens), color in zip(cases, ("C0", "C1", "C2")):
        r_u = np.linspace(0, lens.r_max, 4001)
        r_d = lens.distort(r_u)
        err_a = np.abs(lens.undistort(r_d, method="approx") - r_u)
        err_l = np.abs(lens.undistort(r_d, method="lut", lut_size=1024) - r_u)
        err_n = np.abs(lens.undistort(r_d) - r_u)
        at = [err_a[np.argmin(np.abs(r_u - x))] for x in (0.25, 0.5, 0.75, 1.0)]
        print(f"{label:36s} {'  '.join(f'{a:9.2e}' for a in at):>46s} {err_l.max():9.1e} {err_n.max():11.1e}")
        ax.semilogy(r_u[1:], np.maximum(err_a[1:], 1e-17), color=color, label=f"eq. 7.17 approx, {label}")
        env = maximum_filter1d(err_l, 101)  # local maximum: the LUT error oscillates between nodes
        ax.semilogy(r_u[1:], np.maximum(env[1:], 1e-17), color=color, ls=":", lw=1,
                    label="lookup table, 1024 entries (local max)" if color == "C0" else None)
    ax.axhline(1e-9, color="k", lw=0.8, ls="--", label="Newton target 1e-9 (reached: < 1e-15)")
    ax.set_xlabel("undistorted normalized radius r_u")
    ax.set_ylabel("|r_u estimate - r_u| (normalized radius)")
    ax.set_title("Inverse radial distortion: error vs the exact (Newton) inverse")
    ax.set_ylim(1e-16, 10)
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    out = RESULTS / "lens_inverse_error.png"
    fig.savefig(out, dpi=100)
    shutil.copy(out, DOCS / out.name)
    print(f"wrote {out} (copied to docs/img)")


# ---------------------------------------------------------------------- up-conversion
def report_upconvert(plt) -> None:
    scene = synth.make_scene("room")
    disp, _ = synth.scene_cameras("room", width=256, height=192)
    n = 30  # half a second at 60 Hz; a rendered frame every 6th (10 Hz)
    turn = [_rotated(disp, yaw=0.4 * i, pitch=-0.15 * i) for i in range(n)]  # 24 deg/s head turn
    move = [_rotated(disp.translated([0.004 * i, 0, 0.002 * i]), yaw=0.4 * i) for i in range(n)]  # + 0.24 m/s

    def render(c):
        return synth.render(scene, c, supersample=2)

    def ref(c):
        return synth.render(scene, c, supersample=2).color

    runs = {
        "head turn, rotation warp": upconvert(render, turn, every=6, margin_px=24, mode="rotation", reference=ref),
        "turn + translation, rotation-only warp": upconvert(render, move, every=6, margin_px=24, mode="rotation", reference=ref),
        "turn + translation, depth warp": upconvert(render, move, every=6, margin_px=24, mode="depth", reference=ref),
    }
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    print("\nframe-rate up-conversion 10 -> 60 fps, 256x192, PSNR (dB) of warped frames vs full renders")
    for name, res in runs.items():
        p = np.minimum(res.psnr_db, 45)
        warped = p[~res.rendered]
        print(f"  {name:40s} warped frames: min {warped.min():5.1f}  median {np.median(warped):5.1f}  "
              f"(per frame: {' '.join(f'{x:.1f}' for x in p[:12])} ...)")
        ax.plot(np.arange(n), p, marker=".", label=name)
    ax.set_xlabel("display frame (60 Hz); frames 0, 6, 12, ... rendered (exact crops, shown at the cap)")
    ax.set_ylabel("PSNR vs full render (dB), capped at 45")
    ax.set_title("Time-warp up-conversion 10 -> 60 fps (room scene)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    out = RESULTS / "timewarp_upconvert.png"
    fig.savefig(out, dpi=100)
    shutil.copy(out, DOCS / out.name)
    print(f"wrote {out} (copied to docs/img)")


def plot_speed(plt, rows) -> None:
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    names = [r[0] for r in rows]
    ratios = [r[1] / r[2] for r in rows]
    ax.barh(names[::-1], ratios[::-1], color="C0")
    ax.axvline(1, color="k", lw=0.8)
    ax.set_xscale("log")
    ax.set_xlabel("time / cv2.remap of the same 1920x1080 image (same run)")
    ax.tick_params(axis="y", labelsize=7)
    fig.tight_layout()
    fig.savefig(RESULTS / "stereo_speed.png", dpi=100)
    print(f"wrote {RESULTS / 'stereo_speed.png'}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", choices=("speed", "lens", "upconvert"), default=None)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--quick", action="store_true", help="speed table only, 3 repeats (ibr bench)")
    args = ap.parse_args(argv)
    if args.quick:
        args.only, args.repeats = args.only or "speed", min(args.repeats, 3)
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:  # the speed table needs no plot (ibr bench without the bench extra)
        if args.only != "speed":
            raise
        plt = None

    RESULTS.mkdir(parents=True, exist_ok=True)
    DOCS.mkdir(parents=True, exist_ok=True)
    if args.only in (None, "lens"):
        report_lens(plt)
    if args.only in (None, "speed"):
        rows = bench_speed(args.repeats)
        if plt is not None:
            plot_speed(plt, rows)
    if args.only in (None, "upconvert"):
        report_upconvert(plt)
    return 0


if __name__ == "__main__":
    sys.exit(main())
