"""Synthetic scenes: analytic ray-casting geometry, shading invariants, sample files."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from ibr import interpolate_cameras, look_at
from ibr.base.camera import Camera
from ibr.synth import SCENES, Box, ImageTexture, Rect, Scene, Sphere, make_scene, render, render_rays, rotation, scene_cameras, staircase
from ibr.synth.textures import sample_bilinear

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "samples" / "data"
F32_ULP_REL = 2.0**-23


def flat(value=0.8):
    """Uniform texture: the albedo is ``value`` everywhere."""
    return ImageTexture(np.full((2, 2, 3), value, np.float32), 1.0, "flat")


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


# --------------------------------------------------------------------------- ray casting
def test_ray_hits_fronto_plane_at_analytic_distance():
    scene = make_scene("plane")  # rectangle at z = 3
    o = np.array([[0.2, -0.1, 0.5]])
    d = np.array([[0.3, 0.4, 1.2]]) / 1.3  # |(0.3, 0.4, 1.2)| = 1.3 exactly
    hit = scene.trace(o, d)
    assert hit.prim[0] == 0
    assert abs(hit.t[0] - 2.5 * 1.3 / 1.2) <= 1e-14 * 3  # (3 - 0.5) / d_z, float64 precision
    assert np.allclose(hit.normal[0], [0, 0, -1], atol=1e-15)  # turned toward the ray


def test_ray_hits_tilted_plane_at_analytic_distance():
    # Plane through (0, 0, 4) with normal (0, 0.6, 0.8); the ray along that normal meets it at
    # t = (c . n) / (d . n) = 3.2.
    n = np.array([0.0, 0.6, 0.8])
    scene = Scene((Rect(flat(), (0, 0, 4.0), (1.0, 0, 0), np.cross(n, (1.0, 0, 0))),))
    hit = scene.trace(np.zeros(3), n[None])
    assert abs(hit.t[0] - 3.2) <= 1e-15 * 4
    # A ray through (0, 1, 4 - 0.75) (on the plane: 0.6*1 + 0.8*(-0.75) = 0): t = |p|.
    p = np.array([0.0, 1.0, 3.25])
    hit = scene.trace(np.zeros(3), unit(p)[None])
    assert abs(hit.t[0] - np.linalg.norm(p)) <= 1e-14


def test_sphere_depth_center_and_off_center_pixels():
    c, r = np.array([0.0, 0.0, 5.0]), 1.0
    scene = Scene((Sphere(flat(), c, r),))
    cam = Camera(40.0, 40.0, 32.0, 24.0, 65, 49)  # integer principal point: pixel (32, 24) on axis
    view = render(scene, cam)
    assert view.depth[24, 32] == np.float32(4.0)
    # Off-center pixel (36, 27): planar z solves |z q - c|^2 = r^2 with q = ((u-cx)/f, (v-cy)/f, 1).
    q = np.array([(36 - 32) / 40.0, (27 - 24) / 40.0, 1.0])
    qc = q @ c
    z = (qc - math.sqrt(qc * qc - (q @ q) * (c @ c - r * r))) / (q @ q)
    assert abs(view.depth[27, 36] - z) <= 2 * F32_ULP_REL * z
    hit = scene.trace(np.zeros(3), unit(q)[None])  # float64 path
    assert abs(hit.t[0] - z * np.linalg.norm(q)) <= 1e-13
    # Outward normal at the hit, turned toward the viewer.
    p = z * q
    assert np.allclose(hit.normal[0], (p - c) / r, atol=1e-12)
    # Rays from inside the sphere hit its far side.
    inside = scene.trace(c[None], np.array([[1.0, 0, 0]]))
    assert abs(inside.t[0] - r) <= 1e-15


def test_rotated_box_edge_and_inside_ray():
    # Unit-half cube at z = 5 turned 45 degrees about the vertical: its front edge is at z = 5 - sqrt(2).
    box = Box(flat(), (0.0, 0.0, 5.0), (1.0, 1.0, 1.0), rotation(45.0))
    scene = Scene((box,))
    hit = scene.trace(np.zeros(3), np.array([[0.0, 0.0, 1.0]]))
    assert abs(hit.t[0] - (5 - math.sqrt(2))) <= 1e-14
    # Ray slightly right of the edge hits the face whose normal is (sin45, 0, -cos45) toward the camera.
    d = unit([0.05, 0.0, 1.0])
    hit = scene.trace(np.zeros(3), d[None])
    assert np.allclose(np.abs(hit.normal[0]), [math.sqrt(0.5), 0, math.sqrt(0.5)], atol=1e-12)
    # From the center, the +x direction exits through the face plane at distance 1/cos45.
    out = scene.trace(np.array([[0.0, 0.0, 5.0]]), np.array([[1.0, 0.0, 0.0]]))
    assert abs(out.t[0] - math.sqrt(2)) <= 1e-14
    # A ray parallel to the slabs and outside them misses.
    miss = scene.trace(np.array([[0.0, -3.0, 0.0]]), np.array([[0.0, 0.0, 1.0]]))
    assert miss.prim[0] == -1 and np.isinf(miss.t[0])


def test_staircase_step_heights():
    boxes = staircase(origin=(0.0, 1.0, 2.0), steps=4, step_width=1.0, step_rise=0.2, step_run=0.5,
                      texture=flat())
    scene = Scene(tuple(boxes))
    # Straight down (+y) from y = -2 over the middle of step i: top at y = 1 - 0.2 (i + 1).
    o = np.array([[0.5, -2.0, 2.0 + 0.5 * i + 0.25] for i in range(4)])
    hit = scene.trace(o, np.tile([0.0, 1.0, 0.0], (4, 1)))
    expected = np.array([1.0 - 0.2 * (i + 1) for i in range(4)]) + 2.0
    assert np.max(np.abs(hit.t - expected)) <= 1e-14


@pytest.mark.parametrize("name", ["room", "clutter"])
def test_random_rays_land_on_the_reported_surface(name):
    # 3000 seeded random rays from random points inside the room: every hit point satisfies its
    # primitive's surface equation to ~1e-12 and its normal is a unit vector facing the ray.
    scene = make_scene(name)
    rng = np.random.default_rng(7)
    o = rng.uniform([-1.0, -0.8, -0.5], [1.0, 0.5, 1.0], (3000, 3))
    d = rng.normal(size=(3000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    hit = scene.trace(o, d)
    assert np.all(hit.valid)  # closed rooms
    p = o + hit.t[:, None] * d
    assert np.all(np.abs(np.linalg.norm(hit.normal, axis=1) - 1) < 1e-12)
    assert np.all(np.einsum("ij,ij->i", hit.normal, d) <= 0)
    for i in np.unique(hit.prim):
        prim, q = scene.primitives[i], p[hit.prim == i]
        if isinstance(prim, Sphere):
            res = np.abs(np.linalg.norm(q - prim.center, axis=1) - prim.radius)
        elif isinstance(prim, Box):
            lp = (q - prim.center) @ prim.world_from_box
            res = np.abs(np.max(np.abs(lp) / prim.half_size, axis=1) - 1) * prim.half_size.min()
        else:
            rel = q - prim.center
            res = np.abs(rel @ prim.normal)
            assert np.all(np.abs(rel @ prim.axis_u) <= prim.half_u + 1e-9)
            assert np.all(np.abs(rel @ prim.axis_v) <= prim.half_v + 1e-9)
        assert res.max() < 1e-12 * 10, (type(prim).__name__, res.max())


def test_planar_depth_is_range_times_cosine_off_axis():
    scene = make_scene("room")
    pose = look_at((0.3, -0.2, 0.5), (2.0, 1.0, 5.0))  # oblique view, off-axis pixels everywhere
    cam = Camera(60.0, 60.0, 40.0, 30.0, 80, 60, pose)
    view = render(scene, cam)
    origin, dirs = cam.rays_world()
    _, rng = render_rays(scene, origin, dirs)
    u, v = cam.pixel_grid()
    cos = 1.0 / np.sqrt(((u - cam.cx) / cam.fx) ** 2 + ((v - cam.cy) / cam.fy) ** 2 + 1.0)
    assert np.all(np.isfinite(view.depth))
    err = np.abs(view.depth - rng.astype(np.float64) * cos) / view.depth
    assert err.max() <= 3 * F32_ULP_REL
    # The corner pixels are far off axis: cos is well below 1, so range != depth there.
    assert cos[0, 0] < 0.85 and abs(rng[0, 0] - view.depth[0, 0]) > 0.1


def test_projection_of_known_corners_no_half_pixel_shift():
    # fx = 50, cx = 31.5, z = 2: a rectangle with x in [-0.85, 0.37], y in [-0.61, 0.29] projects to
    # u in [10.25, 40.75], v in [8.25, 30.75] (u = 50 x / 2 + 31.5). Pixel centers at integers:
    # columns 11..40 and rows 9..30 are covered. Sampling at u + 0.5 or u - 0.5 would change both.
    cam = Camera(50.0, 50.0, 31.5, 23.5, 64, 48)
    rect = Rect(flat(), (-0.24, -0.16, 2.0), (1.0, 0, 0), (0, 1.0, 0), 0.61, 0.45)
    view = render(Scene((rect,)), cam)
    expected = np.zeros((48, 64), bool)
    expected[9:31, 11:41] = True
    assert np.array_equal(np.isfinite(view.depth), expected)
    uv, _ = cam.project(np.array([-0.85, -0.61, 2.0]))
    assert np.allclose(uv, [10.25, 8.25], atol=1e-12)


def test_supersampling_positions_and_exact_center_depth():
    # Left edge of a rectangle at u = 10.1. With k = 3 the samples of pixel 10 sit at 9.667, 10,
    # 10.333: one of three hits, so its color is exactly 1/3 of pixel 11's; its depth stays NaN
    # (center 10 < 10.1) and pixel 11's is the exact z = 2.
    cam = Camera(50.0, 50.0, 31.5, 23.5, 64, 48)
    x0 = (10.1 - 31.5) * 2 / 50
    rect = Rect(flat(), (x0 + 1.0, 0.0, 2.0), (1.0, 0, 0), (0, 1.0, 0), 1.0, 1.0)
    view = render(Scene((rect,)), cam, supersample=3)
    row = 24
    assert view.color[row, 9].max() == 0.0
    assert np.allclose(view.color[row, 10], view.color[row, 11] / 3, atol=1e-6)
    assert view.color[row, 11].min() > 0.3
    assert np.isnan(view.depth[row, 10]) and view.depth[row, 11] == np.float32(2.0)


# --------------------------------------------------------------------------- shading
def _center_pixel_camera(eye, target):
    # Odd size: cx = 16, cy = 12 are integers, so the center pixel looks exactly at the target.
    return Camera.from_fov(33, 25, hfov_deg=30.0, world_from_cam=look_at(eye, target))


def test_lambertian_color_is_view_independent_and_specular_is_not():
    scene = make_scene("room")
    p = np.array([0.5, 1.4, 3.0])  # a point on the room's floor (y = 1.4)
    cam1 = _center_pixel_camera((-1.0, 0.0, 0.0), p)
    cam2 = _center_pixel_camera((1.5, -0.5, 1.0), p)
    v1, v2 = render(scene, cam1), render(scene, cam2)
    # Planar depth of the axis pixel is the distance to p.
    assert abs(v1.depth[12, 16] - np.linalg.norm(p - cam1.position)) <= 2 * F32_ULP_REL * 4
    assert abs(v2.depth[12, 16] - np.linalg.norm(p - cam2.position)) <= 2 * F32_ULP_REL * 4
    assert np.max(np.abs(v1.color[12, 16] - v2.color[12, 16])) <= 1e-6
    # Blinn-Phong depends on the viewing direction: the same point differs between the cameras.
    shiny = scene.with_specular(0.5, shininess=4.0)
    s1, s2 = render(shiny, cam1), render(shiny, cam2)
    assert np.max(np.abs(s1.color[12, 16] - s2.color[12, 16])) > 0.01


def test_lambert_formula_on_a_known_plane():
    # Seed 001 eq. 7.5 without specular: L = d (ambient + diffuse max(0, n . l)).
    light = unit([0.0, -1.0, -1.0])
    scene = Scene((Rect(flat(0.5), (0, 0, 3.0), (1.0, 0, 0), (0, 1.0, 0)),), light_dir=light,
                  ambient=0.2, diffuse=0.7)
    hit = scene.trace(np.zeros(3), np.array([[0.0, 0.0, 1.0]]))
    n = np.array([0.0, 0.0, -1.0])
    expected = 0.5 * (0.2 + 0.7 * max(0.0, n @ light))
    assert np.allclose(hit.color[0], expected, atol=1e-7)


def test_texture_bilinear_pixel_centers_and_mirror():
    img = np.arange(12, dtype=np.float32).reshape(2, 6, 1) * np.ones(3, np.float32)
    assert sample_bilinear(img, np.array([3.0]), np.array([0.0]))[0, 0] == 3.0
    assert sample_bilinear(img, np.array([3.5]), np.array([1.0]))[0, 0] == 9.5
    # Mirrored repeat: texel -1 is texel 0, texel 6 is texel 5 (continuous across the seam).
    assert sample_bilinear(img, np.array([-0.5, 5.5]), np.array([0.0, 0.0]))[:, 0].tolist() == [0.0, 5.0]


# --------------------------------------------------------------------------- named scenes
@pytest.mark.parametrize("name", ["room", "clutter", "grazing", "plane"])
def test_default_cameras_see_no_miss(name):
    cam_a, cam_b = scene_cameras(name, width=64, height=48)
    scene = make_scene(name)
    for cam in (cam_a, cam_b, interpolate_cameras(cam_a, cam_b, 0.5)):
        view = render(scene, cam)
        assert np.all(np.isfinite(view.depth)) and view.depth.min() > 0
        assert view.color.dtype == np.float32 and 0 <= view.color.min() and view.color.max() <= 1


@pytest.mark.parametrize("name", ["room", "clutter"])
def test_depth_of_one_view_reprojects_into_the_other(name):
    # Lift view b's depth to world points, cast rays from camera a toward them: the ray's range
    # equals the distance unless something nearer occludes the point (a disocclusion in a).
    cam_a, cam_b = scene_cameras(name, width=96, height=72)
    scene = make_scene(name)
    vb = render(scene, cam_b)
    u, v = cam_b.pixel_grid()
    pts = cam_b.unproject(np.stack([u, v], -1), vb.depth.astype(np.float64)).reshape(-1, 3)
    to = pts - cam_a.position
    dist = np.linalg.norm(to, axis=1)
    _, rng = render_rays(scene, cam_a.position, to / dist[:, None])
    rel = (rng - dist) / dist  # float32 depth of b limits agreement to ~1e-7
    visible = np.abs(rel) < 1e-6
    assert visible.mean() > 0.9
    assert np.all(rel[~visible] < -1e-3)  # the rest is occluded in a, never "behind" the surface


def test_scene_camera_pairs_are_view_interpolation_pairs():
    for name in ("room", "clutter", "grazing"):
        a, b = scene_cameras(name)
        assert (a.width, a.height) == (512, 384) and a.cx == 255.5
        baseline = np.linalg.norm(a.position - b.position)
        assert 0.1 <= baseline <= 0.3
        cos = np.clip((np.trace(a.world_from_cam[:3, :3].T @ b.world_from_cam[:3, :3]) - 1) / 2, -1, 1)
        assert 0.2 < math.degrees(math.acos(cos)) < 5.0


def test_grazing_angle_of_the_ground_plane():
    a, b = scene_cameras("grazing", width=65, height=49)
    mid = interpolate_cameras(a, b, 0.5)
    hit = make_scene("grazing").trace(mid.position, mid.world_from_cam[:3, 2][None])
    incidence = math.degrees(math.acos(abs(hit.normal[0] @ mid.world_from_cam[:3, 2])))
    assert hit.prim[0] == 0 and 80.0 <= incidence <= 85.0


def test_closed_room_equirect_has_no_miss():
    h, w = 32, 64
    lon = ((np.arange(w) + 0.5) / w * 2 - 1) * np.pi
    lat = ((np.arange(h) + 0.5) / h - 0.5) * np.pi
    lon, lat = np.meshgrid(lon, lat)
    dirs = np.stack([np.cos(lat) * np.sin(lon), np.sin(lat), np.cos(lat) * np.cos(lon)], -1)
    color, rng = render_rays(make_scene("room"), (0.0, 0.0, 1.0), dirs)
    assert color.shape == (h, w, 3) and rng.shape == (h, w)
    assert np.all(np.isfinite(rng)) and rng.max() < 9.0


def test_misses_are_nan_and_inf():
    scene = make_scene("box_corner")
    cam_a, _ = scene_cameras("box_corner", width=64, height=48)
    view = render(scene, cam_a)
    assert np.isnan(view.depth[0, 0]) and np.isfinite(view.depth[24, 32])
    assert 0.05 < np.isnan(view.depth).mean() < 0.95
    hit = scene.trace(np.zeros(3), np.array([[0.0, 0.0, -1.0]]))
    assert hit.prim[0] == -1 and np.isinf(hit.t[0]) and np.all(np.isnan(hit.normal[0]))
    _, rng = render_rays(scene, np.zeros(3), np.array([[0.0, 0.0, -1.0]]))
    assert np.isnan(rng[0])


# --------------------------------------------------------------------------- bad input
def test_bad_inputs_raise_clear_errors():
    with pytest.raises(ValueError, match="'clutter'.*'grazing'"):
        make_scene("kitchen")
    with pytest.raises(ValueError, match="unknown scene 'kitchen'"):
        scene_cameras("kitchen")
    scene = make_scene("plane")
    with pytest.raises(ValueError, match=r"dirs: expected shape \(N, 3\), got \(4, 2\)"):
        scene.trace(np.zeros(3), np.zeros((4, 2)))
    with pytest.raises(ValueError, match="dirs: expected unit vectors"):
        scene.trace(np.zeros(3), np.array([[0.0, 0.0, 2.0]]))
    with pytest.raises(ValueError, match=r"origins: expected shape \(3,\) or \(2, 3\)"):
        scene.trace(np.zeros((3, 3)), np.tile([0.0, 0.0, 1.0], (2, 1)))
    with pytest.raises(ValueError, match=r"dirs: expected shape \(\.\.\., 3\)"):
        render_rays(scene, np.zeros(3), np.zeros((5, 4)))
    cam = Camera.from_fov(8, 6, hfov_deg=60)
    with pytest.raises(ValueError, match="supersample: expected an integer >= 1, got 0"):
        render(scene, cam, supersample=0)
    with pytest.raises(TypeError, match="camera: expected a Camera"):
        render(scene, "cam")
    with pytest.raises(ValueError, match="radius: expected a positive number"):
        Sphere(flat(), (0, 0, 0), -1.0)
    with pytest.raises(ValueError, match="world_from_box: expected a proper rotation"):
        Box(flat(), (0, 0, 0), (1, 1, 1), np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(ValueError, match="primitives: expected at least one"):
        Scene(())


# --------------------------------------------------------------------------- bundled samples
def _crop(cam: Camera, u0: int, v0: int, w: int, h: int) -> Camera:
    """The sub-window [u0, u0+w) x [v0, v0+h) of ``cam`` as its own camera (same rays)."""
    return Camera(cam.fx, cam.fy, cam.cx - u0, cam.cy - v0, w, h, cam.world_from_cam)


def test_bundled_samples_match_a_fresh_render():
    io = pytest.importorskip("ibr.io")
    manifest = json.loads((DATA / "manifest.json").read_text())
    assert manifest["format"] == "ibr-samples"
    assert set(manifest["scenes"]) == {"room", "clutter", "grazing"}
    ss = manifest["color"]["supersample"]
    for name, entry in manifest["scenes"].items():
        assert name in SCENES
        a = io.load_view(DATA / entry["a"])
        b = io.load_view(DATA / entry["b"])
        cam_a, cam_b = scene_cameras(name)
        assert a.camera.allclose(cam_a) and b.camera.allclose(cam_b)
        assert [g["t"] for g in entry["ground_truth"]] == [0.25, 0.5, 0.75]
        for g in entry["ground_truth"]:
            gt = io.load_view(DATA / g["view"])
            assert gt.camera.allclose(interpolate_cameras(cam_a, cam_b, g["t"]), atol=1e-9)
        # Re-render a 48x32 window of view b and of the t = 0.5 ground truth.
        for view in (b, io.load_view(DATA / entry["ground_truth"][1]["view"])):
            u0, v0 = 200, 150
            fresh = render(make_scene(name), _crop(view.camera, u0, v0, 48, 32), supersample=ss)
            stored_z = view.depth[v0 : v0 + 32, u0 : u0 + 48]
            assert np.max(np.abs(stored_z - fresh.depth) / fresh.depth) <= F32_ULP_REL
            stored_c = view.color[v0 : v0 + 32, u0 : u0 + 48].astype(np.int16)
            fresh_c = np.rint(fresh.color.astype(np.float64) * 255).astype(np.int16)
            assert view.color.dtype == np.uint8
            assert np.max(np.abs(stored_c - fresh_c)) <= 1


def test_review_findings_of_samples_bench_and_make_scene(tmp_path, capsys):
    """``ibr samples --sequence --keys 10000 --factor 1000`` (10 million frames) ran for hours
    before its first output: at most 100000 ground-truth frames; ``make_scene(specular=-0.5)``
    and NaN were ignored (``Scene`` refuses them)."""
    import cli
    from ibr.synth import make_scene

    assert cli.main(["samples", "--sequence", "--keys", "10000", "--factor", "1000", "--out", str(tmp_path / "s")]) == 1
    assert "at most 100000" in capsys.readouterr().err and not (tmp_path / "s").exists()
    for bad in (-0.5, float("nan"), 2.0):
        with pytest.raises(ValueError, match="specular: expected a weight in"):
            make_scene("room", specular=bad)
