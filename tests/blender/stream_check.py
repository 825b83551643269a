# The add-on's stream client (blender/mocap_live/stream.py, no bpy: plain python3 runs it) on
# mocapd's private Unix socket, started before mocapd is: it must say it is waiting (and why),
# then connect by itself once tests/blender/test_blender_live_link.cpp has started mocapd, and
# hand over whole frames. Prints "waiting: MESSAGE" once, then "ok ..." and exits 0.
# Usage: python3 stream_check.py STREAM_PY SOCKET_PATH
import importlib.util
import sys
import time

spec = importlib.util.spec_from_file_location("stream", sys.argv[1])
stream = importlib.util.module_from_spec(spec)
spec.loader.exec_module(stream)
path = sys.argv[2]

s = stream.PoseStream(path)
s.start()
if not stream.wait_for(lambda: s.status()[0] == "waiting", 10):
    sys.exit("never waiting: %r" % (s.status(),))
print("waiting: " + s.status()[1], flush=True)
if not stream.wait_for(lambda: s.status()[0] == "connected", 60):
    sys.exit("never connected: %r" % (s.status(),))
frames = []
end = time.monotonic() + 20
while len(frames) < 60 and time.monotonic() < end:
    frames += s.take_frames()
    time.sleep(0.01)
s.stop()
if len(frames) < 60:
    sys.exit("only %d frames" % len(frames))
counters = [f.frame for f in frames]
if any(b <= a for a, b in zip(counters, counters[1:])):
    sys.exit("frame counters not increasing: %r" % counters)
if any(len(f.values) != 16 * 7 for f in frames):
    sys.exit("a frame without 16 segments")
print("ok connections=%d frames=%d bad_lines=%d state=%s" %
      (s.connections, len(frames), s.bad_lines, s.status()[0]), flush=True)
