"""Features and pairwise matches of the photos, through ``cv2.detail`` (seed 001, section 7.5:
"features must be found and matched in the overlapping parts of many images").

* :func:`registration_images` scales every photo to the registration resolution (about
  ``megapix`` million pixels, as ``cv2.Stitcher``'s ``registrationResol``) with ``INTER_AREA``;
  pixel centres stay at integers: ``u_work = (u + 0.5) s - 0.5``.
* :func:`detect` runs the detector (SIFT by default) with ``cv2.detail.computeImageFeatures2``.
* :func:`match` runs ``cv2.detail.BestOf2NearestMatcher`` (ratio test, RANSAC homography per
  pair) and then undoes one of its rules: OpenCV sets the confidence of a pair to 0 when it is
  above 3 ("too close images"), which throws away the *strongest* pairs of a well-overlapping,
  well-textured set and left the spanning tree with wrong, weak pairs in our tests. Here the
  confidence is recomputed as OpenCV defines it (Brown & Lowe: inliers / (8 + 0.3 matches)) and
  duplicates are found explicitly instead (:func:`duplicates`).

Keypoint bias. OpenCV's SIFT doubles the image with a centre-aligned resize and halves the
keypoint coordinates with a corner-aligned factor, so its keypoints sit +0.25 px (right and
down) from the pixel-centre convention. Measured on cut-outs of known rotation: a principal
point at (W-1)/2 + 0.25 gives 0.008 deg mean rotation error, (W-1)/2 gives 0.038 deg and
W/2 (OpenCV's default) 0.044 deg. :data:`KEYPOINT_BIAS` holds the offset per detector; the
camera estimate puts the principal point there during bundle adjustment.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

__all__ = ["DETECTORS", "KEYPOINT_BIAS", "MIN_MATCH_FEATURES", "PairData", "detect", "duplicates", "match",
           "pair_data", "registration_images", "rotation_misfit"]

DETECTORS = ("sift", "orb", "akaze")
#: Offset of each detector's keypoints from the pixel-centre convention (registration pixels).
#: SIFT measured (module doc); ORB and AKAZE not measured (0).
KEYPOINT_BIAS = {"sift": 0.25, "orb": 0.0, "akaze": 0.0}
#: ``match_conf`` of BestOf2NearestMatcher per detector: a match is kept when its distance is
#: below (1 - match_conf) times the second best (ratio test 0.7 for SIFT, as Lowe suggests).
MATCH_CONF = {"sift": 0.3, "orb": 0.3, "akaze": 0.3}
#: Fewest keypoints a photo needs to be matched at all: the ratio test compares the 2 nearest.
MIN_MATCH_FEATURES = 2


def _gray_u8(img: np.ndarray) -> np.ndarray:
    """8-bit grey for the detectors (floats are taken as [0, 1], uint16 as [0, 65535])."""
    if img.dtype == np.uint16:
        img = (img.astype(np.float32) * (255.0 / 65535.0))
    elif img.dtype.kind == "f":
        img = np.nan_to_num(img.astype(np.float32)) * 255.0
    if img.dtype != np.uint8:
        img = np.clip(np.rint(img), 0, 255).astype(np.uint8)
    if img.ndim == 3 and img.shape[2] < 3:  # (H, W, 1) grey, or grey + alpha: the grey channel
        img = img[..., 0]
    if img.ndim == 3:
        img = cv2.cvtColor(np.ascontiguousarray(img[..., :3]), cv2.COLOR_RGB2GRAY)
    return np.ascontiguousarray(img)


def registration_images(images, megapix: float) -> tuple[list[np.ndarray], list[float]]:
    """Grey uint8 copies at about ``megapix`` Mpx each (never enlarged) and their scales.

    The scale is ``w_work / w`` of each photo; ``megapix <= 0`` keeps full resolution.
    """
    out, scales = [], []
    for img in images:
        h, w = img.shape[:2]
        s = 1.0 if megapix <= 0 else min(1.0, math.sqrt(megapix * 1e6 / (w * h)))
        g = _gray_u8(img)
        if s < 1.0:
            ww, hh = max(1, int(round(w * s))), max(1, int(round(h * s)))
            g = cv2.resize(g, (ww, hh), interpolation=cv2.INTER_AREA)
            s = ww / w
        out.append(g)
        scales.append(s)
    return out, scales


def _finder(detector: str):
    if detector == "sift":
        return cv2.SIFT_create()
    if detector == "orb":
        return cv2.ORB_create(2000)
    # OpenCV 5 moved AKAZE to the contrib module xfeatures2d (opencv-contrib-python-headless)
    create = getattr(cv2, "AKAZE_create", None) or cv2.xfeatures2d.AKAZE_create
    return create()


def detect(gray_images, detector: str = "sift", masks=None) -> list:
    """``cv2.detail.ImageFeatures`` of every image (``img_idx`` set to its position).

    ``masks``: optional uint8 masks at the same size (features only where mask > 0).
    """
    finder = _finder(detector)
    feats = []
    for k, g in enumerate(gray_images):
        m = None if masks is None or masks[k] is None else masks[k]
        f = cv2.detail.computeImageFeatures2(finder, g, m) if m is not None else \
            cv2.detail.computeImageFeatures2(finder, g)
        f.img_idx = k  # computeImageFeatures2 leaves 0; the matcher and estimators read it
        feats.append(f)
    return feats


def match(features, detector: str = "sift", *, only=None) -> list:
    """n x n pairwise ``MatchesInfo`` (index ``i * n + j``), confidences recomputed without
    OpenCV's "> 3 means too close" zeroing (see module doc).

    Parameters
    ----------
    features : list of cv2.detail.ImageFeatures
        From :func:`detect`, one per photo.
    detector : {'sift', 'orb', 'akaze'}
        The detector that found them (sets the ratio test, :data:`MATCH_CONF`).
    only : sequence of int, optional
        Photos to match (default all). The pairs of every other photo are left empty (no
        matches, ``H`` None), as OpenCV leaves a pair it could not match. A photo with fewer
        than :data:`MIN_MATCH_FEATURES` keypoints is never matched: the 2-nearest-neighbour
        ratio test needs two, and OpenCV's FLANN index asserts ``knn <= index size``.

    Returns
    -------
    list of cv2.detail.MatchesInfo
        ``pairs[i * n + j]`` matches photo i to photo j (source and destination indices i, j;
        -1 on the diagonal, as OpenCV).
    """
    n = len(features)
    keep = [k for k in (range(n) if only is None else only)
            if len(features[k].keypoints) >= MIN_MATCH_FEATURES]
    pairs = [_empty_pair(i, j) for i in range(n) for j in range(n)]
    if len(keep) < 2:
        return pairs
    matcher = cv2.detail.BestOf2NearestMatcher(False, MATCH_CONF[detector])
    sub = list(matcher.apply2([reindexed(features[k], a) for a, k in enumerate(keep)]))
    matcher.collectGarbage()
    m_keep = len(keep)
    for a, i in enumerate(keep):
        for b, j in enumerate(keep):
            m = sub[a * m_keep + b]
            if m.src_img_idx >= 0:
                m.src_img_idx, m.dst_img_idx = i, j
            if m.src_img_idx >= 0 and m.H is not None and np.size(m.H) == 9 and len(m.matches):
                m.confidence = m.num_inliers / (8.0 + 0.3 * len(m.matches))
            pairs[i * n + j] = m
    return pairs


def _empty_pair(i: int, j: int):
    """A ``MatchesInfo`` without matches between photos i and j (-1, -1 on the diagonal)."""
    m = cv2.detail.MatchesInfo()
    m.src_img_idx, m.dst_img_idx = (-1, -1) if i == j else (i, j)
    return m


def reindexed(f, idx: int):
    """A copy of ``ImageFeatures`` ``f`` with ``img_idx`` = ``idx`` (its position in a subset of
    the photos; the caller's object is untouched). Shared by matching and estimation."""
    g = cv2.detail.ImageFeatures()
    g.img_idx, g.img_size, g.keypoints, g.descriptors = idx, f.img_size, f.keypoints, f.descriptors
    return g


@dataclass(frozen=True)
class PairData:
    """Inlier correspondences of one pair (registration pixels): ``src`` (N, 2) in photo i,
    ``dst`` (N, 2) in photo j, and the pair's confidence and homography."""

    i: int
    j: int
    src: np.ndarray
    dst: np.ndarray
    confidence: float
    H: np.ndarray


def pair_data(features, pairs) -> dict[tuple[int, int], PairData]:
    """Inliers of every matched pair i < j, as arrays (read once from the OpenCV objects)."""
    n = len(features)
    pts = [np.array([kp.pt for kp in f.keypoints], np.float64).reshape(-1, 2) for f in features]
    out = {}
    for i in range(n):
        for j in range(i + 1, n):
            m = pairs[i * n + j]
            if m.H is None or np.size(m.H) != 9 or not len(m.matches):
                continue
            keep = np.asarray(m.inliers_mask, bool).ravel()
            q = np.array([d.queryIdx for d in m.matches])[keep]
            t = np.array([d.trainIdx for d in m.matches])[keep]
            out[(i, j)] = PairData(i, j, pts[i][q], pts[j][t], float(m.confidence), np.asarray(m.H, np.float64))
    return out


def duplicates(data: dict, sizes, *, max_shift: float = 0.01, min_inliers: int = 20) -> dict[int, int]:
    """``{j: i}`` for photos j that repeat an earlier photo i (same size; the pair's homography
    moves no image corner by more than ``max_shift`` of the image diagonal). OpenCV's
    homographies are in centred coordinates (origin at (w/2, h/2))."""
    dup = {}
    for (i, j), d in sorted(data.items()):
        if j in dup or i in dup or sizes[i] != sizes[j] or len(d.src) < min_inliers:
            continue
        w, h = sizes[i]
        c = np.array([[-w / 2, -h / 2, 1], [w / 2, -h / 2, 1], [-w / 2, h / 2, 1], [w / 2, h / 2, 1]], np.float64)
        m = c @ d.H.T
        with np.errstate(divide="ignore", invalid="ignore"):
            moved = m[:, :2] / m[:, 2:3]
        shift = np.max(np.linalg.norm(moved - c[:, :2], axis=1))
        if np.isfinite(shift) and shift <= max_shift * math.hypot(w, h):
            dup[j] = i
    return dup


def rotation_misfit(H: np.ndarray, focal_i: float, focal_j: float) -> float:
    """How far a pair's homography is from a camera rotation: ``|M M^T - I|`` (Frobenius) with
    ``M = K_j^-1 H K_i`` scaled to det 1 and ``K = diag(f, f, 1)`` (OpenCV's homographies are in
    centred coordinates). A rotating camera gives 0; in our tests true pairs gave 0.003-0.06,
    true pairs sharing only a 3-4 degree strip 0.16-0.5, and false ones (another scene, a flat
    print of the scene, repeated texture) 0.98 or more. ``inf`` when the homography flips
    orientation."""
    m = np.diag([1.0 / focal_j, 1.0 / focal_j, 1.0]) @ np.asarray(H, np.float64) @ np.diag([focal_i, focal_i, 1.0])
    det = np.linalg.det(m)
    if not np.isfinite(det) or det <= 0:
        return float("inf")
    m = m / np.cbrt(det)
    return float(np.linalg.norm(m @ m.T - np.eye(3)))
