"""``ibr canvas`` through ``cli.main``: images, video frames and strokes on a plane in a view or a panorama."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest

import ibr
from cli import main
from ibr.base.camera import Camera, look_at
from ibr.canvas import Canvas, canvas_from_image, composite, draw_stroke
from ibr.io import read_image, save_view, write_image
from ibr.synth import Box, Rect, Scene, checker_texture, render
from panorama.canvas import composite_equirect
from panorama.directions import equirect_directions

GEO = ["--center", "0.1", "0", "3", "--normal", "0.2", "0", "-1", "--size", "1.2", "0.8"]


@pytest.fixture()
def scene(tmp_path):
    wall = Rect(checker_texture(width_units=2.0), np.array([0, 0, 5.0]), np.array([1.0, 0, 0]),
                np.array([0, 1.0, 0]), 5, 5, (0, 0))
    box = Box(checker_texture(width_units=0.5), np.array([0.4, 0.2, 2.0]), np.array([0.2, 0.2, 0.2]))
    cam = Camera.from_fov(160, 120, hfov_deg=60, world_from_cam=look_at([0.2, -0.1, 0], [0, 0, 3]))
    view = render(Scene((wall, box), ambient=1.0, diffuse=0.0), cam, name="v")
    view = ibr.View(np.rint(view.color * 255).astype(np.uint8), view.depth, cam, "v")
    save_view(view, tmp_path / "v.json")
    poster = np.random.default_rng(3).integers(0, 256, (40, 60, 3), np.uint8)
    write_image(tmp_path / "poster.png", poster)
    return tmp_path, ibr.load_view(tmp_path / "v.json"), poster


def _canvas(**kw):
    return dict(center=[0.1, 0, 3], normal=[0.2, 0, -1], size=[1.2, 0.8], **kw)


def test_image_on_a_view_is_the_library_composite(scene):
    tmp, view, poster = scene
    assert main(["canvas", str(tmp / "v.json"), "--image", str(tmp / "poster.png"), *GEO, "-o", str(tmp / "o.png")]) == 0
    expected = composite(view, canvas_from_image(poster, **_canvas())).color
    got = read_image(tmp / "o.png")
    np.testing.assert_array_equal(got, expected)
    hidden = view.depth < 2.3  # the box in front of the canvas
    assert hidden.sum() > 50 and np.array_equal(got[hidden], view.color[hidden])
    assert not np.array_equal(got, view.color)
    assert main(["canvas", str(tmp / "v.json"), "--image", str(tmp / "poster.png"), *GEO, "--power-of-two",
                 "-o", str(tmp / "p2.png")]) == 0
    p2 = read_image(tmp / "p2.png")
    assert np.abs(p2.astype(int) - expected).mean() < 6  # 60x40 -> 64x64 texels, same picture


def test_video_frames_and_video_file(scene):
    tmp, view, _ = scene
    w = cv2.VideoWriter(str(tmp / "clip.avi"), cv2.VideoWriter_fourcc(*"MJPG"), 24, (48, 32))
    for i in range(4):
        w.write(np.full((32, 48, 3), (0, 60 * i, 200), np.uint8))
    w.release()
    assert main(["canvas", str(tmp / "v.json"), "--video", str(tmp / "clip.avi"), *GEO, "-o", str(tmp / "frames")]) == 0
    frames = sorted((tmp / "frames").glob("frame_*.png"))
    assert len(frames) == 4
    centre = [read_image(f)[60, 80] for f in frames]  # the canvas centre pixel shows the frame's colour
    assert all(abs(int(c[0]) - 200) < 12 for c in centre)
    assert [int(c[1]) for c in centre] == sorted(int(c[1]) for c in centre) and centre[3][1] > 150
    assert main(["canvas", str(tmp / "v.json"), "--video", str(tmp / "clip.avi"), *GEO, "--frames", "2",
                 "-o", str(tmp / "out.avi")]) == 0
    cap = cv2.VideoCapture(str(tmp / "out.avi"))
    n = 0
    while cap.read()[0]:
        n += 1
    assert n == 2


def test_strokes_in_canvas_and_screen_space(scene):
    tmp, view, _ = scene
    doc = {"strokes": [{"points": [[10, 10], [200, 150]], "width": 6, "color": "#00ff00"}], "background": "#ffffff"}
    (tmp / "s.json").write_text(json.dumps(doc))
    assert main(["canvas", str(tmp / "v.json"), "--strokes", str(tmp / "s.json"), *GEO, "--resolution", "240", "160",
                 "-o", str(tmp / "s.png")]) == 0
    c = Canvas(**_canvas(resolution=(240, 160)))
    c.clear((1, 1, 1, 1))
    draw_stroke(c, [[10, 10], [200, 150]], width=6, color="#00ff00")
    np.testing.assert_array_equal(read_image(tmp / "s.png"), composite(view, c).color)
    # screen space: the stroke follows the view's pixels (picked onto the canvas)
    screen = {"space": "screen", "strokes": [{"points": [[60, 50], [100, 50]], "width": 5, "color": [1, 0, 0]}]}
    (tmp / "screen.json").write_text(json.dumps(screen))
    assert main(["canvas", str(tmp / "v.json"), "--strokes", str(tmp / "screen.json"), *GEO, "-o", str(tmp / "t.png")]) == 0
    got = read_image(tmp / "t.png").astype(int)
    red = (got[..., 0] > 200) & (got[..., 1] < 60)
    rows, cols = np.nonzero(red)
    assert abs(rows.mean() - 50) < 1.5 and cols.min() >= 57 and cols.max() <= 103
    outside = {"strokes": [{"points": [[-100, -100], [-50, -80]]}]}
    (tmp / "out.json").write_text(json.dumps(outside))
    assert main(["canvas", str(tmp / "v.json"), "--strokes", str(tmp / "out.json"), *GEO, "-o", str(tmp / "u.png")]) == 0
    np.testing.assert_array_equal(read_image(tmp / "u.png"), view.color)  # nothing drawn: the view unchanged


def test_equirect_panorama(tmp_path):
    d = equirect_directions(128, 64)
    eq = np.stack([0.5 + 0.3 * d[..., 0], 0.5 + 0.3 * d[..., 1], 0.5 + 0.3 * d[..., 2]], -1).astype(np.float32)
    write_image(tmp_path / "eq.exr", eq)
    poster = np.random.default_rng(0).random((20, 30, 3)).astype(np.float32)
    write_image(tmp_path / "poster.exr", poster)
    assert main(["canvas", str(tmp_path / "eq.exr"), "--image", str(tmp_path / "poster.exr"), *GEO,
                 "-o", str(tmp_path / "o.exr")]) == 0
    expected = composite_equirect(eq, [canvas_from_image(poster, **_canvas())])
    np.testing.assert_allclose(read_image(tmp_path / "o.exr"), expected, atol=1e-6)
    rng = np.full((64, 128), 1.0, np.float32)  # a surface at 1 unit in every direction hides the canvas
    write_image(tmp_path / "range.exr", rng)
    assert main(["canvas", str(tmp_path / "eq.exr"), "--image", str(tmp_path / "poster.exr"), *GEO,
                 "--depth", str(tmp_path / "range.exr"), "-o", str(tmp_path / "hidden.exr")]) == 0
    np.testing.assert_array_equal(read_image(tmp_path / "hidden.exr"), eq)


def test_bad_input(scene, capsys):
    tmp, view, _ = scene
    (tmp / "junk.mp4").write_bytes(b"this is not a video")
    cases = [
        (["--image", str(tmp / "poster.png"), "--center", "0", "0", "3", "--normal", "0", "0", "0",
          "--size", "1", "1"], "normal: expected a finite non-zero"),
        (["--image", str(tmp / "poster.png"), "--center", "0", "0", "3", "--normal", "0", "0", "-1",
          "--size", "0", "1"], "argument --size: expected a positive number"),  # a usage error (exit 2)
        (["--image", str(tmp / "poster.png"), "--center", "0", "0", "3", "--normal", "0", "0", "-1",
          "--up", "0", "0", "1", "--size", "1", "1"], "up: must not be parallel"),
        (["--video", str(tmp / "junk.mp4"), *GEO], "cannot open"),
        (["--video", str(tmp / "missing.mp4"), *GEO], "not found"),
        (["--video", str(tmp / "junk.mp4"), *GEO, "--size", "1", "1"], "-o: with --video"),
        (["--image", str(tmp / "poster.png"), *GEO, "--depth", str(tmp / "v.json")], "--depth"),
        (["--image", str(tmp / "poster.png"), *GEO, "--frames", "3"], "--frames"),
    ]
    for extra, match in cases:
        out = tmp / ("bad.png" if match == "-o: with --video" or "--video" not in extra else "bad_frames")
        assert main(["canvas", str(tmp / "v.json"), *extra, "-o", str(out)]) == (2 if match.startswith("argument") else 1)
        err = capsys.readouterr().err
        assert match in err, (extra, err)
        assert not out.exists()
    (tmp / "s.json").write_text(json.dumps({"strokes": [], "colour": "#fff"}))
    assert main(["canvas", str(tmp / "v.json"), "--strokes", str(tmp / "s.json"), *GEO, "-o", str(tmp / "b.png")]) == 1
    assert "unknown key 'colour'" in capsys.readouterr().err
    # an output that is an input (the poster, or the view's own colour file) is refused before any work
    assert main(["canvas", str(tmp / "v.json"), "--image", str(tmp / "poster.png"), *GEO,
                 "-o", str(tmp / "poster.png")]) == 1
    assert "refusing to overwrite an input" in capsys.readouterr().err
    color_file = json.loads((tmp / "v.json").read_text())["color"]
    snapshot = (tmp / color_file).read_bytes()
    assert main(["canvas", str(tmp / "v.json"), "--image", str(tmp / "poster.png"), *GEO,
                 "-o", str(tmp / color_file)]) == 1
    assert (tmp / color_file).read_bytes() == snapshot
    assert main(["canvas", str(tmp / "v.json"), *GEO, "-o", str(tmp / "x.png")]) == 2  # no content given


def test_a_canvas_seen_from_its_back_is_said_to_be_mirrored(scene, capsys):
    """A canvas has two faces; from behind it is drawn mirrored. With the opposite --normal a user
    saw mirrored text and no word of why: now the command says so (and only then)."""
    tmp, view, poster = scene
    back = ["--center", "0.1", "0", "3", "--normal", "-0.2", "0", "1", "--size", "1.2", "0.8"]
    assert main(["canvas", str(tmp / "v.json"), "--image", str(tmp / "poster.png"), *back, "-o", str(tmp / "b.png")]) == 0
    assert "sees its back (--normal points away from it), so it is drawn mirrored" in capsys.readouterr().err
    assert main(["canvas", str(tmp / "v.json"), "--image", str(tmp / "poster.png"), *GEO, "-o", str(tmp / "f.png")]) == 0
    assert "sees its back" not in capsys.readouterr().err
    assert not np.array_equal(read_image(tmp / "b.png"), read_image(tmp / "f.png"))


@pytest.mark.parametrize("where", [
    ["--center", "0.1", "0", "-3", "--normal", "0", "0", "1"],  # behind the camera
    ["--center", "0.3", "0.2", "2.6", "--normal", "0", "0", "-1"],  # just behind the box, hidden by it
])
def test_a_canvas_that_covers_no_pixel_is_said_so(scene, capsys, where):
    """A canvas behind the camera or hidden behind the scene left the output equal to the scene,
    exit 0 and no word (new-user review): now the command says that it covers no pixel."""
    tmp, view, poster = scene
    size = ["--size", "0.1", "0.1"]
    assert main(["canvas", str(tmp / "v.json"), "--image", str(tmp / "poster.png"), *where, *size,
                 "-o", str(tmp / "n.png")]) == 0
    assert "covers no pixel of the output" in capsys.readouterr().err
    np.testing.assert_array_equal(read_image(tmp / "n.png"), view.color)
    assert main(["canvas", str(tmp / "v.json"), "--image", str(tmp / "poster.png"), *GEO, "-o", str(tmp / "s.png")]) == 0
    assert "covers no pixel" not in capsys.readouterr().err
