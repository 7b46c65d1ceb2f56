"""ibr.canvas: the virtual canvas of seed 004 -- mapping, content, strokes, video, picking, compositing."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

import ibr
from ibr.base.camera import Camera, look_at
from ibr.canvas import (Canvas, VideoSource, canvas_from_image, composite, composite_into, draw_stroke,
                        frame_schedule, pick_pixel, pick_pixels, pick_ray, power_of_two_size, stroke_from_screen,
                        texture_scale)
from ibr.canvas.strokes import SCREEN_STEP_PX
from ibr.synth import Box, ImageTexture, Rect, Scene, checker_texture, render
from ibr.synth.textures import _photo


def psnr(a, b):
    return 10 * np.log10(1.0 / max(float(np.mean((np.asarray(a, float) - np.asarray(b, float)) ** 2)), 1e-30))


def truth_rect(canvas: Canvas, image: np.ndarray) -> Rect:
    """The same image textured on the same plane for the ray caster (image corner on the canvas corner)."""
    w, h = canvas.size
    return Rect(ImageTexture(image, w), canvas.center, canvas.right, canvas.down, w / 2, h / 2, (-w / 2, -h / 2))


# ----------------------------------------------------------------------------- mapping (seed 004 section 2.2)
# Seed 004: a plane of N x M scene units centred at O, a T x T canvas, right-handed y-up frame; the four
# axis-aligned cases of its formulas, with the texture coordinate measured from the pixel edge (X_d = x + 1/2).
SEED_CASES = {
    "+z": lambda p, o, n, m, t: (((p[0] - o[0]) + n / 2) / n * t, (-(p[1] - o[1]) + m / 2) / m * t),
    "-z": lambda p, o, n, m, t: ((-(p[0] - o[0]) + n / 2) / n * t, (-(p[1] - o[1]) + m / 2) / m * t),
    "+x": lambda p, o, n, m, t: ((-(p[2] - o[2]) + n / 2) / n * t, (-(p[1] - o[1]) + m / 2) / m * t),
    "-x": lambda p, o, n, m, t: (((p[2] - o[2]) + n / 2) / n * t, (-(p[1] - o[1]) + m / 2) / m * t),
}
NORMALS = {"+z": (0, 0, 1), "-z": (0, 0, -1), "+x": (1, 0, 0), "-x": (-1, 0, 0)}


@pytest.mark.parametrize("case", sorted(SEED_CASES))
def test_seed_four_axis_aligned_cases(case):
    rng = np.random.default_rng(4)
    o, n_units, m_units, t = np.array([0.3, -1.2, 2.5]), 1.6, 0.9, 256
    c = Canvas(o, NORMALS[case], (n_units, m_units), up=(0, 1, 0), resolution=(t, t))
    normal = np.array(NORMALS[case], float)
    in_plane = [a for a in np.eye(3) if abs(a @ normal) < 0.5]
    pts = o + rng.uniform(-0.8, 0.8, (50, 1)) * in_plane[0] + rng.uniform(-0.45, 0.45, (50, 1)) * in_plane[1]
    xy = c.pixel_from_world(pts)
    for p, q in zip(pts, xy):
        xd, yd = SEED_CASES[case](p, o, n_units, m_units, t)
        assert q[0] + 0.5 == pytest.approx(xd, abs=1e-9) and q[1] + 0.5 == pytest.approx(yd, abs=1e-9)


def test_mapping_round_trip_any_orientation():
    rng = np.random.default_rng(0)
    for _ in range(20):
        n = rng.normal(size=3)
        up = rng.normal(size=3)
        c = Canvas(rng.normal(size=3), n, rng.uniform(0.2, 3, 2), up=up, resolution=tuple(rng.integers(3, 900, 2)))
        xy = rng.uniform(-0.5, 800, (100, 2))
        np.testing.assert_allclose(c.pixel_from_world(c.world_from_pixel(xy)), xy, atol=1e-9)
        p = c.world_from_pixel(xy)
        np.testing.assert_allclose((p - c.center) @ c.normal, 0, atol=1e-9)  # on the plane
        # right-handed canvas frame seen from the normal side: right x down = -normal... x right, y down, z = -normal
        np.testing.assert_allclose(np.cross(c.right, c.down), -c.normal, atol=1e-12)
    c = Canvas([0, 0, 3], [0, 0, -1], (2.0, 1.0), resolution=(4, 2))
    np.testing.assert_allclose(c.corners(), [[-1, -0.5, 3], [1, -0.5, 3], [1, 0.5, 3], [-1, 0.5, 3]])
    np.testing.assert_allclose(c.pixel_from_world([0, 0, 3]), [1.5, 0.5])  # centre between pixel centres


@pytest.mark.parametrize("kwargs, match", [
    (dict(normal=(0, 0, 0)), "normal: expected a finite non-zero 3-vector"),
    (dict(size=(0.0, 1.0)), "size: expected a positive finite"),
    (dict(size=(1.0, -2.0)), "size: expected a positive finite"),
    (dict(up=(0, 0, -2)), "up: must not be parallel to normal"),
    (dict(center=(np.nan, 0, 0)), "center: expected finite"),
    (dict(resolution=(0, 4)), "resolution: width"),
    (dict(resolution=(100000, 100000)), "resolution"),
])
def test_degenerate_planes_are_refused(kwargs, match):
    args = dict(center=(0, 0, 2), normal=(0, 0, -1), size=(1.0, 1.0))
    args.update(kwargs)
    extra = {k: args.pop(k) for k in ("up", "resolution") if k in args}
    with pytest.raises(ValueError, match=match):
        Canvas(args["center"], args["normal"], args["size"], **extra)


# ----------------------------------------------------------------------------- content
def test_power_of_two_scale_factors_are_the_corrected_ones():
    assert power_of_two_size(728, 480) == 1024 and power_of_two_size(512, 3) == 512 and power_of_two_size(1, 1) == 2
    fx, fy = texture_scale(728, 480, 1024)
    assert fx == pytest.approx(1024 / 728) and fy == pytest.approx(1024 / 480)
    # the seed's eqs. 5-6 (ceil(Height/T), ceil(Width/T)) would give 1 and 1 here: no scaling at all
    assert (int(np.ceil(480 / 1024)), int(np.ceil(728 / 1024))) == (1, 1)
    # a horizontal ramp through pixel centres stays exact under the pixel-centre mapping (away from the
    # clamped border): x0 = (x1 + 1/2) / f - 1/2
    ramp = np.tile(np.arange(16, dtype=np.float32), (8, 1))
    c = canvas_from_image(ramp / 15, (0, 0, 2), (0, 0, -1), (1, 0.5), power_of_two=True)
    assert c.resolution == (16, 16) and c.rgba.dtype == np.float32
    x1 = np.arange(2, 14)
    np.testing.assert_allclose(c.rgba[5, x1, 0] * 15, (x1 + 0.5) / 1.0 - 0.5, atol=1e-5)
    big = np.zeros((30, 50, 3), np.uint8)
    big[:, :25] = 200
    c = canvas_from_image(big, (0, 0, 2), (0, 0, -1), (1, 0.5), power_of_two=True)  # 50x30 -> 64x64 (enlarged)
    assert c.resolution == (64, 64) and c.rgba[10, 5, 0] == 200 and c.rgba[10, 60, 0] == 0
    assert np.all(c.rgba[..., 3] == 255)
    small = canvas_from_image(big, (0, 0, 2), (0, 0, -1), (1, 0.5), resolution=(10, 6))  # reduced: box filter
    assert small.rgba[3, 2, 0] == 200 and small.rgba[3, 7, 0] == 0


def test_image_dtypes_and_alpha():
    gray = np.full((4, 6), 0.5, np.float32)
    c = canvas_from_image(gray, (0, 0, 2), (0, 0, -1), (1, 1))
    np.testing.assert_allclose(c.rgba[0, 0], [0.5, 0.5, 0.5, 1.0])
    rgba16 = np.zeros((4, 6, 4), np.uint16)
    rgba16[..., 3] = 65535
    c = canvas_from_image(rgba16, (0, 0, 2), (0, 0, -1), (1, 1))
    assert c.rgba.dtype == np.uint16 and c.max_value == 65535
    with pytest.raises(ValueError, match="NaN"):
        canvas_from_image(np.full((4, 4, 3), np.nan, np.float32), (0, 0, 2), (0, 0, -1), (1, 1))


# ----------------------------------------------------------------------------- strokes
def test_stroke_coverage_is_anti_aliased_with_exact_width():
    c = Canvas((0, 0, 2), (0, 0, -1), (1, 1), resolution=(40, 30))
    n = draw_stroke(c, [[5.0, 10.5], [30.0, 10.5]], width=3.0, color=(1, 0, 0, 1))
    col = c.rgba[:, 15].astype(float) / 255
    # distance from row centre to the line: rows 10, 11 -> 0.5 (covered), rows 9, 12 -> 1.5 (half), 8, 13 -> 0
    np.testing.assert_allclose(col[8:14, 3], [0, 0.5, 1, 1, 0.5, 0], atol=1 / 255)
    np.testing.assert_allclose(col[9:13, 0], 1.0)  # straight alpha: the colour stays red at the edge
    assert n == int((c.rgba[..., 3] > 0).sum())
    before = c.rgba.copy()
    assert draw_stroke(c, [[-50, -50], [-20, -30]], width=4) == 0  # entirely outside: a no-op
    np.testing.assert_array_equal(c.rgba, before)
    assert draw_stroke(c, [[-10, 20], [10, 20]], width=2) > 0  # partly outside: clipped
    with pytest.raises(ValueError, match="width"):
        draw_stroke(c, [[1, 1]], width=0)
    with pytest.raises(ValueError, match="color"):
        draw_stroke(c, [[1, 1]], color="#12")
    with pytest.raises(ValueError, match="points"):
        draw_stroke(c, np.zeros((0, 2)))


def test_stroke_over_existing_content_blends_straight_alpha():
    c = Canvas((0, 0, 2), (0, 0, -1), (1, 1), resolution=(20, 20), dtype=np.float32)
    c.clear((0, 0, 1, 0.5))
    draw_stroke(c, [[10, 10]], width=6, color=(1, 0, 0, 0.5))  # a dot
    px = c.rgba[10, 10]
    a = 0.5 + 0.5 * 0.5
    np.testing.assert_allclose(px, [0.5 / a, 0, 0.25 / a, a], atol=1e-6)


def test_stroke_from_screen_points_is_split_where_it_leaves_the_canvas():
    cam = Camera.from_fov(200, 100, hfov_deg=60)
    c = Canvas((0, 0, 2), (0, 0, -1), (1.0, 0.5), resolution=(100, 50))
    other = Canvas((0.3, 0, 1.5), (0, 0, -1), (0.1, 1.0), resolution=(10, 100))  # in front, hides a band
    uv = np.stack([np.linspace(10, 190, 50), np.full(50, 49.5)], -1)
    parts = stroke_from_screen(cam, uv, c, others=[other])
    assert len(parts) == 2  # split by the nearer canvas
    # the screen x where the canvas's edges and the nearer canvas's edges project
    x_of = lambda p: cam.project(np.array([p], float))[0][0, 0]  # noqa: E731
    c_left, c_right = x_of((-0.5, 0, 2)), x_of((0.5, 0, 2))
    o_left, o_right = x_of((0.25, 0, 1.5)), x_of((0.35, 0, 1.5))
    ends = [(c_left, o_left), (o_right, c_right)]
    for part, (x0, x1) in zip(parts, ends):
        got, _ = cam.project(c.world_from_pixel(part))
        inner = got[1:-1, 0]  # the listed points between the ends where the part enters and leaves
        assert np.all(np.isin(np.round(inner, 6), np.round(uv[:, 0], 6)))
        assert abs(got[0, 0] - x0) <= SCREEN_STEP_PX + 1e-9 and abs(got[-1, 0] - x1) <= SCREEN_STEP_PX + 1e-9
    assert stroke_from_screen(cam, [[1, 1], [2, 2]], c) == []  # misses: nothing to draw


def test_a_screen_stroke_between_points_off_the_canvas_crosses_it():
    """Only the listed screen points were picked: a line across the canvas between two points
    off it drew nothing ("no stroke touches the canvas"), three points drew a dot. Now every
    segment is sampled, so the stroke runs from edge to edge of the canvas, as in the CLI."""
    cam = Camera.from_fov(200, 100, hfov_deg=60)
    c = Canvas((0, 0, 2), (0, 0, -1), (1.0, 0.5), resolution=(100, 50))
    for uv in ([[5, 50], [195, 50]], [[5, 50], [100, 50], [195, 50]]):
        parts = stroke_from_screen(cam, uv, c)
        assert len(parts) == 1
        np.testing.assert_allclose(parts[0][[0, -1], 0], [-0.5, 99.5], atol=1.0)  # its edges, to a sample
        assert np.ptp(parts[0][:, 1]) < 1e-6  # a screen row stays a canvas row
        draw_stroke(c, parts[0], width=4)
        painted = c.rgba[..., 3] > 0
        assert painted[:, 0].any() and painted[:, -1].any()  # edge to edge


# ----------------------------------------------------------------------------- picking
def test_pick_round_trip_is_exact_for_any_orientation():
    rng = np.random.default_rng(1)
    worst = 0.0
    for _ in range(25):
        cam = Camera.from_fov(640, 480, hfov_deg=rng.uniform(30, 100),
                              world_from_cam=look_at(rng.normal(size=3) * 0.3, rng.normal(size=3) * 0.2 + [0, 0, 4]))
        n = -cam.world_from_cam[:3, 2] + rng.normal(size=3) * 0.4
        c = Canvas(cam.position + cam.world_from_cam[:3, 2] * rng.uniform(1, 5), n, rng.uniform(0.5, 2, 2),
                   up=rng.normal(size=3), resolution=tuple(rng.integers(10, 2000, 2)))
        w, h = c.resolution
        xy = np.stack([rng.uniform(-0.5, w - 0.5, 40), rng.uniform(-0.5, h - 0.5, 40)], -1)
        uv, z = cam.project(c.world_from_pixel(xy))
        ok = (z > 0) & np.all(np.isfinite(uv), axis=1)
        index, got, _ = pick_pixels(cam, uv[ok], [c])
        assert np.all(index == 0)
        worst = max(worst, float(np.abs(got - xy[ok]).max()))
        p = pick_pixel(cam, *uv[ok][0], c)
        np.testing.assert_allclose(p.xy, xy[ok][0], atol=1e-6)
        np.testing.assert_allclose(p.point, c.world_from_pixel(xy[ok][0]), atol=1e-9)
    assert worst < 1e-6


def test_pick_nearest_canvas_and_scene_occlusion_and_misses():
    cam = Camera.from_fov(100, 100, hfov_deg=60)
    far = Canvas((0, 0, 3), (0, 0, -1), (2, 2), resolution=(50, 50))
    near = Canvas((0, 0, 2), (0, 0, -1), (0.2, 0.2), resolution=(10, 10))
    p = pick_pixel(cam, 49.5, 49.5, [far, near])
    assert p.index == 1 and p.distance == pytest.approx(2.0)
    assert pick_pixel(cam, 30, 49.5, [far, near]).index == 0
    depth = np.full((100, 100), 2.5, np.float32)  # a wall between the two canvases
    assert pick_pixel(cam, 30, 49.5, [far, near], depth=depth) is None  # the far canvas is hidden
    assert pick_pixel(cam, 49.5, 49.5, [far, near], depth=depth).index == 1
    assert pick_pixel(cam, 0, 0, [near]) is None  # a click on no canvas: defined no-op
    assert pick_ray([near], [0, 0, 0], [0, 0, -1]) is None  # behind the ray
    assert pick_ray([near], [0, 0, 0], [1, 0, 0]) is None  # parallel to the plane
    with pytest.raises(ValueError, match="dirs"):
        pick_ray([near], [0, 0, 0], [0, 0, 0])
    with pytest.raises(TypeError, match="canvases"):
        pick_pixel(cam, 1, 1, ["not a canvas"])


# ----------------------------------------------------------------------------- compositing vs the ray caster
@pytest.fixture(scope="module")
def truth_scene():
    img = _photo("astronaut")[::2, ::2].copy()  # 256 x 256 float32
    h, w = img.shape[:2]
    c = canvas_from_image(img, [0.2, -0.1, 4.0], [0.3, 0.1, -1.0], [2.0, 2.0 * h / w], up=[0.1, -1, 0])
    wall = Rect(checker_texture(width_units=2.0), np.array([0, 0, 6.0]), np.array([1.0, 0, 0]),
                np.array([0, 1.0, 0]), 5, 5, (0, 0))
    box = Box(checker_texture(width_units=0.5), np.array([0.6, 0.3, 3.0]), np.array([0.25, 0.25, 0.25]))
    bg = Scene((wall, box), ambient=1.0, diffuse=0.0)  # unlit: the colour is the texture
    full = Scene((wall, box, truth_rect(c, img)), ambient=1.0, diffuse=0.0)
    cam = Camera.from_fov(480, 360, hfov_deg=60, world_from_cam=look_at([0.5, -0.3, 0.0], [0, 0, 4]))
    return c, bg, full, cam


def test_pinhole_composite_matches_the_ray_caster(truth_scene):
    c, bg, full, cam = truth_scene
    base = render(bg, cam)
    truth = render(full, cam)
    hard = composite(base, c, antialias=False)
    assert isinstance(hard, ibr.View)
    assert psnr(hard.color, truth.color) > 80  # same plane, same bilinear texels: only 1/32-px quantization
    # anti-aliased edges (coverage of the pixel by the projected rectangle)
    soft = composite(base, c)
    assert psnr(soft.color, truth.color) > 40
    # occlusion: wherever the box (nearer than the canvas) is seen, the pixel is exactly the scene's
    _, xy = c.intersect(cam.position, cam.rays_world()[1].reshape(-1, 3))
    hit = np.isfinite(xy[:, 0]).reshape(cam.shape)
    box_in_front = hit & (base.depth < 3.6)
    assert box_in_front.sum() > 200
    np.testing.assert_array_equal(hard.color[box_in_front], base.color[box_in_front])
    np.testing.assert_array_equal(soft.color[box_in_front], base.color[box_in_front])
    # the depth of the result is the canvas's where it is seen
    seen = hit & ~(base.depth < 3.6)
    z_truth = truth.depth
    np.testing.assert_allclose(hard.depth[seen], z_truth[seen], rtol=1e-5)


def test_composite_into_warp_renderings_and_uint8_exact_copy():
    # a uint8 image seen fronto-parallel at exactly one canvas pixel per target pixel is copied as it is
    cam = Camera.from_fov(64, 48, hfov_deg=60)
    img = np.random.default_rng(2).integers(0, 256, (20, 30, 3), np.uint8)
    z = 2.0
    size = (30 * z / cam.fx, 20 * z / cam.fy)
    # centre between pixel centres so that canvas pixel centres land on target pixel centres
    center = cam.unproject(np.array([cam.cx + 0.0, cam.cy + 0.0]), z)
    c = canvas_from_image(img, center, (0, 0, -1), size)
    out = np.zeros((48, 64, 3), np.uint8)
    composite_into(out, cam, c, antialias=False)
    u0, v0 = int(cam.cx - 14.5), int(cam.cy - 9.5)
    np.testing.assert_array_equal(out[v0:v0 + 20, u0:u0 + 30], img)
    assert out.sum() == img.astype(np.int64).sum()
    # into an ibr.warp rendering: a Rendering comes back, holes untouched, depth updated
    view = ibr.View(np.zeros((48, 64, 3), np.float32), np.full((48, 64), 5.0, np.float32), cam)
    r = ibr.warp(view, cam)
    rc = composite(r, c)
    assert isinstance(rc, ibr.Rendering) and rc.holes is r.holes
    assert np.nanmin(rc.depth) == pytest.approx(2.0, rel=1e-6) and np.nanmax(rc.depth) == pytest.approx(5.0)
    with pytest.raises(ValueError, match="camera"):
        composite(np.zeros((4, 4, 3), np.float32), c)
    with pytest.raises(ValueError, match="size"):
        composite_into(np.zeros((4, 4, 3), np.float32), cam, c)


def test_public_names_are_functions_after_the_modules_load():
    import importlib

    import ibr.canvas

    importlib.import_module("ibr.canvas.compositor")
    assert callable(ibr.canvas.composite) and ibr.canvas.composite.__module__ == "ibr.canvas.compositor"
    assert ibr.canvas.pick_pixel.__module__ == "ibr.canvas.pick"


def test_canvas_crossing_the_camera_plane_and_behind():
    cam = Camera.from_fov(80, 60, hfov_deg=90)
    floor = Canvas((0, 1, 0), (0, -1, 0), (4, 4), up=(0, 0, 1), resolution=(40, 40))  # under and around the camera
    floor.clear((0, 1, 0, 1))
    out = np.zeros((60, 80, 3), np.float32)
    composite_into(out, cam, floor)
    assert out[59, 40, 1] == pytest.approx(1.0) and out[0, 40, 1] == 0  # floor below, nothing above
    behind = Canvas((0, 0, -2), (0, 0, 1), (1, 1), resolution=(4, 4))
    behind.clear((1, 1, 1, 1))
    out2 = np.zeros((60, 80, 3), np.float32)
    composite_into(out2, cam, behind)
    assert not out2.any()


# ----------------------------------------------------------------------------- video
@pytest.fixture()
def video_file(tmp_path):
    path = tmp_path / "clip.avi"
    w = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 24, (64, 48))
    assert w.isOpened()
    for i in range(6):
        f = np.zeros((48, 64, 3), np.uint8)
        f[..., 1] = 40 * i  # BGR: green ramps up frame by frame
        w.write(f)
    w.release()
    return path


def test_video_frames_into_canvas(video_file, tmp_path):
    src = VideoSource(video_file)
    assert src.size == (64, 48) and src.fps == pytest.approx(24)
    c = Canvas((0, 0, 2), (0, 0, -1), (1.0, 0.75), resolution=src.size)
    greens = []
    while src.read_into(c):
        greens.append(int(c.rgba[20, 30, 1]))
        assert c.rgba[20, 30, 0] < 8 and c.rgba[20, 30, 3] == 255  # BGR -> RGBA
    assert len(greens) == 6 and np.all(np.abs(np.array(greens) - 40 * np.arange(6)) <= 3)
    src.close()
    small = Canvas((0, 0, 2), (0, 0, -1), (1.0, 0.75), resolution=(16, 12))
    with VideoSource(video_file) as s2:
        assert s2.read_into(small) and small.rgba.shape == (12, 16, 4)  # resampled once
    (tmp_path / "bad.mp4").write_bytes(b"this is not a video")
    with pytest.raises(ValueError, match="cannot open|no decodable"):
        VideoSource(tmp_path / "bad.mp4")
    with pytest.raises(FileNotFoundError, match="not found"):
        VideoSource(tmp_path / "missing.mp4")


def test_frame_schedule_is_the_pulldown_of_seed_001():
    np.testing.assert_array_equal(frame_schedule(10, 60, 24), [0, 0, 0, 1, 1, 2, 2, 2, 3, 3])  # 3:2
    np.testing.assert_array_equal(frame_schedule(4, 30, 30), [0, 1, 2, 3])
    np.testing.assert_array_equal(frame_schedule(5, 96, 24), [0, 0, 0, 0, 1])
    with pytest.raises(ValueError, match="display_fps"):
        frame_schedule(3, 0, 24)


def test_review_findings_grey_targets_ray_alpha_rgba_order_and_float64():
    """Found by a review, each against the pinhole RGB path as the reference: (1) a grey target
    read a uint8 canvas's alpha 255x (an opaque grey 0.2 over 100 gave 0, a float target -50.6);
    (2) the ray path multiplied alpha in twice (white at alpha 0.5 over black: 0.252, the
    pinhole 0.502); (3) an RGBA target crashed the ray path; (4) over an image array canvases
    were ordered by their centres only (a farther canvas whose centre is nearer painted over
    the nearer one); (5) a View with float64 colour was refused."""
    from ibr.base.view import View
    from ibr.canvas import composite, composite_into, composite_rays_into, pick_pixel
    from ibr.canvas.pick import camera_rays

    cam = Camera(100.0, 100.0, 31.5, 23.5, 64, 48)
    c = Canvas((0, 0, 10), (0, 0, -1), (2, 1), resolution=(20, 10), dtype=np.uint8)
    c.clear((0.2, 0.2, 0.2, 1.0))
    g, rgb, gf = np.full((48, 64), 100, np.uint8), np.full((48, 64, 3), 100, np.uint8), np.full((48, 64), 0.4, np.float32)
    for img in (g, rgb, gf):
        composite_into(img, cam, c)
    assert g[23, 31] == rgb[23, 31, 0] == 51 and gf[23, 31] == pytest.approx(0.2, abs=1e-6)
    vv, uu = np.mgrid[0:48, 0:64]
    o, d, _ = camera_rays(cam, np.stack([uu.ravel(), vv.ravel()], -1).astype(float))
    d = d.reshape(48, 64, 3)
    half = Canvas((0, 0, 10), (0, 0, -1), (2, 1), resolution=(20, 10), dtype=np.uint8)
    half.clear((1, 1, 1, 0.5))
    for channels in (3, 4):
        p = np.zeros((48, 64, channels), np.float32)
        r = np.zeros((48, 64, channels), np.float32)
        composite_into(p, cam, half)
        composite_rays_into(r, o, d, half)
        np.testing.assert_allclose(r[23, 31], p[23, 31], atol=1e-3)
        assert p[23, 31, 0] == pytest.approx(128 / 255, abs=1e-3)
    a = Canvas((0, 0, 5), (0, 0, -1), (1, 1), resolution=(8, 8), name="A")
    a.clear((1, 0, 0, 1))  # red, z = 5 on the axis
    n = np.array([-1.0, 0, -1.0]) / np.sqrt(2)
    b = Canvas((2, 0, 4), n, (8, 2), resolution=(32, 8), name="B")
    b.clear((0, 0, 1, 1))  # blue: its centre is nearer, but it is at z = 6 on the axis
    assert pick_pixel(cam, 31.5, 23.5, [a, b]).canvas.name == "A"
    black = np.zeros((48, 64, 3), np.uint8)
    for out in (composite(black, [a, b], camera=cam), composite(View(black, None, cam), [a, b]).color):
        assert out[23, 31].tolist() == [255, 0, 0]
    r = np.zeros((48, 64, 3), np.float32)
    composite_rays_into(r, o, d, [a, b])
    assert r[23, 31].tolist() == [1.0, 0.0, 0.0]
    v64 = composite(View(np.zeros((48, 64, 3), np.float64), None, cam), [half])
    assert v64.color.dtype == np.float64 and v64.color[23, 31, 0] == pytest.approx(128 / 255, abs=1e-3)


def test_a_screen_stroke_is_clipped_to_the_screen_and_split_where_it_leaves_it(monkeypatch):
    """Sampling every half pixel grew with a segment's length off screen (+-1e6 px: 4M samples, 3 s);
    segments are clipped to the screen first, and a stroke that leaves the screen and comes back
    is two parts (not joined by a line across the canvas)."""
    import ibr.canvas.strokes as strokes

    picked = []
    pick = strokes.pick_pixels
    monkeypatch.setattr(strokes, "pick_pixels",
                        lambda cam, uv, *a, **k: picked.append(len(uv)) or pick(cam, uv, *a, **k))
    cam = Camera.from_fov(200, 100, hfov_deg=60)
    c = Canvas((0, 0, 2), (0, 0, -1), (1.0, 0.5), resolution=(100, 50))
    (part,) = stroke_from_screen(cam, [[-1e6, 50], [1e6, 50]], c)
    assert picked == [401]  # the 200 px on screen, every half pixel
    np.testing.assert_allclose(part[[0, -1], 0], [-0.5, 99.5], atol=1.0)
    parts = stroke_from_screen(cam, [[80, 50], [80, -500], [120, -500], [120, 50]], c)
    assert len(parts) == 2 and all(np.ptp(p[:, 0]) < 1e-6 for p in parts)  # two vertical pieces
    (dot,) = stroke_from_screen(cam, [[100, 50]], c)
    assert dot.shape == (1, 2)


def test_an_empty_screen_stroke_draws_nothing():
    cam = Camera.from_fov(200, 100, hfov_deg=60)
    c = Canvas((0, 0, 2), (0, 0, -1), (1.0, 0.5), resolution=(100, 50))
    assert stroke_from_screen(cam, np.empty((0, 2)), c) == []
