# The Blender add-on (blender/mocap_live) in Debian's Blender, headless, against the real
# `mocapd --demo` that tests/blender/test_blender_live_link.cpp started. Installs the add-on from
# the zip CMake built (as a user would), connects it, and measures:
#   live     every bone of our armature against the frames this script reads itself from the
#            same stream (its own socket), frame by frame: world rotation relative to the rest
#            pose vs A q A^-1 with A = -90 deg about z (our x fwd, y left, z up -> Blender's
#            character facing -Y: (w, x, y, z) -> (w, y, -x, z)), and the joint positions;
#   retarget a Mixamo-named armature in a T-pose (object turned 90 deg about x, scale 0.01, as
#            an FBX import has it), and Blender's Rigify human meta-rig: each mapped bone's
#            direction vs our segment's direction;
#   record   Record / Stop over 2 s: the Action's keys against the frames this script saw;
#   restart  mocapd is told to quit (the C++ side starts it again): the add-on's state goes to
#            waiting and back to connected, and the bones follow the new daemon;
#   import   the take the first daemon recorded, imported through `mocap export`: its frames and
#            the bone rotations at some of them (compared with the session file by the C++ side).
# Blender runs no timers in background mode, so this script calls the add-on's timer function
# (live.LINK.tick) itself, every 1/60 s as the timer would.
# Usage: blender -b --factory-startup --python live_link_check.py -- PORT CONTROL_SOCKET TAKE
#        MOCAP_PROGRAM ADDON_ZIP RESULT_JSON
import json
import math
import os
import socket
import sys
import threading
import time

import bpy
from mathutils import Quaternion, Vector

argv = sys.argv[sys.argv.index("--") + 1:]
port, control, take_path, mocap, addon_zip, result_path = argv[0:6]
results = {}


def fail(msg):
    raise RuntimeError(msg)


class OwnReader:
    """The test's own client of the stream: plain socket + json, every frame by its counter."""

    def __init__(self):
        self.frames = {}
        self.lock = threading.Lock()
        self.stop = False
        self.sock = socket.create_connection(("127.0.0.1", int(port)), 5)
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self):
        buf = b""
        self.sock.settimeout(0.2)
        while not self.stop:
            try:
                chunk = self.sock.recv(65536)
            except socket.timeout:
                continue
            except OSError:
                return
            if not chunk:
                return
            buf += chunk
            *lines, buf = buf.split(b"\n")
            with self.lock:
                for line in lines:
                    f = json.loads(line)
                    self.frames[f["frame"]] = f

    def first(self, timeout=5.0):
        """The first frame counter this reader received (None if none came)."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            with self.lock:
                if self.frames:
                    return min(self.frames)
            time.sleep(0.005)
        return None

    def get(self, n, timeout=2.0):
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            with self.lock:
                if n in self.frames:
                    return self.frames[n]
            time.sleep(0.002)
        return None

    def close(self):
        self.stop = True
        self.sock.close()
        self.thread.join(2)


def ours_q(q):  # the convention, written out here independently of the add-on
    return Quaternion((q[0], q[2], -q[1], q[3]))


def ours_v(p):
    return Vector((p[1], -p[0], p[2]))


def angle_deg(a, b):
    """Angle of the rotation between two quaternions, in double precision (mathutils works in
    float, whose acos near 1 cannot resolve less than about 0.04 deg)."""
    aw, ax, ay, az = (float(v) for v in a)
    bw, bx, by, bz = (float(v) for v in b)
    # conj(a) * b
    w = aw * bw + ax * bx + ay * by + az * bz
    x = aw * bx - ax * bw - ay * bz + az * by
    y = aw * by + ax * bz - ay * bw - az * bx
    z = aw * bz - ax * by + ay * bx - az * bw
    return math.degrees(2 * math.atan2(math.sqrt(x * x + y * y + z * z), abs(w)))


def vector_angle_deg(a, b):
    ax, ay, az = (float(v) for v in a)
    bx, by, bz = (float(v) for v in b)
    cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
    return math.degrees(math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), ax * bx + ay * by + az * bz))


def tick_until(pred, timeout, what):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        live.LINK.tick()
        if pred():
            return
        time.sleep(1 / 60)
    fail("timed out waiting for " + what + "; link: " + str(live.LINK.status()))


# -- install and enable the add-on from its zip, as the README says -----------------------------
if "FINISHED" not in bpy.ops.preferences.addon_install(filepath=addon_zip):
    fail("addon_install failed")
if "FINISHED" not in bpy.ops.preferences.addon_enable(module="mocap_live"):
    fail("addon_enable failed")
from mocap_live import convention, live  # noqa: E402  (installed just now)

scene = bpy.context.scene
settings = scene.mocap_live
settings.address = "127.0.0.1:" + port
own = OwnReader()
bpy.ops.mocap.connect()
tick_until(lambda: live.LINK.last_frame is not None, 20, "the first frame")
if "FINISHED" not in bpy.ops.mocap.create_armature():
    fail("create_armature failed")
arm = settings.target
names = convention.PRESETS["MOCAP"][1]


def check_ours(reader, frames_wanted, label):
    """Ticks, and after each tick compares the armature with the frame it shows."""
    worst_q = worst_p = 0.0
    worst_bone = ""
    checked = 0
    first = {}
    motion = 0.0
    seen = set()
    first_own = reader.first()
    end = time.monotonic() + 20
    while checked < frames_wanted and time.monotonic() < end:
        live.LINK.tick()
        time.sleep(1 / 60)
        n = live.LINK.applied_frame
        if n is None or n in seen or first_own is None or n < first_own:
            continue  # (frames from before the reader connected)
        seen.add(n)
        f = reader.get(n)
        if f is None:
            fail("%s: frame %d shown by the add-on never reached the test's reader" % (label, n))
        bpy.context.view_layer.update()
        mw = arm.matrix_world
        for i, seg in enumerate(f["segments"]):
            pb = arm.pose.bones[names[i]]
            posed = (mw.to_3x3() @ pb.matrix.to_3x3()) @ (mw.to_3x3() @ pb.bone.matrix_local.to_3x3()).inverted()
            want = ours_q(seg["q"])
            err = angle_deg(posed.to_quaternion(), want)
            if err > worst_q:
                worst_q, worst_bone = err, names[i]
            worst_p = max(worst_p, ((mw @ pb.head) - ours_v(seg["p"])).length)
            first.setdefault(i, want)
            motion = max(motion, angle_deg(first[i], want))
        checked += 1
    return {"frames_checked": checked, "max_err_deg": worst_q, "max_pos_err_m": worst_p,
            "max_motion_deg": motion, "worst_bone": worst_bone}


# -- live: our armature follows the stream --------------------------------------------------------
# The demo performer stands in the N-pose for 3 s, calibrates, then bends knees and elbows:
# compare while it moves.
tick_until(lambda: live.LINK.last_frame.flags & 1, 30, "the demo's calibration")
results["live"] = check_ours(own, 90, "live")

# -- retarget: a Mixamo-named T-pose armature ---------------------------------------------------
def make_mixamo():
    data = bpy.data.armatures.new("mixamo")
    obj = bpy.data.objects.new("mixamo", data)
    scene.collection.objects.link(obj)
    obj.rotation_euler = (math.pi / 2, 0, 0)  # y-up armature space, as an FBX import
    obj.scale = (0.01, 0.01, 0.01)  # centimetres
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    # armature space: y up, character facing +z (world -y after the 90 deg turn), x = its left
    bones = {}

    def bone(name, head, tail, parent=None):
        eb = data.edit_bones.new("mixamorig:" + name)
        eb.head, eb.tail = Vector(head), Vector(tail)
        if parent:
            eb.parent = bones[parent]
        bones[name] = eb

    bone("Hips", (0, 100, 0), (0, 110, 0))
    bone("Spine", (0, 110, 0), (0, 125, 0), "Hips")
    bone("Spine1", (0, 125, 0), (0, 140, 0), "Spine")
    bone("Neck", (0, 150, 0), (0, 160, 0), "Spine1")
    bone("Head", (0, 160, 0), (0, 175, 0), "Neck")
    for side, sx in (("Left", 1), ("Right", -1)):
        bone(side + "Shoulder", (sx * 5, 145, 0), (sx * 18, 145, 0), "Spine1")
        bone(side + "Arm", (sx * 18, 145, 0), (sx * 45, 145, 0), side + "Shoulder")
        bone(side + "ForeArm", (sx * 45, 145, 0), (sx * 70, 145, 0), side + "Arm")
        bone(side + "Hand", (sx * 70, 145, 0), (sx * 80, 145, 0), side + "ForeArm")
        bone(side + "UpLeg", (sx * 9, 95, 0), (sx * 9, 52, 0), "Hips")
        bone(side + "Leg", (sx * 9, 52, 0), (sx * 9, 9, 0), side + "UpLeg")
        bone(side + "Foot", (sx * 9, 9, 0), (sx * 9, 2, 12), side + "Leg")
    bpy.ops.object.mode_set(mode="OBJECT")
    return obj


# Where each segment points in our N-pose, our axes (x fwd, y left, z up), written out here:
# trunk and head up (the head a little forward, as the body model's end offset), arms and legs
# down, feet forward and a little down.
NPOSE = {"pelvis": (0, 0, 1), "torso": (0, 0, 1), "neck": (0, 0, 1), "head": (0.02, 0, 0.12),
         "foot_l": (0.110, 0, -0.039), "foot_r": (0.110, 0, -0.039)}


def check_retarget(obj, frames_wanted):
    """Every mapped bone of obj points where its segment points, frame by frame."""
    settings.target = obj
    preset = settings.preset
    mapped = {i.segment: i.bone for i in settings.bone_map if i.bone}
    worst = 0.0
    checked = 0
    seen = {live.LINK.applied_frame}  # shown on the armature before, not this one
    end = time.monotonic() + 20
    while checked < frames_wanted and time.monotonic() < end:
        live.LINK.tick()
        time.sleep(1 / 60)
        n = live.LINK.applied_frame
        if n is None or n in seen:
            continue
        seen.add(n)
        f = own.get(n)
        bpy.context.view_layer.update()
        mq = obj.matrix_world.to_quaternion()
        for seg in f["segments"]:
            if seg["name"] not in mapped:
                continue
            pb = obj.pose.bones[mapped[seg["name"]]]
            direction = mq @ (pb.matrix.to_quaternion() @ Vector((0, 1, 0)))
            want = ours_q(seg["q"]) @ ours_v(NPOSE.get(seg["name"], (0, 0, -1))).normalized()
            worst = max(worst, vector_angle_deg(direction, want))
        checked += 1
    return {"preset": preset, "frames_checked": checked, "max_dir_err_deg": worst,
            "mapped": len(mapped)}


results["retarget"] = check_retarget(make_mixamo(), 30)
# Blender's human meta-rig (the Rigify add-on Debian's Blender ships).
bpy.ops.preferences.addon_enable(module="rigify")
bpy.ops.object.select_all(action="DESELECT")
bpy.ops.object.armature_human_metarig_add()
results["rigify"] = check_retarget(bpy.context.view_layer.objects.active, 30)
settings.target = arm

# -- record 2 s into an Action ----------------------------------------------------------------
tick_until(lambda: live.LINK.applied_frame is not None, 5, "frames on our armature again")
bpy.ops.mocap.record()
t_start = time.monotonic()
while time.monotonic() - t_start < 2.0:
    live.LINK.tick()
    time.sleep(1 / 60)
recorded = list(live.LINK.recording)
if "FINISHED" not in bpy.ops.mocap.record():
    fail("stopping the recording failed")
action = arm.animation_data.action
numbers = [f.frame for f in recorded]
expected = [n for n in range(numbers[0], numbers[-1] + 1) if own.get(n, 0.5) is not None]
fc = action.fcurves.find('pose.bones["Hips"].rotation_quaternion', index=0)
keys = [k.co[0] for k in fc.keyframe_points]
fps = action["mocap_fps"]
key_times_err = max(abs((keys[k] - keys[0]) / fps - (recorded[k].t_ns - recorded[0].t_ns) * 1e-9)
                    for k in range(len(keys)))
results["record"] = {
    "frames": action["mocap_frames"], "keys": len(keys), "stream_frames_in_span": len(expected),
    "contiguous": numbers == expected, "duration_s": (recorded[-1].t_ns - recorded[0].t_ns) * 1e-9,
    "key_time_err_s": key_times_err, "t_unix_ns": action["mocap_t_unix_ns"],
    "first_t_unix_ns": str(recorded[0].t_unix_ns), "fcurves": len(action.fcurves),
    "wall_s": time.monotonic() - t_start}

# -- restart: mocapd quits, comes back (the C++ side restarts it), the add-on follows -----------
own.close()
conn_before = live.LINK.stream.connections
s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
s.connect(control)
s.sendall(b"quit\n")
s.recv(4096)
s.close()
states = []
tick_until(lambda: states.append(live.LINK.status()[0]) or states[-1] == "waiting", 20,
           "the add-on to notice mocapd left")
waiting_message = live.LINK.status()[1]
last_before = live.LINK.last_frame.frame
# The new daemon's frame counter starts again at 1 (the old one may still serve a moment while
# it shuts down, and the add-on may catch it once more: the counter tells them apart).
tick_until(lambda: live.LINK.stream.connections > conn_before and live.LINK.status()[0] == "connected"
           and live.LINK.last_frame.frame < last_before, 60, "the add-on to follow the new mocapd")
own2 = None
end = time.monotonic() + 20
while own2 is None and time.monotonic() < end:
    try:
        own2 = OwnReader()
    except OSError:
        time.sleep(0.1)
after = check_ours(own2, 20, "after restart")
after.update({"waiting_message": waiting_message, "connections": live.LINK.stream.connections})
results["restart"] = after
own2.close()

# -- import the first daemon's take through `mocap export` -----------------------------------
bpy.context.preferences.addons["mocap_live"].preferences.mocap_program = mocap
bpy.ops.mocap.connect()  # the same button disconnects
if live.LINK.connected():
    fail("the connect button did not disconnect")
t_import = time.monotonic()
if "FINISHED" not in bpy.ops.mocap.import_take(filepath=take_path):
    fail("import_take failed")
import_s = time.monotonic() - t_import
imp = arm.animation_data.action
fc = imp.fcurves.find('pose.bones["Hips"].rotation_quaternion', index=0)
keys = [k.co[0] for k in fc.keyframe_points]
samples = []
n_keys = len(keys)
first_frame = imp["mocap_first_frame"]
for k in sorted({0, n_keys // 4, n_keys // 2, (3 * n_keys) // 4, n_keys - 1}):
    x = keys[k]
    scene.frame_set(int(math.floor(x)), subframe=x - math.floor(x))
    bpy.context.view_layer.update()
    mw = arm.matrix_world.to_3x3()
    bones = []
    for i in range(len(names)):
        pb = arm.pose.bones[names[i]]
        q = ((mw @ pb.matrix.to_3x3()) @ (mw @ pb.bone.matrix_local.to_3x3()).inverted()).to_quaternion()
        bones.append([q.w, q.x, q.y, q.z])
    samples.append({"key": k, "bones": bones})
results["import"] = {"frames": imp["mocap_frames"], "keys": n_keys, "name": imp.name,
                     "first_frame": first_frame, "last_frame": imp["mocap_last_frame"],
                     "t_unix_ns": imp["mocap_t_unix_ns"], "samples": samples, "seconds": import_s}
# The add-on comes off cleanly (unregister: disconnects, removes its classes and properties).
if "FINISHED" not in bpy.ops.preferences.addon_disable(module="mocap_live"):
    fail("addon_disable failed")
results["disabled"] = not hasattr(bpy.types.Scene, "mocap_live")
with open(result_path, "w") as out:
    json.dump(results, out, indent=1)
print("live link check: done")
