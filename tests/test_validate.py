"""Shared argument checks: each error names the argument, what was expected and what came."""

import numpy as np
import pytest

from ibr import synth
from ibr.base.validate import check_near_far, check_unit_vector


def test_unit_vector_is_normalized_and_degenerate_vectors_are_named():
    np.testing.assert_allclose(check_unit_vector("up", [0, 3, 4]), [0, 0.6, 0.8], rtol=1e-15)
    with pytest.raises(ValueError, match=r"up: expected a finite non-zero 3-vector, got \[0.0, 0.0, 0.0\]"):
        check_unit_vector("up", [0, 0, 0])
    with pytest.raises(ValueError, match="light_dir: expected a finite non-zero"):
        check_unit_vector("light_dir", [np.nan, 1, 0])
    with pytest.raises(ValueError, match=r"view_dir: expected shape \(3\), got \(2,\)"):
        check_unit_vector("view_dir", [1, 0])


def test_near_far_order_and_infinite_far():
    assert check_near_far(0.1, float("inf")) == (0.1, float("inf"))
    with pytest.raises(ValueError, match="far: expected far > near, got near=2.0, far=1.0"):
        check_near_far(2.0, 1.0)
    with pytest.raises(ValueError, match="near: expected a positive number"):
        check_near_far(0.0, 1.0)


def test_callers_report_the_zero_vector_by_its_argument_name():
    from ibr.stereo.stereo_camera import StereoCamera

    with pytest.raises(ValueError, match="view_dir: expected a finite non-zero 3-vector"):
        StereoCamera(position=(0, 0, 0), view_dir=(0, 0, 0), up=(0, -1, 0), interaxial=0.1,
                     focal_distance=3.0, vfov_deg=45.0, near=0.1, far=100.0, width=64, height=48)
    with pytest.raises(ValueError, match="light_dir: expected a finite non-zero 3-vector"):
        synth.Scene(synth.make_scene("plane").primitives, light_dir=(0, 0, 0))


def test_review_findings_numbers_poses_look_at_and_float32_depth():
    """Found by a review of ibr/base: bools and strings passed for numbers (``Camera(True, True,
    '0.5', ...)``, ``interpolate_cameras(a, a, '0.5')``); a 401-digit integer raised an
    OverflowError naming nothing; ``np.float32(inf)`` was refused where ``allow_inf``; ``look_at``
    returned NaN poses for NaN input and refused a short perpendicular ``up``; ``sanitize_depth``
    and the decoders returned inf / 0 as valid depth after the float32 cast; a last pose row 1e-5
    off passed the 1e-9 check (np.allclose's rtol); a bool depth map made a View."""
    import math

    from ibr import View
    from ibr.base import depth as D
    from ibr.base.camera import Camera, interpolate_cameras, look_at
    from ibr.base.validate import check_finite_scalar, check_number

    for bad in (True, np.bool_(True), "0.5", b"1"):
        with pytest.raises(TypeError, match="t: expected a real number"):
            check_finite_scalar("t", bad)
    cam = Camera(10.0, 10.0, 1.5, 1.5, 4, 4)
    with pytest.raises(TypeError, match="t: expected a real number"):
        interpolate_cameras(cam, cam, "0.5")
    with pytest.raises(TypeError, match="fx: expected a real number"):
        Camera(True, True, 0.5, 0.5, 2, 2)
    for kw in ({"fx": 10**400}, {"width": 10**400}):
        with pytest.raises(ValueError, match="expected a (finite number|positive integer)"):
            Camera.from_dict({**cam.to_dict(), **kw})
    assert check_number("far", np.float32(np.inf), allow_inf=True) == math.inf
    for bad in ({"eye": [np.inf, 0, 0]}, {"target": [np.nan, 0, 1]}, {"up": [np.nan, -1, 0]}):
        args = {"eye": [0, 0, 0], "target": [0, 0, 1], "up": [0, -1, 0], **bad}
        with pytest.raises(ValueError, match=f"{next(iter(bad))}: expected finite coordinates"):
            look_at(**args)
    np.testing.assert_allclose(look_at([0, 0, 0], [0, 0, 1], up=[0, -1e-13, 0]), np.eye(4), atol=1e-12)
    z, valid = D.sanitize_depth(np.array([1.0, 1e39, 1e-46, 2.0]))
    assert valid.tolist() == [True, False, False, True] and np.isnan(z[1:3]).all()
    assert np.isnan(D.z_from_disparity(np.array([1e-40]), baseline=1.0, focal_px=1.0)).all()
    pose = np.eye(4)
    pose[3, 3] = 1.000009
    with pytest.raises(ValueError, match="last row"):
        cam.with_pose(pose)
    pose = np.eye(4)
    pose[:3, :3] *= 1.0001  # (rounding to 6 decimals, ~5e-7, is accepted)
    with pytest.raises(ValueError, match="proper rotation"):
        cam.with_pose(pose)
    with pytest.raises(TypeError, match="depth: expected a float or integer depth map"):
        View(np.zeros((4, 4, 3), np.uint8), np.ones((4, 4), bool), cam)


def test_check_flag_takes_bools_only():
    from ibr.base.validate import check_flag

    assert check_flag("x", True) is True and check_flag("x", np.bool_(False)) is False
    for bad in ("no", 0, 1.0, None):
        with pytest.raises(TypeError, match="x: expected True or False"):
            check_flag("x", bad)
