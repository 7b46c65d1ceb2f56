"""Spherical ray cameras (equirect, ODS eyes) and exact ray casting of quad meshes into them."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ibr.base.camera import Camera
from ibr.base.ray_camera import SphericalCamera
from ibr.base.view import View
from ibr.mesh import build_mesh
from ibr.render.ray_raster import rasterize_mesh_rays, rasterize_mesh_rays_reference, render_mesh_rays
from ibr.synth import Rect, Scene, image_texture, make_scene, render
from panorama.directions import direction_from_equirect_pixel, equirect_pixel_from_direction


def test_mono_rays_are_the_panorama_convention():
    cam = SphericalCamera(64, 32)
    v, u = np.mgrid[0:32, 0:64].astype(float)
    o, d = cam.rays_world(u, v)
    assert np.allclose(o, 0.0)
    assert np.allclose(d, direction_from_equirect_pixel(u, v, 64, 32), atol=1e-12)
    pu, pv, rng = cam.project(d * 3.0)
    eu, ev = equirect_pixel_from_direction(d, 64, 32)
    assert np.allclose(pu, eu, atol=1e-9) and np.allclose(pv, ev, atol=1e-9)
    assert np.allclose(rng, 3.0)


def test_worked_number_of_the_module_doc():
    """ipd 0.064: a point 2 m ahead is seen by the left eye at lon = asin(0.016) (right of centre)."""
    left = SphericalCamera(4096, 2048, "left", ipd=0.064)
    u, v, rng = left.project(np.array([[0.0, 0.0, 2.0]]))
    lon = math.asin(0.032 / 2.0)
    assert u[0] == pytest.approx((lon / (2 * math.pi) + 0.5) * 4096 - 0.5, abs=1e-9)
    assert u[0] == pytest.approx(2057.93, abs=0.01)
    assert v[0] == pytest.approx(1023.5)
    assert rng[0] == pytest.approx(math.sqrt(4 - 0.032 ** 2))
    right = left.with_eye("right")
    assert right.project(np.array([[0.0, 0.0, 2.0]]))[0][0] == pytest.approx(4095 - u[0], abs=1e-9)


def test_eye_rays_are_tangent_to_the_viewing_circle_and_fade_at_the_poles():
    cam = SphericalCamera(360, 180, "left", ipd=0.064, fade_start_deg=60, fade_end_deg=80)
    v, u = np.mgrid[0:180, 0:360].astype(float)
    o, d = cam.rays_rig(u, v)
    lat = np.degrees(cam.lat(v))
    r = np.linalg.norm(o, axis=-1)
    assert np.allclose(r[np.abs(lat) <= 60], 0.032)
    assert np.allclose(r[np.abs(lat) >= 80], 0.0)
    assert np.all(np.diff(r[:90, 0]) >= -1e-15)  # grows monotonically from the pole toward the fade start
    assert np.allclose(np.sum(o * d, axis=-1), 0.0, atol=1e-15)  # origin perpendicular to the ray
    # the left eye's origin is left of the viewing direction: o = -r * right(lon)
    right_vec = np.stack([np.cos(cam.lon(u)), 0 * u, -np.sin(cam.lon(u))], -1)
    assert np.allclose(np.sum(o * right_vec, -1), -r)


@settings(max_examples=60, deadline=None)
@given(u=st.floats(-0.5, 511.49), v=st.floats(0.0, 255.0), t=st.floats(0.2, 50.0),
       eye=st.sampled_from(["mono", "left", "right"]))
def test_project_inverts_rays(u, v, t, eye):
    """pixel -> ray -> point at distance t -> pixel, inside the fade band too (fixed-point steps)."""
    cam = SphericalCamera(512, 256, eye, ipd=0.064, world_from_rig=np.array(
        [[0.0, 0, 1, 1.5], [0, 1, 0, -0.2], [-1, 0, 0, 3.0], [0, 0, 0, 1]]))
    o, d = cam.rays_world(np.array(u), np.array(v))
    pu, pv, rng = cam.project(o + t * d)
    du = (pu - u + 256) % 512 - 256
    assert abs(du) < 1e-6 and abs(pv - v) < 1e-6
    assert rng == pytest.approx(t, rel=1e-9)


def test_points_inside_the_viewing_circle_are_unseen_not_nan_elsewhere():
    cam = SphericalCamera(64, 32, "right", ipd=0.064)
    u, v, rng = cam.project(np.array([[0.01, 0.0, 0.01], [0.0, 0.0, 1.0]]))
    assert np.isnan(u[0]) and np.isnan(v[0]) and np.isnan(rng[0])
    assert np.isfinite(u[1]) and np.isfinite(v[1])


@pytest.mark.parametrize("kwargs, match", [
    (dict(width=64, height=64), "2:1"),
    (dict(width=64, height=32, eye="middle"), "eye"),
    (dict(width=64, height=32, eye="left", ipd=0.0), "ipd"),
    (dict(width=64, height=32, eye="left", ipd=float("nan")), "ipd"),
    (dict(width=64, height=32, fade_start_deg=80, fade_end_deg=60), "fade"),
    (dict(width=64, height=32, fade_start_deg=60, fade_end_deg=95), "fade"),
    (dict(width=64, height=32, world_from_rig=np.diag([1.0, 1, -1, 1])), "world_from_rig"),
])
def test_bad_camera_parameters_are_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        SphericalCamera(**kwargs)


# --------------------------------------------------------------------------- ray casting
def _view(scene, yaw_deg=0.0, pitch_deg=0.0, size=(96, 72), hfov=90.0, pos=(0.0, 0.0, 0.0)):
    from panorama.directions import world_from_view

    pose = np.eye(4)
    pose[:3, :3] = world_from_view(yaw_deg, pitch_deg)
    pose[:3, 3] = pos
    return render(scene, Camera.from_fov(*size, hfov_deg=hfov, world_from_cam=pose))


@pytest.fixture(scope="module")
def room():
    return make_scene("room")


@pytest.mark.parametrize("eye", ["mono", "left", "right"])
@pytest.mark.parametrize("yaw, pitch", [(0.0, 0.0), (180.0, 0.0), (30.0, 85.0)])
def test_ray_casting_matches_the_brute_force_reference(room, eye, yaw, pitch):
    """Every pixel tested against every quad (reference) = the bounded kernel, bit for bit:
    forward, across the +-180 deg seam (yaw 180) and over the pole (pitch 85)."""
    view = _view(room, yaw, pitch, pos=(0.0, -0.2, 2.0))
    mesh = build_mesh(view)
    cam = SphericalCamera(192, 96, eye, ipd=0.064, world_from_rig=np.array(
        [[1.0, 0, 0, 0.03], [0, 1, 0, -0.2], [0, 0, 1, 2.0], [0, 0, 0, 1]]))
    got = rasterize_mesh_rays(mesh, cam, footprint="none")
    ref = rasterize_mesh_rays_reference(mesh, cam)
    assert got.coverage.sum() > 100
    assert np.array_equal(got.coverage, ref.coverage)
    c = ref.coverage
    assert np.allclose(got.map_u[c], ref.map_u[c], atol=2e-3) and np.allclose(got.map_v[c], ref.map_v[c], atol=2e-3)
    assert np.allclose(got.depth[c], ref.depth[c], rtol=1e-5)
    if yaw == 180.0:  # the view straddles the seam: both image borders are covered
        assert got.coverage[:, 0].any() and got.coverage[:, -1].any()
    if pitch == 85.0:  # the ceiling quad covers the pole: the whole top row
        assert got.coverage[0].all()


def test_a_quad_straddling_the_seam_and_one_over_the_pole():
    tex = image_texture("brick", 1.0)
    behind = Scene((Rect(tex, np.array([0.0, 0.0, -2.0]), np.array([-1.0, 0, 0]), np.array([0, 1.0, 0]), 1.0, 1.0,
                         (0.0, 0.0)),))
    above = Scene((Rect(tex, np.array([0.0, -2.0, 0.0]), np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), 1.5, 1.5,
                        (0.0, 0.0)),))
    for scene, yaw, pitch in ((behind, 180.0, 0.0), (above, 0.0, 90.0)):
        view = _view(scene, yaw, pitch, size=(64, 64), hfov=120.0)
        mesh = build_mesh(view)
        assert len(mesh.rects) == 1  # one planar quad
        cam = SphericalCamera(128, 64)
        got = rasterize_mesh_rays(mesh, cam, footprint="none")
        ref = rasterize_mesh_rays_reference(mesh, cam)
        assert np.array_equal(got.coverage, ref.coverage) and got.coverage.any()
        # range of a plane at distance 2 along its normal: exactly 2 / cos(angle to the normal)
        o, d = cam.rays_world()
        normal = np.array([0, 0, -1.0]) if scene is behind else np.array([0, -1.0, 0])
        assert np.allclose(got.depth[got.coverage], (2.0 / (d @ normal))[got.coverage], rtol=1e-5)
    assert got.coverage[0].all()  # the quad above covers the whole top row (the pole)


def test_geometry_closer_than_half_the_ipd_gives_no_nan_and_no_crash():
    tex = image_texture("brick", 0.1)
    near = Scene((Rect(tex, np.array([0.0, 0.0, 0.02]), np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), 0.05, 0.05,
                       (0.0, 0.0)),))
    view = _view(near, size=(48, 48), hfov=120.0)
    mesh = build_mesh(view)
    for eye in ("left", "right"):
        cam = SphericalCamera(128, 64, eye, ipd=0.064)
        layer = render_mesh_rays(mesh, view.color, cam)
        ref = rasterize_mesh_rays_reference(mesh, cam)
        assert np.array_equal(layer.coverage, ref.coverage)
        assert np.isfinite(layer.color).all()
        assert np.isfinite(layer.depth[layer.coverage]).all() and np.isnan(layer.depth[~layer.coverage]).all()


def test_render_mesh_rays_takes_the_source_colours(room):
    view = _view(room, 20.0, 0.0)
    mesh = build_mesh(view)
    cam = SphericalCamera(256, 128)
    layer = render_mesh_rays(mesh, view.color, cam)
    # a covered equirect pixel shows what the source pixel its ray lands on shows
    o, d = cam.rays_world()
    pts = (o + d * layer.depth[..., None])[layer.coverage]
    uv, _ = view.camera.project(pts)
    iu, iv = np.rint(uv).astype(int).T
    inside = (iu > 0) & (iu < 95) & (iv > 0) & (iv < 71)
    err = np.abs(layer.color[layer.coverage][inside] - view.color[iv[inside], iu[inside]])
    assert np.median(err) < 0.05
    with pytest.raises(TypeError, match="camera"):
        render_mesh_rays(mesh, view.color, view.camera)
    with pytest.raises(ValueError, match="color"):
        render_mesh_rays(mesh, view.color[:10], cam)


def test_a_source_that_sees_nothing_of_the_target_covers_nothing():
    """All quads face away from the rig (it sits behind the only plane): culled, no coverage."""
    plane = make_scene("plane")  # one fronto-parallel rectangle at z = 3
    view = _view(plane, 0.0, 0.0)
    mesh = build_mesh(view)
    behind = np.eye(4)
    behind[:3, 3] = (0.0, 0.0, 5.0)
    for eye in ("mono", "left"):
        cam = SphericalCamera(128, 64, eye, world_from_rig=behind)
        got = rasterize_mesh_rays(mesh, cam)
        assert not got.coverage.any() and np.isnan(got.depth).all()
        assert not rasterize_mesh_rays_reference(mesh, cam).coverage.any()
    in_front = SphericalCamera(128, 64)
    assert rasterize_mesh_rays(mesh, in_front).coverage.any()
