# The add-on's stream module (blender/mocap_live/stream.py) on its own, with plain python3:
# what a frame keeps of a line, lines that are not poses refused, frame times kept in order when
# the stream's clock jumps back, and a real socket server of this script sending a good line,
# garbage, a line with a null and one of an unknown version: bad lines counted, the version
# refused with its number in the state message. Exits 0 when all hold, else names the failure.
# Usage: python3 stream_units.py STREAM_PY
import importlib.util
import json
import socket
import sys
import threading

spec = importlib.util.spec_from_file_location("stream", sys.argv[1])
stream = importlib.util.module_from_spec(spec)
spec.loader.exec_module(stream)


def line(frame=7, t_ns=1000, v=1, segments=16, q0=1.0):
    segs = [{"name": "s%d" % i, "q": [q0, 0.0, 0.0, 0.0], "p": [0.1 * i, 0.0, 0.9], "flags": 1}
            for i in range(segments)]
    return {"v": v, "frame": frame, "t": t_ns * 1e-9, "t_ns": t_ns,
            "t_unix_ns": 1764151200123456789, "flags": 17, "segments": segs, "joints": [],
            "sensors": []}


def check(cond, what):
    if not cond:
        sys.exit("FAIL: " + what)


f = stream.Frame(line())
check((f.frame, f.t_ns, f.t_unix_ns, f.flags) == (7, 1000, 1764151200123456789, 17), "fields")
check(tuple(f.q(3)) == (1.0, 0.0, 0.0, 0.0) and abs(f.p(3)[0] - 0.3) < 1e-12, "q and p")
for bad, why in ((line(segments=15), "15 segments"), (line(q0=None), "a null"),
                 ({"v": 1, "frame": 1}, "no segments"), (line(v=2), "version 2")):
    try:
        stream.Frame(bad)
        sys.exit("FAIL: accepted " + why)
    except ValueError:
        pass

times = stream.frame_times_s([stream.Frame(line(t_ns=t)) for t in (100, 200, 300, 50, 150)])
check(times == sorted(times) and len(set(times)) == 5, "times in order after a jump back: %r" % times)
check(abs(times[3] - 300e-9) < 1e-15, "the jump continues one period on: %r" % times)

server = socket.socket()
server.bind(("127.0.0.1", 0))
server.listen(1)


def serve():
    conn, _ = server.accept()
    good = json.dumps(line()).encode()
    null = json.dumps(line(q0=None)).encode()
    conn.sendall(good + b"\nnot json at all\n" + null + b"\n" + json.dumps(line(v=2)).encode() + b"\n")
    conn.recv(1)  # until the client hangs up
    conn.close()


threading.Thread(target=serve, daemon=True).start()
s = stream.PoseStream("127.0.0.1:%d" % server.getsockname()[1])
s.start()
check(stream.wait_for(lambda: "version 2 is not known" in s.status()[1], 10),
      "unknown version refused: %r" % (s.status(),))
frames = s.take_frames()
s.stop()
check(len(frames) == 1 and s.bad_lines == 2, "1 frame and 2 bad lines, got %d and %d" %
      (len(frames), s.bad_lines))
bad = stream.PoseStream("localhost:notaport")
bad.start()
check(stream.wait_for(lambda: "HOST:PORT" in bad.status()[1], 5), "a malformed address said so")
bad.stop()
print("ok")
