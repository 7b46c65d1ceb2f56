"""Blender scene of the import fixtures (run inside Blender 3.4, Debian's package):

    blender -b --factory-startup --python tests/data/import/make_blender_scene.py -- OUT.blend

A 4 x 3 m floor, a back wall, the default cube moved and turned, a tilted board; two perspective
cameras 0.3 m apart looking at the cube (one with a lens shift); EEVEE, 64 x 48.
"""

import math
import sys

import bpy

out = sys.argv[sys.argv.index("--") + 1]
scene = bpy.context.scene
cube = bpy.data.objects["Cube"]
cube.location = (0.3, 0.2, 0.5)
cube.rotation_euler = (0.0, 0.0, math.radians(25))
cube.scale = (0.5, 0.5, 0.5)
bpy.ops.mesh.primitive_plane_add(size=1, location=(0, 0, 0))
bpy.context.object.scale = (4, 3, 1)
bpy.ops.mesh.primitive_plane_add(size=1, location=(0, 1.5, 1.5), rotation=(math.radians(90), 0, 0))
bpy.context.object.scale = (4, 3, 1)
bpy.ops.mesh.primitive_plane_add(size=0.8, location=(-0.9, 0.4, 0.6), rotation=(math.radians(60), math.radians(20), 0))
for i, obj in enumerate(o for o in scene.objects if o.type == "MESH"):  # distinct colours for warping
    mat = bpy.data.materials.new(f"m{i}")
    mat.diffuse_color = ((0.8, 0.3, 0.2, 1), (0.3, 0.7, 0.3, 1), (0.2, 0.4, 0.8, 1), (0.9, 0.8, 0.2, 1))[i % 4]
    obj.data.materials.clear()
    obj.data.materials.append(mat)
cam = scene.camera
cam.location = (0.15, -3.0, 1.4)
cam.rotation_euler = (math.radians(75), 0, 0)
cam.data.lens = 35
cam.name = "camA"
cam_b = cam.copy()
cam_b.data = cam.data.copy()
cam_b.location = (-0.15, -3.0, 1.4)
cam_b.data.shift_x = 0.02
cam_b.name = "camB"
scene.collection.objects.link(cam_b)
scene.render.engine = "BLENDER_EEVEE"
scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 64, 48, 100
scene.render.film_transparent = False
bpy.ops.wm.save_as_mainfile(filepath=out)
