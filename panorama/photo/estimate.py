"""Camera rotations and focal lengths from pairwise matches, with ``cv2.detail`` (seed 001,
section 7.5: "a hard optimization problem ... matching features while the intrinsic camera
parameters are unknown").

The steps are OpenCV's, in the order of ``cv2.Stitcher``'s panorama mode, with three controls
added where OpenCV fails silently:

1. ``cv2.detail.leaveBiggestComponent``: the photos connected by pairs of confidence above
   ``conf_thresh``; the others are reported (:mod:`panorama.photo.report`).
2. ``cv2.detail.HomographyBasedEstimator``: focal from the homographies, rotations along the
   maximum spanning tree (its matrices are scaled rotations; they are made orthonormal here).
3. **Consistency check** (added): a pair whose inliers disagree with the estimated rotations by
   more than ``max_residual_px`` (median angle x focal) is a false match -- e.g. two views of a
   repetitive texture -- and is removed before bundle adjustment, which has no robust loss and
   would otherwise bend every camera toward it (7-40 deg errors in our tests from one such pair).
4. ``cv2.detail.BundleAdjusterReproj`` refining focal lengths and rotations, with the principal
   point at the centre plus the detector's keypoint bias (:data:`features.KEYPOINT_BIAS`; OpenCV's
   ``BundleAdjusterRay`` fixes it at W/2, which is half a pixel off our convention). With
   ``same_focal`` the median focal is fixed for all photos and the rotations refined again.
5. ``cv2.detail.waveCorrect`` (horizontal): world up = -y is the normal of the plane the cameras'
   x axes span, exact when the photos have no roll. Its sign is then checked against the photos'
   own down axes (OpenCV's choice flipped the world for a full ring plus a symmetric tilted ring).
6. Anchor: the reference photo's optical axis is put at longitude 0 (a rotation about up).

Frames: OpenCV's camera ``R`` maps camera rays to its world (``ray_world = R K^-1 [u, v, 1]``)
with x right, y down, z forward -- the project's frame -- so ``R`` is the rotation block of
``world_from_cam``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from .features import PairData, reindexed

__all__ = ["Estimate", "estimate_rotations", "orthonormal", "yaw_pitch_roll"]


def orthonormal(r) -> np.ndarray:
    """Nearest rotation (SVD) to a 3x3 matrix, det +1."""
    u, _, vt = np.linalg.svd(np.asarray(r, np.float64))
    m = u @ vt
    if np.linalg.det(m) < 0:
        m = u @ np.diag([1.0, 1.0, -1.0]) @ vt
    return m


def yaw_pitch_roll(r) -> tuple[float, float, float]:
    """Degrees (yaw, pitch, roll) with ``r = world_from_view(yaw, pitch, roll)``
    (R_y(yaw) R_x(pitch) R_z(roll), :func:`panorama.directions.world_from_view`)."""
    r = np.asarray(r, np.float64)
    pitch = math.asin(max(-1.0, min(1.0, -r[1, 2])))
    yaw = math.atan2(r[0, 2], r[2, 2])
    roll = math.atan2(r[1, 0], r[1, 1])
    return math.degrees(yaw), math.degrees(pitch), math.degrees(roll)


@dataclass
class Estimate:
    """Result of :func:`estimate_rotations` on the registration images.

    ``used``: indices (into the list given) placed in the panorama; ``rotations[k]`` and
    ``focals[k]`` (registration pixels) belong to ``used[k]``; ``rejected_pairs``: pairs removed
    as inconsistent ``{(i, j): median residual px}``; ``residual_px``: median residual per used
    pair after bundle adjustment.
    """

    used: list[int]
    rotations: list[np.ndarray]
    focals: list[float]
    rejected_pairs: dict = field(default_factory=dict)
    residual_px: dict = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


def _subset(features, pairs, idx):
    """Features and the n' x n' pair list of photos ``idx``, re-indexed (copies of the
    OpenCV objects so the caller's lists are untouched)."""
    n, m = len(features), len(idx)
    feats, sub = [], []
    for a, i in enumerate(idx):
        feats.append(reindexed(features[i], a))
    for a, i in enumerate(idx):
        for b, j in enumerate(idx):
            src = pairs[i * n + j]
            mi = cv2.detail.MatchesInfo()
            if src.src_img_idx >= 0:
                mi.src_img_idx, mi.dst_img_idx = a, b
                mi.matches, mi.inliers_mask, mi.num_inliers = src.matches, src.inliers_mask, src.num_inliers
                mi.H, mi.confidence = src.H, src.confidence
            else:
                mi.src_img_idx, mi.dst_img_idx = -1, -1
            sub.append(mi)
    assert len(sub) == m * m
    return feats, sub


def _residuals(data: dict, idx, rots, focals, centres, conf_thresh, rejected=()) -> dict:
    """Median angle x mean focal (registration px) between matched rays of each used pair."""
    pos = {i: k for k, i in enumerate(idx)}
    out = {}
    for (i, j), d in data.items():
        if i not in pos or j not in pos or d.confidence <= conf_thresh or not len(d.src) \
                or (i, j) in rejected:
            continue
        a, b = pos[i], pos[j]
        rays = []
        for k, p in ((a, d.src), (b, d.dst)):
            cx, cy = centres[k]
            r = np.column_stack([(p[:, 0] - cx) / focals[k], (p[:, 1] - cy) / focals[k], np.ones(len(p))])
            r = r @ rots[k].T
            rays.append(r / np.linalg.norm(r, axis=1, keepdims=True))
        cos = np.clip(np.sum(rays[0] * rays[1], axis=1), -1.0, 1.0)
        out[(i, j)] = float(np.median(np.arccos(cos))) * 0.5 * (focals[a] + focals[b])
    return out


def _drop_pair(pairs, n, i, j):
    for a, b in ((i, j), (j, i)):
        mi = cv2.detail.MatchesInfo()
        mi.src_img_idx, mi.dst_img_idx = a, b
        pairs[a * n + b] = mi


def _cameras(rots, focals, centres):
    cams = []
    for r, f, (cx, cy) in zip(rots, focals, centres):
        c = cv2.detail.CameraParams()
        c.focal, c.aspect, c.ppx, c.ppy = float(f), 1.0, float(cx), float(cy)
        c.R = np.asarray(r, np.float32)
        c.t = np.zeros((3, 1), np.float64)
        cams.append(c)
    return cams


def _bundle_adjust(feats, sub, rots, focals, centres, conf_thresh, refine_focal):
    ba = cv2.detail.BundleAdjusterReproj()
    ba.setConfThresh(float(conf_thresh))
    mask = np.zeros((3, 3), np.uint8)
    if refine_focal:
        mask[0, 0] = 1
    ba.setRefinementMask(mask)
    ok, cams = ba.apply(feats, sub, _cameras(rots, focals, centres))
    if not ok:
        return None
    return [orthonormal(c.R) for c in cams], [float(c.focal) for c in cams]


def estimate_rotations(features, pairs, data: dict, candidates, *, conf_thresh: float = 1.0,
                       focal_px=None, same_focal: bool = True, bias: float = 0.0,
                       max_residual_px: float = 3.0, wave_correct: bool = True,
                       reference: int | None = None) -> Estimate:
    """Rotations (world_from_cam, 3x3) and focal lengths of the largest consistent group.

    Parameters
    ----------
    features, pairs : from :func:`panorama.photo.features.detect` / ``match`` (all photos).
    data : dict
        :func:`panorama.photo.features.pair_data` of the same pairs.
    candidates : list of int
        Photos that may be used (duplicates and featureless photos already removed).
    conf_thresh : float
        Pair confidence above which a pair links two photos (OpenCV's ``panoConfidenceThresh``).
    focal_px : float or list, optional
        Known focal length(s) in registration pixels; then only rotations are estimated.
    same_focal : bool
        All photos share one focal length (one camera, one zoom): the median is fixed.
    bias : float
        Keypoint offset from the pixel-centre convention (registration px).
    max_residual_px : float
        A pair whose median ray residual exceeds this is removed as a false match.
    wave_correct : bool
        Level the horizon with ``cv2.detail.waveCorrect`` (needs 2 or more photos).
    reference : int, optional
        Photo put at longitude 0 (default: the first used photo).
    """
    n = len(features)
    pairs = list(pairs)
    rejected, notes = {}, []
    idx = list(candidates)
    for _ in range(4 * n + 4):
        if not idx:
            return Estimate([], [], [], rejected, {}, notes)
        if len(idx) == 1:
            f0 = focal_px[idx[0]] if focal_px is not None else float(max(features[idx[0]].img_size))
            rots, focals = [np.eye(3)], [float(f0)]
            centres = [((features[idx[0]].img_size[0] - 1) / 2 + bias, (features[idx[0]].img_size[1] - 1) / 2 + bias)]
            break
        feats, sub = _subset(features, pairs, idx)
        if len(idx) > 1:
            comp = [int(k) for k in cv2.detail.leaveBiggestComponent(feats, sub, float(conf_thresh))]
            if len(comp) < len(idx):
                idx = [idx[k] for k in comp]
                feats, sub = _subset(features, pairs, idx)
        centres = [((f.img_size[0] - 1) / 2 + bias, (f.img_size[1] - 1) / 2 + bias) for f in feats]
        if len(idx) == 1:
            continue
        ok, cams = cv2.detail.HomographyBasedEstimator().apply(feats, sub, None)
        if not ok:
            raise RuntimeError("photos: OpenCV could not estimate initial cameras from the matches")
        rots = [orthonormal(c.R) for c in cams]
        focals = [float(c.focal) for c in cams] if focal_px is None else [float(focal_px[i]) for i in idx]
        res = _residuals(data, idx, rots, focals, centres, conf_thresh, rejected)
        worst = max(res, key=res.get) if res else None
        # the spanning-tree estimate carries a few pixels of drift: only gross errors here. With
        # a focal length per photo to find (same_focal=False) OpenCV's estimate gives every photo
        # the median focal, so true pairs of different focals look gross: the check after the
        # bundle adjustment judges them (a 208/307/208 px set lost its middle photo here)
        free_focals = focal_px is None and not same_focal
        if worst is not None and res[worst] > 4 * max_residual_px and not free_focals:
            rejected[worst] = res[worst]
            _drop_pair(pairs, n, *worst)
            continue
        out = _bundle_adjust(feats, sub, rots, focals, centres, conf_thresh, focal_px is None)
        if out is None:
            notes.append("bundle adjustment did not converge; using the spanning-tree estimate")
        else:
            rots, focals = out
            if focal_px is None and same_focal:
                fm = float(np.median(focals))
                out = _bundle_adjust(feats, sub, rots, [fm] * len(idx), centres, conf_thresh, False)
                if out is not None:
                    rots, focals = out
        res = _residuals(data, idx, rots, focals, centres, conf_thresh, rejected)
        worst = max(res, key=res.get) if res else None
        if worst is not None and res[worst] > max(max_residual_px, 5 * float(np.median(list(res.values())))):
            rejected[worst] = res[worst]
            _drop_pair(pairs, n, *worst)
            continue
        break
    else:
        raise RuntimeError("photos: the camera estimate did not settle (too many inconsistent pairs)")
    if wave_correct and len(rots) > 1:
        rots = [orthonormal(r) for r in cv2.detail.waveCorrect([np.asarray(r, np.float32) for r in rots],
                                                                 cv2.detail.WAVE_CORRECT_HORIZ)]
        # OpenCV picks the sign of "up" from the cameras' mean viewing direction, which is
        # vertical (no horizontal part) for a full ring plus a symmetric tilted ring: the result
        # then came out upside down. The photos' own "down" axes decide the sign here.
        if sum(r[1, 1] for r in rots) < 0:
            rots = [np.diag([-1.0, -1.0, 1.0]) @ r for r in rots]
    ref = idx.index(reference) if reference in idx else 0
    fwd = rots[ref][:, 2]
    yaw = math.atan2(fwd[0], fwd[2])
    c, s = math.cos(-yaw), math.sin(-yaw)
    turn = np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])  # R_y(-yaw): the reference to lon 0
    rots = [turn @ r for r in rots]
    res = _residuals(data, idx, rots, focals, centres, conf_thresh, rejected)
    return Estimate(idx, rots, focals, rejected, res, notes)
