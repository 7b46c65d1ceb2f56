"""Known poses -> equirect: exact re-projection with float maps, OpenCV exposure compensation,
seam finding and multi-band blending (seed 001, section 7.5: with a calibrated rig "the relative
positions and orientations of the cameras are precisely known and stitching becomes easy; still,
corrections for lighting and calibration differences are needed or seams remain visible").

Sampling. Every output pixel's ray comes from the project's equirect convention
(:mod:`panorama.directions`: lon = ((u + 0.5)/W - 0.5) 2 pi, lon 0 = +z toward +x, lat positive
up = -y) and is projected exactly into each photo, ``(u, v) = K R^T d`` (pixel centres at
integers), giving float32 maps for ``cv2.remap`` (bilinear; OpenCV 5 keeps float map
coordinates exact). Outside the photo the maps keep going and the remap reflects the photo
(``BORDER_REFLECT``, as ``cv2.Stitcher`` warps), so the blender's coarse bands see no black
step at a photo's edge; what counts as covered is decided analytically (``z > 0`` and inside
[-0.5, w - 0.5] x [-0.5, h - 0.5]) and by the photo's own mask.

Seam-free longitude wrap. OpenCV's blender works on one rectangle, the sphere has no edge. The
blend runs on an *unrolled* canvas of W + P columns starting at equirect column ``c0`` (chosen so
that photos hang over the right edge as little as possible): a photo across the right edge is fed
whole, and every photo within P columns of the left edge is fed a second time W columns to the
right. Canvas columns [O, W + P) then hold every photo that covers them (O = the largest
overhang); the output takes W of them at least one blend radius r from both ends (P = O + 2r),
so no column of the result is next to a cut. The poles need nothing special (a photo holding a
pole spans every column).

OpenCV parts used: ``cv2.detail.GainCompensator`` / ``ChannelsCompensator`` (gains solved on
low-resolution warps, applied here), ``GraphCutSeamFinder`` / ``DpSeamFinder`` /
``VoronoiSeamFinder`` (low resolution, as ``cv2.Stitcher``), ``MultiBandBlender`` (float weights;
images fed as int16 holding value x 8160 so its integer pyramid keeps 13 bits: 255-scale int16
input lost 2.7/255 on average in a test, x 32 loses 0.07/255).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from ibr.base.camera import Camera
from ibr.base.validate import check_choice, check_image, check_image_size

__all__ = ["EXPOSURES", "SEAMS", "Composite", "compose_equirect", "default_bands"]

EXPOSURES = ("gain", "channels", "none")
SEAMS = ("gc_color", "gc_colorgrad", "dp_color", "voronoi", "none")
#: int16 units per unit of colour (1.0 = white) fed to the blender: 255 x 32.
_UNIT = 8160.0


@dataclass
class Composite:
    """An equirect built from posed photos.

    Attributes
    ----------
    image : (H, 2H, C) array
        Input dtype (uint8, uint16, or float32 for float inputs). Uncovered pixels hold ``fill``.
    coverage : (H, 2H) bool
        True where at least one photo (inside its mask) sees the pixel.
    gains : (N, 3) float
        Exposure gain per photo and channel (1 = unchanged; NaN for photos not covering anything).
    bands : int
        Multi-band blender levels used.
    seconds : dict
        Wall time per step.
    """

    image: np.ndarray
    coverage: np.ndarray
    gains: np.ndarray
    bands: int
    seconds: dict = field(default_factory=dict)


@dataclass
class _Piece:
    photo: int
    x0: int
    y0: int
    w: int
    h: int


def default_bands(width: int, height: int) -> int:
    """OpenCV's default number of bands: ceil(log2(5% of sqrt(area))) - 1, within 1..12."""
    blend_width = math.sqrt(width * height) * 0.05
    return min(12, max(1, int(math.ceil(math.log2(max(blend_width, 2.0)))) - 1))  # 12: the blender's most


# ----------------------------------------------------------------------------- geometry
def _project(cam: Camera, d: np.ndarray):
    """Pixel coordinates (u, v) and camera z of world directions d (..., 3)."""
    r = cam.world_from_cam[:3, :3]
    c = d @ r  # (R^T d) for row vectors
    z = c[..., 2]
    zs = np.where(z > 1e-9, z, np.nan)
    u = cam.fx * c[..., 0] / zs + cam.cx
    v = cam.fy * c[..., 1] / zs + cam.cy
    return u, v, z


def _inside(cam: Camera, u, v, z):
    return (z > 1e-9) & (u >= -0.5) & (u <= cam.width - 0.5) & (v >= -0.5) & (v <= cam.height - 0.5)


def _footprint(cam: Camera, width: int, height: int):
    """(u0, span, row0, row1, all_lon): equirect column start and number of columns, row range
    [row0, row1) and whether the photo holds a pole (then it spans every column)."""
    w, h = cam.width, cam.height
    step = 2.0
    t_u = np.append(np.arange(-0.5, w - 0.5, step), w - 0.5)
    t_v = np.append(np.arange(-0.5, h - 0.5, step), h - 0.5)
    border = np.concatenate([
        np.column_stack([t_u, np.full_like(t_u, -0.5)]), np.column_stack([t_u, np.full_like(t_u, h - 0.5)]),
        np.column_stack([np.full_like(t_v, -0.5), t_v]), np.column_stack([np.full_like(t_v, w - 0.5), t_v])])
    rays = np.column_stack([(border[:, 0] - cam.cx) / cam.fx, (border[:, 1] - cam.cy) / cam.fy,
                            np.ones(len(border))]) @ cam.world_from_cam[:3, :3].T
    lon = np.arctan2(rays[:, 0], rays[:, 2])
    lat = np.arctan2(-rays[:, 1], np.hypot(rays[:, 0], rays[:, 2]))
    vv = (0.5 - lat / np.pi) * height - 0.5
    row0, row1 = int(math.floor(vv.min())) - 2, int(math.ceil(vv.max())) + 3
    poles = []
    for sign in (-1.0, 1.0):  # north (up = -y), south
        u, v, z = _project(cam, np.array([0.0, sign, 0.0]))
        poles.append(bool(_inside(cam, u, v, z)))
    if poles[0]:
        row0 = 0
    if poles[1]:
        row1 = height
    row0, row1 = max(0, row0), min(height, row1)
    if any(poles):
        return 0, width, row0, row1, True
    s = np.sort(np.mod(lon, 2 * np.pi))
    gaps = np.diff(np.append(s, s[0] + 2 * np.pi))
    k = int(np.argmax(gaps))
    start = s[(k + 1) % len(s)]                  # the interval begins after the largest gap
    span = 2 * np.pi - gaps[k]
    u_start = ((start / (2 * np.pi)) % 1.0 + 0.5) % 1.0 * width - 0.5   # lon -> u (module doc)
    u0 = int(math.floor(u_start)) - 2
    n = int(math.ceil(span / (2 * np.pi) * width)) + 6
    if n >= width:
        return 0, width, row0, row1, True
    return u0 % width, n, row0, row1, False


def _choose_origin(feet, width: int) -> tuple[int, int]:
    """Canvas origin column c0 and the largest overhang O past W (see module doc)."""
    spans = [(u0, n) for u0, n, _, _, whole in feet if not whole]
    if not spans:
        return 0, 0
    best = None
    for c0 in sorted({u0 for u0, _ in spans} | {0}):
        over = max(max(0, (u0 - c0) % width + n - width) for u0, n in spans)
        if best is None or over < best[1]:
            best = (c0, over)
    return best


def _pieces(feet, width: int, c0: int, canvas_w: int, pad: int) -> list[_Piece]:
    out = []
    for k, (u0, n, r0, r1, whole) in enumerate(feet):
        if r1 <= r0:
            continue
        if whole:
            out.append(_Piece(k, 0, r0, canvas_w, r1 - r0))
            continue
        x0 = (u0 - c0) % width
        out.append(_Piece(k, x0, r0, min(n, canvas_w - x0), r1 - r0))
        if x0 < pad:  # the copy one turn to the right (its longitudes again)
            x1 = x0 + width
            if x1 < canvas_w:
                out.append(_Piece(k, x1, r0, min(n, canvas_w - x1), r1 - r0))
    return out


def _piece_maps(cam: Camera, piece: _Piece, width: int, height: int, c0: int, scale: float,
                rect=None):
    """float32 maps into the photo and the analytic coverage mask for a piece at ``scale``
    (canvas pixel x at scale s is full-resolution canvas coordinate (x + 0.5)/s - 0.5)."""
    x0, y0, w, h = rect if rect is not None else (piece.x0, piece.y0, piece.w, piece.h)
    xs = (np.arange(x0, x0 + w, dtype=np.float64) + 0.5) / scale - 0.5
    ys = (np.arange(y0, y0 + h, dtype=np.float64) + 0.5) / scale - 0.5
    lon = ((xs + c0 + 0.5) / width - 0.5) * 2 * np.pi
    lat = (0.5 - (ys + 0.5) / height) * np.pi
    cl = np.cos(lat)[:, None]
    d = np.empty((h, w, 3))
    d[..., 0] = cl * np.sin(lon)[None, :]
    d[..., 1] = -np.sin(lat)[:, None]
    d[..., 2] = cl * np.cos(lon)[None, :]
    u, v, z = _project(cam, d)
    inside = _inside(cam, u, v, z)
    big = 1e5  # behind the camera: any far coordinate (reflected; never covered)
    mx = np.nan_to_num(np.clip(u, -big, big), nan=-big).astype(np.float32)
    my = np.nan_to_num(np.clip(v, -big, big), nan=-big).astype(np.float32)
    return mx, my, inside


def _warp(img, mask, cam, piece, width, height, c0, scale, rect=None):
    mx, my, inside = _piece_maps(cam, piece, width, height, c0, scale, rect)
    out = cv2.remap(img, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    if mask is not None:
        m = cv2.remap(mask, mx, my, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        inside &= m >= 128
    return out, inside


# ----------------------------------------------------------------------------- inputs
def _as_float_rgb(name: str, img) -> tuple[np.ndarray, np.ndarray | None]:
    """(H, W, 3) float32 in [0, 1] units and the alpha mask (uint8 0/255) if there was one."""
    arr = check_image(name, img, channels=(1, 3, 4))
    alpha = None
    if arr.ndim == 2:
        arr = np.repeat(arr[..., None], 3, axis=2)
    elif arr.shape[2] == 1:
        arr = np.repeat(arr, 3, axis=2)
    elif arr.shape[2] == 4:
        alpha = arr[..., 3]
        arr = arr[..., :3]
    if arr.dtype == np.uint8:
        f = arr.astype(np.float32) / 255.0
        amax = 255
    elif arr.dtype == np.uint16:
        f = arr.astype(np.float32) / 65535.0
        amax = 65535
    elif arr.dtype.kind == "f":
        f = np.nan_to_num(arr.astype(np.float32))
        amax = 1.0
    else:
        raise TypeError(f"{name}: expected uint8, uint16 or float colour, got {arr.dtype}")
    if alpha is not None:
        alpha = np.where(alpha.astype(np.float64) >= 0.5 * amax, 255, 0).astype(np.uint8)
    return np.ascontiguousarray(f), alpha


def _fill_masked(img: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """Copy of ``img`` whose masked-out pixels (mask == 0) hold a smooth extension of the
    pixels around them (normalized box filters of growing size), so that the blender's coarse
    bands, which reach up to 2^bands px past a mask's edge, carry no trace of what was masked."""
    valid = (mask > 0).astype(np.float32)
    if valid.all():
        return img
    out = img.copy()
    todo = valid == 0
    k = 3
    while todo.any() and k < 4 * max(img.shape[:2]):
        num = cv2.blur(img * valid[..., None], (k, k), borderType=cv2.BORDER_REFLECT)
        den = cv2.blur(valid, (k, k), borderType=cv2.BORDER_REFLECT)
        ok = todo & (den > 1e-3)
        out[ok] = num[ok] / den[ok][:, None]
        todo &= ~ok
        k = 2 * k + 1
    out[todo] = 0.0
    return out


def _mask_u8(name: str, mask, shape) -> np.ndarray | None:
    if mask is None:
        return None
    m = np.asarray(mask)
    if m.shape != tuple(shape):
        raise ValueError(f"{name}: expected a mask of shape {tuple(shape)} (the photo's height, width), "
                         f"got {m.shape}")
    return np.where(m > 0, 255, 0).astype(np.uint8)


def _seam_finder(seam: str):
    if seam == "gc_color":
        return cv2.detail.GraphCutSeamFinder("COST_COLOR")
    if seam == "gc_colorgrad":
        return cv2.detail.GraphCutSeamFinder("COST_COLOR_GRAD")
    if seam == "dp_color":
        return cv2.detail.DpSeamFinder("COLOR")
    if seam == "voronoi":  # (the VoronoiSeamFinder constructor's find() crashed in OpenCV 5.0's binding)
        return cv2.detail.SeamFinder_createDefault(cv2.detail.SeamFinder_VORONOI_SEAM)
    return None


# ----------------------------------------------------------------------------- main
def check_photo_index(name: str, value, n: int) -> None:
    """``value`` is None or the index of one of ``n`` photos (an integer, not a bool), else a
    ValueError naming ``name``."""
    if value is not None and (isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer))
                              or not 0 <= value < n):
        raise ValueError(f"{name}: expected a photo index 0..{n - 1}, got {value!r}")


def check_fill(fill, dtype: np.dtype) -> None:
    """``fill``: a finite value (or one per channel) the output dtype holds (``--fill 300`` for
    uint8 photos was an OverflowError after the work)."""
    f = np.asarray(fill, dtype=np.float64) if not isinstance(fill, (bool, str)) else np.array(np.nan)
    if f.ndim > 1 or (f.ndim == 1 and f.size not in (1, 3)) or not np.all(np.isfinite(f)):  # the output is RGB
        raise ValueError(f"fill: expected a finite value or one per RGB channel, got {fill!r}")
    if dtype.kind == "u" and (np.any(f < 0) or np.any(f > np.iinfo(dtype).max)):
        raise ValueError(f"fill: expected values in [0, {np.iinfo(dtype).max}] for {dtype} photos, got {fill!r}")


def compose_equirect(images, cameras, width: int, *, masks=None, exposure: str = "gain",
                     exposure_reference: int | None = None, seam: str = "gc_color",
                     bands: int | None = None, seam_megapix: float = 0.1, fill=0,
                     progress=None) -> Composite:
    """Equirect (width x width/2) of photos taken from one point with known cameras.

    Parameters
    ----------
    images : sequence of (h, w[, C]) arrays
        uint8, uint16 or float (taken as [0, 1]; values above 4.0 clip); grey is repeated to RGB;
        a fourth channel is an alpha mask (>= half of full scale = use).
    cameras : sequence of :class:`ibr.Camera`
        One per photo, sizes equal to the photos'. Only the rotation of ``world_from_cam`` is
        used (all photos from one point); principal point and focal lengths as given.
    width : int
        Output width W (even); height W / 2. Pixel (u, v) looks at lon = ((u + 0.5)/W - 0.5) 360 deg.
    masks : sequence of (h, w) arrays or None, optional
        Per-photo masks (non-zero = use), e.g. to cut out a tripod or a moving person.
    exposure : {'gain', 'channels', 'none'}
        OpenCV exposure compensation: one gain per photo, one per channel, or none.
    exposure_reference : int, optional
        Photo whose exposure is kept (its gain is 1); default: OpenCV's normalization (gains near 1
        on average).
    seam : {'gc_color', 'gc_colorgrad', 'dp_color', 'voronoi', 'none'}
        OpenCV seam finder run at about ``seam_megapix`` Mpx per photo ('none': every photo keeps
        its whole footprint and the blender averages the overlaps).
    bands : int, optional
        Multi-band blender levels; default OpenCV's rule on the output size (:func:`default_bands`).
    fill : scalar or sequence
        Value written to uncovered pixels (in output units, e.g. 0 or (255, 0, 255) for uint8).
    progress : callable, optional
        ``progress(step, done, total)`` after every photo of each step.

    Returns
    -------
    Composite
        ``image`` in the photos' dtype (float32 for float input), ``coverage``, ``gains``.
    """
    import time

    exposure = check_choice("exposure", exposure, EXPOSURES)
    seam = check_choice("seam", seam, SEAMS)
    if isinstance(width, bool) or not isinstance(width, (int, np.integer)) or width < 4 or width % 2:
        raise ValueError(f"width: expected an even integer >= 4, got {width!r}")
    width = int(width)
    height = width // 2
    images = list(images)
    cameras = list(cameras)
    if not images:
        raise ValueError("images: expected at least one photo, got none")
    if len(cameras) != len(images):
        raise ValueError(f"cameras: expected one camera per photo ({len(images)}), got {len(cameras)}")
    if masks is not None and len(masks) != len(images):
        raise ValueError(f"masks: expected one mask (or None) per photo ({len(images)}), got {len(masks)}")
    check_photo_index("exposure_reference", exposure_reference, len(images))
    out_dtype = np.dtype(np.asarray(images[0]).dtype)
    if out_dtype.kind == "f":
        out_dtype = np.dtype(np.float32)
    check_fill(fill, out_dtype)
    floats, user_masks = [], []
    for k, (img, cam) in enumerate(zip(images, cameras)):
        if not isinstance(cam, Camera):
            raise TypeError(f"cameras[{k}]: expected an ibr.Camera, got {type(cam).__name__}")
        f, alpha = _as_float_rgb(f"images[{k}]", img)
        if (cam.width, cam.height) != (f.shape[1], f.shape[0]):
            raise ValueError(f"cameras[{k}]: camera is {cam.width}x{cam.height} but images[{k}] is "
                             f"{f.shape[1]}x{f.shape[0]}")
        m = _mask_u8(f"masks[{k}]", None if masks is None else masks[k], f.shape[:2])
        if m is None:
            m = alpha
        elif alpha is not None:
            m = np.minimum(m, alpha)
        floats.append(f if m is None else _fill_masked(f, m))
        user_masks.append(m)
    bands = default_bands(width, height) if bands is None else int(bands)
    if not 0 <= bands <= 12:
        raise ValueError(f"bands: expected 0..12, got {bands}")
    t = {}
    t0 = time.perf_counter()

    # -- canvas: origin, overhang, pieces (module doc)
    feet = [_footprint(cam, width, height) for cam in cameras]
    c0, over = _choose_origin(feet, width)
    radius = 2 ** (bands + 1) + 8
    pad = over + 2 * radius
    canvas_w = width + pad
    check_image_size("canvas", canvas_w, height, channels=3, itemsize=4)
    pieces = _pieces(feet, width, c0, canvas_w, pad)

    # -- low resolution: exposure gains and seams
    area = np.mean([p.w * p.h for p in pieces]) if pieces else 1.0
    s_low = min(1.0, math.sqrt(seam_megapix * 1e6 / max(area, 1.0)))
    low_w, low_h = int(math.ceil(canvas_w * s_low)), int(math.ceil(height * s_low))
    low_rects, low_imgs, low_masks = [], [], []
    for i, p in enumerate(pieces):
        x0, y0 = int(math.floor(p.x0 * s_low)), int(math.floor(p.y0 * s_low))
        x1 = min(low_w, int(math.ceil((p.x0 + p.w) * s_low)))
        y1 = min(low_h, int(math.ceil((p.y0 + p.h) * s_low)))
        rect = (x0, y0, max(1, x1 - x0), max(1, y1 - y0))
        src = floats[p.photo]
        if s_low < 1.0:  # photo pre-filtered to about the low canvas's texel size
            k = max(1.0, cameras[p.photo].fx * 2 * np.pi / (width * s_low))
            if k > 1.5:
                src = cv2.resize(src, (max(1, round(src.shape[1] / k)), max(1, round(src.shape[0] / k))),
                                 interpolation=cv2.INTER_AREA)
                cam = cameras[p.photo].resized(src.shape[1], src.shape[0])
            else:
                cam = cameras[p.photo]
            mk = user_masks[p.photo]
            if mk is not None and mk.shape[:2] != src.shape[:2]:
                mk = cv2.resize(mk, (src.shape[1], src.shape[0]), interpolation=cv2.INTER_AREA)
        else:
            cam, mk = cameras[p.photo], user_masks[p.photo]
        img, inside = _warp(src, mk, cam, p, width, height, c0, s_low, rect)
        low_rects.append(rect)
        low_imgs.append(img)
        low_masks.append(np.where(inside, 255, 0).astype(np.uint8))
        if progress:
            progress("low-resolution warp", i + 1, len(pieces))
    t["low_warp"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    n = len(images)
    gains = np.full((n, 3), np.nan)
    covered_any = [bool(m.any()) for m in low_masks]
    if exposure != "none" and len(pieces) > 1:
        kind = cv2.detail.EXPOSURE_COMPENSATOR_GAIN if exposure == "gain" else \
            cv2.detail.EXPOSURE_COMPENSATOR_CHANNELS
        comp = cv2.detail.ExposureCompensator_createDefault(kind)
        u8 = [np.clip(np.rint(im * 255.0), 0, 255).astype(np.uint8)[..., ::-1].copy() for im in low_imgs]
        comp.feed(corners=[(r[0], r[1]) for r in low_rects], images=u8,
                  masks=[cv2.UMat(m) for m in low_masks])
        g = [np.asarray(x, np.float64).ravel() for x in comp.getMatGains()]
        piece_gain = np.array([np.repeat(x, 3)[:3] if x.size == 1 else x[::-1][:3] for x in g])  # BGR->RGB
        for k in range(n):
            sel = [i for i, p in enumerate(pieces) if p.photo == k and covered_any[i]]
            if sel:
                wts = np.array([low_masks[i].sum() for i in sel], np.float64)
                gains[k] = (piece_gain[sel] * wts[:, None]).sum(0) / wts.sum()
        if exposure_reference is not None and np.all(np.isfinite(gains[int(exposure_reference)])):
            gains = gains / gains[int(exposure_reference)]
    else:
        for k in range(n):
            gains[k] = 1.0
    t["exposure"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    finder = _seam_finder(seam)
    seam_masks = low_masks
    if finder is not None and len(pieces) > 1:
        imgs_f = [(np.clip(im * np.where(np.isfinite(gains[p.photo]), gains[p.photo], 1.0), 0, 4) * 255.0)
                  .astype(np.float32)[..., ::-1].copy() for im, p in zip(low_imgs, pieces)]
        found = finder.find(imgs_f, [(r[0], r[1]) for r in low_rects], [cv2.UMat(m) for m in low_masks])
        seam_masks = [m.get() if isinstance(m, cv2.UMat) else np.asarray(m) for m in found]
    t["seams"] = time.perf_counter() - t0

    # -- full resolution: warp, gain, seam mask, blend
    t0 = time.perf_counter()
    blender = cv2.detail.MultiBandBlender(0, bands, cv2.CV_32F)
    blender.prepare((0, 0, canvas_w, height))
    coverage = np.zeros((height, canvas_w), np.uint8)
    kernel = np.ones((3, 3), np.uint8)
    fed = 0
    for i, p in enumerate(pieces):
        if not covered_any[i]:
            continue
        img, inside = _warp(floats[p.photo], user_masks[p.photo], cameras[p.photo], p, width, height, c0, 1.0)
        if not inside.any():
            continue
        coverage[p.y0:p.y0 + p.h, p.x0:p.x0 + p.w] |= inside.astype(np.uint8)
        lx0, ly0, lw, lh = low_rects[i]
        sm = cv2.dilate(seam_masks[i], kernel)
        mx = ((np.arange(p.x0, p.x0 + p.w) + 0.5) * s_low - 0.5 - lx0).astype(np.float32)
        my = ((np.arange(p.y0, p.y0 + p.h) + 0.5) * s_low - 0.5 - ly0).astype(np.float32)
        full_seam = cv2.remap(sm, np.broadcast_to(mx[None, :], (p.h, p.w)).copy(),
                              np.broadcast_to(my[:, None], (p.h, p.w)).copy(), cv2.INTER_LINEAR,
                              borderMode=cv2.BORDER_CONSTANT, borderValue=0)
        m = np.where(inside & (full_seam >= 128), 255, 0).astype(np.uint8)
        g = gains[p.photo] if np.all(np.isfinite(gains[p.photo])) else np.ones(3)
        i16 = np.clip(img * (g.astype(np.float32) * _UNIT), 0, 32767).astype(np.int16)
        blender.feed(i16, m, (p.x0, p.y0))
        fed += 1
        if progress:
            progress("blend", i + 1, len(pieces))
    if fed == 0:
        raise ValueError("cameras: no photo covers any pixel of the output (check the cameras)")
    result, _ = blender.blend(None, None)
    t["blend"] = time.perf_counter() - t0

    start = over + radius
    shift = (start + c0) % width
    eq = np.roll(result[:, start:start + width], shift, axis=1).astype(np.float32) / _UNIT
    cov = np.roll(coverage[:, start:start + width], shift, axis=1).astype(bool)
    if out_dtype == np.uint8:
        img = np.clip(np.rint(eq * 255.0), 0, 255).astype(np.uint8)
    elif out_dtype == np.uint16:
        img = np.clip(np.rint(eq * 65535.0), 0, 65535).astype(np.uint16)
    else:
        img = eq
    img[~cov] = np.asarray(fill, dtype=img.dtype)
    return Composite(img, cov, gains, bands, t)
