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
