"""Experiment (issue 11, not in the library): ceilings of the edge-band targets (32 / 34 dB).

Edge band PSNR (bench_edges.edge_band, t = .25/.5/.75) of

1. the scene itself ray traced into each truth camera with k x k samples per pixel (a box
   filter; the truths are k = 3) and with the antialias option's pattern (the centre counted
   twice and four diagonal subsamples at +-1/3 px): what perfect geometry and colour give;
2. ``interpolate(..., supersample=3)`` with the sources' upsampling replaced by perfect 3x
   sources: the scene's exact depth at 3x with our colour, exact depth and colour (3x3
   supersampled at 3x, not refined by the partner), our depth with the exact colour, and the
   exact colour only at the source's depth-edge pixels (the renderer box-filters every pixel
   since the nineteenth session, as the truths are made); and the exact colour made true to the
   source pixels (each pixel's residual spread over its subsamples: a super-resolution perfect
   up to the observations), everywhere and at the edge pixels only; and the exact colour
   low-passed within each surface to the sources' Nyquist frequency and made true to the
   pixels (an ideal reconstruction at the sources' sampling rate), with our and the exact depth;
3. our upsampled sources with the exact depth where ours is within 2 % of it (what better depth
   values of the surfaces would give) or at the edge subsamples ours puts on another surface
   (what better silhouette labels would give).

Usage (from the repository root): ``python benchmarks/exp_band_ceilings.py`` (about 10 minutes).
docs/edges.md section 1 ("Ceilings of the band targets") has the figures (2026-11-27).
"""

from __future__ import annotations

import contextlib
import dataclasses
import sys
from pathlib import Path
from unittest import mock

import numpy as np

sys.path[:0] = [str(Path(__file__).resolve().parent), str(Path(__file__).resolve().parents[1])]
import bench_edges as be  # noqa: E402
import ibr.render.superres as superres  # noqa: E402
import ibr.render.upsample as upsample  # noqa: E402
from ibr.render.view_synthesis import interpolate  # noqa: E402
from ibr.synth import make_scene, render  # noqa: E402
from ibr.synth.scene import _camera_dirs  # noqa: E402


def traced(scene, camera, du=0.0, dv=0.0):
    """(H, W, 3) colour in levels of the rays through pixel centres moved by (du, dv) px."""
    return scene.trace(camera.position, _camera_dirs(camera, du, dv)).color.reshape(camera.height, camera.width, 3) * 255


def perfect_renderers(scene, truths):
    rows = {}
    for g in truths:
        band = be.edge_band(g.depth)
        for k in (1, 2, 4):
            c = render(scene, g.camera, supersample=k).color * 255
            rows.setdefault(f"ray traced, {k}x{k} box", []).append(be.psnr(np.rint(c), g.color, band))
        d = 1 / 3
        pattern = 2 * traced(scene, g.camera) + sum(traced(scene, g.camera, su * d, sv * d) for su in (-1, 1) for sv in (-1, 1))
        rows.setdefault("ray traced, antialias pattern", []).append(be.psnr(np.rint(pattern / 6), g.color, band))
    return rows


def perfect_sources(name, scene, truths):
    cams = [g.camera for g in truths]
    rows = {}
    # the exact colour is not refined by the partner (superres) as ours is
    as_given = mock.patch.object(superres, "super_resolve_pair", lambda sources, ups, k: tuple(u.color for u in ups))
    for label, depth, colour, consistent in (
            ("supersample=3, exact 3x depth", True, None, False),
            ("supersample=3, exact 3x depth + colour", True, "all", False),
            ("supersample=3, our depth, exact 3x colour", False, "all", False),
            ("supersample=3, exact 3x colour at edge pixels only", False, "edge", False),
            ("supersample=3, our depth, exact colour true to the pixels", False, "all", True),
            ("supersample=3, exact colour true to the pixels, edge pixels", False, "edge", True)):
        with mock.patch.object(upsample, "upsample_view", _exact_upsampling(scene, depth, colour, consistent)), \
                (as_given if colour else contextlib.nullcontext()):
            a, b, _ = be.load_pair(name)  # fresh views: nothing cached
            frames = interpolate(a, b, cams, fill="none", supersample=3)
        rows[label] = be.edge_scores(frames, truths)[0]
    for label, exact_depth in (("supersample=3, our depth, band-limited exact colour", False),
                               ("supersample=3, exact depth, band-limited exact colour", True)):
        with mock.patch.object(upsample, "upsample_view", _bandlimited_upsampling(scene, exact_depth)), as_given:
            a, b, _ = be.load_pair(name)
            frames = interpolate(a, b, cams, fill="none", supersample=3)
        rows[label] = be.edge_scores(frames, truths)[0]
    for label, where in (("supersample=3, exact depth where ours is within 2 %", "within"),
                         ("supersample=3, exact depth at edge subsamples > 2 % off", "edge_off")):
        with mock.patch.object(upsample, "upsample_view", _corrected_upsampling(scene, where)):
            a, b, _ = be.load_pair(name)
            frames = interpolate(a, b, cams, fill="none", supersample=3)
        rows[label] = be.edge_scores(frames, truths)[0]
    a, b, _ = be.load_pair(name)
    rows["supersample=3 (today)"] = be.edge_scores(interpolate(a, b, cams, fill="none", supersample=3), truths)[0]
    return rows


def _exact_upsampling(scene, depth: bool, colour: str | None, consistent: bool = False):
    """An ``upsample_view`` whose sources carry the scene's exact depth at k x k (``depth``) and
    its exact colour rendered with 3 x 3 samples per subsample (``colour`` = "all"; "edge": at
    the subsamples of the source's depth-edge pixels only; None: ours); ``consistent``: that
    colour with each pixel's residual spread evenly so that its subsamples average to the
    source pixel (``superres._consistent``): what a super-resolution perfect up to the source's
    own pixels would give (the 3 x 3 rays of a source pixel and the 9 x 9 of its exact
    subsamples differ where the texture aliases: by 3.7 levels rms at room's edge pixels)."""
    original = upsample.upsample_view

    def exact(view, k, **options):
        up = original(view, k, **options)
        big = render(scene, view.camera.resized(view.camera.width * k, view.camera.height * k),
                     supersample=3 if colour else 1)
        color = up.color
        if colour:
            exact = np.clip(np.rint(big.color * 255), 0, 255).astype(up.color.dtype)
            if consistent:
                true_to_pixels = superres._consistent(exact.astype(np.float32), view.color.astype(np.float32), k, (0.0, 255.0))
                exact = superres._as_colour(true_to_pixels, exact.dtype, exact.shape)
            at = np.ones(up.depth.shape, bool) if colour == "all" else np.repeat(np.repeat(
                upsample.depth_edge_pixels(view.depth), k, 0), k, 1)
            color = np.where(at[..., None], exact, color)
        return dataclasses.replace(up, depth=big.depth if depth else up.depth, color=color)

    return exact


def _bandlimited_upsampling(scene, exact_depth: bool):
    """An ``upsample_view`` whose colour is the scene's exact 3x colour low-passed within each
    surface to the source's Nyquist frequency (:func:`_lowpass_within_surfaces`) and made true to
    the source pixels: an ideal reconstruction at the sources' sampling rate (it still knows the
    texture a mixed pixel hides); ``exact_depth``: with the scene's exact 3x depth, else ours."""
    original = upsample.upsample_view

    def bandlimited(view, k, **options):
        up = original(view, k, **options)
        camera = view.camera.resized(view.camera.width * k, view.camera.height * k)
        exact_z = render(scene, camera).depth
        colour = render(scene, camera, supersample=3).color.astype(np.float64) * 255
        for axis in (0, 1):
            colour = _lowpass_within_surfaces(colour, exact_z, axis, 0.5 / k)
        true_to_pixels = superres._consistent(colour.astype(np.float32), view.color.astype(np.float32), k, (0.0, 255.0))
        return dataclasses.replace(up, color=superres._as_colour(true_to_pixels, up.color.dtype, up.color.shape),
                                   depth=exact_z.astype(np.float32) if exact_depth else up.depth)

    return bandlimited


def _lowpass_within_surfaces(colour, z, axis: int, cutoff: float, radius: int = 9):
    """``colour`` ((H, W, C)) filtered along ``axis`` by a Lanczos-windowed sinc of ``cutoff``
    cycles per sample (``radius`` taps each side), each sample from the taps on its own surface
    only (depth ``z`` within 2 %), renormalized (the sample itself where they weigh under 5 %)."""
    n = np.arange(-radius, radius + 1)
    taps = 2 * cutoff * np.sinc(2 * cutoff * n) * np.sinc(n / radius)
    taps /= taps.sum()
    acc, total = np.zeros_like(colour), np.zeros(z.shape)
    for offset, weight in zip(n, taps):
        at = np.clip(np.arange(z.shape[axis]) + offset, 0, z.shape[axis] - 1)
        z_at = np.take(z, at, axis=axis)
        with np.errstate(invalid="ignore"):
            same = weight * (np.abs(z_at - z) <= 0.02 * z)
        acc += same[..., None] * np.take(colour, at, axis=axis)
        total += same
    ok = np.abs(total) > 0.05
    return np.where(ok[..., None], acc / np.where(ok, total, 1.0)[..., None], colour)


def _corrected_upsampling(scene, where):
    """An ``upsample_view`` whose depth takes the scene's exact k x k depth ``where`` = "within":
    at the subsamples whose depth is within 2 % of it (the values of the surfaces ours puts
    right), "edge_off": at the depth-edge pixels' subsamples more than 2 % off (those ours puts
    on the wrong surface)."""
    original = upsample.upsample_view

    def corrected(view, k, **options):
        up = original(view, k, **options)
        exact = render(scene, view.camera.resized(view.camera.width * k, view.camera.height * k)).depth
        with np.errstate(invalid="ignore"):
            close = np.abs(up.depth - exact) <= 0.02 * exact
        edge_k = np.repeat(np.repeat(upsample.depth_edge_pixels(view.depth), k, 0), k, 1)
        use = close if where == "within" else ~close & edge_k & np.isfinite(exact)
        return dataclasses.replace(up, depth=np.where(use, exact, up.depth).astype(np.float32))

    return corrected


def main() -> int:
    print(f"{'scene':<8} {'renderer':<58} {'edge band dB (t = .25/.5/.75)':<30} {'mean':>6}")
    for name in ("clutter", "room"):
        _, _, truths = be.load_pair(name)
        scene = make_scene(name)
        for rows in (perfect_renderers(scene, truths), perfect_sources(name, scene, truths)):
            for label, band in rows.items():
                print(f"{name:<8} {label:<58} {' '.join(f'{x:.2f}' for x in band):<30} {np.mean(band):6.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
