"""The named synthetic scenes and their bundled camera pairs (used through :mod:`ibr.synth`).

World frame: x right, y *down* (world up is -y), z forward from the default viewpoint; units are
"scene units" (think meters). Every scene is fixed (no randomness), so renders are
deterministic.
"""

from __future__ import annotations

import numpy as np

from ..base.camera import Camera, look_at
from .primitives import Box, Rect, Sphere, rotation
from .scene import Scene
from .textures import ImageTexture, checker_texture, image_texture

__all__ = ["SCENES", "build_scene", "camera_poses", "make_scene", "make_staircase", "scene_cameras", "staircase"]

SCENES = {
    "room": "closed room of textured planes (floor, ceiling, 4 walls), two boxes and a staircase",
    "clutter": "spheres, thin poles, a thin tilted slab and overlapping rotated boxes in a closed "
               "room with a photo back wall (depth edges, curved surfaces, disocclusions)",
    "grazing": "large brick ground plane seen at 84 degrees incidence plus a far photo wall",
    "plane": "one fronto-parallel textured rectangle at z = 3 filling the view",
    "box_corner": "one axis-aligned box, corner toward the camera; black background (rays miss)",
    "capture": "a 30 x 32 m hall around a capture point at the origin (eye height 1.6 m) with objects "
               "from 0.5 m to 20 m in every direction: for 360-degree rigs, stitching and ODS",
}

_X, _Y, _Z = np.eye(3)


def _wall(center, axis_u, axis_v, half_u, half_v, tex):
    """Rect whose texture image is centered on the rectangle."""
    h, w = tex.image.shape[:2]
    off = (-tex.width_units / 2, -tex.width_units * h / w / 2)
    return Rect(tex, np.asarray(center, float), np.asarray(axis_u, float), np.asarray(axis_v, float),
                half_u, half_v, off)


def _room_shell(x0, x1, y_ceil, y_floor, z0, z1, tex):
    """Six inward-looking walls of an axis-aligned room; texture rows run downward on walls.

    ``tex`` maps "floor", "ceiling", "front" (z1), "back" (z0), "left" (x0), "right" (x1).
    Image columns run to the right as seen from inside facing the wall (OpenCV: right = down x
    forward).
    """
    cx, cy, cz = (x0 + x1) / 2, (y_ceil + y_floor) / 2, (z0 + z1) / 2
    hx, hy, hz = (x1 - x0) / 2, (y_floor - y_ceil) / 2, (z1 - z0) / 2
    return [
        _wall((cx, y_floor, cz), _X, _Z, hx, hz, tex["floor"]),
        _wall((cx, y_ceil, cz), _X, -_Z, hx, hz, tex["ceiling"]),
        _wall((cx, cy, z1), _X, _Y, hx, hy, tex["front"]),
        _wall((cx, cy, z0), -_X, _Y, hx, hy, tex["back"]),
        _wall((x0, cy, cz), _Z, _Y, hz, hy, tex["left"]),
        _wall((x1, cy, cz), -_Z, _Y, hz, hy, tex["right"]),
    ]


def make_staircase(*, origin, steps, step_width, step_rise, step_run, depth=None, texture, yaw_deg=0.0):
    """See :func:`ibr.synth.staircase`."""
    if int(steps) < 1:
        raise ValueError(f"steps: expected a positive integer, got {steps!r}")
    o = np.asarray(origin, float)
    r = rotation(yaw_deg)
    total = step_run * steps if depth is None else float(depth)
    boxes = []
    for i in range(int(steps)):
        z_lo = i * step_run
        top = (i + 1) * step_rise
        local_center = np.array([step_width / 2, -top / 2, (z_lo + total) / 2])
        half = np.array([step_width / 2, top / 2, (total - z_lo) / 2])
        boxes.append(Box(texture, o + r @ local_center, half, r))
    return boxes


def _room():
    tex = {
        "floor": image_texture("gravel", 1.6),
        "ceiling": image_texture("moon", 2.5),
        "front": image_texture("brick", 1.8),
        "back": image_texture("chelsea", 3.0),
        "left": image_texture("astronaut", 2.6),
        "right": image_texture("rocket", 3.2),
    }
    prims = _room_shell(-3.0, 3.0, -1.6, 1.4, -2.0, 6.0, tex)
    prims.append(Box(image_texture("coffee", 1.2), (-1.4, 1.0, 3.6), (0.45, 0.4, 0.45)))
    prims.append(Box(image_texture("immunohistochemistry", 1.0), (0.2, 1.1, 4.7), (0.5, 0.3, 0.35),
                     rotation(25.0)))
    prims += make_staircase(origin=(1.6, 1.4, 3.0), steps=5, step_width=1.4, step_rise=0.26,
                            step_run=0.5, depth=3.0, texture=image_texture("brick", 1.0))
    return prims


def _clutter():
    tex = {
        "floor": image_texture("grass", 1.5),
        "ceiling": image_texture("moon", 2.0),
        "front": image_texture("astronaut", 4.2),
        "back": image_texture("coffee", 3.0),
        "left": image_texture("brick", 1.4),
        "right": image_texture("brick", 1.4),
    }
    prims = _room_shell(-2.6, 2.6, -1.6, 1.0, -1.5, 5.0, tex)
    pole = image_texture("camera", 0.6)
    prims += [
        # Spheres: one resting on the floor, one floating, one small and near.
        Sphere(image_texture("chelsea"), (-0.75, 0.2, 2.6), 0.45),
        Sphere(checker_texture(), (0.7, 0.55, 3.3), 0.45),
        Sphere(image_texture("hubble_deep_field"), (0.12, -0.3, 1.7), 0.16),
        # Thin poles floor to ceiling (4 cm thick).
        Box(pole, (-0.22, -0.3, 2.05), (0.02, 1.3, 0.02)),
        Box(pole, (1.15, -0.3, 2.5), (0.02, 1.3, 0.02), rotation(30.0)),
        Box(pole, (0.35, -0.3, 3.9), (0.025, 1.3, 0.025)),
        # A thin tilted slab (2 cm).
        Box(image_texture("rocket", 1.2), (0.95, -0.45, 3.7), (0.5, 0.3, 0.01), rotation(30.0, 12.0)),
        # Overlapping rotated boxes.
        Box(image_texture("immunohistochemistry", 1.0), (-1.35, 0.6, 3.7), (0.4, 0.4, 0.4), rotation(20.0)),
        Box(image_texture("gravel", 0.8), (-1.0, 0.75, 3.2), (0.3, 0.25, 0.3), rotation(-35.0)),
    ]
    return prims


def _grazing():
    return [
        # Ground plane 0.35 below the eye, seen by a camera pitched down 6 degrees: the optical
        # axis meets it at 84 degrees from the normal (6 degrees above the surface).
        Rect(image_texture("brick", 1.5), (0.0, 0.35, 6.0), _X, _Z, np.inf, 6.0, (0.0, 0.0)),
        # Far background wall (infinite plane) closing the view at z = 12.
        _wall((0.0, 0.0, 12.0), _X, _Y, np.inf, np.inf, image_texture("astronaut", 9.0)),
    ]


def _plane():
    return [_wall((0.0, 0.0, 3.0), _X, _Y, 3.0, 3.0, image_texture("astronaut", 2.0))]


def _box_corner():
    return [Box(image_texture("coffee", 0.8), (0.8, 0.8, 3.6), (0.5, 0.5, 0.5))]


def _capture():
    """Objects all around the origin, nearest surface 0.5 m, walls 12-20 m away (issue #20)."""
    tex = {
        "floor": image_texture("gravel", 2.0),
        "ceiling": image_texture("moon", 6.0),
        "front": image_texture("astronaut", 14.0),
        "back": image_texture("coffee", 12.0),
        "left": image_texture("brick", 3.0),
        "right": image_texture("rocket", 16.0),
    }
    prims = _room_shell(-16.0, 14.0, -6.0, 1.6, -12.0, 20.0, tex)
    prims += [
        Box(image_texture("immunohistochemistry", 0.5), (-0.75, 0.3, -0.3), (0.2, 0.2, 0.2), rotation(30.0)),
        Sphere(image_texture("chelsea"), (0.9, 0.1, 0.6), 0.3),
        Box(image_texture("camera", 0.6), (0.3, -1.2, 2.0), (0.03, 2.8, 0.03)),
        Sphere(checker_texture(), (-1.2, 0.8, 3.0), 0.6),
        Box(image_texture("coffee", 1.5), (2.5, 0.6, -2.5), (0.7, 1.0, 0.6), rotation(-20.0)),
        Box(image_texture("rocket", 2.0), (-4.0, 0.1, -5.0), (1.0, 1.5, 1.0), rotation(40.0)),
        Sphere(image_texture("hubble_deep_field", 1.0), (5.0, -0.5, 6.0), 1.2),
        Box(image_texture("grass", 2.0), (-7.0, 0.0, 9.0), (1.5, 1.6, 1.5), rotation(15.0)),
    ]
    prims += make_staircase(origin=(6.0, 1.6, 12.0), steps=6, step_width=3.0, step_rise=0.4, step_run=0.8,
                            texture=image_texture("brick", 1.5), yaw_deg=-30.0)
    return prims


_BUILDERS = {"room": _room, "clutter": _clutter, "grazing": _grazing, "plane": _plane,
             "box_corner": _box_corner, "capture": _capture}

# (eye_a, eye_b, target, hfov_deg): cameras 0.2-0.3 units apart converging on a common target,
# i.e. a small relative rotation (1-3 degrees) on top of the horizontal baseline.
_CAMERAS = {
    "room": ((-0.12, 0.0, 0.0), (0.12, 0.0, 0.0), (0.0, 0.25, 5.0), 60.0),
    "clutter": ((-0.12, 0.0, 0.0), (0.12, 0.0, 0.0), (0.0, 0.15, 3.5), 60.0),
    # Optical axes pitched down 6 degrees (converging 6 units ahead).
    "grazing": ((-0.15, 0.0, 0.0), (0.15, 0.0, 0.0), (0.0, 6 * np.sin(np.radians(6.0)), 6 * np.cos(np.radians(6.0))), 60.0),
    "plane": ((-0.1, 0.0, 0.0), (0.1, 0.0, 0.0), (0.0, 0.0, 3.0), 60.0),
    "box_corner": ((-0.1, 0.0, 0.0), (0.1, 0.0, 0.0), (0.8, 0.8, 3.6), 40.0),
    "capture": ((-0.1, 0.0, 0.0), (0.1, 0.0, 0.0), (0.0, 0.0, 5.0), 60.0),
}


def build_scene(name: str):

    return Scene(tuple(_BUILDERS[name]()), name=name)


def camera_poses(name: str):
    """``(world_from_cam_a, world_from_cam_b, hfov_deg)`` of a named scene."""
    eye_a, eye_b, target, hfov = _CAMERAS[name]
    return look_at(eye_a, target), look_at(eye_b, target), hfov


def staircase(
    *,
    origin,
    steps: int,
    step_width: float,
    step_rise: float,
    step_run: float,
    depth: float | None = None,
    texture: ImageTexture,
    yaw_deg: float = 0.0,
) -> list[Box]:
    """Boxes forming a staircase that rises (toward -y, world up) as it runs along local +z.

    ``origin`` is the floor point at the front-left corner of the first step (world coordinates);
    step i spans local z in [i*run, run*steps if depth is None else depth] and rises to
    (i+1)*rise above the floor. ``yaw_deg`` turns the whole staircase about the vertical.
    """
    return make_staircase(origin=origin, steps=steps, step_width=step_width, step_rise=step_rise,
                          step_run=step_run, depth=depth, texture=texture, yaw_deg=yaw_deg)


def make_scene(name: str, *, specular: float = 0.0) -> Scene:
    """Build a named scene (see ``SCENES`` for names and descriptions).

    ``specular > 0`` switches on the view-dependent Blinn-Phong highlight.
    """
    if not isinstance(name, str) or name not in SCENES:
        raise ValueError(f"name: unknown scene {name!r}; expected one of {', '.join(map(repr, SCENES))}")
    if isinstance(specular, (bool, np.bool_)) or not isinstance(specular, (int, float, np.integer, np.floating)) \
            or not 0 <= specular <= 1:
        raise ValueError(f"specular: expected a weight in [0, 1], got {specular!r}")  # as Scene(specular=...)
    scene = build_scene(name)
    return scene.with_specular(specular) if specular > 0 else scene


def scene_cameras(name: str, *, width: int = 512, height: int = 384) -> tuple[Camera, Camera]:
    """The bundled source pair ``(cam_a, cam_b)`` of a named scene.

    Ground-truth intermediate cameras are ``ibr.interpolate_cameras(cam_a, cam_b, t)``.
    Both cameras share one field of view (60 degrees horizontal) and a centered principal point
    (``cx = (width - 1) / 2``, pixel-center convention).
    """
    if not isinstance(name, str) or name not in SCENES:
        raise ValueError(f"name: unknown scene {name!r}; expected one of {', '.join(map(repr, SCENES))}")
    pose_a, pose_b, hfov = camera_poses(name)
    return (Camera.from_fov(width, height, hfov_deg=hfov, world_from_cam=pose_a),
            Camera.from_fov(width, height, hfov_deg=hfov, world_from_cam=pose_b))

