"""What the user sees: the scene settings, the operators (connect, create armature, record,
import a take, bone-map presets), the 3D View sidebar panel "Mocap" and the add-on
preferences (where the `mocap` program is)."""
import os
import time

import bpy
from bpy.props import (BoolProperty, CollectionProperty, EnumProperty, PointerProperty,
                       StringProperty)
from bpy_extras.io_utils import ImportHelper

from . import convention as cv
from . import take
from .live import LINK

ADDON = __package__


def _prefs(context):
    addon = context.preferences.addons.get(ADDON)
    return addon.preferences if addon else None


class MOCAP_AddonPreferences(bpy.types.AddonPreferences):
    bl_idname = ADDON
    mocap_program: StringProperty(
        name="mocap program", subtype="FILE_PATH",
        description="The mocap tool (build/bin/mocap, or installed); empty: $MOCAP_PROGRAM, "
                    "then PATH. Used to import .mocapses takes")

    def draw(self, context):
        self.layout.prop(self, "mocap_program")


_filling = False  # the map is being filled from a preset (not edited by the user)


def _bone_edited(self, context):
    if not _filling and context.scene.mocap_live.preset != "CUSTOM":
        context.scene.mocap_live.preset = "CUSTOM"  # keeps the map as edited


class MOCAP_MapItem(bpy.types.PropertyGroup):
    segment: StringProperty(name="Segment")
    bone: StringProperty(name="Bone", description="The target armature's bone for this segment",
                         update=_bone_edited)


def _fill_map(settings, preset):
    global _filling
    obj = settings.target
    names = [b.name for b in obj.data.bones] if obj else []
    mapping = cv.preset_map(preset, names) if obj else {s: "" for s in cv.SEGMENTS}
    _filling = True
    try:
        settings.bone_map.clear()
        for seg in cv.SEGMENTS:
            item = settings.bone_map.add()
            item.segment, item.bone = seg, mapping[seg]
    finally:
        _filling = False


def _preset_changed(self, context):
    if self.preset != "CUSTOM":
        _fill_map(self, self.preset)


def _target_changed(self, context):
    obj = self.target
    if obj is None:
        return
    found = cv.detect_preset([b.name for b in obj.data.bones])
    if found and found != self.preset:
        self.preset = found  # fills the map
    else:
        _fill_map(self, self.preset if self.preset != "CUSTOM" else "MOCAP")


def _is_armature(self, obj):
    return obj.type == "ARMATURE"


class MOCAP_Settings(bpy.types.PropertyGroup):
    address: StringProperty(
        name="Address", default="127.0.0.1:7301",
        description="mocapd's pose stream: HOST:PORT (outputs.json), or the path of its private "
                    "Unix socket (outputs.json.unix_socket)")
    target: PointerProperty(
        name="Armature", type=bpy.types.Object, poll=_is_armature, update=_target_changed,
        description="The armature the stream drives (empty: Create makes ours)")
    preset: EnumProperty(
        name="Bone names",
        items=[(k, v[0], "segment to bone names of " + v[0]) for k, v in cv.PRESETS.items()] +
              [("CUSTOM", "Custom", "the map below, as edited")],
        default="MOCAP", update=_preset_changed)
    bone_map: CollectionProperty(type=MOCAP_MapItem)
    show_map: BoolProperty(name="Bone map", default=False)
    root_motion: BoolProperty(
        name="Root motion", default=True,
        description="Move the pelvis bone with the body (scaled to the armature's legs)")


class MOCAP_OT_connect(bpy.types.Operator):
    """Connect to mocapd's pose stream (or disconnect); reconnects by itself when mocapd restarts"""
    bl_idname = "mocap.connect"
    bl_label = "Connect"

    def execute(self, context):
        if LINK.connected():
            LINK.disconnect()
        else:
            LINK.connect(context.scene.mocap_live.address)
        return {"FINISHED"}


class MOCAP_OT_create_armature(bpy.types.Operator):
    """Create our 16-bone armature with the streamed body's proportions and drive it"""
    bl_idname = "mocap.create_armature"
    bl_label = "Create mocap armature"

    @classmethod
    def poll(cls, context):
        return LINK.last_frame is not None

    def execute(self, context):
        context.scene.mocap_live.target = None
        LINK.bind(context, LINK.last_frame, create=True)
        return {"FINISHED"}


class MOCAP_OT_record(bpy.types.Operator):
    """Record the live frames (Stop turns them into an Action on the armature, frame times and
    the wall-clock time kept)"""
    bl_idname = "mocap.record"
    bl_label = "Record"

    @classmethod
    def poll(cls, context):
        return LINK.connected() or LINK.recording is not None

    def execute(self, context):
        if LINK.recording is None:
            LINK.start_recording()
            return {"FINISHED"}
        try:
            action = LINK.stop_recording(context)
        except ValueError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, "%s: %d frames" % (action.name, action["mocap_frames"]))
        return {"FINISHED"}


class MOCAP_OT_import_take(bpy.types.Operator, ImportHelper):
    """Import a recorded mocap take (.mocapses) as an Action, through `mocap export`"""
    bl_idname = "mocap.import_take"
    bl_label = "Import take (.mocapses)"
    bl_options = {"REGISTER", "UNDO"}
    filename_ext = ".mocapses"
    filter_glob: StringProperty(default="*.mocapses;*.mcap", options={"HIDDEN"})

    def execute(self, context):
        prefs = _prefs(context)
        mocap = take.find_mocap_program(prefs.mocap_program if prefs else "")
        if mocap is None:
            self.report({"ERROR"}, "mocap program not found: set it in the add-on's preferences "
                                   "or put it on PATH")
            return {"CANCELLED"}
        try:
            frames, notes = take.read_take(mocap, self.filepath)
        except (RuntimeError, OSError, ValueError) as e:
            self.report({"ERROR"}, "%s: %s" % (os.path.basename(self.filepath), e))
            return {"CANCELLED"}
        if not frames:
            self.report({"ERROR"}, "%s holds no poses" % self.filepath)
            return {"CANCELLED"}
        binding = LINK.bind(context, frames[0], create=True)
        name = os.path.splitext(os.path.basename(self.filepath))[0]
        action = take.build_action(binding, frames, name, context.scene, self.filepath)
        scene = context.scene
        last = int(action.frame_range[1]) + 1
        if scene.frame_end < last:
            scene.frame_end = last
        if notes:
            self.report({"WARNING"}, notes.splitlines()[-1])
        self.report({"INFO"}, "%s: %d frames" % (name, len(frames)))
        return {"FINISHED"}


class MOCAP_PT_panel(bpy.types.Panel):
    bl_label = "Mocap live link"
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Mocap"

    def draw(self, context):
        s = context.scene.mocap_live
        layout = self.layout
        col = layout.column()
        col.prop(s, "address")
        state, message = LINK.status()
        icon = {"connected": "LINKED", "waiting": "ERROR", "connecting": "TIME"}.get(state, "UNLINKED")
        col.operator("mocap.connect", text="Disconnect" if LINK.connected() else "Connect",
                     icon=icon)
        col.label(text=message, icon=icon)
        if state == "connected":
            col.label(text="%.0f frames/s" % LINK.rate_hz)
        if LINK.error:
            col.label(text=LINK.error, icon="ERROR")
        box = layout.box()
        box.prop(s, "target")
        box.operator("mocap.create_armature", icon="ARMATURE_DATA")
        box.prop(s, "preset")
        box.prop(s, "root_motion")
        box.prop(s, "show_map", icon="TRIA_DOWN" if s.show_map else "TRIA_RIGHT")
        if s.show_map and s.target is not None:
            for item in s.bone_map:
                box.prop_search(item, "bone", s.target.data, "bones", text=item.segment)
        row = layout.row()
        if LINK.recording is None:
            row.operator("mocap.record", text="Record", icon="REC")
        else:
            secs = time.monotonic() - LINK.record_wall_start
            row.operator("mocap.record", text="Stop (%.1f s, %d frames)" % (secs, len(LINK.recording)),
                         icon="PAUSE")
        layout.operator("mocap.import_take", icon="IMPORT")


def menu_import(self, context):
    self.layout.operator(MOCAP_OT_import_take.bl_idname, text="Mocap take (.mocapses)")


CLASSES = (MOCAP_AddonPreferences, MOCAP_MapItem, MOCAP_Settings, MOCAP_OT_connect,
           MOCAP_OT_create_armature, MOCAP_OT_record, MOCAP_OT_import_take, MOCAP_PT_panel)


def register():
    for c in CLASSES:
        bpy.utils.register_class(c)
    bpy.types.Scene.mocap_live = PointerProperty(type=MOCAP_Settings)
    bpy.types.TOPBAR_MT_file_import.append(menu_import)


def unregister():
    LINK.disconnect()
    bpy.types.TOPBAR_MT_file_import.remove(menu_import)
    del bpy.types.Scene.mocap_live
    for c in reversed(CLASSES):
        bpy.utils.unregister_class(c)
