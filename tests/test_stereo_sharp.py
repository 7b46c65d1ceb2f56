"""Sharp sampling for stereo method 2 (``interpolation="sharp"``): the row kernel runs each
segment's colour through the Lanczos-3 half-way sample of its two pixels (issue 11's sharp
sampling, along rows only). The kernel against its reference: tests/test_stereo.py."""

from __future__ import annotations

import numpy as np
import pytest

import cli
from ibr import synth
from ibr.render.sharp_sampling import half_way_columns, upsample_cosited
from ibr.stereo.pair import _half_way_table, map_pixels, stereo_pair
from ibr.stereo.stereo_camera import auto_stereo
from ibr.sequence.stereo import stereo_sequence
from samples import DATA_DIR


def _row_steps_reference(z):
    """(H, W) bool: pixel m and m + 1 of a row across a depth step (2 % in 1/z, or valid beside
    invalid), at m."""
    with np.errstate(divide="ignore", invalid="ignore"):
        q = 1.0 / z.astype(np.float64)
    valid = np.isfinite(q) & (q > 0)
    a, b = q[:, :-1], q[:, 1:]
    step = np.zeros(z.shape, bool)
    with np.errstate(invalid="ignore"):
        step[:, :-1] = (valid[:, :-1] != valid[:, 1:]) | (valid[:, :-1] & valid[:, 1:] & (np.abs(a - b) > 0.02 * np.maximum(a, b)))
    return step


@pytest.mark.parametrize("dtype", [np.uint8, np.uint16, np.float32])
def test_resolved_half_way_samples_are_clamped_lanczos_or_the_mean_beside_steps(dtype):
    """Away from depth steps the table is the odd columns of the 2-D co-sited upsampling
    (Lanczos-3 clamped to the two pixels); a sample whose six taps hold a step is the mean."""
    rng = np.random.default_rng(5)
    h, w = 7, 50
    hi = 1.0 if dtype == np.float32 else np.iinfo(dtype).max
    color = (rng.uniform(0, 1, (h, w, 3)) * hi).astype(dtype)
    z = np.full((h, w), 2.0, np.float32) + rng.uniform(0, 0.01, (h, w)).astype(np.float32)
    z[:, 20:26] = 1.0  # a bar in front
    z[3, 40] = np.nan
    half = _half_way_table(color, z)
    clean = upsample_cosited(color)[0::2, 1::2]  # no edges: plain clamped Lanczos
    steps = _row_steps_reference(z)
    across = np.zeros((h, w), bool)
    for i in range(w - 1):
        across[:, i] = steps[:, max(i - 2, 0):min(i + 3, w - 1)].any(1)
    mean = (color[:, :-1].astype(np.float64) + color[:, 1:]) / 2
    mean = np.floor(mean + 0.5) if dtype != np.float32 else mean
    got = half[:, :-1].astype(np.float64)
    np.testing.assert_allclose(got[~across[:, :-1]], clean[:, :-1][~across[:, :-1]].astype(np.float64), atol=1e-6 * hi)
    np.testing.assert_allclose(got[across[:, :-1]], mean[across[:, :-1]], atol=1e-6 * hi)
    assert across.sum() > 10 and (~across).sum() > 100
    np.testing.assert_array_equal(half[:, -1], color[:, -1])  # past the border: the pixel itself


def test_a_whole_pixel_shift_is_exact_with_sharp_sampling():
    """Co-sited: where every source pixel lands on a target pixel centre the eye holds the
    source's own pixels (no half-way sample is read)."""
    rng = np.random.default_rng(2)
    h, w = 8, 32
    color = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
    z = np.full((h, w), 3.0, np.float32)
    from ibr.base.camera import Camera
    from ibr.base.view import View

    view = View(color, z, Camera(40.0, 40.0, (w - 1) / 2, (h - 1) / 2, w, h))
    lay = map_pixels(view, dx=0.0, dpixel=2.0, interpolation="sharp", _color32=color)
    np.testing.assert_array_equal(lay.color[:, 2:], color[:, :-2])


@pytest.mark.parametrize("name, gain", [("room", 0.35), ("clutter", 0.1), ("grazing", 1.2)])
def test_sharp_eyes_are_closer_to_ray_traced_eyes(name, gain):
    """Against ray-traced eyes (covered pixels, 256 x 192, float colour) sharp sampling gains:
    measured room 40.77 -> 41.38, clutter 35.82 -> 36.05, grazing 48.57 -> 50.83 dB (512 x 384:
    43.17 -> 44.27, 38.72 -> 39.07, 52.48 -> 55.67)."""
    scene = synth.make_scene(name)
    cam, _ = synth.scene_cameras(name, width=256, height=192)
    view = synth.render(scene, cam, supersample=3)
    e, f = auto_stereo(view.depth)
    scores, truths = [], None
    for interp in ("linear", "sharp"):
        p = stereo_pair(view, e=e, f=f, interpolation=interp)
        truths = truths or [synth.render(scene, c, supersample=3) for c in (p.left_camera, p.right_camera)]
        s = []
        for img, holes, gt in ((p.left, p.left_holes, truths[0]), (p.right, p.right_holes, truths[1])):
            ok = ~holes & np.isfinite(gt.depth)
            s.append(10 * np.log10(1 / np.mean((img[ok] - gt.color[ok]) ** 2)))
        scores.append(np.mean(s))
    assert scores[1] > scores[0] + gain, scores


def test_bad_interpolation_is_refused_by_name_in_library_and_cli(tmp_path, capsys):
    view = synth.render(synth.make_scene("plane"), synth.scene_cameras("plane", width=32, height=24)[0])
    with pytest.raises(ValueError, match="interpolation"):
        stereo_pair(view, e=0.1, f=3.0, interpolation="cubic")
    for method in ("mesh", "splat"):
        with pytest.raises(ValueError, match="interpolation: 'sharp' needs method='pixel'"):
            stereo_pair(view, e=0.1, f=3.0, method=method, interpolation="sharp")
    with pytest.raises(ValueError, match="interpolation: 'sharp' needs method='pixel'"):
        map_pixels(view, dx=0.1, method="splat", interpolation="sharp")
    with pytest.raises(ValueError, match="interpolation: 'sharp' needs method='pixel'"):
        next(stereo_sequence([view], e=0.1, f=3.0, method="mesh", interpolation="sharp"))
    src = DATA_DIR / "clutter_a.json"
    out = tmp_path / "s.png"
    assert cli.main(["stereo", str(src), "--method", "mesh", "--interpolation", "sharp", "-o", str(out)]) == 1
    assert "interpolation: 'sharp' needs method='pixel'" in capsys.readouterr().err
    assert not out.exists()
    with pytest.raises(ValueError, match="edges"):
        half_way_columns(np.zeros((4, 5, 3), np.uint8), np.zeros((4, 5), bool), clamp=False)
    with pytest.raises(ValueError, match="image"):
        half_way_columns(np.zeros((4, 5, 3), np.int32))
    with pytest.raises(ValueError, match="edges"):
        half_way_columns(np.zeros((4, 5, 3), np.uint8), np.zeros((5, 4), bool))


def test_cli_stereo_takes_interpolation(tmp_path):
    from ibr.io import read_image

    src = DATA_DIR / "clutter_a.json"
    imgs = {}
    for interp in ("linear", "sharp"):
        out = tmp_path / f"{interp}.png"
        assert cli.main(["stereo", str(src), "--interpolation", interp, "--mode", "sbs", "-o", str(out)]) == 0
        imgs[interp] = read_image(out)
    assert imgs["linear"].shape == imgs["sharp"].shape
    diff = np.abs(imgs["linear"].astype(int) - imgs["sharp"].astype(int))
    assert 0.05 < (diff > 0).mean() < 0.95  # textures change, flat areas and holes' fill mostly not
