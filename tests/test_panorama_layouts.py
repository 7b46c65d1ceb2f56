"""Cubemap layouts: exact round trips for every layout, tile placement, py360convert interop."""

from __future__ import annotations

import numpy as np
import pytest

import panorama as P
from panorama.directions import FACE_NAMES, equirect_directions
from panorama.layouts import LAYOUTS, layout_index_maps, layout_shape

S = 6


def tagged_faces(s=S, channels=3):
    """Faces whose every texel encodes (face, column, row): any misplacement is visible."""
    f, j, i = np.mgrid[0:6, 0:s, 0:s]
    code = (f * 10000 + j * 100 + i).astype(np.float32)
    return [np.repeat(code[k][..., None], channels, -1) for k in range(6)]


@pytest.mark.parametrize("layout", LAYOUTS)
def test_pack_unpack_round_trip_is_exact(layout):
    faces = tagged_faces()
    packed = P.pack_faces(faces, layout)
    back = P.unpack_faces(packed, layout)
    for a, b in zip(faces, back):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("layout, shape", [("horizon", (S, 6 * S)), ("vstrip", (6 * S, S)),
                                           ("dice", (3 * S, 4 * S))])
def test_image_layout_shapes_and_tiles(layout, shape):
    packed = P.pack_faces(tagged_faces(), layout)
    assert packed.shape[:2] == shape == layout_shape(layout, S)
    face_code = packed[..., 0] // 10000
    tile = lambda c, r: face_code[r * S:(r + 1) * S, c * S:(c + 1) * S]  # noqa: E731
    if layout == "horizon":  # F R B L U D
        expected = ["+z", "+x", "-z", "-x", "-y", "+y"]
        for c, name in enumerate(expected):
            assert np.all(tile(c, 0) == FACE_NAMES.index(name))
    elif layout == "vstrip":  # OpenEXR +X -X +Y -Y +Z -Z in its frame (x, y flipped)
        for r, name in enumerate(["-x", "+x", "-y", "+y", "+z", "-z"]):
            assert np.all(tile(0, r) == FACE_NAMES.index(name))
        # up/down tiles are turned 180 degrees: the tile's top-left texel is the face's last one
        assert packed[2 * S, 0, 0] == FACE_NAMES.index("-y") * 10000 + (S - 1) * 101
    else:
        for (c, r), name in {(1, 0): "-y", (0, 1): "-x", (1, 1): "+z", (2, 1): "+x",
                             (3, 1): "-z", (1, 2): "+y"}.items():
            assert np.all(tile(c, r) == FACE_NAMES.index(name))
        assert np.all(tile(0, 0) == 0) and np.all(packed[:S, 2 * S:] == 0)  # unused cells


@pytest.mark.parametrize("layout", LAYOUTS)
def test_conversions_agree_in_every_layout(layout):
    eq = np.random.default_rng(1).random((32, 64, 3)).astype(np.float32)
    ref = P.equirect_to_cubemap(eq, 16, layout="list")
    cube = P.equirect_to_cubemap(eq, 16, layout=layout)
    for a, b in zip(ref, P.unpack_faces(cube, layout)):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(P.cubemap_to_equirect(cube, 64, 32, layout=layout),
                                  P.cubemap_to_equirect(ref, 64, 32, layout="list"))


def test_layout_index_maps_match_pack():
    face, i, j = layout_index_maps("dice", S)
    packed = P.pack_faces(tagged_faces(), "dice")[..., 0]
    used = face >= 0
    np.testing.assert_array_equal(packed[used], (face * 10000 + j * 100 + i)[used])
    assert not face.flags.writeable


def test_dict_accepts_py360convert_and_file_keys():
    faces = tagged_faces()
    py360 = dict(zip("RLDUFB", faces))  # R=+x L=-x D=+y U=-y F=+z B=-z
    files = dict(zip(["px", "nx", "py", "ny", "pz", "nz"], faces))
    for d in (py360, files):
        for a, b in zip(faces, P.unpack_faces(d, "dict")):
            np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="dict has no face '\\+x'"):
        P.unpack_faces({"a": faces[0]}, "dict")


@pytest.mark.parametrize("fmt", ["horizon", "dice"])
def test_py360convert_images_open_with_the_right_faces(fmt):
    """A smooth panorama converted by py360convert and by us gives the same faces up to
    py360convert's sub-texel grid offsets; a mirrored or misplaced face would differ by ~0.3."""
    py360 = pytest.importorskip("py360convert")
    d = equirect_directions(256, 128)
    eq = (0.5 + 0.4 * d[..., 0] * (1 + 0.3 * d[..., 1]) + 0.1 * d[..., 2]).astype(np.float32)
    theirs = py360.e2c(eq, face_w=32, cube_format=fmt)
    ours = P.equirect_to_cubemap(eq, 32, layout=fmt)
    assert theirs.shape == ours.shape
    assert np.abs(theirs - ours).max() < 0.05


def test_aliases():
    faces = tagged_faces()
    np.testing.assert_array_equal(P.pack_faces(faces, "exr"), P.pack_faces(faces, "vstrip"))
    np.testing.assert_array_equal(P.pack_faces(faces, "cross"), P.pack_faces(faces, "dice"))
    np.testing.assert_array_equal(P.pack_faces(faces, "hstrip"), P.pack_faces(faces, "horizon"))


# ----------------------------------------------------------------------------- auto-detection
def _photo_4x3():
    """The bundled clutter photo: an ordinary 512 x 384 (4:3) picture, no cubemap."""
    from ibr.io import read_image
    from samples import DATA_DIR

    img = read_image(DATA_DIR / "clutter_a_color.png")
    assert img.shape == (384, 512, 3)
    return img


def test_dice_detection_needs_empty_unused_cells(tmp_path):
    """A 4:3 image is a dice only when its six unused cells are empty. Dice images of the project's
    own packer (unused cells 0) are detected, also after a JPEG round trip (ringing at the face
    edges) and with another uniform fill colour; the 4:3 photo is not (below)."""
    from ibr.io import write_image
    from panorama.files import read_panorama, write_cubemap

    eq = np.rint(np.random.default_rng(4).random((64, 128, 3)) * 255).astype(np.uint8)
    faces = P.equirect_to_cubemap(eq, 37, layout="list")
    packed = P.pack_faces(faces, "dice")
    assert P.detect_layout(packed) == "dice"
    for ext in (".png", ".jpg"):
        write_cubemap(tmp_path / f"c{ext}", faces, layout="dice")
        img, layout = read_panorama(tmp_path / f"c{ext}")
        assert layout == "dice" and img.shape == (111, 148, 3)
    white = packed.copy()
    white[layout_index_maps("dice", 37)[0] < 0] = 255
    write_image(tmp_path / "white.png", white)
    assert read_panorama(tmp_path / "white.png")[1] == "dice"
    np.testing.assert_array_equal(P.unpack_faces(white, "dice")[4], faces[4])
    _check_a_4x3_photo_is_refused(tmp_path)


def _check_a_4x3_photo_is_refused(tmp_path):
    """``ibr cubemap clutter_a_color.png -o x.png`` (512 x 384) read the photo as a 4 x 3 cross
    and wrote a garbage equirect with exit 0. Auto-detection now refuses it, says why and how
    to force the layout; an explicit layout is still honoured."""
    from ibr.io import write_image
    from panorama.files import read_panorama

    photo = _photo_4x3()
    expected = (r"pano: a 512 x 384 \(4:3\) image is read as a dice cubemap only when its six unused "
                r"cells are empty.*layout='dice'.*--input-layout dice.*--layout dice")
    with pytest.raises(ValueError, match=expected):
        P.detect_layout(photo)
    with pytest.raises(ValueError, match=expected):
        P.perspective(photo, yaw_deg=0, pitch_deg=0, fov_deg=90, width=8, height=8)
    write_image(tmp_path / "photo.png", photo)
    with pytest.raises(ValueError, match=expected):
        read_panorama(tmp_path / "photo.png")
    # forced: the user's layout wins
    assert read_panorama(tmp_path / "photo.png", layout="dice")[1] == "dice"
    view = P.perspective(photo, yaw_deg=0, pitch_deg=0, fov_deg=90, width=8, height=8, layout="dice")
    assert view.shape == (8, 8, 3)
    # one unused cell of a real dice holding picture content is enough to refuse
    dice = P.pack_faces(P.equirect_to_cubemap(np.zeros((64, 128, 3), np.uint8), 16, layout="list"), "dice")
    assert P.detect_layout(dice) == "dice"
    dice[32:48, 48:64] = photo[:16, :16]  # bottom-right cell
    with pytest.raises(ValueError, match=expected.replace("512 x 384", "64 x 48")):
        P.detect_layout(dice)


@pytest.mark.parametrize("case", ["hdr highlight in a face", "hdr highlight in an unused cell", "12-bit in uint16"])
def test_dice_detection_does_not_depend_on_the_value_range(case):
    """The unused cells' spread is measured against the faces' (interquartile ranges), not the
    value range: an HDR 4:3 photo with one 1e4 highlight (a spread of 3e-5 of its range) and
    12-bit values stored in uint16 (1.8 % of the dtype's range) passed as dice before; a real
    dice in those dtypes is still detected."""
    rng = np.random.default_rng(1)
    if case == "12-bit in uint16":
        photo = rng.integers(0, 4096, (384, 512, 3), dtype=np.uint16)
        faces = [rng.integers(0, 4096, (128, 128, 3), dtype=np.uint16) for _ in range(6)]
    else:
        photo = rng.random((384, 512, 3)).astype(np.float32)
        photo[(200, 200) if "face" in case else (60, 60)] = 1e4  # (200, 200): the front face
        faces = [rng.random((128, 128, 3)).astype(np.float32) for _ in range(6)]
        faces[0][5, 5] = 1e4
    with pytest.raises(ValueError, match="six unused cells are empty"):
        P.detect_layout(photo)
    assert P.detect_layout(P.pack_faces(faces, "dice")) == "dice"


def test_a_photo_of_flat_sky_and_flat_ground_is_no_dice():
    """Each unused cell flat but of another colour (a sky above, a lawn below, a scene between)
    is an ordinary 4:3 photo: the cells must also agree with each other. A real dice of tiny
    blurred faces after JPEG 75 is still detected."""
    import cv2

    rng = np.random.default_rng(0)
    img = np.empty((384, 512, 3))
    img[:128] = np.array([235, 206, 135]) - 20 * np.linspace(0, 1, 384)[:128, None, None]
    img[128:256] = rng.integers(0, 256, (128, 512, 3))
    img[256:] = (70, 90, 80)
    photo = np.clip(img + rng.normal(0, 2.0, img.shape), 0, 255).astype(np.uint8)
    with pytest.raises(ValueError, match="six unused cells are empty"):
        P.detect_layout(photo)
    faces = [cv2.GaussianBlur(rng.integers(0, 256, (24, 24, 3)).astype(np.uint8), (0, 0), 1.5) for _ in range(6)]
    ok, buf = cv2.imencode(".jpg", P.pack_faces(faces, "dice"), [cv2.IMWRITE_JPEG_QUALITY, 75])
    assert P.detect_layout(cv2.imdecode(buf, cv2.IMREAD_COLOR)) == "dice"


def test_dice_unused_spread_refuses_what_is_no_4x3_image():
    """The public spread measure names its argument for a wrong shape or a non-image."""
    from panorama.layouts import dice_unused_spread

    with pytest.raises(ValueError, match=r"pano: a dice image is \(3S, 4S\), got 64 x 32"):
        dice_unused_spread(np.zeros((32, 64, 3), np.uint8))
    with pytest.raises((TypeError, ValueError), match="pano"):
        dice_unused_spread("not an image")
    assert dice_unused_spread(np.zeros((48, 64), np.uint8)) == 0.0  # nothing varies anywhere
