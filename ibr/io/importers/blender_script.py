"""Render RGB-D view files from Blender: run this file *inside* Blender (it does not import ibr).

    blender -b scene.blend --python "$(ibr import blender --script)" -- --out DIR [--all-cameras]
        [--frames 1 5 9] [--multilayer] [--samples 16]

For the active camera (or every camera with ``--all-cameras``) and each frame, it renders the
colour (``<name>_color.png``) and the depth pass the usual way — the compositor's File Output
node writing an OpenEXR RGB image (Blender writes R = G = B = Z; ``--multilayer`` writes one
multilayer EXR holding ``Combined.R/G/B/A`` and ``Depth.V`` instead) — and writes
``<name>.json`` view files (``docs/files.md``) plus ``transforms.json`` (NeRF convention) for the
same frames. Perspective cameras only.

Conversions (``ibr.io.importers.conventions``, ``docs/import.md``):

* pose: Blender's camera looks down -Z with +Y up (OpenGL axes); ours looks down +Z with +Y down:
  ``world_from_cam = matrix_world @ diag(1, -1, -1, 1)``; Blender's world frame is kept.
* intrinsics: with sensor fit AUTO the sensor width spans the larger image side,
  ``f_px = lens_mm / sensor_mm * max(W, H)`` (HORIZONTAL: W, VERTICAL: H, with sensor_height),
  square pixels; the principal point ``(W/2 - shift_x * max(W, H), H/2 + shift_y * max(W, H))``
  in continuous pixels, minus 0.5 for our integer pixel centres.
* depth: the Z pass is the distance along the camera's view axis (planar z) in scene units
  (checked: the floor of the test scene back-projects to world z = 0). EEVEE computes it in half
  precision (steps of 2^-11 relative; where there is no surface it saturates at 65504), Cycles in
  float (1e10 where there is no surface); ``ibr.read_depth`` reads both markers as invalid.
"""

from __future__ import annotations

import json
import math
import os
import sys

GL_FLIP = ((1.0, 0.0, 0.0, 0.0), (0.0, -1.0, 0.0, 0.0), (0.0, 0.0, -1.0, 0.0), (0.0, 0.0, 0.0, 1.0))


def matmul(a, b):
    """4 x 4 product of nested sequences (no numpy needed inside Blender's Python)."""
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def world_from_cam(matrix_world):
    """Our camera-to-world pose of a Blender camera's ``matrix_world`` (rows)."""
    return matmul([list(r) for r in matrix_world], GL_FLIP)


def intrinsics(lens_mm, sensor_width_mm, sensor_height_mm, sensor_fit, width, height, shift_x=0.0, shift_y=0.0):
    """(fx, fy, cx, cy) in pixels, our convention (pixel centres at integers), square pixels."""
    if sensor_fit == "VERTICAL":
        f = lens_mm / sensor_height_mm * height
    elif sensor_fit == "HORIZONTAL":
        f = lens_mm / sensor_width_mm * width
    else:  # AUTO: the sensor width spans the larger side
        f = lens_mm / sensor_width_mm * max(width, height)
    side = max(width, height)
    return f, f, width / 2.0 - shift_x * side - 0.5, height / 2.0 + shift_y * side - 0.5


def view_document(name, width, height, cam):
    fx, fy, cx, cy, pose = cam
    return {"format": "ibr-view", "version": 1, "name": name, "color": f"{name}_color.png",
            "depth": {"path": f"{name}_depth.exr", "encoding": "z"},
            "camera": {"width": width, "height": height, "fx": fx, "fy": fy, "cx": cx, "cy": cy,
                       "world_from_cam": pose}}


def _args(argv):
    import argparse

    argv = argv[argv.index("--") + 1:] if "--" in argv else []
    p = argparse.ArgumentParser(prog="blender -b SCENE --python blender_script.py --")
    p.add_argument("--out", required=True)
    p.add_argument("--all-cameras", action="store_true")
    p.add_argument("--frames", type=int, nargs="+")
    p.add_argument("--multilayer", action="store_true")
    p.add_argument("--samples", type=int, default=16)
    return p.parse_args(argv)


def _depth_output(scene, folder, multilayer):
    """Compositor: Render Layers -> File Output (EXR RGB of the Depth pass, or multilayer)."""
    scene.use_nodes = True
    tree = scene.node_tree
    for n in list(tree.nodes):
        tree.nodes.remove(n)
    rl = tree.nodes.new("CompositorNodeRLayers")
    comp = tree.nodes.new("CompositorNodeComposite")
    tree.links.new(rl.outputs["Image"], comp.inputs["Image"])
    out = tree.nodes.new("CompositorNodeOutputFile")
    out.base_path = folder
    if multilayer:
        out.format.file_format = "OPEN_EXR_MULTILAYER"
        out.format.color_depth = "32"
        out.file_slots.clear()
        out.file_slots.new("Combined")
        out.file_slots.new("Depth")
        tree.links.new(rl.outputs["Image"], out.inputs["Combined"])
        tree.links.new(rl.outputs["Depth"], out.inputs["Depth"])
    else:
        out.format.file_format = "OPEN_EXR"
        out.format.color_mode = "RGB"
        out.format.color_depth = "32"
        tree.links.new(rl.outputs["Depth"], out.inputs[0])
    return out


def main(argv=None):
    import bpy  # only inside Blender

    args = _args(sys.argv if argv is None else argv)
    scene = bpy.context.scene
    folder = os.path.abspath(args.out)
    os.makedirs(folder, exist_ok=True)
    scene.view_layers[0].use_pass_z = True
    r = scene.render
    if r.engine == "CYCLES":
        scene.cycles.samples = args.samples
    elif hasattr(scene, "eevee"):
        scene.eevee.taa_render_samples = args.samples
    r.image_settings.file_format = "PNG"
    r.image_settings.color_mode = "RGB"
    r.image_settings.color_depth = "8"
    width = int(r.resolution_x * r.resolution_percentage / 100)
    height = int(r.resolution_y * r.resolution_percentage / 100)
    cams = [o for o in scene.objects if o.type == "CAMERA"] if args.all_cameras else [scene.camera]
    frames = args.frames or [scene.frame_current]
    node = _depth_output(scene, folder, args.multilayer)
    nerf = {"camera_angle_x": None, "frames": []}
    for cam_obj in cams:
        if cam_obj.data.type != "PERSP":
            raise SystemExit(f"camera {cam_obj.name}: only perspective cameras are supported")
        scene.camera = cam_obj
        for frame in frames:
            scene.frame_set(frame)
            name = f"{cam_obj.name}_{frame:04d}".replace(" ", "_")
            node.file_slots[0].path = f"{name}_depth_" if not args.multilayer else f"{name}_layers_"
            if args.multilayer:
                node.base_path = os.path.join(folder, f"{name}_layers_")
            r.filepath = os.path.join(folder, f"{name}_color.png")
            bpy.ops.render.render(write_still=True)
            written = os.path.join(folder, (f"{name}_depth_" if not args.multilayer else f"{name}_layers_")
                                   + f"{frame:04d}.exr")
            depth_name = f"{name}_depth.exr" if not args.multilayer else f"{name}_layers.exr"
            os.replace(written, os.path.join(folder, depth_name))
            d = cam_obj.data
            fx, fy, cx, cy = intrinsics(d.lens, d.sensor_width, d.sensor_height, d.sensor_fit, width, height,
                                        d.shift_x, d.shift_y)
            pose = world_from_cam(cam_obj.matrix_world)
            doc = view_document(name, width, height, (fx, fy, cx, cy, pose))
            doc["depth"]["path"] = depth_name
            if args.multilayer:
                doc["depth"]["channel"] = "Depth.V"  # the File Output node's slot "Depth" (a value)
            with open(os.path.join(folder, f"{name}.json"), "w") as f:
                json.dump(doc, f, indent=2)
            nerf["camera_angle_x"] = 2 * math.atan(0.5 * width / fx)
            nerf["frames"].append({"file_path": f"{name}_color.png",
                                   "transform_matrix": [list(row) for row in cam_obj.matrix_world],
                                   "depth_file_path": depth_name,
                                   # per frame (lens shift, zoom), continuous pixels (+0.5)
                                   "fl_x": fx, "fl_y": fy, "cx": cx + 0.5, "cy": cy + 0.5, "w": width, "h": height})
            print(f"ibr: wrote {name}.json")
    with open(os.path.join(folder, "transforms.json"), "w") as f:
        json.dump(nerf, f, indent=2)


if __name__ == "__main__":
    main()
