"""Importing other tools' data (issue #19): a Blender-made pair (tests/data/import, rendered by the
shipped script with Debian's Blender 3.4, EEVEE) loaded through every path -- the script's own
view files (RGB depth EXR and multilayer EXR), its transforms.json, a COLMAP model and a TUM
sequence of the same pair -- warps exactly like the pair converted by hand; worked numbers per
format (docs/import.md); round trips; bad inputs named with the file and the entry."""

from __future__ import annotations

import json
import math
import re
import shutil

import numpy as np
import pytest

import cli
from ibr import Camera, View, load_view, warp
from ibr.io import read_depth, read_image, write_image
from ibr.io.importers import blender_script_path, export_nerf, import_views, read_frames
from ibr.io.importers import blender_script as bs
from ibr.io.importers.colmap import read_cameras, read_colmap_depth
from ibr.io.importers.conventions import (ours_from_gl, pose_from_world_to_camera, quaternion_from_rotation,
                                          rotation_from_quaternion)
from ibr.io.importers.tum import associate
from samples import DATA_DIR  # noqa: F401  (the package's sample data are not used here)
from pathlib import Path

DATA = Path(__file__).parent / "data" / "import"
RGB, ML = DATA / "blender_rgb", DATA / "blender_multilayer"
NAMES = ("camA_0001", "camB_0001")
# The scene's raw Blender values (tests/data/import/make_blender_scene.py): lens 35 mm, sensor
# 36 mm (fit AUTO), 64 x 48, rotation_euler (75 deg, 0, 0), locations; camB has shift_x 0.02.
RAW = {"camA_0001": ((0.15, -3.0, 1.4), 0.0), "camB_0001": ((-0.15, -3.0, 1.4), 0.02)}


def _by_hand(name: str) -> Camera:
    """The camera converted by hand from the Blender values, without the importers."""
    loc, shift = RAW[name]
    a = math.radians(75.0)
    rx = np.array([[1, 0, 0], [0, math.cos(a), -math.sin(a)], [0, math.sin(a), math.cos(a)]])
    pose = np.eye(4)
    pose[:3, :3] = rx @ np.diag([1.0, -1.0, -1.0])  # Blender camera looks down -Z, +Y up
    pose[:3, 3] = loc
    f = 35.0 / 36.0 * 64
    return Camera(f, f, 32.0 - shift * 64 - 0.5, 24.0 - 0.5, 64, 48, pose)


def _hand_pair():
    views = []
    for n in NAMES:
        color = read_image(RGB / f"{n}_color.png")
        z = read_image(RGB / f"{n}_depth.exr")[..., 0].copy()  # R = G = B = Z
        z[(z >= 65504) | ~np.isfinite(z)] = np.nan  # EEVEE's background
        views.append(View(color, z, _by_hand(n), n))
    return views


def _psnr_a_to_b(a: View, b: View) -> float:
    r = warp(a, b.camera)
    m = ~r.holes
    d = r.color[m].astype(np.float64) - b.color[m].astype(np.float64)
    return float(10 * np.log10(255.0**2 / np.mean(d * d)))


@pytest.fixture(scope="module")
def hand_psnr():
    a, b = _hand_pair()
    return _psnr_a_to_b(a, b)


def test_worked_numbers():
    """docs/import.md: camA sees the world point (0.3, 0.2, 0.5) -- the cube's centre -- at the
    pixel below, by each convention."""
    cam = load_view(RGB / "camA_0001.json").camera
    (u, v), z = (x[0] for x in cam.project(np.array([[0.3, 0.2, 0.5]])))
    hand = _by_hand("camA_0001")
    (uh, vh), _ = (x[0] for x in hand.project(np.array([[0.3, 0.2, 0.5]])))
    assert (u, v) == pytest.approx((uh, vh), abs=1e-5)
    # by hand (docs/import.md): d = P - C = (0.15, 3.2, -0.9); camera axes x = (1, 0, 0),
    # y = (0, -cos 75, -sin 75), z = (0, sin 75, -cos 75): (0.15, 0.04111, 3.32390) -> f = 35/36*64
    assert (round(u, 2), round(v, 2), round(z, 3)) == (34.31, 24.27, 3.324)
    # Blender intrinsics: 35 mm lens on a 36 mm sensor spanning 64 px; lens shift moves cx
    assert bs.intrinsics(35, 36, 24, "AUTO", 64, 48) == pytest.approx((62.2222222, 62.2222222, 31.5, 23.5))
    assert bs.intrinsics(35, 36, 24, "AUTO", 64, 48, shift_x=0.02)[2] == pytest.approx(30.22)
    assert bs.intrinsics(35, 36, 24, "VERTICAL", 64, 48)[0] == pytest.approx(35 / 24 * 48)
    # OpenGL -> ours flips y and z of the camera axes
    gl = np.eye(4)
    assert np.array_equal(ours_from_gl(gl), np.diag([1.0, -1.0, -1.0, 1.0]))
    # COLMAP's world-to-camera (q, t) -> world_from_cam: the camera centre is -R^T t
    r = rotation_from_quaternion(0.851773, 0.0165051, 0.503764, -0.142941)
    pose = pose_from_world_to_camera(r, (-0.737434, 1.02973, 3.74354))
    np.testing.assert_allclose(pose[:3, 3], -r.T @ np.array([-0.737434, 1.02973, 3.74354]))
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-5)


def test_blender_script_views_match_the_hand_conversion(hand_psnr):
    """The script's view files (RGB EXR depth, and multilayer EXR with its "channel" key) warp to
    the same PSNR as the pair converted by hand (+-0.01 dB), and the depth is planar z: the floor
    rows back-project to world z = 0 (half-float precision)."""
    assert 25 < hand_psnr < 50
    for folder in (RGB, ML):
        a, b = (load_view(folder / f"{n}.json") for n in NAMES)
        assert abs(_psnr_a_to_b(a, b) - hand_psnr) <= 0.01
        for v in (a, b):
            assert v.camera.world_from_cam == pytest.approx(_by_hand(v.name).world_from_cam, abs=1e-6)
    a = load_view(RGB / "camA_0001.json")
    vv, uu = np.mgrid[44:48, 0:64]
    z = a.depth[44:48]
    pts = np.stack([(uu - a.camera.cx) / a.camera.fx * z, (vv - a.camera.cy) / a.camera.fy * z, z, np.ones_like(z)], -1)
    world_z = (pts @ a.camera.world_from_cam.T)[..., 2]
    assert np.abs(world_z).max() < 3e-3 and np.isnan(a.depth).any()  # background -> NaN


def test_nerf_transforms_import_export_round_trip(tmp_path, hand_psnr):
    rep = import_views("nerf", RGB / "transforms.json", tmp_path / "nerf")
    assert [p.name for p in rep.written] == ["camB_0001.json", "camA_0001.json"] and rep.sequence.name == "nerf.json"
    a, b = (load_view(tmp_path / "nerf" / f"{n}.json") for n in NAMES)
    assert abs(_psnr_a_to_b(a, b) - hand_psnr) <= 0.01
    notes = export_nerf([tmp_path / "nerf" / "nerf.json"], tmp_path / "t.json")  # a manifest stands for its views
    assert notes == []
    doc = json.loads((tmp_path / "t.json").read_text())
    assert len(doc["frames"]) == 2 and doc["depth_unit_scale_factor"] == 1.0
    import_views("nerf", tmp_path / "t.json", tmp_path / "again")
    for n in NAMES:
        x, y = load_view(tmp_path / "nerf" / f"{n}.json"), load_view(tmp_path / "again" / f"{n}.json")
        assert np.array_equal(x.color, y.color) and np.array_equal(x.depth, y.depth, equal_nan=True)
        assert (x.camera.fx, x.camera.fy, x.camera.cx, x.camera.cy) == (y.camera.fx, y.camera.fy, y.camera.cx, y.camera.cy)
        assert np.array_equal(x.camera.world_from_cam, y.camera.world_from_cam)


def _colmap_model(folder: Path) -> None:
    """The Blender pair as a COLMAP text model, written by hand from the raw Blender values."""
    (folder / "sparse").mkdir(parents=True)
    (folder / "images").mkdir()
    cams, imgs = ["# Camera list with one line of data per camera:"], ["# Image list with two lines of data per image:"]
    for k, n in enumerate(NAMES, 1):
        c = _by_hand(n)
        rot = c.world_from_cam[:3, :3].T  # world-to-camera
        t = [float(x) for x in -rot @ c.world_from_cam[:3, 3]]
        q = quaternion_from_rotation(rot)
        cams.append(f"{k} PINHOLE 64 48 {c.fx!r} {c.fy!r} {c.cx + 0.5!r} {c.cy + 0.5!r}")
        imgs.append(f"{k} {q[0]!r} {q[1]!r} {q[2]!r} {q[3]!r} {t[0]!r} {t[1]!r} {t[2]!r} {k} {n}.png")
        imgs.append("")  # no 2-D points
        shutil.copy(RGB / f"{n}_color.png", folder / "images" / f"{n}.png")
        shutil.copy(RGB / f"{n}_depth.exr", folder / "depth" / f"{n}.exr") if (folder / "depth").is_dir() else None
    (folder / "sparse" / "cameras.txt").write_text("\n".join(cams) + "\n")
    (folder / "sparse" / "images.txt").write_text("\n".join(imgs) + "\n")


def test_colmap_model_with_depth(tmp_path, hand_psnr):
    (tmp_path / "depth").mkdir()
    _colmap_model(tmp_path)
    rep = import_views("colmap", tmp_path / "sparse", tmp_path / "out", depth=tmp_path / "depth")
    assert len(rep.written) == 2
    a, b = (load_view(tmp_path / "out" / f"{n}.json") for n in NAMES)
    assert abs(_psnr_a_to_b(a, b) - hand_psnr) <= 0.01
    # COLMAP's dense .bin depth maps (column-major float32 after a text header)
    z = load_view(RGB / "camA_0001.json").depth
    raw = np.nan_to_num(z, nan=0.0).astype(np.float32)
    # COLMAP writes the (W, H) array in Fortran order: x fastest, i.e. the image row by row
    (tmp_path / "camA_0001.png.geometric.bin").write_bytes(b"64&48&1&" + raw.tobytes())
    np.testing.assert_array_equal(read_colmap_depth(tmp_path / "camA_0001.png.geometric.bin"), z)


def test_colmap_docs_example_and_unsupported_model(tmp_path):
    """COLMAP's own cameras.txt example: PINHOLE and SIMPLE_PINHOLE read, SIMPLE_RADIAL refused."""
    text = ("# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
            "# Number of cameras: 3\n1 SIMPLE_PINHOLE 3072 2304 2559.81 1536 1152\n"
            "2 PINHOLE 3072 2304 2560.56 2560.56 1536 1152\n")
    (tmp_path / "cameras.txt").write_text(text)
    cams = read_cameras(tmp_path / "cameras.txt")
    assert cams[1] == ("SIMPLE_PINHOLE", 3072, 2304, [2559.81, 1536.0, 1152.0])
    (tmp_path / "cameras.txt").write_text(text + "3 SIMPLE_RADIAL 3072 2304 2559.69 1536 1152 -0.0218531\n")
    with pytest.raises(ValueError, match=r"cameras.txt line 6: camera 3 has model 'SIMPLE_RADIAL', not supported"):
        read_cameras(tmp_path / "cameras.txt")


def test_opencv_model_is_undistorted(tmp_path):
    """An OPENCV camera with distortion: the imported colour equals cv2.undistort of the photo."""
    import cv2

    _colmap_model(tmp_path)
    cam_line = (tmp_path / "sparse" / "cameras.txt").read_text().splitlines()
    parts = cam_line[1].split()
    cam_line[1] = " ".join(["1", "OPENCV"] + parts[2:] + ["-0.2", "0.05", "0.001", "0.0"])
    (tmp_path / "sparse" / "cameras.txt").write_text("\n".join(cam_line) + "\n")
    import_views("colmap", tmp_path / "sparse", tmp_path / "out")
    got = load_view(tmp_path / "out" / "camA_0001.json").color
    src = read_image(tmp_path / "images" / "camA_0001.png")
    c = _by_hand("camA_0001")
    k = np.array([[c.fx, 0, c.cx], [0, c.fy, c.cy], [0, 0, 1]])
    want = cv2.undistort(src, k, np.array([-0.2, 0.05, 0.001, 0.0]))
    assert np.array_equal(got, want) and not np.array_equal(got, src)


def _tum(folder: Path) -> None:
    folder.mkdir()
    rgb, dep, gt = ["# color images"], ["# depth images"], ["# ground truth trajectory"]
    for k, n in enumerate(NAMES):
        t = 1305031102.175304 + k * 0.5
        c = _by_hand(n)
        shutil.copy(RGB / f"{n}_color.png", folder / f"rgb_{k}.png")
        z = load_view(RGB / f"{n}.json").depth
        write_image(folder / f"depth_{k}.png", np.where(np.isfinite(z), np.rint(z * 5000), 0).astype(np.uint16))
        rgb.append(f"{t:.6f} rgb_{k}.png")
        dep.append(f"{t + 0.011:.6f} depth_{k}.png")
        x, y, zq, w = quaternion_from_rotation(c.world_from_cam[:3, :3])[1:] + quaternion_from_rotation(c.world_from_cam[:3, :3])[:1]
        px, py, pz = (float(p) for p in c.position)
        gt.append(f"{t - 0.004:.4f} {px!r} {py!r} {pz!r} {x!r} {y!r} {zq!r} {w!r}")
    rgb.append(f"{1305031102.175304 + 5:.6f} rgb_0.png")  # a frame with no depth nor pose near it
    for name, lines in (("rgb.txt", rgb), ("depth.txt", dep), ("groundtruth.txt", gt)):
        (folder / name).write_text("\n".join(lines) + "\n")


def test_tum_sequence(tmp_path, hand_psnr):
    _tum(tmp_path / "tum")
    c = _by_hand("camA_0001")
    rep = import_views("tum", tmp_path / "tum", tmp_path / "out", intrinsics=(c.fx, c.fy, 31.5, 23.5))
    assert len(rep.written) == 2 and rep.sequence is not None
    assert rep.dropped == [("rgb_0.png", "no depth and pose within 0.02 s of t = 1305031107.175304")]
    a, b = (load_view(p) for p in rep.written)
    # camB's lens shift is not in TUM's single intrinsics set: warp A into B's true camera, and
    # compare with the same TUM files converted by hand (depth codes / 5000, 0 = none)
    b = View(b.color, b.depth, _by_hand("camB_0001"), b.name)
    codes = read_image(tmp_path / "tum" / "depth_0.png").astype(np.float64)
    hand_a = View(read_image(tmp_path / "tum" / "rgb_0.png"), np.where(codes > 0, codes / 5000, np.nan),
                  _by_hand("camA_0001"), "a")
    assert abs(_psnr_a_to_b(a, b) - _psnr_a_to_b(hand_a, b)) <= 0.01
    assert abs(_psnr_a_to_b(a, b) - hand_psnr) <= 0.05  # the 0.2 mm codes cost little
    assert associate([1.0, 2.0], [0.99, 1.5, 2.05], 0.02) == [0, None]


def test_bad_inputs_are_named(tmp_path, capsys):
    t = json.loads((RGB / "transforms.json").read_text())
    del t["frames"][1]["transform_matrix"]
    (tmp_path / "t.json").write_text(json.dumps(t))
    for f in RGB.glob("cam*_*.*"):
        shutil.copy(f, tmp_path)
    with pytest.raises(ValueError, match=r"transforms t.json: frames\[1\]: no 'transform_matrix'"):
        read_frames("nerf", tmp_path / "t.json")
    t = json.loads((RGB / "transforms.json").read_text())
    t["frames"][0]["transfrom_matrix"] = t["frames"][0].pop("transform_matrix")
    (tmp_path / "t.json").write_text(json.dumps(t))
    with pytest.raises(ValueError, match=r"frames\[0\]: unknown key 'transfrom_matrix' \(did you mean 'transform_matrix'\?\)"):
        read_frames("nerf", tmp_path / "t.json")
    # depth and colour of different sizes: named, and nothing written by the command
    t = json.loads((RGB / "transforms.json").read_text())
    write_image(tmp_path / "small.exr", np.ones((10, 10), np.float32))
    t["frames"][0]["depth_file_path"] = "small.exr"
    (tmp_path / "t.json").write_text(json.dumps(t))
    assert cli.main(["import", "nerf", str(tmp_path / "t.json"), "--out", str(tmp_path / "out")]) == 1
    assert "depth small.exr is 10x10 but colour camB_0001_color.png is 64x48" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()
    # channels that disagree
    bad = np.stack([np.ones((48, 64)), 2 * np.ones((48, 64)), np.ones((48, 64))], -1).astype(np.float32)
    write_image(tmp_path / "rgb.exr", bad)
    with pytest.raises(ValueError, match=r"differ at 3072 pixel\(s\) \(R vs G\)"):
        read_depth(tmp_path / "rgb.exr")
    # timestamps that do not associate
    _tum(tmp_path / "tum")
    (tmp_path / "tum" / "groundtruth.txt").write_text("# nothing near\n1.0 0 0 0 0 0 0 1\n")
    with pytest.raises(ValueError, match=r"no colour frame of .* has both a depth frame and a pose within 0.02 s"):
        read_frames("tum", tmp_path / "tum")
    assert cli.main(["import", "nerf-x", "a"]) == 2  # unknown format: usage error


def test_cli_blender_script_path_and_import(tmp_path, capsys):
    assert cli.main(["import", "blender", "--script"]) == 0
    path = capsys.readouterr().out.strip()
    assert Path(path) == blender_script_path() and Path(path).is_file()
    assert "bpy" in Path(path).read_text()
    assert cli.main(["import", "nerf", str(RGB / "transforms.json"), "--out", str(tmp_path / "v")]) == 0
    assert sorted(p.name for p in (tmp_path / "v").iterdir()) == sorted(
        [f"{n}{s}" for n in NAMES for s in (".json", "_color.png", "_depth.exr")] + ["nerf.json"])
    assert cli.main(["import", "export-nerf", *map(str, sorted((tmp_path / "v").glob("cam*.json"))),
                     "--out", str(tmp_path / "t.json")]) == 0
    doc = json.loads((tmp_path / "t.json").read_text())
    assert doc["frames"][0]["file_path"] == "v/camA_0001_color.png"


def test_other_tools_keys_are_ignored_and_misspellings_refused(tmp_path):
    """nerfstudio / instant-ngp keys we do not use are listed in the report, never refused; a key
    a letter or two from one we read is a misspelling."""
    from ibr.io.importers.common import ImportReport

    t = json.loads((RGB / "transforms.json").read_text())
    t.update({"aabb_scale": 16, "scale": 0.33, "offset": [0.5, 0.5, 0.5], "sharpness": 800.0,
              "ply_file_path": "sparse_pc.ply", "applied_transform": [[1, 0, 0, 0]]})
    for fr in t["frames"]:
        fr.update({"mask_path": "m.png", "colmap_im_id": 1})
    for f in RGB.glob("cam*_*.*"):
        shutil.copy(f, tmp_path)
    (tmp_path / "t.json").write_text(json.dumps(t))
    rep = ImportReport()
    assert len(read_frames("nerf", tmp_path / "t.json", report=rep)) == 2
    assert {"aabb_scale", "scale", "offset", "sharpness", "ply_file_path", "applied_transform", "mask_path",
            "colmap_im_id"} <= set(rep.ignored_keys)
    t["frames"][0]["fil_path"] = t["frames"][0].pop("file_path")
    (tmp_path / "t.json").write_text(json.dumps(t))
    with pytest.raises(ValueError, match=r"frames\[0\]: unknown key 'fil_path' \(did you mean 'file_path'\?\)"):
        read_frames("nerf", tmp_path / "t.json")


def test_depth_scale_and_per_frame_focal_length_of_every_format(tmp_path):
    """``depth_scale`` / ``--depth-scale`` reached only COLMAP: for nerf and tum it was accepted
    and ignored (depth 1000x off, exit 0). A frame's own ``camera_angle_x`` lost to the top
    level's ``fl_x`` (nerf: per-frame intrinsics override the top level's)."""
    write_image(tmp_path / "a.png", np.zeros((48, 64, 3), np.uint8))
    from ibr.io import write_depth

    write_depth(tmp_path / "a_depth.exr", np.full((48, 64), 2000.0, np.float32))  # millimetres
    frame = {"file_path": "a.png", "transform_matrix": np.eye(4).tolist(), "depth_file_path": "a_depth.exr"}
    (tmp_path / "t.json").write_text(json.dumps({"fl_x": 50, "w": 64, "h": 48, "frames": [frame]}))
    assert read_frames("nerf", tmp_path / "t.json", depth_scale=0.001)[0].depth_scale == 0.001
    assert cli.main(["import", "nerf", str(tmp_path / "t.json"), "--out", str(tmp_path / "out"),
                     "--depth-scale", "0.001"]) == 0
    (view,) = [load_view(p) for p in sorted((tmp_path / "out").glob("*.json"))]
    np.testing.assert_allclose(view.depth, 2.0, rtol=1e-6)
    _tum(tmp_path / "tum")
    k = dict(intrinsics=(50.0, 50.0, 31.5, 23.5))
    assert [f.depth_scale for f in read_frames("tum", tmp_path / "tum", **k)] == [1 / 5000] * 2
    assert [f.depth_scale for f in read_frames("tum", tmp_path / "tum", depth_scale=0.001, **k)] == [0.001] * 2
    with pytest.raises(ValueError, match="depth_scale"):
        read_frames("tum", tmp_path / "tum", depth_scale=-1.0, **k)
    own = dict(frame, camera_angle_x=math.pi / 2)
    (tmp_path / "t2.json").write_text(json.dumps({"fl_x": 100, "w": 64, "h": 48, "frames": [own, frame]}))
    f_own, f_top = read_frames("nerf", tmp_path / "t2.json")
    assert f_own.camera.fx == pytest.approx(32.0) and f_own.camera.fy == pytest.approx(32.0)
    assert f_top.camera.fx == 100.0


def test_export_nerf_never_writes_over_an_input_and_writes_whole_files(tmp_path):
    """The library call wrote ``transforms.json`` in place: with ``out`` a view file it replaced
    the view (no longer loadable). It now refuses any input (views, their images) by name, and
    writes through a temporary file renamed into place."""
    from ibr.io import save_view

    cam = Camera(10.0, 10.0, 1.5, 1.5, 4, 4)
    save_view(View(np.zeros((4, 4, 3), np.uint8), np.ones((4, 4), np.float32), cam, "a"), tmp_path / "a.json")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    for target in before:
        with pytest.raises(ValueError, match="out: .* is one of the inputs"):
            export_nerf([tmp_path / "a.json"], tmp_path / target)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
    export_nerf([tmp_path / "a.json"], tmp_path / "t.json")
    assert json.loads((tmp_path / "t.json").read_text())["frames"][0]["file_path"] == "a_color.png"
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(list(before) + ["t.json"])  # no temporary left


def test_matrix_entries_and_manifest_views_are_checked(tmp_path):
    """A ``transform_matrix`` of strings or booleans was converted by numpy and imported; a
    manifest whose ``views`` is not a list of names crashed the exporter (TypeError) or read a
    string letter by letter. Both are refused by name."""
    write_image(tmp_path / "a.png", np.zeros((4, 4, 3), np.uint8))
    for rows in ([[str(x) for x in r] for r in np.eye(4).tolist()], [[bool(x) for x in r] for r in np.eye(4)]):
        t = {"fl_x": 10, "w": 4, "h": 4, "frames": [{"file_path": "a.png", "transform_matrix": rows}]}
        (tmp_path / "t.json").write_text(json.dumps(t))
        with pytest.raises(ValueError, match=r"frames\[0\]: bad 'transform_matrix': expected rows of numbers"):
            read_frames("nerf", tmp_path / "t.json")
    for views in ([1], "abc"):
        (tmp_path / "seq.json").write_text(json.dumps({"format": "ibr-sequence", "version": 1, "views": views}))
        with pytest.raises(ValueError, match="'views' must be a non-empty list of view file names"):
            export_nerf([tmp_path / "seq.json"], tmp_path / "out.json")
    assert not (tmp_path / "out.json").exists()


def test_the_manifest_name_is_a_plain_name_and_no_frame_s(tmp_path, capsys):
    """``ibr import ... --name ../../transforms`` wrote the manifest over the input transforms.json;
    ``--name r_0`` (a frame's name) replaced that frame's view file; without --name a frame
    called like the format (``nerf``) was lost the same way. Refused before any work."""
    src = tmp_path / "src"
    shutil.copytree(RGB, src)
    before = (src / "transforms.json").read_bytes()
    names = [Path(f.color).stem.removesuffix("_color") for f in read_frames("nerf", src / "transforms.json")]
    for bad in ("../../transforms", str(src / "transforms"), names[0], ".."):
        out = tmp_path / "out"
        assert cli.main(["import", "nerf", str(src / "transforms.json"), "--out", str(out), "--name", bad]) == 1
        assert "--name: " in capsys.readouterr().err
        assert not out.exists() and (src / "transforms.json").read_bytes() == before


def test_short_keys_misspelt_are_refused_with_the_nearest(tmp_path):
    """``fl_yy`` and ``cxx`` in a transforms.json were listed as other tools' keys and ignored (the
    camera silently took fy = fx, a centred cx); a view file's ``pth`` / ``encodng`` were refused
    without naming the key meant."""
    write_image(tmp_path / "a.png", np.zeros((4, 4, 3), np.uint8))
    for key, near in (("fl_yy", "fl_y"), ("cxx", "cx")):
        t = {"fl_x": 10, "w": 4, "h": 4, key: 3, "frames": [{"file_path": "a.png", "transform_matrix": np.eye(4).tolist()}]}
        (tmp_path / "t.json").write_text(json.dumps(t))
        with pytest.raises(ValueError, match=re.escape(f"unknown key '{key}' (did you mean '{near}'?)")):
            read_frames("nerf", tmp_path / "t.json")
    t["aabb_scale"] = 16  # another tool's key: ignored
    del t["cxx"]
    (tmp_path / "t.json").write_text(json.dumps(t))
    assert read_frames("nerf", tmp_path / "t.json")[0].camera.fx == 10
    from ibr.io import save_view

    save_view(View(np.zeros((4, 4, 3), np.uint8), np.ones((4, 4), np.float32), Camera(10.0, 10.0, 1.5, 1.5, 4, 4), "v"),
              tmp_path / "v.json")
    doc = json.loads((tmp_path / "v.json").read_text())
    for key, near in (("path", "pth"), ("encoding", "encodng")):
        d = json.loads(json.dumps(doc))
        d["depth"][near] = d["depth"].pop(key, "z")
        (tmp_path / "w.json").write_text(json.dumps(d))
        with pytest.raises(ValueError, match=re.escape(f"unknown key '{near}' (did you mean '{key}'?)")):
            load_view(tmp_path / "w.json")


def test_other_tools_fx_key_is_ignored_and_a_list_encoding_named(tmp_path):
    """Regressions of the stricter key checks: another tool's ``fx`` read as a misspelt ``cx``
    (one changed letter; only an added letter counts now); a view file's ``"encoding": ["z"]``
    raised TypeError (unhashable) instead of the named error."""
    write_image(tmp_path / "a.png", np.zeros((4, 4, 3), np.uint8))
    t = {"fl_x": 10, "w": 4, "h": 4, "fx": 10, "frames": [{"file_path": "a.png", "transform_matrix": np.eye(4).tolist()}]}
    (tmp_path / "t.json").write_text(json.dumps(t))
    assert read_frames("nerf", tmp_path / "t.json")[0].camera.fx == 10
    from ibr.io import save_view

    save_view(View(np.zeros((4, 4, 3), np.uint8), np.ones((4, 4), np.float32), Camera(10.0, 10.0, 1.5, 1.5, 4, 4), "v"),
              tmp_path / "v.json")
    doc = json.loads((tmp_path / "v.json").read_text())
    doc["depth"]["encoding"] = ["z"]
    (tmp_path / "w.json").write_text(json.dumps(doc))
    with pytest.raises(ValueError, match="encoding"):
        load_view(tmp_path / "w.json")


def test_tum_missing_image_names_its_list_file(tmp_path):
    """A depth image deleted from a TUM folder was reported as "listed in tum" (the folder), not
    the list file that names it."""
    _tum(tmp_path / "tum")
    (tmp_path / "tum" / "depth_1.png").unlink()
    with pytest.raises(FileNotFoundError, match=re.escape(f"depth_1.png (listed in {tmp_path / 'tum' / 'depth.txt'}) is missing")):
        read_frames("tum", tmp_path / "tum", intrinsics=(50.0, 50.0, 31.5, 23.5))
    _tum(tmp_path / "tum2")
    (tmp_path / "tum2" / "rgb_1.png").unlink()
    with pytest.raises(FileNotFoundError, match=re.escape(f"(listed in {tmp_path / 'tum2' / 'rgb.txt'})")):
        read_frames("tum", tmp_path / "tum2", intrinsics=(50.0, 50.0, 31.5, 23.5))


def test_an_empty_frames_list_is_called_empty(tmp_path):
    """``"frames": []`` was reported as "has no 'frames' list"."""
    (tmp_path / "t.json").write_text(json.dumps({"fl_x": 10, "w": 4, "h": 4, "frames": []}))
    with pytest.raises(ValueError, match="'frames' is an empty list"):
        read_frames("nerf", tmp_path / "t.json")
    (tmp_path / "t.json").write_text(json.dumps({"fl_x": 10, "w": 4, "h": 4}))
    with pytest.raises(ValueError, match="has no 'frames' list"):
        read_frames("nerf", tmp_path / "t.json")


def _colmap_sparse0(root: Path) -> Path:
    """The pair as COLMAP writes a project: root/images, root/depth and root/sparse/0."""
    (root / "depth").mkdir(parents=True)
    _colmap_model(root)
    (root / "sparse" / "0").mkdir()
    for f in ("cameras.txt", "images.txt"):
        (root / "sparse" / f).rename(root / "sparse" / "0" / f)
    return root / "sparse" / "0"


def test_colmap_depth_folder_problems_name_depth_and_each_skipped_image(tmp_path, capsys):
    """A wrong --depth folder said only "no usable image in images.txt" (no reason, no --depth);
    one depth map missing printed "1/1 frames" without saying that one of two images was left out."""
    model = _colmap_sparse0(tmp_path / "cm")
    images = str(tmp_path / "cm" / "images")
    base = ["import", "colmap", str(model), "--images", images]
    assert cli.main(base + ["--depth", str(tmp_path / "nodir"), "--out", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err
    assert f"--depth: {tmp_path / 'nodir'} does not exist" in err and len(err.strip().splitlines()) == 1
    (tmp_path / "empty").mkdir()
    assert cli.main(base + ["--depth", str(tmp_path / "empty"), "--out", str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err
    assert f"none of the 2 image(s) of {model / 'images.txt'} has a depth map in --depth {tmp_path / 'empty'}" in err
    assert "camA_0001.png.geometric.bin" in err and "camA_0001{.exr," in err
    assert not (tmp_path / "o").exists()
    (tmp_path / "d1").mkdir()
    shutil.copy(tmp_path / "cm" / "depth" / "camA_0001.exr", tmp_path / "d1")
    assert cli.main(base + ["--depth", str(tmp_path / "d1"), "--out", str(tmp_path / "o")]) == 0
    err = capsys.readouterr().err
    assert f"1 of 2 images skipped: camB_0001.png: no depth map in --depth {tmp_path / 'd1'}" in err
    assert sorted(p.name for p in (tmp_path / "o").glob("*.json")) == ["camA_0001.json"]
    with pytest.raises(FileNotFoundError, match="depth: .* does not exist"):  # the library names its argument
        read_frames("colmap", model, images=images, depth=tmp_path / "nodir")


def test_colmap_default_image_folder_finds_the_project_layout(tmp_path, capsys):
    """The default --images was SRC/../images: sparse/images for COLMAP's project/sparse/0 layout.
    It now tries SRC/../images, then SRC/../../images, and says which it tried when none exists."""
    model = _colmap_sparse0(tmp_path / "cm")
    assert [f.color for f in read_frames("colmap", model)] == [tmp_path / "cm" / "images" / f"{n}.png" for n in NAMES]
    assert cli.main(["import", "colmap", str(model), "--out", str(tmp_path / "o")]) == 0
    capsys.readouterr()
    _colmap_model(tmp_path / "flat")  # project/sparse beside project/images
    assert read_frames("colmap", tmp_path / "flat" / "sparse")[0].color.parent == tmp_path / "flat" / "images"
    shutil.rmtree(tmp_path / "cm" / "images")
    assert cli.main(["import", "colmap", str(model), "--out", str(tmp_path / "o2")]) == 1
    err = capsys.readouterr().err
    assert (f"no image folder beside {model} (tried {tmp_path / 'cm' / 'sparse' / 'images'}, "
            f"{tmp_path / 'cm' / 'images'}); pass --images DIR") in err
    assert cli.main(["import", "colmap", str(model), "--images", str(tmp_path / "nope"), "--out", str(tmp_path / "o2")]) == 1
    assert f"--images: {tmp_path / 'nope'} does not exist" in capsys.readouterr().err
    assert not (tmp_path / "o2").exists()


def test_options_of_another_format_are_refused_by_name(tmp_path, capsys):
    """``ibr import nerf ... --intrinsics 1 2 3 4 --images foo`` was accepted and the options
    silently ignored; an option the chosen format does not use is refused, naming it."""
    src = str(RGB / "transforms.json")
    for argv, named in ((["nerf", src, "--intrinsics", "1", "2", "3", "4", "--images", "foo"],
                         "--images (colmap only), --intrinsics (tum only): not used by `ibr import nerf`"),
                        (["nerf", src, "--tolerance", "0.1"], "--tolerance (tum only)"),
                        (["tum", str(tmp_path), "--depth", "d"], "--depth (colmap only)"),
                        (["export-nerf", str(RGB / "camA_0001.json"), "--depth-scale", "2"], "--depth-scale ("),
                        (["blender", "--script", "--out", "x"], "--out (")):
        out = tmp_path / "out"
        assert cli.main(["import", *argv] + ([] if "--out" in argv else ["--out", str(out)])) == 1, argv
        assert named in capsys.readouterr().err
        assert not out.exists()
    _tum(tmp_path / "tum")  # the options a format uses still work
    assert cli.main(["import", "tum", str(tmp_path / "tum"), "--tolerance", "0.02", "--intrinsics", "50", "50",
                     "31.5", "23.5", "--out", str(tmp_path / "t")]) == 0


def test_a_one_frame_import_does_not_leave_an_earlier_manifest(tmp_path, capsys):
    """A one-frame transforms.json imported into the folder of an earlier two-frame import left
    the old nerf.json listing both views (the old camA beside the new camB): the import owns its
    manifest name, so the stale manifest is removed with the commit (staged, nothing on failure).
    A user's own JSON of that name that is no manifest is left alone."""
    t = json.loads((RGB / "transforms.json").read_text())
    for f in RGB.glob("cam*_*.*"):
        shutil.copy(f, tmp_path)
    t1 = dict(t, frames=t["frames"][:1])
    (tmp_path / "one.json").write_text(json.dumps(t1))
    out = tmp_path / "out"
    assert cli.main(["import", "nerf", str(RGB / "transforms.json"), "--out", str(out)]) == 0
    assert len(json.loads((out / "nerf.json").read_text())["views"]) == 2
    assert cli.main(["import", "nerf", str(tmp_path / "one.json"), "--out", str(out)]) == 0
    assert not (out / "nerf.json").exists()
    assert "removed 1 file(s) of an earlier run" in capsys.readouterr().err
    (out / "nerf.json").write_text('{"mine": 1}\n')  # not a manifest: the user's file
    assert cli.main(["import", "nerf", str(tmp_path / "one.json"), "--out", str(out)]) == 0
    assert (out / "nerf.json").read_text() == '{"mine": 1}\n'
    # the library writes into the folder directly: the same
    import_views("nerf", RGB / "transforms.json", tmp_path / "lib")
    import_views("nerf", tmp_path / "one.json", tmp_path / "lib")
    assert not (tmp_path / "lib" / "nerf.json").exists()
