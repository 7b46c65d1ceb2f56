"""Regressions from a new-user audit of the command line: each bad input ends in a one-line error
naming the argument (exit 1), nothing is written, and no option is silently ignored."""

import json
from pathlib import Path

import pytest

import cli

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "samples" / "data"


def _error_line(capsys, command):
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.startswith(f"ibr {command}: error:")]
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


@pytest.mark.parametrize("extra", [["--report", "r.json"], ["--factor", "3"], ["--no-tail"]])
def test_interpolate_pair_refuses_sequence_options(tmp_path, capsys, extra):
    """A pair used to ignore --report/--factor/--no-tail silently (exit 0, no report); --truth is a
    pair's option too now (views matched to the frames by camera)."""
    extra = [str(tmp_path / e) if e == "r.json" else e for e in extra]
    out = tmp_path / "frames"
    code = cli.main(["interpolate", str(DATA / "room_a.json"), str(DATA / "room_b.json"), "--t", "0.5",
                     "--out", str(out), *extra])
    assert code == 1
    line = _error_line(capsys, "interpolate")
    assert f"error: {extra[0]}: only used with a sequence" in line
    assert not out.exists() and not (tmp_path / "r.json").exists()


def test_interpolate_bundled_pair_refuses_report(tmp_path, capsys):
    assert cli.main(["interpolate", "--out", str(tmp_path / "o"), "--report", str(tmp_path / "r.json")]) == 1
    assert "error: --report: only used with a sequence" in _error_line(capsys, "interpolate")
    assert list(tmp_path.iterdir()) == []


def test_timewarp_poses_not_text_names_the_option(tmp_path, capsys):
    """A JPEG (not UTF-8) given as --poses used to give a bare codec error."""
    poses = tmp_path / "poses.json"
    poses.write_bytes(b"\xff\xd8\xff\xe0" + bytes(range(256)))
    out = tmp_path / "frames"
    assert cli.main(["timewarp", str(DATA / "room_a.json"), "--poses", str(poses), "-o", str(out)]) == 1
    line = _error_line(capsys, "timewarp")
    assert line.startswith(f"ibr timewarp: error: --poses: {poses} is not valid JSON")
    assert not out.exists()


def _canvas_strokes(tmp_path, doc):
    strokes = tmp_path / "strokes.json"
    strokes.write_text(json.dumps(doc))
    out = tmp_path / "drawn.png"
    code = cli.main(["canvas", str(DATA / "room_a.json"), "--strokes", str(strokes), "--center", "0", "0", "4",
                     "--normal", "0", "0", "-1", "--size", "2", "2", "-o", str(out)])
    return code, out


@pytest.mark.parametrize("points", [[[0, 0], [10, "a"]], [[0, 0], [1, 2, 3]], [[0, 0], None], "abc"])
def test_canvas_stroke_points_not_numbers(tmp_path, capsys, points):
    """A string among the points used to end in "could not convert string to float: 'a'"."""
    code, out = _canvas_strokes(tmp_path, {"strokes": [{"points": [[5, 5]]}, {"points": points}]})
    assert code == 1
    assert "error: --strokes: strokes[1]: points: expected a list of [x, y] pairs" in _error_line(capsys, "canvas")
    assert not out.exists()


def test_canvas_stroke_colour_and_background_name_their_key(tmp_path, capsys):
    code, out = _canvas_strokes(tmp_path, {"strokes": [{"points": [[0, 0], [9, 9]], "color": "#zz0000"}]})
    assert code == 1 and not out.exists()
    assert "error: --strokes: strokes[0]: color:" in _error_line(capsys, "canvas")
    code, out = _canvas_strokes(tmp_path, {"strokes": [{"points": [[0, 0], [9, 9]]}], "background": "blue"})
    assert code == 1 and not out.exists()
    assert "error: --strokes: background: color:" in _error_line(capsys, "canvas")


def test_canvas_strokes_still_draw(tmp_path, capsys):
    """The wrapped drawing path still paints: the stroke's colour is in the output."""
    import numpy as np

    from ibr.io import read_image

    code, out = _canvas_strokes(tmp_path, {"strokes": [{"points": [[0, 0], [511, 511]], "width": 12,
                                                        "color": "#00ff00"}]})
    assert code == 0, capsys.readouterr().err
    img = read_image(out)
    green = (img[..., 1] > 200) & (img[..., 0] < 60) & (img[..., 2] < 60)
    assert green.sum() > 1000


def test_samples_refuses_a_folder_inside_the_bundled_data(capsys):
    """``--out samples/data/rig`` used to write 17 view files into the package's data."""
    target = DATA / "rig"
    before = sorted(p.name for p in target.iterdir())
    assert cli.main(["samples", "--out", str(target), "--no-middlebury"]) == 1
    assert "is inside the bundled data folder" in _error_line(capsys, "samples")
    assert sorted(p.name for p in target.iterdir()) == before
    new = target / "new_sub"
    assert cli.main(["samples", "--out", str(new), "--no-middlebury"]) == 1
    capsys.readouterr()
    assert not new.exists()


@pytest.mark.parametrize("where", [DATA, DATA / "rig"])
def test_samples_sequence_refuses_the_bundled_data(capsys, where):
    """``--sequence --out samples/data`` used to write room_walk*/room_truth* into the bundled data."""
    before = sorted(p.name for p in where.iterdir())
    assert cli.main(["samples", "--sequence", "--size", "48x36", "--keys", "2", "--factor", "2",
                     "--out", str(where)]) == 1
    assert "bundled data folder" in _error_line(capsys, "samples")
    assert sorted(p.name for p in where.iterdir()) == before


def test_options_that_would_be_ignored_are_refused(tmp_path, capsys):
    """cubemap --ext for a one-image output, cubemap --width for equirect input and samples'
    sequence options without --sequence were accepted and ignored (exit 0)."""
    pano = DATA / "rig" / "capture_pano_color.png"
    assert cli.main(["cubemap", str(pano), "-o", str(tmp_path / "c.png"), "--ext", ".exr"]) == 1
    assert "error: --ext: only used for a folder of face files" in _error_line(capsys, "cubemap")
    assert cli.main(["cubemap", str(pano), "-o", str(tmp_path / "c.png"), "--width", "64"]) == 1
    assert "error: --width: only used when converting a cubemap back" in _error_line(capsys, "cubemap")
    assert cli.main(["samples", "--out", str(tmp_path / "s"), "--keys", "3"]) == 1
    assert "error: --keys: only used with --sequence" in _error_line(capsys, "samples")
    assert list(tmp_path.iterdir()) == []
    # the same options where they are used still work
    assert cli.main(["cubemap", str(pano), "-o", str(tmp_path / "faces"), "--ext", ".tif", "--face-size", "16"]) == 0
    assert sorted(p.suffix for p in (tmp_path / "faces").iterdir()) == [".tif"] * 6


def test_view_layout_is_a_usage_error_and_lists_what_read_panorama_takes(tmp_path, capsys):
    """``ibr view --layout foo`` ended as a runtime error (exit 1); argparse now refuses it
    (exit 2, naming --layout), and every listed layout is one read_panorama accepts."""
    from commands.view import PANO_LAYOUTS
    from panorama.layouts import LAYOUTS, _ALIASES

    assert set(PANO_LAYOUTS) == {"auto", "equirect"} | (set(LAYOUTS) - {"list", "dict"}) | set(_ALIASES)
    pano = DATA / "rig" / "capture_pano_color.png"
    assert cli.main(["view", str(pano), "--layout", "foo", "-o", str(tmp_path / "v.png")]) == 2
    assert "argument --layout: invalid choice: 'foo'" in capsys.readouterr().err
    assert cli.main(["view", str(pano), "--layout", "equirect", "--width", "64", "--height", "48",
                     "-o", str(tmp_path / "v.png")]) == 0
    assert (tmp_path / "v.png").is_file()


def test_an_opencv_error_is_a_one_line_message(tmp_path, capsys, monkeypatch):
    """A ``cv2.error`` escaping a command (the one-feature photo of ``stitch-photos`` raised
    OpenCV's FLANN assertion) printed a traceback; main() turns it into the usual one-line error
    with exit 1, keeping OpenCV's reason and function but not its source path."""
    import cv2
    import numpy as np

    import panorama

    def failing_stitch(*args, **kwargs):
        return cv2.resize(np.zeros((0, 0), np.uint8), (4, 4))  # a real OpenCV assertion

    monkeypatch.setattr(panorama, "stitch_photos", failing_stitch)
    photo = DATA / "clutter_a_color.png"
    out = tmp_path / "pano.png"
    assert cli.main(["stitch-photos", str(photo), str(photo), "-o", str(out)]) == 1
    line = _error_line(capsys, "stitch-photos")
    assert line == "ibr stitch-photos: error: OpenCV assertion failed: !ssize.empty() in function 'resize'"
    assert not out.exists()


def test_interpolate_pair_scores_its_truth_by_camera_and_mixes_colour_types(tmp_path, capsys):
    """A pair could not be scored ("--truth: only used with a sequence"); an 8-bit and a 16-bit
    view were refused after both meshes were built ("convert both to one dtype": no way to in the
    CLI). --truth views are matched to the frames by camera; mixed colour types become float 0-1."""
    import shutil

    import numpy as np

    import ibr
    from samples import DATA_DIR

    for name in ("clutter_b", "clutter_t050"):
        for f in DATA_DIR.glob(f"{name}*"):
            shutil.copy(f, tmp_path / f.name)
    a = ibr.load_view(DATA_DIR / "clutter_a.json")
    ibr.save_view(ibr.View(a.color.astype(np.uint16) * 257, a.depth, a.camera, "a16"), tmp_path / "a16.json")
    args = [str(tmp_path / "a16.json"), str(tmp_path / "clutter_b.json"), "--t", "0.25", "0.5", "0.6"]
    assert cli.main(["interpolate", *args, "--truth", str(tmp_path / "clutter_t050.json"), "--out",
                     str(tmp_path / "o")]) == 0
    err = capsys.readouterr().err
    assert "A's colour is uint16, B's uint8: both used as float 0-1" in err
    assert err.count("vs clutter_t050.json") == 1 and "over 1 new frame" in err and "over 1 new frames" not in err  # t = 0.5 only
    psnr = float(err.split("mean PSNR ")[1].split(" dB")[0])
    assert psnr > 35.0  # the bundled pair scores 36.6 dB at t = 0.5
    assert cli.main(["interpolate", *args[:2], "--t", "0.4", "--truth", str(tmp_path / "clutter_t050.json"),
                     "--out", str(tmp_path / "o2")]) == 1
    assert "--truth: no view of" in capsys.readouterr().err and not (tmp_path / "o2").exists()


def test_interpolate_pair_truth_with_alpha_and_a_missing_truth_folder(tmp_path, capsys):
    """An RGBA ground truth failed after rendering with "color: shape ... differs from the
    truth's" (library words); a --truth folder without views did not name --truth."""
    import shutil

    import numpy as np

    import ibr
    from samples import DATA_DIR

    t = ibr.load_view(DATA_DIR / "clutter_t050.json")
    rgba = np.concatenate([t.color, np.full(t.color.shape[:2] + (1,), 255, np.uint8)], axis=2)
    ibr.save_view(ibr.View(rgba, t.depth, t.camera, "t4"), tmp_path / "t4.json")
    pair = [str(DATA_DIR / "clutter_a.json"), str(DATA_DIR / "clutter_b.json"), "--t", "0.5"]
    assert cli.main(["interpolate", *pair, "--truth", str(tmp_path / "t4.json"), "--out", str(tmp_path / "o")]) == 0
    assert "vs t4.json" in capsys.readouterr().err
    (tmp_path / "empty").mkdir()
    assert cli.main(["interpolate", *pair, "--truth", str(tmp_path / "empty"), "--out", str(tmp_path / "o2")]) == 1
    assert "error: --truth: " in capsys.readouterr().err
    shutil.rmtree(tmp_path / "o")
