"""Speed of the synthetic-scene ray caster (ibr.synth): pinhole frames and equirect panoramas.

Run: ``python benchmarks/bench_synth.py [--repeats 3]``. Prints medians and ratios against the
baseline measured in the same run (the 2-primitive ``grazing`` scene, 512x384, supersample 1),
and writes ``benchmarks/results/bench_synth.png``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"  # `ibr bench --out DIR` points this elsewhere
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402
from benchmarks._timing import median_seconds  # noqa: E402


def equirect_dirs(w: int, h: int) -> np.ndarray:
    lon = ((np.arange(w) + 0.5) / w * 2 - 1) * np.pi
    lat = ((np.arange(h) + 0.5) / h - 0.5) * np.pi
    lon, lat = np.meshgrid(lon, lat)
    return np.stack([np.cos(lat) * np.sin(lon), np.sin(lat), np.cos(lat) * np.cos(lon)], -1)


def main(argv=None) -> int:
    from ibr.synth import make_scene, render, render_rays, scene_cameras

    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="one repeat (ibr bench)")
    args = ap.parse_args(argv)
    if args.quick:
        args.repeats = 1
    dirs = equirect_dirs(1024, 512)
    rows = []
    for name in ("grazing", "room", "clutter"):
        scene = make_scene(name)
        cam, _ = scene_cameras(name)
        rows.append((name, len(scene.primitives), "512x384 k=1",
                     median_seconds(lambda: render(scene, cam), args.repeats, warm=False)))
        rows.append((name, len(scene.primitives), "512x384 k=3",
                     median_seconds(lambda: render(scene, cam, supersample=3), args.repeats, warm=False)))
        rows.append((name, len(scene.primitives), "equirect 1024x512",
                     median_seconds(lambda: render_rays(scene, (0.0, 0.0, 1.0), dirs), args.repeats, warm=False)))
    base = rows[0][3]
    print(f"{'scene':8s} {'prims':>5s}  {'job':18s} {'median s':>9s} {'x baseline':>10s}")
    for name, n, job, t in rows:
        print(f"{name:8s} {n:5d}  {job:18s} {t:9.3f} {t / base:10.1f}")
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        out = RESULTS
        out.mkdir(parents=True, exist_ok=True)
        fig, ax = plt.subplots(figsize=(7, 3.2))
        labels = [f"{r[0]}\n{r[2]}" for r in rows]
        ax.bar(range(len(rows)), [r[3] for r in rows])
        ax.set_xticks(range(len(rows)), labels, fontsize=6)
        ax.set_ylabel("median seconds")
        ax.set_title("ibr.synth ray caster (numpy, 1 thread)")
        fig.tight_layout()
        fig.savefig(out / "bench_synth.png", dpi=100)
        print(f"wrote {out / 'bench_synth.png'}")
    except ImportError:
        print("matplotlib not installed: no plot (pip install -e '.[bench]')")
    return 0


if __name__ == "__main__":
    sys.exit(main())
