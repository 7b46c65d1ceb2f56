"""Frame-rate up-conversion of an RGB-D sequence (seed 002 over a whole sequence).

Between every two consecutive key frames i and i + 1 the F - 1 in-between frames at
t = k / F (k = 1 .. F - 1) are rendered from both keys (:func:`ibr.render.iter_interpolate`: quad
meshes, exact homographies, two-source compositing). Over a sequence three things differ from
rendering pairs one at a time:

* **each key's mesh serves both segments it belongs to**: views are loaded one at a time and
  kept for exactly two segments, and the mesh cache of :func:`ibr.render.source_mesh` (keyed on
  the view object) builds it once -- N meshes for N keys, not 2 (N - 1);
* **previous-frame fill runs across segments** (seed 002, step 7): the holes left after
  compositing take the previous *output* frame, including the key frame before the segment and
  the last in-between of the segment before, so the fill never restarts;
* **key frames pass through**: output frame i F is key frame i itself (bit-identical), not a
  re-render of it.

Timeline (the same rule as :func:`ibr.synth.path_frame_cameras`, which renders the ground truth):
output frame j belongs to segment i = j // F at phase k = j % F; with ``tail=True`` (default) the
F - 1 frames after the last key extrapolate the last segment (t = 1 + k / F), so N frames at r fps
become N F frames at F r fps (the clip keeps its duration); ``tail=False`` ends on the last key,
(N - 1) F + 1 frames.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Iterator

import numpy as np

from ..base.validate import check_choice
from ..base.view import View
from ..render.fill import FILLS, _fill_previous_inplace, parallax_axis
from ..render.supersample import check_supersample
from ..render.rendering import Rendering
from ..render.view_synthesis import check_antialias, iter_interpolate

__all__ = ["SequenceFrame", "frame_count", "frame_schedule", "upconvert"]


@dataclass(frozen=True, eq=False)
class SequenceFrame:
    """One output frame of :func:`upconvert`.

    Attributes
    ----------
    index : int
        Output frame number j.
    segment : int
        First key i of the pair (i, i + 1) the frame is rendered from (``j // factor``; in the
        tail N - 2, the last pair).
    t : float
        Phase between key ``segment`` (0) and the next key (1); > 1 in the tail (extrapolation).
    key : bool
        True for a key frame passed through unchanged.
    rendering : Rendering
        Color (the keys' dtype), depth, ``holes`` (not covered by either key, before filling),
        ``filled`` and the camera.
    """

    index: int
    segment: int
    t: float
    key: bool
    rendering: Rendering

    @property
    def color(self) -> np.ndarray:
        return self.rendering.color

    @property
    def camera(self):
        return self.rendering.camera


def _check_factor(factor) -> int:
    if isinstance(factor, bool) or not isinstance(factor, (int, np.integer)) or factor < 1:
        raise ValueError(f"factor: expected an integer >= 1, got {factor!r}")
    return int(factor)


def frame_count(keys: int, factor: int, *, tail: bool = True) -> int:
    """Number of output frames for ``keys`` key frames: N F with the tail, (N - 1) F + 1 without."""
    factor = _check_factor(factor)
    if isinstance(keys, bool) or not isinstance(keys, (int, np.integer)):
        raise TypeError(f"keys: expected an integer number of key frames, got {keys!r}")
    if keys < 2:
        raise ValueError(f"keys: a sequence to up-convert needs at least 2 views, got {keys}")
    return keys * factor if tail else (keys - 1) * factor + 1


def frame_schedule(keys: int, factor: int, *, tail: bool = True) -> list[tuple[int, float]]:
    """``(segment, t)`` of every output frame (module docstring); key frames have t = 0."""
    n = frame_count(keys, factor, tail=tail)
    out = []
    for j in range(n):
        i, k = divmod(j, factor)
        out.append((i, 0.0) if k == 0 else ((i, k / factor) if i < keys - 1 else (keys - 2, 1 + k / factor)))
    return out


def _key_rendering(view: View) -> Rendering:
    z = view.require_depth("a key frame of an up-conversion")
    none = np.zeros(view.shape, bool)
    return Rendering(view.color, z, none, none, view.camera, 0.0)


def _previous_fill(r: Rendering, previous: Rendering, axis: int) -> Rendering:
    """Seed 002 step 7 over the sequence: hole pixels take the previous output frame where it
    showed background there, the background pull-push along ``axis`` elsewhere
    (:data:`ibr.render.fill.PREVIOUS_MIN_DEPTH`)."""
    if not r.holes.any():
        return r
    two_d = r.color.ndim == 2
    color = np.array(r.color[..., None] if two_d else r.color, order="C")  # copies, filled in place
    depth = np.array(r.depth, np.float32, order="C")
    pc = previous.color[..., None] if previous.color.ndim == 2 else previous.color
    filled = _fill_previous_inplace(color, depth, r.holes, None, pc, previous.depth, axis=axis)
    return Rendering(color[..., 0] if two_d else color, depth, r.holes, filled, r.camera, r.t)


def upconvert(
    views: Iterable[View],
    factor: int,
    *,
    fill: str = "previous",
    tail: bool = True,
    method: str = "mesh",
    composite_mode: str = "blend",
    interpolation: str = "sharp",
    mesh_options: dict | None = None,
    supersample: int = 1,
    antialias: bool = False,
) -> Iterator[SequenceFrame]:
    """Up-convert a sequence of RGB-D key frames by ``factor`` (yields frames in order).

    Parameters
    ----------
    views : iterable of View
        Key frames with depth, same size and color dtype, in time order. A generator (e.g.
        :func:`ibr.sequence.iter_views`) is consumed lazily: at most two views are alive at once.
    factor : int
        F >= 1: F - 1 new frames between consecutive keys.
    fill : {"previous", "inpaint", "none"}
        Holes left after compositing: the previous output frame across the whole sequence where
        it showed background there (default, seed step 7 with a depth test; elsewhere the
        background pull-push), the depth-aware background fill of each frame, or nothing.
    tail : bool
        Extrapolate F - 1 frames after the last key (default; keeps the clip's duration).
    method, composite_mode, interpolation, mesh_options, supersample, antialias
        As in :func:`ibr.interpolate`.

    Yields
    ------
    SequenceFrame

    Raises
    ------
    ValueError
        Fewer than two views, a view without depth, views of different sizes or dtypes, bad
        options (raised when reached: frames before the bad view have been yielded).
    """
    factor = _check_factor(factor)
    check_choice("fill", fill, FILLS)
    check_supersample(supersample)
    antialias = check_antialias(antialias, method)
    inner_fill = "none" if fill == "previous" else fill
    opts = dict(method=method, composite_mode=composite_mode, interpolation=interpolation,
                mesh_options=mesh_options, fill=inner_fill, supersample=supersample, antialias=antialias)
    it = iter(views)
    try:
        a = next(it)
    except StopIteration:
        raise ValueError("views: a sequence to up-convert needs at least 2 views, got none") from None
    index = 0
    previous = _key_rendering(a)
    yield SequenceFrame(index, 0, 0.0, True, previous)
    segment, last_pair = 0, None

    def between(va, vb, ts, seg):
        nonlocal previous, index
        for r in iter_interpolate(va, vb, list(ts), **opts):
            if fill == "previous":
                r = _previous_fill(r, previous, parallax_axis(r.camera, [va.camera, vb.camera]))
            previous = r
            index += 1
            yield SequenceFrame(index, seg, float(r.t), False, r)

    for b in it:
        if factor > 1:
            yield from between(a, b, [k / factor for k in range(1, factor)], segment)
        segment += 1
        previous = _key_rendering(b)
        index += 1
        yield SequenceFrame(index, segment, 0.0, True, previous)
        last_pair, a = (a, b), b
    if last_pair is None:
        raise ValueError("views: a sequence to up-convert needs at least 2 views, got 1")
    if tail and factor > 1:
        yield from between(*last_pair, [1 + k / factor for k in range(1, factor)], segment - 1)
