// Joint limit defaults, mirroring, validation and the swing-twist check/clamp.
#include "mocap/skeleton/joint_limits.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "mocap/skeleton/quat_math.hpp"

namespace mocap {

namespace {

JointLimit ball(int twist_axis, int a, int b, double a_min, double a_max, double b_min,
                double b_max, double t_min, double t_max) {
  JointLimit l;
  l.limited = true;
  l.twist_axis = twist_axis;
  l.axis_a = a;
  l.axis_b = b;
  l.a_min_deg = a_min;
  l.a_max_deg = a_max;
  l.b_min_deg = b_min;
  l.b_max_deg = b_max;
  l.twist_min_deg = t_min;
  l.twist_max_deg = t_max;
  return l;
}

void mirror_range(int axis, double& lo, double& hi) {
  if (axis == 1) return;
  const double l = -hi, h = -lo;
  lo = l;
  hi = h;
}

}  // namespace

JointLimit mirror_limit(const JointLimit& left) {
  JointLimit r = left;
  mirror_range(r.axis_a, r.a_min_deg, r.a_max_deg);
  mirror_range(r.axis_b, r.b_min_deg, r.b_max_deg);
  mirror_range(r.twist_axis, r.twist_min_deg, r.twist_max_deg);
  return r;
}

JointLimits default_joint_limits() {
  // Axes: x forward, y left, z up. For a vertical bone, a = rotation about x (lateral bend /
  // abduction), b = rotation about y (flexion/extension), twist about z. Signs (left side):
  // spine bends forward for +b; a leg or arm swings forward for -b; the knee flexes for +b, the
  // elbow for -b; a left arm or leg abducts for +a.
  JointLimits L;
  auto& j = L.joint;
  j[index(Segment::torso)] = ball(2, 0, 1, -35, 35, -30, 90, -45, 45);
  j[index(Segment::neck)] = ball(2, 0, 1, -30, 30, -30, 45, -50, 50);
  j[index(Segment::head)] = ball(2, 0, 1, -30, 30, -30, 50, -45, 45);
  // Shoulder: abduction to 180, adduction 45; flexion 180, extension 60; rotation +-90. The
  // ellipse's adduction half-axis is 45, not the 30 of a hanging arm against the trunk: a raised
  // arm crosses the body much further (a reach across at 70 deg of flexion decomposes to
  // 32 deg of adduction), and a limit must not flag a normal reach.
  j[index(Segment::upper_arm_l)] = ball(2, 0, 1, -45, 180, -180, 60, -90, 90);
  // Elbow: hinge about y, flexion 150 (-b), 5 of hyperextension, 10 off-axis (carrying angle),
  // twist = forearm pronation/supination +-90.
  JointLimit elbow = ball(2, 0, 1, -10, 10, -150, 5, -90, 90);
  elbow.hinge = true;
  j[index(Segment::forearm_l)] = elbow;
  // Wrist (palms face the thighs in N-pose): flexion/extension about x, deviation about y.
  j[index(Segment::hand_l)] = ball(2, 0, 1, -80, 70, -20, 35, -20, 20);
  // Hip: flexion 125 (-b), extension 30 (the normal range; a walk's push-off reaches 20, and
  // a limit at exactly 20 flagged every stride's tracking error); abduction 45, adduction 25;
  // rotation -40..45.
  j[index(Segment::thigh_l)] = ball(2, 0, 1, -25, 45, -125, 30, -40, 45);
  // Knee: hinge about y, flexion 150 (+b), 5 of hyperextension, 10 off-axis, twist +-30.
  JointLimit knee = ball(2, 0, 1, -10, 10, -5, 150, -30, 30);
  knee.hinge = true;
  j[index(Segment::shank_l)] = knee;
  // Ankle: the foot's bone points forward (x): twist = inversion/eversion +-25, b = plantar (+)
  // / dorsal (-) flexion 50/35, a = toe-out about z +-25. Dorsiflexion 35, not the 20 of the
  // open-chain range: with the body's weight on it (a squat, a lunge, knee bends with the heels
  // down) the ankle reaches 35-40 deg, and a limit must not flag or clamp a normal squat.
  j[index(Segment::foot_l)] = ball(0, 2, 1, -25, 25, -35, 50, -25, 25);
  j[index(Segment::upper_arm_r)] = mirror_limit(j[index(Segment::upper_arm_l)]);
  j[index(Segment::forearm_r)] = mirror_limit(j[index(Segment::forearm_l)]);
  j[index(Segment::hand_r)] = mirror_limit(j[index(Segment::hand_l)]);
  j[index(Segment::thigh_r)] = mirror_limit(j[index(Segment::thigh_l)]);
  j[index(Segment::shank_r)] = mirror_limit(j[index(Segment::shank_l)]);
  j[index(Segment::foot_r)] = mirror_limit(j[index(Segment::foot_l)]);
  return L;
}

void validate(const JointLimits& limits) {
  for (int i = 0; i < kSegmentCount; ++i) {
    const JointLimit& l = limits.joint[i];
    if (!l.limited) continue;
    const std::string who = "joint " + std::string(kJointNames[i]);
    auto axis_ok = [](int a) { return a >= 0 && a <= 2; };
    if (!axis_ok(l.twist_axis) || !axis_ok(l.axis_a) || !axis_ok(l.axis_b) ||
        l.twist_axis == l.axis_a || l.twist_axis == l.axis_b || l.axis_a == l.axis_b)
      throw std::invalid_argument(who + ": twist and swing axes must be distinct x/y/z axes");
    auto range_ok = [](double lo, double hi) {
      return std::isfinite(lo) && std::isfinite(hi) && lo <= 0 && hi >= 0 && lo >= -180 &&
             hi <= 180;
    };
    if (!range_ok(l.a_min_deg, l.a_max_deg) || !range_ok(l.b_min_deg, l.b_max_deg) ||
        !range_ok(l.twist_min_deg, l.twist_max_deg))
      throw std::invalid_argument(who + ": each range must satisfy -180 <= min <= 0 <= max <= 180");
  }
}

JointCheck check_joint(const JointLimit& l, const Eigen::Quaterniond& q,
                       Eigen::Quaterniond* clamped) {
  JointCheck c;
  if (!l.limited) {
    if (clamped) *clamped = q;
    return c;
  }
  const SwingTwist st = swing_twist(q, l.twist_axis);
  const double a = st.swing_rad[l.axis_a] * kDegPerRad;
  const double b = st.swing_rad[l.axis_b] * kDegPerRad;
  const double t = st.twist_rad * kDegPerRad;
  c.a_deg = a;
  c.b_deg = b;
  c.twist_deg = t;
  double ca = a, cb = b;
  bool out = false;
  if (l.hinge) {
    ca = std::clamp(a, l.a_min_deg, l.a_max_deg);
    cb = std::clamp(b, l.b_min_deg, l.b_max_deg);
    out = ca != a || cb != b;
  } else {
    constexpr double kMinAxis = 1e-3;
    const double ea = std::max(a >= 0 ? l.a_max_deg : -l.a_min_deg, kMinAxis);
    const double eb = std::max(b >= 0 ? l.b_max_deg : -l.b_min_deg, kMinAxis);
    const double e = (a / ea) * (a / ea) + (b / eb) * (b / eb);
    if (e > 1.0) {
      const double s = 1.0 / std::sqrt(e);
      ca = a * s;
      cb = b * s;
      out = true;
    }
  }
  const double ct = std::clamp(t, l.twist_min_deg, l.twist_max_deg);
  out = out || ct != t;
  if (!out) {
    if (clamped) *clamped = q;
    return c;
  }
  Eigen::Vector3d sw = Eigen::Vector3d::Zero();
  sw[l.axis_a] = ca * kRadPerDeg;
  sw[l.axis_b] = cb * kRadPerDeg;
  const Eigen::Quaterniond qc =
      from_rotation_vector(sw) * axis_rotation(l.twist_axis, ct * kRadPerDeg);
  c.violation_deg = angle_between_deg(q, qc);
  c.violated = true;
  if (clamped) *clamped = qc;
  return c;
}

}  // namespace mocap
