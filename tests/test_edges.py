"""Issue 11: depth edges and holes -- mixed silhouette pixels, streak-free fill, quantized depth,
level of detail from the camera move. The hard cases: one-pixel poles, a silhouette against a far
background, a hole touching the image border, depth quantized to a few codes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from ibr.base.camera import Camera
from ibr.base.depth import (DepthQuantization, code_step, disparity_step, quantization_of, set_quantization,
                            zbuffer_step)
from ibr.base.view import View
from ibr.mesh import build_mesh
from ibr.mesh.segment import segment
from ibr.render.composite import composite, mixed_pixels, source_trust
from ibr.render.fill import fill_background_rows, fill_pullpush, parallax_axis
from ibr.render.rasterize import Layer
from ibr.render.view_synthesis import interpolate, lod_baseline, source_mesh, warp
from ibr.io import load_view
from samples import DATA_DIR

F = 100.0


def cam(x=0.0, w=64, h=48) -> Camera:
    pose = np.eye(4)
    pose[0, 3] = x
    return Camera(F, F, (w - 1) / 2, (h - 1) / 2, w, h, pose)


def bg_texture(h, w, seed=0):
    rng = np.random.default_rng(seed)
    base = np.linspace(60, 180, w)[None, :, None] * np.ones((h, 1, 3))
    return np.clip(base + rng.normal(0, 20, (h, w, 3)), 0, 255)


# --------------------------------------------------------------------------- quantization steps
def test_quantization_steps_match_the_exact_code_steps():
    z = np.array([1.0, 2.0, 5.0])
    q = DepthQuantization.disparity(baseline=0.24, focal_px=443.4)
    exact = disparity_step(z, baseline=0.24, focal_px=443.4)
    np.testing.assert_allclose(q.step(z), exact, rtol=0.2)  # first order vs the next code
    np.testing.assert_allclose(q.step(z), z**2 / (0.24 * 443.4))
    zb = DepthQuantization.zbuffer(near=0.1, far=100, bits=16)
    np.testing.assert_allclose(zb.step(z), zbuffer_step(z, near=0.1, far=100, bits=16), rtol=0.01)
    mm = DepthQuantization.codes(0.001)
    np.testing.assert_allclose(mm.step(z), code_step(z, scale=0.001))
    np.testing.assert_allclose(mm.inv_step(1 / z), 0.001 / z**2)
    assert hash(q) == hash(DepthQuantization.disparity(baseline=0.24, focal_px=443.4))
    with pytest.raises(ValueError, match="c0"):
        DepthQuantization(c0=-1)


def test_view_file_encoding_carries_its_quantization(tmp_path):
    from ibr.io import load_view, save_view

    z = np.full((8, 10), 2.0, np.float32)
    v = View(np.zeros((8, 10, 3), np.uint8), z, cam(w=10, h=8), "v")
    save_view(v, tmp_path / "mm.json", depth_name="mm_depth.png", depth_params={"scale": 0.001})
    assert quantization_of(load_view(tmp_path / "mm.json")) == DepthQuantization.codes(0.001)
    save_view(v, tmp_path / "f.json")  # float EXR: unquantized
    assert quantization_of(load_view(tmp_path / "f.json")) is None
    save_view(v, tmp_path / "d.json", depth_encoding="disparity",
              depth_params={"baseline": 0.1, "focal_px": F, "doffs": 0.0, "step": 0.25})
    assert quantization_of(load_view(tmp_path / "d.json")) == DepthQuantization.disparity(baseline=0.1, focal_px=F,
                                                                                          step=0.25)
    assert set_quantization(v, None) is v and quantization_of(v) is None


def plane_with_codes(levels: int, w=64, h=48):
    """A tilted plane 1/z = a u + c over the image, stored as integer disparities spanning only
    ``levels`` codes (B f = 10), plus the exact depth."""
    bf = 10.0
    u = np.arange(w)[None, :] * np.ones((h, 1))
    d_exact = 4.0 + (levels - 1) * u / (w - 1)  # disparity, linear in u (a plane)
    z_exact = (bf / d_exact).astype(np.float32)
    z_codes = (bf / np.rint(d_exact)).astype(np.float32)
    return z_exact, z_codes, DepthQuantization.disparity(baseline=bf / F, focal_px=F)


def test_depth_quantized_to_a_few_codes_is_one_plane_not_a_staircase():
    """Hard case: a smooth plane stored in 4 integer disparity codes. Without the quantization
    every code step is a depth edge; with it the staircase is one plane, fitted within the
    tolerance plus half a code of the true plane, and a real step of many codes still splits."""
    z_exact, z_codes, q = plane_with_codes(4)
    c = cam()
    view = View(np.zeros((*z_codes.shape, 3), np.uint8), z_codes, c, "codes")
    naive = build_mesh(view, max_error_px=0.05, baseline=0.1)
    aware = build_mesh(view, max_error_px=0.05, baseline=0.1, quantization=q)
    assert len(naive) >= 4 and len(aware) == 1
    tol = aware.info["tolerance_inv_depth"]
    err = np.abs(1 / aware.depth() - 1 / z_exact).max()
    assert err <= tol + q.c0  # the stored codes are within half a code of the truth
    # a real depth step (8 codes) is still an edge
    z2 = z_codes.copy()
    z2[:, 40:] = 10.0 / (np.rint(10.0 / z2[:, 40:]) + 8)
    stepped = build_mesh(View(view.color, z2, c, "step"), max_error_px=0.05, baseline=0.1, quantization=q)
    assert len(stepped) >= 2 and all((r[0] >= 40) or (r[2] <= 40) for r in stepped.rects)
    # the same through segment() and the default view registry
    assert len(segment(z_codes, camera=c, max_error_px=0.05, baseline=0.1, quantization=q).rects) == 1
    set_quantization(view, q)
    assert len(build_mesh(view, max_error_px=0.05, baseline=0.1)) == 1


def tilted_disparity_plane(du: float, dv: float, w=128, h=96):
    """Disparity d = 20 + du u + dv v (a scene plane: 1/z is affine in (u, v)) over a w x h
    view with B f = 10: its exact depth, its 8-bit integer disparity re-encoding, the
    quantization and the analytic disparity."""
    bf = 10.0
    v, u = np.mgrid[0:h, 0:w].astype(np.float64)
    d = 20.0 + du * u + dv * v
    assert d.max() < 255  # fits 8-bit codes
    c = Camera(F, F, (w - 1) / 2, (h - 1) / 2, w, h, np.eye(4))
    color = np.zeros((h, w, 3), np.uint8)
    exact = View(color, (bf / d).astype(np.float32), c, "exact")
    codes = View(color, (bf / np.rint(d)).astype(np.float32), c, "codes")
    return exact, codes, DepthQuantization.disparity(baseline=bf / F, focal_px=F), d


def mesh_disparity_error_codes(mesh, d) -> np.ndarray:
    """(H, W) signed error of the mesh's planes against the analytic disparity, in codes."""
    return 10.0 / mesh.depth().astype(np.float64) - d


def test_tilted_plane_in_8bit_disparity_is_recovered_to_a_hundredth_of_a_code():
    """A plane tilted in u and v across 12 integer disparity codes: the quantization-aware mesh
    is one quad whose least-squares plane averages the rounding of all codes, within 0.01 code
    of the analytic plane everywhere (the stored codes are up to 0.5 code off; without the
    quantization every step is an edge and the mesh follows the staircase)."""
    _, codes, q, d = tilted_disparity_plane(0.07, 0.04)
    opts = dict(max_error_px=0.05, baseline=0.1)  # tolerance 0.05 code: far below one step
    aware = build_mesh(codes, quantization=q, **opts)
    assert len(aware) == 1
    assert np.abs(mesh_disparity_error_codes(aware, d)).max() < 0.01
    naive = build_mesh(codes, **opts)
    assert len(naive) > 100
    assert np.abs(mesh_disparity_error_codes(naive, d)).max() > 0.45


def test_plane_within_one_code_is_only_known_to_half_a_code():
    """The hard case of 8-bit disparity (issue 11's remaining gap on the bundled scenes): a
    plane spanning less than one code, whose position inside the code is not in its pixels.
    The mesh keeps the stated bound (tolerance + half a code of the truth), and no more: the
    least-squares plane on the codes is flat, 0.43 code off at a corner."""
    _, codes, q, d = tilted_disparity_plane(0.004, 0.002)
    assert np.ptp(np.rint(d)) <= 1
    mesh = build_mesh(codes, quantization=q, max_error_px=0.05, baseline=0.1)
    err = np.abs(mesh_disparity_error_codes(mesh, d)).max()
    assert len(mesh) == 1
    assert err <= mesh.info["tolerance_inv_depth"] / q.c0 + 0.5


@settings(max_examples=40, deadline=None)
@given(du=st.floats(-0.15, 0.15), dv=st.floats(-0.08, 0.08))
def test_any_plane_in_8bit_disparity_has_no_break_edge_and_keeps_the_bound(du, dv):
    """Property over tilts, slow ramps included: the rounded codes of a plane have second
    differences of 0 or +-1 code, so at the quantized break threshold (1.5 codes) no pixel pair
    is a break edge; and every quad of the quantization-aware mesh is within its tolerance plus
    one code of the analytic disparity (half a code to the stored codes, half a code from them
    to the truth). Slow ramps (about 1 % of tilts) split into many quads, within that bound."""
    from ibr.mesh.segment import QUANT_BREAK_CODES, break_edges

    # tilts that reach d <= 2 on the 128 x 96 view are dropped before any view is made (a view
    # refuses the depth 10 / d of a disparity near 0: 1e16 scene units, found by hypothesis)
    assume(20.0 + min(du, 0.0) * 127 + min(dv, 0.0) * 95 > 2)
    _, codes, q, d = tilted_disparity_plane(du, dv)
    hb, vb = break_edges(1.0 / codes.depth.astype(np.float64), QUANT_BREAK_CODES * q.c0)
    assert not hb.any() and not vb.any()
    mesh = build_mesh(codes, quantization=q, max_error_px=0.05, baseline=0.1)
    err = np.abs(mesh_disparity_error_codes(mesh, d)).max()
    assert err <= mesh.info["tolerance_inv_depth"] / q.c0 + 1.0 + 1e-6


def test_exact_depth_mesh_is_unchanged_by_a_zero_step_quantization():
    """Exact float depth: the mesh with a quantization of zero step is bit-identical to the one
    without (the quantized path must reduce to the exact one), and it reproduces the analytic
    plane to float32 precision."""
    exact, _, _, d = tilted_disparity_plane(0.07, 0.04)
    plain = build_mesh(exact, max_error_px=0.05, baseline=0.1)
    zero = build_mesh(exact, max_error_px=0.05, baseline=0.1, quantization=DepthQuantization())
    assert np.array_equal(plain.rects, zero.rects)
    assert np.array_equal(plain.inv_depth_planes, zero.inv_depth_planes)
    assert len(plain) == 1
    assert np.abs(mesh_disparity_error_codes(plain, d)).max() < 1e-4



def test_clutter_in_8bit_disparity_renders_close_to_its_exact_depth():
    """The bundled clutter pair re-encoded as 8-bit integer disparity (its own baseline, like
    Middlebury's ground truth), t = 0.5, covered pixels: within 0.75 dB of the render from the
    exact depth (measured 0.66 at t = 0.5, 0.55 over t = .25/.5/.75; 0.87 at t = 0.5 when second
    differences of two codes never broke an edge, and the post right of the face was drawn a
    pixel too wide). Quads stay fewer than on the exact depth."""
    a, b = load_view(DATA_DIR / "clutter_a.json"), load_view(DATA_DIR / "clutter_b.json")
    truth = load_view(DATA_DIR / "clutter_t050.json")
    bf = float(np.linalg.norm(a.camera.position - b.camera.position)) * a.camera.fx
    codes = [View(v.color, (bf / np.rint(bf / v.depth)).astype(np.float32), v.camera, v.name) for v in (a, b)]
    q = DepthQuantization.disparity(baseline=bf / a.camera.fx, focal_px=a.camera.fx)
    # plain bilinear colour: the geometry's share (sharp sampling, the default, draws both frames
    # crisper, and a misplaced texture then costs more: 0.82 dB apart at t = 0.5, both higher)
    exact = interpolate(a, b, truth.camera, fill="none", interpolation="linear")
    quant = interpolate(*codes, truth.camera, fill="none", mesh_options={"quantization": q}, interpolation="linear")
    sharp = interpolate(*codes, truth.camera, fill="none", mesh_options={"quantization": q})

    def psnr(r):
        d = (r.color.astype(np.float64) - truth.color)[~r.holes]
        return 10 * np.log10(255.0**2 / np.mean(d * d))

    assert psnr(quant) > psnr(exact) - 0.75
    assert psnr(sharp) > psnr(quant) + 0.2
    assert len(source_mesh(codes[0], quantization=q)) < len(source_mesh(a))

# --------------------------------------------------------------------------- mixed pixels, trust
def test_mixed_pixels_mark_both_sides_of_a_step_not_a_steep_plane():
    z = np.full((5, 12), 4.0)
    z[:, 6:] = 2.0
    m = mixed_pixels(z)
    assert m[:, 5].all() and m[:, 6].all() and m[:, :5].sum() == 0 and m[:, 7:].sum() == 0
    steep = 1.0 / (0.05 + 0.04 * np.arange(12))[None, :] * np.ones((5, 1))  # 1/z affine: a plane
    assert not mixed_pixels(steep).any()
    t = source_trust(z)
    assert t.dtype == np.float32 and t[0, 5] < 0.1 and t[0, 0] == 1



def test_one_code_steps_of_quantized_depth_are_no_silhouettes():
    """A tilted wall in integer disparity codes (d = 20 .. 23.x, one-code steps of ~5 % in 1/z,
    flat in between) is a staircase: without its quantization every step is taken for a
    silhouette; with it none is, while a real step of 10 codes on the same wall still is."""
    b, f = 0.2, 500.0
    q = DepthQuantization.disparity(baseline=b, focal_px=f)
    d = np.rint(20.0 + 0.2 * np.arange(18))[None, :] * np.ones((6, 1))
    z = b * f / d
    assert mixed_pixels(z).any()  # the staircase's steps, without the quantization
    assert not mixed_pixels(z, quantization=q).any()
    assert not (source_trust(z, quantization=q) < 1).any()
    d[:, 9:] += 10  # a real step: a nearer object
    m = mixed_pixels(b * f / d, quantization=q)
    assert m[:, 8].all() and m[:, 9].all() and m.sum() == 12

def test_trust_lets_the_clean_layer_win_where_both_agree():
    h, w = 2, 3
    ca = np.full((h, w, 3), 200.0, np.float32)
    cb = np.full((h, w, 3), 100.0, np.float32)
    z = np.full((h, w), 2.0, np.float32)
    la, lb = Layer(ca, z, np.ones((h, w), bool)), Layer(cb, z, np.ones((h, w), bool))
    ka = np.ones((h, w), np.float32)
    ka[0, 0] = 0.0  # a mixed silhouette pixel in layer a
    out = composite([la, lb], [0.5, 0.5], trust=[ka, np.ones((h, w), np.float32)])
    assert abs(out.color[0, 0, 0] - 100.0) < 0.2 and out.color[1, 1, 0] == pytest.approx(150.0)
    plain = composite([la, lb], [0.5, 0.5])
    assert plain.color[0, 0, 0] == pytest.approx(150.0)


def test_one_pixel_pole_leaves_no_ghost_outline():
    """Hard case: a one-pixel-wide pole (z = 2) in front of a smoothly coloured plane (z = 4),
    its two neighbours anti-aliased 50/50 with the pole's red as a real camera would. At the mid
    view the mixed neighbours of each source land 1.5-3.5 px beside the pole, where the other
    source sees clean background: with silhouette trust the ghost is gone (compared with the
    exact mid view), and the pole itself stays red."""
    w, h, b = 65, 24, 0.2  # cx = 32: the pole falls on pixel centres in every view

    def source(x, mixed=True):
        c = cam(x, w, h)
        xw = (np.arange(w) - c.cx) / F * 4.0 + x  # world x of the background under each column
        col = np.zeros((h, w, 3))
        col[:, :, 0] = 60 + 40 * np.sin(2.0 * xw)
        col[:, :, 1] = 140 + 30 * np.cos(1.5 * xw)
        col[:, :, 2] = 180
        z = np.full((h, w), 4.0, np.float32)
        pu = int(round(c.cx + F * (0.0 - x) / 2.0))  # the pole stands at world x = 0
        z[:, pu] = 2.0
        col[:, pu] = (255, 0, 0)
        if mixed:
            for n in (pu - 1, pu + 1):
                col[:, n] = 0.5 * col[:, n] + 0.5 * np.array([255, 0, 0])
        return View(np.rint(col).astype(np.uint8), z, c, f"s{x}{mixed}")

    mid = cam(0.0, w, h)
    a, bb = source(-b / 2), source(b / 2)
    on = interpolate(a, bb, mid, fill="none")
    off = interpolate(a, bb, mid, fill="none", silhouettes=False)
    truth = source(0.0, mixed=False).color.astype(float)
    pole = int(round(mid.cx))
    assert (on.color[:, pole, 0] > 200).all() and (on.color[:, pole, 1] < 60).all()
    away = np.ones(w, bool)
    away[pole - 1:pole + 2] = False  # the pole and its own anti-aliased rim
    ghost = lambda r: np.abs(r.color[:, away].astype(float) - truth[:, away]).max()  # noqa: E731
    assert ghost(off) > 40 and ghost(on) < 0.25 * ghost(off)


# --------------------------------------------------------------------------- hole fill
def test_silhouette_against_a_far_background_fills_with_background_only():
    """Hard case: a near square (z = 1, green) over a far wall (z = 100, textured grey). Moving
    sideways opens a disocclusion beside the square; the fill takes the wall's colour and depth,
    never the square's, and changes no covered pixel."""
    w, h = 64, 48
    col = np.full((h, w, 3), 128.0)
    col += np.linspace(-30, 30, h)[:, None, None]
    z = np.full((h, w), 100.0, np.float32)
    z[14:34, 20:40] = 1.0
    col[14:34, 20:40] = (0, 255, 0)
    v = View(col.astype(np.uint8), z, cam(0.0, w, h), "far")
    target = cam(0.05, w, h)  # the square shifts left by 5 px
    r = warp(v, target)
    assert 0.02 < r.hole_fraction < 0.2 and np.array_equal(r.filled, r.holes)
    none = warp(v, target, fill="none")
    np.testing.assert_array_equal(r.color[~r.holes], none.color[~r.holes])
    g = r.color[r.holes].astype(float)
    assert (g[:, 1] - g[:, 0]).max() < 20  # no green in the holes
    assert np.nanmin(r.depth[r.holes]) > 50  # the wall's depth


def test_hole_touching_the_border_is_filled_exactly_and_deterministically():
    """Hard case: a camera shifted so that a strip at the image border sees nothing; every hole
    pixel is filled (holes == filled), covered pixels are untouched, values are finite, and two
    calls agree bit for bit."""
    w, h = 40, 30
    col = bg_texture(h, w, seed=3).astype(np.uint8)
    v = View(col, np.full((h, w), 3.0, np.float32), cam(0.0, w, h), "wall")
    target = cam(0.3, w, h)  # 10 px strip on the right is uncovered
    r1, r2 = warp(v, target), warp(v, target)
    assert r1.holes[:, -5:].all() and np.array_equal(r1.filled, r1.holes)
    np.testing.assert_array_equal(r1.color, r2.color)
    assert np.isfinite(r1.depth[r1.holes]).all()
    np.testing.assert_allclose(r1.depth[r1.holes], 3.0, rtol=1e-5)
    c, d, f = fill_pullpush(np.zeros((4, 5, 3), np.uint8), np.full((4, 5), np.nan, np.float32),
                            np.ones((4, 5), bool))
    assert not f.any()  # nothing covered: nothing invented
    # whole rows of holes at the bottom with row-wise parallax: the directional half falls back
    # to the columns, so the strip continues the row above it (texture varies along the row)
    holes = np.zeros((h, w), bool)
    holes[-3:] = True
    z = np.where(holes, np.nan, 3.0).astype(np.float32)
    both, _, fb = fill_pullpush(col, z, holes, axis=0)
    smooth, _, _ = fill_pullpush(col, z, holes, axis=0, mix=0.0)
    above = col[-4].astype(float)
    assert fb[holes].all()
    assert np.abs(both[-3:].astype(float) - above).mean() < 0.8 * np.abs(smooth[-3:].astype(float) - above).mean()


def test_pullpush_fill_has_no_streaks():
    """A hole in front of a textured background: the row-wise fill copies one column across the
    hole (streaks: every row constant, rows as different as the texture); the pull-push varies
    smoothly in both directions (vertical differences several times smaller)."""
    h, w = 40, 60
    col = bg_texture(h, w, seed=5).astype(np.float32)
    z = np.full((h, w), 5.0, np.float32)
    holes = np.zeros((h, w), bool)
    holes[5:35, 20:40] = True
    z[holes] = np.nan
    c_pp, z_pp, f = fill_pullpush(col, z, holes, axis=0)
    c_rows, _, _ = fill_background_rows(col, z, ~holes)
    region = (slice(6, 34), slice(22, 38))
    vert = lambda c: np.abs(np.diff(c[region], axis=0)).mean()  # noqa: E731
    assert f[holes].all() and vert(c_pp) < 0.5 * vert(c_rows)
    np.testing.assert_allclose(z_pp[holes], 5.0, rtol=1e-5)
    with pytest.raises(ValueError, match="axis"):
        fill_pullpush(col, z, holes, axis=2)


@pytest.mark.parametrize("dtype, scale", [(np.uint8, 1), (np.uint16, 257), (np.float32, 1 / 255)])
def test_a_strip_no_source_sees_inside_a_shading_ramp_is_filled_along_the_ramp(dtype, scale, monkeypatch):
    """The strip beside a thin pole that neither source sees (clutter at t = 0.75, inside the
    chin's shading): a 5 px hole run in a wall at one depth whose colour falls 7 levels per pixel
    across it is the line between its neighbours, within a level of the ramp in every dtype; the
    directional fill alone copied the farther neighbour (up to 35 levels off) and its half of the
    pull-push left the run flat. A step in depth at the run, or a texture (colour not changing at
    the pace it changes across the run), keeps the background fill as it was."""
    h, w = 24, 40
    u = np.arange(w, dtype=np.float64)
    ramp = np.broadcast_to((200 - 7 * u)[None, :, None], (h, w, 3)) * scale
    z = np.full((h, w), 4.96, np.float32)
    holes = np.zeros((h, w), bool)
    holes[:, 18:23] = True
    color = ramp.astype(dtype)
    filled, depth, f = fill_pullpush(color, np.where(holes, np.nan, z).astype(np.float32), holes, axis=0)
    assert f[holes].all()
    np.testing.assert_allclose(filled[holes].astype(float), ramp[holes], atol=1.01 * scale)
    np.testing.assert_allclose(depth[holes], 4.96, rtol=1e-5)
    # a nearer surface on one side: not one surface, the background side as before
    z_step = z.copy()
    z_step[:, :18] = 2.0
    step, _, _ = fill_pullpush(color, np.where(holes, np.nan, z_step).astype(np.float32), holes, axis=0)
    assert np.abs(step[holes].astype(float) - ramp[holes]).max() > 5 * scale
    # a texture: each row's run the same as with the ramp rule off
    texture = bg_texture(h, w, seed=7).astype(dtype) if dtype == np.uint8 else None
    if texture is not None:
        got, _, _ = fill_pullpush(texture, np.where(holes, np.nan, z).astype(np.float32), holes, axis=0)
        monkeypatch.setattr("ibr.render.fill.RAMP_REL", -1.0)  # the ramp rule off
        want, _, _ = fill_pullpush(texture, np.where(holes, np.nan, z).astype(np.float32), holes, axis=0)
        np.testing.assert_array_equal(got, want)


def test_the_farthest_covered_depth_is_numpy_s_masked_maximum():
    """The fill's reference depth in one pass: the maximum over the pixels outside the holes of
    the finite, positive depths, 0 where there is none (NaN, inf, negative, all holes)."""
    from ibr.render._fill_kernels import covered_max_depth

    rng = np.random.default_rng(11)
    for _ in range(100):
        h, w = rng.integers(1, 20, 2)
        z = rng.uniform(-1, 10, (h, w)).astype(np.float32)
        z[rng.random((h, w)) < 0.2] = np.nan
        z[rng.random((h, w)) < 0.1] = np.inf
        holes = rng.random((h, w)) < 0.4
        want = float(np.max(z, where=~holes & (z > 0) & (z < np.inf), initial=0.0))
        assert float(covered_max_depth(z, holes)) == want
    assert covered_max_depth(np.full((3, 3), 5.0, np.float32), np.ones((3, 3), bool)) == 0.0


def test_parallax_axis_follows_the_camera_move():
    c = cam()
    up = np.eye(4)
    up[1, 3] = 0.3
    assert parallax_axis(c, [cam(0.2)]) == 0
    assert parallax_axis(c, [Camera(F, F, 31.5, 23.5, 64, 48, up)]) == 1


# --------------------------------------------------------------------------- level of detail
def test_level_of_detail_comes_from_the_camera_move():
    w, h = 48, 32
    u = np.arange(w)[None, :] * np.ones((h, 1))
    z = (1.0 / (0.25 + 0.002 * u + 0.0005 * (u - 24) ** 2 / 24)).astype(np.float32)  # curved
    v = View(np.zeros((h, w, 3), np.uint8), z, cam(0.0, w, h), "curve")
    med = float(np.median(z))
    assert lod_baseline(v, [cam(0.01, w, h)]) == pytest.approx(0.05 * med)  # small move: the floor
    big = lod_baseline(v, [cam(0.4, w, h), cam(0.3, w, h)])
    assert 0.4 <= big <= 0.4 * np.sqrt(2) and np.log2(big) * 2 == pytest.approx(round(np.log2(big) * 2))
    far = warp(v, cam(0.4, w, h), fill="none")
    assert far.hole_fraction < 0.5
    fine = source_mesh(v, baseline=big)  # the mesh the call built and cached
    assert fine is source_mesh(v, baseline=big)
    assert len(fine) >= len(source_mesh(v))  # a bigger move needs at least as many quads
    err_px = np.abs(1 / fine.depth() - 1 / z).max() * F * big
    assert err_px <= 0.5 + 1e-6


def test_mixed_pixels_in_strips_equal_the_whole_image(monkeypatch):
    """mixed_pixels works in strips of rows (columns) to bound its memory: any strip size gives
    the marks of the whole image at once (steps, NaN borders, one-pixel objects)."""
    import ibr.render.composite as C

    rng = np.random.default_rng(3)
    z = rng.uniform(1, 5, (70, 90)).astype(np.float32)
    z[:, 45:] *= 3
    z[rng.random(z.shape) < 0.05] = np.nan
    z[:, 20] = 0.5  # a one-pixel pole
    monkeypatch.setattr(C, "_STRIP_PIXELS", 1 << 40)
    whole = C.mixed_pixels(z)
    assert 0.05 < whole.mean() < 0.9
    for strip in (1, 90, 200, 1000):
        monkeypatch.setattr(C, "_STRIP_PIXELS", strip)
        np.testing.assert_array_equal(C.mixed_pixels(z), whole)


def test_background_rim_beside_a_disocclusion_is_marked_for_the_fill():
    """A pixel that only one source covers, sampled from that source's background rim (its
    colour mixes in the foreground beside it), is marked for the fill where the target shows a
    hole next to it (a disocclusion) and not where no hole is beside it (the source's own pose)."""
    from ibr.render.composite import rim_beside_holes

    z = np.full((5, 8), 4.0, np.float32)
    z[:, 4:] = 1.0  # foreground on the right: column 3 is the background rim
    rim = mixed_pixels(z, side="far")
    assert rim[:, 3].all() and rim.sum() == 5  # the farther side only
    assert mixed_pixels(z)[:, 3:5].all() and mixed_pixels(z).sum() == 10  # both sides
    coverage = np.ones((5, 8), bool)
    coverage[:2, 2] = False  # a disocclusion beside the rim in rows 0-1 only
    replace = rim_beside_holes(coverage, rim)
    assert replace[:2, 3].all() and replace.sum() == 2


def _rim_source():
    """A source 5 x 8 with a background (depth 4, colour 30) on the left and a foreground (depth 1,
    colour 200) on the right: column 3 is its background rim, whose colour (120) mixes in the
    foreground's. Returns its depth, rim (``mixed_pixels(side="far")``) and colour."""
    z = np.full((5, 8), 4.0, np.float32)
    z[:, 4:] = 1.0
    color = np.full((5, 8, 3), 30, np.uint8)
    color[:, 3] = 120
    color[:, 4:] = 200
    return z, mixed_pixels(z, side="far"), color


def _background_layer(h: int, w: int, cols, src_u):
    """SourceMaps of an h x w target whose columns ``cols`` sample the source's row v at column
    ``src_u`` (depth 4, the background); the other columns are not covered."""
    from ibr.render.rasterize import SourceMaps

    rows = np.repeat(np.arange(h, dtype=np.float32)[:, None], w, 1)
    u = np.full((h, w), -1e6, np.float32)
    d = np.full((h, w), np.nan, np.float32)
    u[:, cols], d[:, cols] = src_u, 4.0
    return SourceMaps(u, np.where(np.isnan(d), np.float32(-1e6), rows), d, ~np.isnan(d))


def test_background_rim_beside_the_other_sources_pixels_is_marked_for_the_fill():
    """A rim sample of source a whose neighbour only source b covers (a's surface ends there: the
    foreground beside it in a has moved away; no hole is left between the two) is marked too, by
    the 8-bit, the float and the bicubic paths alike; a rim sample inside a's own layer is not
    (the pole-rim lines on the clutter pair's face, issue 11)."""
    from ibr.render.composite import pack_trust, remap_composite, rgbt_source, sample_composite, source_trust
    from ibr.render.frame_composite import _rim_samples_beside_gaps

    z, rim, color = _rim_source()
    h, w = 5, 6
    # target columns 0-2 from b's clean background, 3-5 from a: column 3 and 4 on a's rim pixel
    maps = [_background_layer(h, w, [3, 4, 5], [3.0, 3.0, 1.0]), _background_layer(h, w, [0, 1, 2], [0.0, 1.0, 2.0])]
    expected = np.zeros((h, w), bool)
    expected[:, 3] = True  # beside column 2, which only b covers; column 4 has a on both sides
    packed = pack_trust(source_trust(z), rim)
    weights = np.array([0.5, 0.5])
    exact = sample_composite([color, color], maps, weights, dtype=np.uint8, trust=[packed, packed])
    fast = remap_composite([rgbt_source(color, packed[..., 0])] * 2, maps, weights, rims=[rim, rim])
    assert exact.coverage.all() and fast.coverage.all()  # no hole anywhere
    np.testing.assert_array_equal(exact.replace, expected)
    np.testing.assert_array_equal(fast.replace, expected)
    np.testing.assert_array_equal(_rim_samples_beside_gaps(maps, [rim, rim]), expected)


def test_two_rim_samples_each_beside_its_own_layer_s_gap_are_marked_for_the_fill():
    """Where both layers see one surface through background-rim samples, each beside a pixel its
    own layer does not cover, neither source has the surface's colour there (the dot at (74, 230)
    beside clutter's left pole at t = 0.75): the fill recolours it, in the 8-bit, the float and
    the bicubic paths alike. Where one of the two samples is clean, the blend keeps it."""
    from ibr.render.composite import pack_trust, remap_composite, rgbt_source, sample_composite
    from ibr.render.frame_composite import _rim_samples_beside_gaps

    z, rim, color = _rim_source()
    h, w = 5, 7
    # a covers columns 3-6 (its gap: 0-2), b covers 0-3 (its gap: 4-6); column 3 from both rims
    a = _background_layer(h, w, [3, 4, 5, 6], [3.0, 0.0, 1.0, 2.0])
    b = _background_layer(h, w, [0, 1, 2, 3], [0.0, 1.0, 2.0, 3.0])
    b.map_u[:2, 3] = 1.0  # rows 0-1: b's sample there is clean
    expected = np.zeros((h, w), bool)
    expected[2:, 3] = True
    packed = pack_trust(source_trust(z), rim)
    weights = np.array([0.5, 0.5])
    exact = sample_composite([color, color], [a, b], weights, dtype=np.uint8, trust=[packed, packed])
    fast = remap_composite([rgbt_source(color, packed[..., 0])] * 2, [a, b], weights, rims=[rim, rim])
    for comp in (exact, fast):
        assert comp.coverage.all()
        np.testing.assert_array_equal(comp.replace, expected)
        assert (np.abs(comp.color[:2, 3].astype(int) - 30) <= 2).all()  # the clean sample wins the blend
    np.testing.assert_array_equal(_rim_samples_beside_gaps([a, b], [rim, rim]), expected)


def test_a_clean_sample_beside_its_layer_s_gap_keeps_the_background_rim_s_colour_out():
    """A one-layer sample between a clean background pixel (nearest) and the background rim,
    within 2 px of its layer's gap, is the clean colour: the rim's foreground colour there is a
    fainter second line beside the rim sample the fill recolours (the dotted line beside clutter's
    left pole at t = 0.75, issue 11). Farther from the gap, or nearest to the rim, it is the
    plain bilinear sample. The 8-bit path (with and without the 2 x 2 upsampled sources of sharp
    sampling), the float path and the float-layer paths' mending alike."""
    from ibr.render.composite import pack_trust, remap_composite, rgbt_source, sample_composite, trust_channel
    from ibr.render.sharp_sampling import upsample_rgbt
    from ibr.render.frame_composite import _keep_rims_out

    z, rim, color = _rim_source()
    trust = source_trust(z)
    h, w = 5, 8
    # a covers target columns 0-4, column 5 is a hole, b covers 6-7 with clean background
    maps = [_background_layer(h, w, [0, 1, 2, 3, 4], [2.4, 2.6, 1.0, 2.4, 2.4]),
            _background_layer(h, w, [6, 7], [0.0, 1.0])]
    weights = np.array([0.5, 0.5])
    packed = pack_trust(trust, rim)
    up = upsample_rgbt(color, trust_channel(trust, z.shape))
    got = {"float": [sample_composite([color, color], maps, weights, dtype=np.uint8, trust=t)
                     for t in ([packed, packed], None)],
           "8-bit": [remap_composite([rgbt_source(color, trust)] * 2, maps, weights, rims=r)
                     for r in ([rim, rim], None)],
           "8-bit 2x2": [remap_composite([up, up], maps, weights, rims=r, source_scale=2) for r in ([rim, rim], None)]}
    # the float-layer paths (bicubic; sharp sampling of colour that is not 8-bit RGB) mend their composite after it
    plain = sample_composite([color, color], maps, weights, dtype=np.uint8)
    mended = sample_composite([color, color], maps, weights, dtype=np.uint8)
    _keep_rims_out(mended.color, maps, [color, color], [packed, packed])
    got["float layers"] = [mended, plain]
    for name, (comp, plain) in got.items():  # plain: without the silhouettes' trust and rims
        c, p = comp.color[..., 0].astype(int), plain.color[..., 0].astype(int)
        assert (p[:, 3:5] > 45).all() and (np.abs(c[:, 3:5] - 30) <= 2).all(), name  # rim trust 0.03
        np.testing.assert_array_equal(c[:, :3], p[:, :3], err_msg=name)  # 5 px from the hole; the rim's own
        assert (p[:, 1] > p[:, 0]).all() and (c[:, 2] == 30).all() and (c[:, 6:] == 30).all(), name
        assert not comp.coverage[:, 5].any()


def test_a_stray_sample_inside_a_hole_is_recoloured_and_a_lone_source_pixel_kept():
    """A far pixel beside a near block in the source (a depth outlier, as in real disparity maps)
    stays where it was when the camera moves, while the block moves 10 px away: alone in the
    target, it is recoloured by the fill (covered, its depth kept). A far pixel that is alone in
    its source too (no neighbour has depth) is what the source recorded and keeps its colour; with
    ``fill="none"`` nothing is recoloured."""
    h, w = 40, 50
    cam = Camera(50.0, 50.0, (w - 1) / 2, (h - 1) / 2, w, h)
    depth = np.full((h, w), np.nan, np.float32)
    depth[10:30, 10:30] = 2.0
    depth[20, 30] = depth[5, 40] = 1000.0  # beside the block / alone
    color = np.zeros((h, w, 3), np.uint8)
    color[10:30, 10:30] = color[5, 40] = 100  # what the fill has to draw from: 100 everywhere
    color[20, 30] = 250
    pose = np.eye(4)
    pose[0, 3] = 0.4  # the block (z = 2) moves 10 px, the far pixels 0.02 px
    target = Camera(50.0, 50.0, (w - 1) / 2, (h - 1) / 2, w, h, pose)
    view = View(color, depth, cam, "outlier")
    raw = warp(view, target, fill="none")
    assert not raw.holes[20, 30] and not raw.holes[5, 40] and raw.holes[19:22, 29:32].sum() == 8
    assert raw.color[20, 30].min() > 200 and not raw.filled.any()
    r = warp(view, target)
    assert not r.holes[20, 30] and r.filled[20, 30] and r.depth[20, 30] == raw.depth[20, 30]
    assert abs(int(r.color[20, 30, 0]) - 100) <= 10  # recoloured from the covered pixels around
    assert not r.filled[5, 40] and (r.color[5, 40] == raw.color[5, 40]).all()
    np.testing.assert_array_equal(r.holes, raw.holes)  # the hole mask stays exact


def test_ghost_outline_beside_a_disocclusion_is_gone_after_the_fill():
    """Clutter t = 0.75: behind the pole a disocclusion opens on the face; the background rim of
    the pole in the source (dark, pole colour mixed in) lay along it as a dark sliver. With
    silhouette-aware sources that rim is recoloured by the fill (measured in the 20 x 40 box:
    33.2 dB against 26.7 without; full frame 36.54 against 35.70), and the hole mask is unchanged."""
    a, b = load_view(DATA_DIR / "clutter_a.json"), load_view(DATA_DIR / "clutter_b.json")
    truth = load_view(DATA_DIR / "clutter_t075.json")
    new = interpolate(a, b, truth.camera, fill="inpaint")
    old = interpolate(a, b, truth.camera, fill="inpaint", silhouettes=False)
    box = (slice(70, 110), slice(215, 235))

    def psnr(x, y):
        d = x.astype(np.float64) - y.astype(np.float64)
        return 10 * np.log10(255.0**2 / np.mean(d * d))

    assert psnr(new.color[box], truth.color[box]) > psnr(old.color[box], truth.color[box]) + 5
    assert psnr(new.color, truth.color) > psnr(old.color, truth.color) + 0.5
    np.testing.assert_array_equal(new.holes, old.holes)
    assert 0 < (new.filled & ~new.holes).sum() < 0.01 * new.holes.size


def test_sliver_between_two_foreground_edges_takes_the_background_not_the_farther_edge():
    """Hard case (the clutter box at t = 0.75): a 3-px hole between a near post (z = 1.5) and a
    box (z = 3.4) in every row, the wall (z = 5, white) visible above and below. On the row both
    neighbours are foreground, the box the farther: copying it drew a dark line. The fill now
    keeps the directional colour only where its source is as far as the pull-push's depth, so
    the sliver takes the wall's colour; a wide disocclusion (run > DIRECT_CHECK_RUN) still takes
    the directional colour."""
    from ibr.render import fill as F

    h, w = 40, 40
    col = np.full((h, w, 3), 230, np.uint8)  # the wall
    z = np.full((h, w), 5.0, np.float32)
    rows = slice(8, 32)
    col[rows, :18], z[rows, :18] = 10, 1.5  # the post
    col[rows, 21:], z[rows, 21:] = (20, 30, 60), 3.4  # the box
    holes = np.zeros((h, w), bool)
    holes[rows, 18:21] = True
    z[holes] = np.nan
    c, d, f = fill_pullpush(col, z, holes, axis=0)
    assert f[holes].all() and np.median(d[holes]) > 4.0  # mostly the wall's depth
    assert c[holes].astype(float).mean() > 130  # mostly the wall's colour (230), not the box's (~35)
    old = F.DIRECT_CHECK_RUN
    try:
        F.DIRECT_CHECK_RUN = 0  # every run unchecked (before #11's fix): the box's colour leaks in
        c0, _, _ = fill_pullpush(col, z, holes, axis=0)
    finally:
        F.DIRECT_CHECK_RUN = old
    assert c0[holes].astype(float).mean() < c[holes].astype(float).mean() - 40
    # a wide run (12 px) between the post and the box: the directional colour stays (the box)
    wide = np.zeros((h, w), bool)
    wide[rows, 18:30] = True
    zw = np.where(wide, np.nan, np.where(np.arange(w) >= 30, 3.4, z)).astype(np.float32)
    cw = col.copy()
    cw[rows, 30:] = (20, 30, 60)
    a, _, _ = fill_pullpush(cw, zw, wide, axis=0)
    b, _, _ = fill_pullpush(cw, zw, wide, axis=0, mix=0.0)
    assert np.abs(a[wide].astype(float) - b[wide]).mean() > 10  # the directional half was mixed in


def test_pullpush_hard_cases_corner_out_of_view_inf_depth_tiny_eps_int32():
    """Hard cases of the pull-push fill on a uniform grey scene (the fill must give the grey
    back): an L-shaped out-of-view border (top rows and left columns, as after a diagonal
    move), where the corner block has no covered pixel on its row or column and whatever the
    caller left in the holes (0 or 255) leaked into the smoothed directional half; one +inf
    depth (it set the reference depth to inf and turned the whole fill off); push strengths so
    small that the weights became denormal (1 / weight overflowed to inf / NaN); int32 colour
    (OpenCV cannot filter it)."""
    h, w = 60, 80
    grey = np.full((h, w, 3), 100, np.uint8)
    depth = np.full((h, w), 5.0, np.float32)
    holes = np.zeros((h, w), bool)
    holes[:6] = True
    holes[:, :6] = True
    outs = []
    for left_in_holes in (0, 255):
        c = grey.copy()
        c[holes] = left_in_holes
        out, _, filled = fill_pullpush(c, depth, holes)
        assert filled[holes].all() and not filled[~holes].any()
        outs.append(out)
    np.testing.assert_array_equal(outs[0], grey)
    np.testing.assert_array_equal(outs[1], grey)
    z_inf = depth.copy()
    z_inf[30, 40] = np.inf
    out, z, filled = fill_pullpush(grey, z_inf, holes)
    assert filled[holes].all() and (out == 100).all() and np.isfinite(z[holes]).all()
    big = np.zeros((256, 256), bool)
    big[20:236, 20:236] = True
    g256 = np.full((256, 256, 3), 0.4, np.float32)
    for eps in (1e-8, 1e-10):
        out, z, filled = fill_pullpush(g256, np.full((256, 256), 5.0, np.float32), big, eps=eps)
        assert filled[big].all() and np.isfinite(out).all() and np.isfinite(z[big]).all()
        np.testing.assert_allclose(out[big], 0.4, atol=1e-6)
    out, _, filled = fill_pullpush(grey.astype(np.int32), depth, holes)
    assert out.dtype == np.int32 and (out == 100).all()


def test_one_pixel_cracks_between_the_quads_of_a_curved_surface_are_closed():
    """Two neighbouring quads of a curved surface have different planes, so their shared edge
    opens by a pixel in another view (``rasterize_mesh`` keeps that exact coverage); view
    synthesis closes such row cracks from the pixels beside them. On clutter a warped to the
    t = 0.5 camera the closed pixels lie on the true surface (depth within 1 %, against the
    exact ground truth) with the covered pixels' colour accuracy; at t = 0.5 of the pair the
    background no longer shows through the dark sphere's rim (a jagged orange line)."""
    from ibr.render.rasterize import rasterize_mesh
    from ibr.render.sources import _lod_options

    a, b = load_view(DATA_DIR / "clutter_a.json"), load_view(DATA_DIR / "clutter_b.json")
    truth = load_view(DATA_DIR / "clutter_t050.json")
    r = warp(a, truth.camera, fill="none")
    exact = rasterize_mesh(source_mesh(a, **_lod_options(a, [truth.camera], {}, "move")), truth.camera)
    closed = ~exact.coverage & ~r.holes
    assert not (exact.coverage & r.holes).any()  # only uncovered pixels are closed
    assert closed.sum() >= 100
    rel = np.abs(r.depth[closed] - truth.depth[closed]) / truth.depth[closed]
    assert rel.max() < 0.01
    err = np.abs(r.color.astype(int) - truth.color.astype(int)).mean(-1)
    assert err[closed].mean() < 2.5 * err[~r.holes].mean()
    # the rim of the dark sphere at t = 0.5 (only source a sees it): the five pixels of the crack
    # line that showed source b's orange background (~100 levels off) now within 5 levels
    mid = interpolate(a, b, truth.camera, fill="none")
    ys, xs = np.array([182, 183, 184, 185, 186]), np.array([199, 199, 199, 200, 200])
    d = np.abs(mid.color[ys, xs].astype(int) - truth.color[ys, xs].astype(int)).max(-1)
    assert d.max() <= 5, d


def _two_quad_step(axis, t, w=200, h=200):
    """Two quads of 1/z planes 0.5 and 0.4925 (z = 2 and 2.03) meeting along a horizontal
    (``axis`` 0) or vertical (1) edge, and a target camera moved by ``t`` across that edge."""
    from ibr.mesh.quad_mesh import QuadMesh

    src = Camera(100.0, 100.0, (w - 1) / 2, (h - 1) / 2, w, h)
    half = [[0, 0, w, h // 2], [0, h // 2, w, h]] if axis == 0 else [[0, 0, w // 2, h], [w // 2, 0, w, h]]
    qop = np.zeros((h, w), np.int32)
    qop[(slice(h // 2, None), slice(None)) if axis == 0 else (slice(None), slice(w // 2, None))] = 1
    mesh = QuadMesh(src, np.array(half, np.int32), np.array([[0.0, 0.0, 0.5], [0.0, 0.0, 0.5 * 0.985]]), qop, {})
    pose = np.eye(4)
    pose[1 if axis == 0 else 0, 3] = t
    return mesh, Camera(100.0, 100.0, (w - 1) / 2, (h - 1) / 2, w, h, pose)


@pytest.mark.parametrize("axis", [0, 1])
def test_a_one_pixel_crack_along_rows_is_closed_and_a_wider_gap_is_not(axis):
    """The shared edge of two quads 1.5 % apart in depth opens into a one-pixel line when the
    camera moves across it. A vertical edge (``axis`` 1) opens a column of one-pixel gaps along
    the rows: view synthesis's crack closing fills exactly that line, at a depth between the two
    planes', the same on every run (two threads, row bands). A horizontal edge (0, vertical
    parallax) opens a row of gaps along the columns: left to the fill (a column pass cost 6 %
    of a warp for +0.04 dB). A gap of several pixels (a larger move) stays open."""
    from ibr.render.rasterize import CRACK_REL, SourceMaps, _rasterize_many_into

    def render(mesh, cam, rel):
        h, w = cam.shape
        out = SourceMaps(*(np.empty((h, w), np.float32) for _ in range(3)), np.empty((h, w), np.bool_))
        return _rasterize_many_into([mesh], cam, "free", 0.01, [out], crack_rel=rel)[0]

    mesh, cam = _two_quad_step(axis, 1.6)
    exact, closed = render(mesh, cam, 0.0), render(mesh, cam, CRACK_REL)
    line = ~exact.coverage & closed.coverage
    cov = exact.coverage
    inner = np.zeros_like(cov)
    if axis == 0:
        inner[1:-1] = ~cov[1:-1] & cov[:-2] & cov[2:]
    else:
        inner[:, 1:-1] = ~cov[:, 1:-1] & cov[:, :-2] & cov[:, 2:]
    assert inner.sum() == 200  # the one-pixel line is there
    if axis == 0:
        assert not line.any()
        return
    assert np.array_equal(line, inner)  # the whole one-pixel line, nothing else
    assert ((closed.depth[line] > 2.0 - 1e-3) & (closed.depth[line] < 2.0 / 0.985 + 1e-3)).all()
    again = render(mesh, cam, CRACK_REL)
    for name in ("depth", "map_u", "map_v", "coverage"):
        assert np.array_equal(getattr(again, name), getattr(closed, name), equal_nan=True)
    mesh, cam = _two_quad_step(axis, 4.0, 600, 600)  # a gap of 2-3 px: a disocclusion, not a crack
    wide_exact, wide = render(mesh, cam, 0.0), render(mesh, cam, CRACK_REL)
    line = wide_exact.coverage[:, 300] if axis == 0 else wide_exact.coverage[300]
    gaps = np.diff(np.flatnonzero(line))
    assert gaps.max() >= 3  # the open gap between the two quads
    assert np.array_equal(wide.coverage, wide_exact.coverage)


@pytest.mark.parametrize("axis", [1])
def test_the_gap_behind_a_one_pixel_pole_is_no_crack(axis):
    """Behind a one-pixel pole the wall on both sides of its disocclusion
    agrees in depth, but halfway between the two wall samples the source shows the pole: crack
    closing drew the pole's colour there at the wall's depth (224 levels off). The source surface
    test leaves that gap a hole, for the fill: the wall's colour within its texture's 30 levels."""
    from ibr.render.rasterize import CRACK_REL

    h, w = 64, 96
    z = np.full((h, w), 5.0, np.float32)
    col = np.zeros((h, w, 3), np.uint8)
    col[...] = (200, 0, 129)
    if axis == 1:
        z[:, 48], col[:, 48] = 2.0, (20, 230, 10)
    else:
        z[32], col[32] = 2.0, (20, 230, 10)
    src = Camera(80.0, 80.0, (w - 1) / 2, (h - 1) / 2, w, h)
    pose = np.eye(4)
    pose[0 if axis == 1 else 1, 3] = 0.07
    target = Camera(80.0, 80.0, (w - 1) / 2, (h - 1) / 2, w, h, pose)
    r = warp(View(col, z, src, "pole"), target)
    assert CRACK_REL > 0
    wall = r.depth > 4
    err = np.abs(r.color.astype(int) - np.array([200, 0, 129])).max(-1)
    assert wall.sum() > 0.8 * h * w and err[wall].max() <= 30


def test_a_region_out_of_the_sources_view_is_filled_smoothly_not_with_bands():
    """A target seeing far past the source's edges (120 degrees from b's pose: 9 % of the frame is
    more than 160 px from any covered pixel) was filled with the directional copies' long
    horizontal and vertical bands; beyond DIRECT_FADE_PX the pull-push alone fills, smooth (mean
    |difference| of neighbouring pixels there 0.001 / 0.004 levels)."""
    import cv2

    import ibr
    from ibr.render.fill import DIRECT_FADE_PX
    from samples import DATA_DIR

    a, b = ibr.load_view(DATA_DIR / "clutter_a.json"), ibr.load_view(DATA_DIR / "clutter_b.json")
    cam = Camera.from_fov(512, 384, hfov_deg=120, world_from_cam=b.camera.world_from_cam)
    out = ibr.warp(a, cam)
    dist = cv2.distanceTransform(out.holes.astype(np.uint8), cv2.DIST_L2, 5)
    far = dist > DIRECT_FADE_PX[1]
    assert far.mean() > 0.05
    c = out.color.astype(float)
    across_cols = np.abs(np.diff(c, axis=1)).mean(-1)[far[:, 1:] & far[:, :-1]].mean()
    across_rows = np.abs(np.diff(c, axis=0)).mean(-1)[far[1:] & far[:-1]].mean()
    assert across_cols < 0.05 and across_rows < 0.05


def test_the_far_field_test_sees_bands_along_the_right_and_bottom_edges():
    """The all-hole block test cut the image to whole blocks: a far band along the right or bottom
    edge (or an image narrower than a block) was never tested and kept its bands."""
    from ibr.render.fill import _far_from_covered

    right = np.zeros((300, 180), bool)
    right[:, 46:] = True  # a 134-px band: 134 px from the covered part at the image's edge
    narrow = np.ones((40, 1000), bool)
    narrow[:, 0] = False  # one covered column: 999 px away at the far end
    for holes in (right, right.T, narrow, right[:, ::-1], right.T[::-1]):
        fade = _far_from_covered(np.ascontiguousarray(holes))
        assert fade is not None and fade.max() > 0 and fade[~holes].max() == 0


def test_no_covered_pixel_off_clutters_edge_band_is_wrong_by_more_than_48_levels():
    """Issue 11's off-band target on the bundled clutter pair (t = .25/.5/.75, the default fill,
    covered pixels as delivered): none more than 48/255 off in any channel outside the ±1 px band
    of the truth's depth edges. The last one, (190, 148) at t = 0.75, was a blend of two mixed
    samples in which the one 15 % on a clean pixel lost to the wholly mixed one (the pole's grey,
    52 levels off) until the trust floor went from 1e-3 to 3e-4; texture sparkles went with
    sharp sampling (bilinear colour: 1, 2, 1)."""
    from scipy import ndimage

    from ibr.base.depth import depth_steps

    a, b = load_view(DATA_DIR / "clutter_a.json"), load_view(DATA_DIR / "clutter_b.json")
    for name in ("clutter_t025", "clutter_t050", "clutter_t075"):
        truth = load_view(DATA_DIR / f"{name}.json")
        r = interpolate(a, b, truth.camera, fill="inpaint")
        with np.errstate(divide="ignore"):
            band = ndimage.binary_dilation(depth_steps(1.0 / truth.depth, 0.02), np.ones((3, 3), bool))
        err = np.abs(r.color.astype(int) - truth.color.astype(int)).max(-1)
        off = (err > 48) & ~band & ~r.holes
        assert not off.any(), (name, np.argwhere(off)[:5].tolist())
