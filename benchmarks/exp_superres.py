"""Experiment (issue 11): how near the upsampled sources' 3x colour comes to the scene's own.

For each bundled pair (clutter, room; sources at 512 x 384, 3 x 3 box-filtered), the rms error
(levels) of each source's 3 x 3 upsampled colour against the scene's exact 3x colour (each
subsample the mean of its own 3 x 3 rays), off and on the source's depth-edge pixels:

* Lanczos-4 alone (before the nineteenth session),
* back-projected (``ibr.render.upsample.upsample_view``: the depth-edge pixels' subsamples started
  from their own surface, then ``superres.back_project``: every pixel's subsamples average to it),
* refined with the partner source (``super_resolve_pair``: what ``interpolate(..., supersample=3)``
  renders from).

Writes ``benchmarks/results/superres_room.png`` (copied to ``docs/img/``): a crop of room's
source a at 3x, the exact colour, Lanczos-4, back-projected, refined.

Usage (from the repository root): ``python benchmarks/exp_superres.py`` (about a minute).
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT / "benchmarks"), str(ROOT)]
import bench_edges as be  # noqa: E402
from ibr.render.superres import super_resolve_pair  # noqa: E402
from ibr.render.upsample import depth_edge_pixels, upsample_view  # noqa: E402
from ibr.synth import make_scene, render  # noqa: E402


def _rms(c, exact, where) -> float:
    return float(np.sqrt(((c.astype(np.float64) - exact)[where] ** 2).mean()))


def main() -> int:
    print(f"{'scene':<8} {'source':<7} {'colour at 3x':<28} {'rms off edges':>14} {'rms on edges':>13}")
    crops = None
    for name in ("clutter", "room"):
        scene = make_scene(name)
        a, b, _ = be.load_pair(name)
        ups = (upsample_view(a, 3, clean_start=True), upsample_view(b, 3, clean_start=True))  # as a pair's
        refined = super_resolve_pair((a, b), ups, 3)
        for side, v, u, c in (("a", a, ups[0], refined[0]), ("b", b, ups[1], refined[1])):
            exact = render(scene, u.camera, supersample=3).color * 255
            lanczos = cv2.resize(v.color, (u.camera.width, u.camera.height), interpolation=cv2.INTER_LANCZOS4)
            edge = np.repeat(np.repeat(depth_edge_pixels(v.depth), 3, 0), 3, 1)
            inside = ~edge & np.isfinite(u.depth)
            for label, col in (("Lanczos-4", lanczos), ("back-projected", u.color), ("refined with the partner", c)):
                print(f"{name:<8} {side:<7} {label:<28} {_rms(col, exact, inside):>14.2f} {_rms(col, exact, edge):>13.2f}")
            if name == "room" and side == "a":
                ys, xs = slice(560, 740), slice(250, 430)
                panels = [np.clip(np.rint(exact), 0, 255).astype(np.uint8), lanczos, u.color, c]
                crops = np.concatenate([cv2.resize(p[ys, xs], None, fx=2, fy=2, interpolation=cv2.INTER_NEAREST)
                                        for p in panels], 1)
    out = ROOT / "benchmarks" / "results" / "superres_room.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(out), np.ascontiguousarray(crops[..., ::-1]))
    shutil.copy(out, ROOT / "docs" / "img" / out.name)
    print(f"wrote {out} (copied to docs/img): room a at 3x, exact / Lanczos-4 / back-projected / refined")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
