"""panorama conversions: orientation, accuracy against analytic sphere functions, seams, poles,
area filtering, depth and bad input."""

from __future__ import annotations

import numpy as np
import pytest

import panorama as P
from panorama.directions import (
    FACE_NAMES,
    WORLD_FROM_FACE,
    direction_from_equirect_pixel,
    equirect_directions,
    equirect_pixel_from_direction,
    face_directions,
    face_pixel_from_direction,
    world_from_view,
)
from panorama.maps import perspective_rays

W, H, S = 512, 256, 128


def smooth(d):
    """Analytic RGB function on the sphere (a few cycles around, values in [0.2, 0.8])."""
    d = d / np.linalg.norm(d, axis=-1, keepdims=True)
    return np.stack([0.5 + 0.3 * np.sin(5 * d[..., 0] + 2 * d[..., 1]),
                     0.5 + 0.3 * np.cos(4 * d[..., 1] - 3 * d[..., 2]),
                     0.5 + 0.2 * d[..., 0] * d[..., 2]], axis=-1)


def psnr(a, b):
    return 10 * np.log10(1.0 / np.mean((np.asarray(a, np.float64) - b) ** 2))


@pytest.fixture(scope="module")
def eq():
    return smooth(equirect_directions(W, H)).astype(np.float32)


@pytest.fixture(scope="module")
def cube_truth():
    return smooth(face_directions(S))


# ------------------------------------------------------------------ conventions
def test_conventions_worked_numbers():
    u, v = equirect_pixel_from_direction(np.array([[0, 0, 1], [1, 0, 0], [0, -1, 0]]), 4096, 2048)
    np.testing.assert_allclose(u[:2], [2047.5, 3071.5])
    np.testing.assert_allclose(v, [1023.5, 1023.5, -0.5])
    # column 0's centre is 0.044 deg right of the seam at -180
    d = direction_from_equirect_pixel(0, 1023.5, 4096, 2048)
    assert np.degrees(np.arctan2(d[0], d[2])) == pytest.approx(-180 + 360 / 4096 / 2)
    np.testing.assert_allclose(world_from_view(90, 0) @ [0, 0, 1], [1, 0, 0], atol=1e-12)
    np.testing.assert_allclose(world_from_view(0, 90) @ [0, 0, 1], [0, -1, 0], atol=1e-12)
    np.testing.assert_allclose(world_from_view(0, 0, 30) @ [1, 0, 0], [np.cos(np.pi / 6), 0.5, 0], atol=1e-12)


def test_faces_are_proper_rotations_and_cover_the_sphere():
    np.testing.assert_allclose(np.linalg.det(WORLD_FROM_FACE), 1.0)  # no mirrored face
    for f, r in enumerate(WORLD_FROM_FACE):
        np.testing.assert_allclose(r.T @ r, np.eye(3), atol=1e-12)
    face, u, v = face_pixel_from_direction(face_directions(8), 8)
    np.testing.assert_array_equal(face, np.arange(6)[:, None, None] * np.ones((1, 8, 8), int))
    j, i = np.mgrid[0:8, 0:8]
    np.testing.assert_allclose(u, np.broadcast_to(i, u.shape), atol=1e-9)
    np.testing.assert_allclose(v, np.broadcast_to(j, v.shape), atol=1e-9)


# direction -> (face, expected pixel) at S = 512, worked out from the table in directions.py
KNOWN = [
    ((1, 0.5, 0.25), "+x", (191.5, 383.5)),     # right = -z, down = +y
    ((-1, -0.5, 0.25), "-x", (319.5, 127.5)),   # right = +z, down = +y
    ((0.25, 1, 0.5), "+y", (319.5, 127.5)),     # floor: right = +x, down = -z
    ((0.25, -1, 0.5), "-y", (319.5, 383.5)),    # sky: right = +x, down = +z
    ((0.25, 0.5, 1), "+z", (319.5, 383.5)),     # right = +x, down = +y
    ((0.25, 0.5, -1), "-z", (191.5, 383.5)),    # right = -x, down = +y
]


@pytest.mark.parametrize("direction, face, pixel", KNOWN)
def test_known_direction_lands_in_expected_face_pixel(direction, face, pixel):
    """Render a small bright spot at a known direction into an equirect, convert it, and find the
    spot's centroid in the expected face at the expected pixel (catches mirrored/rotated faces)."""
    d0 = np.array(direction, float) / np.linalg.norm(direction)
    w, h, s = 4096, 2048, 512
    # only a window around the spot is non-zero: build the full image sparsely
    img = np.zeros((h, w), np.float32)
    u0, v0 = equirect_pixel_from_direction(d0, w, h)
    vs, us = np.mgrid[int(v0) - 40:int(v0) + 41, int(u0) - 40:int(u0) + 41]
    dirs = direction_from_equirect_pixel(us, vs, w, h)
    img[vs, us % w] = np.exp(-(1 - dirs @ d0) / 2e-5)  # ~0.36 deg wide spot
    faces = P.equirect_to_cubemap(img, s, layout="dict")
    lit = [name for name in FACE_NAMES if faces[name].max() > 0.5]
    assert lit == [face]
    f = faces[face].astype(np.float64)
    jj, ii = np.mgrid[0:s, 0:s]
    centroid = (np.sum(f * ii) / f.sum(), np.sum(f * jj) / f.sum())
    np.testing.assert_allclose(centroid, pixel, atol=0.05)


def test_py360convert_faces_have_our_orientation():
    """py360convert's own sampling grid (its xyzcube, y up) lands on our matching face with our
    orientation; its grid is edge-centred (linspace), ours pixel-centred: u = i S/(S-1) - 0.5."""
    utils = pytest.importorskip("py360convert.utils")
    s = 16
    xyz = np.asarray(utils.xyzcube(s), np.float64)  # (S, 6S, 3) F R B L U D, y up
    ours = {"F": "+z", "R": "+x", "B": "-z", "L": "-x", "U": "-y", "D": "+y"}
    for k, key in enumerate("FRBLUD"):
        d = xyz[:, k * s:(k + 1) * s] * np.array([1, -1, 1])  # y up -> y down
        face, u, v = face_pixel_from_direction(d, s)
        inner = (slice(1, -1), slice(1, -1))  # py360convert's outer texels lie on the cube edges
        assert np.all(face[inner] == FACE_NAMES.index(ours[key])), key
        local = d @ WORLD_FROM_FACE[FACE_NAMES.index(ours[key])]  # face_from_world @ d
        u = (local[..., 0] / local[..., 2] + 1) * s / 2 - 0.5
        v = (local[..., 1] / local[..., 2] + 1) * s / 2 - 0.5
        j, i = np.mgrid[0:s, 0:s]
        np.testing.assert_allclose(u, i * s / (s - 1) - 0.5, atol=1e-4)
        np.testing.assert_allclose(v, j * s / (s - 1) - 0.5, atol=1e-4)


def test_openexr_vstrip_orientation():
    """The vstrip layout follows OpenEXR's ImfEnvmap.cpp (CubeMap::pixelPosition / direction),
    transcribed here: OpenEXR's frame is ours turned 180 deg about z (x_ours = -x_exr,
    y_ours = -y_exr) and it puts the outer texel centres on the cube edges (scale S - 1)."""
    s = 9
    strip = P.pack_faces(list(np.arange(6)[:, None, None] * np.ones((6, s, s))), "vstrip")
    from panorama.layouts import layout_index_maps
    face, i, j = layout_index_maps("vstrip", s)
    ours = face_directions(s)[face, j, i]
    for exr_face in range(6):  # POS_X, NEG_X, POS_Y, NEG_Y, POS_Z, NEG_Z top to bottom
        r, c = np.mgrid[0:s, 0:s].astype(float)
        # inverse of CubeMap::pixelPosition (local row r, column c inside the face's tile)
        pif = {0: (s - 1 - r, c), 1: (s - 1 - r, s - 1 - c), 2: (c, s - 1 - r),
               3: (c, r), 4: (s - 1 - c, s - 1 - r), 5: (c, s - 1 - r)}[exr_face]
        px, py = (pif[0] / (s - 1) * 2 - 1, pif[1] / (s - 1) * 2 - 1)
        one = np.ones_like(px)
        d_exr = {0: (one, px, py), 1: (-one, px, py), 2: (px, one, py), 3: (px, -one, py),
                 4: (px, py, one), 5: (px, py, -one)}[exr_face]
        d = np.stack([-d_exr[0], -d_exr[1], d_exr[2]], -1)
        tile = ours[exr_face * s:(exr_face + 1) * s]
        cosang = np.sum(d * tile, -1) / np.linalg.norm(d, axis=-1) / np.linalg.norm(tile, axis=-1)
        # same texel up to OpenEXR's (S-1) vs our S scaling: well under one texel (90/9 deg)
        assert np.degrees(np.arccos(np.clip(cosang, -1, 1))).max() < 6, exr_face
        assert np.all(strip[exr_face * s:(exr_face + 1) * s] == face[exr_face * s])


# ------------------------------------------------------------------ accuracy, seams, poles
def test_e2c_accuracy_and_seams(eq, cube_truth):
    cube = np.stack(P.equirect_to_cubemap(eq, S, layout="list"))
    err = np.abs(cube - cube_truth).max(-1)
    band = np.zeros((S, S), bool)
    band[[0, -1]] = band[:, [0, -1]] = True
    assert psnr(cube, cube_truth) >= 75
    assert err.max() < 5e-4
    assert err[:, band].max() <= 2 * err[:, ~band].max()


def test_c2e_accuracy_and_seams(eq, cube_truth):
    out = P.cubemap_to_equirect([f.astype(np.float32) for f in cube_truth], W, H, layout="list")
    err = np.abs(out - eq).max(-1)
    _, u, v = face_pixel_from_direction(equirect_directions(W, H), S)
    seam = (u < 0.5) | (u > S - 1.5) | (v < 0.5) | (v > S - 1.5)
    assert psnr(out, eq) >= 75
    assert err[seam].max() <= 2 * err[~seam].max()
    # no duplicated seam column: the two columns next to lon = 180 differ like any neighbours
    assert np.abs(out[:, 0] - out[:, -1]).max() < 3 * np.abs(out[:, 1] - out[:, 0]).max() + 1e-6


@pytest.mark.parametrize("source", ["equirect", "cube"])
@pytest.mark.parametrize("yaw, pitch, roll", [(30, 10, 0), (-170, 90, 20), (180, -89, -45)])
def test_perspective_accuracy_incl_poles(eq, cube_truth, source, yaw, pitch, roll):
    pano = eq if source == "equirect" else [f.astype(np.float32) for f in cube_truth]
    # 192 px over 100 deg: output texels as fine as the 512-wide source's, so no pre-filter
    out = P.perspective(pano, yaw_deg=yaw, pitch_deg=pitch, roll_deg=roll, fov_deg=100,
                        width=192, height=144)
    truth = smooth(perspective_rays(yaw, pitch, roll, 100, 192, 144))
    assert np.abs(out - truth).max() < 2e-3
    assert psnr(out, truth) >= 75


def test_half_pixel_shift_is_detected(eq):
    """The tolerance used above is tight enough that a half-pixel grid error would fail it."""
    cube = np.stack(P.equirect_to_cubemap(eq, S, layout="list"))
    d = face_directions(S)
    shifted = d + 0.5 * (2 / S) * WORLD_FROM_FACE[:, None, None, :, 0]  # half a texel to the right
    err_ok = np.abs(cube - smooth(d)).max()
    err_shift = np.abs(cube - smooth(shifted)).max()
    assert err_ok < 5e-4 < err_shift / 10


@pytest.mark.parametrize("dtype, value", [(np.uint8, 200), (np.uint16, 51234), (np.float32, 0.3)])
def test_uniform_stays_uniform_across_seams_and_poles(dtype, value):
    eq = np.full((64, 128, 3), value, dtype)
    for layout in ("list", "horizon", "vstrip", "dice"):
        cube = P.equirect_to_cubemap(eq, 37, layout=layout)
        faces = np.stack(P.unpack_faces(cube, layout))
        assert faces.dtype == dtype
        np.testing.assert_allclose(faces, value, rtol=1e-6)
    back = P.cubemap_to_equirect(list(faces), 200, 100, layout="list")
    np.testing.assert_allclose(back, value, rtol=1e-6)
    for src in (eq, list(faces)):
        view = P.perspective(src, yaw_deg=45, pitch_deg=88, roll_deg=10, fov_deg=120, width=40, height=30)
        np.testing.assert_allclose(view, value, rtol=1e-6)


def test_area_filter_prevents_aliasing():
    """Fine stripes (2-pixel period in longitude) must average to grey in a small preview."""
    w, h = 1024, 512
    stripes = np.tile(np.array([0.0, 1.0], np.float32), w // 2)[None, :].repeat(h, 0)
    view = P.perspective(stripes, yaw_deg=10, pitch_deg=0, fov_deg=90, width=32, height=24)
    assert np.abs(view - 0.5).max() < 0.1
    faces = np.stack(P.equirect_to_cubemap(stripes, 16, layout="list"))
    assert np.abs(faces[[0, 1, 4, 5]] - 0.5).max() < 0.1


def test_odd_sizes_work(eq):
    w, h, s = 90, 45, 33
    img = smooth(equirect_directions(w, h)).astype(np.float32)
    cube = np.stack(P.equirect_to_cubemap(img, s, layout="list"))
    assert np.abs(cube - smooth(face_directions(s))).max() < 0.02
    back = P.cubemap_to_equirect(list(cube), w, h, layout="list")
    assert back.shape == (h, w, 3)
    assert np.abs(back - img).max() < 0.03


# ------------------------------------------------------------------ depth
def test_planar_range_conversion_is_exact_on_ray_traced_geometry():
    from ibr.synth import make_scene, render_rays
    from panorama.depth import face_ray_lengths, planar_from_range, range_from_planar
    s = 24
    scene = make_scene("room")
    d = face_directions(s)
    _, rng = render_rays(scene, np.zeros(3), d / np.linalg.norm(d, axis=-1, keepdims=True))
    z = planar_from_range(rng, face_ray_lengths(s))
    # planar z is the point's coordinate along each face's forward axis
    pts = rng[..., None] * d / np.linalg.norm(d, axis=-1, keepdims=True)
    fwd = np.einsum("fhwi,fi->fhw", pts, WORLD_FROM_FACE[:, :, 2])
    np.testing.assert_allclose(z, fwd, rtol=1e-6)
    np.testing.assert_allclose(range_from_planar(z, face_ray_lengths(s)), rng, rtol=1e-6)


@pytest.mark.parametrize("interpolation", ["nearest", "linear"])
def test_depth_round_trip_on_a_centred_sphere_is_exact(interpolation):
    r = 3.5
    rng = np.full((64, 128), r, np.float32)
    z = np.stack(P.equirect_to_cubemap(rng, 20, layout="list", depth=True, interpolation=interpolation))
    np.testing.assert_allclose(z, r / np.linalg.norm(face_directions(20), axis=-1), rtol=1e-6)
    back = P.cubemap_to_equirect(list(z), 128, 64, layout="list", depth=True, interpolation=interpolation)
    np.testing.assert_allclose(back, r, rtol=1e-6)
    view = P.perspective(list(z), yaw_deg=20, pitch_deg=70, fov_deg=100, width=30, height=20, depth=True)
    np.testing.assert_allclose(view, r / np.linalg.norm(perspective_rays(20, 70, 0, 100, 30, 20), axis=-1),
                               rtol=1e-6)


def test_depth_matches_ground_truth_renders():
    from ibr.synth import make_scene, scene_cameras
    from panorama.synth import render_cubemap, render_equirect
    scene = make_scene("room")
    origin = scene_cameras("room")[0].position
    _, rng = render_equirect(scene, 256, 128, origin=origin)
    _, z_truth = render_cubemap(scene, 48, origin=origin)
    truth = np.stack(z_truth)
    z = np.stack(P.equirect_to_cubemap(rng, 48, layout="list", depth=True, interpolation="linear"))
    rel = np.abs(z - truth) / truth
    # range differs from planar z by up to 73 % at face corners: a missing or wrong conversion
    # fails by far; what remains is the resampling of a 1.4-degree equirect texel
    assert np.nanmedian(rel) < 5e-4
    assert np.nanpercentile(rel, 90) < 2e-3
    z = np.stack(P.equirect_to_cubemap(rng, 48, layout="list", depth=True))  # nearest (default)
    rel = np.abs(z - truth) / truth
    assert np.nanpercentile(rel, 90) < 0.03  # the nearest texel's ray is up to 0.7 deg away


def test_color_matches_ground_truth_renders():
    from ibr.synth import make_scene, scene_cameras
    from panorama.synth import render_cubemap, render_equirect
    scene = make_scene("plane")
    origin = scene_cameras("plane")[0].position
    col, _ = render_equirect(scene, 256, 128, origin=origin, supersample=2)
    faces, _ = render_cubemap(scene, 64, origin=origin, supersample=2)
    out = np.stack(P.equirect_to_cubemap(col, 64, layout="list"))
    assert psnr(out, np.stack(faces)) > 30


# ------------------------------------------------------------------ bad input
def test_errors_are_clear(eq):
    with pytest.raises(ValueError, match=r"2:1.*got 100 x 64"):
        P.equirect_to_cubemap(np.zeros((64, 100, 3), np.uint8), 16)
    with pytest.raises(ValueError, match="face_size: expected a positive integer"):
        P.equirect_to_cubemap(eq, 0)
    with pytest.raises(ValueError, match="layout: expected one of"):
        P.equirect_to_cubemap(eq, 16, layout="diamond")
    with pytest.raises(ValueError, match="must be square"):
        P.cubemap_to_equirect([np.zeros((8, 9, 3))] * 6, 64, 32, layout="list")
    with pytest.raises(ValueError, match=r"layout 'horizon' needs a \(1\*S, 6\*S\)"):
        P.cubemap_to_equirect(np.zeros((8, 50, 3)), 64, 32, layout="horizon")
    with pytest.raises(ValueError, match=r"width, height: .*2:1"):
        P.cubemap_to_equirect([np.zeros((8, 8))] * 6, 64, 64, layout="list")
    with pytest.raises(TypeError, match="layout 'list' expects a list of 6 faces"):
        P.cubemap_to_equirect([np.zeros((8, 8))] * 5, 64, 32, layout="list")
    with pytest.raises(ValueError, match="fov_deg: expected 0 < fov_deg < 180"):
        P.perspective(eq, yaw_deg=0, pitch_deg=0, fov_deg=180, width=8, height=8)
    with pytest.raises(ValueError, match="cannot tell the layout of a 100 x 64 image"):
        P.perspective(np.zeros((64, 100)), yaw_deg=0, pitch_deg=0, fov_deg=90, width=8, height=8)
    with pytest.raises(ValueError, match="depth must be float"):
        P.equirect_to_cubemap(np.zeros((8, 16), np.uint8), 4, depth=True)
    with pytest.raises(ValueError, match="face -x has shape"):
        P.cubemap_to_equirect([np.zeros((8, 8))] + [np.zeros((4, 4))] * 5, 64, 32, layout="list")


def test_direction_pixel_round_trips_hypothesis():
    hyp = pytest.importorskip("hypothesis")
    st = pytest.importorskip("hypothesis.strategies")

    @hyp.settings(max_examples=200, deadline=None)
    @hyp.given(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1), st.integers(1, 300))
    def check(x, y, z, s):
        d = np.array([x, y, z])
        hyp.assume(np.linalg.norm(d) > 1e-3)
        face, u, v = face_pixel_from_direction(d, s)
        assert -0.5 - 1e-9 <= u <= s - 0.5 + 1e-9 and -0.5 - 1e-9 <= v <= s - 0.5 + 1e-9
        a, b = 2 * (u + 0.5) / s - 1, 2 * (v + 0.5) / s - 1
        back = WORLD_FROM_FACE[face] @ [a, b, 1]
        np.testing.assert_allclose(back / np.linalg.norm(back), d / np.linalg.norm(d), atol=1e-9)
        w = 2 * s
        eu, ev = equirect_pixel_from_direction(d, w, s)
        np.testing.assert_allclose(direction_from_equirect_pixel(eu, ev, w, s), d / np.linalg.norm(d),
                                   atol=1e-9)

    check()


def test_c2e_and_perspective_match_ground_truth_renders():
    """Cube-face renders converted to equirect and to a pinhole view agree with direct renders of
    the same scene (ibr.synth.render for the view: checks yaw/pitch/roll against ibr.Camera)."""
    from ibr.base.camera import Camera
    from ibr.synth import make_scene, render, scene_cameras
    from panorama.synth import render_cubemap, render_equirect
    scene = make_scene("room")
    origin = scene_cameras("room")[0].position
    faces, zf = render_cubemap(scene, 96, origin=origin, supersample=2)
    col, rng = render_equirect(scene, 256, 128, origin=origin, supersample=2)
    eq = P.cubemap_to_equirect(faces, 256, 128, layout="list")
    assert psnr(eq[20:-20], col[20:-20]) > 28
    rng_c = P.cubemap_to_equirect(zf, 256, 128, layout="list", depth=True, interpolation="linear")
    assert np.nanmedian(np.abs(rng_c - rng) / rng) < 2e-3
    pose = np.eye(4)
    pose[:3, :3] = world_from_view(-35, 15, 8)
    pose[:3, 3] = origin
    cam = Camera.from_fov(80, 60, hfov_deg=70, world_from_cam=pose)
    truth = render(scene, cam, supersample=2)
    view = P.perspective(faces, yaw_deg=-35, pitch_deg=15, roll_deg=8, fov_deg=70, width=80, height=60)
    assert psnr(view, truth.color) > 28
    z = P.perspective(zf, yaw_deg=-35, pitch_deg=15, roll_deg=8, fov_deg=70, width=80, height=60,
                      depth=True, interpolation="linear")
    assert np.nanmedian(np.abs(z - truth.depth) / truth.depth) < 2e-3
    wrong = P.perspective(faces, yaw_deg=-35, pitch_deg=15, roll_deg=-8, fov_deg=70, width=80, height=60)
    assert psnr(wrong, truth.color) < psnr(view, truth.color) - 6  # roll sign matters


def test_rgb_sampled_as_rgba_is_the_same_as_three_channels():
    """remap samples large 8-bit RGB outputs through a fourth channel (OpenCV's SIMD path): the
    result is identical, channel for channel, to sampling each channel on its own."""
    import cv2

    from panorama import maps as pmaps
    from panorama.sampling import remap

    rng = np.random.default_rng(11)
    img = rng.integers(0, 256, (64, 128, 3)).astype(np.uint8)
    smap = pmaps.cube_face_map("list", 32, 64, 128)  # 6 x 32^2 = 0.75 of the source's pixels
    assert smap.map_x.size >= 0.5 * img.shape[0] * img.shape[1]
    out = remap(img, smap)
    border = cv2.BORDER_WRAP if not smap.pad else cv2.BORDER_REPLICATE
    per_channel = np.stack([cv2.remap(np.ascontiguousarray(img[..., c]), smap.map_x, smap.map_y, cv2.INTER_LINEAR,
                                      borderMode=border) for c in range(3)], -1)
    np.testing.assert_array_equal(out, per_channel)


@pytest.mark.parametrize("channels", [1, 3, 5])
def test_sources_taller_than_cv2_remap_allows_are_sampled_in_strips(monkeypatch, channels):
    """``cv2.remap`` asserts a source of fewer than 32767 rows, and the padded cube atlas has
    6 (S + 2): faces over 5458 px crashed ``perspective`` and ``cubemap_to_equirect``. Such sources
    are sampled in strips of rows; with the limit lowered to 40 rows the strips must give exactly
    what one remap gives (bilinear and nearest, views and equirects from faces)."""
    import panorama.sampling as S

    rng = np.random.default_rng(3)
    shape = (10, 10) if channels == 1 else (10, 10, channels)
    faces = [rng.integers(0, 255, shape).astype(np.uint8) for _ in range(6)]  # atlas: 72 rows
    args = dict(layout="list", yaw_deg=37.0, pitch_deg=-64.0, fov_deg=120.0, width=48, height=40)
    expect = [P.perspective(faces, **args), P.perspective(faces, interpolation="nearest", **args),
              P.cubemap_to_equirect(faces, 40, 20, layout="list")]
    monkeypatch.setattr(S, "_MAX_REMAP_ROWS", 40)
    got = [P.perspective(faces, **args), P.perspective(faces, interpolation="nearest", **args),
           P.cubemap_to_equirect(faces, 40, 20, layout="list")]
    for e, g in zip(expect, got):
        assert g.shape == e.shape and g.dtype == e.dtype
        np.testing.assert_array_equal(g, e)


def test_depth_zero_and_inf_are_no_depth():
    """0 and +inf in a depth panorama passed as depth (faces held z = 0 and inf); they are no
    depth (NaN), as in a View."""
    rng = np.full((16, 32), 2.0, np.float32)
    rng[3, 5], rng[8, 20] = 0.0, np.inf
    faces = P.equirect_to_cubemap(rng, 8, layout="list", depth=True)
    z = np.concatenate([f.ravel() for f in faces])
    assert not np.any(z == 0) and not np.any(np.isinf(z)) and np.isnan(z).any()
    view = P.perspective(rng, yaw_deg=0.0, pitch_deg=0.0, fov_deg=120.0, width=16, height=12, depth=True)
    assert not np.any(np.isinf(view)) and not np.any(view == 0)
