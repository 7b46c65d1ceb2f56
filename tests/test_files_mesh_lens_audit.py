"""Audit regressions: view-file depth encodings, mesh export, lens distortion and time-warp on
hard and bad inputs (each test failed before its fix)."""

import json
import math

import numpy as np
import pytest

from ibr.base.camera import Camera
from ibr.base.view import View
from ibr.io import load_view, save_view


def _view(z, w=10, h=8):
    cam = Camera(12.0, 11.0, 4.3, 3.6, w, h, np.eye(4))
    color = (np.arange(h * w * 3).reshape(h, w, 3) % 251).astype(np.uint8)
    return View(color, np.asarray(z, np.float32), cam, "t")


def _depth_with_hole(h=8, w=10):
    z = np.linspace(0.5, 9.0, h * w).reshape(h, w)
    z[0, 0] = np.nan
    return z


@pytest.mark.parametrize("encoding", ["fixed16", "fixed24"])
def test_fixed_without_empty_code_refuses_invalid_pixels(tmp_path, encoding):
    # far_is_empty=false leaves no code for "no depth": a NaN pixel was written as the far code
    # and read back as a valid depth at the far plane (z = 10) -- silently.
    view = _view(_depth_with_hole())
    with pytest.raises(ValueError, match="far_is_empty"):
        save_view(view, tmp_path / "v.json", depth_encoding=encoding,
                  depth_params={"near": 0.1, "far": 10.0, "far_is_empty": False})
    assert list(tmp_path.iterdir()) == []
    # without holes it still round-trips, the far plane included
    z = _depth_with_hole()
    z[0, 0] = 10.0
    save_view(_view(z), tmp_path / "v.json", depth_encoding=encoding,
              depth_params={"near": 0.1, "far": 10.0, "far_is_empty": False})
    back = load_view(tmp_path / "v.json").depth
    assert np.isfinite(back).all()
    assert back[0, 0] == pytest.approx(10.0, rel=1e-6)


def test_disparity_png_refuses_non_positive_disparity(tmp_path):
    # d = B f / z - doffs is negative for z > B f / doffs: a 16-bit PNG wrote those pixels as code 0
    # (= invalid), so the view came back with (almost) no depth and no error.
    view = _view(_depth_with_hole())
    params = {"baseline": 0.2, "focal_px": 12.0, "doffs": 3.0, "scale": 0.01}
    with pytest.raises(ValueError, match="disparit"):
        save_view(view, tmp_path / "v.json", depth_name="d.png", depth_encoding="disparity", depth_params=params)
    assert list(tmp_path.iterdir()) == []
    # positive disparities still round-trip within half a code
    params["doffs"] = -3.0
    save_view(view, tmp_path / "v.json", depth_name="d.png", depth_encoding="disparity", depth_params=params)
    z = _depth_with_hole()
    back = load_view(tmp_path / "v.json").depth
    assert np.array_equal(np.isnan(back), np.isnan(z))
    half_code = 2.4 / (2.4 / z - 0.005) - z  # depth change of half a disparity code (0.01 / 2) at z
    ok = np.isfinite(z)
    assert np.all(np.abs(back[ok] - z[ok]) <= np.abs(half_code[ok]) * 1.01 + 1e-6)


def test_chromatic_predistortion_warps_alpha_like_the_colour():
    # with three lenses (chromatic aberration) the alpha channel was copied unwarped: outside the
    # lens the colour went black but stayed opaque, unlike the single-lens path (all channels remapped).
    from ibr.stereo.lens import RadialDistortion, predistort

    rng = np.random.default_rng(3)
    img = rng.integers(0, 256, (40, 48, 4)).astype(np.uint8)
    green = RadialDistortion(0.22, 0.24, 1.5)
    lenses = (RadialDistortion(0.22 * 1.05, 0.24 * 1.05, 1.5), green, RadialDistortion(0.22 * 0.95, 0.24 * 0.95, 1.5))
    out = predistort(img, lenses)
    single = predistort(img, green)
    assert np.array_equal(out[..., 1], single[..., 1])
    assert np.array_equal(out[..., 3], single[..., 3])  # alpha follows the green (reference) lens
    assert out[0, 0, 3] == 0  # outside the lens range: transparent, as the colour is black


@pytest.mark.parametrize("doc, message", [
    ({"pose": "M"}, "unknown key 'pose' (did you mean 'poses'?)"),
    ({"poses": "M", "extra": 1}, "unknown key 'extra'"),
])
def test_timewarp_poses_file_refuses_unknown_keys(tmp_path, capsys, doc, message):
    # {"pose": [...]} said only "expected a non-empty list"; {"poses": [...], "extra": 1} ran and
    # ignored the unknown key (e.g. a misspelt "margin"/"camera" setting) without a word.
    import cli

    cam = Camera(40.0, 40.0, 11.5, 7.5, 24, 16, np.eye(4))
    view = View(np.full((16, 24, 3), 90, np.uint8), np.full((16, 24), 2.0, np.float32), cam, "v")
    save_view(view, tmp_path / "v.json")
    doc = {k: ([np.eye(4).tolist()] if v == "M" else v) for k, v in doc.items()}
    (tmp_path / "poses.json").write_text(json.dumps(doc))
    rc = cli.main(["timewarp", str(tmp_path / "v.json"), "--poses", str(tmp_path / "poses.json"),
                   "-o", str(tmp_path / "frames")])
    err = capsys.readouterr().err
    assert rc == 1
    assert message in err and "--poses" in err and "Traceback" not in err
    assert not (tmp_path / "frames").exists()


@pytest.mark.parametrize("far", [100.0, "inf"])
def test_reversed_z_refuses_depth_outside_near_far(tmp_path, far):
    # 'reversed' was missing from save_view's [near, far] check: z < near (and z > far) were written
    # as reversed values outside [0, 1] and came back as holes, silently.
    z = np.full((8, 10), 5.0, np.float32)
    z[0, 0] = 0.05
    with pytest.raises(ValueError, match="outside \\[near, far\\]"):
        save_view(_view(z), tmp_path / "v.json", depth_encoding="reversed", depth_params={"near": 0.1, "far": far})
    assert list(tmp_path.iterdir()) == []
    z[0, 0] = 0.1  # the near plane itself is fine
    save_view(_view(z), tmp_path / "v.json", depth_encoding="reversed", depth_params={"near": 0.1, "far": far})
    back = load_view(tmp_path / "v.json").depth
    assert np.allclose(back, z, rtol=1e-6)


@pytest.mark.parametrize("encoding, top", [("window", 1.0), ("reversed", 1.0), ("zprime", 2.0**24)])
def test_window_like_files_refuse_values_outside_their_range(tmp_path, encoding, top):
    # a planar-z file declared as 'window' (values 2..9) loaded as a view with no depth at all
    # (every value outside [0, 1] became NaN), without an error.
    from ibr.io import write_depth

    z = _depth_with_hole()
    save_view(_view(z), tmp_path / "v.json")
    doc = json.loads((tmp_path / "v.json").read_text())
    stored = np.where(np.isnan(z), np.nan, 0.5 * top)
    stored[3, 4] = 1.5 * top
    write_depth(tmp_path / "w.exr", stored)
    doc["depth"] = {"path": "w.exr", "encoding": encoding, "near": 0.5, "far": 10.0}
    (tmp_path / "v.json").write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="'depth.path'.*w.exr.*outside"):
        load_view(tmp_path / "v.json")
    stored[3, 4] = top  # the range's end is valid
    write_depth(tmp_path / "w.exr", stored)
    back = load_view(tmp_path / "v.json").depth
    assert np.isnan(back[0, 0]) and np.isfinite(back[1:]).all()


@pytest.mark.parametrize("key", ["color", "depth"])
def test_corrupt_pfm_in_a_view_file_names_the_key(tmp_path, key):
    # a truncated PFM said only "p.pfm: truncated PFM file ...": not which view file or key
    z = _depth_with_hole()
    save_view(_view(z), tmp_path / "v.json")
    doc = json.loads((tmp_path / "v.json").read_text())
    (tmp_path / "p.pfm").write_bytes(b"Pf\n10 8\n-1\n" + b"\0" * 100)
    if key == "color":
        doc["color"] = "p.pfm"
    else:
        doc["depth"]["path"] = "p.pfm"
    (tmp_path / "v.json").write_text(json.dumps(doc))
    with pytest.raises(ValueError, match=f"v.json: '{key}(.path)?'.*p.pfm: truncated PFM"):
        load_view(tmp_path / "v.json")


@pytest.mark.parametrize("extra, option", [(["--center", "1000", "10"], "--center"),
                                           (["--sbs", "--centers", "0", "0", "600", "0"], "--centers")])
def test_distort_lens_centre_outside_names_the_option(tmp_path, capsys, extra, option):
    # the error named the library argument 'center_px', not the option the user typed
    import cli
    from ibr.io import write_image

    write_image(tmp_path / "in.png", np.zeros((16, 24, 3), np.uint8))
    rc = cli.main(["distort", str(tmp_path / "in.png"), "--c1", "0.2", *extra, "-o", str(tmp_path / "out.png")])
    err = capsys.readouterr().err
    assert rc == 1
    assert f"error: {option}: expected a lens centre inside the image" in err
    assert not (tmp_path / "out.png").exists()


def test_distort_center_with_sbs_is_refused_not_ignored(tmp_path, capsys):
    # --sbs used each eye's image centre and dropped --center without a word
    import cli
    from ibr.io import write_image

    write_image(tmp_path / "in.png", np.zeros((16, 24, 3), np.uint8))
    rc = cli.main(["distort", str(tmp_path / "in.png"), "--c1", "0.2", "--sbs", "--center", "3", "4",
                   "-o", str(tmp_path / "out.png")])
    assert rc == 1
    assert "error: --center: not with --sbs" in capsys.readouterr().err
    assert not (tmp_path / "out.png").exists()


def test_distort_refuses_an_output_type_the_image_cannot_be_written_as_before_the_work(tmp_path, capsys):
    """A float EXR image with ``-o out.png`` was remapped first and then refused naming 'array'."""
    import cli
    from ibr.io import write_image

    src = tmp_path / "in.exr"
    write_image(src, np.full((12, 16, 3), 0.5, np.float32))
    assert cli.main(["distort", str(src), "-o", str(tmp_path / "out.png"), "--c1", "0.2"]) == 1
    err = capsys.readouterr().err
    assert "error: -o: a .png file stores" in err and "got float32" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.exr"]
    assert cli.main(["distort", str(src), "-o", str(tmp_path / "out.exr"), "--c1", "0.2"]) == 0


@pytest.mark.parametrize("encoding, cleared", [("window", 1.0), ("reversed", 0.0), ("zprime", 2.0**24)])
def test_window_like_depth_files_can_say_the_far_value_is_empty(tmp_path, encoding, cleared):
    """A cleared depth buffer (window 1, reversed 0, z' 2^24) loaded as a wall at the far plane:
    fixed16/24 had ``far_is_empty``, the float encodings had nothing. Opt-in now (the default
    keeps the far plane, as :func:`ibr.base.depth.z_from_window` documents)."""
    from ibr.io import write_depth

    cam = Camera.from_fov(4, 3, hfov_deg=60)
    z = np.full((3, 4), 2.0, np.float32)
    save_view(View(np.zeros((3, 4, 3), np.uint8), z, cam, "v"), tmp_path / "v.json", depth_name="v_depth.exr",
              depth_encoding=encoding, depth_params={"near": 0.5, "far": 10.0})
    doc = json.loads((tmp_path / "v.json").read_text())
    from ibr.io import read_depth

    stored = read_depth(tmp_path / "v_depth.exr")
    stored[0, 0] = cleared  # the pixel the renderer never drew
    write_depth(tmp_path / "v_depth.exr", stored.astype(np.float32))
    assert load_view(tmp_path / "v.json").depth[0, 0] == pytest.approx(10.0, rel=1e-4)  # default: the far plane
    doc["depth"]["far_is_empty"] = True
    (tmp_path / "v.json").write_text(json.dumps(doc))
    d = load_view(tmp_path / "v.json").depth
    assert np.isnan(d[0, 0]) and np.allclose(d[1:], 2.0, rtol=1e-5)
    # saving with far_is_empty: holes round-trip, a valid pixel at the far plane is refused
    z2 = z.copy()
    z2[0, 0] = np.nan
    save_view(View(np.zeros((3, 4, 3), np.uint8), z2, cam, "w"), tmp_path / "w.json", depth_name="w_depth.exr",
              depth_encoding=encoding, depth_params={"near": 0.5, "far": 10.0, "far_is_empty": True})
    assert np.isnan(load_view(tmp_path / "w.json").depth[0, 0])
    z2[0, 0] = 10.0
    with pytest.raises(ValueError, match=r"valid pixels lie at the far plane, whose \w+ value reads back as empty"):
        save_view(View(np.zeros((3, 4, 3), np.uint8), z2, cam, "u"), tmp_path / "u.json", depth_name="u_depth.exr",
                  depth_encoding=encoding, depth_params={"near": 0.5, "far": 10.0, "far_is_empty": True})
