"""The add-on's client of mocapd's pose JSON stream (docs/streaming.md section 1).

One background thread connects (TCP "HOST:PORT", or the private Unix socket: a path starting
with "/"), reads whole lines, parses them and queues the frames for Blender's main thread, which
takes them with take_frames() from a timer. The thread never touches bpy, and the main thread
never touches the socket: nothing here can block Blender's UI. When mocapd goes away (restart,
crash, not started yet) the thread says so in `state`/`message` and connects again every
RETRY_S seconds until stop(). Standard library only (no bpy), so plain python3 can run it too.
"""
import collections
import json
from array import array
import socket
import threading
import time

RETRY_S = 0.5  # between connection attempts while mocapd is away
READ_TIMEOUT_S = 0.25  # how often the reader looks at its stop flag
MAX_QUEUED = 1 << 15  # frames kept for the main thread (about 4.5 min at 120 Hz)
MAX_LINE = 64 * 1024  # longer than any line mocapd writes (16 KiB): a foreign server


SEGMENT_COUNT = 16
DEFAULT_PERIOD_NS = 8_333_333  # one frame at mocapd's default 120 Hz


class Frame:
    """One pose, kept small (a take holds many): its counter, times, flags, and each segment's
    q_earth_segment (w, x, y, z) and joint position p (metres) in one array of doubles, in the
    stream's segment order. Built from a parsed line; raises ValueError if it is not a pose."""
    __slots__ = ("frame", "t_ns", "t_unix_ns", "flags", "values")

    def __init__(self, line):
        try:
            if line["v"] != 1:
                raise ValueError("pose stream version %r is not known (1 is)" % line["v"])
            self.frame = int(line["frame"])
            self.t_ns = int(line["t_ns"])
            t_unix = line.get("t_unix_ns")
            self.t_unix_ns = int(t_unix) if t_unix is not None else None
            self.flags = int(line.get("flags", 0))
            segments = line["segments"]
            if len(segments) != SEGMENT_COUNT:
                raise ValueError("%d segments, not %d" % (len(segments), SEGMENT_COUNT))
            values = array("d")
            for seg in segments:
                q, p = seg["q"], seg["p"]
                if len(q) != 4 or len(p) != 3:
                    raise ValueError("a segment without q[4] and p[3]")
                values.extend(q)  # a null (a non-finite value) raises TypeError
                values.extend(p)
        except (KeyError, TypeError, AttributeError) as e:
            raise ValueError("not a pose line (%s: %s)" % (type(e).__name__, e)) from e
        self.values = values

    def q(self, i):
        """Segment i's q_earth_segment, (w, x, y, z)."""
        return self.values[7 * i:7 * i + 4]

    def p(self, i):
        """Segment i's joint position, metres."""
        return self.values[7 * i + 4:7 * i + 7]


def frame_times_s(frames):
    """Each frame's time since the first, seconds, from its t_ns. Should the stream's time jump
    back (another mocapd on another machine, a replay, then live again) the frames after the
    jump continue one frame period after the frame before it: keys stay in order."""
    out = []
    offset = 0
    prev = None
    period = DEFAULT_PERIOD_NS
    for f in frames:
        t = f.t_ns + offset
        if prev is not None:
            if t <= prev:
                offset += prev + period - t
                t = prev + period
            else:
                period = t - prev
        out.append((t - frames[0].t_ns) * 1e-9)
        prev = t
    return out


class PoseStream:
    """A self-reconnecting reader of one pose stream.

    state: "connecting" (first attempt), "connected", "waiting" (no mocapd there, or it went
    away; retrying), "stopped". message: the same for a human, with the reason."""

    def __init__(self, address):
        self.address = address.strip()
        self._lock = threading.Lock()
        self._frames = collections.deque(maxlen=MAX_QUEUED)
        self._stop = threading.Event()
        self._thread = None
        self._sock = None
        self.state = "stopped"
        self.message = "not connected"
        self.connections = 0  # successful connections so far (a restart of mocapd adds one)
        self.frames_received = 0
        self.bad_lines = 0
        self.dropped = 0  # frames the main thread did not take before the queue filled

    # -- main thread --------------------------------------------------------------------------
    def start(self):
        if self._thread is not None:
            return
        self._stop.clear()
        self._set("connecting", "connecting to " + self.address)
        self._thread = threading.Thread(target=self._run, name="mocap-pose-stream", daemon=True)
        self._thread.start()

    def stop(self):
        self._stop.set()
        sock = self._sock
        if sock is not None:
            try:
                sock.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
        if self._thread is not None:
            self._thread.join(2.0)
        self._thread = None
        self._set("stopped", "not connected")

    def take_frames(self):
        """Every frame parsed since the last call, oldest first (a list of Frame)."""
        with self._lock:
            out = list(self._frames)
            self._frames.clear()
        return out

    def status(self):
        with self._lock:
            return self.state, self.message

    # -- reader thread ------------------------------------------------------------------------
    def _set(self, state, message):
        with self._lock:
            self.state, self.message = state, message

    def _connect(self):
        if self.address.startswith("/"):
            sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
            sock.settimeout(2.0)
            sock.connect(self.address)
        else:
            host, sep, port = self.address.rpartition(":")
            if not sep or not port.isdigit():
                raise ValueError("address is HOST:PORT or /path/to/socket, not '%s'" % self.address)
            sock = socket.create_connection((host.strip("[]") or "127.0.0.1", int(port)), 2.0)
        sock.settimeout(READ_TIMEOUT_S)
        return sock

    def _run(self):
        while not self._stop.is_set():
            try:
                sock = self._connect()
            except ValueError as e:  # a malformed address does not get better by retrying
                self._set("waiting", str(e))
                self._stop.wait(RETRY_S)
                continue
            except OSError as e:
                reason = e.strerror or str(e) or type(e).__name__
                self._set("waiting", "no mocapd at %s (%s); retrying" % (self.address, reason))
                self._stop.wait(RETRY_S)
                continue
            self._sock = sock
            self.connections += 1
            self._set("connected", "connected to " + self.address)
            reason = self._read(sock)
            self._sock = None
            sock.close()
            if not self._stop.is_set():
                self._set("waiting", "%s: %s; reconnecting" % (self.address, reason))
                self._stop.wait(RETRY_S)

    def _read(self, sock):
        """Reads lines until the server closes or stop(); returns why it ended."""
        buf = b""
        while not self._stop.is_set():
            try:
                chunk = sock.recv(65536)
            except socket.timeout:
                continue
            except OSError as e:
                return e.strerror or str(e)
            if not chunk:
                return "mocapd closed the stream"
            buf += chunk
            lines = buf.split(b"\n")
            buf = lines.pop()
            if len(buf) > MAX_LINE:
                return "a line longer than %d bytes: not a mocapd pose stream" % MAX_LINE
            parsed = []
            refused = None
            for line in lines:
                try:
                    d = json.loads(line)
                except ValueError:
                    self.bad_lines += 1
                    continue
                if isinstance(d, dict) and d.get("v") != 1:
                    refused = "pose stream version %r is not known (1 is)" % d.get("v")
                    break
                try:
                    parsed.append(Frame(d))
                except ValueError:
                    self.bad_lines += 1
            if parsed:
                with self._lock:
                    room = MAX_QUEUED - len(self._frames)
                    if len(parsed) > room:
                        self.dropped += len(parsed) - room
                    self._frames.extend(parsed)
                    self.frames_received += len(parsed)
            if refused:
                return refused
        return "stopped"


def wait_for(predicate, timeout_s, poll_s=0.01):
    """Polls predicate() until true or timeout_s passes (tests and scripts)."""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(poll_s)
    return predicate()
