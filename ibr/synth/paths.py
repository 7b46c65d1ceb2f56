"""Camera paths through the synthetic scenes: RGB-D key frames plus the exact in-between frames.

A *sequence* is what a depth camera or an engine capture delivers: RGB-D frames in time order.
Frame-rate up-conversion by a factor F renders F - 1 new frames between every two consecutive key
frames. Real in-between camera poses are unknown, so the up-converter puts them on the pose
interpolation between the keys (:func:`ibr.interpolate_cameras`: slerp of the rotation, lerp of
position and intrinsics). The ground truth here uses exactly that rule, so a warp can be scored
against a direct render of the same camera and nothing but the renderer is measured:

* output frame j (0 <= j < N F) lies in segment i = j // F at phase k = j % F;
* k = 0 is key frame i itself;
* otherwise the camera is ``interpolate_cameras(key[i], key[i + 1], k / F)``; the F - 1 frames after
  the last key (the *tail*, which keeps the clip's duration: N frames at r fps become N F frames at
  F r fps) extrapolate the last segment, ``interpolate_cameras(key[N - 2], key[N - 1], 1 + k / F)``.

:func:`camera_path` places N key cameras along a straight dolly-and-truck path through a named
scene, every camera looking at the scene's target (so the view also turns a little per frame);
:func:`render_path` renders any list of cameras; :func:`synthetic_sequence` returns the keys and
the N F ground-truth frames. Conventions: world and camera frames x right, y down, z forward;
pixel centers at integer coordinates; planar depth exact at pixel centers (never supersampled).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..base.camera import Camera, interpolate_cameras, look_at
from ..base.validate import check_finite_scalar
from ..base.view import View
from .scene import Scene, render
from .scenes import SCENES, _CAMERAS, make_scene

__all__ = ["SyntheticSequence", "camera_path", "path_frame_cameras", "render_path", "synthetic_sequence"]


def _count(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < minimum:
        raise ValueError(f"{name}: expected an integer >= {minimum}, got {value!r}")
    return int(value)


def camera_path(scene: str = "room", keys: int = 10, *, step: float = 0.1, forward: float = 0.03,
                width: int = 160, height: int = 120) -> list[Camera]:
    """Key cameras along a straight path through a named scene.

    The path runs along the baseline of the scene's bundled camera pair (``ibr.synth.scene_cameras``,
    world x), centered on the pair's midpoint, ``step`` scene units per key frame, and moves
    ``forward`` units per key frame along world z (a dolly); every camera looks at the pair's common
    target, so the optical axis also turns by a fraction of a degree per key frame.

    Parameters
    ----------
    scene : str
        One of ``ibr.synth.SCENES``.
    keys : int
        Number of key frames N >= 2.
    step, forward : float
        Sideways and forward motion per key frame (scene units; 0.1 is a walking camera at 10 fps).
    width, height : int
        Image size; the field of view is the scene's (60 degrees horizontal), principal point centered.

    Returns
    -------
    list of Camera
    """
    if not isinstance(scene, str) or scene not in SCENES:
        raise ValueError(f"scene: unknown scene {scene!r}; expected one of {', '.join(map(repr, SCENES))}")
    n = _count("keys", keys, 2)
    step = check_finite_scalar("step", step)
    forward = check_finite_scalar("forward", forward)
    eye_a, eye_b, target, hfov = _CAMERAS[scene]
    mid = (np.asarray(eye_a, float) + np.asarray(eye_b, float)) / 2
    side = np.asarray(eye_b, float) - np.asarray(eye_a, float)
    side /= np.linalg.norm(side)
    ahead = np.array([0.0, 0.0, 1.0])
    cams = []
    for i in range(n):
        eye = mid + (i - (n - 1) / 2) * step * side + i * forward * ahead
        cams.append(Camera.from_fov(width, height, hfov_deg=hfov, world_from_cam=look_at(eye, target)))
    return cams


def path_frame_cameras(keys: list[Camera], factor: int, *, tail: bool = True) -> list[Camera]:
    """Cameras of the up-converted frames (module docstring): key frames and in-betweens.

    ``tail=True`` gives N F cameras (the last F - 1 extrapolate the last segment); ``tail=False``
    gives (N - 1) F + 1, ending on the last key.
    """
    keys = list(keys)
    n = _count("len(keys)", len(keys), 2)
    f = _count("factor", factor, 1)
    total = n * f if tail else (n - 1) * f + 1
    out = []
    for j in range(total):
        i, k = divmod(j, f)
        if k == 0:
            out.append(keys[i])
        elif i < n - 1:
            out.append(interpolate_cameras(keys[i], keys[i + 1], k / f))
        else:  # tail: extrapolate the last segment
            out.append(interpolate_cameras(keys[n - 2], keys[n - 1], 1 + k / f))
    return out


def _quantize8(color: np.ndarray) -> np.ndarray:
    """float [0, 1] -> uint8, rounded to nearest (as the bundled samples)."""
    return np.clip(np.rint(color.astype(np.float64) * 255.0), 0, 255).astype(np.uint8)


def render_path(scene: Scene, cameras, *, supersample: int = 2, color_dtype: str = "uint8",
                name: str = "frame") -> list[View]:
    """Render every camera of a path: views named ``{name}_{index:04d}``.

    ``color_dtype="uint8"`` rounds the colors to 8 bits (what a video or a PNG sequence holds);
    ``"float32"`` keeps the renderer's [0, 1] floats. Depth is exact planar z, float32.
    """
    if color_dtype not in ("uint8", "float32"):
        raise ValueError(f"color_dtype: expected 'uint8' or 'float32', got {color_dtype!r}")
    views = []
    for i, cam in enumerate(cameras):
        v = render(scene, cam, supersample=supersample, name=f"{name}_{i:04d}")
        if color_dtype == "uint8":
            v = View(_quantize8(v.color), v.depth, v.camera, v.name)
        views.append(v)
    return views


@dataclass(frozen=True, eq=False)
class SyntheticSequence:
    """Key frames and exact in-between frames of a camera path.

    Attributes
    ----------
    keys : list of View
        The N key frames (the input of an up-conversion).
    truth : list of View
        The N F (or (N - 1) F + 1 without tail) ground-truth frames; ``truth[i * factor]`` is
        ``keys[i]`` (the same object).
    factor : int
        Up-conversion factor F.
    tail : bool
        Whether the frames after the last key are included.
    """

    keys: list
    truth: list
    factor: int
    tail: bool = True

    @property
    def is_key(self) -> np.ndarray:
        """(len(truth),) bool: True for the frames that are key frames."""
        return np.arange(len(self.truth)) % self.factor == 0


def synthetic_sequence(scene: str = "room", keys: int = 10, factor: int = 4, *, width: int = 160,
                       height: int = 120, step: float = 0.1, forward: float = 0.03, supersample: int = 2,
                       color_dtype: str = "uint8", tail: bool = True, specular: float = 0.0) -> SyntheticSequence:
    """A camera path through a named scene: N key frames and the N F exact frames of its up-conversion.

    See :func:`camera_path` for the path and the module docstring for where the in-between cameras
    lie. Rendering costs about 0.1 s per 160 x 120 frame with ``supersample=2`` (the 40 truth
    frames of a 10-key, factor-4 sequence: about 4 s on one core).
    """
    f = _count("factor", factor, 1)
    cams = camera_path(scene, keys, step=step, forward=forward, width=width, height=height)
    world = make_scene(scene, specular=specular)
    frames = path_frame_cameras(cams, f, tail=tail)
    key_views = render_path(world, cams, supersample=supersample, color_dtype=color_dtype, name=f"{scene}_key")
    truth = []
    for j, cam in enumerate(frames):
        if j % f == 0:
            truth.append(key_views[j // f])
        else:
            truth.extend(render_path(world, [cam], supersample=supersample, color_dtype=color_dtype,
                                     name=f"{scene}_truth"))
    truth = [v if j % f == 0 else View(v.color, v.depth, v.camera, f"{scene}_truth_{j:04d}")
             for j, v in enumerate(truth)]
    return SyntheticSequence(key_views, truth, f, tail)
