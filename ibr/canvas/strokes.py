"""Drawing on a canvas: anti-aliased strokes of a given width and colour (seed 004's whiteboard).

Seed 004 (section 2.2, fig. 6) draws what the mouse sweeps over a plane: every screen point is
picked onto the plane, mapped to the canvas and painted. Here a stroke is a polyline in canvas
pixels (centres at integers). Its shape is the union of round-capped segments of width ``w``
(a "capsule" per segment); each canvas pixel gets the coverage ``clamp(w/2 + 1/2 - dist)`` with
``dist`` the distance from its centre to the polyline (a one-pixel linear ramp across the edge),
and the colour is blended "over" the buffer once per stroke, so overlapping segments of one
stroke do not darken. Points outside the canvas are fine: the stroke is clipped to the buffer,
and a stroke entirely outside changes nothing (:func:`draw_stroke` returns 0 pixels).

:func:`stroke_from_screen` turns screen points of a pinhole camera into canvas polylines by
picking (:mod:`ibr.canvas.pick`); panoramas do the same through :mod:`panorama.canvas`.
"""

from __future__ import annotations

import numpy as np

from ..base.camera import Camera
from ..base.validate import check_array, check_finite_scalar
from .pick import pick_pixels
from .plane import Canvas

__all__ = ["SCREEN_STEP_PX", "draw_stroke", "parse_color", "stroke_from_screen"]


def parse_color(color) -> np.ndarray:
    """RGBA in [0, 1] (float64, shape (4,)) from RGB/RGBA numbers in [0, 1] or ``'#rrggbb[aa]'``."""
    if isinstance(color, str):
        s = color.strip().lstrip("#")
        if len(s) not in (6, 8) or any(ch not in "0123456789abcdefABCDEF" for ch in s):
            raise ValueError(f"color: expected '#rrggbb' or '#rrggbbaa', got {color!r}")
        vals = [int(s[i:i + 2], 16) / 255.0 for i in range(0, len(s), 2)]
        return np.array(vals + [1.0] * (4 - len(vals)))
    c = check_array("color", color, ndim=1, dtype_kind="fiu").astype(np.float64)
    if c.shape not in ((3,), (4,)):
        raise ValueError(f"color: expected 3 or 4 numbers (RGB[A] in [0, 1]), got shape {c.shape}")
    if not np.all(np.isfinite(c) & (c >= 0) & (c <= 1)):
        raise ValueError(f"color: expected values in [0, 1], got {c.tolist()}")
    return np.append(c, 1.0) if len(c) == 3 else c


def _segment_distance(px, py, a, b):
    """Distance from points (px, py) to the segment a-b."""
    d = b - a
    l2 = float(d @ d)
    if l2 == 0.0:
        return np.hypot(px - a[0], py - a[1])
    s = np.clip(((px - a[0]) * d[0] + (py - a[1]) * d[1]) / l2, 0.0, 1.0)
    return np.hypot(px - (a[0] + s * d[0]), py - (a[1] + s * d[1]))


def draw_stroke(canvas: Canvas, points, *, width: float = 3.0, color=(1.0, 0.0, 0.0, 1.0)) -> int:
    """Paint an anti-aliased polyline onto ``canvas.rgba`` (in place).

    Parameters
    ----------
    canvas : Canvas
    points : (N, 2) array
        Canvas pixel coordinates (column, row; centres at integers), N >= 1 (one point is a dot).
        Points may lie outside the buffer.
    width : float
        Stroke width in canvas pixels (> 0).
    color : RGB or RGBA in [0, 1], or '#rrggbb[aa]'
        Stroke colour; its alpha scales the coverage.

    Returns
    -------
    int
        Number of canvas pixels changed (0: the stroke lies entirely outside the canvas).
    """
    if not isinstance(canvas, Canvas):
        raise TypeError(f"canvas: expected a Canvas, got {type(canvas).__name__}")
    pts = check_array("points", points, ndim=2, dtype_kind="fiu").astype(np.float64)
    if pts.shape[1] != 2 or len(pts) < 1:
        raise ValueError(f"points: expected shape (N, 2) with N >= 1, got {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise ValueError("points: expected finite coordinates")
    w = check_finite_scalar("width", width)
    if w <= 0:
        raise ValueError(f"width: expected a positive stroke width in canvas pixels, got {width!r}")
    rgba = parse_color(color)
    r = w / 2.0 + 0.5  # coverage reaches 0 at distance w/2 + 1/2
    cw, ch = canvas.resolution
    u0 = max(int(np.floor(pts[:, 0].min() - r)), 0)
    u1 = min(int(np.ceil(pts[:, 0].max() + r)) + 1, cw)
    v0 = max(int(np.floor(pts[:, 1].min() - r)), 0)
    v1 = min(int(np.ceil(pts[:, 1].max() + r)) + 1, ch)
    if u0 >= u1 or v0 >= v1:
        return 0
    cov = np.zeros((v1 - v0, u1 - u0))
    segs = [(pts[i], pts[i + 1]) for i in range(len(pts) - 1)] or [(pts[0], pts[0])]
    for a, b in segs:  # coverage of the union = max of the segments' coverages
        su0 = max(int(np.floor(min(a[0], b[0]) - r)), u0)
        su1 = min(int(np.ceil(max(a[0], b[0]) + r)) + 1, u1)
        sv0 = max(int(np.floor(min(a[1], b[1]) - r)), v0)
        sv1 = min(int(np.ceil(max(a[1], b[1]) + r)) + 1, v1)
        if su0 >= su1 or sv0 >= sv1:
            continue
        py, px = np.mgrid[sv0:sv1, su0:su1].astype(np.float64)
        c = np.clip(w / 2.0 + 0.5 - _segment_distance(px, py, a, b), 0.0, 1.0)
        sub = cov[sv0 - v0:sv1 - v0, su0 - u0:su1 - u0]
        np.maximum(sub, c, out=sub)
    a_s = cov * rgba[3]
    changed = a_s > 0
    n = int(changed.sum())
    if n == 0:
        return 0
    # "over" with straight alpha: A = a_s + a_d (1 - a_s), C = (c_s a_s + c_d a_d (1 - a_s)) / A
    m = canvas.max_value
    dst = canvas.rgba[v0:v1, u0:u1].astype(np.float64) / m
    a_d = dst[..., 3]
    a_out = a_s + a_d * (1.0 - a_s)
    with np.errstate(invalid="ignore", divide="ignore"):
        col = (rgba[:3] * a_s[..., None] + dst[..., :3] * (a_d * (1.0 - a_s))[..., None]) / a_out[..., None]
    col = np.where(a_out[..., None] > 0, col, 0.0)
    new = np.concatenate([col, a_out[..., None]], axis=-1)
    region = canvas.rgba[v0:v1, u0:u1]
    region[changed] = canvas.from_unit(new[changed])
    return n


def stroke_from_screen(camera: Camera, uv, canvas: Canvas, *, depth=None, others=(), depth_tol: float = 1e-3):
    """Canvas polylines of a stroke drawn at screen pixels ``uv`` (N, 2) of a pinhole camera.

    The screen polyline is sampled at most :data:`SCREEN_STEP_PX` apart along every segment and
    every sample is picked (nearest visible canvas among ``canvas`` and ``others``, against the
    scene ``depth``), so a segment is clipped where it leaves ``canvas`` (off its edge, hidden by
    the scene or by another canvas) even when its end points lie outside it (only the listed
    points were picked before: a line across the canvas between two points off it drew nothing).
    A plane maps screen lines to canvas lines, so each part keeps only the listed points and
    the points where it enters and leaves.

    Returns
    -------
    list of (M, 2) float64 arrays
        Canvas pixel polylines in stroke order; empty when no point lands on ``canvas`` (drawing
        them is a no-op).
    """
    q = check_array("uv", uv, dtype_kind="fiu").astype(np.float64).reshape(-1, 2)
    if not np.all(np.isfinite(q)):
        raise ValueError("uv: expected finite pixel coordinates")
    w, h = camera.shape[1], camera.shape[0]
    samples, vertex, piece = _densify(q, SCREEN_STEP_PX, (-0.5, -0.5, w - 0.5, h - 0.5))
    parts = []
    if len(samples):
        items = [canvas] + list(others)
        index, xy, _ = pick_pixels(camera, samples, items, depth=depth, depth_tol=depth_tol)
        for start, stop in _runs(index == 0, piece):
            keep = vertex[start:stop].copy()
            keep[[0, -1]] = True  # where the part enters and leaves the canvas
            parts.append(xy[start:stop][keep])
    return parts


#: Largest screen distance (pixels) between two picked samples of a stroke.
SCREEN_STEP_PX = 0.5


def _densify(points, step: float, box):
    """(samples (M, 2), is_vertex (M,) bool, piece (M,) int): the polyline ``points`` clipped to
    the screen rectangle ``box`` (u0, v0, u1, v1) and sampled at most ``step`` apart along each
    segment (its own points flagged as vertices); ``piece`` numbers the stretches that are
    continuous on screen (a segment leaving the screen ends one: a stroke that leaves and comes
    back is two parts, and a segment far off screen costs no samples)."""
    if not len(points):
        return np.empty((0, 2)), np.empty(0, bool), np.empty(0, int)
    out, flag, piece = [], [], []
    k, prev_end = 0, None
    for a, b in list(zip(points[:-1], points[1:])) or [(points[0], points[0])]:  # one point: a dot
        clipped = _clip_segment(a, b, box)
        if clipped is None:
            continue
        t0, t1 = clipped
        n = int(np.ceil(np.linalg.norm(b - a) * (t1 - t0) / step))
        t = t0 + (t1 - t0) * np.arange(n + 1) / max(n, 1)  # one sample for a single point
        if prev_end is None or t0 > 0 or not np.array_equal(prev_end, a):
            k += 1  # a new continuous stretch
        else:
            t = t[1:]  # the previous segment's last sample is this one's first
        out.append(a + t[:, None] * (b - a))
        flag.append((t == 0) | (t == 1))
        piece.append(np.full(len(t), k))
        prev_end = b if t1 == 1 else None
    if not out:
        return np.empty((0, 2)), np.empty(0, bool), np.empty(0, int)
    return np.concatenate(out), np.concatenate(flag), np.concatenate(piece)


def _clip_segment(a, b, box):
    """(t0, t1) of the part of segment a + t (b - a), t in [0, 1], inside ``box`` (Liang-Barsky),
    or None when none is."""
    t0, t1 = 0.0, 1.0
    d = b - a
    for p, q in ((-d[0], a[0] - box[0]), (d[0], box[2] - a[0]), (-d[1], a[1] - box[1]), (d[1], box[3] - a[1])):
        if p == 0:
            if q < 0:
                return None
            continue
        r = q / p
        if p < 0:
            t0 = max(t0, r)
        else:
            t1 = min(t1, r)
        if t0 > t1:
            return None
    return t0, t1


def _runs(mask, piece):
    """(start, stop) of every run of True in the 1-D bool ``mask`` within one ``piece`` (>= 1)."""
    label = np.where(mask, piece, 0)
    bounds = np.concatenate([[0], np.flatnonzero(np.diff(label)) + 1, [len(label)]])
    return [(a, b) for a, b in zip(bounds[:-1], bounds[1:]) if label[a] > 0]
