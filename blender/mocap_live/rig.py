"""Armatures: the 16-bone mocap armature built from a frame's proportions, and the binding that
turns a pose frame into bone rotations of any armature (ours, or the user's through a
segment -> bone map).

How a frame drives a bone (all rotations in world space, C(q) = convention.to_blender_quat):
the bone mapped to segment s gets the world rotation C(q_earth_segment[s]) @ R_s @ Rest_s, where
Rest_s is the bone's rest rotation and R_s the smallest rotation that turns the bone's rest
direction (head to tail) onto the direction segment s has in our N-pose. So in the N-pose every
mapped bone points where our segment points (a T-pose rig's arms hang), and every rotation of a
segment away from the N-pose turns its bone alike. The bone's local rotation is solved against
its parent's posed matrix, walking the armature's own hierarchy (unmapped bones between keep
their current pose), so spines of several bones and shoulder bones need no mapping. On our own
armature R_s is the identity (it is built in the N-pose) and positions are the stream's.
Root motion: the pelvis bone's head goes to the stream's pelvis joint (ours: exactly; another
armature: scaled by its leg length over ours, relative to its rest stance).
"""
import bpy
from mathutils import Matrix, Quaternion, Vector

from . import convention as cv

MOCAP_PROP = "mocap_armature"  # custom property marking the armature this add-on built


def body_offsets(frame):
    """Each segment's joint offset from its parent's joint in the parent's frame (our axes,
    metres), from one frame's positions and orientations; the pelvis: its joint above the
    floor."""
    q = [Quaternion(frame.q(i)) for i in range(len(cv.SEGMENTS))]
    p = [Vector(frame.p(i)) for i in range(len(cv.SEGMENTS))]
    out = []
    for i in range(len(cv.SEGMENTS)):
        par = cv.PARENT[i]
        if par < 0:
            out.append(Vector((0.0, 0.0, p[0].z)))
        else:
            out.append(q[par].inverted() @ (p[i] - p[par]))
    return out


def body_height_m(offsets):
    """The body height the offsets imply (the shank's length over its share of the height)."""
    return offsets[cv.SEGMENTS.index("foot_l")].length / cv.SHANK_FRACTION


def rest_pelvis_height_m(offsets):
    """How high the pelvis joint is standing in the N-pose: the leg's offsets plus the ankle."""
    i = cv.SEGMENTS.index
    leg = offsets[i("thigh_l")].z + offsets[i("shank_l")].z + offsets[i("foot_l")].z
    return -leg + cv.ANKLE_FRACTION * body_height_m(offsets)


def create_armature(context, frame, name="mocap"):
    """A new armature object of our 16 bones in the N-pose with the proportions of `frame`'s
    body, linked to the scene's active collection and made active. Bone names are those of
    our BVH/glTF exports."""
    offsets = body_offsets(frame)
    names = cv.PRESETS["MOCAP"][1]
    rest = []  # joint positions in the N-pose, our axes
    for i, off in enumerate(offsets):
        par = cv.PARENT[i]
        rest.append(off.copy() if par < 0 else rest[par] + off)
    height = body_height_m(offsets)
    chain_end = {0: 1, 1: 2, 2: 3, 4: 5, 5: 6, 7: 8, 8: 9, 10: 11, 11: 12, 13: 14, 14: 15}
    data = bpy.data.armatures.new(name)
    obj = bpy.data.objects.new(name, data)
    obj[MOCAP_PROP] = 1
    context.collection.objects.link(obj)
    context.view_layer.objects.active = obj
    prev_mode = obj.mode
    bpy.ops.object.mode_set(mode="EDIT")
    ebs = []
    for i, seg in enumerate(cv.SEGMENTS):
        eb = data.edit_bones.new(names[i])
        eb.head = cv.to_blender_vec(rest[i])
        if i in chain_end:
            eb.tail = cv.to_blender_vec(rest[chain_end[i]])
        else:
            eb.tail = cv.to_blender_vec(rest[i] + Vector(cv.NPOSE_END_FRACTION[seg]) * height)
        eb.roll = 0.0
        if cv.PARENT[i] >= 0:
            eb.parent = ebs[cv.PARENT[i]]
            eb.use_connect = False
        ebs.append(eb)
    bpy.ops.object.mode_set(mode=prev_mode if prev_mode != "EDIT" else "OBJECT")
    for pb in obj.pose.bones:
        pb.rotation_mode = "QUATERNION"
    return obj


class Binding:
    """One armature and its segment -> bone map, ready to pose frames (see the module doc).
    Built from the armature's rest pose and the body proportions of one frame."""

    def __init__(self, obj, seg_to_bone, frame, root_motion=True):
        self.obj = obj
        self.root_motion = root_motion
        bones = obj.data.bones
        m_world = obj.matrix_world
        self.m_rot = m_world.to_quaternion().normalized()
        self.m_rot_inv = self.m_rot.inverted()
        self.ours = bool(obj.get(MOCAP_PROP))
        self.mapped = {}  # bone name -> segment index
        for i, seg in enumerate(cv.SEGMENTS):
            b = seg_to_bone.get(seg, "")
            if b and b in bones and b not in self.mapped:
                self.mapped[b] = i
        # Bones to walk: every mapped bone and its ancestors, parents first.
        needed = set()
        for b in self.mapped:
            bone = bones[b]
            while bone is not None and bone.name not in needed:
                needed.add(bone.name)
                bone = bone.parent
        self.order = sorted(needed, key=lambda n: len(bones[n].parent_recursive))
        self.parent = {n: (bones[n].parent.name if bones[n].parent else None) for n in self.order}
        self.rel = {}  # the bone's rest matrix in its parent's rest frame (4x4)
        for n in self.order:
            b = bones[n]
            self.rel[n] = (b.parent.matrix_local.inverted() @ b.matrix_local) if b.parent else b.matrix_local.copy()
        # Per mapped bone: the posed armature-space rotation is pre @ C(q) @ post[b].
        self.post = {}
        for n, i in self.mapped.items():
            rest_arm = bones[n].matrix_local.to_quaternion()
            rest_dir_world = self.m_rot @ (rest_arm @ Vector((0.0, 1.0, 0.0)))
            align = rest_dir_world.rotation_difference(cv.npose_direction(cv.SEGMENTS[i]))
            if self.ours:
                align = Quaternion()  # built in the N-pose: exactly the identity
            self.post[n] = align @ self.m_rot @ rest_arm
        self.root_bone = next((n for n, i in self.mapped.items() if i == 0), None)
        # Root motion: our armature takes the stream's positions as they are (armature space);
        # another gets them scaled by its leg length over ours, around its rest stance.
        offsets = body_offsets(frame)
        self.scale = 1.0
        self.rest_pelvis_m = rest_pelvis_height_m(offsets)
        if not self.ours:
            ours_leg = sum(offsets[cv.SEGMENTS.index(s)].length for s in ("shank_l", "foot_l"))
            theirs = [seg_to_bone.get(s, "") for s in ("thigh_l", "shank_l")]
            if all(b in bones for b in theirs) and ours_leg > 0:
                leg = sum((m_world @ bones[b].tail_local - m_world @ bones[b].head_local).length for b in theirs)
                self.scale = leg / ours_leg
        self.m_world_inv = m_world.inverted()
        if self.root_bone:
            self.rest_head_world = m_world @ bones[self.root_bone].head_local
        for n in self.mapped:
            obj.pose.bones[n].rotation_mode = "QUATERNION"

    def signature(self):
        return Binding.key(self.obj, self._map_items(), self.root_motion)

    def _map_items(self):
        return tuple(sorted((cv.SEGMENTS[i], b) for b, i in self.mapped.items()))

    @staticmethod
    def key(obj, map_items, root_motion):
        """What a binding depends on: rebuilt when any of it changes."""
        return (obj.name, tuple(map_items), bool(root_motion),
                tuple(tuple(r) for r in obj.matrix_world), len(obj.data.bones))

    def _root_head_armature(self, frame):
        p = cv.to_blender_vec(frame.p(0))
        if self.ours:
            return p  # our armature's space is the stream's (metres, Blender axes)
        v = Vector((p.x, p.y, p.z - self.rest_pelvis_m)) * self.scale
        return self.m_world_inv @ (self.rest_head_world + v)

    def solve(self, frame):
        """{bone: (location or None, rotation Quaternion)} for the frame: the local (basis)
        values of every mapped bone; a location only for the root-motion bone."""
        pose_bones = self.obj.pose.bones
        posed = {}
        out = {}
        for n in self.order:
            par = self.parent[n]
            base = (posed[par] @ self.rel[n]) if par else self.rel[n]
            i = self.mapped.get(n)
            if i is None:
                posed[n] = base @ pose_bones[n].matrix_basis
                continue
            rot = self.m_rot_inv @ cv.to_blender_quat(frame.q(i)) @ self.post[n]
            moves = self.root_motion and n == self.root_bone
            head = self._root_head_armature(frame) if moves else base.to_translation()
            desired = Matrix.Translation(head) @ rot.to_matrix().to_4x4()
            basis = base.inverted() @ desired
            out[n] = (basis.to_translation() if moves else None, basis.to_quaternion())
            posed[n] = desired
        return out

    def apply(self, frame):
        """Poses the armature to the frame (sets the mapped pose bones)."""
        pose_bones = self.obj.pose.bones
        for n, (loc, rot) in self.solve(frame).items():
            pb = pose_bones[n]
            pb.rotation_quaternion = rot
            if loc is not None:
                pb.location = loc
