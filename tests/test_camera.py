"""Camera model: projection, rays, look_at, pose interpolation, OpenGL interop and validation.

References are analytic: textbook glFrustum / glOrtho matrices, the pinhole formula, rotation
angles of known rotations. Pixel convention under test: pixel (u, v) has its center at integer
coordinates and the image spans [-0.5, W - 0.5]; NDC x = -1 is the left edge of column 0.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation, Slerp

from ibr.base.camera import GL_FROM_CV, Camera, camera_from_gl_projection, gl_frustum_from_projection, interpolate_cameras, look_at
from ibr.base.depth import window_from_z

HYP = settings(max_examples=60, deadline=None)


def pose_from(rotvec, t):
    m = np.eye(4)
    m[:3, :3] = Rotation.from_rotvec(rotvec).as_matrix()
    m[:3, 3] = t
    return m


def gl_frustum(l, r, b, t, n, f):
    """Textbook glFrustum matrix (OpenGL red book), independent of ibr."""
    return np.array([
        [2 * n / (r - l), 0, (r + l) / (r - l), 0],
        [0, 2 * n / (t - b), (t + b) / (t - b), 0],
        [0, 0, -(f + n) / (f - n), -2 * f * n / (f - n)],
        [0, 0, -1, 0],
    ])


def gl_ortho(l, r, b, t, n, f):
    return np.array([
        [2 / (r - l), 0, 0, -(r + l) / (r - l)],
        [0, 2 / (t - b), 0, -(t + b) / (t - b)],
        [0, 0, -2 / (f - n), -(f + n) / (f - n)],
        [0, 0, 0, 1],
    ])


def ndc_of(camera, near, far, points_world):
    """Project world points through the GL view and projection matrices; return NDC and w."""
    p = camera.gl_projection(near, far)
    x = np.c_[points_world, np.ones(len(points_world))]
    clip = x @ (p @ camera.gl_view()).T
    return clip[:, :3] / clip[:, 3:], clip[:, 3]


finite = dict(allow_nan=False, allow_infinity=False)
cameras = st.builds(
    lambda fx, fy, cx, cy, w, h, rv, t: Camera(fx, fy, cx, cy, w, h, pose_from(rv, t)),
    st.floats(50, 2000, **finite), st.floats(50, 2000, **finite),
    st.floats(-50, 300, **finite), st.floats(-50, 300, **finite),
    st.integers(1, 400), st.integers(1, 400),
    st.lists(st.floats(-3, 3, **finite), min_size=3, max_size=3),
    st.lists(st.floats(-10, 10, **finite), min_size=3, max_size=3),
)


# ----------------------------------------------------------------------------- projection
def test_from_fov_worked_numbers_and_edges():
    cam = Camera.from_fov(512, 256, hfov_deg=90)
    assert cam.fx == pytest.approx(256.0, abs=1e-12) and cam.fy == cam.fx
    assert (cam.cx, cam.cy) == (255.5, 127.5)
    # A ray at 45 degrees (x/z = 1) hits the right *edge* of the image, u = W - 0.5, not W - 1.
    uv, z = cam.project([[1.0, 0.0, 1.0], [-1.0, 0.0, 1.0], [0.0, 0.0, 5.0]])
    np.testing.assert_allclose(uv, [[511.5, 127.5], [-0.5, 127.5], [255.5, 127.5]], atol=1e-12)
    np.testing.assert_allclose(z, [1.0, 1.0, 5.0])


@HYP
@given(cameras, st.floats(0.01, 1e4, **finite), st.floats(-1, 2, **finite), st.floats(-1, 2, **finite))
def test_project_unproject_round_trip(cam, z, fu, fv):
    uv = np.array([[fu * cam.width - 0.5, fv * cam.height - 0.5]])
    world = cam.unproject(uv, np.array([z]))
    uv2, z2 = cam.project(world)
    np.testing.assert_allclose(uv2, uv, rtol=0, atol=1e-7 * (1 + np.abs(uv).max()))
    np.testing.assert_allclose(z2, [z], rtol=1e-10)
    # Camera-frame variant agrees with the pinhole formula directly.
    cam_pts = cam.unproject(uv, np.array([z]), frame="cam")
    np.testing.assert_allclose(cam_pts[0, 0], (uv[0, 0] - cam.cx) / cam.fx * z, rtol=1e-12, atol=1e-12)


def test_project_behind_camera_is_nan_and_bad_frame():
    cam = Camera.from_fov(8, 8, hfov_deg=60)
    uv, z = cam.project([[0.0, 0.0, -1.0], [0.0, 0.0, 0.0], [0.1, 0.1, 1.0]])
    assert np.isnan(uv[:2]).all() and np.isfinite(uv[2]).all()
    np.testing.assert_array_equal(z, [-1.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="frame"):
        cam.unproject([[0, 0]], [1.0], frame="screen")
    with pytest.raises(ValueError, match=r"points_world: expected shape \(\.\.\., 3\)"):
        cam.project([[1.0, 2.0]])


def test_rays_pixel_grid_and_translation():
    cam = Camera(100.0, 80.0, 3.2, 2.1, 7, 5, pose_from([0.1, -0.2, 0.3], [1, 2, 3]))
    u, v = cam.pixel_grid()
    assert u[0, 0] == 0 and u[0, -1] == 6 and v[-1, 0] == 4
    rays = cam.rays_cam()
    np.testing.assert_allclose(rays, cam.unproject(np.stack([u, v], -1), np.ones_like(u), frame="cam"))
    origin, d = cam.rays_world()
    np.testing.assert_allclose(np.linalg.norm(d, axis=-1), 1.0, atol=1e-12)
    # A point along each world ray projects back onto its own pixel.
    uv, _ = cam.project(origin + 2.5 * d)
    np.testing.assert_allclose(uv, np.stack([u, v], -1), atol=1e-9)
    # translated() moves along the camera's own axes.
    moved = cam.translated([0.5, 0.0, 0.0])
    np.testing.assert_allclose(moved.position - cam.position, 0.5 * cam.world_from_cam[:3, 0], atol=1e-12)


def test_resized_keeps_pixel_edges():
    cam = Camera(300.0, 300.0, 99.5, 49.5, 200, 100)
    half = cam.resized(100, 50)
    pts = cam.unproject(np.array([[-0.5, -0.5], [199.5, 99.5], [10.0, 20.0]]), np.ones(3))
    uv_full, _ = cam.project(pts)
    uv_half, _ = half.project(pts)
    # Edges map to edges; a full-res pixel center u maps to (u + 0.5) / 2 - 0.5.
    np.testing.assert_allclose(uv_half, (uv_full + 0.5) / 2 - 0.5, atol=1e-12)
    np.testing.assert_allclose(uv_half[:2], [[-0.5, -0.5], [99.5, 49.5]], atol=1e-12)


# ----------------------------------------------------------------------------- look_at
def test_look_at_points_at_target_with_up_upward():
    eye, target, up = np.array([1.0, -2.0, -5.0]), np.array([0.5, 0.3, 2.0]), np.array([0.0, -1.0, 0.0])
    pose = look_at(eye, target, up)
    r = pose[:3, :3]
    np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-12)
    assert np.linalg.det(r) == pytest.approx(1.0)
    cam = Camera(200.0, 200.0, 64.0, 48.0, 128, 96, pose)
    uv, z = cam.project(np.stack([target, target + 0.1 * up, target + np.cross(-up, target - eye) * 0.01]))
    np.testing.assert_allclose(uv[0], [64.0, 48.0], atol=1e-9)  # target on the optical axis
    assert z[0] == pytest.approx(np.linalg.norm(target - eye))
    assert uv[1, 1] < 48.0 - 1  # world up appears above the center (smaller row)
    assert uv[2, 0] > 64.0 + 1  # (-up) x z is the camera's right (x = y x z)
    # The identity camera's frame: looking down +z with the default up is the identity pose.
    np.testing.assert_allclose(look_at([0, 0, 0], [0, 0, 1]), np.eye(4), atol=1e-12)


def test_look_at_errors():
    with pytest.raises(ValueError, match="target: must differ from eye"):
        look_at([1, 2, 3], [1, 2, 3])
    with pytest.raises(ValueError, match="up: must not be parallel"):
        look_at([0, 0, 0], [0, 5, 0], up=(0, -1, 0))
    with pytest.raises(ValueError, match=r"eye: expected shape \(3\)"):
        look_at([0, 0], [0, 0, 1])


# ----------------------------------------------------------------------------- interpolation
def test_interpolate_cameras_endpoints_midpoint_and_extrapolation():
    a = Camera(100.0, 110.0, 30.0, 20.0, 64, 48, pose_from([0.2, -0.1, 0.05], [0, 0, 0]))
    rel = Rotation.from_rotvec([0.0, 0.8, 0.3])  # 0.854 rad about a fixed axis
    pose_b = np.eye(4)
    pose_b[:3, :3] = (rel * Rotation.from_matrix(a.world_from_cam[:3, :3])).as_matrix()
    pose_b[:3, 3] = [2.0, -1.0, 4.0]
    b = Camera(120.0, 130.0, 34.0, 22.0, 64, 48, pose_b)
    assert interpolate_cameras(a, b, 0.0).allclose(a, atol=1e-12)
    assert interpolate_cameras(a, b, 1.0).allclose(b, atol=1e-12)
    angle = np.linalg.norm(rel.as_rotvec())
    for t in (0.5, 0.25, 2.0, -0.5):
        m = interpolate_cameras(a, b, t)
        step = Rotation.from_matrix(m.world_from_cam[:3, :3]) * Rotation.from_matrix(a.world_from_cam[:3, :3]).inv()
        # Slerp: rotation from a is t * angle about the same axis.
        np.testing.assert_allclose(step.as_rotvec(), t * rel.as_rotvec(), atol=1e-9)
        np.testing.assert_allclose(m.position, (1 - t) * a.position + t * b.position, atol=1e-12)
        assert m.fx == pytest.approx(100 + 20 * t) and m.cy == pytest.approx(20 + 2 * t)
    assert angle > 0.8
    with pytest.raises(ValueError, match="image size"):
        interpolate_cameras(a, Camera(100.0, 100.0, 1.0, 1.0, 10, 10), 0.5)
    with pytest.raises(ValueError, match="t: expected a finite number"):
        interpolate_cameras(a, b, float("nan"))


def test_interpolate_cameras_large_rotation_is_the_geodesic():
    """A 3.0-rad turn (near the half turn where rotation vectors get delicate): each step from a
    is t times the relative rotation vector, as scipy's Slerp gives it."""
    a = Camera(100.0, 100.0, 30.0, 20.0, 64, 48, pose_from([-0.4, 1.1, 0.3], [1, 2, 3]))
    rel = Rotation.from_rotvec(3.0 * np.array([0.48, -0.6, 0.64]))
    pose_b = np.eye(4)
    pose_b[:3, :3] = (rel * Rotation.from_matrix(a.world_from_cam[:3, :3])).as_matrix()
    b = Camera(100.0, 100.0, 30.0, 20.0, 64, 48, pose_b)
    slerp = Slerp([0.0, 1.0], Rotation.from_matrix(np.stack([a.world_from_cam[:3, :3], pose_b[:3, :3]])))
    for t in (0.1, 0.5, 0.9):
        np.testing.assert_allclose(interpolate_cameras(a, b, t).world_from_cam[:3, :3], slerp(t).as_matrix(), atol=1e-9)


# ----------------------------------------------------------------------------- OpenGL interop
@pytest.mark.parametrize("far", [100.0, np.inf])
@pytest.mark.parametrize("cx,cy", [(319.5, 239.5), (250.25, 300.75)])  # symmetric, off-axis
def test_gl_projection_round_trip(cx, cy, far):
    cam = Camera(500.0, 480.0, cx, cy, 640, 480, pose_from([0.3, 0.2, -0.4], [1.0, -2.0, 0.5]))
    p = cam.gl_projection(0.25, far)
    back, n, f = camera_from_gl_projection(p, 640, 480, view=cam.gl_view())
    assert back.allclose(cam, atol=1e-9)
    assert n == pytest.approx(0.25, rel=1e-12)
    assert f == pytest.approx(far, rel=1e-12) if np.isfinite(far) else np.isinf(f)
    symmetric = (cx, cy) == (319.5, 239.5)
    assert (abs(p[0, 2]) < 1e-15 and abs(p[1, 2]) < 1e-15) == symmetric
    # A uniformly scaled matrix is the same projection.
    again, _, _ = camera_from_gl_projection(3.0 * p, 640, 480, view=cam.gl_view())
    assert again.allclose(cam, atol=1e-9)


def test_gl_frustum_recovers_textbook_glfrustum():
    l, r, b, t, n, f = -0.3, 0.5, -0.2, 0.25, 0.5, 250.0
    fr = gl_frustum_from_projection(gl_frustum(l, r, b, t, n, f))
    np.testing.assert_allclose([fr.left, fr.right, fr.bottom, fr.top, fr.near, fr.far], [l, r, b, t, n, f], rtol=1e-12)
    # ... and the camera built from it sees the frustum edges at the image edges.
    cam, _, _ = camera_from_gl_projection(gl_frustum(l, r, b, t, n, f), 400, 300)
    corners_gl = np.array([[l, b, -n], [r, t, -n]])
    uv, _ = cam.project_cam(corners_gl * [1, -1, -1])
    np.testing.assert_allclose(uv, [[-0.5, 299.5], [399.5, -0.5]], atol=1e-9)


def test_camera_gl_frustum_matches_the_textbook_matrix_and_its_recovery():
    cam = Camera(500.0, 480.0, 250.25, 300.75, 640, 480)
    fr = cam.gl_frustum(0.25, 80.0)
    # Edges of the image (pixel edges, not centers) on the near plane.
    assert fr.left == pytest.approx(-(250.25 + 0.5) * 0.25 / 500.0, rel=1e-15)
    assert fr.top == pytest.approx((300.75 + 0.5) * 0.25 / 480.0, rel=1e-15)
    np.testing.assert_allclose(fr.projection(), gl_frustum(fr.left, fr.right, fr.bottom, fr.top, 0.25, 80.0), rtol=1e-14)
    back = gl_frustum_from_projection(cam.gl_projection(0.25, 80.0))
    np.testing.assert_allclose(
        [back.left, back.right, back.bottom, back.top, back.near, back.far],
        [fr.left, fr.right, fr.bottom, fr.top, fr.near, fr.far], rtol=1e-12)


def test_gl_ndc_signs_and_half_pixel():
    w, h = 64, 48
    cam = Camera(50.0, 55.0, 30.25, 20.75, w, h, pose_from([0.1, 0.2, 0.3], [0.5, 0.1, -1.0]))
    near, far = 0.5, 50.0
    # Pixel centers, edges and arbitrary subpixel positions at several depths.
    uv = np.array([[-0.5, -0.5], [0.0, 0.0], [w - 0.5, h - 0.5], [10.3, 40.9], [63.0, 1.0]])
    z = np.array([1.0, 2.0, 3.0, 10.0, 49.0])
    ndc, wclip = ndc_of(cam, near, far, cam.unproject(uv, z))
    assert np.all(wclip > 0)  # in front of the camera: w_clip = z_cv > 0
    assert np.all(np.abs(ndc) <= 1 + 1e-12)  # inside the image and between near and far: inside NDC
    assert np.all((ndc[:, 2] > -1) & (ndc[:, 2] < 1))
    # NDC x = -1 is the left edge of column 0 (u = -0.5); NDC y = +1 the top edge of row 0.
    np.testing.assert_allclose(ndc[:, 0], (2 * uv[:, 0] + 1) / w - 1, atol=1e-12)
    np.testing.assert_allclose(ndc[:, 1], 1 - (2 * uv[:, 1] + 1) / h, atol=1e-12)
    np.testing.assert_allclose(ndc[0, :2], [-1.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(ndc[2, :2], [1.0, -1.0], atol=1e-12)
    # A half-pixel shift would move pixel 0's center to NDC -1; ours is at -1 + 1/W.
    assert ndc[1, 0] == pytest.approx(-1 + 1 / w, abs=1e-12)
    # Window depth (z_ndc + 1) / 2 is exactly ibr.depth's window encoding (seed 002 eq. 2 / 2^24).
    np.testing.assert_allclose((ndc[:, 2] + 1) / 2, window_from_z(z, near=near, far=far), atol=1e-12)
    # GL eye frame = diag(1, -1, -1) of the CV camera frame: right stays right, down becomes up.
    x_cv = np.array([0.4, -0.3, 2.0, 1.0])
    x_gl = GL_FROM_CV @ x_cv
    assert x_gl[0] > 0 and x_gl[1] > 0 and x_gl[2] < 0
    world = (cam.world_from_cam @ x_cv)[:3]
    ndc1, _ = ndc_of(cam, near, far, world[None])
    uv1, _ = cam.project(world[None])
    assert (ndc1[0, 0] > (2 * cam.cx + 1) / w - 1) and (ndc1[0, 1] > 1 - (2 * cam.cy + 1) / h)  # right & up
    assert uv1[0, 0] > cam.cx and uv1[0, 1] < cam.cy
    # Behind the camera: w_clip < 0 (clipped by GL).
    _, wb = ndc_of(cam, near, far, (cam.world_from_cam @ [0, 0, -1.0, 1])[None, :3])
    assert wb[0] < 0


def test_gl_refuses_orthographic_and_garbage():
    with pytest.raises(ValueError, match="orthographic"):
        gl_frustum_from_projection(gl_ortho(-1, 1, -1, 1, 0.1, 10))
    rng = np.random.default_rng(3)
    with pytest.raises(ValueError, match="last row must be"):
        gl_frustum_from_projection(rng.normal(size=(4, 4)))
    sheared = gl_frustum(-1, 1, -1, 1, 0.1, 10)
    sheared[0, 1] = 0.3
    with pytest.raises(ValueError, match="shear or translation"):
        gl_frustum_from_projection(sheared)
    flipped = gl_frustum(-1, 1, -1, 1, 0.1, 10)
    flipped[0, 0] *= -1
    with pytest.raises(ValueError, match=r"P\[0,0\] and P\[1,1\] must be positive"):
        gl_frustum_from_projection(flipped)
    bad_depth = gl_frustum(-1, 1, -1, 1, 0.1, 10)
    bad_depth[2, 3] = 0.5
    with pytest.raises(ValueError, match="near > 0"):
        gl_frustum_from_projection(bad_depth)
    with pytest.raises(ValueError, match="non-finite"):
        gl_frustum_from_projection(np.full((4, 4), np.nan))
    with pytest.raises(ValueError, match=r"expected shape \(4, 4\)"):
        gl_frustum_from_projection(np.eye(3))
    with pytest.raises(ValueError, match="far > near"):
        Camera.from_fov(8, 8, hfov_deg=60).gl_projection(10.0, 1.0)


# ----------------------------------------------------------------------------- validation
@pytest.mark.parametrize(
    "kwargs,match",
    [
        (dict(fx=0.0), "fx: expected a positive number"),
        (dict(fy=-3.0), "fy: expected a positive number"),
        (dict(cx=float("nan")), "cx: expected a finite number"),
        (dict(width=0), "width: expected a positive integer"),
        (dict(height=2.5), "height: expected a positive integer"),
        (dict(world_from_cam=np.diag([1.0, 1.0, -1.0, 1.0])), "proper rotation"),
        (dict(world_from_cam=np.diag([2.0, 2.0, 2.0, 1.0])), "proper rotation"),
        (dict(world_from_cam=np.eye(4) + np.eye(4, k=-3)), "last row"),
        (dict(world_from_cam=np.eye(3)), r"expected shape \(4, 4\)"),
    ],
)
def test_impossible_camera_values(kwargs, match):
    args = dict(fx=100.0, fy=100.0, cx=10.0, cy=10.0, width=20, height=20)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        Camera(**args)


def test_dict_round_trip_is_exact_and_missing_keys_named():
    cam = Camera(123.456, 120.0, 33.3, 22.2, 70, 50, pose_from([0.3, -0.2, 1.1], [1e-3, 2.0, -7.0]))
    back = Camera.from_dict(cam.to_dict())
    assert back.allclose(cam, atol=0)
    assert not back.world_from_cam.flags.writeable
    with pytest.raises(ValueError, match="missing key.*fx"):
        Camera.from_dict({k: v for k, v in cam.to_dict().items() if k != "fx"})
    with pytest.raises(TypeError, match="camera: expected a JSON object"):
        Camera.from_dict([1, 2])
    with pytest.raises(ValueError, match="from_fov: give exactly one"):
        Camera.from_fov(10, 10)
    with pytest.raises(ValueError, match="hfov_deg: expected 0 < fov < 180"):
        Camera.from_fov(10, 10, hfov_deg=180)
