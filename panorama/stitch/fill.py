"""Hole fill for stitched panoramas: thin disocclusions from the background side, large unseen
regions (a ring rig's polar caps) smoothly.

A stitched eye or panorama has two kinds of holes. Disocclusions beside objects are a few pixels
wide and open along the parallax (rows of an equirect); the directional background fill of
issue 4 (:func:`ibr.render.fill.fill_background`) fills them better than the pull-push of
``ibr interpolate`` (20-21 dB on the hole pixels of the ODS benchmark, against 14.7-16.6 dB,
docs/stitch.md). An ODS eye's parallax runs along its rows by construction, so its holes take
the row fill of stereo pairs instead (:func:`ibr.render.fill.fill_horizontal_parallax`: the
deeper row neighbour, smoothed across rows): ODS from one centre panorama 20.0-21.7 -> 20.3-23.9
dB on the hole pixels, the ring's eyes within 6 px of a seen pixel 24.2-25.4 -> 25.9-26.7 dB
(``benchmarks/bench_stitch.py``). A mono panorama's sources may be displaced in any direction,
so it keeps the fill of rows and columns.
Regions no camera saw (the zenith and nadir of a ring of cameras, 41.5 % of each ODS eye of the
8-camera ring) are tens to hundreds of pixels from any seen pixel; copying rows or columns into
them draws tall streaks. There the fill blends, with the distance to the nearest seen pixel, into
a smooth normalized pyramid of the seen colours (no depth: nothing behind a cap is known).
Measured on the ring's ODS eyes: hole pixels 23.8 -> 25.6 dB at 1024 wide, 24.5 -> 26.3 at 512
(``benchmarks/bench_stitch.py --quick``), no streaks.

Pixel convention: (u, v) = (column, row) of the equirect (or any image), centres at integers. The
equirect's left and right edges are not joined (as in ``fill_background``): in the ring's caps at
512 wide the two edge columns differ by 0.0047 on average (1.2 levels of 255) against 0.001
between neighbouring columns inside; wrapping a quarter of the width around each side brought it
to 0.0029 for 1.5x the work (measured, not kept).
"""

from __future__ import annotations

import numpy as np

from ibr.base.validate import check_choice, check_number

__all__ = ["CAP_PX_PER_WIDTH", "PARALLAX", "RIM_SHARE", "fill_panorama", "fill_stitched", "rim_samples"]

#: Directions of the parallax :func:`fill_panorama` fills along: every way, or rows (ODS eyes).
PARALLAX = ("any", "rows")

#: Hole pixels farther than ``cap_px`` from any seen pixel blend into the smooth fill, fully at
#: twice that distance; ``cap_px`` defaults to this share of the image width (8 px at 1024 wide,
#: 32 at the default 4096), at least 4. Disocclusions of the ODS benchmark reach 4.2 px at 1024
#: wide and are unchanged; on the ring's caps 4 / 8 / 16 px gave 25.7 / 25.6 / 25.3 dB.
CAP_PX_PER_WIDTH = 1.0 / 128

#: :func:`_row_rim_samples`: a seen pixel beside a row run of an ODS eye's holes, on the run's
#: deeper side, is refilled with the run when at least this share of its colour is the nearer
#: side's. 0.15 / 0.3 / none (every such pixel) on the eyes from one centre panorama, hole pixels:
#: 512 wide +1.2 / +1.1 / +1.3 dB left, -0.2 / 0.0 / -1.3 right; 1024 +3.3 / +3.3 / +3.3, -0.5 /
#: 0.0 / -0.6 (eleventh session, the bundled capture scene).
RIM_SHARE = 0.3


def fill_panorama(color, depth, holes, *, cap_px: float | None = None, parallax: str = "any"):
    """Fill the holes of a stitched panorama (or one ODS eye).

    Parameters
    ----------
    color : (H, W) or (H, W, C) array, any dtype (integers are rounded back); the values at
        hole pixels are ignored (NaN allowed there)
    depth : (H, W) float32 range or depth of the seen pixels (NaN where unknown)
    holes : (H, W) bool, the pixels no view saw
    cap_px : float, optional
        Distance (pixels) from the nearest seen pixel beyond which a hole pixel starts to blend
        into the smooth fill (fully at ``2 cap_px``); default ``max(4, W * CAP_PX_PER_WIDTH)``.
    parallax : {"any", "rows"}
        Direction of the parallax that opened the disocclusions: ``"any"`` (a mono panorama
        from sources displaced every way) takes the farther of the row and column neighbours
        (:func:`ibr.render.fill.fill_background`), ``"rows"`` (an ODS eye) the deeper row
        neighbour smoothed across rows (:func:`ibr.render.fill.fill_horizontal_parallax`).

    Returns
    -------
    color, depth, filled
        New arrays, colour in the input's shape: holes take the background side's colour
        (:func:`ibr.render.fill.fill_background`), blended far from any seen pixel into the
        smooth fill; hole pixels the directional fill cannot reach (no seen neighbour with depth
        on their row or column) take the smooth fill alone. The depth is the directional fill's
        (NaN where it reached nothing); ``filled`` marks every hole pixel given a colour (all of
        them when any pixel was seen). Seen pixels are bit-identical.
    """
    import cv2

    if cap_px is not None:
        cap_px = float(check_number("cap_px", cap_px, minimum=0, exclusive_minimum=True))
    check_choice("parallax", parallax, PARALLAX)
    color = np.asarray(color)
    flat = color.ndim == 2
    out, z, filled = _directional(color[..., None] if flat else color, depth, holes, parallax)
    h, w = out.shape[:2]
    holes = np.asarray(holes)
    if holes.any() and not holes.all():
        cap = max(4.0, w * CAP_PX_PER_WIDTH) if cap_px is None else cap_px
        dist = cv2.distanceTransform(holes.astype(np.uint8), cv2.DIST_L2, 5)
        # blend weight of the smooth fill: 0 near seen pixels, 1 from 2 cap_px on, and 1 where the
        # directional fill reached nothing
        t = np.where(filled, np.clip((dist - cap) / cap, 0.0, 1.0), 1.0)
        t[~holes] = 0.0
        far = t > 0
        if far.any():
            seen_color = np.where(holes[..., None], 0.0, out.astype(np.float32))  # hole values ignored
            smooth = _smooth_fill(seen_color, holes)
            tf = t[far][:, None]
            blend = (1.0 - tf) * np.where(filled[far][:, None], out[far].astype(np.float32), 0.0) + tf * smooth[far]
            if out.dtype.kind in "ui":
                info = np.iinfo(out.dtype)
                blend = np.clip(np.rint(blend), info.min, info.max)
            out[far] = blend.astype(out.dtype)
            filled = filled | far
    return (out[..., 0] if flat else out), z, filled


def _directional(color, depth, holes, parallax: str):
    """The background side of each hole, along rows and columns (``"any"``) or along rows
    (``"rows"``): new (colour (H, W, C) in the input dtype, depth float32, filled)."""
    from ibr.render.fill import fill_background, fill_horizontal_parallax

    if parallax == "any":
        return fill_background(color, depth, holes)
    holes = np.asarray(holes)
    seen = ~holes
    out, z, _ = fill_horizontal_parallax(color, depth, seen)
    return out, z, holes & seen.any(axis=1)[:, None]  # a row nobody saw is not filled


def _smooth_fill(color: np.ndarray, holes: np.ndarray) -> np.ndarray:
    """(H, W, C) float32: the seen colours (``color`` 0 at the holes) spread smoothly over the
    holes by a normalized pyramid: ``cv2.pyrDown`` of the weighted colour and of the weight; on
    the way up each level keeps its own normalized colour where its weight is high and takes the
    coarser level's elsewhere; the coarsest level's empty cells take the mean seen colour."""
    import cv2

    weight = (~holes).astype(np.float32)
    mean = color.reshape(-1, color.shape[2]).sum(0) / max(float(weight.sum()), 1.0)
    levels = []
    s, wt = color, weight  # the colour is already 0 at the holes: it is the weighted colour
    while min(s.shape[:2]) > 2:
        levels.append((s, wt))
        s, wt = cv2.pyrDown(s), cv2.pyrDown(wt)
        if s.ndim == 2:  # OpenCV drops a single channel
            s = s[..., None]
    own = np.clip(4.0 * wt, 0.0, 1.0)[..., None]
    val = own * (s / np.maximum(wt, 1e-6)[..., None]) + (1.0 - own) * mean
    for s, wt in reversed(levels):
        up = cv2.pyrUp(val, dstsize=(s.shape[1], s.shape[0]))
        if up.ndim == 2:
            up = up[..., None]
        own = np.clip(4.0 * wt, 0.0, 1.0)[..., None]
        val = own * (s / np.maximum(wt, 1e-6)[..., None]) + (1.0 - own) * up
    return val.astype(np.float32)


def fill_stitched(stitched, views=None):
    """A :class:`~panorama.stitch.rgbd.Stitched` panorama with its holes filled by
    :func:`fill_panorama` (colour and depth; ``holes`` still marks them); returned as is when
    it has none. The one fill of ``ibr stitch`` and of the ODS eyes (``fill="background"``); an
    ODS eye (camera ``eye`` "left" / "right") is filled along its rows (``parallax="rows"``).

    With ``views`` (the sources it was stitched from) a mono panorama's seen pixels beside a hole
    whose winning sample lies on its source's background rim (:func:`rim_samples`) are filled too
    instead of being copied into the hole: a silhouette's mixed colour at the background's depth
    drew a comb of dark stripes into the disocclusion under the bundled rig's eyeball sphere
    (hole pixels at 4096 wide 19.08 -> 20.72 dB; a ring rig's +0.01-0.04 dB). An ODS eye has no
    winner's source rim to read (from one centre panorama, that rule lost up to 3.7 dB on the
    eyes): its seen pixels on the deeper side of a row run of holes whose colour holds much of
    the nearer side's are filled instead (:func:`_row_rim_samples`; the brown crescent beside the
    bundled rig's eyeball sphere in the right eye)."""
    from .rgbd import Stitched

    if not stitched.holes.any():
        return stitched
    eye = getattr(stitched.camera, "eye", "mono")
    holes, depth = stitched.holes, stitched.depth
    rim = None
    if eye in ("left", "right"):
        rim = _row_rim_samples(stitched.color, depth, holes)
    elif views is not None:
        rim = rim_samples(stitched, views)
    if rim is not None and (not rim.any() or (holes | rim).all()):  # none, or nothing left to fill from
        rim = None
    if rim is not None:
        holes, depth = holes | rim, np.where(rim, np.float32(np.nan), depth).astype(np.float32)
    color, depth, _ = fill_panorama(stitched.color, depth, holes,
                                    parallax="rows" if eye in ("left", "right") else "any")
    if rim is not None:  # recoloured, but seen: their depth stays
        depth[rim] = stitched.depth[rim]
    return Stitched(color, depth, stitched.holes, stitched.winner, stitched.camera)


def _row_rim_samples(color, depth, holes, *, share: float = RIM_SHARE) -> np.ndarray:
    """(H, W) bool: seen pixels an ODS eye's row fill should not copy from: for each run of
    ``holes`` along a row with seen pixels at both ends, the end pixel on the deeper side (the
    side :func:`ibr.render.fill.fill_horizontal_parallax` copies) when the next pixel outward is
    seen on the same surface (depth within 3 %) and the end pixel's colour C holds at least
    ``share`` of the nearer end's colour F against that next pixel's B: ``(C - B).(F - B) /
    |F - B|^2 >= share``, with ``|F - B|`` at least 20/255 of the colour range. Such a pixel is a
    silhouette's mixed colour at the background's depth; copied across the run it drew a
    translucent crescent of the foreground beside it. Runs at the image border are left alone.

    ``color`` (H, W) or (H, W, C), any dtype (floats in [0, 1]); ``depth`` (H, W), read where not
    ``holes``; ``holes`` (H, W) bool.
    """
    src = np.asarray(color)
    col = src[..., None] if src.ndim == 2 else src  # read at the runs' ends only
    rng = float(np.iinfo(src.dtype).max) if src.dtype.kind in "ui" else 1.0
    holes = np.asarray(holes, bool)
    z = np.where(holes, np.nan, np.asarray(depth, np.float32))
    h, w = holes.shape
    seen = ~holes
    cols = np.broadcast_to(np.arange(w, dtype=np.int32), (h, w))
    prev_seen = np.maximum.accumulate(np.where(seen, cols, -1), axis=1)  # at or left of each pixel
    next_seen = np.minimum.accumulate(np.where(seen, cols, w)[:, ::-1], axis=1)[:, ::-1]  # at or right
    rim = np.zeros((h, w), bool)
    for step in (1, -1):  # end pixels left of a run (its hole to the right), then right of one
        end = np.zeros((h, w), bool)
        if step == 1:
            end[:, 1:-1] = seen[:, 1:-1] & holes[:, 2:] & seen[:, :-2]
        else:
            end[:, 1:-1] = seen[:, 1:-1] & holes[:, :-2] & seen[:, 2:]
        v, u = np.nonzero(end)
        near = next_seen[v, u + 1] if step == 1 else prev_seen[v, u - 1]  # the run's other end
        ok = (near >= 0) & (near < w)
        v, u, near = v[ok], u[ok], near[ok]
        out = u - step  # the next pixel outward
        zc, zn, zo = z[v, u], z[v, near], z[v, out]
        with np.errstate(invalid="ignore"):
            # the side the row fill copies (fill_rows_background: the left one on a tie)
            deeper = zc >= zn if step == 1 else zc > zn
            same = np.abs(zo - zc) <= 0.03 * zc
        c, f, b = (col[v, x].astype(np.float32) for x in (u, near, out))
        fb = f - b
        n2 = (fb * fb).sum(-1)
        mixed = ((c - b) * fb).sum(-1) >= share * n2
        rim[v, u] = deeper & same & mixed & (n2 >= (20.0 / 255.0 * rng) ** 2)
    return rim


def rim_samples(stitched, views) -> np.ndarray:
    """(H, W) bool: the seen pixels of a stitched panorama that touch a hole (8-neighbours) and
    whose winning source sample (``stitched.winner``, nearest pixel of its projection) lies on
    that source's background rim (:func:`ibr.render.composite.mixed_pixels` ``side="far"``, with
    the view's depth quantization): a silhouette's mixed colour drawn at the background's depth.
    ``views`` are the sources in the order they were stitched; a sample counts only where the
    source's depth there agrees with the panorama's point (within 3 %), so views of another
    stitch or order mark (next to) nothing. Spherical targets only (their depth is the range
    along each ray); none for a pinhole target."""
    import cv2

    from ibr.base.depth import quantization_of
    from ibr.render.composite import mixed_pixels

    from .rgbd import check_views

    views = check_views(views)
    if stitched.winner.size and int(stitched.winner.max()) >= len(views):
        raise ValueError(f"views: the panorama was stitched from at least {int(stitched.winner.max()) + 1} views, "
                         f"got {len(views)}; give the views it was stitched from, in order")

    from ibr.base.ray_camera import SphericalCamera

    holes = stitched.holes
    rim = np.zeros(holes.shape, bool)
    if not isinstance(stitched.camera, SphericalCamera):  # a pinhole target: none marked
        return rim
    ring = cv2.dilate(holes.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool) & ~holes
    ys, xs = np.nonzero(ring)
    if not ys.size:
        return rim
    origin, direction = stitched.camera.rays_world(xs.astype(np.float64), ys.astype(np.float64))
    points = origin + direction * stitched.depth[ys, xs, None]
    winner = stitched.winner[ys, xs]
    for s, view in enumerate(views):
        sel = np.flatnonzero(winner == s)
        if not sel.size:
            continue
        uv, z = view.camera.project(points[sel])
        ok = np.isfinite(uv).all(axis=1)
        u = np.clip(np.floor(uv[ok, 0] + 0.5), 0, view.camera.width - 1).astype(np.intp)
        v = np.clip(np.floor(uv[ok, 1] + 0.5), 0, view.camera.height - 1).astype(np.intp)
        with np.errstate(invalid="ignore"):
            same = np.abs(view.depth[v, u] - z[ok]) <= 0.03 * z[ok]  # this source's sample of it
        far = mixed_pixels(view.depth, side="far", quantization=quantization_of(view))
        rim[ys[sel[ok]], xs[sel[ok]]] = far[v, u] & same
    return rim
