"""``stitch_photos``: overlapping photos taken from one spot -> an equirect photosphere, the
estimated cameras and a report of every photo's fate (seed 001, section 7.5, option 1: "take
pictures with one camera in different directions until the whole sphere is covered").

Pipeline (each step is OpenCV's; see the modules): registration images
(:func:`~panorama.photo.features.registration_images`) -> SIFT features -> best-of-2-nearest
matching with RANSAC homographies (:mod:`~panorama.photo.features`) -> duplicates found ->
largest connected group, homography-based initial cameras, false pairs removed, bundle
adjustment, wave correction, anchor (:mod:`~panorama.photo.estimate`) -> exact re-projection,
exposure compensation, seams, multi-band blending into the equirect
(:mod:`~panorama.photo.compose`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ibr.base.camera import Camera
from ibr.base.validate import check_choice, check_image

from .compose import EXPOSURES, SEAMS, check_fill, check_photo_index, compose_equirect
from .estimate import estimate_rotations, yaw_pitch_roll
from .features import (DETECTORS, KEYPOINT_BIAS, detect, duplicates, match, pair_data, registration_images,
                       rotation_misfit)
from .report import ImageReport, StitchReport

__all__ = ["MAX_ROTATION_MISFIT", "MIN_FEATURES", "MIN_OVERLAP_INLIERS", "StitchResult", "coverage_extent", "native_width",
           "stitch_photos"]

#: Fewer features than this: the photo is dropped as ``no_features``.
MIN_FEATURES = 20
#: A photo that cannot be placed is ``little_overlap`` (rather than ``no_match``) when it has a
#: pair with at least this many RANSAC inliers whose homography is a camera rotation
#: (:func:`~panorama.photo.features.rotation_misfit` below :data:`MAX_ROTATION_MISFIT`).
MIN_OVERLAP_INLIERS = 8
MAX_ROTATION_MISFIT = 0.7


@dataclass
class StitchResult:
    """Result of :func:`stitch_photos`.

    Attributes
    ----------
    image : (W/2, W, C) array
        Equirect photosphere in the photos' dtype (float32 for float photos); pixel (u, v) looks
        at lon = ((u + 0.5)/W - 0.5) 360 deg (0 = +z, toward +x), lat = (0.5 - (v + 0.5)/H) 180 deg.
        Uncovered pixels hold ``fill``.
    coverage : (W/2, W) bool
        True where a photo covers the pixel (the uncovered part is the rest).
    cameras : list of ibr.Camera or None
        Per input photo: the estimated camera (focal length in the photo's own pixels, principal
        point at its centre, ``world_from_cam`` = rotation into the panorama's frame, no
        translation), or None if the photo was dropped.
    report : StitchReport
        Used/dropped photos and why and coverage (:meth:`StitchReport.table`), seconds per stage
        (``seconds``).
    """

    image: np.ndarray
    coverage: np.ndarray
    cameras: list
    report: StitchReport


#: Largest default equirect width (the image ceiling for float RGB: 16384 x 8192 = 2^27 pixels).
MAX_NATIVE_WIDTH = 16384


def native_width(focal_px: float) -> int:
    """Equirect width whose equator texel matches a photo's centre pixel: 2 pi f, rounded up to
    a multiple of 16."""
    return int(math.ceil(2 * math.pi * float(focal_px) / 16.0)) * 16


def coverage_extent(coverage: np.ndarray) -> tuple[tuple[float, float], tuple[float, float]]:
    """((lon_min, lon_max), (lat_min, lat_max)) in degrees of the covered pixels' centres;
    the longitude range is the shortest arc holding every covered column (lon_max may exceed 180
    when it wraps), or (-180, 180) when every column is covered."""
    h, w = coverage.shape
    rows = np.flatnonzero(coverage.any(axis=1))
    cols = np.flatnonzero(coverage.any(axis=0))
    if len(rows) == 0:
        nan = float("nan")
        return (nan, nan), (nan, nan)
    lat = lambda v: (0.5 - (v + 0.5) / h) * 180.0  # noqa: E731
    lon = lambda u: ((u + 0.5) / w - 0.5) * 360.0  # noqa: E731
    lat_rng = (lat(rows[-1]), lat(rows[0]))
    if len(cols) == w:
        return (-180.0, 180.0), lat_rng
    gaps = np.diff(np.append(cols, cols[0] + w))
    k = int(np.argmax(gaps))
    first, last = cols[(k + 1) % len(cols)], cols[k]
    lo, hi = lon(first), lon(last)
    if hi < lo:
        hi += 360.0
    return (lo, hi), lat_rng


def _check_inputs(images, names, masks, focal_px):
    images = list(images)
    if not images:
        raise ValueError("images: expected at least one photo, got none")
    for k, img in enumerate(images):
        check_image(f"images[{k}]", img, channels=(1, 3, 4))
    if names is None:
        names = [f"image {k}" for k in range(len(images))]
    elif len(names) != len(images):
        raise ValueError(f"names: expected {len(images)} names, got {len(names)}")
    if masks is not None and len(masks) != len(images):
        raise ValueError(f"masks: expected one mask (or None) per photo ({len(images)}), got {len(masks)}")
    if focal_px is not None:
        f = np.broadcast_to(np.asarray(focal_px, np.float64), (len(images),))
        if not np.all(np.isfinite(f)) or np.any(f <= 0):
            raise ValueError(f"focal_px: expected positive focal lengths in pixels, got {focal_px!r}")
        focal_px = f
    return images, list(names), focal_px


def _classify(report, est, data, candidates, conf_thresh):
    """Give every candidate photo left out of ``est.used`` its reason (report module doc)."""
    used = set(est.used)
    focal = float(np.median(est.focals)) if est.focals else 1.0
    links = {k: set() for k in candidates}
    for (i, j), d in data.items():
        if i in links and j in links and d.confidence > conf_thresh and (i, j) not in est.rejected_pairs:
            links[i].add(j)
            links[j].add(i)
    for k in candidates:
        if k in used:
            continue
        group, todo = {k}, [k]
        while todo:
            for m in links[todo.pop()] - group:
                group.add(m)
                todo.append(m)
        if len(group) > 1:
            report.images[k].drop("separate_group", f"matches photos {sorted(group - {k})}, a group not "
                                  f"connected to the {len(used)} stitched photos")
            continue
        mine = [(d.src.shape[0], d.confidence, (i, j)) for (i, j), d in data.items() if k in (i, j)]
        rot = [m for m in mine if m[0] >= MIN_OVERLAP_INLIERS
               and rotation_misfit(data[m[2]].H, focal, focal) < MAX_ROTATION_MISFIT]
        n_inl, conf, pair = max(rot or mine, default=(0, 0.0, None))
        other = None if pair is None else (pair[1] if pair[0] == k else pair[0])
        bad = [p for p in est.rejected_pairs if k in p]
        if bad:
            p = max(bad, key=lambda q: est.rejected_pairs[q])
            o = p[1] if p[0] == k else p[0]
            report.images[k].drop("little_overlap", f"its matches with photo {o} contradict the other "
                                  f"photos (median residual {est.rejected_pairs[p]:.1f} px); no other link")
        elif rot:
            report.images[k].drop("little_overlap", f"best match photo {other}: {n_inl} inliers, confidence "
                                  f"{conf:.2f} < {conf_thresh:g}")
        else:
            report.images[k].drop("no_match", f"no match fits a camera rotation (best: {n_inl} inliers"
                                  + (f" with photo {other})" if other is not None else ")")
                                  + ": another scene, or no overlap")


def _drop_featureless(report, feats) -> list[int]:
    """Drop the photos with fewer than :data:`MIN_FEATURES` features as ``no_features`` (before
    matching: OpenCV's matcher asserts on a photo with one feature); return the others' indices."""
    enough = []
    for k, f in enumerate(feats):
        count = len(f.keypoints)
        if count < MIN_FEATURES:
            report.images[k].drop("no_features", f"only {count} features (fewer than {MIN_FEATURES}); not matched")
        else:
            enough.append(k)
    return enough


def stitch_photos(images, *, width: int | None = None, names=None, masks=None, focal_px=None,
                  detector: str = "sift", registration_megapix: float = 0.6, conf_thresh: float = 1.0,
                  same_focal: bool = True, wave_correct: bool = True, reference: int = 0,
                  exposure: str = "gain", exposure_reference: int | None = None, seam: str = "gc_color",
                  bands: int | None = None, fill=0, max_residual_px: float = 3.0,
                  progress=None) -> StitchResult:
    """Stitch overlapping photos taken from one spot into an equirectangular photosphere.

    Parameters
    ----------
    images : sequence of (h, w[, C]) arrays
        Photos (uint8, uint16 or float in [0, 1]; grey or RGB; a 4th channel is an alpha mask).
        Sizes may differ. Positions are assumed equal (a rotating camera).
    width : int, optional
        Output width W (height W/2). Default: :func:`native_width` of the median focal length.
    names : sequence of str, optional
        Names for the report (e.g. file names).
    masks : sequence of (h, w) arrays or None, optional
        Per-photo masks, non-zero = use (features and pixels outside are ignored).
    focal_px : float or sequence, optional
        Known focal length(s) in each photo's pixels; then only rotations are estimated.
    detector : {'sift', 'orb', 'akaze'}
        Feature detector (SIFT is the accurate default).
    registration_megapix : float
        Resolution for features and camera estimation (OpenCV's default 0.6 Mpx; <= 0 = full).
    conf_thresh : float
        Pair confidence (Brown & Lowe, inliers / (8 + 0.3 matches)) that links two photos.
    same_focal : bool
        One camera and zoom for all photos: a single focal length is fitted.
    wave_correct : bool
        Level the horizon (``cv2.detail.waveCorrect``, horizontal).
    reference : int
        Photo whose optical axis is placed at longitude 0 (if it is used; else the first used).
    exposure, exposure_reference, seam, bands, fill
        Compositing options of :func:`panorama.photo.compose_equirect`.
    max_residual_px : float
        Pairs whose matches disagree with the estimate by more than this (registration px,
        median) are removed as false matches.
    progress : callable, optional
        ``progress(step, done, total)``.

    Returns
    -------
    StitchResult

    Raises
    ------
    ValueError
        Bad arguments, or no two photos could be placed together (the message holds the report
        table, naming every photo's reason).
    """
    detector = check_choice("detector", detector, DETECTORS)
    check_choice("exposure", exposure, EXPOSURES)
    check_choice("seam", seam, SEAMS)
    if width is not None and (isinstance(width, bool) or not isinstance(width, (int, np.integer))
                              or width < 4 or width % 2):
        raise ValueError(f"width: expected an even integer >= 4, got {width!r}")
    images, names, focal_px = _check_inputs(images, names, masks, focal_px)
    dtype = np.dtype(images[0].dtype)
    check_fill(fill, np.dtype(np.float32) if dtype.kind == "f" else dtype)  # before the work
    n = len(images)
    for arg, value in (("reference", reference), ("exposure_reference", exposure_reference)):
        check_photo_index(arg, value, n)
    report = StitchReport(images=[ImageReport(k, names[k]) for k in range(n)])
    secs = report.seconds

    t0 = time.perf_counter()
    gray, scales = registration_images(images, registration_megapix)
    # where features may lie: ``masks``, else a photo's 4th channel (alpha > 0), as for compositing
    feature_masks = [masks[k] if masks is not None and masks[k] is not None
                     else (img[..., 3] if img.ndim == 3 and img.shape[2] == 4 else None)
                     for k, img in enumerate(images)]
    reg_masks = None
    if any(m is not None for m in feature_masks):
        import cv2
        reg_masks = [None if m is None else
                     cv2.resize(np.where(np.asarray(m) > 0, 255, 0).astype(np.uint8), g.shape[::-1],
                                interpolation=cv2.INTER_NEAREST) for m, g in zip(feature_masks, gray)]
    feats = detect(gray, detector, reg_masks)
    secs["features"] = time.perf_counter() - t0
    if progress:
        progress("features", n, n)
    for k, f in enumerate(feats):
        report.images[k].features = len(f.keypoints)
    enough = _drop_featureless(report, feats)

    t0 = time.perf_counter()
    pairs = match(feats, detector, only=enough) if n > 1 else []
    data = pair_data(feats, pairs) if n > 1 else {}
    secs["matching"] = time.perf_counter() - t0
    if progress:
        progress("matching", n, n)

    sizes = [g.shape[::-1] for g in gray]
    dup = duplicates(data, sizes)
    candidates = []
    for k in enough:
        if k in dup:
            report.images[k].drop("duplicate", f"same view as photo {dup[k]} (homography moves no corner "
                                  f"by more than 1% of the diagonal)")
        else:
            candidates.append(k)

    t0 = time.perf_counter()
    reg_focal = None if focal_px is None else [focal_px[k] * scales[k] for k in range(n)]
    if len(candidates) < 2 and reg_focal is None:
        est = None
    else:
        est = estimate_rotations(feats, pairs, data, candidates, conf_thresh=conf_thresh, focal_px=reg_focal,
                                 same_focal=same_focal, bias=KEYPOINT_BIAS[detector],
                                 max_residual_px=max_residual_px, wave_correct=wave_correct,
                                 reference=reference)
    secs["cameras"] = time.perf_counter() - t0
    if progress:
        progress("cameras", n, n)
    if est is not None:
        _classify(report, est, data, candidates, conf_thresh)
        report.notes += est.notes
        for (i, j), r in sorted(est.rejected_pairs.items()):
            report.notes.append(f"pair {i}-{j} removed as a false match (median residual {r:.1f} px)")
    else:
        for k in candidates:
            report.images[k].drop("no_match", "no other photo to match" if n == 1 else
                                  "no photo to pair it with")
    if est is None or len(est.used) == 0 or (len(est.used) < 2 and reg_focal is None):
        if est is not None:
            for k in est.used:
                report.images[k].drop("no_match", "matches no other photo well enough")
        raise ValueError("images: no two of the {} photos could be stitched together (a known focal length, "
                         "focal_px or the CLI's --focal, places a single photo):\n{}".format(n, report.table()))

    cameras: list = [None] * n
    for k, r, f in zip(est.used, est.rotations, est.focals):
        h, w = images[k].shape[:2]
        pose = np.eye(4)
        pose[:3, :3] = r
        fk = f / scales[k]
        cameras[k] = Camera(fk, fk, (w - 1) / 2.0, (h - 1) / 2.0, w, h, pose)
        rep = report.images[k]
        rep.used, rep.reason, rep.focal_px = True, "", fk
        rep.yaw_deg, rep.pitch_deg, rep.roll_deg = yaw_pitch_roll(r)
        rep.detail = f"placed; worst pair residual {max((v for p, v in est.residual_px.items() if k in p), default=0.0):.2f} px"
    ref = reference if reference in est.used else est.used[0]
    report.notes.append(f"photo {ref} is at longitude 0; horizon levelled: {bool(wave_correct)}")

    if width is None:
        width = native_width(float(np.median([cameras[k].fx for k in est.used])))
        if width > MAX_NATIVE_WIDTH:  # a long focal length (1e9 px asked for a 6e9-px equirect)
            report.notes.append(f"the photos' native equirect width {width} px exceeds {MAX_NATIVE_WIDTH}; "
                                f"using {MAX_NATIVE_WIDTH} (give width to choose)")
            width = MAX_NATIVE_WIDTH
    used_imgs = [images[k] for k in est.used]
    used_cams = [cameras[k] for k in est.used]
    used_masks = None if masks is None else [masks[k] for k in est.used]
    ref_pos = None
    if exposure_reference is not None:
        if exposure_reference not in est.used:
            raise ValueError(f"exposure_reference: photo {exposure_reference} was not used "
                             f"({report.images[exposure_reference].reason})")
        ref_pos = est.used.index(exposure_reference)
    comp = compose_equirect(used_imgs, used_cams, int(width), masks=used_masks, exposure=exposure,
                            exposure_reference=ref_pos, seam=seam, bands=bands, fill=fill, progress=progress)
    for k, g in zip(est.used, comp.gains):
        report.images[k].gain = float(np.nanmean(g))
    secs.update({f"compose_{k}": v for k, v in comp.seconds.items()})
    report.covered_fraction = float(comp.coverage.mean())
    report.lon_range_deg, report.lat_range_deg = coverage_extent(comp.coverage)
    return StitchResult(comp.image, comp.coverage, cameras, report)
