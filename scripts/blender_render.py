"""Dev-only: import a shapeflow .glb into Blender and render it (issue: results
visible in every viewer). Not part of CI (Blender is large and slow to start).

    blender -b --factory-startup --python scripts/blender_render.py -- IN.glb OUT.png

Imports with Blender's own glTF importer, sets the scene's frame range from the
animation (evolution.glb), frames the result with a camera (from +z, orthographic,
for a plane curve; obliquely for a surface), renders one frame with Cycles on the
CPU (the last frame of an evolution) and prints a JSON line: the frame range, the
objects imported and the share of pixels that differ from the background.
"""

import json
import sys

import bpy
import numpy
from mathutils import Vector

# Debian's Blender 3.4 importer uses `numpy.bool`, which Debian's numpy 1.24 no
# longer has (install python3-numpy beside blender)
if not hasattr(numpy, "bool"):
    numpy.bool = bool

glb, out = sys.argv[sys.argv.index("--") + 1:][:2]

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=glb)
scene = bpy.context.scene

# the frame range of the animation: the one line the README shows
if bpy.data.actions:
    scene.frame_start, scene.frame_end = 1, int(max(a.frame_range[1] for a in bpy.data.actions))
scene.frame_set(scene.frame_end)

meshes = [o for o in scene.objects if o.type == "MESH"]
visible = [o for o in meshes if min(o.matrix_world.to_scale()) > 1e-6]
corners = [o.matrix_world @ Vector(c) for o in visible for c in o.bound_box]
lo = Vector((min(c[k] for c in corners) for k in range(3)))
hi = Vector((max(c[k] for c in corners) for k in range(3)))
center, size = (lo + hi) / 2, hi - lo
# a plane curve: glTF's z = 0 plane (ribbons a little above it) is Blender's y = 0
thin = min(range(3), key=lambda k: size[k])
flat = size[thin] < 0.05 * max(size)

camera = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
scene.collection.objects.link(camera)
scene.camera = camera
if flat:
    camera.data.type = "ORTHO"
    camera.data.ortho_scale = 1.15 * max(size) * 320 / 240  # the scale spans the wider side
    direction = Vector([1.0 if k == thin else 0.0 for k in range(3)])
    if thin == 1:
        direction = -direction  # glTF's +z is Blender's -y
    camera.location = center + direction * (max(size) + 1)
else:
    direction = Vector((1.0, -1.2, 0.9)).normalized()
    camera.location = center + direction * 2.2 * size.length
camera.rotation_euler = (-direction).to_track_quat("-Z", "Y").to_euler()
camera.data.clip_start = 1e-3 * size.length
camera.data.clip_end = 100 * size.length

sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun.data.energy = 3.0
sun.rotation_euler = (0.6, 0.2, 0.4)
scene.collection.objects.link(sun)
world = bpy.data.worlds.new("world")
world.color = (0.05, 0.05, 0.05)
scene.world = world

scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 8
scene.cycles.use_denoising = False  # Debian's build has no OpenImageDenoise
scene.render.resolution_x, scene.render.resolution_y = 320, 240
scene.render.filepath = out
bpy.ops.render.render(write_still=True)

image = bpy.data.images.load(out)
px = list(image.pixels)
background = px[0:3]
n = len(px) // 4
differ = sum(1 for k in range(n) if sum(abs(px[4 * k + c] - background[c]) for c in range(3)) > 0.05)
print(json.dumps({
    "glb": glb,
    "frame_range": [scene.frame_start, scene.frame_end],
    "objects": len(meshes),
    "flat": flat,
    "ink": differ / n,
}))
