"""Frames into an Action (the live recording and the take import share it), and the import of a
recorded session (.mocapses) through `mocap export --json` (frames and times as recorded, in
the stream's own line format, so an imported take goes through the same code as a live one).

Frame times are kept: a frame at stream time t (its `t_ns`) becomes keys at the scene frame
frame_start + (t - t_first) * fps, fractional where it falls between scene frames. The Action
carries custom properties to line the take up with other recordings:
  mocap_t_unix_ns  the first frame's wall-clock time, UTC ns since 1970, as a decimal string
                   (exact; an ID property int has 32 bits), "" when the source had no wall clock
  mocap_t_unix_s   the same in seconds (float: about 0.2 us resolution)
  mocap_frame_start, mocap_fps  the scene frame of the first frame and the frame rate used, so
                   wall-clock time at scene frame x = t_unix + (x - frame_start) / fps
  mocap_frames     how many frames were keyed; mocap_first_frame/mocap_last_frame their stream
                   frame counters; mocap_source  the address or file they came from.
"""
import json
import os
import shutil
import subprocess
import tempfile

import bpy

from . import convention as cv
from .stream import Frame, frame_times_s

EXPORT_TIMEOUT_S = 600


def _fcurve(action, path, index, group, count):
    fc = action.fcurves.new(path, index=index, action_group=group)
    fc.keyframe_points.add(count)
    return fc


def _fill(fc, xs, ys):
    co = [0.0] * (2 * len(xs))
    co[0::2] = xs
    co[1::2] = ys
    fc.keyframe_points.foreach_set("co", co)
    fc.keyframe_points.foreach_set("interpolation", [1] * len(xs))  # LINEAR (enum index)
    fc.update()


def build_action(binding, frames, name, scene, source):
    """An Action keying every frame on the bound armature (assigned to it); returns it."""
    if not frames:
        raise ValueError("no frames to key")
    fps = scene.render.fps / scene.render.fps_base
    frame_start = float(scene.frame_current)
    xs = [frame_start + t * fps for t in frame_times_s(frames)]
    solved = [binding.solve(f) for f in frames]
    action = bpy.data.actions.new(name)
    for bone in binding.mapped:
        group = bone
        path = 'pose.bones["%s"]' % bpy.utils.escape_identifier(bone)
        quats = []
        prev = None
        for s in solved:  # one hemisphere along the take: no flips between keys
            q = s[bone][1].copy()
            if prev is not None and prev.dot(q) < 0.0:
                q.negate()
            quats.append(q)
            prev = q
        for k in range(4):
            fc = _fcurve(action, path + ".rotation_quaternion", k, group, len(frames))
            _fill(fc, xs, [q[k] for q in quats])
        if solved[0][bone][0] is not None:
            for k in range(3):
                fc = _fcurve(action, path + ".location", k, group, len(frames))
                _fill(fc, xs, [s[bone][0][k] for s in solved])
    t_unix = frames[0].t_unix_ns
    action["mocap_t_unix_ns"] = str(t_unix) if t_unix is not None else ""
    action["mocap_t_unix_s"] = t_unix * 1e-9 if t_unix is not None else 0.0
    action["mocap_frame_start"] = frame_start
    action["mocap_fps"] = fps
    action["mocap_frames"] = len(frames)
    action["mocap_first_frame"] = frames[0].frame & 0x7FFFFFFF
    action["mocap_last_frame"] = frames[-1].frame & 0x7FFFFFFF
    action["mocap_source"] = source
    obj = binding.obj
    if obj.animation_data is None:
        obj.animation_data_create()
    obj.animation_data.action = action
    return action


def find_mocap_program(configured=""):
    """The `mocap` tool: the add-on's preference, $MOCAP_PROGRAM, then PATH; None if absent."""
    for cand in (configured, os.environ.get("MOCAP_PROGRAM", "")):
        if cand:
            path = bpy.path.abspath(cand)
            if os.path.isfile(path) and os.access(path, os.X_OK):
                return path
    return shutil.which("mocap")


def read_take(mocap, session_path):
    """Every pose of a recorded session as stream frames (dicts), through
    `mocap export SESSION --json`. Raises RuntimeError with mocap's own message on failure."""
    with tempfile.TemporaryDirectory(prefix="mocap-take-") as tmp:
        out = os.path.join(tmp, "take.jsonl")
        r = subprocess.run([mocap, "export", session_path, "--json", out],
                           capture_output=True, text=True, timeout=EXPORT_TIMEOUT_S)
        if r.returncode not in (0, 3):  # 3: exported, damaged ranges skipped (said on stderr)
            raise RuntimeError((r.stderr or r.stdout).strip() or "mocap export failed")
        frames = []
        with open(out, encoding="utf-8") as f:
            for n, line in enumerate(f, 1):
                try:
                    frames.append(Frame(json.loads(line)))
                except ValueError as e:
                    raise RuntimeError("mocap export's line %d: %s" % (n, e)) from e
        return frames, r.stderr.strip()


def segment_map_of(settings):
    """segment -> bone from the add-on's scene settings."""
    return {item.segment: item.bone for item in settings.bone_map}


def default_map_for_ours():
    return {seg: cv.PRESETS["MOCAP"][1][i] for i, seg in enumerate(cv.SEGMENTS)}
