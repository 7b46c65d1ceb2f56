"""Anti-aliased silhouettes from subsamples of the depth-edge pixels (ibr.render.edge_antialias)."""

from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import ibr.render.frame_composite as frame
import ibr.render.view_synthesis as vs
from ibr.base.camera import Camera
from ibr.base.view import View
from ibr.io import load_view
from ibr.render.edge_antialias import (SUBSAMPLE_OFFSETS, average_edge_pixels, edge_candidates, subsample_maps,
                                       unpack_subsamples)
from ibr.render.rasterize import rasterize_mesh
from samples import DATA_DIR

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the checkout, for its benchmarks
from benchmarks.bench_edges import edge_band  # noqa: E402  (issue 11's band: +-1 px of depth edges)

TS = (0.25, 0.5, 0.75)


def psnr(a, b, mask) -> float:
    d = (np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2
    return float(10 * np.log10(255.0**2 / d[mask].mean()))


@pytest.fixture(scope="module")
def clutter():
    return (load_view(DATA_DIR / "clutter_a.json"), load_view(DATA_DIR / "clutter_b.json"),
            [load_view(DATA_DIR / f"clutter_t{round(t * 100):03d}.json") for t in TS])


def test_the_edge_band_gains_against_the_scene_truth(clutter):
    """Clutter, t = .25/.5/.75, fill "none": the edge band (covered pixels) gains over a dB
    (measured 28.47 -> 29.99), the covered frame does not lose (37.80 -> 38.66), and the pixels
    that change lie at the truth's depth edges."""
    a, b, truths = clutter
    cams = [g.camera for g in truths]
    plain = vs.interpolate(a, b, cams, fill="none")
    smooth = vs.interpolate(a, b, cams, fill="none", antialias=True)
    band = [[psnr(r.color, g.color, edge_band(g.depth) & ~r.holes) for r, g in zip(rs, truths)] for rs in (plain, smooth)]
    assert np.mean(band[1]) > np.mean(band[0]) + 1.0, band
    cover = [[psnr(r.color, g.color, ~r.holes) for r, g in zip(rs, truths)] for rs in (plain, smooth)]
    assert np.mean(cover[1]) > np.mean(cover[0]) + 0.3, cover
    for p, s, g in zip(plain, smooth, truths):
        np.testing.assert_array_equal(p.holes, s.holes)  # the geometry is the frame's
        np.testing.assert_array_equal(p.depth, s.depth)
        changed = (p.color != s.color).any(-1)
        assert changed.sum() > 1000 and not (changed & s.holes).any()
        near_edge = np.zeros_like(changed)
        near_edge[1:-1, 1:-1] = edge_band(g.depth)[1:-1, 1:-1]
        assert (changed & near_edge).sum() > 0.9 * changed.sum()


def test_sources_come_back_unchanged_at_their_own_pose(clutter):
    """Every subsample of a pixel lies in that pixel's own quad there: no pixel is an edge."""
    a, b, _ = clutter
    for v in (a, b):
        r = vs.warp(v, v.camera, fill="none", antialias=True)
        np.testing.assert_array_equal(r.color[~r.holes], v.color[~r.holes])


def test_subsample_maps_are_the_frame_moved_by_the_subsample_offset(clutter):
    """A subsample at (x + du, y + dv) is pixel (x, y) of the camera whose principal point is
    moved by (-du, -dv): rasterized there (the exact renderer), the maps agree wherever that
    pixel's quad covers one of the nine centres around it."""
    a, _, truths = clutter
    cam = truths[1].camera
    mesh = vs.source_mesh(a)
    maps = rasterize_mesh(mesh, cam)
    ys, xs = edge_candidates(maps.depth, np.zeros(cam.shape, np.uint8))
    assert len(ys) > 1000
    sub, same = subsample_maps(mesh, cam, maps, ys, xs, far_coord=-7.0)
    assert 0.2 < same.mean() < 0.9  # most subsamples of edge pixels lie on their centre's quad
    n = len(ys)
    agree = total = 0
    for s, (du, dv) in enumerate(SUBSAMPLE_OFFSETS):
        moved = Camera(cam.fx, cam.fy, cam.cx - du, cam.cy - dv, cam.width, cam.height, cam.world_from_cam)
        ref = rasterize_mesh(mesh, moved)
        cov, z = unpack_subsamples(sub.coverage, n)[s], unpack_subsamples(sub.depth, n)[s]
        with np.errstate(invalid="ignore"):  # a quad between the centres (a thin pole's) is missed
            same = (cov == ref.coverage[ys, xs]) & (~cov | (np.abs(z / ref.depth[ys, xs] - 1) < 1e-5))
        agree += same.sum()
        total += n
        both = same & cov
        np.testing.assert_allclose(unpack_subsamples(sub.map_u, n)[s][both], ref.map_u[ys, xs][both], atol=2e-3)
        np.testing.assert_allclose(unpack_subsamples(sub.map_v, n)[s][both], ref.map_v[ys, xs][both], atol=2e-3)
        assert (unpack_subsamples(sub.map_u, n)[s][~cov] == -7.0).all()
        assert np.isnan(unpack_subsamples(sub.depth, n)[s][~cov]).all()
    assert agree > 0.99 * total, (agree, total)  # measured 99.3 %


def _reference_average(color, depth, ys, xs, sub_color, sub_depth, sub_cov, sub_same, tol):
    out = color.astype(np.float64)
    for i, (y, x) in enumerate(zip(ys, xs)):
        others = [s for s in range(len(sub_depth)) if not sub_same[s, i]]  # not on the centre's quads
        q = sorted([1 / depth[y, x]] + [1 / sub_depth[s, i] for s in others if sub_cov[s, i]])
        edge = any(not sub_cov[s, i] for s in others) or any(q[j] > q[j - 1] * (1 + tol) for j in range(1, len(q)))
        if edge:
            samples = [color[y, x]] * 2 + [sub_color[s, i] if sub_cov[s, i] else color[y, x] for s in range(len(sub_depth))]
            out[y, x] = np.mean(np.asarray(samples, np.float64), 0)
    return out


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32])
def test_averaging_matches_a_plain_python_reference(dtype):
    rng = np.random.default_rng(3)
    h, w, n, m = 12, 14, 60, len(SUBSAMPLE_OFFSETS)
    top = 255 if dtype == np.uint8 else (65535 if dtype == np.uint16 else 1.0)
    color = (rng.random((h, w, 3)) * top).astype(dtype)
    depth = rng.uniform(1, 3, (h, w)).astype(np.float32)
    flat = rng.choice(h * w, n, replace=False)
    ys, xs = flat // w, flat % w
    sub_color = (rng.random((m, n, 3)) * top).astype(dtype)
    base = depth[ys, xs][None]
    sub_depth = np.where(rng.random((m, n)) < 0.5, base * rng.uniform(0.999, 1.001, (m, n)),
                         base * rng.uniform(1.01, 1.3, (m, n))).astype(np.float32)  # same surface or another
    sub_cov = rng.random((m, n)) > 0.15
    sub_depth[~sub_cov] = np.nan
    sub_same = rng.random((m, n)) < 0.3
    for same in (None, sub_same):
        ref = _reference_average(color, depth, ys, xs, sub_color, sub_depth, sub_cov,
                                 np.zeros((m, n), bool) if same is None else same, 0.02)
        got = color.copy()
        count = average_edge_pixels(got, depth, ys, xs, sub_color, sub_depth, sub_cov, same, 0.02)
        assert 5 < count < n
        if dtype == np.float32:
            np.testing.assert_allclose(got, ref, rtol=1e-5)
        else:
            np.testing.assert_array_equal(got, np.floor(ref + 0.5).astype(dtype))


def test_candidates_need_a_step_or_a_hole_and_colours_that_differ():
    z = np.full((9, 12), 3.0, np.float32)
    z[:, 6:] = 3.03  # 1 % apart: one surface
    c = np.zeros((9, 12, 3), np.uint8)
    assert len(edge_candidates(z, c)[0]) == 0
    z[:, 6:] = 4.0  # a step
    ys, xs = edge_candidates(z, c)
    assert set(xs.tolist()) == {5, 6} and len(ys) == 18
    assert len(edge_candidates(z, c, contrast=10)[0]) == 0  # alike colours: nothing to mix
    c[:, 6:] = 40
    assert len(edge_candidates(z, c, contrast=30)[0]) == 18
    z[4, 2] = np.nan  # a hole: its neighbours are candidates, so is the hole's own pixel
    ys, xs = edge_candidates(z, c)
    assert {(y, x) for y, x in zip(ys, xs) if x < 5} == {(y, x) for y in (3, 4, 5) for x in (1, 2, 3)}
    excl = np.zeros(z.shape, bool)
    excl[4, 2] = True
    assert (4, 2) not in set(zip(*edge_candidates(z, c, exclude=excl)))


def test_hard_cases_holes_inf_depth_wide_fields_and_a_view_of_nothing(clutter):
    """Sources with NaN and inf depth beside the sphere, a 150-degree target, a target looking
    away: no warning, holes unchanged, and the usual error when nothing is seen."""
    a, b, truths = clutter
    views = []
    for v in (a, b):
        z = v.depth.copy()
        z[100:140, 200:260] = np.nan
        z[0, :] = np.inf
        views.append(View(v.color, z, v.camera, v.name))
    cam = truths[1].camera
    wide = Camera.from_fov(cam.width, cam.height, hfov_deg=150.0, world_from_cam=cam.world_from_cam)
    turned = cam.with_pose(cam.world_from_cam @ np.diag([-1.0, 1.0, -1.0, 1.0]))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        for target in (cam, wide):
            r = vs.interpolate(*views, target, fill="none", antialias=True)
            p = vs.interpolate(*views, target, fill="none")
            np.testing.assert_array_equal(r.holes, p.holes)
            assert (r.color[r.holes] == 0).all() and (r.color != p.color).any()
        with pytest.raises(ValueError, match="sees nothing"):
            vs.interpolate(*views, turned, fill="none", antialias=True)


def test_fill_modes_and_the_flag(clutter):
    a, b, truths = clutter
    cam = truths[2].camera
    none = vs.interpolate(a, b, cam, fill="none", antialias=True)
    filled = vs.interpolate(a, b, cam, fill="inpaint", antialias=True)
    kept = ~filled.filled  # covered pixels do not depend on the fill (uncovered subsamples stand for their pixel)
    np.testing.assert_array_equal(none.color[kept], filled.color[kept])
    with pytest.raises(TypeError, match="antialias: expected True or False"):
        vs.interpolate(a, b, cam, antialias="yes")
    with pytest.raises(TypeError, match="antialias: expected True or False"):
        vs.warp(a, cam, antialias=1)
    with pytest.raises(ValueError, match="antialias: the edge subsamples trace the quad mesh"):
        vs.interpolate(a, b, cam, method="forward", antialias=True)
    from ibr.sequence.frame_rate import upconvert

    with pytest.raises(ValueError, match="needs method='mesh'"):  # at once, before any frame
        next(upconvert([a, b], 2, method="forward", antialias=True))
    # supersampling subsamples every pixel: the flag changes nothing there
    k3 = [vs.warp(a, cam, supersample=3, antialias=x).color for x in (True, False)]
    np.testing.assert_array_equal(*k3)


def test_bad_input_is_refused_by_name(clutter):
    a = clutter[0]
    mesh = vs.source_mesh(a)
    maps = rasterize_mesh(mesh, a.camera)
    z, c = a.depth, a.color
    with pytest.raises(ValueError, match="depth"):
        edge_candidates(z[None], c)
    with pytest.raises(ValueError, match="color"):
        edge_candidates(z, c[:10])
    with pytest.raises(ValueError, match="depth_tol"):
        edge_candidates(z, c, depth_tol=0)
    with pytest.raises(ValueError, match="exclude"):
        edge_candidates(z, c, exclude=np.zeros((3, 3), bool))
    with pytest.raises(TypeError, match="mesh"):
        subsample_maps("mesh", a.camera, maps, [1], [1])
    with pytest.raises(ValueError, match="maps"):
        subsample_maps(mesh, a.camera.resized(10, 10), maps, [1], [1])
    with pytest.raises(ValueError, match="ys, xs: expected pixels inside"):
        subsample_maps(mesh, a.camera, maps, [1], [10_000])
    with pytest.raises(ValueError, match="ys, xs: expected one row and one column"):
        subsample_maps(mesh, a.camera, maps, [1, 2], [1])
    with pytest.raises(ValueError, match="xs"):
        subsample_maps(mesh, a.camera, maps, [1], [1.5])
    m = len(SUBSAMPLE_OFFSETS)
    with pytest.raises(ValueError, match="sub_same"):
        average_edge_pixels(c.copy(), z, [1], [1], np.zeros((m, 1, 3), np.uint8), np.ones((m, 1), np.float32),
                            np.ones((m, 1), bool), np.ones((m, 2), bool))
    with pytest.raises(ValueError, match="sub_color, sub_depth, sub_coverage"):
        average_edge_pixels(c.copy(), z, [1], [1], np.zeros((m, 2, 3), np.uint8), np.ones((m, 1), np.float32),
                            np.ones((m, 1), bool))
    with pytest.raises(ValueError, match="color"):
        average_edge_pixels(c[..., 0].copy(), z, [1], [1], np.zeros((m, 1, 3), np.uint8),
                            np.ones((m, 1), np.float32), np.ones((m, 1), bool))


def test_cli_interpolate_and_warp_take_antialias(tmp_path, capsys):
    """``--antialias`` on the bundled pair (whole frame against the truth) and on a warp (its
    report over covered pixels): both gain."""
    import re

    import cli
    from ibr.io import read_image

    truth = load_view(DATA_DIR / "clutter_t050.json").color
    scores = {}
    for flag in ((), ("--antialias",)):
        out = tmp_path / f"i{len(flag)}"
        assert cli.main(["interpolate", "--t", "0.5", "--out", str(out), *flag]) == 0
        scores[flag] = psnr(read_image(out / "frame_000_t0.500.png"), truth, np.ones(truth.shape[:2], bool))
    assert scores[("--antialias",)] > scores[()] + 0.1, scores  # measured 37.48 -> 37.70 dB at t = 0.5
    warped = {}
    for flag in ((), ("--antialias",)):
        out = tmp_path / f"w{len(flag)}.png"
        assert cli.main(["warp", str(DATA_DIR / "clutter_a.json"), "--to", str(DATA_DIR / "clutter_t050.json"),
                         "-o", str(out), *flag]) == 0
        warped[flag] = float(re.search(r"PSNR over covered pixels ([0-9.]+) dB", capsys.readouterr().err).group(1))
    assert warped[("--antialias",)] > warped[()] + 0.3, warped


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**31 - 1), st.sampled_from([np.uint8, np.float32]))
def test_random_step_scenes_come_back_unchanged_at_their_own_pose(seed, dtype):
    """Random blocks of depth (steps of any size, NaN holes) and colour: every pixel a source
    covers at its own pose keeps its value with the edge subsamples on."""
    rng = np.random.default_rng(seed)
    h, w = 24, 32
    depth = np.kron(rng.uniform(0.5, 20.0, (h // 4, w // 4)), np.ones((4, 4))).astype(np.float32)
    depth[rng.random((h, w)) < 0.03] = np.nan
    color = (rng.random((h, w, 3)) * (255 if dtype == np.uint8 else 1.0)).astype(dtype)
    v = View(color, depth, Camera(25.0, 25.0, (w - 1) / 2, (h - 1) / 2, w, h), "steps")
    r = vs.warp(v, v.camera, fill="none", antialias=True)
    np.testing.assert_array_equal(r.color[~r.holes], color[~r.holes])


def test_rim_subsamples_are_re_mixed_over_the_new_background(clutter, monkeypatch):
    """Clutter t = 0.5: the grey column along the dark sphere's rim (x = 327-331, y = 80-105; b
    alone sees it, with the light wall behind it in b) comes back in the subsamples unless they
    are re-mixed like the frame's rims (measured max error there 63 -> 41 levels; band 29.90 ->
    29.99 dB over t = .25/.5/.75); the sources still come back exactly at their own poses."""
    a, b, truths = clutter
    cams = [g.camera for g in truths]
    new = vs.interpolate(a, b, cams, fill="none", antialias=True)
    with monkeypatch.context() as m:
        m.setattr(frame, "rematte_subsamples", lambda *args, **kw: 0)
        old = vs.interpolate(a, b, cams, fill="none", antialias=True)
    col = (slice(80, 106), slice(327, 332))
    g = truths[1].color.astype(np.float64)
    err_old, err_new = (np.abs(r[1].color[col] - g[col]).max() for r in (old, new))
    assert err_old > 50 and err_new < 0.75 * err_old, (err_old, err_new)
    band = [np.mean([psnr(r.color, t.color, edge_band(t.depth) & ~r.holes) for r, t in zip(rs, truths)])
            for rs in (old, new)]
    assert band[1] > band[0] + 0.03, band
    for t, v in ((0.0, a), (1.0, b)):
        np.testing.assert_array_equal(vs.interpolate(a, b, t, fill="none", antialias=True).color, v.color)


def test_rim_subsample_re_mix_matches_a_plain_python_reference(clutter, monkeypatch):
    from ibr.render.matting import MIN_CHANGE, rematte_subsamples

    a, b, truths = clutter
    got = {}

    def capture(sub_color, *args, **kw):
        # copies: the frame's colour and depth change later in place (the fill, the averaging)
        copied = [a.copy() if isinstance(a, np.ndarray) else a for a in args]
        got.update(before=sub_color.copy(), args=copied)
        n = rematte_subsamples(sub_color, *args, **kw)
        got.update(after=sub_color.copy(), n=n)
        return n

    monkeypatch.setattr(frame, "rematte_subsamples", capture)
    vs.interpolate(a, b, truths[1].camera, fill="none", antialias=True)
    sub_depth, layers, ys, xs, color, depth, mattes, shapes = got["args"]
    ref = got["before"].astype(np.float64)
    m, n = sub_depth.shape
    count = 0
    for j, (L, matte, (hs, ws)) in enumerate(zip(layers, mattes, shapes)):
        rim = {int(f): k for k, f in enumerate(matte.flat)}
        for s in range(m):
            for i in range(n):
                z = float(sub_depth[s, i])
                if not L.coverage[s, i] or not abs(L.depth[s, i] - z) <= 0.02 * z:
                    continue
                o = layers[1 - j]
                if o.coverage[s, i] and abs(o.depth[s, i] - z) <= 0.02 * z:
                    continue
                su = min(max(int(np.floor(float(L.map_u[s, i]) + 0.5)), 0), ws - 1)
                sv = min(max(int(np.floor(float(L.map_v[s, i]) + 0.5)), 0), hs - 1)
                k = rim.get(sv * ws + su)
                if k is None:
                    continue
                ty = min(max(ys[i] + matte.toward[k, 0], 0), depth.shape[0] - 1)
                tx = min(max(xs[i] + matte.toward[k, 1], 0), depth.shape[1] - 1)
                change = color[ty, tx].astype(np.float64) - matte.behind[k]
                if depth[ty, tx] > z * 1.02 and np.abs(change).max() > MIN_CHANGE * 255:
                    ref[s, i] = np.clip(np.rint(ref[s, i] + (1 - matte.alpha[k]) * change), 0, 255)
                    count += 1
    assert got["n"] == count > 20
    np.testing.assert_array_equal(got["after"], ref)
    with pytest.raises(ValueError, match="sub_color, sub_depth, sub_layers, mattes"):
        rematte_subsamples(got["before"][:, :5], sub_depth, layers, ys, xs, color, depth, mattes, shapes)
    with pytest.raises(TypeError, match="mattes"):
        rematte_subsamples(got["before"], sub_depth, layers, ys, xs, color, depth, ["m", "m"], shapes)
