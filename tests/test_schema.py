"""Strict schemas and limits (issue #12): view and camera files refuse unknown keys at every level
with the nearest valid name, numbers are checked for type, finiteness and range, image sizes have
ceilings, command-line ranges are checked at parse time."""

from __future__ import annotations

import argparse
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

import cli
from bad_inputs import CASES, counts, make_base
from ibr.base.validate import (CAMERA_KEYS, MAX_IMAGE_BYTES, MAX_IMAGE_PIXELS, MAX_IMAGE_SIDE, check_camera_dict,
                               check_image_size, check_keys, check_number, check_relative_path, nearest_name)
from ibr.io import DEPTH_ENCODINGS, load_camera, load_view
from ibr.io.view_files import VIEW_KEYS

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def base(tmp_path_factory):
    return make_base(tmp_path_factory.mktemp("schema_base") / "base")


def _write(folder: Path, doc) -> Path:
    p = folder / "t.json"
    p.write_text(json.dumps(doc))
    return p


# --------------------------------------------------------------------------- unknown keys, every level
def _misspell(key: str) -> str:
    return key[:-1] if len(key) > 4 else key + "s"


@pytest.mark.parametrize("key", [k for k in VIEW_KEYS if k not in ("format",)])
def test_misspelled_top_level_key_is_refused_with_its_name(base, tmp_path, key):
    doc = json.loads((base / "a.json").read_text())
    doc.setdefault(key, doc.get(key, "a"))
    doc[_misspell(key)] = doc.pop(key)
    (tmp_path / "a_color.png").write_bytes((base / "a_color.png").read_bytes())
    (tmp_path / "a_depth.exr").write_bytes((base / "a_depth.exr").read_bytes())
    with pytest.raises(ValueError, match=rf"unknown key '{_misspell(key)}' \(did you mean '{key}'\?\)"):
        load_view(_write(tmp_path, doc))


@pytest.mark.parametrize("key", CAMERA_KEYS)
def test_misspelled_camera_key_is_refused_in_view_and_camera_files(base, tmp_path, key):
    cam = json.loads((base / "cam.json").read_text())
    cam[_misspell(key)] = cam.pop(key)
    pattern = rf"unknown key '{_misspell(key)}' \(did you mean '{key}'\?\)"
    with pytest.raises(ValueError, match=pattern):
        load_camera(_write(tmp_path, cam))
    with pytest.raises(ValueError, match=pattern):
        load_camera(_write(tmp_path, {"camera": cam}))


@pytest.mark.parametrize("encoding", list(DEPTH_ENCODINGS))
def test_misspelled_depth_parameter_is_refused_for_every_encoding(base, tmp_path, encoding):
    required, optional = DEPTH_ENCODINGS[encoding]
    key = (required + optional)[0]
    doc = json.loads((base / "a.json").read_text())
    doc["depth"] = {"path": "a_depth.exr", "encoding": encoding, _misspell(key): 1.0}
    (tmp_path / "a_color.png").write_bytes((base / "a_color.png").read_bytes())
    with pytest.raises(ValueError, match=rf"unknown parameter\(s\) {_misspell(key)} \(did you mean '{key}'\?\)"):
        load_view(_write(tmp_path, doc))


def test_pose_key_of_other_tools_is_named_and_never_becomes_the_identity(base, tmp_path, capsys):
    """The issue's 19.4 dB instead of 37.3: a misspelled pose used to become the identity."""
    from ibr.io import read_image

    good = json.loads((base / "cam.json").read_text())
    for alias in ("pose", "transform_matrix", "c2w", "world_from_camera"):
        bad = {k: v for k, v in good.items() if k != "world_from_cam"}
        bad[alias] = good["world_from_cam"]
        p = tmp_path / f"{alias}.json"
        p.write_text(json.dumps(bad))
        assert cli.main(["warp", str(base / "a.json"), "--to", str(p), "-o", str(tmp_path / "o.png")]) == 1
        assert f"unknown key '{alias}' (did you mean 'world_from_cam'?)" in capsys.readouterr().err
        assert not (tmp_path / "o.png").exists()
    # the correct key renders the target: close to b's own colour, far from the identity pose
    assert cli.main(["warp", str(base / "a.json"), "--to", str(base / "cam.json"), "-o", str(tmp_path / "o.png")]) == 0
    out = read_image(tmp_path / "o.png").astype(float)
    b = read_image(base / "b_color.png").astype(float)
    # what the bug produced: the same camera with the identity pose
    ident = dict(good, world_from_cam=np.eye(4).tolist())
    (tmp_path / "ident.json").write_text(json.dumps(ident))
    assert cli.main(["warp", str(base / "a.json"), "--to", str(tmp_path / "ident.json"), "-o",
                     str(tmp_path / "i.png")]) == 0
    wrong = read_image(tmp_path / "i.png").astype(float)
    assert np.mean(np.abs(out - b)) < 0.8 * np.mean(np.abs(wrong - b))


def test_nearest_name():
    assert nearest_name("dpeth", VIEW_KEYS) == "depth"
    assert nearest_name("world_from_camera", CAMERA_KEYS) == "world_from_cam"
    assert nearest_name("scal", ("scale",)) == "scale"
    assert nearest_name("zzzz", CAMERA_KEYS) is None
    assert nearest_name(3, CAMERA_KEYS) is None


def test_check_keys_lists_the_allowed_keys_without_a_guess():
    with pytest.raises(ValueError, match=r"^cam: unknown key 'skew'; allowed: width, height, fx, fy, cx, cy, world_from_cam$"):
        check_keys("cam", {"skew": 0}, CAMERA_KEYS)
    with pytest.raises(TypeError, match="cam: expected a JSON object, got list"):
        check_keys("cam", [], CAMERA_KEYS)


# --------------------------------------------------------------------------- numbers
@pytest.mark.parametrize("value,kw,exc,match", [
    (True, {}, TypeError, r"x: expected a number, got True \(bool\)"),
    ("1", {}, TypeError, r"x: expected a number, got '1'"),
    (None, {"integer": True}, TypeError, r"x: expected an integer, got None"),
    ([1], {}, TypeError, r"got \[1\]"),
    (math.nan, {}, ValueError, r"x: expected a finite number, got nan"),
    (math.inf, {}, ValueError, r"x: expected a finite number, got inf"),
    (2.5, {"integer": True}, ValueError, r"x: expected an integer, got 2.5"),
    (0, {"minimum": 0, "exclusive_minimum": True}, ValueError, r"x: expected a positive number, got 0"),
    (-1, {"minimum": 0}, ValueError, r"x: expected a number >= 0, got -1"),
    (11, {"maximum": 10}, ValueError, r"x: expected a number <= 10, got 11"),
])
def test_check_number_refuses(value, kw, exc, match):
    with pytest.raises(exc, match=match):
        check_number("x", value, **kw)


def test_check_number_accepts():
    assert check_number("x", 3.0, integer=True) == 3 and isinstance(check_number("x", 3.0, integer=True), int)
    assert check_number("x", np.float32(2.5)) == 2.5
    assert check_number("far", "inf", allow_inf=True) == math.inf
    assert check_number("far", math.inf, allow_inf=True) == math.inf


def test_camera_dict_values_and_default_pose():
    d = check_camera_dict({"width": 64.0, "height": 48, "fx": 50, "fy": 50, "cx": 31.5, "cy": 23.5})
    assert d["width"] == 64 and isinstance(d["width"], int)
    np.testing.assert_array_equal(d["world_from_cam"], np.eye(4))


# --------------------------------------------------------------------------- size ceilings
def test_image_size_ceilings():
    assert check_image_size("img", MAX_IMAGE_SIDE, 1) == (MAX_IMAGE_SIDE, 1)
    with pytest.raises(ValueError, match=rf"img: {MAX_IMAGE_SIDE + 1}x1 exceeds the ceiling of {MAX_IMAGE_SIDE} px a side"):
        check_image_size("img", MAX_IMAGE_SIDE + 1, 1)
    with pytest.raises(ValueError, match=rf"exceeds the ceiling of {MAX_IMAGE_PIXELS} pixels"):
        check_image_size("img", 16384, 16384)
    side = int(math.sqrt(MAX_IMAGE_PIXELS))  # 11585^2 px fits; 8 float64 channels do not
    with pytest.raises(ValueError, match=r"GiB exceeds the ceiling of 2 GiB per image"):
        check_image_size("img", side, side, channels=8, itemsize=8)
    assert MAX_IMAGE_BYTES == 2**31


def test_image_files_are_checked_from_their_header(tmp_path):
    from ibr.io import read_image
    import OpenImageIO as oiio

    # a 40000 x 1 PNG is tiny on disk, but over the side ceiling
    spec = oiio.ImageSpec(40000, 1, 1, oiio.UINT8)
    out = oiio.ImageOutput.create(str(tmp_path / "wide.png"))
    out.open(str(tmp_path / "wide.png"), spec)
    out.write_image(np.zeros((1, 40000, 1), np.uint8))
    out.close()
    with pytest.raises(ValueError, match=r"image .*wide.png: 40000x1 exceeds the ceiling"):
        read_image(tmp_path / "wide.png")


# --------------------------------------------------------------------------- relative paths
@pytest.mark.parametrize("name", ["../x.png", "a/../../x.png", "/etc/x", "C:\\x.png", "\\\\server\\x", "", " ",
                                  "a\x00b"])
def test_relative_paths_refused(name):
    with pytest.raises(ValueError, match="color"):
        check_relative_path("color", name)


@pytest.mark.parametrize("name", ["x.png", "sub/x.png", "./x.png", "a..b.png"])
def test_relative_paths_accepted(name):
    assert check_relative_path("color", name) == name


# --------------------------------------------------------------------------- parse-time ranges
def test_parse_time_types():
    from commands._common import frame_rate, image_side, number_in, port_number

    assert frame_rate("24") == 24.0 and port_number("0") == 0 and image_side("32768") == 32768
    for parse, text in ((frame_rate, "0"), (frame_rate, "nan"), (port_number, "65536"), (port_number, "-1"),
                        (image_side, "32769"), (image_side, "1.5"), (number_in(0, 180, lo_open=True, hi_open=True), "180")):
        with pytest.raises(argparse.ArgumentTypeError):
            parse(text)


def test_every_numeric_cli_option_has_a_checked_type():
    """No command option is a bare int or float: each goes through a range-checked parser."""
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    mine = ("samples", "interpolate", "warp", "mesh", "bench", "stereo", "distort", "timewarp", "cubemap", "view")
    for name, p in sub.choices.items():
        if name not in mine:
            continue
        for action in p._actions:
            assert action.type not in (int, float), f"ibr {name} {action.option_strings}: unchecked {action.type}"


# --------------------------------------------------------------------------- the README's counts
def test_readme_states_the_bad_input_table_counts():
    c = counts()
    text = (ROOT / "README.md").read_text()
    m = re.search(r"bad-input table: (\d+) cases", text)
    assert m, "README.md: no line about the bad-input table"
    assert int(m.group(1)) == c["total"] == len(CASES)
    assert f"{c['issue']} from issue #12" in text
