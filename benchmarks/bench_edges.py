"""Depth edges and holes on real data (issue 11): every figure of the issue, before -> after.

Run from the repository root (``pip install -e ".[bench]"``)::

    python benchmarks/bench_edges.py             # everything, incl. the slow classical inpainters
    python benchmarks/bench_edges.py --quick     # no biharmonic / FSR, 5 repeats (also: ibr bench edges)

"Before" is issue 4's behaviour, still reachable through options: ``silhouettes=False`` (plain
viewpoint blend), ``fill="background"`` (directional fill of rows and columns), ``lod="depth"``
(baseline 5 % of the median depth), meshes without ``quantization``, ``interpolation="linear"``
(plain bilinear colour; the default is sharp sampling since the twelfth session).

1. Bundled synthetic pairs (room, clutter), t = 0.25/0.5/0.75, covered pixels before filling:
   PSNR in the edge band (within 1 px, 8-connected, of a ground-truth depth edge: neighbours whose
   depths differ by more than 2 %), over all covered pixels, and the number of covered pixels off
   the band with an error over 48/255 in some channel; then, after the single-frame fill
   (``fill="inpaint"``), PSNR and off-band errors over all pixels and over the covered ones
   (as delivered: the fill recolours the background rims beside disocclusions). The *ceilings* of the current layers:
   per pixel the best of layer a, layer b and their blend (an oracle compositor), and 3x3
   supersampling of the target (an oracle anti-aliasing of the same geometry); and what any
   method scores whose every pixel is 1/4 or 1/2 px off (the truth against itself shifted).
2. Middlebury motorcycle left -> right, the hole pixels (no source coverage) against the real
   right image: our fills and cv2.inpaint (Telea, Navier-Stokes), skimage inpaint_biharmonic and
   cv2.xphoto.inpaint (FSR fast), all on the same holes in the same run; fill time as the median
   of per-repeat ratios to issue 4's fill timed back to back; covered-pixel PSNR before/after.
   The ceiling of a smooth fill: the right image itself blurred (Gaussian sigma 2/4/8 px).
3. Synthetic pairs re-encoded as 8-bit integer disparity (the pair's own baseline, like
   Middlebury ground truth) and as 16-bit millimetre depth: quads and PSNR over covered pixels,
   without and with the encoding's quantization (with the default sharp sampling and with plain
   bilinear colour: crisper textures make a misplaced one cost more); for 8-bit disparity also
   with the planes on the codes only ("code planes": before the large quads were fitted to the
   other source's colour, :mod:`ibr.render.plane_refine`); and the real motorcycle's disparity
   rounded to integers: its planes against the float ground truth, on the codes and fitted.
4. Time of the 512x512 two-source frame with cached meshes (issue target <= 8 ms), before and
   after options, back to back; and of the quality options (``supersample=3``, bicubic colour)
   against the default; and the first frame of fresh views, ``supersample=3`` against the
   default, with the part the sources' upsampling and colour refinement take. Sections 1 and 2
   score those options too.

Writes ``benchmarks/results/edges_motorcycle_fill.png``, ``edges_clutter_silhouette.png`` and
``edges_8bit_wall.png`` (copied to ``docs/img/`` by a full run).
"""

from __future__ import annotations

import argparse
import contextlib
import shutil
import sys
import time
from pathlib import Path
from unittest import mock

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import cv2  # noqa: E402
from scipy import ndimage  # noqa: E402

from benchmarks._timing import median_ms, paired_ms  # noqa: E402
from ibr.base.depth import DepthQuantization, fixed_from_z, z_from_fixed  # noqa: E402
from ibr.base.view import View  # noqa: E402
from ibr.io import load_view  # noqa: E402
from ibr.mesh import build_mesh, code_bins  # noqa: E402
from ibr.render import plane_refine  # noqa: E402
from ibr.render.composite import viewpoint_weights  # noqa: E402
from ibr.render.fill import fill_background, fill_pullpush, parallax_axis  # noqa: E402
from ibr.render.rasterize import render_mesh  # noqa: E402
from ibr.render.view_synthesis import interpolate, interpolation_meshes, source_mesh, warp  # noqa: E402
from samples import DATA_DIR  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results"
DOCS = ROOT / "docs" / "img"
TS = (0.25, 0.5, 0.75)
BEFORE = dict(silhouettes=False, lod="depth", interpolation="linear")
AFTER: dict = {}
#: Quality options (not defaults: they cost frame time, section 4): 3 x 3 subsamples per pixel
#: box-filtered at depth edges; bicubic colour.
SUPERSAMPLED = dict(supersample=3)
CUBIC = dict(interpolation="cubic")
#: The defaults before sharp sampling (twelfth session): plain bilinear colour.
BILINEAR = dict(interpolation="linear")
#: A quality option (fourteenth session): the depth-edge pixels anti-aliased by subsamples, ~1.5x the frame.
ANTIALIASED = dict(antialias=True)


def psnr(a, b, mask=None) -> float:
    d = (np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2
    d = d[mask] if mask is not None else d
    return float(10 * np.log10(255.0**2 / max(d.mean(), 1e-12)))


def edge_band(depth, rel=0.02) -> np.ndarray:
    """Pixels within 1 px (8-connected) of a depth edge: 4-neighbours whose planar depths differ
    by more than ``rel`` of the nearer one, or exactly one of which is valid."""
    z = np.asarray(depth, np.float64)
    e = np.zeros(z.shape, bool)
    with np.errstate(invalid="ignore"):
        dh = (np.abs(z[:, 1:] - z[:, :-1]) > rel * np.fmin(z[:, 1:], z[:, :-1])) | (np.isnan(z[:, 1:]) != np.isnan(z[:, :-1]))
        dv = (np.abs(z[1:] - z[:-1]) > rel * np.fmin(z[1:], z[:-1])) | (np.isnan(z[1:]) != np.isnan(z[:-1]))
    e[:, 1:] |= dh
    e[:, :-1] |= dh
    e[1:] |= dv
    e[:-1] |= dv
    return ndimage.binary_dilation(e, ndimage.generate_binary_structure(2, 2))


def load_pair(name):
    a, b = load_view(DATA_DIR / f"{name}_a.json"), load_view(DATA_DIR / f"{name}_b.json")
    truths = [load_view(DATA_DIR / f"{name}_t{round(t * 100):03d}.json") for t in TS]
    return a, b, truths


def edge_scores(frames, truths):
    band, cov_p, off = [], [], []
    for r, g in zip(frames, truths):
        bd, cov = edge_band(g.depth), ~r.holes
        band.append(psnr(r.color, g.color, bd & cov))
        cov_p.append(psnr(r.color, g.color, cov))
        err = np.abs(r.color.astype(int) - g.color.astype(int)).max(-1)
        off.append(int(((err > 48) & cov & ~bd).sum()))
    return band, cov_p, off


def ceilings(a, b, truths):
    """Oracle compositor (per pixel best of a, b, blend) and 3x3 supersampled target, edge band;
    and the pixels off the band that the oracle still gets wrong by more than 48/255."""
    orc, ssaa, off = [], [], []
    for g in truths:
        la = render_mesh(source_mesh(a), a.color, g.camera)
        lb = render_mesh(source_mesh(b), b.color, g.camera)
        gt = g.color.astype(np.float64)
        wa, wb = viewpoint_weights(g.camera, [a.camera, b.camera])
        errs = [((la.color - gt) ** 2).mean(-1), ((lb.color - gt) ** 2).mean(-1),
                ((wa * la.color + wb * lb.color - gt) ** 2).mean(-1)]
        best = np.where(la.coverage, errs[0], np.inf)
        best = np.where(lb.coverage, np.minimum(best, errs[1]), best)
        both = la.coverage & lb.coverage
        best = np.where(both, np.minimum(best, errs[2]), best)
        m = edge_band(g.depth) & np.isfinite(best)
        orc.append(float(10 * np.log10(255.0**2 / best[m].mean())))
        # off the band: pixels that even the per-pixel best of a, b and the blend gets wrong by > 48
        worst = [np.abs(x - gt).max(-1) for x in (la.color, lb.color, wa * la.color + wb * lb.color)]
        pick = np.where(la.coverage, worst[0], np.inf)
        pick = np.where(lb.coverage, np.minimum(pick, worst[1]), pick)
        pick = np.where(both, np.minimum(pick, worst[2]), pick)
        off.append(int(((pick > 48) & np.isfinite(pick) & ~edge_band(g.depth)).sum()))
        k = 3
        big = g.camera.resized(g.camera.width * k, g.camera.height * k)
        r = interpolate(a, b, big, fill="inpaint")
        c = r.color.astype(np.float64).reshape(g.camera.height, k, g.camera.width, k, -1).mean((1, 3))
        ssaa.append(psnr(c, g.color, edge_band(g.depth)))
    return orc, ssaa, off


def shifted_truth(truths, px, axis=1):
    """What a method whose every pixel is ``px`` pixels off would score: the ground truth against
    itself resampled (bilinear) ``px`` to the right (``axis`` = 1) or down (0); edge band PSNR
    and off-band pixels over 48/255, the last column and row left out."""
    band, off = [], []
    for g in truths:
        h, w = g.depth.shape
        u, v = np.meshgrid(np.arange(w, dtype=np.float32) + px * (axis == 1),
                           np.arange(h, dtype=np.float32) + px * (axis == 0))
        s = cv2.remap(g.color.astype(np.float32), u, v, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        bd, inside = edge_band(g.depth), np.ones((h, w), bool)
        inside[:, -1] = inside[-1] = False
        band.append(psnr(s, g.color, bd & inside))
        off.append(int(((np.abs(s - g.color).max(-1) > 48) & ~bd & inside).sum()))
    return band, off


def section_edges(quick):
    print("\n1. edge band (+-1 px of ground-truth depth edges), covered pixels, t = 0.25/0.5/0.75")
    print(f"{'scene':<8} {'variant':<22} {'edge band dB':<24} {'mean':>6} {'all dB':>7} {'off-band > 48/255':>18}")
    for name in ("clutter", "room"):
        a, b, truths = load_pair(name)
        cams = [g.camera for g in truths]
        for label, kw in (("before (issue 4)", BEFORE), ("after", AFTER), ("after, antialias", ANTIALIASED),
                          ("after, bilinear", BILINEAR),
                          ("after, supersample 3", SUPERSAMPLED), ("after, cubic", CUBIC)):
            frames = interpolate(a, b, cams, fill="none", **kw)
            band, cov_p, off = edge_scores(frames, truths)
            print(f"{name:<8} {label:<22} {' '.join(f'{x:.2f}' for x in band):<24} {np.mean(band):6.2f} "
                  f"{np.mean(cov_p):7.2f} {str(off):>18}")
            # after the single-frame fill, every pixel (the fill recolours background rims too)
            filled = interpolate(a, b, cams, fill="inpaint", **kw)
            full = [psnr(r.color, g.color) for r, g in zip(filled, truths)]
            big = [(np.abs(r.color.astype(int) - g.color.astype(int)).max(-1) > 48) & ~edge_band(g.depth)
                   for r, g in zip(filled, truths)]
            off_all = [int(m.sum()) for m in big]
            # the covered pixels as delivered: background rims beside their layer's gaps recoloured by the fill
            off_cov = [int((m & ~r.holes).sum()) for m, r in zip(big, filled)]
            print(f"{'':<8} {'  filled, all pixels':<22} {' '.join(f'{x:.2f}' for x in full):<24} {np.mean(full):6.2f} "
                  f"{'':>7} {str(off_all):>18}   covered: {off_cov}")
        if not quick:
            orc, ssaa, off = ceilings(a, b, truths)
            print(f"{name:<8} {'ceiling: oracle pick':<22} {' '.join(f'{x:.2f}' for x in orc):<24} {np.mean(orc):6.2f} "
                  f"{'':>7} {str(off):>18}")
            print(f"{name:<8} {'ceiling: 3x3 SSAA':<22} {' '.join(f'{x:.2f}' for x in ssaa):<24} {np.mean(ssaa):6.2f}")
            for px, axis in ((0.25, 1), (0.5, 1), (0.25, 0), (0.5, 0)):
                band, off = shifted_truth(truths, px, axis)
                label = f"truth {px} px {'right' if axis else 'down'}"
                print(f"{name:<8} {label:<22} {' '.join(f'{x:.2f}' for x in band):<24} "
                      f"{np.mean(band):6.2f} {'':>7} {str(off):>18}")


def section_motorcycle(repeats, classical):
    from ibr.io.middlebury import motorcycle_views

    left, right = motorcycle_views()
    print("\n2. motorcycle left -> right: hole pixels against the real right image")
    before = warp(View(left.color, left.depth, left.camera, "l0"), right.camera, fill="none", lod="depth")
    r0 = warp(left, right.camera, fill="none")
    holes = r0.holes
    gt = right.color
    axis = parallax_axis(right.camera, [left.camera])
    fine = warp(left, right.camera, fill="none", **SUPERSAMPLED)
    smooth = warp(left, right.camera, fill="none", **ANTIALIASED)
    print(f"holes {holes.mean():.1%}; covered PSNR before {psnr(before.color, gt, ~before.holes):.2f} dB "
          f"(lod from depth), after {psnr(r0.color, gt, ~holes):.2f} dB (lod from the move), "
          f"antialias: {psnr(smooth.color, gt, ~holes):.2f} dB, supersample 3: {psnr(fine.color, gt, ~fine.holes):.2f} dB")
    print("ceiling of a smooth fill (the right image blurred): "
          + ", ".join(f"sigma {s}: {psnr(cv2.GaussianBlur(gt.astype(np.float32), (0, 0), s), gt, holes):.2f} dB"
                      for s in (2, 4, 8)))
    rows = []
    old_c, _, _ = fill_background(r0.color, r0.depth, holes)
    old_ms = median_ms(lambda: fill_background(r0.color, r0.depth, holes), repeats)
    rows.append(("issue 4 fill (rows + columns)", psnr(old_c, gt, holes), old_ms, 1.0))
    new_c, new_z, new_f = fill_pullpush(r0.color, r0.depth, holes, axis=axis)
    assert new_f.sum() == holes.sum() and np.array_equal(new_c[~holes], r0.color[~holes])
    ms, ratio = paired_ms(lambda: fill_pullpush(r0.color, r0.depth, holes, axis=axis),
                          lambda: fill_background(r0.color, r0.depth, holes), repeats)
    rows.append(("pull-push + parallax axis (new)", psnr(new_c, gt, holes), ms, ratio))
    pp_c, _, _ = fill_pullpush(r0.color, r0.depth, holes, mix=0.0)
    rows.append(("pull-push only (mix 0)", psnr(pp_c, gt, holes), float("nan"), float("nan")))
    mask = holes.astype(np.uint8) * 255
    bgr = np.ascontiguousarray(r0.color[..., ::-1])
    for label, flag in (("cv2.inpaint Telea r=3", cv2.INPAINT_TELEA), ("cv2.inpaint Navier-Stokes r=3", cv2.INPAINT_NS)):
        t0 = time.perf_counter()
        out = cv2.inpaint(bgr, mask, 3, flag)[..., ::-1]
        rows.append((label, psnr(out, gt, holes), (time.perf_counter() - t0) * 1e3, float("nan")))
    if classical:
        from skimage.restoration import inpaint_biharmonic

        t0 = time.perf_counter()
        out = inpaint_biharmonic(r0.color.astype(np.float64) / 255, holes, channel_axis=-1) * 255
        rows.append(("skimage inpaint_biharmonic", psnr(out, gt, holes), (time.perf_counter() - t0) * 1e3,
                     float("nan")))
        dst = np.zeros_like(bgr)
        t0 = time.perf_counter()
        cv2.xphoto.inpaint(bgr, (~holes).astype(np.uint8) * 255, dst, cv2.xphoto.INPAINT_FSR_FAST)
        rows.append(("cv2.xphoto.inpaint FSR fast", psnr(dst[..., ::-1], gt, holes), (time.perf_counter() - t0) * 1e3,
                     float("nan")))
    print(f"{'fill':<34} {'holes dB':>8} {'ms':>9} {'x issue-4 fill':>15}")
    for label, p, ms, ratio in rows:
        print(f"{label:<34} {p:8.2f} {ms:9.1f} {'' if not np.isfinite(ratio) else f'{ratio:.2f}':>15}")
    # what `ibr warp` gives: the pull-push, and stray samples inside the holes recoloured with it
    default = warp(left, right.camera)
    print(f"default warp (the fill + stray samples refilled): whole image {psnr(default.color, gt):.2f} dB "
          f"(the fill alone {psnr(new_c, gt):.2f}), covered {psnr(default.color, gt, ~holes):.2f} dB")
    return r0, old_c, default.color


def in_disparity_codes(views, bf: float) -> list:
    """New views whose depth is re-encoded as integer disparity codes ``round(bf / z)`` (``bf`` =
    baseline x focal length in px), like 8-bit Middlebury ground truth."""
    return [View(v.color, (bf / np.rint(bf / v.depth)).astype(np.float32), v.camera, v.name) for v in views]


def code_planes():
    """Quads of quantized depth keep their least-squares planes on the codes (before the
    photo-consistent planes of :mod:`ibr.render.plane_refine`, fifteenth session)."""
    return mock.patch.object(plane_refine, "COARSE_PX", np.inf)


def colour_planes_only():
    """Quads of quantized depth fitted to the other view's colour only, the others kept on their
    codes (before :mod:`ibr.mesh.code_bins`, sixteenth session)."""
    return mock.patch.object(plane_refine, "fit_mesh_in_code_bins", lambda mesh, depth, quads=None: mesh)


def unsplit_bins():
    """Quads placed inside the codes' bins but never split (before the seventeenth session)."""
    return mock.patch.object(code_bins, "SPLIT_SHARE", np.inf)


def section_quantized():
    print("\n3. quantized re-encodings: quads of source a's mesh as rendered and PSNR over covered pixels "
          "(t = 0.25/0.5/0.75)")
    print(f"{'scene':<8} {'encoding':<48} {'quads':>6} {'x exact':>8} {'PSNR dB':>8} {'vs exact':>9}")
    for name in ("room", "clutter"):
        a, b, truths = load_pair(name)
        cams = [g.camera for g in truths]
        base = float(np.linalg.norm(a.camera.position - b.camera.position))
        f = a.camera.fx

        def scores(va, vb, q):
            opts = {} if q is None else {"quantization": q}
            n = len(interpolation_meshes(va, vb, cams, mesh_options=opts)[0])  # as rendered: split quads counted
            got = []
            for kw in (AFTER, BILINEAR):
                frames = interpolate(va, vb, cams, fill="none", mesh_options=opts, **kw)
                got.append(float(np.mean([psnr(r.color, g.color, ~r.holes) for r, g in zip(frames, truths)])))
            return n, got

        n0, (p0, l0) = scores(a, b, None)
        print(f"{name:<8} {'exact float depth':<48} {n0:6d} {1.0:8.2f} {p0:8.2f} {0.0:9.2f}   bilinear {l0:.2f}")

        def disparity_views():
            return in_disparity_codes((a, b), base * f)

        assert all(np.nanmax(base * f / v.depth) <= 255 for v in (a, b))
        mm = [View(v.color, (np.rint(v.depth * 1000) / 1000).astype(np.float32), v.camera, v.name) for v in (a, b)]
        disparity = DepthQuantization.disparity(baseline=base, focal_px=f)
        rows = (("8-bit disparity, no quantization", disparity_views(), None, None),
                ("8-bit disparity, quantization, code planes", disparity_views(), disparity, code_planes),
                ("8-bit disparity, quantization, colour fit only", disparity_views(), disparity, colour_planes_only),
                ("8-bit disparity, quantization, bins not split", disparity_views(), disparity, unsplit_bins),
                ("8-bit disparity, quantization", disparity_views(), disparity, None),
                ("16-bit mm, no quantization", mm, None, None),
                ("16-bit mm, quantization", mm, DepthQuantization.codes(0.001), None))
        for label, views, q, before in rows:
            with before() if before else contextlib.nullcontext():
                n, (p, lp) = scores(*views, q)
            print(f"{name:<8} {label:<48} {n:6d} {n / n0:8.2f} {p:8.2f} {p - p0:+9.2f}   "
                  f"bilinear {lp:.2f} {lp - l0:+.2f}")
        quantized_supersampled(name, (a, b), disparity_views(), disparity, truths, mm)
    motorcycle_rounded_disparity()


def quantized_supersampled(name, exact, codes, quantization, truths, mm):
    """``supersample=3`` from 8-bit disparity codes against the exact depth's (the coarse source
    upsampled from its fitted mesh's depth moved into its codes' bins, and from its codes as
    before the seventeenth session), and from the 16-bit millimetres ``mm``."""
    from ibr.render import sources

    cams = [g.camera for g in truths]

    def score(views, **kw):
        frames = interpolate(*views, cams, fill="none", supersample=3, **kw)
        return float(np.mean([psnr(r.color, g.color, ~r.holes) for r, g in zip(frames, truths)]))

    p0, p = score(exact), score(codes, mesh_options={"quantization": quantization})
    fresh = [View(v.color, v.depth, v.camera, v.name) for v in codes]  # new views: nothing cached on them
    with mock.patch.object(sources, "_with_mesh_depth", lambda view, mesh, *partner: view):
        before = score(fresh, mesh_options={"quantization": quantization})
    p_mm = score(mm, mesh_options={"quantization": DepthQuantization.codes(0.001)})
    near, far = 0.003, 1e6  # a coarse 16-bit z-buffer: a code is about 4.6 cm at 3 m
    zbuffer = [View(v.color, z_from_fixed(fixed_from_z(v.depth, near=near, far=far, bits=16), near=near, far=far,
                                          bits=16).astype(np.float32), v.camera, v.name) for v in exact]
    p_zb = score(zbuffer, mesh_options={"quantization": DepthQuantization.zbuffer(near=near, far=far, bits=16)})
    print(f"{name:<8} {'supersample 3: exact / 8-bit from fitted planes / from codes':<64} {p0:.2f} / {p:.2f} "
          f"({p - p0:+.2f}) / {before:.2f} ({before - p0:+.2f}); 16-bit mm {p_mm:.2f} ({p_mm - p0:+.2f}); "
          f"16-bit z-buffer {p_zb:.2f} ({p_zb - p0:+.2f})")


def motorcycle_rounded_disparity():
    """The real motorcycle left view with its disparity rounded to integers: the rms disparity
    error (px) of its mesh's planes against the float ground truth, with the planes on the codes
    and fitted to the right view's colour (:mod:`ibr.render.plane_refine`; no right depth, so
    nothing is marked occluded)."""
    from ibr.io.middlebury import MOTORCYCLE_CALIBRATION, motorcycle_views
    from ibr.mesh.code_bins import depth_in_code_bins
    from ibr.mesh.quad_mesh import mesh_depth
    from ibr.render.plane_refine import refine_planes

    left, right = motorcycle_views()
    cal = MOTORCYCLE_CALIBRATION
    bf, doffs = cal["baseline"] * cal["focal_px"], cal["doffs"]
    disparity = bf / left.depth - doffs
    codes = View(left.color, (bf / (np.rint(disparity) + doffs)).astype(np.float32), left.camera, "left, integer codes")
    other = View(right.color, np.full(disparity.shape, np.nan, np.float32), right.camera, "right")
    mesh = build_mesh(codes, quantization=DepthQuantization.disparity(baseline=bf / left.camera.fx,
                                                                      focal_px=left.camera.fx))
    with colour_planes_only():
        colour_only = refine_planes(mesh, codes, other)
    with unsplit_bins():
        unsplit = refine_planes(mesh, codes, other)
    for label, m in (("planes on the codes", mesh), ("fitted to the right view's colour", colour_only),
                     ("the same, the others in the codes' bins, not split", unsplit),
                     ("the same, split where a plane does not follow the bins", refine_planes(mesh, codes, other))):
        err = bf / mesh_depth(m) - doffs - disparity
        print(f"{'motorcycle':<10} {'integer disparity, ' + label:<75} rms disparity error vs the float ground truth "
              f"{np.sqrt(np.nanmean(err**2)):.3f} px")
    # what supersample=3 upsamples a coarse source from: the fitted planes moved into the bins pixel by pixel
    per_pixel = depth_in_code_bins(mesh_depth(refine_planes(mesh, codes, other)), codes.depth, mesh.info["quantization"])
    err = bf / per_pixel - doffs - disparity
    print(f"{'motorcycle':<10} {'integer disparity, the same moved into the bins pixel by pixel':<75} rms disparity "
          f"error vs the float ground truth {np.sqrt(np.nanmean(err**2)):.3f} px")


def section_timing(repeats):
    from bench_render import room_pair
    from ibr.base.camera import interpolate_cameras

    a, b = room_pair(512, 512)
    cam = interpolate_cameras(a.camera, b.camera, 0.5)
    for kw in (BEFORE, AFTER):
        interpolate(a, b, cam, fill="none", **kw)
    ms_after, ratio = paired_ms(lambda: interpolate(a, b, cam, fill="none", **AFTER),
                                lambda: interpolate(a, b, cam, fill="none", **BEFORE), repeats)
    ms_fill = median_ms(lambda: interpolate(a, b, cam, fill="inpaint"), repeats)
    print(f"\n4. 512x512 two-source frame, cached meshes: {ms_after:.2f} ms (x{ratio:.2f} of the issue-4 options "
          f"timed back to back; target 8 ms); with the pull-push fill {ms_fill:.2f} ms")
    for label, kw in (("antialias", ANTIALIASED), ("bilinear", BILINEAR), ("supersample 3", SUPERSAMPLED),
                      ("cubic", CUBIC)):
        interpolate(a, b, cam, fill="none", **kw)
        ms, ratio = paired_ms(lambda: interpolate(a, b, cam, fill="none", **kw),
                              lambda: interpolate(a, b, cam, fill="none", **AFTER), repeats)
        print(f"   {label}: {ms:.2f} ms (x{ratio:.2f} of the default, back to back)")
    _first_frames(a, b, cam, max(3, repeats // 3))


def _first_frames(a, b, cam, repeats):
    """The first frame of fresh views (everything cached per view built anew), default against
    ``supersample=3``, and how much of the latter is the sources' upsampling and colour refinement
    (``ibr.render.superres``)."""
    from ibr.base.view import View
    from ibr.render.view_synthesis import _upsampled_pair

    def fresh():
        return View(a.color, a.depth, a.camera, a.name), View(b.color, b.depth, b.camera, b.name)

    ms, ratio = paired_ms(lambda: interpolate(*fresh(), cam, fill="none", **SUPERSAMPLED),
                          lambda: interpolate(*fresh(), cam, fill="none", **AFTER), repeats)
    ms_up, ratio_up = paired_ms(lambda: _upsampled_pair(*fresh(), {}, "move", "mesh", 3),
                                lambda: interpolate(*fresh(), cam, fill="none", **AFTER), repeats)
    print(f"   first frame of fresh views, supersample 3: {ms:.0f} ms (x{ratio:.1f} of the default's, back to back), "
          f"of which the sources upsampled and refined by each other {ms_up:.0f} ms (x{ratio_up:.1f})")


def pictures(r0, old_c, new_c, out_dir: Path):
    from ibr.io.middlebury import motorcycle_views

    _, right = motorcycle_views()
    y0, y1, x0, x1 = 130, 350, 380, 741
    strip = [c[y0:y1, x0:x1] for c in (r0.color * (~r0.holes[..., None]), old_c, new_c, right.color)]  # new: `ibr warp`
    sheet = np.concatenate([np.concatenate(strip[:2], 1), np.concatenate(strip[2:], 1)], 0)
    cv2.imwrite(str(out_dir / "edges_motorcycle_fill.png"), np.ascontiguousarray(sheet[..., ::-1]))
    a, b, truths = load_pair("clutter")
    g = truths[-1]
    crops = [g.color]
    for kw in (BEFORE, AFTER, ANTIALIASED, SUPERSAMPLED):
        crops.append(interpolate(a, b, g.camera, fill="inpaint", **kw).color)
    ys, xs = slice(30, 150), slice(180, 300)
    row = np.concatenate([c[ys, xs] for c in crops], 1)
    row = cv2.resize(row, None, fx=3, fy=3, interpolation=cv2.INTER_NEAREST)
    cv2.imwrite(str(out_dir / "edges_clutter_silhouette.png"), np.ascontiguousarray(row[..., ::-1]))


def picture_quantized(out_dir: Path):
    """Room t = 0.5, 3x crop of the back wall: truth, exact depth; 8-bit disparity with the
    planes on the codes, and fitted to the other source's colour (section 3)."""
    a, b, truths = load_pair("room")
    g = truths[1]
    base, f = float(np.linalg.norm(a.camera.position - b.camera.position)), a.camera.fx
    q = DepthQuantization.disparity(baseline=base, focal_px=f)

    def codes():
        return in_disparity_codes((a, b), base * f)

    crops = [g.color, interpolate(a, b, g.camera, fill="none").color]
    with code_planes():
        crops.append(interpolate(*codes(), g.camera, fill="none", mesh_options={"quantization": q}).color)
    crops.append(interpolate(*codes(), g.camera, fill="none", mesh_options={"quantization": q}).color)
    ys, xs = slice(170, 250), slice(170, 290)
    row = cv2.resize(np.concatenate([c[ys, xs] for c in crops], 1), None, fx=3, fy=3, interpolation=cv2.INTER_NEAREST)
    cv2.imwrite(str(out_dir / "edges_8bit_wall.png"), np.ascontiguousarray(row[..., ::-1]))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip biharmonic/FSR and the ceilings, 5 repeats")
    ap.add_argument("--repeats", type=int, default=21, help="timing repeats (median), default %(default)s")
    args = ap.parse_args(argv)
    repeats = 5 if args.quick else args.repeats
    sys.path.insert(0, str(ROOT / "benchmarks"))
    section_edges(args.quick)
    r0, old_c, new_c = section_motorcycle(repeats, classical=not args.quick)
    section_quantized()
    section_timing(repeats)
    RESULTS.mkdir(parents=True, exist_ok=True)
    pictures(r0, old_c, new_c, RESULTS)
    picture_quantized(RESULTS)
    names = ("edges_motorcycle_fill.png", "edges_clutter_silhouette.png", "edges_8bit_wall.png")
    if not args.quick:
        DOCS.mkdir(parents=True, exist_ok=True)
        for n in names:
            shutil.copyfile(RESULTS / n, DOCS / n)
    print("\nwrote " + ", ".join(str(RESULTS / n) for n in names))
    return 0


if __name__ == "__main__":
    sys.exit(main())
