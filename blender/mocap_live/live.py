"""The live link's state on Blender's main thread: the stream, the binding of the target
armature, the recording. tick() is the bpy.app.timers callback (every TICK_S while connected):
it takes the frames the stream thread parsed, keeps them all while recording, and poses the
target armature to the newest. Headless scripts (the tests) call tick() themselves: Blender
runs no timers in background mode.
"""
import time

import bpy

from . import rig
from . import take
from .stream import PoseStream

TICK_S = 1.0 / 60.0


class LiveLink:
    def __init__(self):
        self.stream = None
        self.binding = None
        self.last_frame = None  # newest frame received (a stream.Frame)
        self.applied_frame = None  # the frame counter last put on the armature
        self.recording = None  # frames kept since Record, or None
        self.record_wall_start = 0.0
        self.rate_hz = 0.0  # frames per second received, measured over the last second
        self._rate_window = []
        self._shown = None  # last status drawn (redraw only on change)
        self.error = ""  # the last error of tick(), shown in the panel

    # -- connection ---------------------------------------------------------------------------
    def connect(self, address):
        self.disconnect()
        self.stream = PoseStream(address)
        self.stream.start()
        if not bpy.app.timers.is_registered(timer):
            bpy.app.timers.register(timer, first_interval=TICK_S)

    def disconnect(self):
        if self.stream is not None:
            self.stream.stop()
        self.stream = None
        if bpy.app.timers.is_registered(timer):
            bpy.app.timers.unregister(timer)

    def connected(self):
        return self.stream is not None

    def status(self):
        """(state, message): "stopped", "connecting", "connected" or "waiting" (retrying)."""
        if self.stream is None:
            return "stopped", "not connected"
        return self.stream.status()

    # -- recording ----------------------------------------------------------------------------
    def start_recording(self):
        self.recording = []
        self.record_wall_start = time.monotonic()

    def stop_recording(self, context, name=None):
        """Turns the recorded frames into an Action on the target armature (creating ours when
        there is none). Returns the Action; raises ValueError when nothing was recorded."""
        frames, self.recording = self.recording, None
        if not frames:
            raise ValueError("no frames arrived while recording (is mocapd running?)")
        binding = self.bind(context, frames[0], create=True)
        src = self.stream.address if self.stream else "stream"
        return take.build_action(binding, frames, name or "mocap live take", context.scene, src)

    # -- armature -----------------------------------------------------------------------------
    def bind(self, context, frame, create=False):
        """The binding of the scene's target armature (rebuilt when the target, its map or its
        placement changed); with create, our armature is made when no target is set. None when
        there is nothing to drive."""
        settings = context.scene.mocap_live
        obj = settings.target
        if obj is not None and obj.name not in context.scene.objects:
            obj = None  # deleted or unlinked
        if obj is None:
            if not create:
                self.binding = None
                return None
            obj = rig.create_armature(context, frame)
            settings.target = obj  # its update fills the map (the "mocap" preset)
        items = tuple(sorted((i.segment, i.bone) for i in settings.bone_map if i.bone))
        key = rig.Binding.key(obj, items, settings.root_motion)
        if self.binding is None or self.binding.obj != obj or self.binding.signature() != key:
            self.binding = rig.Binding(obj, dict(items), frame, settings.root_motion)
        return self.binding

    # -- the timer ----------------------------------------------------------------------------
    def tick(self, context=None):
        """Takes the stream's frames, records them, poses the target to the newest. Returns the
        number of frames taken."""
        context = context or bpy.context
        frames = self.stream.take_frames() if self.stream else []
        now = time.monotonic()
        if frames:
            self.last_frame = frames[-1]
            if self.recording is not None:
                self.recording.extend(frames)
            self._rate_window.append((now, len(frames)))
        self._rate_window = [(t, n) for t, n in self._rate_window if now - t <= 1.0]
        self.rate_hz = float(sum(n for _, n in self._rate_window))
        if frames and context.scene is not None:
            try:
                binding = self.bind(context, frames[-1])
                if binding is not None:
                    binding.apply(frames[-1])
                    self.applied_frame = frames[-1].frame
            except ReferenceError:  # the armature went away under us
                self.binding = None
        self._redraw_if_changed()
        return len(frames)

    def _redraw_if_changed(self):
        shown = (self.status(), round(self.rate_hz), self.recording is not None,
                 len(self.recording) // 60 if self.recording else 0)
        if shown == self._shown:
            return
        self._shown = shown
        wm = bpy.context.window_manager
        for window in (wm.windows if wm else []):
            for area in window.screen.areas:
                if area.type == "VIEW_3D":
                    area.tag_redraw()


LINK = LiveLink()


def timer():
    try:
        LINK.tick()
    except Exception as e:  # a raising timer is dropped by Blender: say why and keep going
        LINK.error = "%s: %s" % (type(e).__name__, e)
        print("mocap live link:", LINK.error)
    return TICK_S if LINK.connected() else None
