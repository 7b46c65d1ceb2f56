"""Regressions from an audit of the public library functions on hard and bad inputs."""

from __future__ import annotations

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
