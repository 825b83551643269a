"""Our body model and axes as Blender sees them, and the bone-name presets.

Axes (docs/conventions.md, docs/streaming.md): the stream's earth/body frame has x forward (the
facing direction at calibration), y left, z up; `segments[].q` = q_earth_segment (w, x, y, z,
identity in the N-pose facing +x); `segments[].p` = the segment's joint in metres, floor z = 0.
Blender: z up, a character faces -Y (the front view). So a vector (x, y, z) of ours is
(y, -x, z) in Blender: the rotation A = -90 deg about z, and a rotation q of ours is
A q A^-1 = (w, y, -x, z). This is the same placement as our BVH and glTF exports imported into
Blender (tests/skeleton/blender_test_util.hpp), so a live armature and an imported take agree.
"""
from mathutils import Quaternion, Vector

# The stream's segment order (core/include/mocap/core/segments.hpp), parents before children.
SEGMENTS = (
    "pelvis", "torso", "neck", "head",
    "upper_arm_l", "forearm_l", "hand_l",
    "upper_arm_r", "forearm_r", "hand_r",
    "thigh_l", "shank_l", "foot_l",
    "thigh_r", "shank_r", "foot_r",
)
PARENT = (-1, 0, 1, 2, 1, 4, 5, 1, 7, 8, 0, 10, 11, 0, 13, 14)

# Where each segment points in the N-pose (our axes: joint to its end, as the body model's end
# offsets in skeleton/src/body_model.cpp): trunk and head up, arms and legs down, feet forward
# and a little down. A target armature's bone is turned onto this direction for the N-pose.
NPOSE_END_FRACTION = {  # end offset of the leaf segments, fractions of the body height
    "head": (0.020, 0.0, 0.120),
    "hand_l": (0.0, 0.0, -0.108), "hand_r": (0.0, 0.0, -0.108),
    "foot_l": (0.110, 0.0, -0.039), "foot_r": (0.110, 0.0, -0.039),
}
SHANK_FRACTION = 0.246  # knee to ankle, fraction of the body height (body_model.cpp)
ANKLE_FRACTION = 0.039  # ankle joint above the floor, fraction of the body height


def to_blender_vec(p):
    """A vector of ours (x fwd, y left, z up) in Blender's axes (character facing -Y)."""
    return Vector((p[1], -p[0], p[2]))


def to_blender_quat(q):
    """A rotation of ours, [w, x, y, z], in Blender's axes: A q A^-1 with A = -90 deg about z."""
    return Quaternion((q[0], q[2], -q[1], q[3]))


def npose_direction(segment):
    """Unit direction (Blender axes) a segment points along in the N-pose."""
    if segment in NPOSE_END_FRACTION:
        return to_blender_vec(NPOSE_END_FRACTION[segment]).normalized()
    if segment in ("pelvis", "torso", "neck"):
        return Vector((0.0, 0.0, 1.0))
    return Vector((0.0, 0.0, -1.0))  # arms and legs hang


# Bone-name presets: segment -> bone. "mocap" is the armature this add-on creates, with the
# bone names of our BVH and glTF exports (skeleton/include/mocap/skeleton/bvh.hpp), so an
# imported export can be driven live too. Mixamo's names are the same but for a prefix
# ("mixamorig:", matched whatever it is). Rigify: Blender's human meta-rig (Add > Armature >
# Human (Meta-Rig), the Rigify add-on): torso on the lower spine, the chest following.
PRESETS = {
    "MOCAP": ("mocap (our BVH/glTF names)", (
        "Hips", "Spine", "Neck", "Head",
        "LeftArm", "LeftForeArm", "LeftHand",
        "RightArm", "RightForeArm", "RightHand",
        "LeftUpLeg", "LeftLeg", "LeftFoot",
        "RightUpLeg", "RightLeg", "RightFoot")),
    "MIXAMO": ("Mixamo", (
        "mixamorig:Hips", "mixamorig:Spine", "mixamorig:Neck", "mixamorig:Head",
        "mixamorig:LeftArm", "mixamorig:LeftForeArm", "mixamorig:LeftHand",
        "mixamorig:RightArm", "mixamorig:RightForeArm", "mixamorig:RightHand",
        "mixamorig:LeftUpLeg", "mixamorig:LeftLeg", "mixamorig:LeftFoot",
        "mixamorig:RightUpLeg", "mixamorig:RightLeg", "mixamorig:RightFoot")),
    "RIGIFY": ("Rigify meta-rig", (
        "spine", "spine.001", "spine.004", "spine.006",
        "upper_arm.L", "forearm.L", "hand.L",
        "upper_arm.R", "forearm.R", "hand.R",
        "thigh.L", "shin.L", "foot.L",
        "thigh.R", "shin.R", "foot.R")),
}


def find_bone(bone_names, wanted):
    """The armature's bone for a preset name: exact, else the same name after another prefix
    ("mixamorig1:Hips" for "mixamorig:Hips"); None if absent."""
    if wanted in bone_names:
        return wanted
    base = wanted.split(":")[-1]
    for name in bone_names:
        if name.split(":")[-1] == base and (":" in name or ":" in wanted):
            return name
    return None


def preset_map(preset, bone_names):
    """segment -> bone of the armature for a preset ("" where the armature lacks the bone)."""
    names = PRESETS[preset][1]
    return {seg: (find_bone(bone_names, names[i]) or "") for i, seg in enumerate(SEGMENTS)}


def detect_preset(bone_names):
    """The preset that finds the most of its bones in the armature (None if none finds 4)."""
    best, found = None, 3
    for key in PRESETS:
        n = sum(1 for b in preset_map(key, bone_names).values() if b)
        if n > found:
            best, found = key, n
    return best
