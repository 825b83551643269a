# Imports a BVH file with Blender's own importer (headless) and dumps, per frame and bone, the
# bone's world rotation relative to its rest orientation (armature space, w x y z) and its head
# position, as JSON. Usage:
#   blender -b --factory-startup --python-exit-code 1 --python blender_bvh_dump.py -- in.bvh out.json
import builtins
import json
import sys

import bpy

# Debian's Blender 3.4 importer opens files with mode 'rU', which Python 3.11 rejects.
_open = builtins.open


def _open_without_u(file, mode="r", *args, **kwargs):
    if isinstance(mode, str) and "U" in mode:
        mode = mode.replace("U", "") or "r"
    return _open(file, mode, *args, **kwargs)


builtins.open = _open_without_u

argv = sys.argv[sys.argv.index("--") + 1:]
src, dst = argv[0], argv[1]
bpy.ops.wm.read_factory_settings(use_empty=True)
try:
    bpy.ops.preferences.addon_enable(module="io_anim_bvh")
except Exception:
    pass
result = bpy.ops.import_anim.bvh(filepath=src, global_scale=0.01, rotate_mode="QUATERNION",
                                 update_scene_duration=True)
if "FINISHED" not in result:
    raise RuntimeError("BVH import failed: %s" % result)
arm = next(o for o in bpy.context.scene.objects if o.type == "ARMATURE")
action = arm.animation_data.action
first, last = (int(round(v)) for v in action.frame_range)
frames = []
for f in range(first, last + 1):
    bpy.context.scene.frame_set(f)
    bones = {}
    for pb in arm.pose.bones:
        d = pb.matrix.to_3x3() @ pb.bone.matrix_local.to_3x3().inverted()
        q = d.to_quaternion()
        bones[pb.name] = {"q": [q.w, q.x, q.y, q.z], "head": list(pb.head)}
    frames.append(bones)
with _open(dst, "w") as out:
    json.dump({"object_matrix_identity": arm.matrix_world.is_identity if hasattr(arm.matrix_world, "is_identity") else True,
               "frames": frames}, out)
