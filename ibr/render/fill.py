"""Hole filling after compositing (seed 002 section 2.2, step 2, and a single-frame fill).

* ``fill_previous``: in an animated transition the holes left after two-source compositing take
  the previous output frame ("painter's algorithm" over the last frame), which avoids flicker.
  Only hole pixels are written.
* ``fill_background``: for a single frame, a depth-aware fill. Disocclusions open *behind*
  foreground objects, so each hole pixel takes the farther (background) of its nearest covered
  neighbours along the row and the column, never the foreground; the filled depth is the
  background's.
* ``fill_pullpush`` (the single-frame default): a background-weighted pull-push pyramid. Each
  covered pixel enters with the weight ``(z / z_max)^power``, so wherever near and far surfaces
  meet in a pyramid cell the farther one (the background a disocclusion opens onto) dominates;
  the push spreads those colours smoothly in 2-D (no row or column streaks), and half of the
  written colour is the background side *along the parallax axis* (where a disocclusion's
  hidden background continues), smoothed across that axis so that it shows no streaks; a short
  run inside a shading ramp of one surface (a strip that neither source sees) is the line
  between its neighbours (:data:`RAMP_REL`).
* ``fill_background_rows``: the same rule along rows only, for horizontal-only parallax (seed
  003): each run of uncovered pixels takes the deeper of its two row neighbours.
* ``fill_horizontal_parallax`` (stereo pairs): the row rule, then each filled pixel smoothed
  across rows (binomial, sigma 1.4 px), so that rows copied from different pixels of a
  silhouette's rim show no streaks.

Both return new arrays and a ``filled`` mask; nothing is invented silently (the interpolation
result carries ``holes`` and ``filled``). Pixel convention: (u, v) = (column, row), centers at
integers.
"""

from __future__ import annotations

import numpy as np

from . import _fill_kernels as _k
from .bands import run_bands
from ..base.first_run import await_kernels
from ..base.validate import check_array, check_image, check_positive

__all__ = ["FILLS", "fill_background", "fill_background_rows", "fill_horizontal_parallax", "fill_previous",
           "fill_pullpush", "parallax_axis"]

#: Fill modes accepted by :func:`ibr.interpolate` and ``ibr interpolate --fill``: the previous
#: frame (sequences), the background pull-push ("inpaint"), issue 4's directional background
#: fill ("background"), or none.
FILLS = ("previous", "inpaint", "background", "none")

#: The pull-push works on the holes' bounding box grown by this many pixels (the context it
#: reads); few small holes then cost a small pyramid.
CONTEXT_PX = 64
#: Pull-push defaults (tuned on the Middlebury motorcycle's disocclusions, docs/edges.md).
PULLPUSH_POWER = 32.0
PULLPUSH_EPS = 0.002
PULLPUSH_MIX = 0.5
#: The directional colour of a hole run of at most DIRECT_CHECK_RUN pixels is used only where
#: its source lies at least at DIRECT_MIN_DEPTH times the pull-push's depth for the pixel. In a
#: sliver between two foreground edges (the clutter box and sphere at t = 0.75) both row
#: neighbours are foreground: the farther one (the box, z = 3.4) is not the wall the hole
#: uncovers (the pull-push says 4.8), and copying it drew a dark line along the box (#11).
#: Measured (bench_edges): clutter after the fill +0.13 dB (36.69 -> 36.82), pixels off by more
#: than 48/255 at t = 0.75 273 -> 229; the motorcycle's wide disocclusions 17.78 -> 17.61 dB;
#: room and grazing unchanged. Checking every run cost the motorcycle 0.35 dB.
DIRECT_MIN_DEPTH = 0.9
DIRECT_CHECK_RUN = 8
#: A hole run of RAMP_MIN_RUN to DIRECT_CHECK_RUN pixels whose two neighbours on the axis lie within
#: RAMP_REL of each other in depth, with the colour changing across it at the pace it changes
#: just outside it (within RAMP_SLOPE of the colour's full scale per pixel, every channel), is
#: taken as the line between them, unsmoothed and without the pull-push (twenty-second session:
#: the strip beside clutter's left pole at t = 0.75 that neither source sees, inside the chin's
#: shading, was filled flat: its line 7.9 -> 4.2 levels, the default frames +0.04 dB; the
#: motorcycle's holes 17.55 either way; without the slope test its same-depth runs, 3 243
#: pixels, fell from 17.62 to 16.94 dB: a real image's runs between two samples of one depth are
#: mostly no ramps).
RAMP_REL = 0.003
RAMP_SLOPE = 8.0 / 255.0
#: Shorter runs are left to the background fill: checking every run of one or two pixels (the
#: motorcycle's noisy disocclusions are full of them) took the fill from 1.85x to 1.95-2.0x the
#: issue-4 fill's time, against the issue's 2x.
RAMP_MIN_RUN = 3
#: Hole pixels far from every covered pixel (a region out of the sources' view) fade from the mix
#: to the pull-push alone between these distances (px): the copies drew long bands there.
DIRECT_FADE_PX = (64.0, 160.0)
#: Binomial [1 8 28 56 70 56 28 8 1] / 256 (sigma sqrt(2) px): the directional half of the
#: pull-push fill is smoothed with it across the parallax axis.
_ACROSS = np.array([1, 8, 28, 56, 70, 56, 28, 8, 1], np.float32) / np.float32(256)
_ONE_PIXEL = np.zeros((1, 1, 1), np.float32)
#: Dtypes ``cv2.sepFilter2D`` filters as they are (others go through float32).
_FILTER_DTYPES = (np.dtype(np.uint8), np.dtype(np.uint16), np.dtype(np.int16), np.dtype(np.float32),
                  np.dtype(np.float64))


def _check(color, depth, holes):
    color = np.asarray(color)
    depth = np.asarray(depth)
    holes = np.asarray(holes)
    if color.ndim != 3:
        raise ValueError(f"color: expected (H, W, C), got shape {color.shape}")
    if depth.shape != color.shape[:2]:
        raise ValueError(f"depth: expected shape {color.shape[:2]}, got {depth.shape}")
    if holes.shape != color.shape[:2] or holes.dtype != np.bool_:
        raise ValueError(f"holes: expected a bool array of shape {color.shape[:2]}, got {holes.dtype} {holes.shape}")
    return color, depth, holes


def fill_previous(color, depth, holes, previous_color, previous_depth=None):
    """Copy the previous frame into the hole pixels (seed 002 step 7).

    Parameters
    ----------
    color : (H, W, C) array
    depth : (H, W) float32
    holes : (H, W) bool
        Pixels to fill.
    previous_color : (H, W, C) array
        Previous output frame (same shape and dtype as ``color``).
    previous_depth : (H, W) float32, optional
        Its depth; filled pixels get NaN depth when omitted.

    Returns
    -------
    color, depth, filled
        New arrays; ``filled`` equals ``holes``. Pixels outside ``holes`` are bit-identical to the
        input.
    """
    color, depth, holes = _check(color, depth, holes)
    prev = np.asarray(previous_color)
    if prev.shape != color.shape:
        raise ValueError(f"previous_color: expected shape {color.shape}, got {prev.shape}")
    out = color.copy()
    out[holes] = prev[holes]
    z = depth.astype(np.float32, copy=True)
    if previous_depth is None:
        z[holes] = np.nan
    else:
        pz = np.asarray(previous_depth)
        if pz.shape != depth.shape:
            raise ValueError(f"previous_depth: expected shape {depth.shape}, got {pz.shape}")
        z[holes] = pz[holes]
    return out, z, holes.copy()


#: The previous frame fills a hole pixel only where it showed background there: its depth at least
#: this times the depth the background pull-push estimates for the pixel. Copied blindly, it pasted
#: the foreground it held before into the disocclusion the foreground had just left (the bundled
#: clutter pair at t = 0.75: a black stripe of the dark sphere across the light wall, 2.6 dB below
#: the single-frame fill, #11). The estimate leans to the far side but blends in a nearer surface
#: beside a narrow gap (the blue card beside that wall gap: 3.8 between the card's 3.4 and the
#: wall's 4.9), so nothing nearer than the estimate is trusted: 0.9 still pasted the card
#: (bundled pair 36.75 dB against 36.86 at 1.0; the single-frame fill 36.84). Measured on the
#: room walk (`ibr interpolate seq/room_walk.json --factor 4`): flicker in static hole pixels
#: 0.37 (blind copy) -> 0.69 levels (0.9: 0.42; the single-frame fill 5.43), PSNR unchanged.
PREVIOUS_MIN_DEPTH = 1.0


def _fill_previous_inplace(color, depth, holes, replace, previous_color, previous_depth, *, axis: int = 0):
    """Seed 002 step 7 with a depth test, in place (``color`` C-contiguous (H, W, C), ``depth``
    float32): the background pull-push (:func:`fill_pullpush` along ``axis``) fills ``holes``
    and ``replace`` (background-rim samples, never from the previous frame: it holds other
    content there); then every hole pixel whose previous-frame depth is at least
    :data:`PREVIOUS_MIN_DEPTH` times the pull-push's depth there (or that the pull-push could not
    reach) takes the previous frame's colour and depth. Returns ``filled``."""
    pp = holes if replace is None else holes | replace
    filled = _fill_pullpush_inplace(color, depth, pp, axis=axis)
    prev_z = np.asarray(previous_depth, np.float32)
    with np.errstate(invalid="ignore"):
        take = holes & np.isfinite(prev_z) & (~filled | (prev_z >= np.float32(PREVIOUS_MIN_DEPTH) * depth))
    color[take] = previous_color[take]
    depth[take] = prev_z[take]
    return filled | take


def fill_background(color, depth, holes, *, depth_tol: float = 0.05, max_dist: int | None = None):
    """Depth-aware single-frame fill that propagates background, not foreground.

    Each hole pixel looks for the nearest non-hole pixel left, right, up and down (at most
    ``max_dist`` pixels away). The farthest of those depths ``z_bg`` marks the background; the
    candidates with depth ``>= z_bg (1 - depth_tol)`` are averaged with weights 1/distance.

    Parameters
    ----------
    color : (H, W, C) array (any dtype; integer results are rounded)
    depth : (H, W) float32 planar depth, NaN where unknown
    holes : (H, W) bool
    depth_tol : float
        Relative depth band counted as background.
    max_dist : int, optional
        Search radius in pixels (default: unlimited).

    Returns
    -------
    color, depth, filled
        New arrays. ``filled`` marks the hole pixels that got a value; holes without any
        candidate (e.g. a whole empty row and column) stay as they were.
    """
    color, depth, holes = _check(color, depth, holes)
    out = np.ascontiguousarray(color).copy()
    z = np.ascontiguousarray(depth, dtype=np.float32).copy()
    return out, z, _fill_background_inplace(out, z, holes, depth_tol=depth_tol, max_dist=max_dist)


def _fill_background_inplace(color, depth, holes, *, depth_tol: float = 0.05, max_dist=None) -> np.ndarray:
    """:func:`fill_background` writing into ``color`` (C-contiguous (H, W, C)) and ``depth``
    (C-contiguous float32); returns ``filled``. Internal: callers own both arrays."""
    depth_tol = check_positive("depth_tol", depth_tol)
    max_dist = np.iinfo(np.int64).max if max_dist is None else int(check_positive("max_dist", max_dist))
    filled = np.zeros(holes.shape, np.bool_)
    if holes.any():
        await_kernels("background-fill")  # a first `ibr stitch`: the helper may be caching it right now
        _k.background_fill(color, depth, np.ascontiguousarray(holes), depth_tol, max_dist,
                           color.dtype.kind in "ui", filled)
    return filled


def fill_pullpush(color, depth, holes, *, axis: int = 0, power: float = PULLPUSH_POWER,
                  eps: float = PULLPUSH_EPS, smooth: bool = False, mix: float = PULLPUSH_MIX):
    """Streak-free single-frame fill: background-weighted pull-push (see the module docstring).

    Parameters
    ----------
    color : (H, W, C) array (any dtype; integer results are rounded)
    depth : (H, W) float32 planar depth of the covered pixels (NaN where unknown)
    holes : (H, W) bool
        Pixels to fill; every other pixel is returned bit-identical.
    axis : {0, 1}
        Image axis along which the parallax of the camera move runs (0: rows, horizontal
        parallax as in a stereo pair; 1: columns); see :func:`parallax_axis`. Disocclusions open
        along it, so the background continues along it.
    power : float
        Background preference: a covered pixel weighs ``(z / z_max)^power`` (32: a surface at
        80 % of the farthest depth weighs 1e-3 of it); rounded to a power of two. The defaults
        (power, eps, mix) were tuned on the Middlebury motorcycle's disocclusions (docs/edges.md).
    eps : float
        Push strength of the coarser (smoother, more background) level against a cell's own
        weight: ``value = (S + e up) / (W + e)``, ``e = eps * up(W_coarse) / 4``, where
        ``W_coarse`` is the weight behind the coarser value (its own plus what it inherited).
    smooth : bool
        Smooth the half-resolution level with a 3x3 binomial kernel before the last push
        (off by default: with the directional half it scored 0.05 dB lower on the motorcycle).
    mix : float
        Share of the directional background fill along ``axis`` (each run of hole pixels takes
        the farther of its two neighbours on the axis, as :func:`fill_background_rows`; along
        the other axis where a whole line is a hole, e.g. a strip at the border), smoothed
        across the axis by a 9-tap binomial (sigma 1.4 px) so that it shows no streaks, in the
        written colour (0: pull-push only). In runs of at most ``DIRECT_CHECK_RUN`` pixels it is
        used only where its source is about as far as the pull-push's depth for the pixel
        (``DIRECT_MIN_DEPTH``): a sliver between two foreground edges has no background
        neighbour on the axis. Such a run inside a ramp of one surface (``RAMP_REL``,
        ``RAMP_SLOPE``) is written as the line between its neighbours alone.

    Returns
    -------
    color, depth, filled
        New arrays. Hole pixels get colour and a background depth; ``filled`` marks them (all
        holes, unless no pixel of the image is covered).
    """
    color, depth, holes = _check(color, depth, holes)
    out = np.ascontiguousarray(color).copy()
    z = np.ascontiguousarray(depth, dtype=np.float32).copy()
    return out, z, _fill_pullpush_inplace(out, z, holes, axis=axis, power=power, eps=eps, smooth=smooth, mix=mix)


def parallax_axis(camera, sources) -> int:
    """Image axis along which parallax runs for a move from ``sources`` (cameras) to ``camera``:
    0 (rows) when the sources' centres, seen from the target camera, are displaced more along x
    than along y (in pixels at unit depth, ``fx |t_x|`` vs ``fy |t_y|``), else 1 (columns).
    A pure rotation gives 0."""
    cx = cy = 0.0
    for s in sources:
        t = camera.cam_from_world[:3, :3] @ s.position + camera.cam_from_world[:3, 3]
        cx += abs(camera.fx * t[0])
        cy += abs(camera.fy * t[1])
    return 0 if cx >= cy else 1


def _pyramid_sizes(h: int, w: int) -> list[tuple[int, int]]:
    sizes = [(h, w)]
    while sizes[-1][0] > 1 or sizes[-1][1] > 1:
        hh, ww = sizes[-1]
        sizes.append(((hh + 1) // 2, (ww + 1) // 2))
    return sizes


def _fill_pullpush_inplace(color, depth, holes, *, axis=0, power=PULLPUSH_POWER, eps=PULLPUSH_EPS, smooth=False,
                           mix=PULLPUSH_MIX) -> np.ndarray:
    """:func:`fill_pullpush` writing into ``color`` (C-contiguous (H, W, C)) and ``depth``
    (C-contiguous float32); returns ``filled``. Internal: callers own both arrays."""
    import cv2

    if axis not in (0, 1):
        raise ValueError(f"axis: expected 0 (rows) or 1 (columns), got {axis!r}")
    power = check_positive("power", power)
    eps = check_positive("eps", eps)
    if not 0 <= mix <= 1:
        raise ValueError(f"mix: expected a number in [0, 1], got {mix!r}")
    holes = np.ascontiguousarray(holes)
    filled = np.zeros(holes.shape, np.bool_)
    rows, cols = np.flatnonzero(holes.any(axis=1)), np.flatnonzero(holes.any(axis=0))
    if rows.size == 0:
        return filled
    # work on the holes' bounding box plus CONTEXT_PX (few small holes: a small pyramid)
    v0, v1 = max(rows[0] - CONTEXT_PX, 0), min(rows[-1] + 1 + CONTEXT_PX, holes.shape[0])
    u0, u1 = max(cols[0] - CONTEXT_PX, 0), min(cols[-1] + 1 + CONTEXT_PX, holes.shape[1])
    if (v1 - v0) * (u1 - u0) < holes.size:
        box = (slice(v0, v1), slice(u0, u1))
        c, z, hb = (np.ascontiguousarray(a[box]) for a in (color, depth, holes))
        f = _fill_pullpush_inplace(c, z, hb, axis=axis, power=power, eps=eps, smooth=smooth, mix=mix)
        color[box], depth[box], filled[box] = c, z, f
        return filled
    zmax = float(_k.covered_max_depth(depth, holes))  # the farthest covered depth (np.max with a mask: 0.43 ms)
    if not zmax > 0:
        return filled
    h, w, nc = color.shape
    await_kernels("fill")  # a first run: the helper may be caching the fill's kernels right now
    direct, direct_ok, direct_z, ramps = _directional_fill(color, depth, holes, axis, mix)
    squarings = max(int(round(np.log2(power))), 0)
    sizes = _pyramid_sizes(h, w)
    izref = np.float32(1.0 / zmax)
    sums = [None] + [np.empty((hh, ww, nc + 2), np.float32) for hh, ww in sizes[1:]]
    _k.pp_pull0(color, depth, holes, izref, squarings, sums[1])
    for lv in range(2, len(sizes)):
        _pull(sums[lv - 1], sums[lv])
    # push: each level only where the finer level reads it (parents of needed cells + 1 cell)
    k2, k3 = np.ones((2, 2), np.uint8), np.ones((3, 3), np.uint8)
    need = [holes.view(np.uint8)]
    for lv in range(1, len(sizes)):
        # parents of flagged cells (the max over each 2x2 block), + the bilinear taps (and at
        # level 1 the 3x3 smoothing's taps)
        parents = np.ascontiguousarray(cv2.dilate(need[-1], k2, anchor=(0, 0))[::2, ::2])
        need.append(cv2.dilate(parents, k3, iterations=2 if (lv == 1 and smooth) else 1))
    val = _top_values(sums[-1])
    for lv in range(len(sizes) - 2, 0, -1):
        nxt = np.empty_like(sums[lv])
        _k.pp_push(sums[lv], val, np.float32(eps), need[lv], nxt)
        val = nxt
    if smooth and len(sizes) > 1:  # 3x3 binomial at half resolution: no pyramid blocks
        sm = np.empty_like(val)
        _k.binomial3(val, need[1], sm)
        val = sm
    fade = _far_from_covered(holes) if mix > 0 else None
    if fade is not None:  # the pull-push alone, blended in below
        smooth_color, scratch_depth, unused = color.copy(), np.empty_like(depth), np.zeros_like(filled)
        _k.pp_write0(smooth_color, scratch_depth, holes, val, 0.0, direct, direct_ok, direct_z, *ramps, 0.0,
                     np.float32(DIRECT_MIN_DEPTH), color.dtype.kind in "ui", unused)
    _k.pp_write0(color, depth, holes, val, float(mix), direct, direct_ok, direct_z, *ramps, 1.0 if mix > 0 else 0.0,
                 np.float32(DIRECT_MIN_DEPTH), color.dtype.kind in "ui", filled)
    if fade is not None:
        far = fade > 0
        f = fade[far][:, None]
        blend = (1.0 - f) * color[far].astype(np.float32) + f * smooth_color[far].astype(np.float32)
        color[far] = np.rint(blend) if color.dtype.kind in "ui" else blend
    return filled


def _far_from_covered(holes):
    """(H, W) float32 share of the pull-push alone: 0 within DIRECT_FADE_PX[0] of a covered pixel,
    1 beyond DIRECT_FADE_PX[1]; None when no hole pixel is that far (pixels outside the image
    count as far, as for ``cv2.distanceTransform``). The distance transform (0.5 ms on the
    motorcycle, whose disocclusions are all nearer) runs only where such a pixel may be:
    :func:`_may_be_far`."""
    import cv2

    a, b = DIRECT_FADE_PX
    if not _may_be_far(holes, a):
        return None
    dist = cv2.distanceTransform(holes.view(np.uint8), cv2.DIST_L2, 5)
    if not (dist > a).any():
        return None
    return np.clip((dist - a) / (b - a), 0.0, 1.0)


def _may_be_far(holes, a: float, step: int = 4) -> bool:
    """False only when no hole pixel can be farther than ``a`` from every covered pixel, told on
    blocks of ``step`` px (0.1 ms on the motorcycle): a pixel's distance is at most the distance
    between its block and the nearest block holding a covered pixel, plus ``step * sqrt 2``
    (``2 step`` with the distance transform's rounding)."""
    import cv2

    # all-hole blocks: the minimum over each block (erosion anchored at its corner; outside the
    # image counts as hole, the erosion's default border), read at the block corners
    kernel = np.ones((step, step), np.uint8)
    empty = np.ascontiguousarray(cv2.erode(holes.view(np.uint8), kernel, anchor=(0, 0))[::step, ::step])
    if empty.all():
        return True
    return float(cv2.distanceTransform(empty, cv2.DIST_L2, 5).max()) * step + 2 * step > a


def _directional_fill(color, depth, holes, axis, mix):
    """The directional half of :func:`fill_pullpush`: (colour (H, W, C) smoothed across the axis,
    ok (H, W) bool, the depth of each colour's source (H, W) float32, +inf where unchecked, and
    the ramps: (H, W) bool where a run is a ramp's line (:data:`RAMP_REL`) and the colour
    unsmoothed, which those take). ``mix`` 0: nothing (ok all False)."""
    import cv2

    h, w, nc = color.shape
    direct_ok = np.zeros((h, w), np.bool_)
    direct_z = np.full((h, w), np.inf, np.float32)
    ramp = np.zeros((h, w), np.bool_)
    if not mix > 0:
        return _ONE_PIXEL, direct_ok, direct_z, (ramp, _ONE_PIXEL)
    # the background side along the parallax axis (rows or columns) ...
    direct = color.copy()  # the source dtype: uint8 filters fastest, values are copies
    _axis_fill(color, depth, holes, axis, direct, direct_ok, direct_z, ramp)
    lack = holes & ~direct_ok
    unreached = None  # hole pixels whose whole row and column are holes (a corner out of view)
    if lack.any():  # whole lines of holes along the axis (a strip at the border): the other axis
        other, other_ok, other_z = color.copy(), np.zeros((h, w), np.bool_), np.full((h, w), np.inf, np.float32)
        other_ramp = np.zeros((h, w), np.bool_)
        _axis_fill(color, depth, holes, 1 - axis, other, other_ok, other_z, other_ramp)
        take = lack & other_ok
        direct[take] = other[take]
        direct_z[take] = other_z[take]
        ramp[take] = other_ramp[take]
        direct_ok |= take
        unreached = lack & ~other_ok
    # ... smoothed across the axis (binomial, sigma 1.4 px), so that neighbouring rows copied from
    # different pixels do not show as streaks; outside the holes it reads the image (a ramp's line
    # is its own row's: pp_write0 takes it unsmoothed)
    one = np.ones(1, np.float32)
    kx, ky = (_ACROSS, one) if axis == 1 else (one, _ACROSS)
    if direct.dtype not in _FILTER_DTYPES or (unreached is not None and unreached.any()):
        # normalized: the unreached pixels hold whatever the caller left in the holes, never
        # read (float32: also the dtypes OpenCV cannot filter)
        known = np.ones((h, w), np.float32) if unreached is None else (~unreached).astype(np.float32)
        lines = direct.astype(np.float32)
        sums = cv2.sepFilter2D(lines * known[..., None], -1, kx, ky, borderType=cv2.BORDER_REPLICATE).reshape(h, w, nc)
        wts = cv2.sepFilter2D(known, -1, kx, ky, borderType=cv2.BORDER_REPLICATE)
        smoothed = sums / np.maximum(wts, np.float32(1e-6))[..., None]
    else:
        lines = direct
        smoothed = cv2.sepFilter2D(direct, -1, kx, ky, borderType=cv2.BORDER_REPLICATE).reshape(h, w, nc)
    return smoothed, direct_ok, direct_z, (ramp, lines)


def _pull(fine, coarse):
    """Pull step: ``coarse`` = 2x2 box sums of ``fine`` (weighted values and weights, float32),
    added in the order (0, 0), (0, 1), (1, 0), (1, 1); a missing row or column adds nothing.
    numpy slices, not a kernel (a first run compiled one in 0.4 s, #13)."""
    h, w = fine.shape[:2]
    if h % 2 or w % 2:  # an odd side: pad with zeros (exact: x + 0 = x)
        padded = np.zeros((h + h % 2, w + w % 2) + fine.shape[2:], fine.dtype)
        padded[:h, :w] = fine
        fine = padded
    np.add(fine[0::2, 0::2], fine[0::2, 1::2], out=coarse)
    coarse += fine[1::2, 0::2]
    coarse += fine[1::2, 1::2]


def _top_values(sums):
    """Mean values of the coarsest level (last channel: the weight sum; values 0 where it is 0)."""
    wt = sums[..., -1:]
    val = np.zeros_like(sums)
    np.divide(sums[..., :-1], wt, out=val[..., :-1], where=wt > 0)
    val[..., -1:] = wt
    return val


def _axis_fill(color, depth, holes, axis, out, ok, out_z, ramp):
    """:func:`_fill_kernels.axis_background` along rows (axis 0) or columns (axis 1)."""
    slope = RAMP_SLOPE * (float(np.iinfo(color.dtype).max) if color.dtype.kind in "ui" else 1.0)
    args = (DIRECT_CHECK_RUN, RAMP_MIN_RUN, RAMP_REL, slope, color.dtype.kind in "ui")
    if axis == 1:
        _k.axis_background(color.transpose(1, 0, 2), depth.T, holes.T, out.transpose(1, 0, 2), ok.T, out_z.T,
                           ramp.T, *args)
    else:
        _k.axis_background(color, depth, holes, out, ok, out_z, ramp, *args)


def fill_background_rows(color, depth, coverage) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fill uncovered pixels row by row from the background side.

    Each run of uncovered pixels takes the color and depth of the deeper of its two covered row
    neighbours (a disocclusion opens behind a foreground edge, so the background is what the
    hidden area most likely continues); runs at the image border take their only neighbour.
    Returns copies ``(color float32 (H, W, C), depth float32, holes bool)``.
    """
    col, d, cov = _row_fill_inputs(color, depth, coverage)
    col = col.astype(np.float32, copy=False)
    holes = np.zeros(cov.shape, np.bool_)
    run_bands(_k.fill_rows_background, col.shape[0], col, d, cov, holes)
    return col, d, holes


def fill_horizontal_parallax(color, depth, coverage) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Fill the uncovered pixels of a view rendered with horizontal parallax only (a stereo eye).

    Each run of uncovered pixels takes the deeper of its two covered row neighbours (a
    disocclusion opens behind a foreground edge; a run at the border takes its only neighbour),
    as :func:`fill_background_rows`; then every filled pixel's colour is smoothed across rows by
    the binomial [1 8 28 56 70 56 28 8 1] / 256 (sigma 1.4 px) of the row-filled image, so that
    neighbouring rows copied from different pixels of a silhouette's rim show no streaks (#11).
    Depth stays the copied background depth.

    Parameters
    ----------
    color : (H, W) or (H, W, C) array (any dtype; integer results are rounded)
    depth : (H, W) float planar depth (scene units), read where ``coverage`` is True
    coverage : (H, W) bool
        Pixels the rendering covered; every other pixel is filled (its values are ignored).

    Returns
    -------
    color (H, W, C) in the input dtype, depth float32, holes bool
        Copies; ``holes`` is ``~coverage``. Rows without any covered pixel are not filled
        (colour as given, depth NaN).
    """
    col, d, cov = _row_fill_inputs(color, depth, coverage)
    return col, d, _fill_horizontal_parallax_inplace(col, d, cov)


def _row_fill_inputs(color, depth, coverage):
    """Checked copies for the row fills: colour (H, W, C) C-contiguous in its dtype, float32
    depth with NaN where not covered, C-contiguous coverage."""
    col = check_image("color", color)
    col = np.ascontiguousarray(col[..., None] if col.ndim == 2 else col).copy()
    d = check_array("depth", depth, shape=col.shape[:2], dtype_kind="f").astype(np.float32, copy=True)
    cov = np.ascontiguousarray(check_array("coverage", coverage, shape=col.shape[:2], dtype_kind="b"))
    d[~cov] = np.nan
    return col, d, cov


def _fill_horizontal_parallax_inplace(color, depth, coverage) -> np.ndarray:
    """:func:`fill_horizontal_parallax` writing into ``color`` (C-contiguous (H, W, C)) and
    ``depth`` (C-contiguous float32); returns the holes (``~coverage``)."""
    holes = np.zeros(coverage.shape, np.bool_)
    await_kernels("row-fill")  # a first ODS `ibr stitch`: the helper may be caching the row fill right now
    run_bands(_k.fill_rows_background, color.shape[0], color, depth, coverage, holes)
    row_ok = coverage.any(axis=1)  # rows the row fill could fill (the others keep their colour)
    idx = np.flatnonzero(holes)
    smoothed = np.empty((idx.size, color.shape[2]), np.float32)
    _k.smooth_across_rows(color, idx, row_ok, _ACROSS, smoothed)
    if color.dtype.kind in "ui":
        np.floor(smoothed + 0.5, out=smoothed)
    color.reshape(-1, color.shape[2])[idx] = smoothed
    return holes
