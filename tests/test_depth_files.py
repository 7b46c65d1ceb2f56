"""Depth files as other tools write them (issue #19, item 1): Blender's File Output node (RGB EXR,
R = G = B = Z), Blender's multilayer EXR (``ViewLayer.Depth.Z``), 16-bit millimetre PNGs of depth
cameras, TUM RGB-D's 5000 codes per metre, float TIFF and PFM; and the view file's "channel" key."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ibr import Camera, load_view
from ibr.io import read_depth, write_image
from ibr.io.images import depth_channel_names, write_pfm

RNG = np.random.default_rng(19)
Z = RNG.uniform(0.5, 9.0, (12, 16)).astype(np.float32)


def _write_named_exr(path, planes: dict[str, np.ndarray]) -> None:
    """An EXR with the given channel names, as Blender's multilayer output names them."""
    import OpenImageIO as oiio

    names = list(planes)
    data = np.stack([planes[n] for n in names], -1).astype(np.float32)
    spec = oiio.ImageSpec(data.shape[1], data.shape[0], len(names), oiio.FLOAT)
    spec.channelnames = tuple(names)
    out = oiio.ImageOutput.create(str(path))
    assert out.open(str(path), spec) and out.write_image(data)
    out.close()


def test_blender_file_output_rgb_exr(tmp_path):
    """File Output node, EXR RGB(A): every colour channel holds Z; alpha 1."""
    rgba = np.stack([Z, Z, Z, np.ones_like(Z)], -1)
    write_image(tmp_path / "z.exr", rgba)
    np.testing.assert_array_equal(read_depth(tmp_path / "z.exr"), Z)
    bad = rgba.copy()
    bad[3, 4, 1] += 0.25
    write_image(tmp_path / "bad.exr", bad)
    with pytest.raises(ValueError, match=r"differ at 1 pixel\(s\) \(R vs G\).*name the depth channel with channel="):
        read_depth(tmp_path / "bad.exr")
    with pytest.raises(ValueError, match=r"a colour image, not a depth pass\?$"):  # no way to name one
        read_depth(tmp_path / "bad.exr", what="--panorama RANGE", name_channel="")


def test_blender_multilayer_exr_picks_the_depth_pass(tmp_path):
    path = tmp_path / "multilayer.exr"
    colour = RNG.uniform(0, 1, (12, 16, 3)).astype(np.float32)
    _write_named_exr(path, {"ViewLayer.Combined.R": colour[..., 0], "ViewLayer.Combined.G": colour[..., 1],
                            "ViewLayer.Combined.B": colour[..., 2], "ViewLayer.Combined.A": np.ones_like(Z),
                            "ViewLayer.Depth.Z": Z})
    assert "ViewLayer.Depth.Z" in depth_channel_names(path)
    np.testing.assert_array_equal(read_depth(path), Z)  # found by name
    np.testing.assert_array_equal(read_depth(path, channel="ViewLayer.Depth.Z"), Z)
    np.testing.assert_array_equal(read_depth(path, channel="Depth.Z"), Z)  # the part after the layer
    np.testing.assert_array_equal(read_depth(path, channel="ViewLayer.Combined.G"), colour[..., 1])
    with pytest.raises(ValueError, match=r"no channel 'ViewLayer.Depht.Z' \(did you mean 'ViewLayer.Depth.Z'\?\)"):
        read_depth(path, channel="ViewLayer.Depht.Z")


def test_integer_depth_of_depth_cameras_and_tum(tmp_path):
    mm = np.rint(Z * 1000).astype(np.uint16)
    mm[0, 0] = 0  # no reading
    write_image(tmp_path / "mm.png", mm)
    got = read_depth(tmp_path / "mm.png", scale=0.001)
    assert np.isnan(got[0, 0])
    np.testing.assert_allclose(got[1:], Z[1:], atol=0.0005 + 1e-6)
    tum = np.rint(Z * 5000).astype(np.uint16)  # TUM RGB-D: 5000 codes per metre
    write_image(tmp_path / "tum.png", tum)
    np.testing.assert_allclose(read_depth(tmp_path / "tum.png", scale=1 / 5000), Z, atol=0.0001 + 1e-6)


def test_float_tiff_and_pfm(tmp_path):
    write_image(tmp_path / "z.tif", Z)
    np.testing.assert_array_equal(read_depth(tmp_path / "z.tif"), Z)
    write_pfm(tmp_path / "z.pfm", Z)
    np.testing.assert_array_equal(read_depth(tmp_path / "z.pfm"), Z)


def test_view_file_channel_key(tmp_path):
    cam = Camera.from_fov(16, 12, hfov_deg=60.0)
    write_image(tmp_path / "c.png", np.zeros((12, 16, 3), np.uint8))
    colour = RNG.uniform(0, 1, (12, 16)).astype(np.float32)
    _write_named_exr(tmp_path / "ml.exr", {"ViewLayer.Combined.R": colour, "ViewLayer.Combined.G": colour + 1,
                                           "ViewLayer.Combined.B": colour + 2, "ViewLayer.Depth.Z": Z})
    doc = {"format": "ibr-view", "version": 1, "color": "c.png", "camera": cam.to_dict(),
           "depth": {"path": "ml.exr", "encoding": "z", "channel": "ViewLayer.Depth.Z"}}
    (tmp_path / "v.json").write_text(json.dumps(doc))
    np.testing.assert_array_equal(load_view(tmp_path / "v.json").depth, Z)
    doc["depth"]["channel"] = "Depth.Y"
    (tmp_path / "v.json").write_text(json.dumps(doc))
    with pytest.raises(ValueError, match=r"'depth.path'.*no channel 'Depth.Y' \(did you mean 'ViewLayer.Depth.Z'\?\)"):
        load_view(tmp_path / "v.json")
    doc["depth"]["channel"] = 3
    (tmp_path / "v.json").write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="'channel' must be a channel name"):
        load_view(tmp_path / "v.json")


def test_a_misspelt_encoding_parameter_is_matched_against_the_parameters(tmp_path):
    """'scael' in a view file's depth section was answered "did you mean 'channel'?": only the
    section's structural keys were offered at first. Parameters of the encoding are now named by
    the parameter check (scale), the structural keys still by the first ('chanel' -> channel)."""
    import shutil

    from samples import DATA_DIR

    for name in ("room_a_color.png", "room_a_depth.exr"):
        shutil.copy(DATA_DIR / name, tmp_path / name)
    doc = json.loads((DATA_DIR / "room_a.json").read_text())
    for key, near in (("scael", "scale"), ("sclae", "scale"), ("chanel", "channel")):
        bad = {**doc, "depth": {**doc["depth"], key: 1.0}}
        (tmp_path / "v.json").write_text(json.dumps(bad))
        with pytest.raises(ValueError, match=rf"{key}\b.*did you mean '{near}'"):
            load_view(tmp_path / "v.json")


def test_json_format_reads_the_format_or_none(tmp_path):
    from ibr.io.view_files import json_format

    (tmp_path / "v.json").write_text(json.dumps({"format": "ibr-view"}))
    (tmp_path / "list.json").write_text("[1, 2]")
    (tmp_path / "bad.json").write_bytes(b"\x89PNG")
    assert json_format(tmp_path / "v.json") == "ibr-view"
    assert json_format(tmp_path / "list.json") is None and json_format(tmp_path / "bad.json") is None
    assert json_format(tmp_path / "missing.json") is None and json_format(tmp_path) is None
