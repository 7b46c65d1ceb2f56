"""Regressions from a new-user walkthrough of the command line: warnings where the output is
mostly a guess, notes on defaults a file relies on, and messages that name what the user gave."""

import json
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

import cli

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "samples" / "data"


def _copy_view(src: Path, folder: Path, name: str, **camera) -> Path:
    """A copy of view file ``src`` (with its colour and depth files) in ``folder`` as ``name``,
    its camera's keys replaced by ``camera`` (None: the key removed)."""
    doc = json.loads(src.read_text())
    for key in ("color",):
        shutil.copyfile(src.parent / doc[key], folder / doc[key])
    if doc.get("depth"):
        shutil.copyfile(src.parent / doc["depth"]["path"], folder / doc["depth"]["path"])
    for k, v in camera.items():
        if v is None:
            doc["camera"].pop(k, None)
        else:
            doc["camera"][k] = v
    path = folder / name
    path.write_text(json.dumps(doc))
    return path


# --------------------------------------------------------------------------- 1: mostly invented output
def test_warp_warns_when_most_of_the_output_is_invented_by_the_fill(tmp_path, capsys):
    cam = json.loads((DATA / "room_a.json").read_text())["camera"]
    wide = tmp_path / "wide.json"
    wide.write_text(json.dumps(dict(cam, fx=50, fy=50)))  # sees the room as a speck in the middle
    out = tmp_path / "w.png"
    assert cli.main(["warp", str(DATA / "room_a.json"), "--to", str(wide), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    holes = float(re.search(r"holes (\d+\.\d+)% \(filled", err).group(1))
    m = re.search(r"warp: WARNING: the output is (\d+\.\d)% invented by the hole fill .*a guess", err)
    assert m, err
    assert holes > 90 and float(m.group(1)) == pytest.approx(holes, abs=0.05)
    assert out.is_file()
    # unfilled: said as holes
    assert cli.main(["warp", str(DATA / "room_a.json"), "--to", str(wide), "-o", str(out), "--fill", "none"]) == 0
    assert re.search(r"warp: WARNING: the output is 9\d\.\d% holes .*left black", capsys.readouterr().err)
    # a target that sees the source: no warning
    assert cli.main(["warp", str(DATA / "room_a.json"), "--to", str(DATA / "room_b.json"), "-o", str(out)]) == 0
    assert "WARNING" not in capsys.readouterr().err


def test_interpolate_warns_about_the_frames_the_fill_invents(tmp_path, capsys):
    """B turned 110 degrees from A: the frame half-way looks where neither source looked."""
    a = np.deg2rad(110)
    pose = np.eye(4)
    pose[:3, :3] = [[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]
    turned = _copy_view(DATA / "room_a.json", tmp_path, "turned.json", world_from_cam=pose.tolist())
    out = tmp_path / "o"
    assert cli.main(["interpolate", str(DATA / "room_a.json"), str(turned), "--frames", "3", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    holes = float(re.search(r"frame 2/3 t=0.500: .*holes (\d+\.\d+)%", err).group(1))
    m = re.search(r"interpolate: WARNING: 1 of 3 frames is mostly guessed; frame 2 \(t=0.500\) is (\d+\.\d)% "
                  r"invented by the hole fill", err)
    assert m, err
    assert 50 < holes and float(m.group(1)) == pytest.approx(holes, abs=0.05)
    assert len(list(out.glob("frame_*.png"))) == 3


def test_invented_warning_starts_above_half():
    from commands._common import invented_warning

    assert invented_warning("warp", [("", 0.5, 0.5)]) is None
    assert invented_warning("warp", [("", 0.49, 0.0)]) is None
    line = invented_warning("warp", [("", 0.501, 0.501)], hint="check --to")
    assert line.startswith("warp: WARNING: the output is 50.1% invented by the hole fill") and line.endswith("; check --to")
    two = invented_warning("interpolate", [("frame 1", 0.6, 0.6), ("frame 2", 0.9, 0.8), ("frame 3", 0.1, 0.1)])
    assert "2 of 3 frames are mostly guessed; frame 2 is 80.0% invented" in two


# --------------------------------------------------------------------------- 2: a camera without a pose
def test_a_view_or_camera_file_without_a_pose_loads_with_the_identity_and_is_noted(tmp_path, capsys):
    from ibr.io import load_camera, load_view

    view = _copy_view(DATA / "room_a.json", tmp_path, "a.json", world_from_cam=None)
    cam = tmp_path / "cam.json"
    cam.write_text(json.dumps({k: v for k, v in json.loads((DATA / "room_b.json").read_text())["camera"].items()
                               if k != "world_from_cam"}))
    assert np.array_equal(load_view(view).camera.world_from_cam, np.eye(4))
    assert np.array_equal(load_camera(cam).world_from_cam, np.eye(4))
    out = tmp_path / "o.png"
    assert cli.main(["warp", str(view), "--to", str(cam), "-o", str(out)]) == 0
    notes = [line for line in capsys.readouterr().err.splitlines() if line.startswith("note:")]
    assert notes == [f"note: {p} has no world_from_cam: camera at the origin looking down +z (the identity pose)"
                     for p in (view, cam)]
    # posed files: no note
    assert cli.main(["warp", str(DATA / "room_a.json"), "--to", str(DATA / "room_b.json"), "-o", str(out)]) == 0
    assert "no world_from_cam" not in capsys.readouterr().err


def test_many_files_without_a_pose_are_noted_in_one_line(tmp_path):
    from ibr.io.outputs import OutputPlan

    lines = []
    paths = [_copy_view(DATA / "room_a.json", tmp_path, f"v{i}.json", world_from_cam=None) for i in range(5)]
    with OutputPlan("test", log=lines.append) as plan:
        for p in paths + paths[:1]:  # the same file twice is one file
            plan.add_view_input("VIEW", p)
        plan.add_view_input("posed", DATA / "room_b.json")
        plan.check()
    assert lines == [f"note: 5 view files ({paths[0]}, {paths[1]}, ...) have no world_from_cam: each camera at "
                     "the origin looking down +z (the identity pose)"]


# --------------------------------------------------------------------------- 10: the mesh's texture file
def test_mesh_names_its_texture_replaces_an_old_one_and_refuses_an_input(tmp_path, capsys):
    from ibr.io import load_view, read_image

    view = _copy_view(DATA / "room_a.json", tmp_path, "a.json")
    old = tmp_path / "m_texture.png"
    old.write_bytes(b"an earlier run's texture")
    assert cli.main(["mesh", str(view), "--ply", str(tmp_path / "m.ply")]) == 0
    err = capsys.readouterr().err
    assert f"wrote {tmp_path / 'm.ply'} (" in err and f"its texture {old} (replaced)" in err
    assert np.array_equal(read_image(old), load_view(view).color)
    assert cli.main(["mesh", str(view), "--obj", str(tmp_path / "n.obj")]) == 0
    err = capsys.readouterr().err
    assert f"its material {tmp_path / 'n.mtl'} and texture {tmp_path / 'n_texture.png'}" in err
    assert "(replaced)" not in err
    # the texture name is the view's own colour file: refused before any work
    colour = json.loads(view.read_text())["color"]
    before = (tmp_path / colour).read_bytes()
    (tmp_path / "room_texture.png").symlink_to(colour)
    assert cli.main(["mesh", str(view), "--ply", str(tmp_path / "room.ply")]) == 1
    err = capsys.readouterr().err
    assert "ibr mesh: error: --ply (its texture): " in err and "is the input VIEW 'color'" in err
    assert (tmp_path / colour).read_bytes() == before and not (tmp_path / "room.ply").exists()


def test_mesh_help_names_the_texture_and_material_files(capsys):
    assert cli.main(["mesh", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "OUT.mtl and the texture OUT_texture.png" in text and "the texture OUT_texture.png beside it" in text


# --------------------------------------------------------------------------- 3: all-NaN depth names the file
@pytest.mark.parametrize("command", ["warp", "interpolate", "mesh", "stereo"])
def test_a_depth_without_valid_pixels_is_refused_naming_the_file_not_the_view_name(tmp_path, capsys, command):
    from ibr.io import write_depth

    view = _copy_view(DATA / "room_a.json", tmp_path, "room_a_nandepth.json")
    doc = json.loads(view.read_text())
    write_depth(tmp_path / "nan.exr", np.full((doc["camera"]["height"], doc["camera"]["width"]), np.nan, np.float32))
    doc["depth"] = {"path": "nan.exr", "encoding": "z"}  # its 'name' is still room_a
    view.write_text(json.dumps(doc))
    out = tmp_path / "o"
    argv = {"warp": ["warp", str(view), "--to", str(DATA / "room_b.json"), "-o", str(out) + ".png"],
            "interpolate": ["interpolate", str(DATA / "room_a.json"), str(view), "--out", str(out)],
            "mesh": ["mesh", str(view), "--viz", str(out) + ".png"],
            "stereo": ["stereo", str(view), "--auto", "-o", str(out) + ".png"]}[command]
    assert cli.main(argv) == 1
    err = capsys.readouterr().err
    who = "B" if command == "interpolate" else "VIEW"
    assert f"ibr {command}: error: {who}: {view}: the depth has no valid pixel (NaN, zero, negative or infinite " \
           "everywhere)" in err, err
    assert "room_a'" not in err and not list(tmp_path.glob("o*"))


# --------------------------------------------------------------------------- 4: a file inside the new --out
def test_contact_sheet_inside_the_new_out_folder(tmp_path, capsys):
    out = tmp_path / "o_f5"
    argv = ["interpolate", str(DATA / "room_a.json"), str(DATA / "room_b.json"), "--frames", "5", "--out", str(out),
            "--contact-sheet", str(out / "sheet.png")]
    assert cli.main(argv) == 0
    assert sorted(p.name for p in out.iterdir()) == [f"frame_00{i}_t{i / 4:.3f}.png" for i in range(5)] + ["sheet.png"]
    assert f"wrote contact sheet {out / 'sheet.png'}" in capsys.readouterr().err
    assert [p.name for p in tmp_path.iterdir()] == ["o_f5"]  # no staging folder left
    assert cli.main(argv) == 0  # a second run: the folder exists, the sheet is replaced
    assert len(list(out.iterdir())) == 6


def test_output_plan_stages_a_file_in_a_frame_folder_it_creates(tmp_path):
    from ibr.io.outputs import OutputPlan

    for finish in ("commit", "fail"):
        folder = tmp_path / finish / "new"
        (tmp_path / finish).mkdir()
        try:
            with OutputPlan("test") as plan:
                frames = plan.add_folder("--out", folder, ("frame_#.png",))
                sheet = plan.add_file("--sheet", folder / "sheet.png", (".png",))
                plan.check()
                (plan.stage(frames, "frame_1.png")).write_bytes(b"f")
                plan.stage(sheet).write_bytes(b"s")
                if finish == "fail":
                    raise RuntimeError("the work failed")
                written = plan.commit()
        except RuntimeError:
            pass
        if finish == "commit":
            assert (folder / "sheet.png").read_bytes() == b"s" and (folder / "frame_1.png").read_bytes() == b"f"
            assert folder / "sheet.png" in written
        else:  # nothing half-written: no folder, no staging
            assert list((tmp_path / finish).iterdir()) == []
    with OutputPlan("test") as plan:  # a file in a folder that nothing creates is still refused
        plan.add_folder("--out", tmp_path / "x", ("frame_#.png",))
        plan.add_file("--sheet", tmp_path / "y" / "sheet.png", (".png",))
        with pytest.raises(FileNotFoundError, match=r"--sheet: the output folder .*y of .*sheet.png does not exist"):
            plan.check()


# --------------------------------------------------------------------------- 5: interpolate's options
def test_interpolate_o_is_out_and_fps_needs_a_video(tmp_path, capsys):
    pair = [str(DATA / "room_a.json"), str(DATA / "room_b.json")]
    assert cli.main(["interpolate", *pair, "--frames", "2", "-o", str(tmp_path / "f")]) == 0
    assert sorted(p.name for p in (tmp_path / "f").iterdir()) == ["frame_000_t0.000.png", "frame_001_t1.000.png"]
    capsys.readouterr()
    assert cli.main(["interpolate", *pair, "--fps", "30", "-o", str(tmp_path / "g")]) == 1
    err = capsys.readouterr().err
    assert "ibr interpolate: error: --fps: only used with --video (the video's frame rate)" in err
    assert not (tmp_path / "g").exists()


def test_interpolate_report_on_a_pair_does_not_suggest_frames(tmp_path, capsys):
    pair = [str(DATA / "room_a.json"), str(DATA / "room_b.json")]
    assert cli.main(["interpolate", *pair, "--report", str(tmp_path / "r.json"), "-o", str(tmp_path / "f")]) == 1
    err = capsys.readouterr().err
    assert "error: --report: only used with a sequence" in err and "printed" in err
    assert "--frames or --t" not in err
    assert cli.main(["interpolate", *pair, "--factor", "2", "-o", str(tmp_path / "f")]) == 1
    assert "use --frames or --t for a pair" in capsys.readouterr().err


def test_interpolate_help_says_the_contact_sheet_is_for_pairs(capsys):
    assert cli.main(["interpolate", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "-o DIR, --out DIR" in text
    assert "--contact-sheet SHEET.png pairs only" in text
    assert "frame rate of --video (only with --video" in text


# --------------------------------------------------------------------------- 7: PSNR over the new frames
def test_interpolate_truth_mean_is_over_the_new_frames_and_never_inf(tmp_path, capsys):
    from ibr.io import load_view
    from ibr.sequence.files import save_sequence

    names = ("room_a", "room_t025", "room_t050", "room_t075", "room_b")
    save_sequence([load_view(DATA / f"{n}.json") for n in names], tmp_path / "truth.json")
    pair = [str(DATA / "room_a.json"), str(DATA / "room_b.json")]
    assert cli.main(["interpolate", *pair, "--frames", "5", "--truth", str(tmp_path / "truth.json"),
                     "-o", str(tmp_path / "f")]) == 0
    err = capsys.readouterr().err
    assert not re.search(r"\binf\b", err)
    per_frame = [float(x) for x in re.findall(r"t=0\.(?:250|500|750): .*PSNR (\d+\.\d+) dB", err)]
    assert len(per_frame) == 3 and err.count("identical to truth_") == 2  # t = 0 and 1
    m = re.search(r"ground truth: mean PSNR (\d+\.\d+) dB, mean SSIM 0\.\d{4} over 3 new frames \(the key frames "
                  r"t = 0 / 1, copies of A / B, left out\)", err)
    assert m, err
    assert float(m.group(1)) == pytest.approx(np.mean(per_frame), abs=0.006)


def test_truth_summary_leaves_out_key_and_identical_frames():
    from commands.interpolate import truth_summary

    assert truth_summary([(0.0, np.inf, 1.0), (0.5, 30.0, 0.9), (1.0, np.inf, 1.0)]) == (
        "ground truth: mean PSNR 30.00 dB, mean SSIM 0.9000 over 1 new frame (the key frames t = 0 / 1, copies of "
        "A / B, left out)")
    assert truth_summary([(0.25, 30.0, 0.8), (0.5, np.inf, 1.0)]) == (
        "ground truth: mean PSNR 30.00 dB, mean SSIM 0.9000 over 2 new frames (1 identical, left out of the PSNR mean)")
    assert "no new frame to score" in truth_summary([(0.0, np.inf, 1.0), (1.0, np.inf, 1.0)])
    assert not re.search(r"\binf\b", truth_summary([(0.5, np.inf, 1.0)]))


# --------------------------------------------------------------------------- 6: frame names sort in order
def test_number_width_pads_to_the_count():
    from ibr.io.outputs import number_width

    assert [number_width(n, 3) for n in (1, 5, 1000, 1001, 10001)] == [3, 3, 3, 4, 5]
    assert [number_width(n) for n in (0, 10000, 10001, 100000)] == [4, 4, 5, 5]


def test_interpolate_1001_frames_sort_by_name_in_order(tmp_path, capsys):
    from ibr.base.view import View
    from ibr.io import save_view
    from ibr.synth import make_scene, render, scene_cameras

    scene = make_scene("room")
    for cam, name in zip(scene_cameras("room", width=16, height=12), ("a", "b")):
        v = render(scene, cam, name=name)
        save_view(View((np.clip(v.color, 0, 1) * 255 + 0.5).astype(np.uint8), v.depth, v.camera, name),
                  tmp_path / f"{name}.json")
    out = tmp_path / "f"
    assert cli.main(["interpolate", str(tmp_path / "a.json"), str(tmp_path / "b.json"), "--frames", "1001",
                     "--fill", "none", "-o", str(out)]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert len(names) == 1001
    assert names[0] == "frame_0000_t0.000.png" and names[100] == "frame_0100_t0.100.png"
    assert names[-1] == "frame_1000_t1.000.png"
    assert [int(n.split("_")[1]) for n in names] == list(range(1001))  # name order is frame order


# --------------------------------------------------------------------------- 8: --scene is a choice
def test_interpolate_scene_is_a_parser_choice_of_the_bundled_scenes(tmp_path, capsys):
    from commands.interpolate import SAMPLE_SCENES

    assert list(SAMPLE_SCENES) == list(json.loads((DATA / "manifest.json").read_text())["scenes"])
    assert cli.main(["interpolate", "--scene", "nope", "-o", str(tmp_path / "f")]) == 2
    assert "argument --scene: invalid choice: 'nope' (choose from 'room', 'clutter', 'grazing')" in \
        capsys.readouterr().err
    assert not (tmp_path / "f").exists()
    assert cli.main(["interpolate", "--help"]) == 0
    assert "--scene {room,clutter,grazing}" in capsys.readouterr().out
    assert cli.main(["interpolate", "--scene", "grazing", "--t", "0.5", "-o", str(tmp_path / "f")]) == 0
    assert "bundled sample pair grazing_a.json / grazing_b.json" in capsys.readouterr().err


# --------------------------------------------------------------------------- 9: the quantized bound in px
def _quantized_room(folder: Path) -> Path:
    from ibr.io import load_view, write_depth

    view = _copy_view(DATA / "room_a.json", folder, "room_q.json")
    write_depth(folder / "room_q_depth.png", load_view(DATA / "room_a.json").depth, scale=0.05)  # 5 cm codes
    doc = json.loads(view.read_text())
    doc["depth"] = {"path": "room_q_depth.png", "encoding": "z", "scale": 0.05}
    view.write_text(json.dumps(doc))
    return view


def test_mesh_bound_in_px_includes_half_a_code_of_the_file_quantization(tmp_path, capsys):
    from ibr.base.depth import quantization_of
    from ibr.io import load_view
    from ibr.mesh.quad_mesh import build_mesh

    view = load_view(_quantized_room(tmp_path))
    q = quantization_of(view)
    mesh = build_mesh(view)
    i, f = mesh.info, max(view.camera.fx, view.camera.fy)
    half_code_px = 0.5 * q.max_inv_step(view.depth) * f * i["baseline"]
    assert half_code_px > 0.3  # 5 cm codes at 3-6 m: a third of a pixel and more
    assert i["guaranteed_px"] == pytest.approx(0.5 + half_code_px, rel=1e-9)
    assert i["guaranteed_px"] == pytest.approx(i["tolerance_inv_depth"] * f * i["baseline"], rel=1e-12)
    exact = build_mesh(load_view(DATA / "room_a.json")).info
    assert exact["guaranteed_px"] == pytest.approx(0.5, rel=1e-12) and exact["quantization_allowance_inv_depth"] == 0

    assert cli.main(["mesh", str(tmp_path / "room_q.json")]) == 0
    err = capsys.readouterr().err
    m = re.search(r"guaranteed max \|error in 1/z\| (\S+) \(= (\S+) px for a baseline of ([0-9.]+): 0.5 px plus half a "
                  r"code of the depth's quantization\); the file's depth quantization \(depth codes of 0.05 scene "
                  r"units\) applied", err)
    assert m, err
    tol, px, b = map(float, m.groups())
    assert px == pytest.approx(tol * f * b, rel=2e-3) and px > 0.8


def test_depth_quantization_describes_itself():
    from ibr.base.depth import DepthQuantization

    assert DepthQuantization.codes(0.05).describe() == "depth codes of 0.05 scene units"
    assert DepthQuantization.disparity(baseline=0.2, focal_px=500).describe() == "codes of 0.01 in 1/z"
    assert DepthQuantization().describe() == "no steps"


# --------------------------------------------------------------------------- 11: mesh --threshold default, --viz
def test_mesh_paper_default_threshold_is_the_one_help_and_docs_state(tmp_path, capsys):
    assert cli.main(["mesh", str(DATA / "clutter_a.json"), "--method", "paper"]) == 0
    printed = re.search(r"mesh: threshold (\d+) in z' units", capsys.readouterr().err).group(1)
    assert printed != "32768"
    assert cli.main(["mesh", "--help"]) == 0
    help_text = " ".join(capsys.readouterr().out.split()).replace("- ", "-")
    assert f"e.g. {printed} for the bundled clutter view with --method paper" in help_text
    docs = (ROOT / "docs" / "mesh.md").read_text()
    assert f"{printed} for the bundled clutter view" in " ".join(docs.split())


def test_mesh_viz_colours_are_the_ones_the_help_names(tmp_path, capsys):
    from ibr.io import read_image, write_depth
    from ibr.mesh.quad_mesh import build_mesh
    from ibr.io import load_view

    view = _copy_view(DATA / "room_a.json", tmp_path, "a.json")
    depth = load_view(view).depth.copy()
    depth[100:110, 200:210] = np.nan       # no depth: black
    depth[50, 50] = depth[50, 50] * 0.5    # a lone near pixel: a one-pixel quad, yellow
    write_depth(tmp_path / "d.exr", depth)
    doc = json.loads(view.read_text())
    doc["depth"] = {"path": "d.exr", "encoding": "z"}
    view.write_text(json.dumps(doc))
    assert cli.main(["mesh", str(view), "--viz", str(tmp_path / "seg.png")]) == 0
    seg = read_image(tmp_path / "seg.png")
    mesh = build_mesh(load_view(view))
    assert mesh.quad_of_pixel[105, 205] == -1 and tuple(seg[105, 205]) == (0, 0, 0)
    assert mesh.areas[mesh.quad_of_pixel[50, 50]] == 1 and tuple(seg[50, 50]) == (255, 220, 0)
    assert tuple(seg[0, 0]) == (255, 40, 40)                      # an outline
    assert cli.main(["mesh", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "red one-pixel outlines" in text and "yellow one-pixel quads" in text and "black pixels without depth" in text


# --------------------------------------------------------------------------- 12: ibr bench list TOPIC
def test_bench_list_with_a_topic_says_how_to_list_or_run(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["bench", "list", "mesh"]) == 1
    err = capsys.readouterr().err
    assert "ibr bench: error: topic: 'list' lists the benchmarks (" in err
    assert "run 'ibr bench list', or 'ibr bench mesh' to run it" in err and "got 'list'" not in err
    assert list(tmp_path.iterdir()) == []  # nothing run, no ./ibr-bench made
    assert cli.main(["bench", "list"]) == 0
    listed = capsys.readouterr().out.split()
    assert "mesh" in listed and "render" in listed


# --------------------------------------------------------------------------- 13: docs/cli.md lists every command
def test_cli_page_lists_every_command_with_a_docs_page():
    text = (ROOT / "docs" / "cli.md").read_text()
    rows = {m.group(1): m.group(2) for m in re.finditer(r"^\| `ibr ([a-z-]+)[^`]*` \|[^|\n]*(?:\\\|[^|\n]*)*\| (.*) \|$",
                                                       text, re.M)}
    assert sorted(rows) == sorted(name for name, _ in cli.COMMANDS)
    for name, docs in rows.items():
        links = re.findall(r"\]\(([a-z_]+\.md)(?:#[a-z-]+)?\)", docs)
        assert links, name
        assert all((ROOT / "docs" / link).is_file() for link in links), (name, links)
    assert "#ibr-samples" in text and "### `ibr samples`" in (ROOT / "docs" / "synth.md").read_text()


def test_a_reader_that_leaves_early_ends_the_command_quietly(monkeypatch, capsys):
    """'ibr bench list | head -3' printed 'ibr bench: error: [Errno 32] Broken pipe': a closed
    pipe on stdout now ends the command with the SIGPIPE status and no message."""
    import sys

    from cli import main

    class ClosedPipe:
        def write(self, text):
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self):
            pass

    monkeypatch.setattr(sys, "stdout", ClosedPipe())
    assert main(["bench", "list"]) == 141
    assert "error" not in capsys.readouterr().err


def test_one_wording_for_a_depth_without_a_valid_pixel(tmp_path):
    """The library (warp, stereo) and the CLI say the same sentence, each naming the view its way."""
    from ibr.base.camera import Camera
    from ibr.base.view import View, no_valid_depth_message
    from ibr.stereo.pair import stereo_pair
    from ibr.render.view_synthesis import warp

    cam = Camera(20.0, 20.0, 3.5, 2.5, 8, 6)
    view = View(np.zeros((6, 8, 3), np.uint8), np.full((6, 8), np.nan, np.float32), cam, "empty")
    core = "the depth has no valid pixel (NaN, zero, negative or infinite everywhere)"
    assert no_valid_depth_message("VIEW: a.json", ", so it has no mesh") == f"VIEW: a.json: {core}, so it has no mesh"
    with pytest.raises(ValueError) as lib:
        warp(view, cam)
    with pytest.raises(ValueError) as pair:
        stereo_pair(view, e=0.06, f=2.0)
    assert f"view 'empty': {core}, so it cannot be a source" in str(lib.value)
    assert str(pair.value) == f"view 'empty': {core}; a stereo pair needs depth"
