"""Bad inputs (issue #12): the table in ``tests/bad_inputs.py`` and hypothesis fuzzing.

The only allowed outcomes are success or a documented exception (``ValueError``, ``TypeError``,
``FileNotFoundError``, other ``OSError`` subclasses; on the command line: exit 1 with the message,
or exit 2 for a usage error) whose message names the user's input -- never another exception,
never a changed input file, never a staging folder left behind. Bounded for CI: the hypothesis
tests are derandomized with fixed example counts (the whole file runs in well under 60 s).
"""

from __future__ import annotations

import copy
import hashlib
import json
import math
import os
import re
import shutil
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import cli
from bad_inputs import CASES, Case, make_base, view_doc

ALLOWED = (ValueError, TypeError, FileNotFoundError, OSError)


# --------------------------------------------------------------------------- fixtures and helpers
@pytest.fixture(scope="module")
def base(tmp_path_factory):
    return make_base(tmp_path_factory.mktemp("bad_inputs_base") / "base")


def snapshot(folder: Path) -> dict[str, str]:
    """Relative path -> sha256 of every file (symlinks: their target) under ``folder``."""
    out = {}
    for root, dirs, files in os.walk(folder):
        for name in files + [d for d in dirs if os.path.islink(os.path.join(root, d))]:
            p = Path(root) / name
            rel = str(p.relative_to(folder))
            out[rel] = ("link:" + os.readlink(p)) if p.is_symlink() else hashlib.sha256(p.read_bytes()).hexdigest()
    return out


def staging_left(folder: Path) -> list[str]:
    return [str(p) for p in folder.rglob(".ibr-staging-*")]


def _faces(folder: Path, drop=None):
    from ibr.io import write_image

    folder.mkdir()
    for i, n in enumerate(("px", "nx", "py", "ny", "pz", "nz")):
        if f"{n}.png" != drop:
            write_image(folder / f"{n}.png", np.full((8, 8, 3), 40 * i, np.uint8))


def prepare(case: Case, base: Path, tmp_path: Path, monkeypatch) -> Path:
    """The case's own copy of the base folder, with the case's setup applied."""
    d = tmp_path / "d"
    shutil.copytree(base, d, symlinks=True)
    x = case.extra
    if "write" in x:
        name, data = x["write"]
        (d / name).write_bytes(data if isinstance(data, bytes) else data.encode())
    if "camera" in x or "camera_wrap" in x:
        doc = json.loads((d / "cam.json").read_text())
        if "camera" in x:
            x["camera"](doc)
        if "camera_wrap" in x:
            doc = {"camera": doc, **x["camera_wrap"]}
        (d / "cam.json").write_text(json.dumps(doc))
    if "faces" in x:
        _faces(d / x["faces"], x.get("drop_face"))
    if "symlink" in x:
        name, target = x["symlink"]
        os.symlink(target, d / name)
    if "hardlink" in x:
        name, target = x["hardlink"]
        os.link(d / target, d / name)
    if "mkdir" in x:
        (d / x["mkdir"]).mkdir()
    if "dice" in x:
        import panorama
        from ibr.io import write_image

        faces = [np.full((8, 8, 3), 30 * i, np.uint8) for i in range(6)]
        write_image(d / x["dice"], panorama.pack_faces(faces, "dice"))
    if x.get("readonly"):  # root ignores permission bits: make the staging folder fail instead
        import ibr.io.outputs as outputs

        def refuse(*a, **k):
            raise PermissionError(13, "Permission denied")

        monkeypatch.setattr(outputs.tempfile, "mkdtemp", refuse)
    if x.get("copy_view_as_frame"):
        shutil.copyfile(d / "a_color.png", d / "frame_000_t0.000.png")
        doc = view_doc(d)
        doc["color"] = "frame_000_t0.000.png"
        (d / "a.json").write_text(json.dumps(doc))
    if "old_frames" in x:
        (d / x["old_frames"]).mkdir()
        (d / x["old_frames"] / "frame_009_t0.900.png").write_bytes(b"old")
        (d / x["old_frames"] / "keep.txt").write_text("mine")
    if "old_tour" in x:
        (d / x["old_tour"]).mkdir()
        (d / x["old_tour"] / "frame_0009.png").write_bytes(b"old")
        (d / x["old_tour"] / "keep.txt").write_text("mine")
    if "site_nonempty" in x:
        (d / x["site_nonempty"]).mkdir()
        (d / x["site_nonempty"] / "mine.txt").write_text("keep")
    return d


def check_inputs_kept(case: Case, d: Path, before: dict) -> None:
    after = snapshot(d)
    allowed = tuple(case.extra.get("changes", ()))
    changed = [k for k, v in before.items() if k.split(os.sep)[0] not in allowed and after.get(k) != v]
    assert not changed, f"{case.id}: input files changed or vanished: {changed}"
    assert not staging_left(d), f"{case.id}: staging folders left: {staging_left(d)}"
    for name in case.extra.get("absent", ()):
        assert not (d / name).exists(), f"{case.id}: {name} was written although the command failed"


# --------------------------------------------------------------------------- the table
def test_table_has_at_least_150_distinct_cases():
    ids = [c.id for c in CASES]
    assert len(ids) == len(set(ids)), "duplicate case ids"
    assert len(CASES) >= 150
    assert {c.expect for c in CASES} <= {"usage", "error", "ok"}


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input(case: Case, base, tmp_path, monkeypatch, capsys):
    d = prepare(case, base, tmp_path, monkeypatch)
    before = snapshot(d)
    if case.area == "view file":
        from ibr.io import load_view

        doc = view_doc(d)
        case.mutate(doc)
        (d / "bad.json").write_text(json.dumps(doc))
        before = snapshot(d)
        with pytest.raises(ALLOWED) as info:
            load_view(d / "bad.json")
        message = str(info.value)
        assert re.search(case.match, message), message
        assert "bad.json" in message  # names the user's file
        # the command line refuses it with the same message (exit 1)
        rc = cli.main(["warp", str(d / "bad.json"), "--to", str(d / "b.json"), "-o", str(d / "o.png")])
        err = capsys.readouterr().err
        assert rc == 1 and message in err, err
        assert not (d / "o.png").exists()
    elif case.argv:
        argv = [a.format(d=d) for a in case.argv]
        rc = cli.main(argv)
        err = capsys.readouterr().err
        assert rc == {"usage": 2, "error": 1, "ok": 0}[case.expect], err
        assert re.search(case.match, err), err
        assert "Traceback" not in err
    else:
        if case.expect == "ok":
            case.call(d)
        else:
            with pytest.raises(case.exc) as info:
                case.call(d)
            assert re.search(case.match, str(info.value)), str(info.value)
    check_inputs_kept(case, d, before)
    x = case.extra
    if "old_frames" in x or "old_tour" in x:
        folder = d / (x.get("old_frames") or x.get("old_tour"))
        assert (folder / "keep.txt").read_text() == "mine"  # other files untouched
        assert not any(p.read_bytes() == b"old" for p in folder.glob("frame_*"))  # stale frames gone
        assert len(list(folder.glob("frame_*"))) == 2


# --------------------------------------------------------------------------- hypothesis: view files
JSON_SCALARS = st.one_of(
    st.none(), st.booleans(), st.integers(-10**12, 10**12),
    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=8),
    st.sampled_from([0, -1, 1e-300, 1e300, 1e30, 100000, "inf", "", "../x", "/etc/hostname", "a_color.png",
                     "a_depth.exr", [], {}, [1, 2], [[1, 0, 0, 0]] * 4]),
)
KEYS = st.one_of(st.sampled_from(["format", "version", "name", "color", "depth", "camera", "path", "encoding",
                                  "scale", "near", "far", "width", "height", "fx", "fy", "cx", "cy",
                                  "world_from_cam", "pose", "dpeth", "skew", "baseline", "focal_px", "doffs"]),
                 st.text(min_size=1, max_size=6))


def _paths(doc, prefix=()):
    yield prefix
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            yield from _paths(v, prefix + (i,))


@st.composite
def mutated_view_docs(draw, base_doc):
    doc = json.loads(json.dumps(base_doc))
    for _ in range(draw(st.integers(1, 3))):
        paths = [p for p in _paths(doc) if p]
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        action = draw(st.sampled_from(["set", "delete", "add", "rename"]))
        if action == "set":
            parent[path[-1]] = copy.deepcopy(draw(JSON_SCALARS))  # sampled lists are shared objects
        elif action == "delete":
            del parent[path[-1]]
        elif action == "add" and isinstance(parent, dict):
            parent[draw(KEYS)] = copy.deepcopy(draw(JSON_SCALARS))
        elif action == "rename" and isinstance(parent, dict):
            parent[draw(KEYS)] = parent.pop(path[-1])
    return doc


@pytest.fixture(scope="module")
def fuzz_dir(base, tmp_path_factory):
    d = tmp_path_factory.mktemp("fuzz") / "d"
    shutil.copytree(base, d)
    return d


def _names_input(message: str, *names: str) -> bool:
    return any(n in message for n in names)


def test_fuzz_view_files(fuzz_dir):
    """Random mutations of a valid view file: a View or a documented error naming the file."""
    from ibr.base.view import View
    from ibr.io import load_view

    before = snapshot(fuzz_dir)
    base_doc = view_doc(fuzz_dir)

    @settings(max_examples=300, deadline=None, derandomize=True, database=None,
              suppress_health_check=[HealthCheck.too_slow])
    @given(mutated_view_docs(base_doc))
    def check(doc):
        path = fuzz_dir / "fuzz.json"
        try:
            text = json.dumps(doc)
        except (TypeError, ValueError):
            return
        path.write_text(text)
        try:
            assert isinstance(load_view(path), View)
        except ALLOWED as exc:
            assert _names_input(str(exc), "fuzz.json"), str(exc)

    check()
    after = snapshot(fuzz_dir)
    assert {k: v for k, v in after.items() if k != "fuzz.json"} == before


# --------------------------------------------------------------------------- hypothesis: camera objects
CAMERA_VALUES = st.one_of(JSON_SCALARS, st.integers(1, 4096), st.floats(1e-3, 1e4))


@settings(max_examples=300, deadline=None, derandomize=True, database=None)
@given(st.dictionaries(st.sampled_from(["width", "height", "fx", "fy", "cx", "cy", "world_from_cam", "pose", "skew"]),
                       CAMERA_VALUES, max_size=8))
def test_fuzz_camera_dicts(d):
    from ibr.base.camera import Camera

    try:
        cam = Camera.from_dict(d)
    except ALLOWED as exc:
        assert str(exc)
        return
    assert set(d) <= {"width", "height", "fx", "fy", "cx", "cy", "world_from_cam"}
    assert cam.width * cam.height <= 2**27 and cam.fx > 0 and math.isfinite(cam.cx)


# --------------------------------------------------------------------------- hypothesis: arrays
DTYPES = st.sampled_from([np.uint8, np.uint16, np.float32, np.float64, np.int8, np.int32, np.int64, np.bool_,
                          np.float16, np.complex64])
SPECIAL = st.sampled_from([0.0, -1.0, np.nan, np.inf, -np.inf, 1e-30, 1e30, 1e38, 2.0, 5.0])


@st.composite
def arrays(draw, shapes):
    shape = draw(shapes)
    dtype = draw(DTYPES)
    fill = draw(SPECIAL)
    a = np.full(shape, 2.0, np.float64)
    if a.size:
        idx = draw(st.lists(st.integers(0, a.size - 1), max_size=5))
        a.flat[idx] = fill
    with np.errstate(all="ignore"):
        return a.astype(dtype)


IMAGE_SHAPES = st.sampled_from([(12, 16), (12, 16, 3), (12, 16, 4), (12, 16, 2), (0, 16, 3), (12,), (1, 12, 16, 3),
                                (1, 1), (12, 16, 1)])


def _tiny_camera():
    from ibr.base.camera import Camera

    return Camera(14.0, 14.0, 7.5, 5.5, 16, 12)


@settings(max_examples=120, deadline=None, derandomize=True, database=None)
@given(arrays(IMAGE_SHAPES), arrays(st.sampled_from([(12, 16), (12, 16, 1), (12, 15), (12, 16, 3)])),
       st.sampled_from(["warp", "mesh", "stereo", "interpolate", "forward"]))
def test_fuzz_view_arrays_through_the_engine(color, depth, what):
    """Colour/depth arrays of any dtype, shape and value go through View and the renderers:
    success, or a documented exception naming the argument."""
    import ibr
    from ibr.base.view import View
    from ibr.stereo.pair import stereo_pair

    cam = _tiny_camera()
    try:
        v = View(color, depth, cam, "fuzz")
        other = cam.translated([0.05, 0.0, 0.0])
        if what == "warp":
            r = ibr.warp(v, other)
            assert r.color.shape[:2] == (12, 16)
        elif what == "forward":
            ibr.warp(v, other, method="forward")
        elif what == "mesh":
            ibr.build_mesh(v)
        elif what == "stereo":
            stereo_pair(v, e=0.05, f=2.0)
        else:
            ibr.interpolate(v, v, [0.5])
    except ALLOWED as exc:
        assert re.search(r"color|depth|view|camera|fuzz|target", str(exc)), str(exc)


@settings(max_examples=80, deadline=None, derandomize=True, database=None)
@given(arrays(st.sampled_from([(8, 16), (8, 16, 3), (8, 16, 1), (8, 15, 3), (8, 16, 5)])), st.booleans(),
       st.sampled_from([1, 4, 0, -2, 2.5, 200000]))
def test_fuzz_panorama_arrays(img, depth, size):
    import panorama

    try:
        panorama.equirect_to_cubemap(img, size, depth=depth)
    except ALLOWED as exc:
        assert re.search(r"image|face_size|depth", str(exc)), str(exc)
    try:
        panorama.perspective(img, yaw_deg=10.0, pitch_deg=0.0, fov_deg=80.0, width=size if isinstance(size, int) else 4,
                             height=4, depth=depth)
    except ALLOWED as exc:
        assert re.search(r"pano|width|height|depth|layout|image", str(exc)), str(exc)


@settings(max_examples=80, deadline=None, derandomize=True, database=None)
@given(arrays(st.sampled_from([(12, 16), (12, 16, 3), (12, 16, 4), (12, 16, 2)])),
       st.tuples(st.floats(allow_nan=True, allow_infinity=True), st.floats(allow_nan=True, allow_infinity=True)),
       st.sampled_from([None, 0.0, -1.0, 5.0, np.nan]))
def test_fuzz_lens(img, center, scale):
    from ibr.stereo.lens import RadialDistortion, predistort

    try:
        out = predistort(img, RadialDistortion(0.2, 0.05, 1.5), center_px=center, scale_px=scale)
        assert out.shape == img.shape and -0.5 <= center[0] <= 15.5 and -0.5 <= center[1] <= 11.5
    except ALLOWED as exc:
        assert re.search(r"image|center_px|scale_px", str(exc)), str(exc)


# --------------------------------------------------------------------------- hypothesis: command lines
NUMBERS = st.sampled_from(["0", "-1", "1", "2", "0.5", "nan", "inf", "-inf", "1e9", "200000", "x", "", "3.5", "70000"])


@st.composite
def command_lines(draw, d):
    """A command with a random subset of its options, values from NUMBERS or paths that are
    inputs, new names, names with odd extensions, folders or missing folders."""
    paths = st.sampled_from([f"{d}/{n}" for n in ("a.json", "b.json", "a_color.png", "a_depth.exr", "cam.json", "pano.png",
                                                  "img.png", "poses.json", "notes.txt", "sub", "new.png", "new.exr",
                                                  "new", "new.bmp", "nodir/x.png", "new.mp4", "newdir", "odd.png")])
    cmd = draw(st.sampled_from(["warp", "interpolate", "mesh", "stereo", "distort", "timewarp", "cubemap", "view"]))
    spec = {
        "warp": (["{a}", "--to", "{b}"], {"-o": "p", "--depth-out": "p", "--holes-out": "p", "--method": ["mesh", "forward", "x"]}),
        "interpolate": (["{a}", "{b}"], {"--frames": "n", "--t": "n", "--fps": "n", "--out": "p", "--video": "p",
                                         "--contact-sheet": "p"}),
        "mesh": (["{a}"], {"--threshold": "n", "--max-error": "n", "--baseline": "n", "--obj": "p", "--ply": "p",
                           "--viz": "p", "--viz-scale": "n"}),
        "stereo": (["{a}"], {"--e": "n", "--f": "n", "--max-angle": "n", "-o": "p",
                             "--mode": ["anaglyph", "separate", "sbs"]}),
        "distort": (["{p}", "--c1", "0.2"], {"--c2": "n", "--r-max": "n", "--scale": "n", "-o": "p"}),
        "timewarp": (["{a}", "--poses", "{p}"], {"--margin": "n", "-o": "p"}),
        "cubemap": (["{p}"], {"-o": "p", "--face-size": "n", "--width": "n"}),
        "view": (["{p}"], {"-o": "p", "--width": "n", "--height": "n", "--fov": "n", "--tour": "n", "--fps": "n"}),
    }[cmd]
    argv = [cmd]
    for a in spec[0]:
        argv.append({"{a}": f"{d}/a.json", "{b}": f"{d}/b.json", "{p}": draw(paths)}.get(a, a))
    for opt, kind in spec[1].items():
        if draw(st.booleans()):
            value = draw(paths) if kind == "p" else draw(NUMBERS) if kind == "n" else draw(st.sampled_from(kind))
            argv += [opt, value]
    # small renders keep the successful runs quick
    if cmd == "view" and "--width" not in argv:
        argv += ["--width", "16", "--height", "8"]
    if cmd == "interpolate" and "--frames" not in argv and "--t" not in argv:
        argv += ["--t", "0.5"]
    if cmd == "interpolate" and "--out" not in argv:
        argv += ["--out", f"{d}/fr"]
    return argv


def _inputs_of(argv, d: Path) -> list[Path]:
    """The input files of a command line: positional paths, --to, --poses, and the colour and
    depth files their view files name."""
    opts_with_inputs = {"--to", "--poses"}
    out = []
    for i, a in enumerate(argv[1:], 1):
        prev = argv[i - 1]
        if a.startswith(str(d)) and (not prev.startswith("-") or prev in opts_with_inputs or prev == argv[0]):
            if prev.startswith("-") and prev not in opts_with_inputs:
                continue
            out.append(Path(a))
    for p in list(out):
        if p.suffix == ".json" and p.is_file():
            try:
                doc = json.loads(p.read_text())
                out.append(p.parent / doc["color"])
                if doc.get("depth"):
                    out.append(p.parent / doc["depth"]["path"])
            except (ValueError, KeyError, TypeError):
                pass
    return [p for p in out if p.is_file()]


def test_fuzz_command_lines(base, tmp_path, capsys):
    """Random command lines over the tiny inputs: exit 0, 1 or 2, no traceback, no input file
    changed (each example starts from a fresh copy of the inputs)."""
    d = tmp_path / "d"

    @settings(max_examples=100, deadline=None, derandomize=True, database=None,
              suppress_health_check=[HealthCheck.too_slow])
    @given(command_lines(d))
    def check(argv):
        shutil.rmtree(d, ignore_errors=True)
        shutil.copytree(base, d)
        for opt in ("--frames", "--tour"):  # keep runs short: the count is checked at parse time anyway
            if opt in argv:
                i = argv.index(opt) + 1
                if argv[i] not in ("0", "-1", "nan", "inf", "-inf", "x", "", "3.5", "0.5"):
                    argv[i] = "2"
        inputs = {p: hashlib.sha256(p.read_bytes()).hexdigest() for p in _inputs_of(argv, d)}
        rc = cli.main(argv)
        err = capsys.readouterr().err
        assert rc in (0, 1, 2), (argv, err)
        assert "Traceback" not in err
        if rc == 1:
            assert err.startswith(f"ibr {argv[0]}: error: "), err
        changed = [str(p) for p, h in inputs.items() if not p.is_file() or hashlib.sha256(p.read_bytes()).hexdigest() != h]
        assert not changed, (argv, changed)
        assert not staging_left(d)

    check()
