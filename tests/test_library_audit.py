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
