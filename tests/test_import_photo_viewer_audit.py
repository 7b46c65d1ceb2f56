"""Audit regressions: importers, photo stitching and the viewer's site/tour generation with bad or
awkward inputs (each test failed on the code before its fix)."""

from __future__ import annotations

import json

import numpy as np
import pytest

import cli
from ibr.io import read_image, write_image


def _nerf_folder(tmp_path, n=2):
    src = tmp_path / "src"
    (src / "images").mkdir(parents=True)
    frames = []
    for i in range(n):
        write_image(src / "images" / f"f{i}.png", (np.random.default_rng(i).random((12, 16, 3)) * 255).astype(np.uint8))
        pose = np.eye(4)
        pose[0, 3] = 0.1 * i
        frames.append({"file_path": f"images/f{i}", "transform_matrix": pose.tolist()})
    (src / "transforms.json").write_text(json.dumps({"camera_angle_x": 1.0, "frames": frames}))
    return src


def test_export_nerf_never_overwrites_a_view_listed_through_a_manifest(tmp_path, capsys):
    src = _nerf_folder(tmp_path)
    views = tmp_path / "views"
    assert cli.main(["import", "nerf", str(src / "transforms.json"), "--out", str(views)]) == 0
    before = (views / "f0.json").read_text()
    capsys.readouterr()
    rc = cli.main(["import", "export-nerf", str(views / "nerf.json"), "--out", str(views / "f0.json")])
    assert rc == 1
    assert "refusing to overwrite an input" in capsys.readouterr().err
    assert (views / "f0.json").read_text() == before


def _colmap(tmp_path, images_txt):
    src = _nerf_folder(tmp_path)
    model = tmp_path / "sparse"
    model.mkdir()
    (model / "cameras.txt").write_text("1 PINHOLE 16 12 14.6 14.6 8 6\n")
    (model / "images.txt").write_text(images_txt)
    return model, src / "images"


def test_colmap_images_without_points_lines_are_refused_not_dropped(tmp_path):
    from ibr.io.importers import read_frames

    # every image line must be followed by its POINTS2D line: without them, image 2 was read as the
    # points of image 1 and silently left out (one view written, exit 0)
    model, images = _colmap(tmp_path, "1 1 0 0 0 0 0 0 1 f0.png\n2 1 0 0 0 0.1 0 0 1 f1.png\n")
    with pytest.raises(ValueError, match=r"images.txt line 2: .*POINTS2D"):
        read_frames("colmap", model, images=images)
    # the usual layouts still read: empty points lines, and points triples
    model2, _ = _colmap(tmp_path / "b", "1 1 0 0 0 0 0 0 1 f0.png\n\n2 1 0 0 0 0.1 0 0 1 f1.png\n1.5 2.5 -1 3 4 7\n")
    frames = read_frames("colmap", model2, images=images)
    assert [f.name for f in frames] == ["f0", "f1"]
    assert frames[1].camera.world_from_cam[0, 3] == pytest.approx(-0.1)


def test_stitch_photos_exposure_reference_out_of_range_is_named(tmp_path, capsys):
    from panorama.photo import stitch_photos
    from panorama.photo.testdata import cut_photos, photo_sphere

    ps = cut_photos(photo_sphere(512), [(0, 0), (50, 0)], width=240, height=180)
    with pytest.raises(ValueError, match="exposure_reference"):
        stitch_photos(ps.images, width=512, exposure_reference=7)
    paths = []
    for k, im in enumerate(ps.images):
        write_image(tmp_path / f"p{k}.png", im)
        paths.append(str(tmp_path / f"p{k}.png"))
    rc = cli.main(["stitch-photos", *paths, "-o", str(tmp_path / "s.png"), "--keep-exposure-of", "7"])
    assert rc == 1
    assert "--keep-exposure-of" in capsys.readouterr().err
    assert not (tmp_path / "s.png").exists()


def test_stitch_photos_exr_output_from_8bit_photos(tmp_path):
    from panorama.photo.testdata import cut_photos, photo_sphere

    ps = cut_photos(photo_sphere(512), [(0, 0), (50, 0)], width=240, height=180)
    paths = []
    for k, im in enumerate(ps.images):
        write_image(tmp_path / f"p{k}.png", im)
        paths.append(str(tmp_path / f"p{k}.png"))
    assert cli.main(["stitch-photos", *paths, "-o", str(tmp_path / "s.png"), "--width", "512"]) == 0
    # -o .exr (offered by --help) failed after all the work: 'a .exr file stores float32 ... got uint8'
    assert cli.main(["stitch-photos", *paths, "-o", str(tmp_path / "s.exr"), "--width", "512",
                     "--cube", str(tmp_path / "faces")]) == 0
    png, exr = read_image(tmp_path / "s.png"), read_image(tmp_path / "s.exr")
    assert exr.dtype == np.float32
    assert np.abs(exr * 255.0 - png).max() < 0.51  # the same picture in [0, 1] units
    assert (tmp_path / "faces" / "pz.exr").is_file()


def test_tour_site_never_removes_a_scene_panorama_in_the_site_folder(tmp_path, capsys):
    import panorama
    from panorama.files import write_cubemap

    site = tmp_path / "site"
    site.mkdir()
    pano = (np.random.default_rng(0).random((64, 128, 3)) * 255).astype(np.uint8)
    write_cubemap(site, panorama.equirect_to_cubemap(pano, 32, layout="list"), layout="files", ext=".png")
    write_image(tmp_path / "pano.png", pano)
    (site / "tour.json").write_text(json.dumps({"scenes": {"a": {"panorama": "."},
                                                           "b": {"panorama": "../pano.png"}}}))
    before = {p.name: p.read_bytes() for p in site.iterdir()}
    rc = cli.main(["view", str(site / "tour.json"), "--site", str(site), "--force"])
    assert rc == 1
    assert "input" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in site.iterdir()} == before


def test_import_into_a_folder_replaces_only_its_own_files(tmp_path, capsys):
    """``*.json`` was an output pattern of ``ibr import --out``: every JSON file already in the
    folder (the user's notes, a tour) was removed as 'an earlier run's'. Now only the files this
    import writes are replaced, and a second run over the first replaces exactly those."""
    src = _nerf_folder(tmp_path)
    out = tmp_path / "o"
    out.mkdir()
    (out / "notes.json").write_text("{}")
    (out / "tour.json").write_text('{"format": "ibr-tour"}')
    (out / "f0_color.jpg").write_bytes(b"mine")
    assert cli.main(["import", "nerf", str(src / "transforms.json"), "--out", str(out)]) == 0
    assert (out / "notes.json").read_text() == "{}" and (out / "tour.json").read_text() == '{"format": "ibr-tour"}'
    assert (out / "f0_color.jpg").read_bytes() == b"mine"
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(["notes.json", "tour.json", "f0_color.jpg", "nerf.json", "f0.json", "f1.json",
                            "f0_color.png", "f1_color.png"]), names
    first = (out / "f1.json").read_text()
    assert cli.main(["import", "nerf", str(src / "transforms.json"), "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == names and (out / "f1.json").read_text() == first


def _tum_folder(folder, rgb_time="1.0", w=16, h=12):
    folder.mkdir(parents=True)
    write_image(folder / "rgb_0.png", np.zeros((h, w, 3), np.uint8))
    write_image(folder / "depth_0.png", np.full((h, w), 5000, np.uint16))
    (folder / "rgb.txt").write_text(f"{rgb_time} rgb_0.png\n")
    (folder / "depth.txt").write_text("1.0 depth_0.png\n")
    (folder / "groundtruth.txt").write_text("1.0 0 0 0 0 0 0 1\n")
    return folder


def test_importers_refuse_silent_wrong_cameras(tmp_path):
    """TUM's 640 x 480 default intrinsics were applied to images of any size (cx 319.5 on a 16 px
    image); a NaN timestamp dropped its frame quietly; a COLMAP camera id defined twice kept the
    last; NeRF's fl_y beside camera_angle_x was ignored (fy = fx), and camera_angle_y >= pi was
    blamed on fy."""
    from ibr.io.importers import read_frames

    with pytest.raises(ValueError, match=r"^intrinsics: the default TUM calibration is for 640 x 480 images, "
                                         r"these are 16 x 12"):
        read_frames("tum", _tum_folder(tmp_path / "t1"))
    frames = read_frames("tum", _tum_folder(tmp_path / "t2"), intrinsics=(14.0, 14.0, 7.5, 5.5))
    assert frames[0].camera.cx == 7.5
    with pytest.raises(ValueError, match=r"^tum rgb.txt line 1: bad timestamp 'nan'"):
        read_frames("tum", _tum_folder(tmp_path / "t3", rgb_time="nan"), intrinsics=(14.0, 14.0, 7.5, 5.5))
    model, images = _colmap(tmp_path / "c", "1 1 0 0 0 0 0 0 1 f0.png\n\n")
    (model / "cameras.txt").write_text("1 PINHOLE 16 12 14.6 14.6 8 6\n1 PINHOLE 16 12 99 99 8 6\n")
    with pytest.raises(ValueError, match=r"^colmap cameras.txt line 2: camera id 1 is defined twice"):
        read_frames("colmap", model, images=images)
    src = _nerf_folder(tmp_path / "n")
    doc = json.loads((src / "transforms.json").read_text())
    doc["fl_y"] = 20.0
    (src / "transforms.json").write_text(json.dumps(doc))
    cam = read_frames("nerf", src / "transforms.json")[0].camera
    assert cam.fx == pytest.approx(8.0 / np.tan(0.5)) and cam.fy == 20.0
    del doc["fl_y"]
    doc["camera_angle_y"] = 4.0
    (src / "transforms.json").write_text(json.dumps(doc))
    with pytest.raises(ValueError, match=r"'camera_angle_y' must be below pi"):
        read_frames("nerf", src / "transforms.json")


def test_importer_camera_errors_name_the_file_and_line(tmp_path):
    from ibr.io.importers import read_frames

    model, images = _colmap(tmp_path / "c", "1 0 0 0 0 0 0 0 1 f0.png\n\n")  # a zero quaternion
    with pytest.raises(ValueError, match=r"^colmap images.txt line 1: image 'f0.png' \(camera 1\): quaternion: "):
        read_frames("colmap", model, images=images)
    (model / "cameras.txt").write_text("1 PINHOLE 16 12 -14.6 14.6 8 6\n")
    (model / "images.txt").write_text("1 1 0 0 0 0 0 0 1 f0.png\n\n")
    with pytest.raises(ValueError, match=r"^colmap images.txt line 1: image 'f0.png' \(camera 1\): fx: "):
        read_frames("colmap", model, images=images)
    folder = _tum_folder(tmp_path / "t")
    (folder / "groundtruth.txt").write_text("1.0 0 0 0 0 0 0 0\n")
    with pytest.raises(ValueError, match=r"^tum groundtruth.txt: the pose at t = 1.0: quaternion: "):
        read_frames("tum", folder, intrinsics=(14.0, 14.0, 7.5, 5.5))
    (folder / "groundtruth.txt").write_text("1.0 0 0 0 0 0 0 1\n")
    with pytest.raises(ValueError, match=r"^tum: the camera of rgb_0.png: fx: "):
        read_frames("tum", folder, intrinsics=(-14.0, 14.0, 7.5, 5.5))


def test_colmap_depth_bin_errors_name_the_file(tmp_path):
    from ibr.io.importers.colmap import read_colmap_depth

    good = np.arange(1, 7, dtype=np.float32)
    (tmp_path / "a.bin").write_bytes(b"3&2&1&" + good.tobytes())
    np.testing.assert_array_equal(read_colmap_depth(tmp_path / "a.bin"), good.reshape(3, 2, order="F").T)
    for name, raw in (("cut.bin", b"3&2&1&" + good.tobytes()[:-1]), ("neg.bin", b"-3&-2&1&" + good.tobytes())):
        (tmp_path / name).write_bytes(raw)
        with pytest.raises(ValueError, match=rf"^colmap depth: .*{name}: header"):
            read_colmap_depth(tmp_path / name)  # were numpy's 'buffer size must be a multiple' / 'one unknown dimension'


def test_colmap_binary_model_says_how_to_convert_it(tmp_path):
    from ibr.io.importers import read_frames

    model = tmp_path / "sparse"
    model.mkdir()
    (model / "cameras.bin").write_bytes(b"\0" * 8)
    with pytest.raises(FileNotFoundError, match=r"missing .*cameras\.txt; cameras\.bin is there: a binary model, "
                                                r"convert it with `colmap model_converter"):
        read_frames("colmap", model, images=tmp_path)
