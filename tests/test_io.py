"""Files: image/depth round trips per format, PFM orientation, atomic writes, view files, bad input.

Orientation and channel order are checked against an independent reader (OpenCV) and against
hand-built PFM bytes, so a bug that is symmetric between our reader and writer still shows.
"""

import json
import os
from pathlib import Path

import cv2
import numpy as np
import pytest

from ibr.base import depth as D
from ibr.base.camera import Camera
from ibr.io import DEPTH_ENCODINGS, atomic_path, load_view, read_depth, read_image, read_pfm, save_view, write_depth, write_image, write_pfm
from ibr.base.view import View

RNG = np.random.default_rng(7)


def marked(h, w, c, dtype):
    """Random image with distinct corner values, so flips and channel swaps are visible."""
    if np.dtype(dtype).kind == "f":
        a = RNG.uniform(-2, 5, (h, w, c)).astype(dtype)
    else:
        a = RNG.integers(0, np.iinfo(dtype).max, (h, w, c), endpoint=True).astype(dtype)
    a[0, 0] = np.arange(1, c + 1)
    return a[..., 0] if c == 1 else a


def listing(folder):
    return sorted(p.name for p in Path(folder).iterdir())


def make_view(dtype=np.uint8, depth=True, w=20, h=12):
    cam = Camera(30.0, 31.0, 9.25, 5.75, w, h, _pose())
    color = marked(h, w, 3, dtype) if dtype != np.float32 else RNG.uniform(0, 1, (h, w, 3)).astype(np.float32)
    z = None
    if depth:
        z = RNG.uniform(0.6, 40.0, (h, w)).astype(np.float32)
        z[0, :3] = np.nan
    return View(color, z, cam, "v")


def _pose():
    from scipy.spatial.transform import Rotation

    m = np.eye(4)
    m[:3, :3] = Rotation.from_rotvec([0.1, -0.4, 0.2]).as_matrix()
    m[:3, 3] = [0.5, -1.0, 2.0]
    return m


# ----------------------------------------------------------------------------- images
@pytest.mark.parametrize(
    "ext,dtype,channels",
    [(".png", np.uint8, 1), (".png", np.uint8, 3), (".png", np.uint8, 4), (".png", np.uint16, 3),
     (".tif", np.uint8, 3), (".tif", np.uint16, 1), (".tif", np.float32, 3), (".tif", np.uint32, 1),
     (".exr", np.float32, 1), (".exr", np.float32, 3), (".exr", np.uint32, 1), (".pfm", np.float32, 1),
     (".pfm", np.float32, 3)],
)
def test_lossless_round_trip_keeps_dtype(tmp_path, ext, dtype, channels):
    a = marked(9, 13, channels, dtype)
    path = tmp_path / f"img{ext}"
    write_image(path, a)
    b = read_image(path)
    assert b.dtype == a.dtype and b.shape == a.shape
    np.testing.assert_array_equal(b, a)
    assert listing(tmp_path) == [path.name]  # no temporary file left


def test_exr_keeps_nan_and_inf_and_png_matches_opencv(tmp_path):
    a = marked(6, 5, 1, np.float32)
    a[1, 1], a[2, 2], a[3, 3] = np.nan, np.inf, -np.inf
    write_image(tmp_path / "f.exr", a)
    np.testing.assert_array_equal(read_image(tmp_path / "f.exr"), a)  # NaN == NaN here
    rgb = marked(7, 11, 3, np.uint16)
    write_image(tmp_path / "c.png", rgb)
    # Independent reader: OpenCV returns BGR, row 0 at the top.
    np.testing.assert_array_equal(cv2.imread(str(tmp_path / "c.png"), cv2.IMREAD_UNCHANGED)[..., ::-1], rgb)
    bgr = marked(7, 11, 3, np.uint8)
    cv2.imwrite(str(tmp_path / "cv.png"), bgr)
    np.testing.assert_array_equal(read_image(tmp_path / "cv.png"), bgr[..., ::-1])


def test_jpeg_is_uint8_and_close(tmp_path):
    from skimage.data import astronaut
    from skimage.transform import downscale_local_mean

    a = downscale_local_mean(astronaut(), (4, 4, 1)).round().astype(np.uint8)
    write_image(tmp_path / "a.jpg", a)
    b = read_image(tmp_path / "a.jpg")
    assert b.dtype == np.uint8 and b.shape == a.shape
    err = np.abs(b.astype(int) - a.astype(int))
    assert np.percentile(err, 99) <= 24 and np.median(err) <= 2  # quality 95 (q75 gives ~2x more)
    # Not flipped: the error against the vertically flipped original is far larger.
    assert np.median(np.abs(b[::-1].astype(int) - a.astype(int))) > 10


@pytest.mark.parametrize(
    "name,array,match",
    [("a.png", np.zeros((4, 4), np.float32), r"\.png file stores uint8 or uint16, got float32"),
     ("a.jpg", np.zeros((4, 4, 3), np.uint16), r"\.jpg file stores uint8, got uint16"),
     ("a.jpg", np.zeros((4, 4, 4), np.uint8), "a JPEG file holds 1 or 3 channels, got 4"),  # alpha was dropped
     ("a.exr", np.zeros((4, 4), np.float64), r"\.exr file stores float32 or float16 or uint32, got float64"),
     ("a.bmp", np.zeros((4, 4), np.uint8), "unsupported extension '.bmp'"),
     ("a.png", np.zeros((4, 4, 2, 2), np.uint8), "expected 2 or 3 dimensions"),
     ("a.png", np.zeros((4, 4), bool), "png file stores uint8 or uint16, got bool")],
)
def test_write_image_refuses_bad_input_and_writes_nothing(tmp_path, name, array, match):
    with pytest.raises(ValueError, match=match):
        write_image(tmp_path / name, array)
    assert listing(tmp_path) == []


def test_read_image_missing_corrupt_truncated(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"image: file not found: .*nope\.png"):
        read_image(tmp_path / "nope.png")
    (tmp_path / "junk.png").write_bytes(b"this is not a png")
    with pytest.raises(ValueError, match=r"image: cannot read .*junk\.png"):
        read_image(tmp_path / "junk.png")
    write_image(tmp_path / "ok.png", marked(64, 64, 3, np.uint8))
    data = (tmp_path / "ok.png").read_bytes()
    (tmp_path / "cut.png").write_bytes(data[: len(data) // 2])
    with pytest.raises(ValueError, match=r"cut\.png") as err:
        read_image(tmp_path / "cut.png")
    assert "\n" not in str(err.value)  # OpenImageIO's three lines about it, joined: errors are one line
    # each distinct line once: "Read error: hit end of file" stood alone and again inside the next
    message = str(err.value).split("cut.png: ", 1)[1]
    assert message.count("hit end of file") == 1, message
    with pytest.raises(IsADirectoryError, match="expected a file"):
        read_image(tmp_path)


# ----------------------------------------------------------------------------- PFM
def test_pfm_is_bottom_to_top_little_endian(tmp_path):
    a = np.array([[1.0, 2.0, 3.0], [4.0, 5.0, np.nan]], np.float32)  # row 0 = top
    write_pfm(tmp_path / "d.pfm", a)
    raw = (tmp_path / "d.pfm").read_bytes()
    assert raw.startswith(b"Pf\n3 2\n-1\n")
    body = np.frombuffer(raw[len(b"Pf\n3 2\n-1\n"):], "<f4")
    # First stored row is the *bottom* image row; NaN is stored as +inf (Middlebury "no value").
    np.testing.assert_array_equal(body, [4.0, 5.0, np.inf, 1.0, 2.0, 3.0])
    back, scale = read_pfm(tmp_path / "d.pfm")
    assert scale == 1.0
    np.testing.assert_array_equal(back, np.where(np.isnan(a), np.inf, a))
    d = read_depth(tmp_path / "d.pfm")
    assert np.isnan(d[1, 2]) and d[0, 0] == 1.0


def test_pfm_big_endian_colour_and_oiio_written_file(tmp_path):
    a = np.arange(2 * 3 * 3, dtype=np.float32).reshape(2, 3, 3)
    (tmp_path / "be.pfm").write_bytes(b"PF\n3 2\n2.5\n" + a[::-1].astype(">f4").tobytes())
    back, scale = read_pfm(tmp_path / "be.pfm")
    assert scale == 2.5 and back.shape == (2, 3, 3)
    np.testing.assert_array_equal(back, a)
    # A file written by another library (OpenImageIO) reads back top row first.
    import OpenImageIO as oiio

    g = np.arange(12, dtype=np.float32).reshape(3, 4)
    out = oiio.ImageOutput.create(str(tmp_path / "oiio.pfm"))
    out.open(str(tmp_path / "oiio.pfm"), oiio.ImageSpec(4, 3, 1, oiio.FLOAT))
    out.write_image(g[..., None])
    out.close()
    np.testing.assert_array_equal(read_image(tmp_path / "oiio.pfm"), g)


def test_pfm_bad_files(tmp_path):
    (tmp_path / "h.pfm").write_bytes(b"P6\n3 2\n255\n" + bytes(18))
    with pytest.raises(ValueError, match="not a PFM file"):
        read_pfm(tmp_path / "h.pfm")
    (tmp_path / "t.pfm").write_bytes(b"Pf\n3 2\n-1\n" + bytes(10))
    with pytest.raises(ValueError, match=r"truncated PFM file \(10 bytes of pixel data, expected 24\)"):
        read_pfm(tmp_path / "t.pfm")
    (tmp_path / "z.pfm").write_bytes(b"Pf\n3 2\n0\n" + bytes(24))
    with pytest.raises(ValueError, match="bad PFM header"):
        read_pfm(tmp_path / "z.pfm")


# ----------------------------------------------------------------------------- depth files
def test_depth_exr_exact_and_png_scaled(tmp_path):
    z = RNG.uniform(0.5, 60.0, (10, 14)).astype(np.float32)
    z[2, 3] = np.nan
    write_depth(tmp_path / "z.exr", z)
    np.testing.assert_array_equal(read_depth(tmp_path / "z.exr"), z)
    write_depth(tmp_path / "z.png", z, scale=0.001)  # millimetre codes
    codes = read_image(tmp_path / "z.png")
    assert codes.dtype == np.uint16 and codes[2, 3] == 0
    np.testing.assert_array_equal(codes[~np.isnan(z)], np.rint(z[~np.isnan(z)] / 0.001))
    back = read_depth(tmp_path / "z.png", scale=0.001)
    assert np.isnan(back[2, 3])
    assert np.nanmax(np.abs(back - z)) <= 0.0005 + 1e-6  # half a code
    with pytest.raises(ValueError, match=r"stores integer codes \(uint16\); give `scale`"):
        read_depth(tmp_path / "z.png")
    with pytest.raises(ValueError, match="scale: a 16-bit PNG depth needs `scale`"):
        write_depth(tmp_path / "y.png", z)
    with pytest.raises(ValueError, match=r"a 16-bit PNG holds 1\.\.65535"):
        write_depth(tmp_path / "y.png", z, scale=1e-4)  # 60 m / 0.1 mm overflows
    with pytest.raises(ValueError, match=r"a 16-bit PNG holds 1\.\.65535"):
        write_depth(tmp_path / "y.png", np.full((2, 2), 0.001), scale=0.01)  # would read back as invalid
    rgb = RNG.uniform(0.5, 2.0, (3, 3, 3)).astype(np.float32)  # a colour image, not a depth pass
    write_image(tmp_path / "rgb.exr", rgb)
    with pytest.raises(ValueError, match=r"whose values differ at \d+ pixel\(s\) \(R vs G\)"):
        read_depth(tmp_path / "rgb.exr")
    assert not (tmp_path / "y.png").exists()


# ----------------------------------------------------------------------------- atomic writes
def test_atomic_path_success_and_failure(tmp_path):
    target = tmp_path / "out.txt"
    with atomic_path(target) as tmp:
        assert tmp.parent == tmp_path and tmp.name.endswith(".tmp.txt") and tmp != target
        tmp.write_text("new")
        assert not target.exists()  # nothing visible until the block succeeds
    assert target.read_text() == "new" and listing(tmp_path) == ["out.txt"]
    assert (target.stat().st_mode & 0o777) == (0o666 & ~_umask())
    before = target.stat().st_mtime_ns
    with pytest.raises(RuntimeError, match="boom"):
        with atomic_path(target) as tmp:
            tmp.write_text("half")
            raise RuntimeError("boom")
    assert target.read_text() == "new" and target.stat().st_mtime_ns == before
    assert listing(tmp_path) == ["out.txt"]
    with pytest.raises(OSError, match="nothing was written"):
        with atomic_path(tmp_path / "empty.txt") as tmp:
            tmp.unlink()
    with pytest.raises(FileNotFoundError, match="output folder .* does not exist"):
        with atomic_path(tmp_path / "missing" / "x.png"):
            pass
    assert listing(tmp_path) == ["out.txt"]


def _umask():
    m = os.umask(0)
    os.umask(m)
    return m


def test_save_view_failure_leaves_existing_files_untouched(tmp_path, monkeypatch):
    view = make_view()
    save_view(view, tmp_path / "a.json")
    snapshot = {p: p.read_bytes() for p in tmp_path.iterdir()}
    import ibr.io.view_files as io_mod

    def broken(*args, **kwargs):
        raise OSError("disk full")

    monkeypatch.setattr(io_mod, "write_depth", broken)  # fails after the color was written
    other = make_view()
    with pytest.raises(OSError, match="disk full"):
        save_view(other, tmp_path / "a.json")
    assert {p: p.read_bytes() for p in tmp_path.iterdir()} == snapshot  # no temp files, no changes


# ----------------------------------------------------------------------------- view files
ENCODINGS = [
    ("z", {}, None), ("z", {"scale": 0.001}, "d.png"), ("range", {}, None),
    ("disparity", {"baseline": 0.12, "focal_px": 30.0, "doffs": 4.5}, None),
    ("disparity", {"baseline": 0.12, "focal_px": 30.0, "doffs": 4.5}, "d.pfm"),
    ("window", {"near": 0.5, "far": 50.0}, None), ("reversed", {"near": 0.5, "far": 50.0}, None),
    ("reversed", {"near": 0.5, "far": "inf"}, None), ("zprime", {"near": 0.5, "far": 50.0}, None),
    ("fixed16", {"near": 0.5, "far": 50.0}, None), ("fixed24", {"near": 0.5, "far": 50.0}, None),
]


@pytest.mark.parametrize("encoding,params,depth_name", ENCODINGS)
def test_view_round_trip_every_encoding(tmp_path, encoding, params, depth_name):
    view = make_view()
    save_view(view, tmp_path / "v.json", depth_encoding=encoding, depth_params=params, depth_name=depth_name)
    back = load_view(tmp_path / "v.json")
    np.testing.assert_array_equal(back.color, view.color)
    assert back.camera.allclose(view.camera, atol=0) and back.name == "v"
    assert back.depth.dtype == np.float32
    np.testing.assert_array_equal(np.isnan(back.depth), np.isnan(view.depth))
    ok = ~np.isnan(view.depth)
    z, zb = view.depth[ok].astype(np.float64), back.depth[ok].astype(np.float64)
    if encoding == "z" and not params:
        np.testing.assert_array_equal(zb, z)
    elif encoding.startswith("fixed"):
        bits = int(encoding[5:])
        step = D.zbuffer_step(z, near=0.5, far=50.0, bits=bits)
        assert np.all(np.abs(zb - z) <= 0.5 * step * 1.01 + 1e-6 * z)
    elif params.get("scale"):
        assert np.max(np.abs(zb - z)) <= 0.5 * params["scale"] + 1e-6
    else:
        # float32 storage: window and z' lose ~z/(n f) relative precision at depth; others ~1e-6.
        tol = 3e-7 * z * 50 / 0.5 if encoding in ("window", "zprime") else np.full_like(z, 1e-6)
        if encoding == "disparity":  # float32 d = B f / z - doffs cancels when B f / z << doffs
            d = 0.12 * 30.0 / z - 4.5
            tol = 1.2e-7 * (np.abs(d) + 4.5) / (d + 4.5) + 1e-6
        assert np.max(np.abs(zb - z) / z / tol) <= 1.0
    doc = json.loads((tmp_path / "v.json").read_text())
    assert doc["depth"]["encoding"] == encoding and not Path(doc["depth"]["path"]).is_absolute()


def test_view_round_trip_dtypes_no_depth_and_relative_paths(tmp_path):
    for dtype in (np.uint16, np.float32):
        view = make_view(dtype)
        save_view(view, tmp_path / f"{np.dtype(dtype).name}.json")
        back = load_view(tmp_path / f"{np.dtype(dtype).name}.json")
        assert back.color.dtype == dtype
        np.testing.assert_array_equal(back.color, view.color)
    save_view(make_view(depth=False), tmp_path / "nodepth.json")
    doc = json.loads((tmp_path / "nodepth.json").read_text())
    assert doc["depth"] is None and doc["format"] == "ibr-view" and doc["version"] == 1
    assert load_view(tmp_path / "nodepth.json").depth is None
    # Paths are relative to the JSON: the folder can move.
    moved = tmp_path.parent / (tmp_path.name + "_moved")
    tmp_path.rename(moved)
    assert load_view(moved / "float32.json").color.dtype == np.float32
    assert sorted(p.name for p in moved.iterdir()) == sorted(
        ["uint16.json", "uint16_color.png", "uint16_depth.exr", "float32.json", "float32_color.exr",
         "float32_depth.exr", "nodepth.json", "nodepth_color.png"])


def test_save_view_over_its_own_files(tmp_path):
    view = make_view()
    save_view(view, tmp_path / "a.json")
    loaded = load_view(tmp_path / "a.json")
    save_view(loaded, tmp_path / "a.json")  # replaces its own files atomically, same content
    again = load_view(tmp_path / "a.json")
    np.testing.assert_array_equal(again.depth, view.depth)
    assert listing(tmp_path) == ["a.json", "a_color.png", "a_depth.exr"]


def test_save_view_refuses_bad_requests(tmp_path):
    view = make_view()
    with pytest.raises(ValueError, match="must be distinct"):
        save_view(view, tmp_path / "a.json", color_name="x.png", depth_name="x.png")
    with pytest.raises(ValueError, match="must be distinct"):
        save_view(view, tmp_path / "a.json", color_name="a.json")
    with pytest.raises(ValueError, match="must end in .json"):
        save_view(view, tmp_path / "a.txt")
    with pytest.raises(ValueError, match="unknown depth encoding 'inverse'"):
        save_view(view, tmp_path / "a.json", depth_encoding="inverse")
    with pytest.raises(ValueError, match="needs parameter\\(s\\) near, far"):
        save_view(view, tmp_path / "a.json", depth_encoding="fixed24")
    with pytest.raises(ValueError, match="lie outside \\[near, far\\]"):
        save_view(view, tmp_path / "a.json", depth_encoding="fixed16", depth_params={"near": 1.0, "far": 10.0})
    with pytest.raises(ValueError, match="needs a 'scale'"):
        save_view(view, tmp_path / "a.json", depth_name="d.png")
    with pytest.raises(ValueError, match=r"\.png file stores uint8 or uint16, got float32"):
        save_view(make_view(np.float32), tmp_path / "a.json", color_name="c.png")
    with pytest.raises(TypeError, match="view: expected an ibr View"):
        save_view("view", tmp_path / "a.json")
    with pytest.raises(FileNotFoundError, match="output folder"):
        save_view(view, tmp_path / "no" / "a.json")
    assert listing(tmp_path) == []


# ----------------------------------------------------------------------------- bad view files
@pytest.fixture()
def good(tmp_path):
    save_view(make_view(), tmp_path / "g.json")
    return tmp_path / "g.json"


def edit(path, fn):
    doc = json.loads(path.read_text())
    fn(doc)
    path.write_text(json.dumps(doc))
    return path


@pytest.mark.parametrize(
    "change,exc,match",
    [
        (lambda d: d.update(color="gone.png"), FileNotFoundError, r"'color' refers to a missing file .*gone\.png"),
        (lambda d: d["depth"].update(path="gone.exr"), FileNotFoundError, r"'depth\.path' refers to a missing file .*gone\.exr"),
        (lambda d: d["camera"].update(fx=0), ValueError, "bad 'camera': fx: expected a positive number, got 0"),
        (lambda d: d["camera"].update(fy=-5.0), ValueError, "fy: expected a positive number"),
        (lambda d: d["camera"].update(world_from_cam=np.diag([1, 1, -1, 1.0]).tolist()), ValueError, "proper rotation"),
        (lambda d: d["camera"].update(world_from_cam=(2 * np.eye(4)).tolist()), ValueError, "proper rotation|last row"),
        (lambda d: d["camera"].pop("cx"), ValueError, "missing key\\(s\\) cx"),
        (lambda d: d["camera"].update(width=21), ValueError, r"camera size 21x12 does not match the color image g_color\.png \(20x12\)"),
        (lambda d: d["depth"].update(encoding="inverse"), ValueError, "unknown depth encoding 'inverse'.*; expected one of 'z'"),
        (lambda d: d["depth"].update(encoding="disparity", baseline=0.1), ValueError, "needs parameter\\(s\\) focal_px, doffs"),
        (lambda d: d["depth"].update(encoding="window", near=1.0, far=0.5), ValueError, "need 0 < near < far"),
        (lambda d: d["depth"].update(dofs=3.0), ValueError, "unknown parameter\\(s\\) dofs for encoding 'z'"),
        (lambda d: d["depth"].update(scale="big"), ValueError, "parameter 'scale' must be a finite number"),
        (lambda d: d["depth"].update(encoding="fixed16", near=0.5, far="inf"), ValueError, "needs a finite far plane"),
        (lambda d: d.update(format="other"), ValueError, "'format' must be 'ibr-view'"),
        (lambda d: d.update(version=2), ValueError, "unsupported 'version' 2"),
        (lambda d: d.pop("camera"), ValueError, "missing key 'camera'"),
        (lambda d: d.update(depth="g_depth.exr"), ValueError, "'depth' must be null or an object"),
    ],
)
def test_load_view_bad_inputs(good, change, exc, match):
    with pytest.raises(exc, match=match):
        load_view(edit(good, change))


def test_load_view_bad_files(good):
    folder = good.parent
    with pytest.raises(FileNotFoundError, match="view file: file not found"):
        load_view(folder / "none.json")
    (folder / "bad.json").write_text("{not json")
    with pytest.raises(ValueError, match="not valid JSON"):
        load_view(folder / "bad.json")
    # Corrupt color image: the message names the key.
    (folder / "g_color.png").write_bytes(b"\x89PNG\r\n\x1a\n garbage")
    with pytest.raises(ValueError, match=r"'color'.*g_color\.png"):
        load_view(good)
    # Color/depth size mismatch.
    write_image(folder / "g_color.png", marked(12, 20, 3, np.uint8))
    write_depth(folder / "g_depth.exr", np.ones((11, 20), np.float32))
    with pytest.raises(ValueError, match=r"depth g_depth\.exr is 20x11 but color g_color\.png is 20x12"):
        load_view(good)
    # 16-bit PNG depth without its scale.
    write_depth(folder / "p.png", np.ones((12, 20)), scale=0.01)
    edit(good, lambda d: d["depth"].update(path="p.png"))
    with pytest.raises(ValueError, match=r"'depth.path'.*give `scale`"):
        load_view(good)
    edit(good, lambda d: d["depth"].update(scale=0.01))
    np.testing.assert_allclose(load_view(good).depth, 1.0, rtol=1e-6)
    # An infinite far plane written as "inf" or as Python's non-standard Infinity literal.
    rev = np.full((12, 20), 0.25, np.float32)  # reversed-z n / z with n = 0.5: z = 2
    write_depth(folder / "r.exr", rev)
    for far in ('"inf"', "Infinity"):
        text = json.dumps({**json.loads(good.read_text()), "depth": {"path": "r.exr", "encoding": "reversed", "near": 0.5, "far": 0}})
        good.write_text(text.replace('"far": 0', f'"far": {far}'))
        np.testing.assert_allclose(load_view(good).depth, 2.0, rtol=1e-6)


def test_encodings_table_is_complete():
    assert set(DEPTH_ENCODINGS) == {"z", "range", "disparity", "window", "reversed", "zprime", "fixed16", "fixed24"}
    assert {e for e, _, _ in ENCODINGS} == set(DEPTH_ENCODINGS)


def test_png_is_written_at_the_faster_zlib_level(tmp_path):
    """PNGs use zlib level PNG_COMPRESSION_LEVEL (4: 2.3x faster than the default 6, #13): the
    zlib header of the first IDAT chunk says "fast" (FLEVEL 1, levels 2-5), and the pixels round-trip."""
    import struct

    from ibr.io.images import PNG_COMPRESSION_LEVEL

    rng = np.random.default_rng(3)
    img = (rng.random((64, 80, 3)) * 40).astype(np.uint8) + np.arange(80, dtype=np.uint8)[None, :, None]
    path = tmp_path / "a.png"
    write_image(path, img)
    data = path.read_bytes()
    pos = 8
    while True:  # walk the chunks to the first IDAT
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        if kind == b"IDAT":
            cmf, flg = data[pos + 8], data[pos + 9]
            break
        pos += 12 + length
    assert cmf & 0x0F == 8 and (cmf * 256 + flg) % 31 == 0  # deflate, a valid zlib header
    assert PNG_COMPRESSION_LEVEL == 4 and flg >> 6 == 1
    np.testing.assert_array_equal(read_image(path), img)


def test_brackets_in_names_survive_and_load_camera_checks_the_version(tmp_path):
    """The JSON writer put every bracketed list of numbers on one line, also inside strings: a
    view named "take [ 2 ]" came back "take [2]", and a colour file "shot [1,  2].png" was
    written under that name but recorded as "shot [1, 2].png" (the view no longer loaded).
    ``load_camera`` read a view file of an unknown version that ``load_view`` refuses."""
    import json

    from ibr import Camera, View
    from ibr.io import load_camera, load_view, save_view

    cam = Camera(10.0, 10.0, 1.5, 1.5, 4, 4)
    v = View(np.zeros((4, 4, 3), np.uint8), None, cam, "take [ 2 ]")
    save_view(v, tmp_path / "a.json", color_name="shot [1,  2].png")
    back = load_view(tmp_path / "a.json")
    assert back.name == "take [ 2 ]" and (tmp_path / "shot [1,  2].png").is_file()
    doc = json.loads((tmp_path / "a.json").read_text())
    assert '"world_from_cam": [' in (tmp_path / "a.json").read_text()  # poses still one row per line
    doc["version"] = 99
    (tmp_path / "c.json").write_text(json.dumps(doc))
    for load in (load_view, load_camera):
        with pytest.raises(ValueError, match="unsupported 'version' 99"):
            load(tmp_path / "c.json")


def test_blender_no_surface_markers_only_in_depth_passes(tmp_path):
    """1e10 and 65504 mean "no surface" in Blender's depth passes; a z' buffer or a disparity map
    holding exactly 65504 lost that pixel (read as NaN). z' = 2^24 (1 - near / z) with far = inf
    is 65504 at z = 1 for this near."""
    near = 1 - 65504 / 2**24
    z = np.full((2, 2), 3.0, np.float32)
    z[0, 0] = 1.0
    cam = Camera(1.0, 1.0, 0.5, 0.5, 2, 2)
    save_view(View(np.zeros((2, 2, 3), np.uint8), z, cam), tmp_path / "zp.json", depth_encoding="zprime",
              depth_params={"near": near, "far": float("inf")})
    back = load_view(tmp_path / "zp.json").depth
    assert np.isfinite(back).all() and back[0, 0] == pytest.approx(1.0, rel=1e-6)
    write_depth(tmp_path / "z.exr", np.array([[2.0, 65504.0], [1e10, 3.0]], np.float32))
    assert np.isnan(read_depth(tmp_path / "z.exr")).sum() == 2  # a depth pass: both markers are no surface


def test_fixed_codes_out_of_range_name_the_view_file(tmp_path):
    """A fixed16 depth file holding 70000 said only "q: codes must lie in [0, 65535]"; it names
    the view file, the key and the file now, like the window encodings."""
    import json

    cam = Camera(1.0, 1.0, 1.5, 1.5, 4, 4)
    write_image(tmp_path / "c.png", np.zeros((4, 4, 3), np.uint8))
    write_depth(tmp_path / "d.exr", np.full((4, 4), 70000.0, np.float32))
    doc = {"format": "ibr-view", "version": 1, "color": "c.png", "camera": cam.to_dict(),
           "depth": {"path": "d.exr", "encoding": "fixed16", "near": 0.1, "far": 10}}
    (tmp_path / "v.json").write_text(json.dumps(doc))
    with pytest.raises(ValueError, match=r"v\.json: 'depth\.path' d\.exr: 16 value\(s\) outside \[0, 65535\]"):
        load_view(tmp_path / "v.json")


def test_integer_depth_codes_carry_their_step_whatever_the_extension(tmp_path):
    """Integer depth codes were recognised by the ``.png`` extension only: the same millimetre
    codes in a uint16 TIFF got no quantization step (the step the mesh builder reads)."""
    import json

    from ibr.base.depth import quantization_of

    cam = Camera(1.0, 1.0, 1.5, 1.5, 4, 4)
    write_image(tmp_path / "c.png", np.zeros((4, 4, 3), np.uint8))
    steps = []
    for ext in (".png", ".tif"):
        write_image(tmp_path / f"d{ext}", np.full((4, 4), 2000, np.uint16))
        doc = {"format": "ibr-view", "version": 1, "color": "c.png", "camera": cam.to_dict(),
               "depth": {"path": f"d{ext}", "encoding": "z", "scale": 0.001}}
        (tmp_path / f"v{ext}.json").write_text(json.dumps(doc))
        v = load_view(tmp_path / f"v{ext}.json")
        assert np.allclose(v.depth, 2.0)
        steps.append(quantization_of(v))
    assert steps[0] is not None and steps[1] == steps[0]
