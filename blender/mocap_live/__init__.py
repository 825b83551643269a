"""mocap live link: drives a Blender armature from mocapd's pose stream, records it into
Actions and imports recorded takes. Install: README "Use with" (Blender), docs/blender.md."""
bl_info = {
    "name": "Mocap live link",
    "author": "the mocap project",
    "version": (1, 0, 0),
    "blender": (3, 4, 0),
    "location": "3D View > Sidebar > Mocap; File > Import > Mocap take (.mocapses)",
    "description": "Live poses from mocapd (TCP or its private Unix socket) onto an armature, "
                   "recorded into Actions with their frame times; .mocapses takes imported",
    "category": "Animation",
}

if "ui" in locals():  # Blender's "Reload Scripts"
    import importlib
    for _m in (stream, convention, rig, take, live, ui):  # noqa: F821
        importlib.reload(_m)
else:
    from . import stream, convention, rig, take, live, ui


def register():
    ui.register()


def unregister():
    ui.unregister()
