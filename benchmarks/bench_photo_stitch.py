"""Photo stitching (issue #16): rotations, PSNR, seams, report cases' cost, and the time for 12
photos of 1280 x 960 -> 8192-wide equirect beside ``cv2.Stitcher``'s default pipeline, one run.

    flock /tmp/ibr-bench.lock python benchmarks/bench_photo_stitch.py            # full (a few minutes)
    flock /tmp/ibr-bench.lock python benchmarks/bench_photo_stitch.py --quick    # small set only

Truth: :func:`panorama.photo.testdata.photo_sphere` (six scikit-image photos as cube faces),
photos cut out of it at known rotations with exposure gains (0.9-1.1, photo 0 at 1) and
Gaussian noise (sigma 1/255), quantized to uint8. PSNR (peak 1) over covered pixels against the
source reduced to the output width (``INTER_AREA``). Seam band: pixels within 8 px of any
photo's footprint edge; interior: the other covered pixels.

Rows:
* small set: 12 photos 400 x 300, hfov 75 deg (8 at pitch 0, 4 at pitch 40) -> 1536-wide.
* big set:   12 photos 1280 x 960, hfov 75 deg (same layout)                 -> 8192-wide.
  (At hfov 60 deg the upper row overlaps the horizon row by 5 deg of latitude and its photos
  not at all with each other: two of them are rightly reported as "little_overlap".)
  Time of ``stitch_photos`` and of ``cv2.Stitcher.create(PANORAMA).stitch`` (OpenCV's defaults:
  ORB features, 0.6 Mpx registration, ray bundle adjustment, wave correction, block gains, graph-cut
  seams, multi-band blending, its own spherical projection at its own scale), back to back.
  OpenCV's rotations are compared after the best global rotation (its frame is arbitrary); ours
  also without any alignment.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

from panorama.photo import compose_equirect, stitch_photos  # noqa: E402
from panorama.photo.testdata import (cut_photos, photo_sphere, psnr, ring_poses,  # noqa: E402
                                     rotation_errors_deg, seam_band)

RESULTS = HERE / "results"


def _aligned_errors(rots, truth) -> np.ndarray:
    """Degrees between estimated and true rotations after the best global rotation G
    (G R_est ~ R_true, Kabsch over all cameras)."""
    m = sum(t @ r.T for r, t in zip(rots, truth))
    u, _, vt = np.linalg.svd(m)
    g = u @ np.diag([1.0, 1.0, np.linalg.det(u @ vt)]) @ vt
    return np.array([np.degrees(np.arccos(np.clip((np.trace((g @ r).T @ t) - 1) / 2, -1, 1)))
                     for r, t in zip(rots, truth)])


def _quality(name, img, cov, ref, band, rows):
    x = img.astype(np.float32) / 255.0 if img.dtype == np.uint8 else img
    rms = lambda m: float(np.sqrt(np.mean((x - ref)[m] ** 2)))  # noqa: E731
    p = psnr(x, ref, cov)
    inner, seams = rms(cov & ~band), rms(cov & band)
    rows.append((f"{name}: PSNR covered", f"{p:.2f} dB", f"covered {100 * cov.mean():.1f}%"))
    rows.append((f"{name}: seam band / interior RMS", f"{seams / inner:.2f}",
                 f"{255 * seams:.2f} vs {255 * inner:.2f} (x/255; target <= 2)"))
    return p


def run_set(label, sphere, width, photo, rows, out, *, stitcher=False):
    poses = ring_poses(((0.0, 8), (40.0, 4)))
    ps = cut_photos(sphere, poses, **photo, gain_spread=0.1, noise=1 / 255, seed=3)
    clean = cut_photos(sphere, poses, **photo, gains=np.ones(len(poses)), noise=0.0)
    ref = cv2.resize(sphere, (width, width // 2), interpolation=cv2.INTER_AREA) \
        if sphere.shape[1] != width else sphere
    band = seam_band(ps.cameras, width, px=8)
    truth = [c.world_from_cam[:3, :3] for c in ps.cameras]

    t0 = time.perf_counter()
    res = stitch_photos(ps.images, width=width, exposure_reference=0)
    t_ours = time.perf_counter() - t0
    err = rotation_errors_deg(res.cameras, ps.cameras)
    err_al = _aligned_errors([c.world_from_cam[:3, :3] for c in res.cameras], truth)
    f_err = max(abs(c.fx / ps.cameras[0].fx - 1) for c in res.cameras)
    rows.append((f"{label}: rotation error, no alignment", f"{err.max():.3f} deg",
                 f"median {np.median(err):.3f}; after best global rotation max {err_al.max():.3f}; "
                 f"focal within {100 * f_err:.2f}% (target 0.2 deg)"))
    p = _quality(f"{label} stitched", res.image, res.coverage, ref, band, rows)
    kp = compose_equirect(ps.images, ps.cameras, width, exposure_reference=0)
    _quality(f"{label} known poses", kp.image, kp.coverage, ref, band, rows)
    ceil = compose_equirect(clean.images, clean.cameras, width, exposure="none")
    _quality(f"{label} ceiling (clean photos, true poses)", ceil.image, ceil.coverage, ref, band, rows)
    out[label] = {"rotation_error_max_deg": float(err.max()), "rotation_error_aligned_max_deg": float(err_al.max()),
                  "psnr_stitched": p, "seconds_ours": t_ours, "stages": res.report.seconds,
                  "report": res.report.table()}
    rows.append((f"{label}: stitch_photos time", f"{t_ours:.2f} s",
                 ", ".join(f"{k} {v:.2f}" for k, v in res.report.seconds.items())))
    if not stitcher:
        return
    bgr = [np.ascontiguousarray(im[..., ::-1]) for im in ps.images]
    st = cv2.Stitcher.create(cv2.Stitcher_PANORAMA)
    t0 = time.perf_counter()
    status, pano = st.stitch(bgr)
    t_cv = time.perf_counter() - t0
    # ours again, right after, so both see the same machine load
    t0 = time.perf_counter()
    stitch_photos(ps.images, width=width, exposure_reference=0)
    t_ours2 = time.perf_counter() - t0
    note = f"status {status}"
    if status == cv2.Stitcher_OK:
        comp = list(st.component())
        rots = [np.asarray(c.R, np.float64) for c in st.cameras()]
        cv_err = _aligned_errors(rots, [truth[k] for k in comp])
        note += (f", used {len(comp)}/12, output {pano.shape[1]}x{pano.shape[0]}, rotation error after best "
                 f"global rotation max {cv_err.max():.3f} deg (median {np.median(cv_err):.3f})")
        out[label]["opencv_rotation_error_aligned_max_deg"] = float(cv_err.max())
        cv2.imwrite(str(RESULTS / "photo_stitch_opencv.jpg"), pano)
    t_mean = 0.5 * (t_ours + t_ours2)
    rows.append((f"{label}: cv2.Stitcher default time", f"{t_cv:.2f} s", note))
    rows.append((f"{label}: ours / cv2.Stitcher", f"{t_mean / t_cv:.2f}x",
                 f"ours {t_ours:.2f} s and {t_ours2:.2f} s (mean {t_mean:.2f}) vs {t_cv:.2f} s"))
    out[label].update({"seconds_opencv": t_cv, "seconds_ours_second_run": t_ours2})
    cv2.imwrite(str(RESULTS / "photo_stitch_ours.jpg"), res.image[..., ::-1])


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="the small set only (about 20 s)")
    p.add_argument("--width", type=int, default=8192, help="output width of the big set")
    p.add_argument("--figure", metavar="PNG", help="also write a picture: ours above OpenCV's stitch (full run)")
    args = p.parse_args(argv)
    RESULTS.mkdir(parents=True, exist_ok=True)
    rows, out = [], {}
    run_set("400x300 -> 1536", photo_sphere(2048), 1536, dict(width=400, height=300, hfov_deg=75.0), rows, out)
    if not args.quick:
        big = photo_sphere(args.width)
        run_set(f"1280x960 -> {args.width}", big, args.width, dict(width=1280, height=960, hfov_deg=75.0),
                rows, out, stitcher=True)
    wid = max(len(r[0]) for r in rows)
    print(f"{'measure':<{wid}}  {'value':>10}  notes")
    for name, val, note in rows:
        print(f"{name:<{wid}}  {val:>10}  {note}")
    (RESULTS / "photo_stitch.json").write_text(json.dumps(out, indent=2, default=float) + "\n")
    if args.figure and not args.quick:
        figure(Path(args.figure))
    return 0


def figure(path: Path, width: int = 1600) -> None:
    """Ours (8192-wide equirect) above OpenCV's default stitch, each reduced to ``width``, labelled."""
    tiles = []
    for name, label in (("photo_stitch_ours.jpg", "ours: stitch_photos -> equirect"),
                        ("photo_stitch_opencv.jpg", "cv2.Stitcher default (its own projection and crop)")):
        img = cv2.imread(str(RESULTS / name))
        if img is None:
            continue
        img = cv2.resize(img, (width, max(1, round(img.shape[0] * width / img.shape[1]))), interpolation=cv2.INTER_AREA)
        cv2.putText(img, label, (12, 34), cv2.FONT_HERSHEY_SIMPLEX, 1.0, (0, 0, 0), 5, cv2.LINE_AA)
        cv2.putText(img, label, (12, 34), cv2.FONT_HERSHEY_SIMPLEX, 1.0, (255, 255, 255), 2, cv2.LINE_AA)
        tiles.append(img)
    if tiles:
        path.parent.mkdir(parents=True, exist_ok=True)
        cv2.imwrite(str(path), np.vstack(tiles))


if __name__ == "__main__":
    sys.exit(main())
