"""Quaternion helpers and the best-fit hinge of two segments' orientations, shared by
scripts/qmt-knees and scripts/qmt-filter-check (the real 6D run's consistency checks).
Quaternions are (w, x, y, z) tuples, earth <- sensor/segment."""
import math


def qmul(a, b):
    w1, x1, y1, z1 = a
    w2, x2, y2, z2 = b
    return (w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
            w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2)


def conj(q):
    return (q[0], -q[1], -q[2], -q[3])


def rot(q, v):
    return qmul(qmul(q, (0.0,) + tuple(v)), conj(q))[1:]


def unit(v):
    n = math.sqrt(sum(x * x for x in v))
    return tuple(x / n for x in v)


def angle_deg(u, v):
    return math.degrees(math.acos(max(-1.0, min(1.0, sum(a * b for a, b in zip(u, v))))))


def hinge_fit_deg(windows, fit_heading):
    """RMS over every sample of the angle between q_t j_t and R_z(d_w) q_s j_s: one axis pair
    (j_t in the upper frame, j_s in the lower) for all windows, and if fit_heading the two
    frames' relative heading d_w per window (else 0). windows: [(q_t list, q_s list), ...].
    Alternating least squares from three starts, the best; it converges slowly: 100 rounds are
    within 0.05 deg of 300 on the run, 30-40 rounds read 10 s windows up to 4 deg high."""
    best = None
    for init in ((1, 0, 0), (0, 1, 0), (0, 0, 1)):
        jt, js, d = init, init, [0.0] * len(windows)
        for _ in range(100):
            rel = []
            for (qt, qs), dw in zip(windows, d):
                rz = (math.cos(dw / 2), 0.0, 0.0, math.sin(dw / 2))
                rel += [qmul(conj(x), qmul(rz, y)) for x, y in zip(qt, qs)]
            jt = unit([sum(c) for c in zip(*[rot(r, js) for r in rel])])
            js = unit([sum(c) for c in zip(*[rot(conj(r), jt) for r in rel])])
            if not fit_heading:
                continue
            for i, (qt, qs) in enumerate(windows):
                c = sn = 0.0  # the yaw taking the lower axes onto the upper, horizontally
                for x, y in zip(qt, qs):
                    u, v = rot(x, jt), rot(y, js)
                    c += u[0] * v[0] + u[1] * v[1]
                    sn += v[0] * u[1] - v[1] * u[0]
                d[i] = math.atan2(sn, c)
        sq = []
        for (qt, qs), dw in zip(windows, d):
            rz = (math.cos(dw / 2), 0.0, 0.0, math.sin(dw / 2))
            sq += [angle_deg(rot(x, jt), rot(qmul(rz, y), js)) ** 2 for x, y in zip(qt, qs)]
        e = math.sqrt(sum(sq) / len(sq))
        best = e if best is None else min(best, e)
    return best
