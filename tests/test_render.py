"""Quad-mesh inverse warp (ibr.render): exact geometry, fill rule, z-buffer, clipping, sampling.

Geometry is checked against analytic ray-plane intersections and against the independent numpy
reference ``rasterize_mesh_reference`` (world-frame planes from quad corners); colors against
the ray caster's ground-truth renders of the same plane.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ibr import synth
from ibr.base.camera import Camera, look_at
from ibr.mesh.quad_mesh import QuadMesh, build_mesh
from ibr.render.rasterize import Layer, rasterize_mesh, rasterize_mesh_reference, render_mesh
from ibr.base.view import View


# ----------------------------------------------------------------------------- helpers
def plane_coeffs(cam: Camera, point_w, normal_w) -> np.ndarray:
    """(a, b, c) with 1/z = a u + b v + c in ``cam``'s pixels for the world plane through
    ``point_w`` with normal ``normal_w`` (requires the plane not to pass through the camera)."""
    r = cam.world_from_cam[:3, :3]
    nw = np.asarray(normal_w, float)
    d = nw @ (np.asarray(point_w, float) - cam.position)
    n = r.T @ nw / d  # n . X_cam = 1
    a, b = n[0] / cam.fx, n[1] / cam.fy
    return np.array([a, b, n[2] - a * cam.cx - b * cam.cy])


def mesh_from_rects(cam, rects, planes) -> QuadMesh:
    rects = np.asarray(rects, np.int32).reshape(-1, 4)
    planes = np.asarray(planes, float).reshape(-1, 3)
    qop = np.full(cam.shape, -1, np.int32)
    for i, (u0, v0, u1, v1) in enumerate(rects):
        qop[v0:v1, u0:u1] = i
    return QuadMesh(cam, rects, planes, qop)


def random_partition(rng, u0, v0, u1, v1, min_size=1, p_stop=0.25):
    """Random binary split of a rectangle into half-open rects (like the seed's split)."""
    if (u1 - u0 <= min_size and v1 - v0 <= min_size) or rng.random() < p_stop:
        return [[u0, v0, u1, v1]]
    if (u1 - u0 >= v1 - v0 and u1 - u0 > min_size) or v1 - v0 <= min_size:
        s = int(rng.integers(u0 + 1, u1)) if u1 - u0 > 1 else u0
        if s == u0:
            return [[u0, v0, u1, v1]]
        return random_partition(rng, u0, v0, s, v1, min_size, p_stop) + random_partition(rng, s, v0, u1, v1, min_size, p_stop)
    s = int(rng.integers(v0 + 1, v1))
    return random_partition(rng, u0, v0, u1, s, min_size, p_stop) + random_partition(rng, u0, s, u1, v1, min_size, p_stop)


def analytic_maps(src: Camera, tgt: Camera, point_w, normal_w):
    """Exact source coordinates and target depth of an infinite world plane, per target pixel."""
    o, _ = tgt.rays_world()
    d = tgt.rays_cam() @ tgt.world_from_cam[:3, :3].T  # z_t = 1 scaled
    nw = np.asarray(normal_w, float)
    lam = ((np.asarray(point_w) - o) @ nw) / (d @ nw)
    pts = o + lam[..., None] * d
    uv, zs = src.project(pts.reshape(-1, 3))
    return uv.reshape(*tgt.shape, 2), lam, zs.reshape(tgt.shape)


def random_pose(rng, scale=0.5, ang=0.2):
    pose = np.eye(4)
    pose[:3, :3] = Rotation.from_rotvec(rng.normal(0, ang, 3)).as_matrix()
    pose[:3, 3] = rng.normal(0, scale, 3)
    return pose


SRC = Camera.from_fov(64, 48, hfov_deg=60)


# ----------------------------------------------------------------------------- exact geometry
@pytest.mark.parametrize("seed", range(6))
def test_kernel_matches_reference_on_random_meshes(seed):
    """Random partitions with random (also steep) planes, random target poses and intrinsics."""
    rng = np.random.default_rng(seed)
    rects = random_partition(rng, 0, 0, SRC.width, SRC.height, min_size=1, p_stop=0.15)
    mesh = mesh_from_rects(SRC, rects, random_planes(rng, rects, (1, 4), 0.004))
    for k in range(4):
        tgt = Camera(rng.uniform(30, 80), rng.uniform(30, 80), rng.uniform(20, 40), rng.uniform(15, 30),
                     56, 40, random_pose(rng, scale=0.8 if k else 2.5))
        assert_matches_reference(mesh, tgt)


def random_planes(rng, rects, z_range, slope) -> list:
    """Inverse-depth planes (a, b, c) per rect: depth uniform in ``z_range`` at the rect's centre,
    gradients normal with deviation ``slope`` (1/z per pixel)."""
    planes = []
    for u0, v0, u1, v1 in rects:
        z = rng.uniform(*z_range)
        a, b = rng.normal(0, slope, 2)
        planes.append([a, b, 1 / z - a * (u0 + u1 - 1) / 2 - b * (v0 + v1 - 1) / 2])
    return planes


def assert_matches_reference(mesh, tgt) -> None:
    """The kernel's maps of ``mesh`` in ``tgt`` against the numpy reference: the same coverage,
    source coordinates within 2e-3 px, depth within 1e-5, NaN where uncovered."""
    got = rasterize_mesh(mesh, tgt, footprint="none")
    ref = rasterize_mesh_reference(mesh, tgt)
    np.testing.assert_array_equal(got.coverage, ref.coverage)
    c = got.coverage
    if c.any():
        assert np.abs(got.map_u - ref.map_u)[c].max() < 2e-3
        assert np.abs(got.map_v - ref.map_v)[c].max() < 2e-3
        assert np.max(np.abs(got.depth[c] / ref.depth[c] - 1)) < 1e-5
    assert np.isnan(got.depth[~c]).all()


@pytest.mark.parametrize("seed", range(4))
def test_large_quads_match_reference_at_grazing_and_wide_views(seed):
    """Quads spanning many target pixels per row take the kernel's sure-interior path (no
    per-pixel outline tests one pixel inside the analytic row span): steep planes seen at
    grazing angles by wide and narrow targets must still cover exactly the reference's pixels."""
    rng = np.random.default_rng(100 + seed)
    cam = Camera.from_fov(96, 72, hfov_deg=70)
    rects = random_partition(rng, 0, 0, cam.width, cam.height, min_size=24, p_stop=0.3)
    mesh = mesh_from_rects(cam, rects, random_planes(rng, rects, (1, 3), 0.01))  # steep: z up to ~2x across
    wide = rng.uniform(0.15, 0.5) * 96
    for k in range(3):
        f = wide if k == 0 else rng.uniform(60, 150)
        assert_matches_reference(mesh, Camera(f, f, rng.uniform(30, 60), rng.uniform(20, 45), 90, 64,
                                              random_pose(rng, scale=0.6, ang=0.5)))


def test_row_span_bounds_for_degenerate_forms():
    """The analytic row bounds (and the pixels sure to pass) of the rasterizer for forms that are
    constant along the row or not finite: what the per-pixel test would do at every u."""
    from ibr.render._raster_kernels import _span

    lo, hi, slo, shi = _span(np.nan, 0.0, 1.0, 3.0, True, 0, 100, 0, 100)  # NaN * u + 1: fails
    assert hi < lo and shi < slo
    lo, hi, slo, shi = _span(0.0, 0.0, 1.0, 3.0, True, 0, 100, 0, 100)  # 1 > 0 everywhere
    assert (lo, hi, slo, shi) == (0, 100, 0, 100)
    lo, hi, slo, shi = _span(0.0, 0.0, 0.0, 3.0, False, 0, 100, 0, 100)  # 0 >= 0 passes, not "sure"
    assert (lo, hi) == (0, 100) and shi < slo
    lo, hi, slo, shi = _span(0.0, 0.0, 0.0, 3.0, True, 0, 100, 0, 100)  # 0 > 0 fails
    assert hi < lo and shi < slo
    lo, hi, slo, shi = _span(1.0, 0.0, -10.5, 3.0, True, 0, 100, 0, 100)  # u > 10.5
    assert lo <= 11 and slo >= 11 and slo <= 13 and (hi, shi) == (100, 100)


@pytest.mark.parametrize(
    "normal_w, move",
    [
        ((0.0, 0.0, -1.0), (0.3, -0.1, 0.4)),  # fronto-parallel, camera moves in
        ((0.3, -0.2, -1.0), (-0.4, 0.2, -0.3)),  # tilted
        ((0.0, -1.0, -0.12), (0.15, 0.0, 0.5)),  # grazing floor (about 83 degrees incidence)
    ],
)
def test_plane_maps_and_depth_are_exact(normal_w, move):
    """Source coordinates and depth of every covered pixel equal the analytic ray-plane values;
    a half-pixel error (or a pixel-corner convention) would be 5000x over the tolerance."""
    point = np.array([0.0, 0.4, 3.0])
    tgt = SRC.with_pose(look_at(np.asarray(move), point + (0, 0, 1.0)))
    mesh = mesh_from_rects(SRC, [[0, 0, SRC.width, SRC.height]], [plane_coeffs(SRC, point, normal_w)])
    got = rasterize_mesh(mesh, tgt, footprint="none")
    uv, lam, zs = analytic_maps(SRC, tgt, point, normal_w)
    inside = (lam > 0) & (zs > 0) & (uv[..., 0] >= -0.5) & (uv[..., 0] < SRC.width - 0.5) \
        & (uv[..., 1] >= -0.5) & (uv[..., 1] < SRC.height - 0.5)
    np.testing.assert_array_equal(got.coverage, inside)
    assert inside.mean() > 0.2
    c = got.coverage
    assert np.abs(got.map_u[c] - uv[..., 0][c]).max() < 1e-4
    assert np.abs(got.map_v[c] - uv[..., 1][c]).max() < 1e-4
    assert np.abs(got.depth[c] / lam[c] - 1).max() < 1e-6


def _plane_scene(normal_w, point):
    nw = np.asarray(normal_w, float)
    nw /= np.linalg.norm(nw)
    axis_u = np.cross(nw, (0, 1.0, 0)) if abs(nw[1]) < 0.9 else np.cross(nw, (0, 0, 1.0))
    axis_v = np.cross(nw, axis_u)
    rect = synth.Rect(synth.image_texture("coffee", width_units=16.0), np.asarray(point, float), axis_u, axis_v,
                      np.inf, np.inf)
    return synth.Scene((rect,), name="plane", ambient=1.0, diffuse=0.0)


@pytest.mark.parametrize("grazing", [False, True])
def test_textured_plane_matches_ground_truth_render(grazing):
    """Warp a ray-traced textured plane (also a grazing one) to a new camera and compare with
    the ray-traced target: only interpolation error remains (under 0.3% of the range at the 90th
    percentile), clearly below a half-pixel-shifted warp's error."""
    cam = Camera.from_fov(128, 96, hfov_deg=60)
    if grazing:
        normal, point, move = (0.0, -1.0, -0.1), (0.0, 0.5, 3.0), (0.1, 0.05, 0.3)
    else:
        normal, point, move = (0.2, 0.1, -1.0), (0.0, 0.0, 3.0), (0.25, -0.1, 0.2)
    scene = _plane_scene(normal, point)
    src = synth.render(scene, cam, supersample=2)
    tgt_cam = cam.with_pose(look_at(np.asarray(move), np.asarray(point) + (0, 0, 2.0)))
    truth = synth.render(scene, tgt_cam, supersample=2)
    mesh = mesh_from_rects(cam, [[0, 0, 128, 96]], [plane_coeffs(cam, point, normal)])
    layer = render_mesh(mesh, src.color, tgt_cam, footprint="free")
    c = layer.coverage & np.isfinite(truth.depth)
    assert c.mean() > 0.5
    np.testing.assert_allclose(layer.depth[c], truth.depth[c], rtol=2e-6)
    if grazing:  # the far half is minified many times (aliased in both renders): compare the near half
        c &= truth.depth < np.median(truth.depth[c])
    err = np.abs(layer.color - truth.color)[c].max(axis=-1)
    shifted = render_mesh(mesh, src.color, Camera(tgt_cam.fx, tgt_cam.fy, tgt_cam.cx + 0.5, tgt_cam.cy, 128, 96,
                                                  tgt_cam.world_from_cam), footprint="free")
    c2 = c & shifted.coverage
    err_shift = np.abs(shifted.color - truth.color)[c2].max(axis=-1)
    assert np.percentile(err, 90) < 0.003  # colors in [0, 1]
    assert np.percentile(err, 50) < 0.7 * np.percentile(err_shift, 50)


def test_identity_warp_returns_the_source_exactly():
    scene = synth.make_scene("box_corner")
    cam = Camera.from_fov(96, 72, hfov_deg=60, world_from_cam=look_at((2.0, -1.5, -3.0), (0, 0, 0)))
    view = synth.render(scene, cam)
    mesh = build_mesh(view)
    layer = render_mesh(mesh, view.color, cam)
    valid = np.isfinite(view.depth)
    np.testing.assert_array_equal(layer.coverage, mesh.quad_of_pixel >= 0)
    np.testing.assert_array_equal(layer.color[valid], view.color[valid])  # bit-exact
    # depth: the mesh's planes evaluated at the pixel centers (exact up to float rounding)
    np.testing.assert_allclose(layer.depth[valid], mesh.depth()[valid], rtol=1e-6)
    assert np.isnan(layer.depth[~layer.coverage]).all()


# ----------------------------------------------------------------------------- fill rule
@pytest.mark.parametrize("seed", range(4))
def test_adjacent_coplanar_quads_neither_crack_nor_double_cover(seed):
    rng = np.random.default_rng(100 + seed)
    point, normal = (0.0, 0.0, 2.5), rng.normal(0, 0.3, 3) + (0, 0, -1.0)
    plane = plane_coeffs(SRC, point, normal)
    rects = random_partition(rng, 0, 0, SRC.width, SRC.height, min_size=1, p_stop=0.1)
    tiles = mesh_from_rects(SRC, rects, [plane] * len(rects))
    whole = mesh_from_rects(SRC, [[0, 0, SRC.width, SRC.height]], [plane])
    tgt = Camera.from_fov(80, 60, hfov_deg=75, world_from_cam=random_pose(rng, 0.3, 0.15))
    ref = rasterize_mesh(whole, tgt, footprint="none")
    got = rasterize_mesh(tiles, tgt, footprint="none")
    np.testing.assert_array_equal(got.coverage, ref.coverage)  # no crack
    assert ref.coverage.mean() > 0.3
    # no double cover: each quad rendered alone; the coverage counts must be exactly 0/1
    count = np.zeros(tgt.shape, int)
    for r in rects:
        count += rasterize_mesh(mesh_from_rects(SRC, [r], [plane]), tgt, footprint="none").coverage
    np.testing.assert_array_equal(count, ref.coverage.astype(int))


def test_shared_edge_belongs_to_one_quad_under_identity():
    """Two quads split at column 10: pixel 9 belongs to the left quad (edge at 9.5), pixel 10 to
    the right one: the half-open rule in source space."""
    cam = Camera.from_fov(20, 4, hfov_deg=60)
    mesh = mesh_from_rects(cam, [[0, 0, 10, 4], [10, 0, 20, 4]], [[0, 0, 0.5], [0, 0, 0.25]])
    maps = rasterize_mesh(mesh, cam, footprint="none")
    np.testing.assert_array_equal(maps.depth[:, :10], 2.0)
    np.testing.assert_array_equal(maps.depth[:, 10:], 4.0)


# ----------------------------------------------------------------------------- visibility
def test_occlusion_keeps_the_nearer_quad_in_any_order():
    cam = Camera.from_fov(40, 30, hfov_deg=60)
    near = [10, 8, 30, 22]
    rects = [[0, 0, 40, 30], near]  # a far wall quad overlapped in the target by a near quad
    planes = [[0, 0, 1 / 6.0], [0, 0, 1 / 2.0]]
    tgt = cam.translated(np.array([0.3, 0.0, 0.0]))
    maps = [rasterize_mesh(mesh_from_rects(cam, r, p), tgt, footprint="none")
            for r, p in ((rects, planes), (rects[::-1], planes[::-1]))]
    np.testing.assert_array_equal(maps[0].depth, maps[1].depth)
    d = maps[0].depth
    # the near quad moves by fx * 0.3 / 2 = 10.4 px left, the far wall by 10.4 / 3 = 3.5 px
    assert np.all(d[15, 5:15] == 2.0)
    assert np.all(d[15, 30:35] == 6.0)
    assert np.isclose(np.nanmin(d), 2.0) and np.isclose(np.nanmax(d), 6.0)


def test_quad_crossing_the_camera_plane_is_clipped_not_smeared():
    """A floor plane that extends behind the target camera: only its part in front is drawn,
    exactly where the analytic ray-plane hits are, with positive depth."""
    cam = Camera.from_fov(64, 48, hfov_deg=70)
    point, normal = (0.0, 1.0, 0.0), (0.0, -1.0, 0.0)  # floor 1 unit below the source camera
    mesh = mesh_from_rects(cam, [[0, 30, 64, 48]], [plane_coeffs(cam, point, normal)])
    # target: moved forward past the near part of the floor, looking down and back
    tgt = cam.with_pose(look_at((0.0, 0.2, 3.0), (0.0, 1.0, 1.5)))
    got = rasterize_mesh(mesh, tgt, footprint="none")
    ref = rasterize_mesh_reference(mesh, tgt)
    np.testing.assert_array_equal(got.coverage, ref.coverage)
    assert got.coverage.any()
    # the quad's own corners: some are behind the target camera
    corners_w = mesh.corners_cam[0] @ cam.world_from_cam[:3, :3].T
    _, z = tgt.project(corners_w)
    assert (z < 0).any() and (z > 0).any()
    assert (got.depth[got.coverage] > 0).all()
    uv, lam, zs = analytic_maps(cam, tgt, point, normal)
    c = got.coverage
    assert np.abs(got.map_u[c] - uv[..., 0][c]).max() < 1e-3
    assert np.abs(got.depth[c] / lam[c] - 1).max() < 1e-6


def test_back_facing_and_edge_on_quads_are_culled():
    cam = Camera.from_fov(32, 24, hfov_deg=60)
    mesh = mesh_from_rects(cam, [[0, 0, 32, 24]], [[0, 0, 1 / 2.0]])  # plane z = 2
    behind = cam.with_pose(look_at((0, 0, 4.0), (0, 0, 0)))  # behind the plane, facing it
    assert not rasterize_mesh(mesh, behind).coverage.any()
    edge_on = cam.with_pose(look_at((0, 0, 2.0), (1.0, 0, 2.0)))  # camera inside the plane
    assert not rasterize_mesh(mesh, edge_on).coverage.any()


def test_plane_through_the_source_camera_plane_inside_a_rect():
    """1/z reaches 0 inside the rect's outline (a corner at infinity): still exact."""
    cam = Camera.from_fov(32, 24, hfov_deg=60)
    a = 0.02
    planes = [[a, 0, -a * -0.2]]  # 1/z = a (u + 0.2): 0 at u = -0.2, inside [-0.5, 31.5)
    mesh = mesh_from_rects(cam, [[0, 0, 32, 24]], planes)
    tgt = cam.translated(np.array([0.1, 0.05, -0.2]))
    got = rasterize_mesh(mesh, tgt, footprint="none")
    ref = rasterize_mesh_reference(mesh, tgt)
    np.testing.assert_array_equal(got.coverage, ref.coverage)
    assert got.coverage.mean() > 0.5


# ----------------------------------------------------------------------------- sampling
def test_surface_footprint_stops_color_bleeding_across_depth_edges():
    """Red near square over a blue far wall: with footprint="surface" no covered wall pixel picks
    up red; the unclamped footprint does (so the test can fail)."""
    cam = Camera.from_fov(48, 32, hfov_deg=60)
    color = np.zeros((32, 48, 3), np.float32)
    color[..., 2] = 1.0
    color[10:22, 16:32] = (1.0, 0, 0)
    depth = np.full((32, 48), 6.0, np.float32)
    depth[10:22, 16:32] = 2.0
    rects = [[0, 0, 48, 10], [0, 22, 48, 32], [0, 10, 16, 22], [32, 10, 48, 22], [16, 10, 32, 22]]
    planes = [[0, 0, 1 / 6.0]] * 4 + [[0, 0, 1 / 2.0]]
    mesh = mesh_from_rects(cam, rects, planes)
    tgt = cam.translated(np.array([0.23, 0.11, 0.0]))
    wall = lambda layer: layer.coverage & (layer.depth > 5)  # noqa: E731
    clamped = render_mesh(mesh, color, tgt, footprint="surface")
    free = render_mesh(mesh, color, tgt, footprint="free")
    assert clamped.color[wall(clamped)][:, 0].max() == 0.0
    assert free.color[wall(free)][:, 0].max() > 0.2
    # and the near square stays pure red inside (its own quad is clamped too)
    sq = clamped.coverage & (clamped.depth < 3)
    assert sq.sum() > 100 and clamped.color[sq][:, 2].max() == 0.0


def test_free_footprint_does_not_darken_the_image_border():
    """Sampling half a pixel outside the source (u in [-0.5, 0)) must not read remap's black
    border: a constant image stays constant up to the edge."""
    cam = Camera.from_fov(32, 24, hfov_deg=60)
    mesh = mesh_from_rects(cam, [[0, 0, 32, 24]], [[0, 0, 0.5]])
    tgt = Camera(cam.fx, cam.fy, cam.cx + 0.4, cam.cy - 0.3, 32, 24)  # samples at u - 0.4, v + 0.3
    layer = render_mesh(mesh, np.full((24, 32, 3), 7.0, np.float32), tgt)
    assert layer.coverage[:, 0].all() and layer.coverage[-1].all()
    np.testing.assert_array_equal(layer.color[layer.coverage], 7.0)


def test_layer_shapes_and_dtypes():
    cam = Camera.from_fov(16, 12, hfov_deg=60)
    mesh = mesh_from_rects(cam, [[0, 0, 16, 12]], [[0, 0, 0.5]])
    gray = np.arange(16 * 12, dtype=np.uint16).reshape(12, 16)
    layer = render_mesh(mesh, gray, cam)
    assert isinstance(layer, Layer)
    assert layer.color.shape == (12, 16, 1) and layer.color.dtype == np.float32
    np.testing.assert_array_equal(layer.color[..., 0], gray.astype(np.float32))
    assert layer.depth.dtype == np.float32 and layer.coverage.dtype == np.bool_


def test_render_mesh_rejects_bad_arguments():
    cam = Camera.from_fov(16, 12, hfov_deg=60)
    mesh = mesh_from_rects(cam, [[0, 0, 16, 12]], [[0, 0, 0.5]])
    with pytest.raises(ValueError, match="color: size 15x12 does not match"):
        render_mesh(mesh, np.zeros((12, 15, 3)), cam)
    with pytest.raises(ValueError, match="footprint: expected one of"):
        render_mesh(mesh, np.zeros((12, 16, 3)), cam, footprint="wide")
    with pytest.raises(TypeError, match="camera: expected a Camera"):
        render_mesh(mesh, np.zeros((12, 16, 3)), "cam")
    with pytest.raises(ValueError, match="depth_tol"):
        rasterize_mesh(mesh, cam, depth_tol=-1)
    View(np.zeros((12, 16, 3)), None, cam)  # (sanity: a View without depth is fine as data)


@pytest.mark.parametrize("hfov", [70.0, 170.0])
def test_a_ground_plane_whose_horizon_runs_along_a_pixel_edge_is_drawn_whole(hfov):
    """A level camera of even height has its horizon on a row boundary: the floor's fitted plane
    puts the quad's top corners ~4e8 away, and the bounding box was clipped at 1e-7 of that
    (z = 40), so only one row of the floor was drawn (0.021 of the image instead of 0.5; at 170
    degrees "sees nothing"). The clip is now relative to the corner nearest the target's plane."""
    import ibr

    cam = Camera.from_fov(64, 48, hfov_deg=hfov)
    u, v = cam.pixel_grid()
    z = np.where(v > cam.cy, cam.fy / (v - cam.cy), np.nan).astype(np.float32)  # the floor y = 1
    view = View(np.full((48, 64, 3), 0.5, np.float32), z, cam)
    out = ibr.warp(view, cam, fill="none")
    np.testing.assert_array_equal(~out.holes, np.isfinite(z))
    moved = cam.with_pose(np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.5], [0, 0, 0, 1.0]]))
    ref = rasterize_mesh_reference(build_mesh(view), moved)
    got = rasterize_mesh(build_mesh(view), moved)
    assert got.coverage.mean() > 0.45
    np.testing.assert_array_equal(got.coverage, ref.coverage)


def test_sample_points_is_bilinear_at_scattered_points_in_any_channel_count():
    """``ibr.render.points.sample_points``: pixel centres give the pixels, a midpoint their mean,
    points outside the given value; 9 channels (remap takes 4 at a time), 2-D images, 2000
    points (rows of 1024)."""
    from ibr.render.points import sample_points

    rng = np.random.default_rng(1)
    img = rng.random((7, 11, 9)).astype(np.float32)
    u = rng.integers(0, 11, 2000).astype(float)
    v = rng.integers(0, 7, 2000).astype(float)
    got = sample_points(img, u, v)
    assert got.shape == (2000, 9) and np.array_equal(got, img[v.astype(int), u.astype(int)])
    mid = sample_points(img[..., 0], [2.5], [3.0])
    assert mid.shape == (1, 1) and mid[0, 0] == pytest.approx((img[3, 2, 0] + img[3, 3, 0]) / 2, rel=1e-5)
    assert np.isnan(sample_points(img, [-3.0, 20.0], [1.0, 1.0], outside=np.nan)).all()
    assert (sample_points(img, [-3.0], [1.0]) == 0).all()
    with pytest.raises(ValueError, match="v: expected 2 values"):
        sample_points(img, [1.0, 2.0], [1.0])
