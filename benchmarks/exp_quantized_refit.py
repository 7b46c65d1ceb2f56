"""Experiment (issue 11, not in the library): refit quads of 8-bit-disparity depth whose own
pixels span at most one code over a grown same-surface neighbourhood, and compare the
interpolation's PSNR (covered pixels, t = .25/.5/.75) with the exact depth's.

Usage (from the repository root):
    python benchmarks/exp_quantized_refit.py SCENE NCODES KEEP ACC ENC CONN
SCENE clutter|room; NCODES: the neighbourhood is grown (1, 2, 3, 4, 6, 8 x the quad) until its
inliers span this many codes; KEEP: inlier band (codes) of the iterated plane; ACC: extra
allowance (codes) over half a code for the quad's own pixels; ENC disp|mm; CONN 1: inliers must be
4-connected to the quad. docs/edges.md section 3 has the figures (2026-11-25); e.g.
``python benchmarks/exp_quantized_refit.py clutter 2 0.75 0.2 disp 0``.
"""
import sys, time
import numpy as np
import cv2
from pathlib import Path

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]
import bench_edges as be
from ibr.base.view import View
from ibr.base.depth import DepthQuantization
from ibr.mesh.quad_mesh import QuadMesh
import ibr.mesh as M
from ibr.render.view_synthesis import interpolate

NCODES = float(sys.argv[2]) if len(sys.argv) > 2 else 3.0
KEEP = float(sys.argv[3]) if len(sys.argv) > 3 else 0.75
ACC = float(sys.argv[4]) if len(sys.argv) > 4 else 0.2
GROWS = (1, 2, 3, 4, 6, 8)
ENC = sys.argv[5] if len(sys.argv) > 5 else "disp"
CONN = int(sys.argv[6]) if len(sys.argv) > 6 else 1

def refit(mesh, view, q):
    h, w = view.depth.shape
    inv = 1.0 / view.depth.astype(np.float64)
    pl = mesh.inv_depth_planes.copy()
    n = 0
    for k, (u0, v0, u1, v1) in enumerate(mesh.rects):
        own = inv[v0:v1, u0:u1]
        if not np.isfinite(own).all():
            continue
        a, b, c = pl[k]
        step = float(q.inv_step(a * (u0 + u1 - 1) / 2 + b * (v0 + v1 - 1) / 2 + c))
        if (own.max() - own.min()) > step * 1.0001:
            continue  # spans more than one code: its own pixels pin the plane
        for g in GROWS:
            gu, gv = (u1 - u0) * g, (v1 - v0) * g
            U0, V0, U1, V1 = max(u0 - gu, 0), max(v0 - gv, 0), min(u1 + gu, w), min(v1 + gv, h)
            win = inv[V0:V1, U0:U1]
            vv, uu = np.mgrid[V0:V1, U0:U1]
            fit = a * uu + b * vv + c
            sol = None
            for it in range(3):
                ok = np.isfinite(win) & (np.abs(win - fit) <= (1.5 if it == 0 else KEEP) * step)
                if CONN:  # only inliers connected to the quad (4-neighbours)
                    n_lab, lab = cv2.connectedComponents(ok.astype(np.uint8), connectivity=4)
                    ids = np.unique(lab[v0 - V0:v1 - V0, u0 - U0:u1 - U0])
                    ok = np.isin(lab, ids[ids > 0])
                if ok.sum() < 3:
                    break
                A = np.stack([uu[ok], vv[ok], np.ones(ok.sum())], 1)
                sol, *_ = np.linalg.lstsq(A, win[ok], rcond=None)
                fit = sol[0] * uu + sol[1] * vv + sol[2]
            if sol is None or ok.sum() < 3:
                break
            if (win[ok].max() - win[ok].min()) >= NCODES * step * 0.9999:
                ovv, ouu = np.mgrid[v0:v1, u0:u1]
                res = np.abs(sol[0] * ouu + sol[1] * ovv + sol[2] - own)
                if res.max() <= (0.5 + ACC) * step:
                    pl[k] = sol
                    n += 1
                break
            if U0 == 0 and V0 == 0 and U1 == w and V1 == h:
                break
    return QuadMesh(mesh.camera, mesh.rects, pl, mesh.quad_of_pixel, dict(mesh.info)), n

name = sys.argv[1]
if name in ("room", "clutter", "grazing"):
    a, b, truths = be.load_pair(name)
else:  # another synthetic scene: its bundled camera pair, truths rendered here
    from ibr.base.camera import interpolate_cameras
    from ibr.synth import make_scene, render, scene_cameras
    scene = make_scene(name)
    ca, cb = scene_cameras(name)
    a, b = (render(scene, c, supersample=3, name=n) for c, n in ((ca, "a"), (cb, "b")))
    truths = [render(scene, interpolate_cameras(ca, cb, t), supersample=3, name=f"t{t}") for t in (0.25, 0.5, 0.75)]
    a, b = (View(v.color, np.where(np.isfinite(v.depth), v.depth, np.nan).astype(np.float32), v.camera, v.name) for v in (a, b))
cams = [g.camera for g in truths]
base = float(np.linalg.norm(a.camera.position - b.camera.position)); f = a.camera.fx
if ENC == "disp":
    views = [View(v.color, (base * f / np.rint(base * f / v.depth)).astype(np.float32), v.camera, v.name) for v in (a, b)]
    q = DepthQuantization.disparity(baseline=base, focal_px=f)
else:
    views = [View(v.color, (np.rint(v.depth * 1000) / 1000).astype(np.float32), v.camera, v.name) for v in (a, b)]
    q = DepthQuantization.codes(0.001)
opts = {"quantization": q}
def score(views, patch=None, o=opts):
    orig = M.build_mesh
    if patch: M.build_mesh = patch
    try:
        frames = interpolate(*views, cams, fill="none", mesh_options=o)
    finally:
        M.build_mesh = orig
    return [be.psnr(r.color, g.color, ~r.holes) for r, g in zip(frames, truths)]
p_exact = np.mean(score((a, b), o={}))
p_q = score(views)
stats = []
def patched(view, **kw):
    m = M.quad_mesh.build_mesh(view, **kw)
    t = time.perf_counter(); r, n = refit(m, view, q); stats.append((round(time.perf_counter() - t, 2), n, len(m.rects)))
    return r
views2 = [View(v.color, v.depth, v.camera, v.name) for v in views]
p_r = score(views2, patched)
print(name, ENC, sys.argv[2:5], f"quant {np.mean(p_q) - p_exact:+.3f} refit {np.mean(p_r) - p_exact:+.3f}", np.round(np.array(p_r) - np.array(p_q), 2), stats)
