"""Regressions from an audit of the public library functions on hard and bad inputs."""

from __future__ import annotations

import re

import numpy as np
import pytest

from ibr.base.camera import Camera
from ibr.stereo import pair as stereo_pair_mod
from ibr.stereo import timewarp as timewarp_mod


def _img(h=6, w=8, c=3, seed=0):
    return (np.random.default_rng(seed).random((h, w, c)) * 255).astype(np.uint8)


# ----------------------------------------------------------- stereo output formats and time-warp
@pytest.mark.parametrize("dtype", [np.float16, np.bool_, np.int64, np.int8])
@pytest.mark.parametrize("mode", ["sbs-half", "tb-half", "anaglyph", "dubois", "sbs"])
def test_pack_stereo_refuses_non_colour_dtypes(dtype, mode):
    img = _img().astype(dtype)
    # was: OpenCV "(-215:Assertion failed) func != 0 in function 'resize'" or a silent result
    with pytest.raises(TypeError, match=rf"^left: expected a colour dtype uint8, uint16, float32, float64, "
                                        rf"got {np.dtype(dtype).name}$"):
        stereo_pair_mod.pack_stereo(img, img, mode)


def test_pack_stereo_colour_dtypes_still_work():
    img = _img()
    out = stereo_pair_mod.pack_stereo(img, img, "sbs-half")
    assert out.shape == img.shape and out.dtype == np.uint8
    np.testing.assert_array_equal(stereo_pair_mod.anaglyph(img, img), img)


@pytest.mark.parametrize("dtype", [np.float16, np.bool_, np.int64])
def test_warp_rotation_refuses_non_colour_dtypes(dtype):
    cam = Camera.from_fov(8, 6, hfov_deg=90)
    # was: OpenCV "(-215:Assertion failed) ifunc != 0 in function 'remap'"
    with pytest.raises(TypeError, match=rf"^color: expected a colour dtype .*got {np.dtype(dtype).name}$"):
        timewarp_mod.warp_rotation(_img().astype(dtype), cam, cam)


def test_warp_rotation_checks_cameras_first():
    with pytest.raises(TypeError, match="^src: expected a Camera, got NoneType$"):  # was AttributeError
        timewarp_mod.warp_rotation(_img(), None, None)


def test_warp_rotation_identity_is_exact():
    cam = Camera.from_fov(8, 6, hfov_deg=90)
    img = _img()
    np.testing.assert_array_equal(timewarp_mod.warp_rotation(img, cam, cam).color, img)


# ----------------------------------------------------------- panoramas with more than 4 channels
def test_panorama_five_channels_match_per_channel_result():
    import panorama

    rng = np.random.default_rng(1)
    eq = (rng.random((32, 64, 5)) * 255).astype(np.uint8)
    # was: OpenCV "(-215:Assertion failed) func != 0 && cn <= 4 in function 'resize'"
    for layout in ("dict", "horizon", "dice"):
        five = panorama.equirect_to_cubemap(eq, 4, layout=layout)
        ref = [panorama.equirect_to_cubemap(np.ascontiguousarray(eq[..., c:c + 1]), 4, layout=layout)
               for c in range(5)]
        if layout == "dict":
            for k in five:
                np.testing.assert_array_equal(five[k], np.concatenate([r[k] for r in ref], axis=2))
        else:
            np.testing.assert_array_equal(five, np.concatenate(ref, axis=2))
    faces = panorama.equirect_to_cubemap(eq, 16, layout="list")
    back = panorama.cubemap_to_equirect(faces, 16, 8, layout="list")
    ref = np.concatenate([panorama.cubemap_to_equirect([np.ascontiguousarray(f[..., c:c + 1]) for f in faces],
                                                       16, 8, layout="list") for c in range(5)], axis=2)
    np.testing.assert_array_equal(back, ref)


# ----------------------------------------------------------- cameras and views
@pytest.mark.parametrize("bad", [float("nan"), float("inf"), "a", None, True])
def test_camera_size_refuses_non_numbers_naming_the_argument(bad):
    # was: "cannot convert float NaN to integer", OverflowError, "invalid literal for int()"
    with pytest.raises(ValueError, match="^" + re.escape(f"width: expected a positive integer, got {bad!r}") + "$"):
        Camera(100, 100, 1, 1, bad, 4)
    with pytest.raises(ValueError, match=r"^height: expected a positive integer"):
        Camera(100, 100, 1, 1, 4, bad)


@pytest.mark.parametrize("value", [1e40, 1e-50])
def test_view_refuses_float64_depth_outside_float32_range(value):
    from ibr.base.view import View

    cam = Camera(100, 100, 1.5, 1.5, 4, 4)
    depth = np.full((4, 4), 2.0)
    depth[1, 2] = value  # was: cast to float32 inf / 0, then silently NaN (no depth)
    want = f"depth: valid values must lie in [1e-06, 1e+09] scene units, got {min(value, 2.0):.6g}..{max(value, 2.0):.6g} "
    with pytest.raises(ValueError, match="^" + re.escape(want)):
        View(np.zeros((4, 4, 3), np.uint8), depth, cam)


def test_view_depth_float64_in_range_and_invalid_values():
    from ibr.base.view import View

    cam = Camera(100, 100, 1.5, 1.5, 4, 4)
    depth = np.full((4, 4), 2.5)
    depth[0, :4] = [np.nan, 0.0, -1e40, np.inf]
    v = View(np.zeros((4, 4, 3), np.uint8), depth, cam)
    assert v.depth.dtype == np.float32
    assert np.isnan(v.depth[0]).all() and (v.depth[1:] == np.float32(2.5)).all()


# ----------------------------------------------------------- canvas
@pytest.mark.parametrize("resolution", [None, (8, 8)])
@pytest.mark.parametrize("dtype", [np.int64, np.bool_, np.int16])
def test_canvas_refuses_non_colour_dtypes_with_or_without_resampling(dtype, resolution):
    import ibr.canvas as cv

    img = _img(40, 60).astype(dtype)
    # was: refused without resolution, but with a resolution resample() turned it into float32 first and the
    # canvas silently held the raw integer codes (88..154) as float colours
    with pytest.raises(ValueError, match=rf"^image: expected uint8, uint16 or float pixels, got {np.dtype(dtype).name}$"):
        cv.canvas_from_image(img, [0, 0, 3], [0, 0, -1], [1, 1], resolution=resolution)


def test_canvas_uint8_resampled_keeps_values():
    import ibr.canvas as cv

    img = np.full((40, 60, 3), 77, np.uint8)
    c = cv.canvas_from_image(img, [0, 0, 3], [0, 0, -1], [1, 1], resolution=(8, 8))
    assert c.rgba.dtype == np.uint8 and (c.rgba[..., :3] == 77).all() and (c.rgba[..., 3] == 255).all()


# ----------------------------------------------------------- warp / interpolate options
@pytest.mark.parametrize("bad", [5, [("threshold", 1.0)], "threshold=1"])
def test_warp_and_interpolate_refuse_non_dict_mesh_options(bad):
    import ibr
    from ibr.synth import make_scene, render, scene_cameras

    cams = scene_cameras("room", width=32, height=24)
    scene = make_scene("room")
    a, b = render(scene, cams[0]), render(scene, cams[-1])
    want = f"^mesh_options: expected a dict of ibr.build_mesh options, got {type(bad).__name__}$"
    with pytest.raises(TypeError, match=want):  # was "'int' object is not iterable" and the like
        ibr.warp(a, b.camera, mesh_options=bad)
    with pytest.raises(TypeError, match=want):
        ibr.interpolate(a, b, 0.5, mesh_options=bad)
    ok = ibr.warp(a, b.camera, mesh_options={"max_error_px": 0.5})
    ref = ibr.warp(a, b.camera, mesh_options=None)
    np.testing.assert_array_equal(ok.color, ref.color)


# ----------------------------------------------------------- second pass: names, ranges, layouts
def test_camera_refuses_what_a_camera_file_refuses_and_names_the_side():
    from ibr.base.validate import MAX_FOCAL_PX

    with pytest.raises(ValueError, match=r"^fx: expected at most 1e\+09 pixels, got 1e\+300$"):
        Camera(1e300, 1.0, 1.0, 1.0, 4, 4)  # a camera file caps fx at MAX_FOCAL_PX; the library did not
    with pytest.raises(ValueError, match=r"^cy: expected at most 1e\+09 pixels in magnitude"):
        Camera(10.0, 10.0, 1.0, -1e12, 4, 4)
    assert Camera(MAX_FOCAL_PX, MAX_FOCAL_PX, 0.0, 0.0, 4, 4).fx == MAX_FOCAL_PX
    with pytest.raises(ValueError, match=r"^width: expected a positive integer, got 0$"):
        Camera.from_fov(0, 10, hfov_deg=90)  # was named fx (the focal length computed from width 0)
    cam = Camera(10.0, 10.0, 1.5, 1.5, 4, 4)
    with pytest.raises(ValueError, match=r"^height: expected a positive integer, got 0$"):
        cam.resized(8, 0)
    assert cam.resized(8, 8).fx == 20.0 and cam.resized(8, 8).cx == 3.5


def test_interpolate_far_outside_the_span_names_t():
    from ibr import interpolate
    from ibr.base.camera import interpolate_cameras
    from ibr.io import load_view
    from samples import DATA_DIR

    a, b = load_view(DATA_DIR / "room_a.json"), load_view(DATA_DIR / "room_b.json")
    with pytest.raises(ValueError, match=r"^t: 1e\+300 extrapolates to an impossible camera \(fx: "):
        interpolate(a, b, 1e300)  # was "fx: expected a positive number, got 0.0"
    far = interpolate_cameras(a.camera, b.camera, 3.0)  # plain extrapolation still works
    assert far.fx == pytest.approx(a.camera.fx) and far.position == pytest.approx([0.6, 0.0, 0.0])


def test_options_are_checked_where_they_are_unused_too():
    from ibr import build_mesh, interpolate, warp
    from ibr.io import load_view
    from ibr.stereo.lens import RadialDistortion, distortion_maps, predistort
    from ibr.stereo.pair import stereo_pair
    from samples import DATA_DIR

    a, b = load_view(DATA_DIR / "room_a.json"), load_view(DATA_DIR / "room_b.json")
    for bad in (0, 1.5, True):  # the edge method does not use min_band; it accepted any value
        with pytest.raises(ValueError, match=r"^min_band: expected an integer >= 1"):
            build_mesh(a, min_band=bad)
    with pytest.raises(ValueError, match=r"^splat: expected one of 'inverse', 'nearest', got 'x'$"):
        warp(a, b.camera, splat="x")
    with pytest.raises(ValueError, match=r"^splat: "):
        interpolate(a, b, 0.5, splat="x")
    with pytest.raises(TypeError, match=r"^silhouettes: expected True or False, got 'x'$"):
        interpolate(a, b, 0.5, silhouettes="x")
    with pytest.raises(TypeError, match=r"^mesh_options: expected a dict"):
        warp(a, b.camera, method="forward", mesh_options=5)
    for method in ("mesh", "pixel"):
        with pytest.raises(TypeError, match=r"^mesh_options: expected a dict"):
            stereo_pair(a, e=0.06, f=3.0, method=method, mesh_options=5)  # was "argument after ** must be a mapping"
    lens = RadialDistortion(0.2, 0.0, 1.5)
    img = _img()
    with pytest.raises(ValueError, match=r"^method: expected one of 'newton', 'lut', 'approx', got 'x'$"):
        predistort(img, lens, method="x")  # unused without inverse=True, and accepted
    with pytest.raises(TypeError, match=r"^inverse: expected True or False, got 'x'$"):
        predistort(img, lens, inverse="x")
    with pytest.raises(TypeError, match=r"^width: expected an integer"):
        distortion_maps("8", 6, lens)
    with pytest.raises(ValueError, match=r"^width: expected a finite number, got nan$"):
        distortion_maps(np.nan, 6, lens)  # was "cannot convert float NaN to integer"


def test_canvas_sizes_and_pixel_lists_are_named():
    from ibr.canvas.pick import pick_pixels
    from ibr.canvas.resample import power_of_two_size, resample, texture_scale
    from ibr.base.validate import check_positive

    img = _img()
    with pytest.raises(ValueError, match=r"^resolution\[0\]: expected a finite number, got nan$"):
        resample(img, (np.nan, 3))
    with pytest.raises(ValueError, match=r"^resolution: expected \(W, H\)"):
        resample(img, (3, 3, 3))
    assert resample(img, (4, 3)).shape == (3, 4, 3)
    with pytest.raises(ValueError, match=r"^width: expected a finite number, got nan$"):
        power_of_two_size(np.nan, 5)
    assert power_of_two_size(728, 480) == 1024 and texture_scale(728, 480, 1024) == pytest.approx((1.4066, 2.1333), abs=1e-4)
    cam = Camera.from_fov(8, 6, hfov_deg=90)
    with pytest.raises(ValueError, match=r"^uv: expected \(N, 2\) pixel positions"):
        pick_pixels(cam, np.zeros((3, 3)), [])  # was numpy's "cannot reshape array of size 9"
    with pytest.raises(TypeError, match=r"^far: expected a real number, got 'x'$"):
        check_positive("far", "x", allow_inf=True)  # was "could not convert string to float"
    assert check_positive("far", np.inf, allow_inf=True) == np.inf


@pytest.mark.parametrize("source", ["center", "left", "right"])
def test_stereo_eyes_keep_a_single_channel_axis_like_the_source(source):
    """An (H, W, 1) source gave an (H, W, 1) kept eye beside an (H, W) new one (source="left")
    and (H, W) eyes for "center", where ``ibr.warp`` keeps the axis; now both eyes keep the
    source's layout, with the same pixels as from the (H, W) source."""
    from ibr.base.view import View
    from ibr.io import load_view
    from ibr.stereo.pair import stereo_pair
    from samples import DATA_DIR

    a = load_view(DATA_DIR / "room_a.json")
    flat = View(a.color[..., 0].copy(), a.depth, a.camera, "flat")
    axis = View(a.color[..., :1].copy(), a.depth, a.camera, "axis")
    p2 = stereo_pair(flat, e=0.06, f=3.0, source=source)
    p3 = stereo_pair(axis, e=0.06, f=3.0, source=source)
    assert p2.left.shape == p2.right.shape == a.color.shape[:2]
    assert p3.left.shape == p3.right.shape == a.color.shape[:2] + (1,)
    np.testing.assert_array_equal(p3.left[..., 0], p2.left)
    np.testing.assert_array_equal(p3.right[..., 0], p2.right)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_canvas_float_image_outside_0_1_is_refused_whatever_its_float_type(dtype):
    """A float image in 0..254 (a uint8 image converted without scaling) was kept as is in a
    float32 canvas from float32 input but clipped to white from float64 input; both are refused
    now, and the same image scaled to [0, 1] gives the same canvas from either float type."""
    from ibr.canvas.resample import canvas_from_image

    img = _img(8, 8)
    with pytest.raises(ValueError, match=r"^image: float pixels must lie in \[0, 1\] \(1\.0 = white\), got values in"):
        canvas_from_image(img.astype(dtype), [0, 0, 3], [0, 0, -1], [1, 1])
    a = canvas_from_image((img / 255.0).astype(np.float32), [0, 0, 3], [0, 0, -1], [1, 1])
    b = canvas_from_image((img / 255.0).astype(dtype), [0, 0, 3], [0, 0, -1], [1, 1])
    np.testing.assert_allclose(a.rgba, b.rgba, atol=1e-6)


def test_view_colour_big_endian_is_made_native_and_non_finite_is_refused():
    """Big-endian float/uint16 colour reached the numba kernels (a TypingError traceback); NaN or
    inf colour was accepted and the hole fill spread it over every filled pixel."""
    import ibr
    from ibr.base.view import View

    from samples import DATA_DIR

    a, b = ibr.load_view(DATA_DIR / "clutter_a.json"), ibr.load_view(DATA_DIR / "clutter_b.json")
    native = ibr.warp(View((a.color / 255).astype("<f4"), a.depth, a.camera), b.camera)
    for dtype in (">f4", ">u2"):
        colour = (a.color / 255).astype(dtype) if dtype[1] == "f" else (a.color.astype(np.uint16) * 257).astype(dtype)
        v = View(colour, a.depth, a.camera)
        assert v.color.dtype.isnative and np.array_equal(v.color, colour)
        got = ibr.warp(v, b.camera)
        if dtype == ">f4":
            np.testing.assert_array_equal(got.color, native.color)
    bad = (a.color / 255).astype(np.float32)
    bad[100:110, 100:110] = np.nan
    bad[0, 0, 0] = np.inf
    with pytest.raises(ValueError, match=r"color: 301 non-finite value\(s\)"):
        View(bad, a.depth, a.camera)


def test_iter_interpolate_is_top_level_and_checks_before_the_first_frame():
    """ibr.iter_interpolate did not exist (only ibr.render's), and its options were checked at the
    first next(); a misspelt mesh_options key reached build_mesh ("unexpected keyword argument")."""
    import inspect

    import ibr
    from ibr.base.validate import MESH_OPTIONS
    from ibr.mesh.quad_mesh import build_mesh
    from samples import DATA_DIR

    a, b = ibr.load_view(DATA_DIR / "clutter_a.json"), ibr.load_view(DATA_DIR / "clutter_b.json")
    with pytest.raises(ValueError, match="fill: expected one of"):
        ibr.iter_interpolate(a, b, [0.5], fill="bogus")  # no next(): raised at the call
    frames = list(ibr.iter_interpolate(a, b, [0.25, 0.5]))
    assert [f.t for f in frames] == [0.25, 0.5]
    assert MESH_OPTIONS == tuple(k for k in inspect.signature(build_mesh).parameters if k != "view")
    with pytest.raises(ValueError, match=r"mesh_options: unknown key 'max_eror_px' \(did you mean 'max_error_px'\?\)"):
        ibr.interpolate(a, b, 0.5, mesh_options={"max_eror_px": 0.1})


def test_messages_name_what_was_wrong():
    """All-zero depth was reported as "(all NaN)"; save_view's unknown depth_encoding blamed
    depth_params; a 179.9-degree target that squeezes the scene under a pixel was asked whether
    it looked away."""
    import ibr
    from ibr.base.view import View
    from samples import DATA_DIR

    a, b = ibr.load_view(DATA_DIR / "clutter_a.json"), ibr.load_view(DATA_DIR / "clutter_b.json")
    zero = View(a.color, np.zeros_like(a.depth), a.camera, "zero")
    with pytest.raises(ValueError, match=r"no valid pixel \(NaN, zero, negative or infinite everywhere\)"):
        ibr.warp(zero, b.camera)
    with pytest.raises(ValueError, match=r"^depth_encoding: unknown depth encoding 'zz' \(did you mean 'z'\?\)"):
        ibr.save_view(a, "unused.json", depth_encoding="zz")
    wide = Camera.from_fov(512, 384, hfov_deg=179.9, world_from_cam=b.camera.world_from_cam)
    with pytest.raises(ValueError, match="or so wide .* that they fall between its pixel centres"):
        ibr.warp(a, wide)
