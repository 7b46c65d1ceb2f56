"""Audit of panorama.stitch and ibr.sequence on hard and bad inputs (regressions of the fixes).

Tiny views built in place (no synthetic renders) so the file runs in seconds.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from ibr import Camera, View
from ibr.sequence import load_sequence, save_sequence


def _view(seed=0, w=16, h=12, z=2.0, x=0.0):
    pose = np.eye(4)
    pose[0, 3] = x
    cam = Camera.from_fov(w, h, hfov_deg=60, world_from_cam=pose)
    rng = np.random.default_rng(seed)
    return View(rng.integers(0, 256, (h, w, 3), dtype=np.uint8), np.full((h, w), z, np.float32), cam, f"v{seed}")


@pytest.fixture()
def manifest(tmp_path):
    return save_sequence([_view(0), _view(1, x=0.01)], tmp_path / "walk.json", fps=10,
                         ground_truth={"sequence": "walk.json", "factor": 1})


def _rewrite(path, **changes):
    doc = json.loads(path.read_text())
    for k, v in changes.items():
        if v is None:
            doc.pop(k)
        else:
            doc[k] = v
    path.write_text(json.dumps(doc))
    return path


# --------------------------------------------------------------------------- sequence manifests
def test_manifest_misspelt_keys_are_refused_with_the_nearest_name(manifest):
    doc = json.loads(manifest.read_text())
    _rewrite(manifest, fps=None, fsp=10)                           # was silently ignored: fps None
    with pytest.raises(ValueError, match=r"unknown key 'fsp' \(did you mean 'fps'\?\)"):
        load_sequence(manifest)
    manifest.write_text(json.dumps(doc))
    _rewrite(manifest, ground_truth=None, groundtruth=doc["ground_truth"])   # was ignored: no scoring
    with pytest.raises(ValueError, match=r"unknown key 'groundtruth' \(did you mean 'ground_truth'\?\)"):
        load_sequence(manifest)
    manifest.write_text(json.dumps(doc))
    _rewrite(manifest, ground_truth={"sequence": "walk.json", "factr": 1})
    with pytest.raises(ValueError, match=r"'ground_truth': unknown key 'factr' \(did you mean 'factor'\?\)"):
        load_sequence(manifest)
    manifest.write_text(json.dumps(doc))
    _rewrite(manifest, views=None, view=doc["views"])
    with pytest.raises(ValueError, match=r"unknown key 'view' \(did you mean 'views'\?\)"):
        load_sequence(manifest)
    manifest.write_text(json.dumps(doc))
    assert load_sequence(manifest).fps == 10                       # the written manifest still loads


def test_manifest_infinite_fps_is_refused(manifest):
    manifest.write_text(manifest.read_text().replace('"fps": 10.0', '"fps": Infinity'))
    with pytest.raises(ValueError, match="'fps' must be a positive finite number, got inf"):
        load_sequence(manifest)


# --------------------------------------------------------------------------- ibr interpolate SEQ
def _cli(*argv):
    import cli

    return cli.main([str(a) for a in argv])


@pytest.mark.parametrize("given, expected", [(["--fps", "24"], 24.0), ([], 20.0), (["--fps", "12.5"], 12.5)])
def test_interpolate_sequence_keeps_an_explicit_fps_of_24(manifest, tmp_path, given, expected):
    """An explicit --fps 24 was taken for the parser's default and replaced by fps x factor (20)."""
    import cv2

    _rewrite(manifest, ground_truth=None)
    video = tmp_path / "v.avi"
    assert _cli("interpolate", manifest, "--factor", 2, "--out", tmp_path / "f", "--video", video, *given) == 0
    assert cv2.VideoCapture(str(video)).get(cv2.CAP_PROP_FPS) == pytest.approx(expected)


def test_interpolate_report_is_strict_json_with_factor_1(manifest, tmp_path, capsys):
    """--factor 1 (keys only) wrote "median_ms": NaN and "flicker_holes_8bit": NaN (not JSON) and
    printed numpy's "Mean of empty slice" warning; the values are null now."""
    import warnings

    report = tmp_path / "r.json"
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert _cli("interpolate", manifest, "--factor", 1, "--out", tmp_path / "f", "--report", report) == 0
    text = report.read_text()
    doc = json.loads(text, parse_constant=lambda c: pytest.fail(f"report holds {c}"))
    s = doc["summary"]
    assert s["frames"] == 2 and s["median_ms"] is None and s["flicker_holes_8bit"] is None
    assert [row["key"] for row in doc["frames"]] == [True, True]
    err = capsys.readouterr().err
    assert "nan%" not in err
    # keys that moved: no static pixel to measure flicker on, said in words, not "flicker nan"
    assert "flicker not measured" in err and "nan" not in err


# --------------------------------------------------------------------------- flicker and PSNR
def test_scores_refuse_colours_without_a_white_level():
    from ibr.sequence import psnr
    from ibr.sequence.metrics import frame_change

    black, white = np.zeros((4, 4), np.int64), np.full((4, 4), 255, np.int64)
    with pytest.raises(TypeError, match="color: expected a colour dtype uint8, uint16, float16, float32, float64, "
                                        "got int64"):
        psnr(black, white)                                         # was -48.13 dB
    with pytest.raises(TypeError, match="current: expected a colour dtype .* got int64"):
        frame_change(np.zeros((4, 4), np.uint8), white, np.ones((4, 4), bool))   # was 255 "[0, 1] units"
    assert psnr(black.astype(np.uint8), white.astype(np.uint8)) == 0.0
    assert psnr(np.full((4, 4), 255, np.uint8), np.full((4, 4), 65535, np.uint16)) == float("inf")


def test_flicker_masks_and_tolerances_are_checked():
    from ibr.sequence import flicker
    from ibr.sequence.metrics import frame_change, static_mask_from_motion, static_mask_from_truth

    a, b = np.zeros((4, 4), np.float32), np.full((4, 4), 0.5, np.float32)
    with pytest.raises(TypeError, match="static: expected a boolean mask, got dtype float64"):
        frame_change(a, b, np.full((4, 4), 0.2))                   # 0.2 counted as static
    assert frame_change(a, b, np.ones((4, 4), bool)) == 0.5
    with pytest.raises(ValueError, match=r"current: shape \(4, 4, 3\) differs from previous \(4, 4, 1\)"):
        static_mask_from_truth(a, np.zeros((4, 4, 3), np.float32))   # broadcast into a wrong mask
    for tol in (-1.0, float("nan")):
        with pytest.raises(ValueError, match="tol: expected"):
            static_mask_from_truth(a, a, tol=tol)                  # marked nothing static, silently
    assert static_mask_from_truth(a, a).all()
    cam = Camera.from_fov(4, 4, hfov_deg=60)
    for max_px in (-1.0, float("nan"), 0):
        with pytest.raises(ValueError, match="max_px: expected a"):
            static_mask_from_motion(np.ones((4, 4)), cam, cam, max_px=max_px)
    with pytest.raises(TypeError, match="previous_camera: expected an ibr Camera, got NoneType"):
        static_mask_from_motion(np.ones((4, 4)), cam, None)
    assert static_mask_from_motion(np.ones((4, 4)), cam, cam).all()
    with pytest.raises(ValueError, match="frames: expected at least one frame, got none"):
        flicker([], [])                                            # was "expected -1 masks"


def test_frame_count_refuses_a_non_integer_number_of_keys():
    from ibr.sequence import frame_count

    with pytest.raises(TypeError, match="keys: expected an integer number of key frames, got 2.5"):
        frame_count(2.5, 2)                                        # was 5.0 frames
    with pytest.raises(TypeError, match="keys: expected an integer"):
        frame_count("3", 2)
    assert frame_count(np.int64(3), 2) == 6 and frame_count(2, 1, tail=False) == 2


# --------------------------------------------------------------------------- panorama.stitch
def test_stitch_names_bad_views_center_and_mesh_options():
    from panorama.stitch import equirect_camera, ods_cameras, stitch_rgbd

    v = _view(0)
    with pytest.raises(TypeError, match="views: expected a sequence of ibr Views, got NoneType"):
        stitch_rgbd(None, 16)                                     # was "'NoneType' object is not iterable"
    with pytest.raises(ValueError, match=r"center: expected a finite 3-vector, got shape \(2,\)"):
        equirect_camera(16, center=(0, 0))                        # was "cannot reshape array of size 2"
    with pytest.raises(TypeError, match="center: expected a finite 3-vector, got 'abc'"):
        ods_cameras(16, center="abc")
    with pytest.raises(TypeError, match="mesh_options: expected a dict"):
        stitch_rgbd([v], 16, mesh_options=3)                      # was "'int' object is not iterable"
    with pytest.raises(ValueError, match=r"mesh_options: unknown key 'max_eror_px' \(did you mean 'max_error_px'\?\)"):
        stitch_rgbd([v], 16, mesh_options={"max_eror_px": 1.0})
    a = stitch_rgbd([v], 16, mesh_options={"max_error_px": 0.5})
    b = stitch_rgbd([v], 16, mesh_options={"max_error_px": 0.5})
    assert np.array_equal(a.color, b.color) and not a.holes.all()


def test_pack_ods_cube_face_size_zero_is_refused():
    from panorama.stitch import OdsPair, Stitched, pack_ods

    eye = Stitched(np.zeros((8, 16, 3), np.uint8), np.ones((8, 16), np.float32), np.zeros((8, 16), bool),
                   np.zeros((8, 16), np.int16), None)
    pair = OdsPair(eye, eye)
    for bad in (0, -4, 2.5, True):
        with pytest.raises(ValueError, match="face_size: expected a positive integer"):
            pack_ods(pair, "cube", face_size=bad)                 # 0 silently became W / 4
    left, right = pack_ods(pair, "cube", face_size=3)
    assert left["+x"].shape == (3, 3, 3)
    assert pack_ods(pair, "cube")[0]["+x"].shape == (4, 4, 3)


# --------------------------------------------------------------------------- ibr stitch
def test_stitch_cli_refuses_ignored_center_and_faceless_cube(tmp_path, capsys):
    from samples import DATA_DIR

    rig = DATA_DIR / "rig"
    pano = ["--panorama", rig / "capture_pano_color.png", rig / "capture_pano_range.exr"]
    out = tmp_path / "p.png"
    assert _cli("stitch", *pano, "--stereo", "ods", "-o", out, "--width", 16, "--center", 5, 5, 5) == 1
    assert "ibr stitch: error: --center: only used with view files; a --panorama is its own capture point" \
        in capsys.readouterr().err
    assert _cli("stitch", rig / "rig_00.json", "-o", out, "--width", 2, "--layout", "cube") == 1
    assert "--width: --layout cube makes faces of width / 4 pixels; expected >= 4, got 2" in capsys.readouterr().err
    assert not list(tmp_path.iterdir())                          # nothing written


def test_save_sequence_checks_fields_before_writing_any_view(tmp_path):
    for kw, err in (({"fps": float("nan")}, "fps: expected a positive finite frame rate, got nan"),
                    ({"fps": -1}, "fps: expected a positive finite frame rate, got -1"),
                    ({"ground_truth": {"sequence": "t.json", "factr": 2}},
                     r"ground_truth: unknown key 'factr' \(did you mean 'factor'\?\)")):
        with pytest.raises(ValueError, match=err):
            save_sequence([_view(0), _view(1)], tmp_path / "w.json", **kw)
        assert not list(tmp_path.iterdir())                      # no view files left behind


def test_stitch_refuses_a_view_given_twice_and_a_target_no_view_sees():
    """A duplicate moved the default centre and doubled that view's weight (pixels changed by up
    to 117 levels); a centre far from every view gave an all-black panorama, exit 0."""
    from panorama.stitch import equirect_camera, stitch_rgbd

    a, b = _view(0), _view(1, x=0.05)
    copy = View(a.color.copy(), a.depth.copy(), a.camera, "copy")
    for views in ([a, b, a], [a, b, copy]):
        with pytest.raises(ValueError, match=r"^views\[2\] \('(v0|copy)'\): the same view as views\[0\] \('v0'\)"):
            stitch_rgbd(views, 32)
    moved = View(a.color.copy(), a.depth, Camera.from_fov(16, 12, hfov_deg=60, world_from_cam=np.eye(4)), "moved")
    moved.color[0, 0] ^= 1  # same camera, other colour: a different view
    assert stitch_rgbd([a, moved], 32).color.shape == (16, 32, 3)
    # the library reports a target no view sees in ``holes`` (test_stitch); the CLI refuses it
    assert stitch_rgbd([a, b], equirect_camera(32, center=(1e6, 0.0, 0.0))).holes.all()


def test_stitch_cli_refuses_a_panorama_no_view_sees(tmp_path, capsys):
    import cli
    from pathlib import Path

    rig = Path(__file__).resolve().parents[1] / "samples" / "data" / "rig"
    out = tmp_path / "p.png"
    code = cli.main(["stitch", str(rig / "rig_00.json"), "--width", "64", "--center", "1e6", "0", "0", "-o", str(out)])
    assert code == 1 and not out.exists() and list(tmp_path.iterdir()) == []
    assert "error: no view sees any pixel of the panorama; check --center" in capsys.readouterr().err
    assert cli.main(["stitch", str(rig / "rig_00.json"), str(rig / "rig_00.json"), "--width", "64", "-o", str(out)]) == 1
    assert "the same view as views[0]" in capsys.readouterr().err and not out.exists()


def test_ring_rig_and_batch_files_name_what_is_wrong(tmp_path):
    from ibr.sequence import load_jobs
    from panorama.stitch.rigs import ring_rig

    with pytest.raises(TypeError, match=r"^radius: expected a real number, got 'a'$"):
        ring_rig(4, radius="a")
    with pytest.raises(ValueError, match=r"^vfov_deg: expected 0 < fov < 180, got 200$"):
        ring_rig(4, vfov_deg=200)  # was blamed on fy
    with pytest.raises(ValueError, match=r"^pitches_deg\[1\]: expected a finite number"):
        ring_rig(4, pitches_deg=(0.0, float("nan")))  # was blamed on world_from_cam
    assert len(ring_rig(4, pitches_deg=(0.0, 30.0), vfov_deg=60)) == 8
    path = tmp_path / "jobs.json"
    path.write_text(json.dumps({"format": "ibr-batch", "version": 1, "jbos": []}))
    with pytest.raises(ValueError, match=r"unknown key 'jbos' \(did you mean 'jobs'\?\)"):
        load_jobs(path)
    path.write_text(json.dumps({"format": "ibr-batch", "version": 2, "jobs": [["warp", "a", "-o", "b.png"]]}))
    with pytest.raises(ValueError, match=r"'version' must be 1, got 2"):
        load_jobs(path)


def test_stitch_blend_option_typos_name_the_nearest_option():
    from panorama.stitch import stitch_rgbd

    with pytest.raises(TypeError, match=r"^blend_options: unknown option 'rel_tl' \(did you mean 'rel_tol'\?\)"):
        stitch_rgbd([_view(0)], 32, rel_tl=0.05)  # was Python's "unexpected keyword argument"
    assert stitch_rgbd([_view(0)], 32, rel_tol=0.05, sigma_deg=5.0).color.shape == (16, 32, 3)


@pytest.mark.parametrize("width", [0, np.int64(0), 7])
def test_stitch_int_camera_names_camera(width):
    from panorama.stitch import stitch_rgbd

    with pytest.raises(ValueError, match=r"^camera: an int is the width of a mono equirect, even and >= 2"):
        stitch_rgbd([_view(0)], width)  # was named 'width' (of equirect_camera)


def test_interpolate_sequence_without_static_holes_says_so(tmp_path, capsys):
    """A sequence whose static pixels never were holes printed "in static hole pixels nan"; the
    summary says it in words (no ground truth: static pixels from depth and camera motion)."""
    seq = save_sequence([_view(0), _view(1, x=0.001)], tmp_path / "still.json", fps=10)
    assert _cli("interpolate", seq, "--factor", 2, "--out", tmp_path / "f") == 0
    err = capsys.readouterr().err
    line = [x for x in err.splitlines() if "interpolate: flicker" in x]
    assert len(line) == 1 and "nan" not in line[0]
    assert "no static pixel was a hole" in line[0] or "in static hole pixels" in line[0]


def test_stitch_takes_a_rig_file_or_its_folder(tmp_path, capsys):
    """`ibr stitch RIG_FOLDER` stitched the folder as one camera's sequence (10 frames of 1 view,
    holes 68 %, into a folder named like the -o file) and `ibr stitch rig/rig.json` failed on
    "'format' must be 'ibr-view'": a rig file (or its folder) now stands for its views, with its
    capture point as the centre, giving the panorama of its view files bit for bit."""
    import cv2

    from panorama.stitch.rigs import read_rig
    from samples import DATA_DIR

    rig = DATA_DIR / "rig"
    views = [str(v) for v in read_rig(rig).views]
    outs = {}
    for name, args in (("views", views), ("file", [rig / "rig.json"]), ("folder", [rig])):
        outs[name] = tmp_path / f"{name}.png"
        assert _cli("stitch", *args, "-o", outs[name], "--width", 64, "--depth-out", "none") == 0
    ref = cv2.imread(str(outs["views"]))
    for name in ("file", "folder"):
        np.testing.assert_array_equal(cv2.imread(str(outs[name])), ref)
    assert _cli("stitch", rig / "rig.json", *views[:2], "-o", tmp_path / "x.png", "--width", 64) == 1
    assert "rig.json is a rig file; give it alone" in capsys.readouterr().err
    bad = tmp_path / "rig.json"
    bad.write_text(json.dumps({"format": "ibr-rig", "version": 1, "views": ["a.json"], "centre": [0, 0, 0]}))
    assert _cli("stitch", bad, "-o", tmp_path / "y.png") == 1
    assert "unknown key 'centre' (did you mean 'center'?)" in capsys.readouterr().err
    bad.write_text('{"format": "ibr-rig", "version": 1, "views": [}')  # a typo: still a rig, its error named
    assert _cli("stitch", tmp_path, "-o", tmp_path / "y.png") == 1
    assert "rig file" in (err := capsys.readouterr().err) and "not valid JSON" in err
    # a rig elsewhere, naming views outside its folder, with a centre off the cameras' centroid:
    # the centre is the rig's (as --center gives it), not the default centroid
    (tmp_path / "off").mkdir()
    import os

    off = {"format": "ibr-rig", "version": 1, "views": [os.path.relpath(v, tmp_path / "off") for v in views],
           "center": [0.05, 0.0, 0.0]}
    (tmp_path / "off" / "rig.json").write_text(json.dumps(off))
    assert _cli("stitch", tmp_path / "off", "-o", tmp_path / "off.png", "--width", 64, "--depth-out", "none") == 0
    assert _cli("stitch", *views, "--center", 0.05, 0, 0, "-o", tmp_path / "c.png", "--width", 64,
                "--depth-out", "none") == 0
    np.testing.assert_array_equal(cv2.imread(str(tmp_path / "off.png")), cv2.imread(str(tmp_path / "c.png")))
    assert not np.array_equal(cv2.imread(str(tmp_path / "off.png")), ref)


def test_stitch_refuses_options_it_would_ignore(manifest, tmp_path, capsys):
    """--ipd / --fade on a mono panorama were accepted and ignored; with rig sequences a file
    name for -o became a folder of that name."""
    from samples import DATA_DIR

    view = DATA_DIR / "rig" / "rig_00.json"
    for opt in (["--ipd", "0.05"], ["--fade", "50", "70"]):
        assert _cli("stitch", view, "-o", tmp_path / "m.png", "--width", 16, *opt) == 1
        assert f"{opt[0]}: only used with --stereo ods" in capsys.readouterr().err
    assert _cli("stitch", manifest, manifest, "-o", tmp_path / "f3.png", "--width", 16, "--depth-out", "none") == 1
    assert "-o: " in (err := capsys.readouterr().err) and "f3.png is named like a file, but this output is a folder" in err
    assert not (tmp_path / "f3.png").exists() and not (tmp_path / "m.png").exists()


def test_interpolate_sequence_checks_its_keys_and_truth_before_any_frame(tmp_path, capsys):
    """A manifest of one view said "keys: ..." (a library parameter), a key without depth was found
    after frame 1 ("view_b: ... has no depth"), a ground truth of another key count was scored
    against frames that do not match, and --contact-sheet was told to "use --factor"."""
    from ibr.sequence import save_sequence

    views = [_view(0), _view(1, x=0.01), _view(2, x=0.02)]
    for d in ("one", "nd", "t", "k"):
        (tmp_path / d).mkdir()
    one = save_sequence(views[:1], tmp_path / "one" / "s.json")
    assert _cli("interpolate", one, "--factor", 2, "--out", tmp_path / "o1") == 1
    assert "SEQ: " in (err := capsys.readouterr().err) and "lists 1 view(s) in its 'views'" in err
    flat = View(views[1].color, None, views[1].camera, "flat")
    nodepth = save_sequence([views[0], flat], tmp_path / "nd" / "s.json")
    assert _cli("interpolate", nodepth, "--factor", 2, "--out", tmp_path / "o2") == 1
    assert "SEQ: view 1 of" in (err := capsys.readouterr().err) and "has no depth" in err
    truth = save_sequence(views * 3, tmp_path / "t" / "truth.json")  # 9 frames: not 2 keys at factor 2
    keys = save_sequence(views[:2], tmp_path / "k" / "s.json", ground_truth={"sequence": "../t/truth.json",
                                                                              "factor": 2})
    assert _cli("interpolate", keys, "--factor", 2, "--out", tmp_path / "o3") == 1
    assert "SEQ: its ground truth" in (err := capsys.readouterr().err) and "9 frames, but 2 keys at --factor 2 make 3 or 4" in err
    assert _cli("interpolate", keys, "--factor", 2, "--out", tmp_path / "o4", "--contact-sheet", tmp_path / "c.png") == 1
    assert "--contact-sheet: not used with a sequence" in (err := capsys.readouterr().err) and "--factor" not in err
    assert not [p for p in tmp_path.iterdir() if p.name.startswith("o") and p.name != "one"]  # no frames written


def test_interpolate_pair_names_a_and_b(tmp_path, capsys):
    """The pair's source checks named the library's view_a / view_b."""
    from ibr.io import save_view

    a = save_view(_view(0), tmp_path / "a.json")
    flat = save_view(View(_view(1).color, None, _view(1).camera, "flat"), tmp_path / "flat.json")
    big = save_view(_view(2, w=20, h=15), tmp_path / "big.json")
    assert _cli("interpolate", a, flat, "--out", tmp_path / "o") == 1
    assert "error: B: " in (err := capsys.readouterr().err) and "flat.json has no depth" in err
    assert _cli("interpolate", a, big, "--out", tmp_path / "o") == 1
    assert "B: " in (err := capsys.readouterr().err) and "big.json is 20x15, A (" in err and "view_b" not in err


def test_warp_to_its_own_camera_scores_inf_twice(tmp_path, capsys):
    """An exact copy printed "PSNR over covered pixels 200.00 dB ... (whole image: inf dB)"."""
    from ibr.io import save_view

    a = save_view(_view(0), tmp_path / "a.json")
    assert _cli("warp", a, "--to", a, "-o", tmp_path / "x.png") == 0
    assert "PSNR over covered pixels inf dB vs a.json (whole image: inf dB)" in capsys.readouterr().err


def test_new_panorama_functions_refuse_bad_input_by_name(tmp_path):
    """check_rgbd_panorama, read_rig / is_rig_file and rim_samples: each bad input is a clear
    error naming the argument (or the rig file and its key)."""
    from panorama.stitch import check_rgbd_panorama, equirect_camera, is_rig_file, read_rig, rim_samples, stitch_rgbd

    color = np.zeros((8, 16, 3), np.uint8)
    rng = np.full((8, 16), 2.0, np.float32)
    for args, exc, message in (
            ((np.zeros((8, 8, 3), np.uint8), rng), ValueError, r"^color: expected an equirect image"),
            ((color, rng[:4]), ValueError, r"^range_map: expected shape \(8, 16\)"),
            ((color, rng.astype(np.int32)), TypeError, r"^range_map: expected a float range map"),
            ((color, -rng), ValueError, r"^range_map: expected positive ranges"),
            ((color, rng * np.nan), ValueError, r"^range_map: no pixel has a range")):
        with pytest.raises(exc, match=message):
            check_rgbd_panorama(*args)
    with pytest.raises(ValueError, match=r"^--panorama RANGE: expected positive"):
        check_rgbd_panorama(color, -rng, names=("--panorama COLOR", "--panorama RANGE"))
    from panorama.stitch import ods_from_panorama

    one = np.full((64, 128), np.nan, np.float32)
    one[0, 0] = 2.0  # one range, lost when the faces are resampled (ods_from_views([]) said "views")
    with pytest.raises(ValueError, match="^range_map: no cube face of the panorama keeps a range"):
        ods_from_panorama(np.zeros((64, 128, 3), np.uint8), one)

    rig = tmp_path / "rig.json"
    assert not is_rig_file(tmp_path / "missing.json") and not is_rig_file(tmp_path)
    with pytest.raises(FileNotFoundError, match="rig file .*rig.json: not found"):
        read_rig(rig)
    good = {"format": "ibr-rig", "version": 1, "views": ["a.json"]}
    for doc, message in (({**good, "version": 2}, "expected format 'ibr-rig' version 1"),
                         ({**good, "views": []}, "'views' must be a non-empty list"),
                         ({**good, "views": "a.json"}, "'views' must be a non-empty list"),
                         ({**good, "views": [""]}, "'views' must be a non-empty list"),
                         ({**good, "center": [0, 0]}, "center: expected a finite 3-vector"),
                         ({**good, "panorama": {"color": "c.png"}}, r"'panorama': missing key\(s\) range"),
                         ({"format": "ibr-rig", "views": ["a.json"]}, r"missing key\(s\) version")):
        rig.write_text(json.dumps(doc))
        assert is_rig_file(rig)
        with pytest.raises(ValueError, match=message):
            read_rig(rig)
    rig.write_text(json.dumps({**good, "center": [1, 2, 3]}))
    assert read_rig(tmp_path).center.tolist() == [1, 2, 3] and read_rig(tmp_path).views == (tmp_path / "a.json",)

    v = _view(0)
    res = stitch_rgbd([v], equirect_camera(32))
    with pytest.raises(TypeError, match="views: expected a sequence of ibr Views"):
        rim_samples(res, None)
    with pytest.raises(TypeError, match=r"views\[0\]: expected an ibr View"):
        rim_samples(res, ["a.json"])


def test_stitch_never_writes_over_the_files_a_rig_names(tmp_path, capsys):
    """The rig file's centre panorama (capture_pano_color.png / _range.exr) is an input too: -o
    and --depth-out onto it overwrote it (exit 0)."""
    import shutil

    from samples import DATA_DIR

    rig = tmp_path / "rig"
    shutil.copytree(DATA_DIR / "rig", rig)
    before = {p.name: p.read_bytes() for p in rig.iterdir()}
    assert _cli("stitch", rig, "-o", rig / "capture_pano_color.png", "--width", 32, "--depth-out", "none") == 1
    assert "is the input VIEW (rig)" in capsys.readouterr().err
    assert _cli("stitch", rig, "-o", tmp_path / "x.png", "--width", 32, "--depth-out", rig / "capture_pano_range.exr") == 1
    assert _cli("stitch", rig, "-o", tmp_path / "y.png", "--width", 32, "--depth-out", "none") == 0  # the rig is fine
    assert {p.name: p.read_bytes() for p in rig.iterdir()} == before
