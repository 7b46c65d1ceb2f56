"""Sequences (issue #15): files, synthetic camera paths, up-conversion, flicker, the CLI.

Ground truth comes from ibr.synth (exact renders of the in-between cameras); images are tiny
(64 x 48) so the whole file runs in seconds.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import cli
from ibr import Camera, View, interpolate_cameras, look_at
from ibr.io import load_view, read_image
from ibr.sequence import (flicker, frame_count, frame_schedule, is_sequence, iter_views, load_sequence, psnr,
                          referenced_files, save_sequence, sequence_stereo_params, static_masks_from_truth,
                          stereo_sequence, upconvert)
from ibr.sequence.metrics import frame_change, static_mask_from_motion
from ibr.synth import camera_path, path_frame_cameras, synthetic_sequence


@pytest.fixture(scope="module")
def walk():
    """4 keys of the room, factor 3, small motion: no holes, exact truth for 12 frames."""
    return synthetic_sequence("room", 4, 3, width=64, height=48, step=0.1, supersample=2)


@pytest.fixture(scope="module")
def cluttered():
    """Larger steps through the clutter scene: about 1 % of pixels are disoccluded per new frame."""
    return synthetic_sequence("clutter", 4, 3, width=64, height=48, step=0.25, supersample=2)


# --------------------------------------------------------------------------- timeline and paths
def test_schedule_counts_and_tail():
    assert frame_count(10, 4) == 40 and frame_count(10, 4, tail=False) == 37
    s = frame_schedule(3, 2)
    assert s == [(0, 0.0), (0, 0.5), (1, 0.0), (1, 0.5), (2, 0.0), (1, 1.5)]
    assert frame_schedule(3, 2, tail=False) == s[:5]
    with pytest.raises(ValueError, match="at least 2 views"):
        frame_count(1, 4)
    with pytest.raises(ValueError, match="factor"):
        frame_count(3, 0)


def test_path_cameras_follow_the_schedule():
    keys = camera_path("room", 3, width=32, height=24)
    cams = path_frame_cameras(keys, 4)
    assert len(cams) == 12
    for j, (seg, t) in enumerate(frame_schedule(3, 4)):
        want = keys[seg] if t == 0 else interpolate_cameras(keys[seg], keys[seg + 1], t)
        assert cams[j].allclose(want)
    # the path moves `step` per key along the pair's baseline (world x) and `forward` along z
    d = keys[1].position - keys[0].position
    assert d == pytest.approx([0.1, 0.0, 0.03])


def test_synthetic_sequence_truth_contains_the_keys(walk):
    assert len(walk.keys) == 4 and len(walk.truth) == 12
    assert all(walk.truth[3 * i] is k for i, k in enumerate(walk.keys))
    assert walk.keys[0].color.dtype == np.uint8
    assert walk.is_key.tolist() == [j % 3 == 0 for j in range(12)]


# --------------------------------------------------------------------------- up-conversion
def test_upconvert_keys_pass_through_and_cameras_match_truth(walk):
    frames = list(upconvert(walk.keys, 3))
    assert len(frames) == 12
    for fr, gt in zip(frames, walk.truth):
        assert fr.camera.allclose(gt.camera)
        if fr.key:
            assert np.array_equal(fr.color, gt.color)          # bit-identical, not re-rendered
    new = [psnr(f.color, g.color) for f, g in zip(frames, walk.truth) if not f.key]
    assert len(new) == 8 and min(new) > 30.0                    # 32.3 dB mean at 64 x 48


def test_each_key_mesh_is_built_once(walk, monkeypatch):
    import ibr.mesh

    keys = [View(k.color, k.depth, k.camera, k.name) for k in walk.keys]  # fresh objects: empty mesh cache
    calls = []
    real = ibr.mesh.build_mesh
    monkeypatch.setattr(ibr.mesh, "build_mesh", lambda view, **kw: calls.append(view.name) or real(view, **kw))
    list(upconvert(iter(keys), 3))
    assert sorted(calls) == sorted(k.name for k in keys)        # N builds for N keys, not 2 (N - 1)


def test_previous_fill_runs_across_segments(cluttered):
    """Seed step 7 across key frames: a hole pixel takes the previous output frame (colour and
    depth) where that frame showed background there (at least the depth of the background
    pull-push's estimate), else the estimate, which is then farther than the previous frame."""
    frames = list(upconvert(cluttered.keys, 3, fill="previous"))
    holes = taken = 0
    for prev, fr in zip(frames, frames[1:]):
        r = fr.rendering
        assert np.array_equal(r.filled, r.holes)
        h = r.holes
        p = prev.rendering
        same = (r.color[h] == p.color[h]).all(-1) & (r.depth[h] == p.depth[h])
        assert (same | (p.depth[h] < r.depth[h])).all()
        holes += int(h.sum())
        taken += int(same.sum())
    assert holes > 100                                          # the test sees real disocclusions
    assert 20 <= taken < holes                                  # both sources of the fill occur


def test_flicker_is_lowest_with_previous_frame_fill(cluttered):
    masks = static_masks_from_truth([v.color for v in cluttered.truth])
    fl = {fill: flicker([f.color for f in upconvert(cluttered.keys, 3, fill=fill)], masks).mean
          for fill in ("previous", "inpaint", "none")}
    assert fl["previous"] < fl["inpaint"] < fl["none"]


def test_upconvert_refuses_bad_input(walk):
    with pytest.raises(ValueError, match="at least 2 views"):
        list(upconvert([walk.keys[0]], 3))
    with pytest.raises(ValueError, match="factor"):
        list(upconvert(walk.keys, 0))
    no_depth = View(walk.keys[0].color, None, walk.keys[0].camera, "flat")
    with pytest.raises(ValueError, match="depth"):
        list(upconvert([no_depth, walk.keys[1]], 2))


# --------------------------------------------------------------------------- metrics
def test_flicker_and_psnr_formulas():
    a = np.zeros((4, 5, 3), np.uint8)
    b = a.copy()
    b[1, 2] = 51                                                # 0.2 in [0, 1] units
    static = np.ones((4, 5), bool)
    assert frame_change(a, b, static) == pytest.approx(0.2 / 20)
    rep = flicker([a, b, b], [static, static])
    assert rep.per_pair == pytest.approx((0.01, 0.0)) and rep.mean == pytest.approx(0.005)
    assert static_masks_from_truth([a, b])[0].sum() == 19
    assert psnr(a, b) == pytest.approx(10 * np.log10(1 / (0.04 / 20)))
    assert np.isnan(frame_change(a, b, np.zeros((4, 5), bool)))


def test_static_mask_from_motion_matches_the_parallax():
    # fronto-parallel plane at z = 4, camera moved 0.02 sideways: every pixel moves fx * 0.02 / 4 px
    cam0 = Camera.from_fov(40, 30, hfov_deg=60, world_from_cam=look_at((0, 0, 0), (0, 0, 4)))
    cam1 = cam0.translated((0.02, 0, 0))
    shift = cam0.fx * 0.02 / 4                                  # 0.173 px
    depth = np.full(cam1.shape, 4.0, np.float32)
    assert static_mask_from_motion(depth, cam1, cam0, max_px=shift * 1.01).all()
    assert not static_mask_from_motion(depth, cam1, cam0, max_px=shift * 0.99).any()
    depth[0, 0] = np.nan
    assert not static_mask_from_motion(depth, cam1, cam0, max_px=1)[0, 0]


# --------------------------------------------------------------------------- files
def test_save_and_load_sequence(tmp_path, walk):
    manifest = save_sequence(walk.keys, tmp_path / "walk.json", fps=10, ground_truth={"sequence": "t.json", "factor": 3})
    seq = load_sequence(manifest)
    assert is_sequence(manifest) and len(seq) == 4 and seq.fps == 10 and seq.truth_factor == 3
    assert [p.name for p in seq.views] == [f"walk_{i:04d}.json" for i in range(4)]
    views = list(iter_views(seq))
    assert np.array_equal(views[2].color, walk.keys[2].color) and views[2].camera.allclose(walk.keys[2].camera)
    folder = load_sequence(tmp_path)                            # the same views as a numbered folder
    assert folder.views == seq.views and folder.name == "walk"
    refs = {p.name for p in referenced_files(manifest)}
    assert {"walk.json", "walk_0001.json", "walk_0001_color.png", "walk_0001_depth.exr"} <= refs
    assert not is_sequence(seq.views[0])                       # a view file is not a sequence


def test_sequence_files_refuse_bad_input(tmp_path, walk):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"format": "ibr-sequence", "version": 1, "views": ["missing.json"]}))
    with pytest.raises(FileNotFoundError, match=r"views\[0\]"):
        load_sequence(bad)
    bad.write_text(json.dumps({"format": "ibr-view", "version": 1}))
    with pytest.raises(ValueError, match="ibr-sequence"):
        load_sequence(bad)
    bad.write_text(json.dumps({"format": "ibr-sequence", "version": 1, "views": []}))
    with pytest.raises(ValueError, match="non-empty"):
        load_sequence(bad)
    mixed = tmp_path / "mixed"
    mixed.mkdir()
    save_sequence(walk.keys[:2], mixed / "a.json")
    save_sequence(walk.keys[:2], mixed / "b.json")
    with pytest.raises(ValueError, match="several prefixes"):
        load_sequence(mixed)
    (tmp_path / "empty").mkdir()
    with pytest.raises(ValueError, match="no view files"):
        load_sequence(tmp_path / "empty")


# --------------------------------------------------------------------------- stereo
def test_stereo_sequence_uses_one_pair_for_all_frames(walk):
    e, f = sequence_stereo_params(v.depth for v in walk.keys)
    pooled = np.concatenate([v.depth[::4, ::4].ravel() for v in walk.keys])
    from ibr.stereo import auto_stereo

    assert (e, f) == auto_stereo(pooled[np.isfinite(pooled)])
    pairs = list(stereo_sequence(walk.keys, e=e, f=f))
    shift = {round(p.left_camera.cx - k.camera.cx, 9) for p, k in zip(pairs, walk.keys)}
    assert len(pairs) == 4 and len(shift) == 1                 # the same principal-point shift everywhere


# --------------------------------------------------------------------------- command line
def test_cli_samples_interpolate_and_stereo_over_a_sequence(tmp_path, capsys):
    seq = tmp_path / "seq"
    assert cli.main(["samples", "--sequence", "--size", "48x36", "--keys", "3", "--factor", "2",
                     "--out", str(seq)]) == 0
    manifest = seq / "room_walk.json"
    assert load_sequence(manifest).truth == seq / "room_truth.json"
    out, report = tmp_path / "frames", tmp_path / "r.json"
    assert cli.main(["interpolate", str(manifest), "--factor", "2", "--out", str(out), "--video",
                     str(tmp_path / "v.avi"), "--report", str(report)]) == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == [f"frame_{j:04d}.png" for j in range(6)]
    key = load_view(seq / "room_walk_0001.json").color
    assert np.array_equal(read_image(out / "frame_0002.png"), key)
    doc = json.loads(report.read_text())
    assert doc["summary"]["frames"] == 6 and doc["summary"]["static_basis"] == "truth"
    assert doc["summary"]["psnr_mean"] > 25 and doc["summary"]["flicker"] >= 0
    assert (tmp_path / "v.avi").stat().st_size > 0
    err = capsys.readouterr().err
    assert "frames/s" in err and "ETA" in err and "PSNR vs ground truth" in err
    st = tmp_path / "st"
    assert cli.main(["stereo", str(manifest), "--mode", "sbs", "-o", str(st)]) == 0
    assert sorted(p.name for p in st.iterdir()) == [f"stereo_{i:04d}.png" for i in range(3)]
    assert read_image(st / "stereo_0000.png").shape == (36, 96, 3)
    # a sequence argument together with pair-only options is refused before any work
    assert cli.main(["interpolate", str(manifest), "--frames", "3", "--out", str(tmp_path / "x")]) == 1
    assert not (tmp_path / "x").exists()


def test_ground_truth_sequences_are_inputs_never_outputs(tmp_path, capsys):
    """``ibr interpolate SEQ`` did not count the ground truth (the manifest's or ``--truth``) as an
    input: ``--report`` on the truth manifest or one of its views replaced it, and ``--out`` on a
    truth folder of ``frame_NNNN`` views wrote over its images. All are refused before any work,
    whether the truth is scored or not (another ``--factor``)."""
    import shutil

    seq = tmp_path / "seq"
    assert cli.main(["samples", "--sequence", "--size", "48x36", "--keys", "3", "--factor", "2",
                     "--out", str(seq)]) == 0
    manifest = seq / "room_walk.json"
    before = {p.name: p.read_bytes() for p in seq.iterdir()}
    for factor in ("2", "3"):  # scored, and declared for another factor (not scored)
        for victim in ("room_truth.json", "room_truth_0001.json"):
            assert cli.main(["interpolate", str(manifest), "--factor", factor, "--out", str(tmp_path / "q"),
                             "--report", str(seq / victim)]) == 1
            assert "ground truth" in capsys.readouterr().err
    gt = tmp_path / "gt"  # the truth as a folder of numbered views
    gt.mkdir()
    for j in range(6):
        doc = json.loads((seq / f"room_truth_{j:04d}.json").read_text())
        shutil.copy(seq / doc["color"], gt / f"frame_{j:04d}.png")
        shutil.copy(seq / doc["depth"]["path"], gt / f"frame_{j:04d}_depth.exr")
        doc["color"], doc["depth"]["path"] = f"frame_{j:04d}.png", f"frame_{j:04d}_depth.exr"
        (gt / f"frame_{j:04d}.json").write_text(json.dumps(doc))
    gt_before = {p.name: p.read_bytes() for p in gt.iterdir()}
    assert cli.main(["interpolate", str(manifest), "--factor", "2", "--truth", str(gt), "--out", str(gt)]) == 1
    assert "ground truth" in capsys.readouterr().err
    assert {p.name: p.read_bytes() for p in gt.iterdir()} == gt_before
    assert {p.name: p.read_bytes() for p in seq.iterdir()} == before


def test_stereo_over_a_sequence_of_sparse_depth(tmp_path, capsys):
    """Depth valid on every other row and column only (odd rows and columns): the pooled grid
    (every 4th pixel of every 4th row) saw none of it. ``ibr stereo SEQ --f 4`` crashed
    (IndexError in a percentile of nothing) and without --f it said no frame had depth."""
    from ibr.io import save_view
    from ibr.sequence.stereo import pool_depths

    seq = tmp_path / "seq"
    assert cli.main(["samples", "--sequence", "--size", "48x36", "--keys", "2", "--factor", "1",
                     "--out", str(seq)]) == 0
    sparse = tmp_path / "sparse"
    sparse.mkdir()
    names = []
    for i, v in enumerate(load_sequence(seq / "room_walk.json").views):
        view = load_view(v)
        z = np.full(view.depth.shape, np.nan, np.float32)
        z[1::2, 1::2] = view.depth[1::2, 1::2]
        save_view(View(view.color, z, view.camera, f"p{i}"), sparse / f"p_{i:04d}.json")
        names.append(f"p_{i:04d}.json")
    (sparse / "s.json").write_text(json.dumps({"format": "ibr-sequence", "version": 1, "views": names}))
    zs = [load_view(sparse / n).depth for n in names]
    pooled = pool_depths(zs)
    assert pooled.size > 0 and np.isfinite(pooled).all()
    for extra in (["--f", "4"], ["--auto"]):
        assert cli.main(["stereo", str(sparse / "s.json"), *extra, "-o", str(tmp_path / f"o{len(extra)}")]) == 0
    with pytest.raises(ValueError, match="depths: no valid"):
        pool_depths([np.full((4, 4), np.nan, np.float32)])
