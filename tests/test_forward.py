"""Forward-warp baseline (seed 003 method 2): z-buffered per-pixel splat, round to nearest."""

from __future__ import annotations

import numpy as np
import pytest

from ibr.base.camera import Camera
from ibr.render.forward import forward_maps, forward_warp
from ibr.base.view import View

CAM = Camera.from_fov(40, 30, hfov_deg=60)


def reference_splat(depth, src: Camera, tgt: Camera):
    """Plain-Python splat: unproject, move, project, round half up, smaller z wins."""
    h, w = depth.shape
    zbuf = np.full(tgt.shape, np.inf)
    su = np.full(tgt.shape, np.nan)
    sv = np.full(tgt.shape, np.nan)
    u, v = src.pixel_grid()
    pts = src.unproject(np.stack([u, v], -1), depth.astype(np.float64))
    uv, z = tgt.project(pts.reshape(-1, 3))
    for i in range(h * w):
        if not (z[i] > 0) or not np.isfinite(uv[i]).all():
            continue
        iu, iv = int(np.floor(uv[i, 0] + 0.5)), int(np.floor(uv[i, 1] + 0.5))
        if 0 <= iu < tgt.width and 0 <= iv < tgt.height and z[i] < zbuf[iv, iu]:
            zbuf[iv, iu] = z[i]
            su[iv, iu], sv[iv, iu] = i % w, i // w
    return zbuf, su, sv


@pytest.mark.parametrize("seed", range(3))
def test_splat_matches_reference(seed):
    rng = np.random.default_rng(seed)
    depth = rng.uniform(1.0, 4.0, CAM.shape).astype(np.float32)
    depth[rng.random(CAM.shape) < 0.1] = np.nan
    tgt = Camera(45.0, 47.0, 21.3, 14.8, 44, 28).with_pose(CAM.translated(rng.normal(0, 0.3, 3)).world_from_cam)
    maps = forward_maps(depth, CAM, tgt, splat="nearest")
    zbuf, su, sv = reference_splat(depth, CAM, tgt)
    np.testing.assert_array_equal(maps.coverage, np.isfinite(zbuf))
    c = maps.coverage
    np.testing.assert_allclose(maps.depth[c], zbuf[c], rtol=1e-6)
    np.testing.assert_array_equal(maps.map_u[c], su[c])
    np.testing.assert_array_equal(maps.map_v[c], sv[c])


def test_rounds_to_nearest_not_down():
    """A fronto-parallel plane at z = 2 seen by a camera moved by 0.6 px worth of baseline to the
    left: every pixel moves +0.6 px, so target column u shows source column u - 1 (floor, like
    cv2.warpFrame, would give u)."""
    depth = np.full(CAM.shape, 2.0, np.float32)
    shift_px = 0.6
    tgt = CAM.translated(np.array([-shift_px * 2.0 / CAM.fx, 0, 0]))
    maps = forward_maps(depth, CAM, tgt, splat="nearest")
    np.testing.assert_array_equal(maps.map_u[:, 1:], np.broadcast_to(np.arange(39, dtype=np.float32), (30, 39)))
    assert not maps.coverage[:, 0].any()


def test_inverse_splat_samples_at_the_exact_source_position():
    """Same 0.6 px shift: the inverse variant samples the source at u - 0.6, so a linear ramp is
    reproduced exactly (up to remap's 1/32-px position quantization)."""
    depth = np.full(CAM.shape, 2.0, np.float32)
    ramp = np.broadcast_to(np.arange(40, dtype=np.float32) * 10.0, (30, 40))[..., None].repeat(3, -1)
    view = View(np.ascontiguousarray(ramp), depth, CAM)
    tgt = CAM.translated(np.array([-0.6 * 2.0 / CAM.fx, 0, 0]))
    layer = forward_warp(view, tgt, splat="inverse")
    expect = (np.arange(1, 40) - 0.6) * 10.0
    assert np.abs(layer.color[:, 1:, 0] - expect).max() <= 10.0 / 64 + 1e-4
    nearest = forward_warp(view, tgt, splat="nearest")
    assert np.abs(nearest.color[:, 1:, 0] - expect).max() > 3.9  # off by 0.4 px of the ramp


def test_nearer_pixel_wins():
    depth = np.full(CAM.shape, 4.0, np.float32)
    depth[10:20, 10:20] = 1.0  # near square: moves 4x farther than the wall
    tgt = CAM.translated(np.array([0.1, 0, 0]))
    maps = forward_maps(depth, CAM, tgt)
    # near square shifted by fx*0.1/1 = 3.46 px to the left: columns 6.5..16 hold depth 1
    assert np.all(maps.depth[12:18, 8:15] == 1.0)
    assert np.all(maps.depth[12:18, 20:30] == 4.0)


def test_identity_copies_the_source():
    rng = np.random.default_rng(4)
    color = rng.integers(0, 256, (30, 40, 3), dtype=np.uint8)
    depth = rng.uniform(1, 3, (30, 40)).astype(np.float32)
    layer = forward_warp(View(color, depth, CAM), CAM)
    assert layer.coverage.all()
    np.testing.assert_array_equal(layer.color, color.astype(np.float32))
    np.testing.assert_array_equal(layer.depth, depth)


def test_errors():
    with pytest.raises(ValueError, match="splat: expected one of"):
        forward_maps(np.ones(CAM.shape), CAM, CAM, splat="floor")
    with pytest.raises(ValueError, match=r"depth: expected shape \(30, 40\)"):
        forward_maps(np.ones((3, 4)), CAM, CAM)
    with pytest.raises(ValueError, match="needs depth"):
        forward_warp(View(np.zeros((30, 40, 3), np.uint8), None, CAM), CAM)
