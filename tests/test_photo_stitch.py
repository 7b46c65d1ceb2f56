"""panorama.photo: photos cut out of a known equirect at known rotations, stitched back (#16).

Truth: :func:`panorama.photo.testdata.photo_sphere` (six scikit-image photos as cube faces) and
:func:`~panorama.photo.testdata.cut_photos` (exact perspective cut-outs with exposure gains and
noise). The stitched equirect is compared with the source reduced to the output width.
"""

from __future__ import annotations

import json
import math

import cv2
import numpy as np
import pytest

import panorama
from ibr.base.camera import Camera
from panorama.directions import world_from_view
from panorama.photo import compose_equirect, coverage_extent, stitch_photos
from panorama.photo.compose import _footprint
from panorama.photo.estimate import yaw_pitch_roll
from panorama.photo.features import rotation_misfit
from panorama.photo.testdata import (cut_photos, photo_sphere, psnr, ring_poses, rotation_errors_deg,
                                     seam_band)

W_OUT = 1536          # output equirect width for the 400 x 300 photos (native 2 pi f = 1638)
PHOTO = dict(width=400, height=300, hfov_deg=75.0)


@pytest.fixture(scope="module")
def sphere():
    return photo_sphere(2048)


@pytest.fixture(scope="module")
def reference(sphere):
    return cv2.resize(sphere, (W_OUT, W_OUT // 2), interpolation=cv2.INTER_AREA)


@pytest.fixture(scope="module")
def photos(sphere):
    # 12 photos: 8 around the horizon, 4 tilted up 40 deg; gains 0.9..1.1 (photo 0 at 1), noise 1/255
    return cut_photos(sphere, ring_poses(((0.0, 8), (40.0, 4))), **PHOTO, gain_spread=0.1,
                      noise=1 / 255, seed=3)


@pytest.fixture(scope="module")
def stitched(photos):
    return stitch_photos(photos.images, width=W_OUT, exposure_reference=0)


def _errors(img, ref, cov, band):
    x = img.astype(np.float32) / 255.0
    rms = lambda m: float(np.sqrt(np.mean((x - ref)[m] ** 2)))  # noqa: E731
    return psnr(x, ref, cov), rms(cov & ~band), rms(cov & band)


# ----------------------------------------------------------------------------- the pipeline
def test_rotations_focal_and_placement(stitched, photos):
    assert stitched.report.used == list(range(12))
    err = rotation_errors_deg(stitched.cameras, photos.cameras)
    # no global alignment: wave correction levels the horizon and photo 0 is put at lon 0
    assert err.max() < 0.2, err
    f_true = photos.cameras[0].fx
    for cam in stitched.cameras:
        assert abs(cam.fx / f_true - 1) < 0.005
        assert (cam.cx, cam.cy) == (199.5, 149.5)
    yaw, pitch, _ = yaw_pitch_roll(stitched.cameras[9].world_from_cam[:3, :3])
    assert abs(yaw - 135.0) < 0.2 and abs(pitch - 40.0) < 0.2  # ring 2 is turned by 45 deg


def test_stitched_equirect_matches_the_source(stitched, photos, reference):
    band = seam_band(photos.cameras, W_OUT, px=8)
    p, interior, seams = _errors(stitched.image, reference, stitched.coverage, band)
    assert p >= 30.0
    assert seams <= 2 * interior, (seams, interior)
    # the uncovered part is marked: coverage is exactly where some photo looks (up to a pixel)
    from panorama.photo.testdata import footprint_masks
    union = np.any(footprint_masks(photos.cameras, W_OUT), axis=0)
    assert np.mean(union != stitched.coverage) < 0.002
    assert np.all(stitched.image[~stitched.coverage] == 0)
    assert stitched.report.lat_range_deg[1] > 60 and stitched.report.lon_range_deg == (-180.0, 180.0)


def test_known_pose_path_and_masks(photos, reference):
    band = seam_band(photos.cameras, W_OUT, px=8)
    out = compose_equirect(photos.images, photos.cameras, W_OUT, exposure_reference=0)
    p, interior, seams = _errors(out.image, reference, out.coverage, band)
    assert p >= 38.0 and seams <= 2 * interior
    # exposure: the applied gains undo the ones the photos were given (within 3 %)
    np.testing.assert_allclose(out.gains[:, 0] * photos.gains, 1.0, atol=0.03)
    # a masked-out region never reaches the panorama: paint it magenta and mask it
    imgs = [im.copy() for im in photos.images]
    masks = [None] * len(imgs)
    imgs[2][100:200, 150:250] = (255, 0, 255)
    masks[2] = np.ones(imgs[2].shape[:2], bool)
    masks[2][95:205, 145:255] = False
    masked = compose_equirect(imgs, photos.cameras, W_OUT, masks=masks, exposure_reference=0)
    assert psnr(masked.image.astype(np.float32) / 255, reference, masked.coverage) >= p - 0.5
    # an alpha channel is a mask too
    alpha = np.dstack([imgs[2], np.where(masks[2], 255, 0).astype(np.uint8)])
    with_alpha = compose_equirect(imgs[:2] + [alpha] + imgs[3:], photos.cameras, W_OUT, exposure_reference=0)
    assert np.array_equal(with_alpha.image, masked.image)


def test_known_pose_ceiling_and_float_input(sphere, reference):
    # ceiling: clean photos (no noise, no gain), true poses -> only the two resamplings are left
    clean = cut_photos(sphere, ring_poses(((0.0, 8), (40.0, 4))), **PHOTO, gains=np.ones(12), noise=0.0)
    out = compose_equirect([im.astype(np.float32) / 255 for im in clean.images], clean.cameras, W_OUT,
                           exposure="none")
    assert out.image.dtype == np.float32
    assert psnr(out.image, reference, out.coverage) >= 39.5


def test_longitude_wrap_is_seam_free(photos):
    # the same photos turned 180 deg about up: photo 0 now straddles lon +-180, where the
    # unrolled canvas must blend it as anywhere else -> the same panorama, rolled by W/2
    turn = np.eye(4)
    turn[:3, :3] = world_from_view(180.0, 0.0, 0.0)
    turned = [c.with_pose(turn @ c.world_from_cam) for c in photos.cameras]
    a = compose_equirect(photos.images, photos.cameras, W_OUT, exposure_reference=0, seam="voronoi")
    b = compose_equirect(photos.images, turned, W_OUT, exposure_reference=0, seam="voronoi")
    rolled = np.roll(b.image, W_OUT // 2, axis=1)
    assert np.array_equal(np.roll(b.coverage, W_OUT // 2, axis=1), a.coverage)
    assert psnr(rolled.astype(np.float32), a.image.astype(np.float32), a.coverage, peak=255.0) >= 45.0


def test_single_photo_with_known_focal_and_pole(sphere):
    # a photo straight up holds the north pole: it spans every column of the equirect
    cam = Camera.from_fov(320, 240, hfov_deg=90.0, world_from_cam=np.eye(4))
    pose = np.eye(4)
    pose[:3, :3] = world_from_view(0.0, 90.0, 0.0)
    up = cam.with_pose(pose)
    u0, span, r0, r1, whole = _footprint(up, 512, 256)
    assert whole and span == 512 and r0 == 0 and 0 < r1 < 128
    shot = cut_photos(sphere, [(0.0, 90.0)], width=320, height=240, hfov_deg=90.0)
    known = compose_equirect(shot.images, shot.cameras, 512)
    assert known.coverage[0].all() and not known.coverage[-1].any()
    ref = cv2.resize(sphere, (512, 256), interpolation=cv2.INTER_AREA)
    assert psnr(known.image.astype(np.float32) / 255, ref, known.coverage) >= 30.0
    # one photo and its focal length: nothing tells where up is, so it is placed at lon 0, lat 0
    res = stitch_photos(shot.images, width=512, focal_px=shot.cameras[0].fx)
    assert res.report.used == [0] and res.coverage[128, 256] and not res.coverage[0].any()


# ----------------------------------------------------------------------------- the report
def test_report_names_duplicate_other_scene_and_little_overlap(sphere):
    import skimage.data

    # yaw 0, 45, 90 overlap by 30 deg; the 4th photo at 90 + 71.7 shares a 3.3 deg strip
    ps = cut_photos(sphere, [(0.0, 0.0), (45.0, 0.0), (90.0, 0.0), (161.7, 0.0)], width=480, height=360,
                    hfov_deg=75.0, gain_spread=0.1, noise=1 / 255, seed=1)
    dup = np.clip(ps.images[1].astype(int) + np.random.default_rng(5).integers(-2, 3, ps.images[1].shape),
                  0, 255).astype(np.uint8)
    other = cv2.resize(skimage.data.rocket(), (480, 360), interpolation=cv2.INTER_AREA)
    res = stitch_photos(ps.images + [dup, other], width=512,
                        names=["a", "b", "c", "sliver", "b again", "rocket"])
    assert res.report.used == [0, 1, 2]
    assert res.report.dropped == {3: "little_overlap", 4: "duplicate", 5: "no_match"}
    assert res.cameras[3] is None and res.cameras[4] is None
    table = res.report.table()
    for word in ("DROPPED (little_overlap)", "DROPPED (duplicate)", "same view as photo 1", "another scene"):
        assert word in table


def test_zero_usable_photos_is_a_clear_error(sphere):
    import skimage.data

    with pytest.raises(ValueError, match="images: expected at least one photo"):
        stitch_photos([])
    unrelated = [cv2.resize(skimage.data.rocket(), (320, 240)), cv2.resize(skimage.data.chelsea(), (320, 240))]
    with pytest.raises(ValueError, match="no two of the 2 photos could be stitched") as exc:
        stitch_photos(unrelated, width=256)
    assert "no_match" in str(exc.value)
    with pytest.raises(ValueError, match="detector"):
        stitch_photos(unrelated, detector="surf")
    with pytest.raises(ValueError, match="width"):
        stitch_photos(unrelated, width=101)



def _one_feature_photo(width=320, height=240):
    """A flat grey photo with one lopsided blob: SIFT finds exactly one keypoint in it (two
    Gaussians, the second darker and off-centre, so the blob has a single dominant orientation)."""
    y, x = np.mgrid[:height, :width]
    blob = lambda cx, cy, s, a: a * np.exp(-((x - cx) ** 2 + (y - cy) ** 2) / (2 * s ** 2))  # noqa: E731
    g = 128 + blob(width / 2, height / 2, 6.0, 100) + blob(width / 2 + 12, height / 2 + 8.4, 3.6, -40)
    return np.dstack([np.clip(np.rint(g), 0, 255).astype(np.uint8)] * 3)


def test_a_photo_with_one_feature_is_dropped_before_matching(sphere):
    """``ibr stitch-photos`` with a ceiling view (one SIFT keypoint) ended in OpenCV's FLANN
    assertion "(size_t)knn <= index_->size()": the photo went into the 2-nearest-neighbour
    matcher and only then was checked against MIN_FEATURES. It is now dropped as
    ``no_features`` before matching and the others are stitched."""
    from panorama.photo.stitch import MIN_FEATURES
    from panorama.photo.features import detect, registration_images

    one = _one_feature_photo()
    gray, _ = registration_images([one], 0.6)
    assert len(detect(gray)[0].keypoints) == 1  # the case that crashed
    p = cut_photos(sphere, [(0.0, 0.0), (45.0, 0.0)], width=320, height=240, hfov_deg=75.0)
    res = stitch_photos([p.images[0], one, p.images[1]], width=512)
    assert res.report.used == [0, 2] and res.report.dropped == {1: "no_features"}
    assert res.report.images[1].features == 1 and res.cameras[1] is None
    assert f"only 1 features (fewer than {MIN_FEATURES}); not matched" in res.report.table()
    # one good photo left: the documented error, naming the dropped photo's reason
    with pytest.raises(ValueError, match="no two of the 2 photos could be stitched") as exc:
        stitch_photos([p.images[0], one], width=512)
    assert "DROPPED (no_features)" in str(exc.value)


def test_match_skips_photos_with_fewer_than_two_features(photos):
    """The ratio test needs two neighbours: ``match`` leaves the pairs of a photo with one
    keypoint empty instead of handing it to OpenCV's FLANN index (which asserts)."""
    from panorama.photo.features import detect, match, registration_images

    gray, _ = registration_images([photos.images[0], _one_feature_photo(), photos.images[1]], 0.6)
    feats = detect(gray)
    pairs = match(feats)
    assert len(pairs) == 9
    assert [(m.src_img_idx, m.dst_img_idx) for m in pairs[1::3]] == [(0, 1), (-1, -1), (2, 1)]
    assert all(len(pairs[k].matches) == 0 and pairs[k].H is None for k in (1, 3, 5, 7))
    assert pairs[2].src_img_idx == 0 and pairs[2].dst_img_idx == 2 and pairs[2].num_inliers >= 20
    only = match(feats, only=[0, 1])
    assert only[2].H is None and len(only[2].matches) == 0  # photo 2 left out on request


# ----------------------------------------------------------------------------- helpers
def test_helpers_exact_values():
    r = world_from_view(30.0, -20.0, 5.0)
    np.testing.assert_allclose(yaw_pitch_roll(r), (30.0, -20.0, 5.0), atol=1e-12)
    # a pure camera rotation as OpenCV's centred homography has misfit 0
    f = 300.0
    k = np.diag([f, f, 1.0])
    rel = world_from_view(40.0, 0.0, 0.0).T @ world_from_view(0.0, 0.0, 0.0)
    assert rotation_misfit(k @ rel @ np.linalg.inv(k) * 3.7, f, f) < 1e-12
    assert rotation_misfit(np.diag([1.0, 1.0, -1.0]), f, f) == math.inf
    cov = np.zeros((4, 8), bool)
    cov[1, [7, 0, 1]] = True  # wraps across lon 180
    (lo, hi), (la, lb) = coverage_extent(cov)
    assert (lo, hi) == (157.5, 247.5) and (la, lb) == (22.5, 22.5)


# ----------------------------------------------------------------------------- command line
def test_cli_writes_outputs_and_nothing_on_failure(tmp_path, photos, capsys):
    import skimage.data

    from cli import main
    from ibr.io import read_image, write_image

    paths = []
    for k in (0, 1, 2, 8):
        p = tmp_path / f"p{k}.png"
        write_image(p, photos.images[k])
        paths.append(str(p))
    out, faces, rep = tmp_path / "pano.jpg", tmp_path / "faces", tmp_path / "rep.json"
    assert main(["stitch-photos", *paths, "-o", str(out), "--width", "1024", "--cube", str(faces),
                 "--report", str(rep), "--keep-exposure-of", "0"]) == 0
    table = capsys.readouterr().out
    assert "4 of 4 photos used" in table
    pano = read_image(out)
    assert pano.shape == (512, 1024, 3) and pano.dtype == np.uint8
    assert sorted(x.name for x in faces.iterdir()) == [f"{n}.jpg" for n in ("nx", "ny", "nz", "px", "py", "pz")]
    doc = json.loads(rep.read_text())
    assert [p["used"] for p in doc["photos"]] == [True] * 4 and doc["photos"][0]["camera"]["width"] == 400
    # ibr view works on the result
    assert main(["view", str(out), "--yaw", "20", "-o", str(tmp_path / "v.png"), "--width", "64",
                 "--height", "48"]) == 0
    # failure: nothing written, an existing output untouched
    other = tmp_path / "rocket.png"
    write_image(other, cv2.resize(skimage.data.rocket(), (320, 240)))
    before = out.read_bytes()
    assert main(["stitch-photos", str(other), paths[0], "-o", str(out), "--cube", str(tmp_path / "f2")]) == 1
    assert out.read_bytes() == before and not (tmp_path / "f2").exists()
    # an output on an input is refused before any work
    assert main(["stitch-photos", *paths, "-o", paths[0]]) == 1
    assert "refusing to overwrite an input" in capsys.readouterr().err
    assert read_image(paths[0]).shape == (300, 400, 3)



def test_cli_drops_a_one_feature_photo_and_says_so(tmp_path, photos, capsys):
    """The CLI side of the one-feature crash: exit 0, the photo reported as no_features."""
    from cli import main
    from ibr.io import write_image

    paths = []
    for k, img in enumerate([photos.images[0], _one_feature_photo(400, 300), photos.images[1]]):
        paths.append(str(tmp_path / f"p{k}.png"))
        write_image(paths[-1], img)
    out = tmp_path / "pano.png"
    assert main(["stitch-photos", *paths, "-o", str(out), "--width", "512"]) == 0
    captured = capsys.readouterr()
    assert "Traceback" not in captured.err and out.is_file()
    assert "DROPPED (no_features)" in captured.out and "2 of 3 photos used" in captured.out


@pytest.mark.parametrize("detector", ["sift", "orb", "akaze"])
def test_every_offered_detector_finds_features(photos, detector):
    """Each --detector choice builds (OpenCV 5 keeps AKAZE in xfeatures2d) and finds keypoints on
    a textured photo, but none on a flat one."""
    from panorama.photo.features import detect

    gray = cv2.cvtColor(np.ascontiguousarray(photos.images[0]), cv2.COLOR_RGB2GRAY)
    feats = detect([gray, np.full_like(gray, 128)], detector)
    assert len(feats[0].keypoints) >= 50 and len(feats[1].keypoints) == 0


def test_review_findings_free_focals_alpha_masks_grey_and_no_usable_photo(sphere):
    """Found by a review: (1) ``same_focal=False`` dropped a correct photo of another focal
    length (OpenCV's first estimate gives every photo the median focal, and the check before the
    bundle adjustment took the true pair for a false match); (2) a photo's alpha channel, "a 4th
    channel = mask", limited the compositing but not the features; (3) (H, W, 1) grey photos
    crashed the detector; (4) with ``focal_px`` and no usable photo an IndexError replaced the
    documented error."""
    a = cut_photos(sphere, [(0.0, 0.0), (80.0, 0.0)], width=320, height=240, hfov_deg=75.0)
    b = cut_photos(sphere, [(40.0, 0.0)], width=320, height=240, hfov_deg=55.0)
    imgs, cams = [a.images[0], b.images[0], a.images[1]], [a.cameras[0], b.cameras[0], a.cameras[1]]
    r = stitch_photos(imgs, width=512, same_focal=False)
    assert r.report.used == [0, 1, 2]
    focals = [r.report.images[k].focal_px for k in range(3)]
    np.testing.assert_allclose(focals, [c.fx for c in cams], rtol=0.03)  # 208.5 / 307.4 / 208.5
    assert max(rotation_errors_deg(r.cameras, cams)) < 1.0
    p = cut_photos(sphere, [(0.0, 0.0), (45.0, 0.0), (180.0, 0.0)], width=320, height=240, hfov_deg=75.0)
    pa = p.images[0].copy()
    pa[:, :140] = p.images[2][:, 90:230]  # a poster of another view, masked out by alpha
    alpha = np.full(pa.shape[:2], 255, np.uint8)
    alpha[:, :150] = 0
    mask = (alpha > 0).astype(np.uint8)
    by_mask = stitch_photos([pa, p.images[1], p.images[2]], width=512, masks=[mask, None, None])
    opaque = np.full(pa.shape[:2], 255, np.uint8)
    by_alpha = stitch_photos([np.dstack([pa, alpha]), np.dstack([p.images[1], opaque]), np.dstack([p.images[2], opaque])],
                             width=512)
    assert by_alpha.report.images[0].features == by_mask.report.images[0].features
    assert by_alpha.report.used == by_mask.report.used
    grey = [cv2.cvtColor(im, cv2.COLOR_RGB2GRAY)[..., None] for im in p.images[:2]]
    assert stitch_photos(grey, width=256).report.used == [0, 1]
    blank = np.zeros((240, 320, 3), np.uint8)
    with pytest.raises(ValueError, match="no two of the 1 photos could be stitched"):
        stitch_photos([blank], width=256, focal_px=200.0)


def test_fill_outside_the_output_range_is_refused_before_the_work(sphere):
    """``ibr stitch-photos ... --fill 300`` on 8-bit photos ended in an OverflowError traceback
    after the registration; the library refuses it first, naming ``fill``."""
    p = cut_photos(sphere, [(0.0, 0.0), (45.0, 0.0)], width=160, height=120, hfov_deg=75.0)
    for bad in (300, -1, float("nan"), (1, 2)):
        with pytest.raises(ValueError, match="fill: expected"):
            stitch_photos(p.images, width=256, fill=bad)
    assert stitch_photos(p.images, width=256, fill=(255, 0, 255)).report.used == [0, 1]


def test_an_rgb_fill_for_grey_and_rgba_photos(sphere):
    """The output is RGB whatever the photos' channels: fill=(255, 0, 255), the docstring's
    example, was refused for grey and RGBA photos by the new fill check."""
    p = cut_photos(sphere, [(0.0, 0.0), (45.0, 0.0)], width=160, height=120, hfov_deg=75.0)
    rgba = [np.dstack([im, np.full(im.shape[:2], 255, np.uint8)]) for im in p.images]
    r = stitch_photos(rgba, width=256, fill=(255, 0, 255))
    assert r.image.shape[2] == 3 and tuple(r.image[~r.coverage][0]) == (255, 0, 255)


def test_cli_warns_when_most_photos_are_left_out(capsys):
    """A wrong --focal removed every pair as a false match: one photo stitched, exit 0 (docs
    audit). The command now warns when fewer than half the photos are in the photosphere, and
    names --focal when it was given; not when half or more are used."""
    from commands.stitch_photos import _warn_most_dropped

    _warn_most_dropped(1, 12, 1109.5)
    err = capsys.readouterr().err
    assert "WARNING: only 1 of 12 photos are in the photosphere; --focal 1109.5 may not be" in err
    _warn_most_dropped(5, 12, None)
    assert "only 5 of 12 photos" in (err := capsys.readouterr().err) and "the table above says why" in err
    _warn_most_dropped(6, 12, 1109.5)
    _warn_most_dropped(1, 1, None)
    assert "WARNING" not in capsys.readouterr().err
