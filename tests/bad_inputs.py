"""The table of bad inputs tried against the command line and the library (issue #12).

Every row is one distinct bad input and the outcome it must have:

* ``usage``  -- the CLI exits 2 at parse time (argparse) with a message naming the option;
* ``error``  -- the CLI exits 1 / the library raises a documented exception (``ValueError``,
  ``TypeError``, ``FileNotFoundError`` or another ``OSError`` subclass) whose message matches;
* ``ok``     -- the input is unusual but valid and gives correct output.

In every row no input file may change (``tests/test_fuzz.py`` hashes the case folder before
and after) and no staging folder may be left behind. Rows marked ``issue=True`` are the cases
listed in issue #12. The counts in README.md come from :func:`counts`.

Placeholders in command lines: ``{d}`` is the case's own copy of the base folder made by
:func:`make_base` (tiny 64x48 views ``a.json``/``b.json`` of the room scene, a bare camera
``cam.json``, a 64x32 equirect ``pano.png``, a range map ``range_neg.exr`` with negative values,
``poses.json``, and views whose depth is all NaN, 1e30 or 1e-30).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

# --------------------------------------------------------------------------- the base folder
W, H = 64, 48


def make_base(folder: Path) -> Path:
    """Write the inputs every case starts from into ``folder`` (once per test session)."""
    from ibr.io import save_view, write_depth, write_image
    from ibr.synth import make_scene, render, scene_cameras

    folder.mkdir(parents=True, exist_ok=True)
    ca, cb = scene_cameras("room", width=W, height=H)
    scene = make_scene("room")
    from ibr.base.view import View

    a, b = (render(scene, c, name=n) for c, n in ((ca, "a"), (cb, "b")))
    a, b = (View((np.clip(v.color, 0, 1) * 255 + 0.5).astype(np.uint8), v.depth, v.camera, v.name) for v in (a, b))
    save_view(a, folder / "a.json")
    save_view(b, folder / "b.json")
    (folder / "cam.json").write_text(json.dumps(cb.to_dict()))
    write_image(folder / "img.png", a.color)
    odd = np.zeros((H, W - 1, 3), np.uint8)
    write_image(folder / "odd.png", odd)
    lon = np.linspace(0, 1, 64, dtype=np.float32)
    pano = (np.stack(np.meshgrid(lon, np.linspace(0, 1, 32)), -1)[..., [0, 1, 0]] * 255).astype(np.uint8)
    write_image(folder / "pano.png", np.ascontiguousarray(pano))
    rng = np.full((32, 64), 2.0, np.float32)
    rng[10, 10] = -1.0
    write_image(folder / "range_neg.exr", rng)
    write_image(folder / "notpano.png", np.zeros((37, 100, 3), np.uint8))
    write_image(folder / "square.png", np.zeros((64, 64, 3), np.uint8))  # an ODS pair's shape (top-bottom)
    (folder / "poses.json").write_text(json.dumps([cb.world_from_cam.tolist(), ca.world_from_cam.tolist()]))
    (folder / "notes.txt").write_text("not an image\n")
    (folder / "sub").mkdir()
    # views whose depth is all NaN / absurdly far / absurdly near (written around View's checks)
    doc = json.loads((folder / "a.json").read_text())
    for name, value in (("nan", np.nan), ("far", 1e30), ("near", 1e-30)):
        write_depth(folder / f"{name}_depth.exr", np.full((H, W), value, np.float32))
        d = dict(doc, name=name, depth={"path": f"{name}_depth.exr", "encoding": "z"})
        (folder / f"{name}.json").write_text(json.dumps(d))
    return folder


def view_doc(folder: Path) -> dict:
    return json.loads((folder / "a.json").read_text())


# --------------------------------------------------------------------------- the table
@dataclass(frozen=True)
class Case:
    id: str
    area: str                      # "view file", "camera file", "cli", "outputs", "library"
    expect: str                    # "usage", "error" or "ok"
    match: str                     # regex the message (stderr or exception) must contain
    argv: tuple = ()               # CLI cases: ibr arguments with {d} placeholders
    mutate: Callable | None = None  # view/camera-file cases: doc -> None (edits in place)
    call: Callable | None = None   # library cases: call(d: Path) -> anything
    exc: tuple = ()                # library cases: allowed exception types
    issue: bool = False            # listed in issue #12
    extra: dict = field(default_factory=dict)


CASES: list[Case] = []


def _add(*args, **kw):
    CASES.append(Case(*args, **kw))


def _set(path, value):
    """A mutation setting doc[path...] = value (path: tuple of keys/indices)."""
    def f(doc):
        obj = doc
        for k in path[:-1]:
            obj = obj[k]
        obj[path[-1]] = value
    return f


def _del(path):
    def f(doc):
        obj = doc
        for k in path[:-1]:
            obj = obj[k]
        del obj[path[-1]]
    return f


def _rename(path, new):
    def f(doc):
        obj = doc
        for k in path[:-1]:
            obj = obj[k]
        obj[new] = obj.pop(path[-1])
    return f


def _all(*fs):
    def f(doc):
        for g in fs:
            g(doc)
    return f


# ---- view files: every mutation of a.json is loaded by the library AND by `ibr warp` (same message)
V = "view file"
_add("top-level key misspelled 'dpeth'", V, "error", r"unknown key 'dpeth' \(did you mean 'depth'\?\)",
     mutate=_rename(("depth",), "dpeth"), issue=True)
_add("unknown top-level key 'skew'", V, "error", r"unknown key 'skew'; allowed: format", mutate=_set(("skew",), 0.0))
_add("top-level 'colour' for 'color'", V, "error", r"unknown key 'colour' \(did you mean 'color'\?\)",
     mutate=_rename(("color",), "colour"))
_add("top-level 'cam' for 'camera'", V, "error", r"unknown key 'cam' \(did you mean 'camera'\?\)",
     mutate=_rename(("camera",), "cam"))
_add("format misspelled", V, "error", r"'format' must be 'ibr-view', got 'ibr_view'", mutate=_set(("format",), "ibr_view"))
_add("format missing", V, "error", r"'format' must be 'ibr-view', got None", mutate=_del(("format",)))
_add("version 2", V, "error", r"unsupported 'version' 2", mutate=_set(("version",), 2))
_add("version as a string", V, "error", r"unsupported 'version' '1'", mutate=_set(("version",), "1"))
_add("version true", V, "error", r"unsupported 'version' True", mutate=_set(("version",), True))
_add("name a number", V, "error", r"'name' must be a string, got 5", mutate=_set(("name",), 5))
_add("color null", V, "error", r"'color' must be a relative file name, got None", mutate=_set(("color",), None))
_add("color a number", V, "error", r"'color' must be a relative file name, got 5", mutate=_set(("color",), 5))
_add("color empty", V, "error", r"'color' must be a relative file name, got ''", mutate=_set(("color",), ""))
_add("color escapes the folder", V, "error", r"'color': expected a file name inside the view file's folder",
     mutate=_set(("color",), "../a_color.png"))
_add("color absolute path", V, "error", r"'color': expected a file name inside", mutate=_set(("color",), "/etc/hostname"))
_add("color missing file", V, "error", r"'color' refers to a missing file", mutate=_set(("color",), "nope.png"))
_add("color not an image", V, "error", r"'color': cannot read|corrupt", mutate=_set(("color",), "notes.txt"))
_add("color a folder", V, "error", r"'color' refers to a folder, not an image file", mutate=_set(("color",), "sub"))
_add("color of another size", V, "error", r"does not match the color image", mutate=_set(("color",), "odd.png"))
_add("depth a string", V, "error", r"'depth' must be null or an object", mutate=_set(("depth",), "a_depth.exr"))
_add("depth without path", V, "error", r"'depth' must be null or an object with a 'path'", mutate=_set(("depth",), {}))
_add("depth path escapes", V, "error", r"'depth': 'path': expected a file name inside",
     mutate=_set(("depth", "path"), "../x/a_depth.exr"))
_add("depth encoding unknown", V, "error", r"unknown depth encoding 'inverse'", mutate=_set(("depth", "encoding"), "inverse"))
_add("depth encoding wrong case", V, "error", r"unknown depth encoding 'Z' \(did you mean 'z'\?\)",
     mutate=_set(("depth", "encoding"), "Z"))
_add("depth encoding a number", V, "error", r"unknown depth encoding 3", mutate=_set(("depth", "encoding"), 3))
_add("depth key misspelled 'scal'", V, "error", r"unknown parameter\(s\) scal \(did you mean 'scale'\?\)",
     mutate=_set(("depth", "scal"), 1.0))
_add("depth key misspelled 'pth'", V, "error", r"'depth': unknown key 'pth' \(did you mean 'path'\?\)",
     mutate=_rename(("depth", "path"), "pth"))
_add("depth scale 0", V, "error", r"parameter 'scale' must be positive, got 0", mutate=_set(("depth", "scale"), 0))
_add("depth scale negative", V, "error", r"parameter 'scale' must be positive, got -1", mutate=_set(("depth", "scale"), -1))
_add("depth scale a string", V, "error", r"parameter 'scale' must be a finite number, got 'abc'",
     mutate=_set(("depth", "scale"), "abc"))
_add("depth scale NaN", V, "error", r"parameter 'scale' must be a finite number, got nan", mutate=_set(("depth", "scale"), math.nan))
_add("depth scale Infinity", V, "error", r"parameter 'scale' must be a finite number, got inf",
     mutate=_set(("depth", "scale"), math.inf))
_add("depth scale true", V, "error", r"parameter 'scale' must be a finite number, got True", mutate=_set(("depth", "scale"), True))
_add("depth scale tiny: depth outside the range", V, "error", r"depth: valid values must lie in",
     mutate=_set(("depth", "scale"), 1e-12))
_add("disparity without baseline", V, "error", r"encoding 'disparity' needs parameter\(s\) baseline",
     mutate=_set(("depth",), {"path": "a_depth.exr", "encoding": "disparity", "focal_px": 50, "doffs": 0}))
_add("disparity 'baselin' misspelled", V, "error", r"unknown parameter\(s\) baselin \(did you mean 'baseline'\?\)",
     mutate=_set(("depth",), {"path": "a_depth.exr", "encoding": "disparity", "baselin": 0.1, "focal_px": 50,
                              "doffs": 0}))
_add("window near > far", V, "error", r"need 0 < near < far", mutate=_set(("depth",), {"path": "a_depth.exr",
     "encoding": "window", "near": 10, "far": 1}))
_add("window near 0", V, "error", r"need 0 < near < far", mutate=_set(("depth",), {"path": "a_depth.exr",
     "encoding": "window", "near": 0, "far": 1}))
_add("fixed16 infinite far", V, "error", r"needs a finite far plane", mutate=_set(("depth",), {"path": "a_depth.exr",
     "encoding": "fixed16", "near": 0.1, "far": "inf"}))
_add("far_is_empty a string", V, "error", r"'far_is_empty' must be true or false", mutate=_set(("depth",), {
     "path": "a_depth.exr", "encoding": "fixed16", "near": 0.1, "far": 10, "far_is_empty": "yes"}))
_add("depth missing file", V, "error", r"'depth.path' refers to a missing file", mutate=_set(("depth", "path"), "nope.exr"))
_add("depth is a colour PNG (3 channels)", V, "error", r"channels \(R, G, B\) whose values differ at \d+ pixel",
     mutate=_set(("depth", "path"), "img.png"))
_add("depth of another size", V, "error", r"depth range_neg.exr is 64x32 but color", mutate=_set(("depth", "path"), "range_neg.exr"))
_add("depth a text file", V, "error", r"cannot read|corrupt", mutate=_set(("depth", "path"), "notes.txt"))
_add("camera 'pose' for world_from_cam", V, "error", r"unknown key 'pose' \(did you mean 'world_from_cam'\?\)",
     mutate=_rename(("camera", "world_from_cam"), "pose"), issue=True)
_add("camera 'world_from_camera'", V, "error", r"unknown key 'world_from_camera' \(did you mean 'world_from_cam'\?\)",
     mutate=_rename(("camera", "world_from_cam"), "world_from_camera"), issue=True)
_add("camera unknown key 'skew'", V, "error", r"unknown key 'skew'; allowed: width", mutate=_set(("camera", "skew"), 0.0),
     issue=True)
_add("camera 'Fx' wrong case", V, "error", r"unknown key 'Fx'", mutate=_rename(("camera", "fx"), "Fx"))
_add("camera width Infinity", V, "error", r"width: expected a finite number, got inf", mutate=_set(("camera", "width"), math.inf),
     issue=True)
_add("camera width 1e30", V, "error", r"exceeds the ceiling", mutate=_set(("camera", "width"), 1e30))
_add("camera 100000 x 100000", V, "error", r"exceeds the ceiling", mutate=_all(_set(("camera", "width"), 100000),
     _set(("camera", "height"), 100000)))
_add("camera width 0", V, "error", r"width: expected a number >= 1, got 0", mutate=_set(("camera", "width"), 0))
_add("camera width negative", V, "error", r"width: expected a number >= 1, got -5", mutate=_set(("camera", "width"), -5))
_add("camera width 3.5", V, "error", r"width: expected an integer, got 3.5", mutate=_set(("camera", "width"), 3.5))
_add("camera width a string", V, "error", r"width: expected an integer, got '64'", mutate=_set(("camera", "width"), "64"))
_add("camera width true", V, "error", r"width: expected an integer, got True", mutate=_set(("camera", "width"), True))
_add("camera width null", V, "error", r"width: expected an integer, got None", mutate=_set(("camera", "width"), None))
_add("camera fx 0", V, "error", r"fx: expected a positive number, got 0", mutate=_set(("camera", "fx"), 0))
_add("camera fx negative", V, "error", r"fx: expected a positive number, got -1", mutate=_set(("camera", "fx"), -1))
_add("camera fx NaN", V, "error", r"fx: expected a finite number, got nan", mutate=_set(("camera", "fx"), math.nan))
_add("camera fx 1e300", V, "error", r"fx: expected a number <= 1e\+09", mutate=_set(("camera", "fx"), 1e300))
_add("camera fx a list", V, "error", r"fx: expected a number, got \[1\]", mutate=_set(("camera", "fx"), [1]))
_add("camera cx Infinity", V, "error", r"cx: expected a finite number", mutate=_set(("camera", "cx"), -math.inf))
_add("camera cy 1e20", V, "error", r"cy: expected a number <= 1e\+09", mutate=_set(("camera", "cy"), 1e20))
_add("camera cx missing", V, "error", r"missing key\(s\) cx", mutate=_del(("camera", "cx")))
_add("camera pose 3x3", V, "error", r"world_from_cam: must be a 4x4 matrix",
     mutate=_set(("camera", "world_from_cam"), np.eye(3).tolist()))
_add("camera pose scaled (not a rotation)", V, "error", r"rotation block must be a proper rotation",
     mutate=_set(("camera", "world_from_cam"), np.diag([2.0, 2, 2, 1]).tolist()))
_add("camera pose mirrored (det -1)", V, "error", r"rotation block must be a proper rotation",
     mutate=_set(("camera", "world_from_cam"), np.diag([1.0, 1, -1, 1]).tolist()))
_add("camera pose last row", V, "error", r"last row must be \[0, 0, 0, 1\]",
     mutate=_set(("camera", "world_from_cam"), [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 1]]))
_add("camera pose with a string", V, "error", r"world_from_cam\[0\]\[1\]: expected a number, got 'a'",
     mutate=_set(("camera", "world_from_cam"), [[1, "a", 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]))
_add("camera pose with NaN", V, "error", r"world_from_cam\[1\]\[3\]: expected a finite number",
     mutate=_set(("camera", "world_from_cam"), [[1, 0, 0, 0], [0, 1, 0, math.nan], [0, 0, 1, 0], [0, 0, 0, 1]]))
_add("camera pose null", V, "error", r"world_from_cam: must be a 4x4 matrix", mutate=_set(("camera", "world_from_cam"), None))
_add("camera size differs from the image", V, "error", r"camera size 100x48 does not match the color image",
     mutate=_set(("camera", "width"), 100))
_add("camera a list", V, "error", r"camera: expected a JSON object, got list", mutate=_set(("camera",), [1, 2]))
_add("camera null", V, "error", r"camera: expected a JSON object, got NoneType", mutate=_set(("camera",), None))

# ---- whole view files and bare camera files through the CLI
C = "cli"
WARP = ("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/out.png")
_add("view file is not JSON", C, "error", r"not valid JSON", argv=("warp", "{d}/notes.txt", "--to", "{d}/b.json", "-o", "{d}/o.png"))
_add("view file missing", C, "error", r"view file: file not found", argv=("warp", "{d}/nope.json", "--to", "{d}/b.json", "-o", "{d}/o.png"))
_add("view file is a folder", C, "error", r"expected a file, got the folder", argv=("warp", "{d}/sub", "--to", "{d}/b.json", "-o", "{d}/o.png"))
_add("view file is a JSON list", C, "error", r"expected a JSON object, got list", argv=WARP, extra={"write": ("a.json", "[1, 2]")})
_add("view file empty", C, "error", r"not valid JSON", argv=WARP, extra={"write": ("a.json", "")})
_add("view file not UTF-8", C, "error", r"not valid JSON", argv=WARP, extra={"write": ("a.json", b"\xff\xfe{")})
_add("view file truncated", C, "error", r"not valid JSON", argv=WARP, extra={"write": ("a.json", '{"format": "ibr-view", ')})
_add("--to missing", C, "error", r"--to: .* does not exist", argv=("warp", "{d}/a.json", "--to", "{d}/nope.json", "-o", "{d}/o.png"))
_add("--to not JSON", C, "error", r"--to: .* is not valid JSON", argv=("warp", "{d}/a.json", "--to", "{d}/notes.txt", "-o", "{d}/o.png"))
_add("--to camera with 'pose'", C, "error", r"--to .*cam.json: camera: unknown key 'pose' \(did you mean 'world_from_cam'\?\)",
     argv=("warp", "{d}/a.json", "--to", "{d}/cam.json", "-o", "{d}/o.png"), extra={"camera": _rename(("world_from_cam",), "pose")},
     issue=True)
_add("--to camera with 'skew'", C, "error", r"unknown key 'skew'", argv=("warp", "{d}/a.json", "--to", "{d}/cam.json", "-o",
     "{d}/o.png"), extra={"camera": _set(("skew",), 0)}, issue=True)
_add("--to camera width Infinity", C, "error", r"width: expected a finite number", argv=("warp", "{d}/a.json", "--to",
     "{d}/cam.json", "-o", "{d}/o.png"), extra={"camera": _set(("width",), math.inf)}, issue=True)
_add("--to a 100000^2 camera", C, "error", r"exceeds the ceiling", argv=("warp", "{d}/a.json", "--to", "{d}/cam.json", "-o",
     "{d}/o.png"), extra={"camera": _all(_set(("width",), 100000), _set(("height",), 100000))}, issue=True)
_add("--to wrapped camera with an extra key", C, "error", r"unknown key 'extra'", argv=("warp", "{d}/a.json", "--to",
     "{d}/cam.json", "-o", "{d}/o.png"), extra={"camera_wrap": {"extra": 1}})
_add("--to wrapped camera", C, "ok", r"wrote", argv=("warp", "{d}/a.json", "--to", "{d}/cam.json", "-o", "{d}/o.png"),
     extra={"camera_wrap": {}})
_add("--to bare camera", C, "ok", r"wrote .*o.png", argv=("warp", "{d}/a.json", "--to", "{d}/cam.json", "-o", "{d}/o.png"))
_add("--to bare camera without world_from_cam (noted)", C, "ok",
     r"note: .*cam.json has no world_from_cam: camera at the origin looking down \+z",
     argv=("warp", "{d}/a.json", "--to", "{d}/cam.json", "-o", "{d}/o.png"), extra={"camera": _del(("world_from_cam",))})

GEO = ("--center", "0", "0", "4", "--normal", "0", "0", "-1", "--size", "1", "1")  # a canvas in front of a.json

# ---- outputs: extensions, folders, inputs (README: a failure never touches an existing file)
O = "outputs"
_add("warp -o the source's colour image", O, "error", r"-o: .*a_color.png is the input VIEW 'color'",
     argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/a_color.png"), issue=True)
_add("warp --depth-out the source's depth", O, "error", r"--depth-out: .*a_depth.exr is the input VIEW 'depth.path'",
     argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/o.png", "--depth-out", "{d}/a_depth.exr"), issue=True)
_add("warp -o the target's colour", O, "error", r"is the input --to 'color'",
     argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/b_color.png"))
_add("warp -o the view file", O, "error", r"has the extension '.json'|is the input VIEW", argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/a.json"))
_add("warp --holes-out the --to file", O, "error", r"--holes-out: .* is the input --to|has the extension '.json'",
     argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/o.png", "--holes-out", "{d}/b.json"))
_add("warp -o a symlink to the colour", O, "error", r"is the input VIEW 'color'",
     argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/link.png"), extra={"symlink": ("link.png", "a_color.png")})
_add("warp -o through a symlinked folder", O, "error", r"is the input VIEW 'color'",
     argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/lnk/a_color.png"), extra={"symlink": ("lnk", ".")})
_add("warp -o a hard link of the colour", O, "error", r"is the input VIEW 'color'",
     argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/hard.png"), extra={"hardlink": ("hard.png", "a_color.png")})
_add("warp --depth-out into a missing folder (existing -o kept)", O, "error", r"--depth-out: the output folder .*nodir",
     argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/img.png", "--depth-out", "{d}/nodir/d.exr"), issue=True)
_add("warp -o without extension", O, "error", r"-o: .*out has no extension; expected one of .png",
     argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/out"), issue=True)
_add("warp -o .bmp", O, "error", r"-o: .*o.bmp has the extension '.bmp'", argv=("warp", "{d}/a.json", "--to", "{d}/b.json",
     "-o", "{d}/o.bmp"), issue=True)
_add("warp -o .gif", O, "error", r"has the extension '.gif'", argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/o.gif"),
     issue=True)
_add("warp -o an existing folder", O, "error", r"-o: .*sub\.png is a folder",
     argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/sub.png"), extra={"mkdir": "sub.png"})
_add("warp -o and --depth-out the same file", O, "error", r"is also the output of -o",
     argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/o.exr", "--depth-out", "{d}/o.exr"))
_add("warp --depth-out .png (needs a scale)", O, "error", r"--depth-out: .* has the extension '.png'",
     argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/o.png", "--depth-out", "{d}/d.png"))
_add("stereo -o .pfm", O, "error", r"-o: .*s.pfm has the extension '.pfm'", argv=("stereo", "{d}/a.json", "-o", "{d}/s.pfm"))
_add("view -o .pfm from an 8-bit panorama (converted to float, was a late dtype error)", O, "ok", r"view: yaw 0",
     argv=("view", "{d}/pano.png", "-o", "{d}/v.pfm", "--width", "16", "--height", "8"))
_add("warp -o into a folder that cannot be written", O, "error", r"-o: cannot write into the folder",
     argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/o.png"), extra={"readonly": True}, issue=True)
_add("warp -o replaces an older output", O, "ok", r"wrote .*img.png",
     argv=("warp", "{d}/a.json", "--to", "{d}/b.json", "-o", "{d}/img.png"), extra={"changes": ("img.png",)})
_add("stereo -o the source's colour", O, "error", r"-o: .*a_color.png is the input VIEW 'color'",
     argv=("stereo", "{d}/a.json", "-o", "{d}/a_color.png"), issue=True)
_add("stereo --mode separate onto the colour", O, "error", r"-o \(left\): .*a_left.png is the input",
     argv=("stereo", "{d}/a.json", "-o", "{d}/a.png", "--mode", "separate"), extra={"symlink": ("a_left.png", "a_color.png")})
_add("mesh --viz the source's colour", O, "error", r"--viz: .*a_color.png is the input VIEW 'color'",
     argv=("mesh", "{d}/a.json", "--viz", "{d}/a_color.png"), issue=True)
_add("mesh --obj the view file", O, "error", r"--obj: .* has the extension '.json'", argv=("mesh", "{d}/a.json", "--obj", "{d}/a.json"))
_add("mesh --obj whose texture is an input", O, "error", r"--obj \(its texture\): .*is the input",
     argv=("mesh", "{d}/a.json", "--obj", "{d}/t.obj"), extra={"symlink": ("t_texture.png", "a_color.png")})
_add("mesh --ply whose texture is an input", O, "error", r"--ply \(its texture\): .*t_texture.png is the input VIEW 'color'",
     argv=("mesh", "{d}/a.json", "--ply", "{d}/t.ply"), extra={"symlink": ("t_texture.png", "a_color.png"), "absent": ("t.ply",)})
_add("mesh --viz .jpg", O, "error", r"--viz: .* has the extension '.jpg'; expected one of .png",
     argv=("mesh", "{d}/a.json", "--viz", "{d}/s.jpg"))
_add("cubemap -o the input", O, "error", r"-o: .*pano.png is the input INPUT", argv=("cubemap", "{d}/pano.png", "-o", "{d}/pano.png"),
     issue=True)
_add("cubemap --layout files into the input's folder of faces", O, "error", r"is the input INPUT",
     argv=("cubemap", "{d}/faces", "-o", "{d}/faces.png"), extra={"faces": "faces", "symlink": ("faces.png", "faces/px.png")})
_add("distort -o the input", O, "error", r"-o: .*img.png is the input IMAGE", argv=("distort", "{d}/img.png", "--c1", "0.2",
     "-o", "{d}/img.png"))
_add("view -o the panorama", O, "error", r"-o: .*pano.png is the input PANO", argv=("view", "{d}/pano.png", "-o", "{d}/pano.png"))
_add("view --tour frames folder is a file", O, "error", r"exists and is not a folder",
     argv=("view", "{d}/pano.png", "--tour", "2", "--width", "16", "--height", "8", "-o", "{d}/tourfile"),
     extra={"write": ("tourfile", "x")})
_add("interpolate --out is a file", O, "error", r"--out: .* exists and is not a folder",
     argv=("interpolate", "{d}/a.json", "{d}/b.json", "--out", "{d}/notes.txt"))
_add("interpolate --video onto A's colour", O, "error", r"--video: .*has the extension '.png'",
     argv=("interpolate", "{d}/a.json", "{d}/b.json", "--out", "{d}/fr", "--video", "{d}/a_color.png"))
_add("interpolate --video .txt", O, "error", r"--video: .*v.txt has the extension '.txt'; expected one of .mp4",
     argv=("interpolate", "{d}/a.json", "{d}/b.json", "--out", "{d}/fr", "--video", "{d}/v.txt"))
_add("interpolate --contact-sheet inside the new --out", O, "ok", r"wrote contact sheet .*fr/sheet.png",
     argv=("interpolate", "{d}/a.json", "{d}/b.json", "--out", "{d}/fr", "--frames", "2", "--contact-sheet", "{d}/fr/sheet.png"),
     extra={"changes": ("fr",)})
_add("interpolate --contact-sheet in a missing folder inside the new --out", O, "error",
     r"--contact-sheet: the output folder .*fr/sub of .*sheet.png does not exist",
     argv=("interpolate", "{d}/a.json", "{d}/b.json", "--out", "{d}/fr", "--contact-sheet", "{d}/fr/sub/sheet.png"),
     extra={"absent": ("fr",)})
_add("interpolate --contact-sheet .exr", O, "error", r"--contact-sheet: .* has the extension '.exr'",
     argv=("interpolate", "{d}/a.json", "{d}/b.json", "--out", "{d}/fr", "--contact-sheet", "{d}/c.exr"))
_add("interpolate --out holds an input of the frame pattern", O, "error", r"--out: .*frame_000_t0.000.png.* is the input",
     argv=("interpolate", "{d}/a.json", "{d}/b.json", "--out", "{d}"), extra={"copy_view_as_frame": True})
_add("interpolate re-run removes only its own frames", O, "ok", r"removed 1 file\(s\) of an earlier run",
     argv=("interpolate", "{d}/a.json", "{d}/b.json", "--out", "{d}/fr", "--frames", "2"),
     extra={"old_frames": "fr", "changes": ("fr",)}, issue=True)
_add("view --tour re-run removes only its own frames", O, "ok", r"removed 1 file\(s\) of an earlier run",
     argv=("view", "{d}/pano.png", "--tour", "2", "--width", "16", "--height", "8", "-o", "{d}/tour"),
     extra={"old_tour": "tour", "changes": ("tour",)}, issue=True)
_add("timewarp -o is a file", O, "error", r"-o: .* exists and is not a folder",
     argv=("timewarp", "{d}/a.json", "--poses", "{d}/poses.json", "-o", "{d}/notes.txt"))
_add("view --site non-empty without --force", O, "error", r"site: .* is not empty .*--force",
     argv=("view", "{d}/pano.png", "--serve", "--site", "{d}/sub2", "--port", "0"), extra={"site_nonempty": "sub2"}, issue=True)
_add("view --site is a file", O, "error", r"site: .* exists and is not a folder",
     argv=("view", "{d}/pano.png", "--serve", "--site", "{d}/notes.txt", "--port", "0"))
_add("view --force without --serve", O, "error", r"--force: only with --site",
     argv=("view", "{d}/pano.png", "--force", "-o", "{d}/v.png"))
_add("samples --out is a file", O, "error", r"--out: .* exists and is not a folder", argv=("samples", "--out", "{d}/notes.txt"))
_add("timewarp -o named like a file (became a folder frames.png)", O, "error", r"-o: .*frames.png is named like a file",
     argv=("timewarp", "{d}/a.json", "--poses", "{d}/poses.json", "-o", "{d}/frames.png"), extra={"absent": ("frames.png",)})
_add("cubemap --layout files -o c.png (became a folder c.png)", O, "error", r"-o: .*c.png is named like a file",
     argv=("cubemap", "{d}/pano.png", "--layout", "files", "-o", "{d}/c.png"), extra={"absent": ("c.png",)})
_add("cubemap -o a face folder whose px.png is a folder (was a bare Errno 21)", O, "error",
     r"-o: .*sub/px.png is a folder where an output file goes", argv=("cubemap", "{d}/pano.png", "-o", "{d}/sub"),
     extra={"mkdir": "sub/px.png"})
_add("canvas on a face folder -o f.png (became a folder f.png)", O, "error", r"-o: .*f.png is named like a file",
     argv=("canvas", "{d}/faces", "--image", "{d}/img.png", *GEO, "-o", "{d}/f.png"),
     extra={"faces": "faces", "absent": ("f.png",)})
_add("bench --out is a file", O, "error", r"--out: .* exists and is not a folder", argv=("bench", "synth", "--out", "{d}/notes.txt"))

# ---- command-line ranges (parse time: exit 2 before any file is touched)
U = "cli"
_add("interpolate --fps 0", U, "usage", r"argument --fps: expected a frame rate > 0",
     argv=("interpolate", "{d}/a.json", "{d}/b.json", "--frames", "24", "--video", "{d}/v.mp4", "--fps", "0"), issue=True)
_add("bench list with a topic", C, "error", r"topic: 'list' lists the benchmarks \(.*mesh.*\) and takes no other topic; "
     r"run 'ibr bench list', or 'ibr bench mesh' to run it", argv=("bench", "list", "mesh", "--out", "{d}/bench"),
     extra={"absent": ("bench",)})
_add("interpolate --fps without --video", C, "error", r"--fps: only used with --video", argv=("interpolate", "{d}/a.json",
     "{d}/b.json", "--fps", "30", "-o", "{d}/fr"), extra={"absent": ("fr",)})
_add("interpolate --fps -1", U, "usage", r"argument --fps: expected a frame rate", argv=("interpolate", "--fps", "-1"))
_add("interpolate --fps nan", U, "usage", r"argument --fps: expected a finite number", argv=("interpolate", "--fps", "nan"))
_add("interpolate --fps inf", U, "usage", r"argument --fps: expected a finite number", argv=("interpolate", "--fps", "inf"))
_add("interpolate --frames 0", U, "usage", r"argument --frames: expected a number of frames >= 1", argv=("interpolate", "--frames", "0"))
_add("interpolate --frames -3", U, "usage", r"argument --frames", argv=("interpolate", "--frames", "-3"))
_add("samples --sequence --scene unknown", U, "usage", r"argument --scene: expected one of room, .*got 'kitchen'",
     argv=("samples", "--sequence", "--scene", "kitchen"))
_add("samples --sequence --size 160x", U, "usage", r"argument --size: expected WxH .*got '160x'",
     argv=("samples", "--sequence", "--size", "160x"))
_add("interpolate --frames 2.5", U, "usage", r"argument --frames: expected an integer", argv=("interpolate", "--frames", "2.5"))
_add("interpolate --frames 10^9", U, "usage", r"argument --frames: .*<= 100000", argv=("interpolate", "--frames", "1000000000"))
_add("interpolate --t nan", U, "usage", r"argument --t: expected a finite number", argv=("interpolate", "--t", "nan"))
_add("interpolate --t x", U, "usage", r"argument --t: expected a number, got 'x'", argv=("interpolate", "--t", "x"))
_add("interpolate one view", C, "error", r"views: expected two view files", argv=("interpolate", "{d}/a.json"))
_add("interpolate mistyped sequence", C, "error", r"SEQ: file not found: .*nope\.json",
     argv=("interpolate", "{d}/seq/nope.json", "--factor", "4"))
_add("interpolate three views", C, "error", r"views: expected two view files", argv=("interpolate", "{d}/a.json", "{d}/b.json",
     "{d}/a.json"))
_add("interpolate --scene with views", C, "error", r"--scene: only used without view files",
     argv=("interpolate", "{d}/a.json", "{d}/b.json", "--scene", "room", "--out", "{d}/fr"))
_add("interpolate unknown --scene", U, "usage", r"argument --scene: invalid choice: 'nope' \(choose from 'room', 'clutter', "
     r"'grazing'\)", argv=("interpolate", "--scene", "nope", "--out", "{d}/fr"), extra={"absent": ("fr",)})
_add("interpolate --t outside [0, 1] (extrapolation)", C, "ok", r"wrote 1 frame ",
     argv=("interpolate", "{d}/a.json", "{d}/b.json", "--t", "1.25", "--out", "{d}/fr"), extra={"changes": ("fr",)})
_add("mesh --viz-scale 1000", U, "usage", r"argument --viz-scale: expected a scale >= 1 and <= 64", argv=("mesh", "{d}/a.json",
     "--viz", "{d}/v.png", "--viz-scale", "1000"), issue=True)
_add("mesh --viz-scale 0", U, "usage", r"argument --viz-scale", argv=("mesh", "{d}/a.json", "--viz-scale", "0"))
_add("mesh --threshold -1", U, "usage", r"argument --threshold: expected a positive number", argv=("mesh", "{d}/a.json",
     "--threshold", "-1"))
_add("mesh --threshold nan", U, "usage", r"argument --threshold: expected a finite number", argv=("mesh", "{d}/a.json",
     "--threshold", "nan"))
_add("mesh --max-error 0", U, "usage", r"argument --max-error: expected a positive number", argv=("mesh", "{d}/a.json",
     "--max-error", "0"))
_add("mesh --baseline -2", U, "usage", r"argument --baseline", argv=("mesh", "{d}/a.json", "--baseline", "-2"))
_add("mesh --threshold with --max-error", U, "usage", r"not allowed with argument", argv=("mesh", "{d}/a.json", "--threshold",
     "1", "--max-error", "1"))
_add("stereo --e -1", U, "usage", r"argument --e: expected a number >= 0", argv=("stereo", "{d}/a.json", "--e", "-1", "--f", "2",
     "-o", "{d}/s.png"))
_add("stereo --f 0", U, "usage", r"argument --f: expected a positive number", argv=("stereo", "{d}/a.json", "--f", "0", "-o",
     "{d}/s.png"))
_add("stereo --max-angle 0", U, "usage", r"argument --max-angle: expected an angle > 0", argv=("stereo", "{d}/a.json",
     "--max-angle", "0", "-o", "{d}/s.png"))
_add("stereo --max-angle 95", U, "usage", r"argument --max-angle: .*<= 10", argv=("stereo", "{d}/a.json", "--max-angle", "95",
     "-o", "{d}/s.png"))
_add("stereo --mode unknown", U, "usage", r"argument --mode: invalid choice", argv=("stereo", "{d}/a.json", "--mode", "3d",
     "-o", "{d}/s.png"))
_add("stereo --interpolation cubic", U, "usage", r"argument --interpolation: invalid choice",
     argv=("stereo", "{d}/a.json", "--interpolation", "cubic", "-o", "{d}/s.png"))
_add("stereo --interpolation sharp --method mesh", C, "error", r"interpolation: 'sharp' needs method='pixel'",
     argv=("stereo", "{d}/a.json", "--interpolation", "sharp", "--method", "mesh", "-o", "{d}/s.png"))
_add("interpolate --antialias --method forward", C, "error", r"antialias: the edge subsamples trace the quad mesh, "
     r"so it needs method='mesh'", argv=("interpolate", "{d}/a.json", "{d}/b.json", "--method", "forward", "--antialias",
                                         "--out", "{d}/fr"))
_add("stereo --auto with --e", C, "error", r"--auto: give either --auto or --e/--f", argv=("stereo", "{d}/a.json", "--auto",
     "--e", "0.1", "--f", "2", "-o", "{d}/s.png"))
_add("stereo --e without --f", C, "error", r"--e: needs --f", argv=("stereo", "{d}/a.json", "--e", "0.1", "-o", "{d}/s.png"))
_add("stereo --e absurd for --f", C, "error", r"e: the zero-parallax shift .* exceeds 10 image widths",
     argv=("stereo", "{d}/a.json", "--e", "1e6", "--f", "1", "-o", "{d}/s.png"))
_add("stereo on all-NaN depth", C, "error", r"VIEW: \S*/nan.json: the depth has no valid pixel", argv=("stereo", "{d}/nan.json", "-o",
     "{d}/s.png"))
_add("stereo on depth 1e30", C, "error", r"nan.json|far.json: depth: valid values must lie in \[1e-06, 1e\+09\]",
     argv=("stereo", "{d}/far.json", "-o", "{d}/s.png"), issue=True)
_add("warp on depth 1e-30", C, "error", r"near.json: depth: valid values must lie in", argv=("warp", "{d}/near.json", "--to",
     "{d}/b.json", "-o", "{d}/o.png"), issue=True)
_add("warp on all-NaN depth", C, "error", r"VIEW: \S*/nan.json: the depth has no valid pixel \(NaN, zero, negative or infinite everywhere\), so it cannot be a source", argv=("warp", "{d}/nan.json", "--to", "{d}/b.json", "-o",
     "{d}/o.png"))
_add("interpolate B on all-NaN depth (the file named, not its 'name')", C, "error",
     r"error: B: \S*/nan.json: the depth has no valid pixel", argv=("interpolate", "{d}/a.json", "{d}/nan.json", "--out", "{d}/fr"),
     extra={"absent": ("fr",)})
_add("mesh on all-NaN depth", C, "error", r"error: VIEW: \S*/nan.json: the depth has no valid pixel .*so it has no mesh",
     argv=("mesh", "{d}/nan.json", "--viz", "{d}/seg.png"), extra={"absent": ("seg.png",)})
_add("warp --method unknown", U, "usage", r"argument --method: invalid choice", argv=("warp", "{d}/a.json", "--to", "{d}/b.json",
     "-o", "{d}/o.png", "--method", "magic"))
_add("warp without --to", U, "usage", r"the following arguments are required: --to", argv=("warp", "{d}/a.json", "-o", "{d}/o.png"))
_add("distort --center 5000 5000", C, "error", r"--center: expected a lens centre inside the image",
     argv=("distort", "{d}/img.png", "--c1", "0.2", "--center", "5000", "5000", "-o", "{d}/o.png"), issue=True)
_add("distort --center nan 0", U, "usage", r"argument --center: expected a finite number", argv=("distort", "{d}/img.png",
     "--c1", "0.2", "--center", "nan", "0", "-o", "{d}/o.png"))
_add("distort --c1 nan", U, "usage", r"argument --c1: expected a finite number", argv=("distort", "{d}/img.png", "--c1", "nan",
     "-o", "{d}/o.png"))
_add("distort --r-max 0", U, "usage", r"argument --r-max: expected a positive number", argv=("distort", "{d}/img.png", "--c1",
     "0.2", "--r-max", "0", "-o", "{d}/o.png"))
_add("distort --r-max 1e200", C, "error", r"r_max: expected a number <= 1000", argv=("distort", "{d}/img.png", "--c1",
     "0.2", "--r-max", "1e200", "-o", "{d}/o.png"))  # r_max^2 overflowed (traceback)
_add("canvas --fps inf", U, "usage", r"argument --fps: expected a finite number", argv=(
     "canvas", "{d}/a.json", "--image", "{d}/img.png", "--center", "0", "0", "4", "--normal", "0", "0", "-1", "--size", "1",
     "1", "--fps", "inf", "-o", "{d}/o.png"))  # cv2.VideoWriter spun forever at fps = inf
_add("distort --scale -1", U, "usage", r"argument --scale", argv=("distort", "{d}/img.png", "--c1", "0.2", "--scale", "-1",
     "-o", "{d}/o.png"))
_add("distort --chromatic 0 1", U, "usage", r"argument --chromatic: expected a positive number", argv=("distort", "{d}/img.png",
     "--c1", "0.2", "--chromatic", "0", "1", "-o", "{d}/o.png"))
_add("distort --centers without --sbs", C, "error", r"--centers: only with --sbs", argv=("distort", "{d}/img.png", "--c1", "0.2",
     "--centers", "1", "1", "2", "2", "-o", "{d}/o.png"))
_add("distort --sbs on an odd width", C, "error", r"--sbs needs an even width, got 63", argv=("distort", "{d}/odd.png", "--c1",
     "0.2", "--sbs", "-o", "{d}/o.png"))
_add("distort IMAGE missing", C, "error", r"image: file not found", argv=("distort", "{d}/nope.png", "--c1", "0.2", "-o",
     "{d}/o.png"))
_add("distort IMAGE not an image", C, "error", r"cannot read", argv=("distort", "{d}/notes.txt", "--c1", "0.2", "-o", "{d}/o.png"))
_add("distort --center on the edge (valid)", C, "ok", r"distort: pre-distortion", argv=("distort", "{d}/img.png", "--c1", "0.2",
     "--center", "-0.5", "47.5", "-o", "{d}/o.png"))
_add("timewarp --margin -1", U, "usage", r"argument --margin: expected an integer >= 0", argv=("timewarp", "{d}/a.json",
     "--poses", "{d}/poses.json", "-o", "{d}/tw", "--margin", "-1"))
_add("timewarp --margin too large", C, "error", r"--margin: expected 0 <= margin < half the view size",
     argv=("timewarp", "{d}/a.json", "--poses", "{d}/poses.json", "-o", "{d}/tw", "--margin", "500"))
_add("timewarp poses missing", C, "error", r"--poses: .* does not exist", argv=("timewarp", "{d}/a.json", "--poses",
     "{d}/nope.json", "-o", "{d}/tw"))
_add("timewarp poses not JSON", C, "error", r"--poses: .* is not valid JSON", argv=("timewarp", "{d}/a.json", "--poses",
     "{d}/notes.txt", "-o", "{d}/tw"))
_add("timewarp poses empty", C, "error", r"--poses: expected a non-empty list", argv=("timewarp", "{d}/a.json", "--poses",
     "{d}/poses.json", "-o", "{d}/tw"), extra={"write": ("poses.json", "[]")})
_add("timewarp pose 3x3", C, "error", r"pose 0: expected a 4x4 matrix", argv=("timewarp", "{d}/a.json", "--poses",
     "{d}/poses.json", "-o", "{d}/tw"), extra={"write": ("poses.json", "[[[1,0,0],[0,1,0],[0,0,1]]]")})
_add("timewarp pose with NaN", C, "error", r"pose 0: \[0\]\[3\]: expected a finite number", argv=("timewarp", "{d}/a.json",
     "--poses", "{d}/poses.json", "-o", "{d}/tw"),
     extra={"write": ("poses.json", "[[[1,0,0,NaN],[0,1,0,0],[0,0,1,0],[0,0,0,1]]]")})
_add("timewarp camera pose with 'pose' key", C, "error", r"pose 0: camera: unknown key 'pose'", argv=("timewarp", "{d}/a.json",
     "--poses", "{d}/poses.json", "-o", "{d}/tw"), extra={"write": ("poses.json", json.dumps([{"width": 64, "height": 48,
     "fx": 50, "fy": 50, "cx": 31.5, "cy": 23.5, "pose": np.eye(4).tolist()}]))})
_add("cubemap --face-size 200000", U, "usage", r"argument --face-size: expected a size in pixels >= 1 and <= 32768",
     argv=("cubemap", "{d}/pano.png", "-o", "{d}/c.png", "--face-size", "200000"), issue=True)
_add("cubemap --face-size 0", U, "usage", r"argument --face-size", argv=("cubemap", "{d}/pano.png", "-o", "{d}/c.png",
     "--face-size", "0"))
_add("cubemap --face-size 20000 (six faces over the ceiling)", C, "error", r"face_size: .*exceeds the ceiling",
     argv=("cubemap", "{d}/pano.png", "-o", "{d}/c.png", "--face-size", "20000"))
_add("cubemap --width odd", C, "error", r"--width: expected an even number", argv=("cubemap", "{d}/c.png", "-o", "{d}/e.png",
     "--width", "33"), extra={"dice": "c.png"})
_add("cubemap --depth on a negative range map", C, "error", r"image: depth must be positive .*1 negative value",
     argv=("cubemap", "{d}/range_neg.exr", "--depth", "-o", "{d}/c.exr"), issue=True)
_add("stitch --panorama with a negative range (named as the option, was the library's range_)", C, "error",
     r"--panorama RANGE: expected positive ranges", argv=("stitch", "--panorama", "{d}/pano.png", "{d}/range_neg.exr",
     "--stereo", "ods", "-o", "{d}/ods.png"))
_add("cubemap --depth to .png", C, "error", r"-o: depth is float", argv=("cubemap", "{d}/range_neg.exr", "--depth", "-o",
     "{d}/c.png"))
_add("cubemap --ext .bmp", C, "error", r"--ext: expected one of", argv=("cubemap", "{d}/pano.png", "-o", "{d}/faces",
     "--ext", ".bmp"))
_add("cubemap input missing", C, "error", r"pano: file or folder not found", argv=("cubemap", "{d}/nope.png", "-o", "{d}/c.png"))
_add("view a square image (an ODS pair?)", C, "error", r"cannot tell the layout of a 64 x 64 image.*--stereo top-bottom",
     argv=("view", "{d}/square.png", "-o", "{d}/v.png"))
_add("cubemap input not a panorama shape", C, "error", r"cannot tell the layout|layout", argv=("cubemap", "{d}/notpano.png",
     "-o", "{d}/c.png"))
_add("cubemap face folder missing a face", C, "error", r"no face file nz", argv=("cubemap", "{d}/faces", "-o", "{d}/e.png"),
     extra={"faces": "faces", "drop_face": "nz.png"})
_add("cubemap -o a face folder from a cubemap", C, "error", r"-o: .* names a face folder, but INPUT is already a cubemap",
     argv=("cubemap", "{d}/c.png", "-o", "{d}/faces2"), extra={"dice": "c.png"})
_add("view --width 200000", U, "usage", r"argument --width: expected a size in pixels", argv=("view", "{d}/pano.png",
     "--width", "200000", "-o", "{d}/v.png"), issue=True)
_add("view --width 30000 --height 30000 (pixel ceiling)", C, "error", r"width, height: 30000x30000 = .*exceeds the ceiling",
     argv=("view", "{d}/pano.png", "--width", "30000", "--height", "30000", "-o", "{d}/v.png"))
_add("view --height 0", U, "usage", r"argument --height", argv=("view", "{d}/pano.png", "--height", "0", "-o", "{d}/v.png"))
_add("view --fov 0", U, "usage", r"argument --fov: expected an angle > 0 and < 180", argv=("view", "{d}/pano.png", "--fov", "0",
     "-o", "{d}/v.png"))
_add("view --fov 180", U, "usage", r"argument --fov", argv=("view", "{d}/pano.png", "--fov", "180", "-o", "{d}/v.png"))
_add("view --yaw nan", U, "usage", r"argument --yaw: expected a finite number", argv=("view", "{d}/pano.png", "--yaw", "nan",
     "-o", "{d}/v.png"))
_add("view --tour 0", U, "usage", r"argument --tour", argv=("view", "{d}/pano.png", "--tour", "0", "-o", "{d}/t.gif"))
_add("view --tour 3 --fps 0", U, "usage", r"argument --fps: expected a frame rate > 0", argv=("view", "{d}/pano.png", "--tour",
     "3", "--fps", "0", "-o", "{d}/t.gif"), issue=True)
_add("view --serve --port 70000", U, "usage", r"argument --port: expected a port", argv=("view", "{d}/pano.png", "--serve",
     "--port", "70000"), issue=True)
_add("view --port -1", U, "usage", r"argument --port", argv=("view", "{d}/pano.png", "--serve", "--port", "-1"))
_add("view without -o", C, "error", r"-o/--output: required unless --serve", argv=("view", "{d}/pano.png"))
_add("view -o .bmp", O, "error", r"-o: .*v.bmp has the extension '.bmp'", argv=("view", "{d}/pano.png", "-o", "{d}/v.bmp"))
_add("view --tour -o .txt", O, "error", r"-o: .*t.txt has the extension '.txt'; expected one of .gif",
     argv=("view", "{d}/pano.png", "--tour", "2", "-o", "{d}/t.txt"))
# options that had no effect where they were given (exit 0, silently ignored), library words
_add("view -o with --site (the still was never written)", C, "error", r"-o: not used with --serve/--site",
     argv=("view", "{d}/pano.png", "-o", "{d}/v.png", "--site", "{d}/site"), extra={"absent": ("site", "v.png")})
_add("view --tiles for a still", C, "error", r"--tiles: only with --serve/--site", argv=("view", "{d}/pano.png",
     "--tiles", "-o", "{d}/v.png"), extra={"absent": ("v.png",)})
_add("view --face-size for a still", C, "error", r"--face-size: only with --serve/--site", argv=("view", "{d}/pano.png",
     "--face-size", "8", "-o", "{d}/v.png"), extra={"absent": ("v.png",)})
_add("view --fps for a still", C, "error", r"--fps: only with --tour and an animation -o", argv=("view", "{d}/pano.png",
     "--fps", "5", "-o", "{d}/v.png"), extra={"absent": ("v.png",)})
_add("view --tour --fps into a frames folder", C, "error", r"--fps: only with --tour and an animation -o",
     argv=("view", "{d}/pano.png", "--tour", "2", "--fps", "5", "-o", "{d}/tour"), extra={"absent": ("tour",)})
_add("view --head-box without --depth", C, "error", r"--head-box: only with --depth", argv=("view", "{d}/pano.png",
     "--head-box", "1", "-o", "{d}/v.png"), extra={"absent": ("v.png",)})
_add("view --stereo-out without --stereo", C, "error", r"--stereo-out: only with --stereo", argv=("view", "{d}/pano.png",
     "--stereo-out", "sbs", "-o", "{d}/v.png"), extra={"absent": ("v.png",)})
_add("view --port with --site only", C, "error", r"--port: only with --serve", argv=("view", "{d}/pano.png", "--site",
     "{d}/site", "--port", "0"), extra={"absent": ("site",)})
_add("view --yaw with --site only (the site stores no view)", C, "error", r"--yaw: only with --serve",
     argv=("view", "{d}/pano.png", "--site", "{d}/site", "--yaw", "30"), extra={"absent": ("site",)})
_add("view --width with --serve", C, "error", r"--width: not used with --serve/--site", argv=("view", "{d}/pano.png",
     "--serve", "--width", "16"))
_add("view --layout with --stereo (read as an equirect pair)", C, "error", r"--layout: a --stereo panorama is an equirect",
     argv=("view", "{d}/pano.png", "--stereo", "sbs", "--layout", "dice", "-o", "{d}/v.png"))
_add("view --fov 1e-6 (was the library's fx)", C, "error", r"--fov: expected at least .* degrees at --width 32",
     argv=("view", "{d}/pano.png", "--fov", "1e-6", "--width", "32", "--height", "16", "-o", "{d}/v.png"))
_add("view of no known layout names --layout (was layout=)", C, "error", r"or pass --layout\n",
     argv=("view", "{d}/notpano.png", "-o", "{d}/v.png"))
_add("cubemap of no known layout names --input-layout (was layout=)", C, "error", r"or pass --input-layout\n",
     argv=("cubemap", "{d}/notpano.png", "-o", "{d}/c.png"))
_add("cubemap --depth on a colour image to .png (was '-o: depth is float')", C, "error",
     r"INPUT: .*pano.png is not a depth/range map but an 8-bit colour image", argv=("cubemap", "{d}/pano.png", "--depth",
     "-o", "{d}/c.png"))
_add("cubemap --depth on a colour image to .exr (was the library's image:)", C, "error",
     r"INPUT: .*pano.png is not a depth/range map but an 8-bit colour image", argv=("cubemap", "{d}/pano.png", "--depth",
     "-o", "{d}/c.exr"), extra={"absent": ("c.exr",)})
_add("stereo --max-angle 90 (60-70 % disocclusion)", U, "usage",
     r"argument --max-angle: expected an angle > 0 and <= 10, got 90 \(.*comfortable", argv=("stereo", "{d}/a.json",
     "--max-angle", "90", "-o", "{d}/s.png"))
_add("stereo --max-angle 10 (the ceiling, valid)", C, "ok", r"stereo: wrote", argv=("stereo", "{d}/a.json",
     "--max-angle", "10", "-o", "{d}/s.png"))
_add("stereo --video on one view", C, "error", r"--video: only used with a sequence", argv=("stereo", "{d}/a.json",
     "--video", "{d}/v.mp4", "-o", "{d}/s.png"), extra={"absent": ("s.png", "v.mp4")})
_add("stereo --fps on one view", C, "error", r"--fps: only used with a sequence", argv=("stereo", "{d}/a.json",
     "--fps", "5", "-o", "{d}/s.png"), extra={"absent": ("s.png",)})
_add("stereo SEQ --fps without --video", C, "error", r"--fps: only with --video", argv=("stereo", "{d}/sub", "--fps", "5",
     "-o", "{d}/st"), extra={"absent": ("st",)})
_add("stereo on an image (was a JSON codec error)", C, "error", r"view file .*img.png: an image, not a JSON file \(a view file is .json",
     argv=("stereo", "{d}/img.png", "-o", "{d}/s.png"))
_add("timewarp on an image (was a JSON codec error)", C, "error", r"img.png: an image, not a JSON file",
     argv=("timewarp", "{d}/img.png", "--poses", "{d}/poses.json", "-o", "{d}/tw"))
_add("canvas --video a still image", C, "error", r"--video: .*img.png is a still image; use --image",
     argv=("canvas", "{d}/a.json", "--video", "{d}/img.png", *GEO, "-o", "{d}/fr"), extra={"absent": ("fr",)})
_add("canvas --fps with a frames folder", C, "error", r"--fps: only with a video file -o",
     argv=("canvas", "{d}/a.json", "--video", "{d}/v.mp4", "--fps", "5", *GEO, "-o", "{d}/fr"), extra={"absent": ("fr",)})
_add("canvas --video on a face folder (was a traceback)", C, "error", r"--video: not on a folder of faces",
     argv=("canvas", "{d}/faces", "--video", "{d}/v.mp4", *GEO, "-o", "{d}/fr.mp4"), extra={"faces": "faces"})
_add("bench unknown topic", C, "error", r"topic: expected one of", argv=("bench", "nosuch", "--out", "{d}/bench"))
_add("unknown command", U, "usage", r"invalid choice", argv=("warpp",))
_add("unknown option (told with the command's usage)", U, "usage", r"(?s)usage: ibr samples .*ibr samples: error: unrecognized arguments: --bogus",
     argv=("samples", "--bogus"))

# ---- the library refuses what the CLI refuses (same checks, same messages)
L = "library"


def _view(d, **kw):
    from ibr.io import load_view

    v = load_view(d / "a.json")
    args = dict(color=v.color, depth=v.depth, camera=v.camera, name="a")
    args.update(kw)
    from ibr.base.view import View

    return View(**args)


def _lib(id, expect, match, call, exc=(ValueError,), issue=False):
    _add(id, L, expect, match, call=call, exc=exc, issue=issue)


_lib("View colour int8", "error", r"color: expected a colour dtype uint8, uint16, float32, float64, got int8",
     lambda d: _view(d, color=np.zeros((H, W, 3), np.int8)), (TypeError,), issue=True)
_lib("View colour bool", "error", r"color: expected a colour dtype .* got bool", lambda d: _view(d, color=np.zeros((H, W), bool)),
     (TypeError,), issue=True)
_lib("View colour int64", "error", r"got int64", lambda d: _view(d, color=np.zeros((H, W, 3), np.int64)), (TypeError,), issue=True)
_lib("View colour float16", "error", r"got float16", lambda d: _view(d, color=np.zeros((H, W, 3), np.float16)), (TypeError,))
_lib("View colour complex", "error", r"expected dtype of kind|got complex",
     lambda d: _view(d, color=np.zeros((H, W, 3), np.complex64)), (TypeError, ValueError))
_lib("View colour object", "error", r"expected a numeric array, got dtype object",
     lambda d: _view(d, color=np.empty((H, W, 3), object)), (TypeError,))
_lib("View colour 2 channels", "error", r"color: expected 1 or 3 or 4 channels", lambda d: _view(d, color=np.zeros((H, W, 2),
     np.uint8)))
_lib("View colour 4-D", "error", r"color: expected 2 or 3 dimensions", lambda d: _view(d, color=np.zeros((1, H, W, 3), np.uint8)))
_lib("View colour 0 x 0", "error", r"color: image must be at least 1x1", lambda d: _view(d, color=np.zeros((0, 0, 3), np.uint8)))
_lib("View colour size differs from the camera", "error", r"color: size 10x10 does not match camera size",
     lambda d: _view(d, color=np.zeros((10, 10, 3), np.uint8)))
_lib("View depth of another size", "error", r"depth: size 10x10 does not match color size",
     lambda d: _view(d, depth=np.ones((10, 10), np.float32)))
_lib("View depth with 3 channels", "error", r"depth: expected 1 channels", lambda d: _view(d, depth=np.ones((H, W, 3), np.float32)))
_lib("View depth 1e-30", "error", r"depth: valid values must lie in", lambda d: _view(d, depth=np.full((H, W), 1e-30)), issue=True)
_lib("View depth 1e30", "error", r"depth: valid values must lie in", lambda d: _view(d, depth=np.full((H, W), 1e30)), issue=True)
_lib("View camera not a Camera", "error", r"camera: expected a Camera, got dict", lambda d: _view(d, camera={}), (TypeError,))
_lib("View depth NaN/inf/negative become invalid (valid)", "ok", "",
     lambda d: _check(np.isnan(_view(d, depth=np.array([[np.nan, np.inf, -1.0, 0.0] * (W // 4)] * H)).depth).all()))
_lib("Camera fx 0", "error", r"fx: expected a positive number", lambda d: _camera(fx=0))
_lib("Camera 100000 x 100000", "error", r"camera: 100000x100000 exceeds the ceiling", lambda d: _camera(width=100000,
     height=100000), issue=True)
_lib("Camera width True", "error", r"width: expected a positive integer, got True", lambda d: _camera(width=True))
_lib("Camera cx NaN", "error", r"cx: expected a finite number", lambda d: _camera(cx=math.nan))
_lib("Camera.from_dict 'pose'", "error", r"unknown key 'pose' \(did you mean 'world_from_cam'\?\)",
     lambda d: _from_dict(_rename(("world_from_cam",), "pose")), issue=True)
_lib("Camera.from_dict a list", "error", r"camera: expected a JSON object, got list", lambda d: _camera_from([1]), (TypeError,))
_lib("load_camera 'pose'", "error", r"camera file .*cam_bad.json: camera: unknown key 'pose'",
     lambda d: _load_camera(d, _rename(("world_from_cam",), "pose")))
_lib("save_view colour name escapes the folder", "error", r"color_name: expected a file name inside the view file's folder",
     lambda d: _save(d, color_name="../x.png"), issue=True)
_lib("save_view colour name absolute", "error", r"color_name: expected a file name inside", lambda d: _save(d, color_name="/tmp/x.png"))
_lib("save_view depth name escapes", "error", r"depth_name: expected a file name inside", lambda d: _save(d, depth_name="../d.exr"))
_lib("save_view path not .json", "error", r"path: a view file must end in .json", lambda d: _save(d, path="v.txt"))
_lib("save_view a dict, not a View", "error", r"view: expected an ibr View, got dict", lambda d: _save(d, view={}), (TypeError,))
_lib("save_view into a missing folder", "error", r"path: output folder .* does not exist", lambda d: _save(d, path="no/v.json"),
     (FileNotFoundError,))
_lib("save_view colour and depth on one name", "error", r"must be distinct", lambda d: _save(d, color_name="x.exr",
     depth_name="x.exr"))
_lib("stereo_pair on all-NaN depth (as the CLI)", "error", r"view 'a': the depth has no valid pixel \(NaN, zero, negative or infinite everywhere\); a stereo pair",
     lambda d: _stereo(d, depth=np.full((H, W), np.nan)), issue=True)
_lib("stereo_pair e negative", "error", r"e: expected an interaxial >= 0", lambda d: _stereo(d, e=-1))
_lib("stereo_pair e absurd", "error", r"e: the zero-parallax shift", lambda d: _stereo(d, e=1e9))
_lib("stereo_pair method unknown", "error", r"method: expected one of", lambda d: _stereo(d, method="magic"))
_lib("predistort centre far outside (1e5, 1e5)", "error", r"center_px: expected a lens centre inside the image",
     lambda d: _predistort(center_px=(1e5, 1e5)), issue=True)
_lib("predistort centre NaN", "error", r"center_px: expected a lens centre inside", lambda d: _predistort(center_px=(math.nan, 0)))
_lib("predistort centre of 3 numbers", "error", r"center_px: expected shape \(2\)", lambda d: _predistort(center_px=(1, 2, 3)))
_lib("predistort scale 0", "error", r"scale_px: expected a positive number", lambda d: _predistort(scale_px=0))
_lib("equirect_to_cubemap negative range", "error", r"image: depth must be positive", lambda d: _e2c(depth=True, neg=True),
     issue=True)
_lib("equirect_to_cubemap face_size 200000", "error", r"face_size: .*exceeds the ceiling", lambda d: _e2c(face_size=200000),
     issue=True)
_lib("equirect_to_cubemap face_size 2.5", "error", r"face_size: expected a positive integer", lambda d: _e2c(face_size=2.5))
_lib("equirect_to_cubemap not 2:1", "error", r"must be 2:1", lambda d: _e2c(shape=(10, 30)))
_lib("perspective 200000 wide", "error", r"width, height: .*exceeds the ceiling", lambda d: _persp(width=200000), issue=True)
_lib("perspective fov 180", "error", r"fov_deg: expected 0 < fov_deg < 180", lambda d: _persp(fov_deg=180))
_lib("cubemap_to_equirect odd width", "error", r"must be 2:1", lambda d: _c2e(width=33, height=16))
_lib("write_image .bmp", "error", r"array: unsupported extension '.bmp'", lambda d: _write(d, "x.bmp"))
_lib("write_image float64 as .png", "error", r"a .png file stores uint8 or uint16, got float64",
     lambda d: _write(d, "x.png", np.zeros((4, 4), np.float64)))
_lib("write_image uint16 as .jpg", "error", r"a .jpg file stores uint8, got uint16", lambda d: _write(d, "x.jpg",
     np.zeros((4, 4), np.uint16)))
_lib("write_image into a missing folder", "error", r"output folder .* does not exist", lambda d: _write(d, "no/x.png"),
     (FileNotFoundError,))
_lib("write_depth .png without scale", "error", r"scale: a 16-bit PNG depth needs `scale`", lambda d: _write_depth(d, "z.png"))
_lib("write_depth values beyond 16-bit codes", "error", r"codes .*a 16-bit PNG holds 1..65535",
     lambda d: _write_depth(d, "z.png", scale=1e-9))
_lib("read_image missing", "error", r"image: file not found", lambda d: _read(d / "nope.png"), (FileNotFoundError,))
_lib("read_image a text file", "error", r"cannot read", lambda d: _read(d / "notes.txt"))
_lib("read_pfm bad header", "error", r"not a PFM file", lambda d: _read(_file(d, "bad.pfm", b"P7\n1 1\n-1\n")))
_lib("read_pfm header 100000 x 100000", "error", r"pfm .*exceeds the ceiling",
     lambda d: _read(_file(d, "big.pfm", b"Pf\n100000 100000\n-1.0\n" + b"\0" * 16)))
_lib("read_pfm truncated", "error", r"truncated PFM file", lambda d: _read(_file(d, "short.pfm", b"Pf\n4 4\n-1.0\n" + b"\0" * 8)))
_lib("write_segmentation_png scale 1000", "error", r"scale: .*exceeds the ceiling",
     lambda d: _seg(d, scale=1000))
_lib("serve port 70000", "error", r"port: expected 1..65535", lambda d: _serve(d, port=70000), issue=True)
_lib("write_site into a non-empty folder", "error", r"site: .* is not empty", lambda d: _site(d), (FileExistsError,), issue=True)
_lib("write_site force into a non-empty folder (valid)", "ok", "", lambda d: _site(d, force=True))
_lib("load_view misspelled 'dpeth' (as the CLI)", "error", r"unknown key 'dpeth' \(did you mean 'depth'\?\)",
     lambda d: _load_mutated(d, _rename(("depth",), "dpeth")), issue=True)
_lib("interpolate antialias 'yes'", "error", r"antialias: expected True or False, got 'yes'",
     lambda d: _interpolate(d, antialias="yes"), (TypeError,))
_lib("warp antialias 1", "error", r"antialias: expected True or False, got 1", lambda d: _warp(d, antialias=1), (TypeError,))
_lib("warp antialias with the forward splat", "error", r"antialias: .* needs method='mesh'",
     lambda d: _warp(d, antialias=True, method="forward"))
_lib("upconvert antialias None", "error", r"antialias: expected True or False, got None",
     lambda d: list(_upconvert(d, antialias=None)), (TypeError,))


# --------------------------------------------------------------------------- helpers of the library rows
def _check(ok):
    if not ok:
        raise AssertionError("expected outcome not met")


def _camera(**kw):
    from ibr.base.camera import Camera

    args = dict(fx=50.0, fy=50.0, cx=31.5, cy=23.5, width=W, height=H)
    args.update(kw)
    return Camera(**args)


def _camera_from(d):
    from ibr.base.camera import Camera

    return Camera.from_dict(d)


def _from_dict(mutate):
    doc = _camera().to_dict()
    mutate(doc)
    return _camera_from(doc)


def _load_camera(d, mutate):
    from ibr.io import load_camera

    doc = json.loads((d / "cam.json").read_text())
    mutate(doc)
    (d / "cam_bad.json").write_text(json.dumps(doc))
    return load_camera(d / "cam_bad.json")


def _load_mutated(d, mutate):
    from ibr.io import load_view

    doc = view_doc(d)
    mutate(doc)
    (d / "bad.json").write_text(json.dumps(doc))
    return load_view(d / "bad.json")


def _save(d, *, view=None, path="v.json", **kw):
    from ibr.io import save_view

    return save_view(_view(d) if view is None else view, d / path, **kw)


def _interpolate(d, **kw):
    from ibr.render.view_synthesis import interpolate

    v = _view(d)
    return interpolate(v, v, 0.5, **kw)


def _warp(d, **kw):
    from ibr.render.view_synthesis import warp

    v = _view(d)
    return warp(v, v.camera, **kw)


def _upconvert(d, **kw):
    from ibr.sequence.frame_rate import upconvert

    v = _view(d)
    return upconvert([v, v], 2, **kw)


def _stereo(d, *, e=0.05, f=2.0, method="pixel", **kw):
    from ibr.stereo.pair import stereo_pair

    return stereo_pair(_view(d, **kw), e=e, f=f, method=method)


def _predistort(**kw):
    from ibr.stereo.lens import RadialDistortion, predistort

    return predistort(np.zeros((H, W, 3), np.uint8), RadialDistortion(0.2, 0.0, 1.5), **kw)


def _e2c(*, face_size=8, depth=False, neg=False, shape=(16, 32)):
    import panorama

    img = np.full(shape, 2.0, np.float32) if depth else np.zeros(shape + (3,), np.uint8)
    if neg:
        img[3, 3] = -1.0
    return panorama.equirect_to_cubemap(img, face_size, depth=depth)


def _persp(**kw):
    import panorama

    args = dict(yaw_deg=0.0, pitch_deg=0.0, fov_deg=90.0, width=16, height=8)
    args.update(kw)
    return panorama.perspective(np.zeros((16, 32, 3), np.uint8), **args)


def _c2e(**kw):
    import panorama

    return panorama.cubemap_to_equirect([np.zeros((8, 8, 3), np.uint8)] * 6, layout="list", **kw)


def _write(d, name, arr=None):
    from ibr.io import write_image

    return write_image(d / name, np.zeros((4, 4, 3), np.uint8) if arr is None else arr)


def _write_depth(d, name, scale=None):
    from ibr.io import write_depth

    return write_depth(d / name, np.full((4, 4), 2.0, np.float32), scale=scale)


def _read(path):
    from ibr.io import read_image

    return read_image(path)


def _file(d, name, data: bytes):
    (d / name).write_bytes(data)
    return d / name


def _seg(d, scale):
    from ibr.io.mesh_files import write_segmentation_png
    from ibr.mesh.quad_mesh import build_mesh

    v = _view(d)
    return write_segmentation_png(build_mesh(v), v.color, d / "seg.png", scale=scale)


def _serve(d, port):
    from panorama.viewer import serve, write_site

    write_site(d / "site", np.zeros((16, 32, 3), np.uint8), face_size=8)
    return serve(d / "site", port=port)


def _site(d, force=False):
    from panorama.viewer import write_site

    (d / "site_full").mkdir()
    (d / "site_full" / "mine.txt").write_text("keep me")
    write_site(d / "site_full", np.zeros((16, 32, 3), np.uint8), face_size=8, force=force)
    _check((d / "site_full" / "mine.txt").read_text() == "keep me")


def counts() -> dict[str, Any]:
    """Counts for README.md: cases by area and by expected outcome, and those listed in #12."""
    out: dict[str, Any] = {"total": len(CASES), "issue": sum(c.issue for c in CASES)}
    for key in ("area", "expect"):
        for c in CASES:
            v = getattr(c, key)
            out[v] = out.get(v, 0) + 1
    return out
