#!/usr/bin/env python3
"""Prints joint angles from mocapd's pose JSON stream (docs/streaming.md); standard library only.

usage: examples/joint_angles.py [HOST:PORT | /path/to/stream.sock] [FRAMES]
  default 127.0.0.1:7301; a path starting with / is the private Unix-socket stream
  (outputs.json.unix_socket); FRAMES = stop after that many frames (default: run until closed).
Each line: frame counter, UTC wall-clock time of the pose, then every joint's rotation angle
(child segment relative to its parent, degrees; 0 in the N-pose)."""
import datetime, json, math, socket, sys


def connect(address):
    if address.startswith("/"):
        sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        sock.connect(address)
    else:
        host, _, port = address.rpartition(":")
        sock = socket.create_connection((host or "127.0.0.1", int(port)))
    return sock.makefile("r", encoding="utf-8")


def angle_deg(q):  # rotation angle of the unit quaternion [w, x, y, z]
    return math.degrees(2.0 * math.acos(min(1.0, abs(q[0]))))


def main():
    address = sys.argv[1] if len(sys.argv) > 1 else "127.0.0.1:7301"
    frames = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    for count, line in enumerate(connect(address), 1):
        f = json.loads(line)
        if f["v"] != 1:
            sys.exit(f"unknown pose stream version {f['v']}")
        when = "time-unknown"
        if f["t_unix_ns"] is not None:  # an exact int: UTC ns since 1970
            sec, ns = divmod(f["t_unix_ns"], 1_000_000_000)
            utc = datetime.datetime.fromtimestamp(sec, datetime.timezone.utc)
            when = utc.replace(microsecond=ns // 1000).isoformat()
        angles = " ".join(f"{j['name']}={angle_deg(j['q']):.1f}" for j in f["joints"])
        print(f"frame {f['frame']} {when} {angles}", flush=True)
        if count == frames:
            break


if __name__ == "__main__":
    main()
