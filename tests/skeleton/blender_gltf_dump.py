# Imports a binary glTF file with Blender's own importer (headless) and dumps the armature's
# bones, the action's frame range and, per frame and bone, the bone's world rotation relative to
# its rest orientation (w x y z) and its head position (world space, Blender's z-up axes), as
# JSON. Usage:
#   blender -b --factory-startup --python-exit-code 1 --python blender_gltf_dump.py -- in.glb out.json FPS
import json
import sys

import bpy

argv = sys.argv[sys.argv.index("--") + 1:]
src, dst, fps = argv[0], argv[1], int(argv[2])
bpy.ops.wm.read_factory_settings(use_empty=True)
try:
    bpy.ops.preferences.addon_enable(module="io_scene_gltf2")
except Exception:
    pass
bpy.context.scene.render.fps = fps
result = bpy.ops.import_scene.gltf(filepath=src)
if "FINISHED" not in result:
    raise RuntimeError("glTF import failed: %s" % result)
arms = [o for o in bpy.context.scene.objects if o.type == "ARMATURE"]
if len(arms) != 1:
    raise RuntimeError("expected one armature, got %d" % len(arms))
arm = arms[0]
action = arm.animation_data.action
first, last = (int(round(v)) for v in action.frame_range)
w3 = arm.matrix_world.to_3x3()
frames = []
for f in range(first, last + 1):
    bpy.context.scene.frame_set(f)
    bones = {}
    for pb in arm.pose.bones:
        d = (w3 @ pb.matrix.to_3x3()) @ (w3 @ pb.bone.matrix_local.to_3x3()).inverted()
        q = d.to_quaternion()
        bones[pb.name] = {"q": [q.w, q.x, q.y, q.z], "head": list(arm.matrix_world @ pb.head)}
    frames.append(bones)
with open(dst, "w") as out:
    json.dump({"bones": [b.name for b in arm.data.bones],
               "parents": {b.name: (b.parent.name if b.parent else None) for b in arm.data.bones},
               "actions": len(bpy.data.actions), "first": first, "last": last,
               "frames": frames}, out)
